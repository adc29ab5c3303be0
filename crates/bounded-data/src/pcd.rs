//! PCL's PCD format: ascii, binary and binary_compressed.
