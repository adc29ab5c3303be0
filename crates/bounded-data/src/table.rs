//! A point table: positions plus the extra per-point properties a file carried.
