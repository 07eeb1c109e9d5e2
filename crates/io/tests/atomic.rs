//! Atomic replacement observed from outside: a reader holding the old file keeps the old content
//! whole, the path names the old complete file while the new one is being written and the new
//! complete file afterwards, and the new file is a different inode (a rename, not an in-place
//! rewrite or a copy-then-delete, both of which a held handle would see).

#![cfg(unix)]

use std::io::{Read, Seek, SeekFrom};
use std::os::unix::fs::MetadataExt;

use nurbspring_io::atomic::{write_atomic, write_atomic_bytes};

fn content(tag: u8, len: usize) -> Vec<u8> {
    (0..len)
        .map(|i| tag.wrapping_add((i % 251) as u8))
        .collect()
}

#[test]
fn a_reader_holding_the_old_file_sees_the_old_content_whole() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("data.bin");
    let old = content(1, 300_000);
    let new = content(7, 200_000);
    write_atomic_bytes(&path, &old).unwrap();
    let ino_old = std::fs::metadata(&path).unwrap().ino();

    let mut held = std::fs::File::open(&path).unwrap();
    let mut first = vec![0u8; 1000];
    held.read_exact(&mut first).unwrap();

    write_atomic_bytes(&path, &new).unwrap();

    // The held handle still reads the old file, from where it was and from the start.
    let mut rest = Vec::new();
    held.read_to_end(&mut rest).unwrap();
    first.extend_from_slice(&rest);
    assert_eq!(first, old, "the held handle saw the replacement");
    held.seek(SeekFrom::Start(0)).unwrap();
    let mut again = Vec::new();
    held.read_to_end(&mut again).unwrap();
    assert_eq!(again, old);
    assert_eq!(held.metadata().unwrap().ino(), ino_old);

    // The path names a different inode holding exactly the new content.
    let meta = std::fs::metadata(&path).unwrap();
    assert_ne!(meta.ino(), ino_old, "replaced in place, not by rename");
    assert_eq!(meta.len(), new.len() as u64);
    assert_eq!(std::fs::read(&path).unwrap(), new);
}

#[test]
fn while_the_new_file_is_written_the_path_names_the_old_complete_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("report.json");
    let old = content(3, 50_000);
    write_atomic_bytes(&path, &old).unwrap();
    let ino_old = std::fs::metadata(&path).unwrap().ino();
    let mut checks = 0;
    write_atomic(&path, |w| {
        for chunk in 0..20u8 {
            w.write_all(&content(chunk, 40_000))?;
            w.flush()?;
            // Mid-write: the path is still the whole old file, same inode.
            assert_eq!(std::fs::read(&path).unwrap(), old, "chunk {chunk}");
            assert_eq!(std::fs::metadata(&path).unwrap().ino(), ino_old);
            checks += 1;
        }
        Ok(())
    })
    .unwrap();
    assert_eq!(checks, 20);
    let expected: Vec<u8> = (0..20u8).flat_map(|c| content(c, 40_000)).collect();
    assert_eq!(std::fs::read(&path).unwrap(), expected);
}

#[test]
fn a_first_write_creates_nothing_at_the_path_until_it_is_complete() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fresh.csv");
    write_atomic(&path, |w| {
        w.write_all(b"t,x\n0,1\n")?;
        w.flush()?;
        assert!(!path.exists(), "a partial file appeared at the target path");
        w.write_all(b"1,2\n")
    })
    .unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"t,x\n0,1\n1,2\n");
}

#[test]
fn concurrent_readers_only_ever_see_complete_versions() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("series.txt");
    let versions: Vec<Vec<u8>> = (0..8u8)
        .map(|t| content(t * 17, 20_000 + 5_000 * t as usize))
        .collect();
    write_atomic_bytes(&path, &versions[0]).unwrap();
    let stop = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|s| {
        let reader = s.spawn(|| {
            let mut reads = 0usize;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) || reads == 0 {
                let got = std::fs::read(&path).unwrap();
                assert!(
                    versions.contains(&got),
                    "a reader saw a partial or mixed file of {} bytes",
                    got.len()
                );
                reads += 1;
            }
            reads
        });
        for round in 0..40 {
            let v = &versions[round % versions.len()];
            write_atomic(&path, |w| {
                for part in v.chunks(1000) {
                    w.write_all(part)?;
                    w.flush()?;
                }
                Ok(())
            })
            .unwrap();
        }
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        assert!(reader.join().unwrap() > 0);
    });
}
