//! Output folders as one unit: a run writes into a fresh sibling folder ([`StagedDir`]) that is
//! swapped in for the target only when the run is complete.
//!
//! A folder therefore holds exactly one run's files: no stale frames of a longer earlier run, no
//! new `msm.json` beside an old `report.md`. A run that fails or is interrupted leaves the
//! previous run intact. The swap is one `renameat2(RENAME_EXCHANGE)` on Linux (atomic: a reader
//! sees the old folder or the new one); elsewhere, or on file systems without it, two renames with
//! the old folder parked under a recognisable name that the next run restores if the process
//! died between them.
//!
//! Names, for a target `out` (all siblings of it):
//! - `.out.staging-{pid}-{n}`: a run in progress (or killed);
//! - `.out.old-{pid}-{n}`: a previous run being replaced;
//! - `out.interrupted`: what an interrupted run kept, when the caller asks for it
//!   ([`StagedDir::keep_interrupted`]).
//!
//! Leftovers of processes that are no longer alive are removed (or, for a parked old folder whose
//! target is missing, restored) by the next [`StagedDir::create`] for the same target.
//!
//! Every folder nurbspring writes carries the marker file [`MARKER`]. An existing non-empty
//! target without it is refused: nurbspring never replaces a folder it did not write.
//!
//! ```
//! use nurbspring_io::folder::StagedDir;
//! # let dir = tempfile::tempdir().unwrap();
//! let target = dir.path().join("run");
//! let staged = StagedDir::create(&target).unwrap();
//! std::fs::write(staged.path().join("a.txt"), "first").unwrap();
//! staged.commit().unwrap();
//! // A second run that fails leaves the first one as it was.
//! let staged = StagedDir::create(&target).unwrap();
//! std::fs::write(staged.path().join("b.txt"), "second").unwrap();
//! drop(staged);
//! assert!(target.join("a.txt").exists() && !target.join("b.txt").exists());
//! ```

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::OutputError;

/// The file that marks a folder as written by nurbspring.
pub const MARKER: &str = ".nurbspring-run";

static COUNTER: AtomicU64 = AtomicU64::new(0);
static COMMITTING: AtomicBool = AtomicBool::new(false);
/// Staging folders of this process not yet committed or dropped ([`remove_pending`]).
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Removes the staging folders of runs in progress: for a process about to exit on a signal
/// (the target folders keep their previous runs).
pub fn remove_pending() {
    if let Ok(list) = PENDING.lock() {
        for p in list.iter() {
            let _ = std::fs::remove_dir_all(p);
        }
    }
}

fn forget(path: &Path) {
    if let Ok(mut list) = PENDING.lock()
        && let Some(i) = list.iter().position(|p| p == path)
    {
        list.swap_remove(i);
    }
}

/// True while a [`StagedDir::commit`] is swapping folders: a signal handler that would end the
/// process at once should wait for it (the swap takes microseconds).
pub fn committing() -> bool {
    COMMITTING.load(Ordering::SeqCst)
}

/// A run's output folder in the making; see the [module documentation](self).
#[derive(Debug)]
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    done: bool,
}

impl StagedDir {
    /// Prepares a fresh staging folder beside `target` (creating `target`'s parents), after
    /// removing leftovers of dead runs for the same target.
    ///
    /// Refuses a `target` that exists and is not a folder, or is a non-empty folder without
    /// [`MARKER`] (the error says which entry).
    pub fn create(target: impl AsRef<Path>) -> Result<StagedDir, OutputError> {
        let target = target.as_ref().to_path_buf();
        let name = target
            .file_name()
            .filter(|n| *n != "." && *n != "..")
            .ok_or_else(|| {
                OutputError::invalid(
                    &target,
                    "an output folder needs a name of its own (not `.`, `..` or `/`)",
                )
            })?
            .to_string_lossy()
            .into_owned();
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(|e| OutputError::io(&parent, e))?;
        clean_leftovers(&parent, &name, &target)?;
        check_replaceable(&target)?;
        let pid = std::process::id();
        loop {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let staging = parent.join(format!(".{name}.staging-{pid}-{n}"));
            match std::fs::create_dir(&staging) {
                Ok(()) => {
                    if let Ok(mut list) = PENDING.lock() {
                        list.push(staging.clone());
                    }
                    let dir = StagedDir {
                        target,
                        staging,
                        done: false,
                    };
                    let marker = dir.staging.join(MARKER);
                    std::fs::write(&marker, "written by nurbspring\n")
                        .map_err(|e| OutputError::io(&marker, e))?;
                    return Ok(dir);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(OutputError::io(&staging, e)),
            }
        }
    }

    /// The folder to write into.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The folder the run will be in once committed.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Swaps the staged folder in for the target and removes the previous run.
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        COMMITTING.store(true, Ordering::SeqCst);
        let result = self.swap_in(&self.target.clone());
        COMMITTING.store(false, Ordering::SeqCst);
        result?;
        self.done = true;
        Ok(self.target.clone())
    }

