//! `remove_temporaries`, as a signal handler calls it (a process of its own: it closes the
//! process-wide registry).

use bounded_geom::atomic::{
    ScratchDir, WriteError, remove_temporaries, stale_temporaries, write, write_with,
};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

#[test]
fn removing_the_temporaries_deletes_the_live_ones_and_refuses_new_ones() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.bin");
    let listing = || std::fs::read_dir(dir.path()).unwrap().count();
    // A scratch directory that another thread keeps filling, as the main thread of a file
    // labelled in blocks does while the handler removes it. Not joined before the checks:
    // a failed one ends the test, and the thread with it.
    let scratch = ScratchDir::create(dir.path()).unwrap();
    let made = Arc::new(AtomicUsize::new(0));
    let filler = {
        let (scratch, made) = (scratch.path().to_path_buf(), made.clone());
        std::thread::spawn(move || {
            while std::fs::write(scratch.join(made.load(Ordering::Relaxed).to_string()), b"x")
                .is_ok()
            {
                made.fetch_add(1, Ordering::Relaxed);
            }
        })
    };
    while made.load(Ordering::Relaxed) < 100 && !filler.is_finished() {
        std::thread::yield_now();
    }
    assert!(!filler.is_finished(), "the scratch directory takes files");
    let result = write_with(&path, |file| -> Result<(), WriteError> {
        use std::io::Write;
        file.write_all(b"partial").unwrap();
        assert_eq!(
            listing(),
            2,
            "the temporary file and the scratch directory exist"
        );
        // What the signal handler does while the output is being written.
        remove_temporaries();
        assert_eq!(listing(), 0, "and are gone");
        Ok(())
    });
    assert!(result.is_err(), "the write cannot complete");
    filler.join().unwrap();
    assert_eq!(listing(), 0, "nothing landed after the removal");
    assert!(stale_temporaries(dir.path()).is_empty());
    // Every later write is refused before it creates anything.
    let e = write(&path, b"late").unwrap_err();
    assert_eq!(e.source.kind(), std::io::ErrorKind::Interrupted);
    assert!(ScratchDir::create(dir.path()).is_err());
    assert_eq!(listing(), 0);
    drop(scratch);
}
