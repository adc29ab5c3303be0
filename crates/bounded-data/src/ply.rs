//! PLY: ascii and binary, any vertex properties.