    /// Keeps what an interrupted run wrote as `{target}.interrupted` (replacing an earlier one),
    /// leaving the target untouched, and returns that path.
    pub fn keep_interrupted(mut self) -> Result<PathBuf, OutputError> {
        let mut name = self.target.as_os_str().to_owned();
        name.push(".interrupted");
        let kept = PathBuf::from(name);
        check_replaceable(&kept)?;
        COMMITTING.store(true, Ordering::SeqCst);
        let result = self.swap_in(&kept);
        COMMITTING.store(false, Ordering::SeqCst);
        result?;
        self.done = true;
        Ok(kept)
    }

    /// Puts the staging folder at `to`, replacing a folder there.
    fn swap_in(&self, to: &Path) -> Result<(), OutputError> {
        if !to.exists() {
            return std::fs::rename(&self.staging, to).map_err(|e| OutputError::io(to, e));
        }
        if exchange(&self.staging, to).is_ok() {
            // The staging name now holds the previous run.
            let _ = std::fs::remove_dir_all(&self.staging);
            return Ok(());
        }
        let old = self.staging.with_file_name(
            self.staging
                .file_name()
                .map(|n| n.to_string_lossy().replacen(".staging-", ".old-", 1))
                .unwrap_or_default(),
        );
        std::fs::rename(to, &old).map_err(|e| OutputError::io(to, e))?;
        if let Err(e) = std::fs::rename(&self.staging, to) {
            let _ = std::fs::rename(&old, to);
            return Err(OutputError::io(to, e));
        }
        let _ = std::fs::remove_dir_all(&old);
        Ok(())
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
        forget(&self.staging);
    }
}

/// Atomically exchanges two existing paths.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

/// Whether the process `pid` is alive (on other systems than Unix: assumed alive).
fn alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        if pid == std::process::id() {
            return true;
        }
        let Some(pid) = i32::try_from(pid)
            .ok()
            .and_then(rustix::process::Pid::from_raw)
        else {
            return false;
        };
        match rustix::process::test_kill_process(pid) {
            Ok(()) => true,
            Err(e) => e == rustix::io::Errno::PERM,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

/// Removes staging folders of dead runs for `name` in `parent`, and restores a parked old folder
/// whose swap was cut short (the target missing).
fn clean_leftovers(parent: &Path, name: &str, target: &Path) -> Result<(), OutputError> {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return Ok(());
    };
    let staging = format!(".{name}.staging-");
    let old = format!(".{name}.old-");
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let (rest, is_old) = if let Some(r) = file.strip_prefix(&staging) {
            (r, false)
        } else if let Some(r) = file.strip_prefix(&old) {
            (r, true)
        } else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if alive(pid) {
            continue;
        }
        let path = entry.path();
        if is_old && !target.exists() {
            std::fs::rename(&path, target).map_err(|e| OutputError::io(target, e))?;
        } else {
            let _ = std::fs::remove_dir_all(&path);
        }
    }
    Ok(())
}

