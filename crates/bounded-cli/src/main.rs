//! The `bounded` command-line tool.

fn main() {}
