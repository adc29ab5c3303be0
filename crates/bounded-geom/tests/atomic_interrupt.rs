//! `remove_temporaries`, as a signal handler calls it (a process of its own: it closes the
//! process-wide registry).

use bounded_geom::atomic::{WriteError, remove_temporaries, stale_temporaries, write, write_with};

#[test]
fn removing_the_temporaries_deletes_the_live_ones_and_refuses_new_ones() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.bin");
    let listing = || std::fs::read_dir(dir.path()).unwrap().count();
    let result = write_with(&path, |file| -> Result<(), WriteError> {
        use std::io::Write;
        file.write_all(b"partial").unwrap();
        assert_eq!(listing(), 1, "the temporary file exists");
        // What the signal handler does while the output is being written.
        remove_temporaries();
        assert_eq!(listing(), 0, "and is gone");
        Ok(())
    });
    assert!(result.is_err(), "the write cannot complete");
    assert_eq!(listing(), 0);
    assert!(stale_temporaries(dir.path()).is_empty());
    // Every later write is refused before it creates anything.
    let e = write(&path, b"late").unwrap_err();
    assert_eq!(e.source.kind(), std::io::ErrorKind::Interrupted);
    assert_eq!(listing(), 0);
}
