//! `remove_pending`, what a process ended by a signal calls: it deletes the temporary files of
//! the writes in progress. Its own test binary, because it removes every pending temporary of
//! the process, which would break writes running beside it in another test.

use nurbspring_io::atomic::{remove_pending, write_atomic};

#[test]
fn remove_pending_deletes_the_temporary_of_a_write_in_progress() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frame.csv");
    let listing = || -> Vec<String> {
        std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    };
    let mut before = Vec::new();
    let mut after = Vec::new();
    let result = write_atomic(&path, |w| {
        w.write_all(b"partial")?;
        before = listing();
        remove_pending();
        after = listing();
        Ok(())
    });
    assert_eq!(before.len(), 1, "{before:?}");
    assert!(before[0].starts_with(".frame.csv.tmp-"), "{before:?}");
    assert!(after.is_empty(), "{after:?}");
    // The rename of a removed temporary fails, so the write reports an error and no target
    // appears.
    assert!(result.is_err());
    assert!(!path.exists());
}
