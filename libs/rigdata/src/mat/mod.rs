//! MATLAB `.mat` files as TTC runs come in them: Level 5 (MATLAB 5.0 to 7, the `-v7` default,
//! optionally zlib-compressed) read and written, Level 4 read. Version 7.3 files are HDF5 and get
//! an error asking for a re-save with `-v7`.
//!
//! A TTC `.mat` holds one numeric vector per channel (named as in the `.dat`), either as
//! top-level variables or as the fields of one struct variable, plus the strings `tireid` and
//! `testid`. MATLAB files carry no units: the TTC units are assumed and checked against the
//! magnitudes when the table is interpreted.
//!
//! Layout of Level 5 (MathWorks, *MAT-File Format*): a 128-byte header (116 bytes of text, 8 of
//! subsystem offset, version `0x0100`, endian indicator `IM` little / `MI` big), then data
//! elements, each an 8-byte tag (type, byte count; or the 4-byte "small data element" form when
//! the count is ≤ 4) and its data padded to 8 bytes. A variable is an `miMATRIX` element (array
//! flags with the class, dimensions, name, then the values, which may be stored in a smaller
//! type than the class: MATLAB saves doubles holding small integers as `int8`, `uint8`, …), or
//! an `miCOMPRESSED` element whose zlib stream holds the `miMATRIX`.

mod read;
mod write;

pub use read::{MatFile, parse_mat, read_mat};
pub use write::{CharEncoding, MatLayout, MatUnits, MatWriteOptions, to_mat, write_mat};

/// Data element types (MAT-File Format, Table 1-1).
pub(crate) mod ty {
    pub const INT8: u32 = 1;
    pub const UINT8: u32 = 2;
    pub const INT16: u32 = 3;
    pub const UINT16: u32 = 4;
    pub const INT32: u32 = 5;
    pub const UINT32: u32 = 6;
    pub const SINGLE: u32 = 7;
    pub const DOUBLE: u32 = 9;
    pub const INT64: u32 = 12;
    pub const UINT64: u32 = 13;
    pub const MATRIX: u32 = 14;
    pub const COMPRESSED: u32 = 15;
    pub const UTF8: u32 = 16;
    pub const UTF16: u32 = 17;
    pub const UTF32: u32 = 18;
}

/// Array classes (MAT-File Format, Table 1-3).
pub(crate) mod class {
    pub const CELL: u8 = 1;
    pub const STRUCT: u8 = 2;
    pub const CHAR: u8 = 4;
    pub const DOUBLE: u8 = 6;
    pub const UINT64: u8 = 15;
}
