//! mftyre: the MF-Tyre 6.1 model (ISO-W, SI) and `.tir` property-file I/O. Pure library.
