//! XYZ / TXT / CSV text formats.
