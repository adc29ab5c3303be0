//! The atomic writer follows the umask (a process of its own: the umask is process-wide).

#![cfg(unix)]

use bounded_geom::atomic::write;
use rustix::fs::Mode;
use rustix::process::umask;
use std::os::unix::fs::PermissionsExt;

#[test]
fn new_files_get_0666_less_the_umask() {
    let dir = tempfile::tempdir().unwrap();
    let mode = |p: &std::path::Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    for (mask, expected) in [
        (0o022, 0o644),
        (0o077, 0o600),
        (0o002, 0o664),
        (0o027, 0o640),
    ] {
        umask(Mode::from_bits_truncate(mask));
        let path = dir.path().join(format!("new-{mask:o}"));
        write(&path, b"x").unwrap();
        assert_eq!(mode(&path), expected, "umask {mask:o}");
    }
}
