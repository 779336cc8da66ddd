//! procedure: GS2MF / Square Matrix procedure files, sweep primitives and expansion into setpoints.
