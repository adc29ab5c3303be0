//! LAS / LAZ reading and writing.
