//! Atomic file writes: every file nurbspring writes goes through [`write_atomic`].
//!
//! The content is written to a temporary file in the target's folder (a unique name
//! `.{name}.tmp-{pid}-{counter}`), flushed and synced to disk, then renamed over the target. A
//! reader therefore sees either the old file or the complete new one, never a half-written file,
//! even if the program is interrupted. On any error (including a panic inside the writer
//! closure) the temporary file is removed and an existing target is left untouched.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::OutputError;

/// Distinguishes temporary files of concurrent writes within one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Temporary files being written now, so that a process ended by a signal can remove them
/// ([`remove_pending`]).
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Removes the temporary files of writes in progress: for a process about to exit on a signal,
/// so that no `.NAME.tmp-*` file outlives it (a staged output folder is removed as a whole
/// anyway; this matters for single files written in place).
pub fn remove_pending() {
    if let Ok(list) = PENDING.lock() {
        for p in list.iter() {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// Removes the temporary file when dropped, unless disarmed after a successful rename.
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl TempGuard {
    fn new(path: PathBuf) -> Self {
        if let Ok(mut list) = PENDING.lock() {
            list.push(path.clone());
        }
        Self { path, armed: true }
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if self.armed {
            let _ = std::fs::remove_file(&self.path);
        }
        if let Ok(mut list) = PENDING.lock()
            && let Some(i) = list.iter().position(|p| *p == self.path)
        {
            list.swap_remove(i);
        }
    }
}

/// The folder a file lives in (`.` for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Creates a fresh temporary file next to `path`; retries on the (unlikely) name collision.
fn create_temp(path: &Path) -> Result<(File, PathBuf), OutputError> {
    let name = path
        .file_name()
        .ok_or_else(|| OutputError::invalid(path, "the path has no file name"))?
        .to_string_lossy()
        .into_owned();
    let dir = parent_dir(path);
    let pid = std::process::id();
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.tmp-{pid}-{n}"));
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((f, tmp)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(OutputError::io(path, e)),
        }
    }
}

/// Writes a file atomically: `write` fills a buffered writer on a temporary file in the same
/// folder, which is then flushed, synced and renamed over `path`.
///
/// If `write` returns an error (or panics), or any step after it fails, the temporary file is
/// deleted and an existing file at `path` keeps its old content.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("hello.txt");
/// nurbspring_io::atomic::write_atomic(&path, |w| writeln!(w, "hello")).unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "hello\n");
/// ```
pub fn write_atomic<F>(path: impl AsRef<Path>, write: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    let path = path.as_ref();
    let (file, tmp) = create_temp(path)?;
    let mut guard = TempGuard::new(tmp);
    let mut writer = BufWriter::new(file);
    write(&mut writer).map_err(|e| OutputError::io(path, e))?;
    writer.flush().map_err(|e| OutputError::io(path, e))?;
    let file = writer
        .into_inner()
        .map_err(|e| OutputError::io(path, e.into_error()))?;
    file.sync_all().map_err(|e| OutputError::io(path, e))?;
    drop(file);
    std::fs::rename(&guard.path, path).map_err(|e| OutputError::io(path, e))?;
    guard.armed = false;
    // Make the rename itself durable where the platform allows syncing a directory.
    if let Ok(dir) = File::open(parent_dir(path)) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically (see [`write_atomic`]).
pub fn write_atomic_bytes(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic(path, |w| w.write_all(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic_bytes(&p, b"one").unwrap();
        write_atomic_bytes(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(entries(dir.path()), vec!["a.txt".to_string()]);
    }

    #[test]
    fn failing_writer_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("b.txt");
        let err = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("disk on fire"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("disk on fire"), "{err}");
        assert!(err.to_string().contains("b.txt"), "{err}");
        assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
    }

    #[test]
    fn failing_writer_keeps_existing_target() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.txt");
        write_atomic_bytes(&p, b"original").unwrap();
        let r = write_atomic(&p, |w| {
            w.write_all(&[b'x'; 100_000])?;
            Err(std::io::Error::other("stop"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"original");
        assert_eq!(entries(dir.path()), vec!["c.txt".to_string()]);
    }

    #[test]
    fn panicking_writer_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("d.txt");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic(&p, |_| panic!("boom"));
        });
        assert!(r.is_err());
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn missing_folder_is_an_io_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/e.txt");
        let err = write_atomic_bytes(&p, b"x").unwrap_err();
        assert!(matches!(err, OutputError::Io { .. }));
        assert!(err.to_string().contains("e.txt"));
    }

    #[test]
    fn concurrent_writes_use_distinct_temp_files() {
        let dir = tempfile::tempdir().unwrap();
        std::thread::scope(|s| {
            for t in 0..4 {
                let p = dir.path().join(format!("f{t}.txt"));
                s.spawn(move || {
                    for i in 0..20 {
                        write_atomic_bytes(&p, format!("{t}-{i}").as_bytes()).unwrap();
                    }
                });
            }
        });
        assert_eq!(entries(dir.path()).len(), 4);
        assert_eq!(
            std::fs::read_to_string(dir.path().join("f2.txt")).unwrap(),
            "2-19"
        );
    }

    /// The temporary names of this test's writes in progress (`.NAME.tmp-*` in `dir`).
    fn temps(dir: &Path, name: &str) -> Vec<PathBuf> {
        let prefix = format!(".{name}.tmp-");
        entries(dir)
            .into_iter()
            .filter(|e| e.starts_with(&prefix))
            .map(|e| dir.join(e))
            .collect()
    }

    #[test]
    fn the_temporary_file_lies_in_the_target_folder() {
        // A temporary anywhere else (the working folder, say) would make the rename a copy
        // across file systems, or fail, and leave strays where nobody looks.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.txt");
        let mut seen = Vec::new();
        write_atomic(&p, |w| {
            seen = temps(dir.path(), "g.txt");
            w.write_all(b"x")
        })
        .unwrap();
        assert_eq!(seen.len(), 1, "{:?}", entries(dir.path()));
        let tmp = seen[0].file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            tmp.starts_with(&format!(".g.txt.tmp-{}-", std::process::id())),
            "{tmp}"
        );
        assert!(
            !Path::new(&tmp).exists(),
            "a stray {tmp} in the working folder"
        );
    }

    #[test]
    fn parent_dir_is_the_containing_folder() {
        assert_eq!(parent_dir(Path::new("out/a/f.csv")), PathBuf::from("out/a"));
        assert_eq!(parent_dir(Path::new("/f.csv")), PathBuf::from("/"));
        assert_eq!(parent_dir(Path::new("f.csv")), PathBuf::from("."));
    }

    #[test]
    fn a_finished_write_leaves_the_pending_list() {
        // The signal handler's list must hold only writes in progress: a finished or failed
        // write takes its own temporary off it (and only its own).
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("h.txt");
        let mut during = Vec::new();
        write_atomic(&p, |w| {
            during = temps(dir.path(), "h.txt");
            assert!(PENDING.lock().unwrap().contains(&during[0]));
            w.write_all(b"x")
        })
        .unwrap();
        assert!(!PENDING.lock().unwrap().contains(&during[0]));
        let r = write_atomic(&p, |_| {
            during = temps(dir.path(), "h.txt");
            Err(std::io::Error::other("stop"))
        });
        assert!(r.is_err());
        assert!(!PENDING.lock().unwrap().contains(&during[0]));
        // Another write's entry is left alone when one finishes.
        let other = dir.path().join(".other.tmp-test");
        let guard = TempGuard::new(other.clone());
        write_atomic_bytes(&p, b"y").unwrap();
        assert!(PENDING.lock().unwrap().contains(&other));
        drop(guard);
        assert!(!PENDING.lock().unwrap().contains(&other));
    }

    #[test]
    fn a_temporary_name_in_use_is_skipped() {
        // A leftover temporary of an earlier process with the same pid and counter must not
        // fail the write: the next name is tried. The next thousand names are taken here (the
        // counter is shared with the tests running beside this one).
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("k.txt");
        let first = COUNTER.load(Ordering::Relaxed);
        let pid = std::process::id();
        for n in first..first + 1000 {
            std::fs::write(dir.path().join(format!(".k.txt.tmp-{pid}-{n}")), b"stale").unwrap();
        }
        write_atomic_bytes(&p, b"fresh").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"fresh");
        assert_eq!(entries(dir.path()).len(), 1001);
    }
}