/// Refuses a path nurbspring may not replace: not a folder, or a non-empty folder it did not
/// write.
fn check_replaceable(target: &Path) -> Result<(), OutputError> {
    let Ok(meta) = std::fs::symlink_metadata(target) else {
        return Ok(());
    };
    if !meta.is_dir() {
        return Err(OutputError::invalid(
            target,
            "exists and is not a folder; give a new or empty folder",
        ));
    }
    if target.join(MARKER).exists() {
        return Ok(());
    }
    let mut entries = std::fs::read_dir(target).map_err(|e| OutputError::io(target, e))?;
    if let Some(Ok(entry)) = entries.next() {
        return Err(OutputError::invalid(
            target,
            format!(
                "holds files nurbspring did not write (such as {:?}), so it will not replace it; give a new or empty folder, or one an earlier nurbspring run wrote",
                entry.file_name()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commit_replaces_the_whole_folder() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        let s = StagedDir::create(&target).unwrap();
        for i in 0..5 {
            std::fs::write(s.path().join(format!("frame_{i}.vtu")), "x").unwrap();
        }
        s.commit().unwrap();
        let s = StagedDir::create(&target).unwrap();
        std::fs::write(s.path().join("frame_0.vtu"), "y").unwrap();
        s.commit().unwrap();
        let mut names: Vec<_> = std::fs::read_dir(&target)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        assert_eq!(names, [MARKER, "frame_0.vtu"]);
        assert_eq!(
            std::fs::read_to_string(target.join("frame_0.vtu")).unwrap(),
            "y"
        );
        // Nothing else beside the target.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn the_swap_keeps_the_inode_of_the_new_run() {
        // The committed folder is the staging folder itself (renamed), not a copy.
        use std::os::unix::fs::MetadataExt;
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        StagedDir::create(&target).unwrap().commit().unwrap();
        let s = StagedDir::create(&target).unwrap();
        let ino = std::fs::metadata(s.path()).unwrap().ino();
        let old_ino = std::fs::metadata(&target).unwrap().ino();
        s.commit().unwrap();
        let now = std::fs::metadata(&target).unwrap().ino();
        assert_eq!(now, ino);
        assert_ne!(now, old_ino);
    }

    #[test]
    fn refuses_folders_it_did_not_write() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scene.toml"), "").unwrap();
        let e = StagedDir::create(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains("scene.toml") && e.contains("did not write"),
            "{e}"
        );
        let file = dir.path().join("scene.toml");
        let e = StagedDir::create(&file).unwrap_err().to_string();
        assert!(e.contains("not a folder"), "{e}");
        assert!(StagedDir::create(".").is_err());
        // An empty folder is fine, and left as the only entry.
        let empty = dir.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        StagedDir::create(&empty).unwrap().commit().unwrap();
        assert!(empty.join(MARKER).exists());
    }

    #[test]
    fn leftovers_of_dead_runs_are_removed_and_cut_swaps_restored() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        // pid 0x7fff_fff0 is not a running process.
        let dead = dir.path().join(".out.staging-2147483632-0");
        std::fs::create_dir(&dead).unwrap();
        let live = dir
            .path()
            .join(format!(".out.staging-{}-999", std::process::id()));
        std::fs::create_dir(&live).unwrap();
        let parked = dir.path().join(".out.old-2147483632-1");
        std::fs::create_dir(&parked).unwrap();
        std::fs::write(parked.join(MARKER), "").unwrap();
        std::fs::write(parked.join("msm.json"), "{}").unwrap();
        let s = StagedDir::create(&target).unwrap();
        assert!(!dead.exists() && live.exists() && !parked.exists());
        // The parked run was restored as the target, and stays until the new one commits.
        assert!(target.join("msm.json").exists());
        drop(s);
        assert!(target.join("msm.json").exists());
    }

    #[test]
    fn interrupted_runs_are_kept_beside_the_target() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        let s = StagedDir::create(&target).unwrap();
        std::fs::write(s.path().join("a"), "1").unwrap();
        s.commit().unwrap();
        for round in 0..2 {
            let s = StagedDir::create(&target).unwrap();
            std::fs::write(s.path().join("partial"), round.to_string()).unwrap();
            let kept = s.keep_interrupted().unwrap();
            assert_eq!(kept, dir.path().join("out.interrupted"));
            assert_eq!(
                std::fs::read_to_string(kept.join("partial")).unwrap(),
                round.to_string()
            );
        }
        assert!(target.join("a").exists() && !target.join("partial").exists());
    }
}
