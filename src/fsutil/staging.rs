//! Staging folders: a job's output files are written into a hidden folder and moved into the
//! destination folder together at the end ([`StagingDir`]).
//!
//! Two locks (advisory `flock` locks through `std::fs::File::lock`, released by the kernel when
//! their holder dies, whatever its PID namespace or host on shared storage that honours them):
//! - each staging folder holds a lock file that its job keeps locked while it lives, so the
//!   clean-up of folders left by killed jobs removes only folders whose lock it can take;
//! - the destination folder itself is locked while files are moved into it, so concurrent jobs
//!   into one folder commit one after another and the folder holds one job's whole set.

use std::fs::File;
use std::path::{Path, PathBuf};

use super::replace::replace_all;
use super::{io_error, unique_tag};
use crate::error::{Error, Result};

/// The prefix of every staging folder's name.
const STAGING_PREFIX: &str = ".sketchbody-tmp";
/// The prefix of a staging folder while it is being set up (before its lock is held); the
/// clean-up never looks at these.
const NEW_PREFIX: &str = ".sketchbody-new";
/// The lock file inside each staging folder.
const LOCK_NAME: &str = ".sketchbody-lock";

/// Removes staging folders in `dir` left by jobs that died before committing (killed runs):
/// entries named `.sketchbody-tmp-...` whose lock file exists and can be locked, so no live job
/// holds it. A folder without a lock file is left alone (it is not this version's). Errors are
/// ignored (another job may be cleaning the same folder).
fn remove_stale_staging(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let name = e.file_name();
        let ours = name.to_str().and_then(|n| n.strip_prefix(STAGING_PREFIX)).is_some_and(|r| r.starts_with('-'));
        if !ours || !e.file_type().is_ok_and(|t| t.is_dir()) {
            continue;
        }
        let Ok(lock) = File::open(e.path().join(LOCK_NAME)) else { continue };
        if lock.try_lock().is_ok() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Locks the folder `dest` (exclusive, waiting for other holders) and returns the open folder,
/// which holds the lock until dropped. When `dest` was replaced or removed while this waited,
/// the lock is taken again on what the path names now. Not available outside Unix (a folder
/// cannot be opened as a file there): `None`, no lock.
fn lock_folder(dest: &Path) -> Result<Option<File>> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let io = |source| Error::Io { path: dest.to_path_buf(), source };
        loop {
            std::fs::create_dir_all(dest).map_err(io)?;
            let f = File::open(dest).map_err(io)?;
            f.lock().map_err(io)?;
            let held = f.metadata().map_err(io)?;
            match std::fs::metadata(dest) {
                Ok(now) if (now.dev(), now.ino()) == (held.dev(), held.ino()) => return Ok(Some(f)),
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(io(e)),
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = dest;
        Ok(None)
    }
}

/// A folder of outputs written as a unit: files go into a hidden staging folder and
/// [`StagingDir::commit`] moves them into the destination, so a failed or cancelled job leaves
/// nothing of its own in it and the previous outputs as they were. Dropping an uncommitted
/// staging folder removes it and everything inside.
///
/// When the destination exists, the staging folder is created inside it (hidden,
/// `.sketchbody-tmp-PID-THREAD-N`), otherwise beside it (`.sketchbody-tmp-PID-THREAD-N-NAME`).
/// The job holds the lock file inside it until it is dropped; staging folders whose lock is
/// free (a killed job's) are removed by the next `new` that stages in the same place.
#[derive(Debug)]
pub struct StagingDir {
    tmp: PathBuf,
    dest: PathBuf,
    committed: bool,
    /// The staging folder's lock file, locked while this value lives (`None` where the file
    /// system has no locks: such a folder is then never removed by another job's clean-up).
    _lock: Option<File>,
}

impl StagingDir {
    /// Prepares a staging folder for `dest`, creating `dest`'s parent folders when missing.
    /// Errors ([`Error::Io`], naming the path): `dest` is a file, or a folder cannot be created
    /// (unwritable location, a file in the way).
    pub fn new(dest: &Path) -> Result<StagingDir> {
        let io = |path: &Path, source| Error::Io { path: path.to_path_buf(), source };
        let tag = unique_tag(STAGING_PREFIX);
        let (place, name) = if dest.exists() {
            if !dest.is_dir() {
                return Err(io_error(dest, std::io::ErrorKind::AlreadyExists, "exists and is not a folder".into()));
            }
            (dest.to_path_buf(), std::ffi::OsString::from(&tag))
        } else {
            let dest_name = dest
                .file_name()
                .ok_or_else(|| io_error(dest, std::io::ErrorKind::InvalidInput, "output folder has no name".into()))?;
            let parent = dest.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
            let mut n = std::ffi::OsString::from(&tag);
            n.push("-");
            n.push(dest_name);
            (parent.to_path_buf(), n)
        };
        remove_stale_staging(&place);
        // Set up under another prefix, so the clean-up never sees a staging folder before its
        // lock is held; the lock belongs to the file, so it survives the rename.
        let init = place.join(format!("{NEW_PREFIX}{}", &tag[STAGING_PREFIX.len()..]));
        std::fs::create_dir(&init).map_err(|e| io(&init, e))?;
        let tmp = place.join(name);
        let setup = (|| {
            let lock = File::create_new(init.join(LOCK_NAME))?;
            let lock = lock.lock().is_ok().then_some(lock);
            std::fs::rename(&init, &tmp)?;
            Ok(lock)
        })();
        match setup {
            Ok(lock) => Ok(StagingDir { tmp, dest: dest.to_path_buf(), committed: false, _lock: lock }),
            Err(e) => {
                let _ = std::fs::remove_dir_all(&init);
                Err(io(&init, e))
            }
        }
    }

    /// Where to write the output file `name` (inside the staging folder).
    pub fn path(&self, name: &str) -> PathBuf {
        self.tmp.join(name)
    }

    /// The destination folder.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Moves every staged file into the destination (created when missing), holding the
    /// destination's lock, so concurrent jobs into one folder commit one after another: the
    /// folder ends with the whole set of the last to commit, never a mix. Only regular files
    /// are replaced: when a destination entry of the same name is a symlink, a folder, a device
    /// or a FIFO, the commit fails ([`Error::Io`], "not a regular file") before anything is
    /// moved. When a move fails midway (an unreplaceable file), every file already replaced
    /// gets its previous version back, so the destination is as it was before the job, and the
    /// error names the file.
    pub fn commit(mut self) -> Result<()> {
        let created = !self.dest.exists();
        let lock = lock_folder(&self.dest)?;
        let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(&self.tmp)
            .map_err(|e| Error::Io { path: self.tmp.clone(), source: e })?
            .filter_map(|e| e.ok().map(|e| e.file_name()))
            .filter(|n| n != LOCK_NAME)
            .collect();
        names.sort();
        let moves: Vec<(PathBuf, PathBuf)> = names.iter().map(|n| (self.tmp.join(n), self.dest.join(n))).collect();
        let result = replace_all(&moves);
        if result.is_err() && created {
            // Only when still empty: another job may have committed into it meanwhile.
            let _ = std::fs::remove_dir(&self.dest);
        }
        drop(lock);
        result?;
        let _ = std::fs::remove_dir_all(&self.tmp);
        self.committed = true;
        Ok(())
    }
}

impl Drop for StagingDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fsutil::write_atomic;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("skb-staging-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(d).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    /// Fault matrix (issue 20 item 5): a symlink where an output goes fails the commit before
    /// anything moves (the link and its target stay as they were), and a destination folder
    /// created by another job after `new` is merged into instead of failing the commit.
    #[test]
    fn commit_refuses_non_regular_targets_and_merges_into_a_folder_made_meanwhile() {
        let root = scratch("commit");
        let dest = root.join("out");
        std::fs::create_dir(&dest).unwrap();
        let target = root.join("elsewhere.glb");
        std::fs::write(&target, b"keep").unwrap();
        std::os::unix::fs::symlink(&target, dest.join("b.glb")).unwrap();
        let s = StagingDir::new(&dest).unwrap();
        write_atomic(&s.path("a.json"), b"1").unwrap();
        write_atomic(&s.path("b.glb"), b"2").unwrap();
        let e = s.commit().unwrap_err().to_string();
        assert!(e.contains("not a regular file") && e.contains("b.glb"), "{e}");
        assert!(std::fs::symlink_metadata(dest.join("b.glb")).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
        assert_eq!(names(&dest), ["b.glb"], "a.json was not moved in and the staging folder is gone");
        // Two jobs staging the same new folder: both commit, the later one's files win.
        let fresh = root.join("fresh");
        let first = StagingDir::new(&fresh).unwrap();
        let second = StagingDir::new(&fresh).unwrap();
        write_atomic(&first.path("x.txt"), b"first").unwrap();
        write_atomic(&second.path("x.txt"), b"second").unwrap();
        write_atomic(&second.path("y.txt"), b"second").unwrap();
        first.commit().unwrap();
        second.commit().unwrap();
        assert_eq!(std::fs::read(fresh.join("x.txt")).unwrap(), b"second");
        assert_eq!(names(&fresh), ["x.txt", "y.txt"]);
        assert_eq!(names(&root), ["elsewhere.glb", "fresh", "out"], "no staging left");
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn staging_commits_whole_or_leaves_nothing() {
        let root = scratch("whole");
        // New destination: nothing there before the commit.
        let dest = root.join("a/out");
        let s = StagingDir::new(&dest).unwrap();
        write_atomic(&s.path("x.txt"), b"1").unwrap();
        assert!(!dest.exists());
        s.commit().unwrap();
        assert_eq!(names(&dest), ["x.txt"]);
        // Existing destination: files moved in, staging folder gone.
        let s = StagingDir::new(&dest).unwrap();
        write_atomic(&s.path("y.txt"), b"2").unwrap();
        s.commit().unwrap();
        assert_eq!(names(&dest), ["x.txt", "y.txt"]);
        // Dropped without commit: nothing left anywhere.
        let s = StagingDir::new(&root.join("b")).unwrap();
        write_atomic(&s.path("z.txt"), b"3").unwrap();
        drop(s);
        assert_eq!(names(&root), ["a"]);
        // A file in the way is an I/O error naming it.
        assert!(matches!(StagingDir::new(&dest.join("x.txt")), Err(Error::Io { .. })));
        assert!(matches!(StagingDir::new(&dest.join("x.txt/sub")), Err(Error::Io { .. })));
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// Finding 7 of the first audit and issue 52 finding 3: the clean-up judges a staging folder
    /// by its lock, not its PID. A killed job's folder (lock free) is removed inside and beside
    /// the destination, even when its PID is this process's own (a PID reused, or from another
    /// PID namespace); a folder whose lock is held is kept even when its PID is not running
    /// here (a job in a container or on another host); a folder without a lock file is kept.
    #[test]
    fn stale_staging_folders_are_judged_by_their_lock() {
        let d = scratch("stale");
        let dest = d.join("out");
        std::fs::create_dir(&dest).unwrap();
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let folder = |place: &Path, pid: u32, n: u32, lock: bool| {
            let f = place.join(format!("{STAGING_PREFIX}-{pid}-1-{n}"));
            std::fs::create_dir(&f).unwrap();
            std::fs::write(f.join("half.glb"), b"half").unwrap();
            if lock {
                std::fs::write(f.join(LOCK_NAME), b"").unwrap();
            }
            f
        };
        let stale = folder(&dest, dead, 0, true);
        let stale_own_pid = folder(&dest, std::process::id(), 1, true);
        let live_elsewhere = folder(&dest, dead, 2, true);
        let held = File::open(live_elsewhere.join(LOCK_NAME)).unwrap();
        held.lock().unwrap();
        let legacy = folder(&dest, dead, 3, false);
        let beside = d.join(format!("{STAGING_PREFIX}-{dead}-1-4-new"));
        std::fs::create_dir(&beside).unwrap();
        std::fs::write(beside.join(LOCK_NAME), b"").unwrap();
        let s = StagingDir::new(&dest).unwrap();
        assert!(!stale.exists() && !stale_own_pid.exists(), "folders with a free lock removed");
        assert!(live_elsewhere.join("half.glb").exists(), "a held lock keeps the folder, whatever its PID");
        assert!(legacy.exists(), "a folder without a lock file is not judged");
        // The new job's own folder is locked: another clean-up in the same place keeps it.
        let t = StagingDir::new(&dest).unwrap();
        assert!(s.tmp.join(LOCK_NAME).exists() && t.tmp.exists());
        drop((s, t));
        let s = StagingDir::new(&d.join("new")).unwrap();
        assert!(!beside.exists(), "stale staging beside the destination removed");
        drop(s);
        drop(held);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Issue 52 finding 8: jobs committing into one new folder at the same time leave one job's
    /// whole set, never files of several. Three threads, each committing 20 files holding its
    /// own number, 10 rounds (each round a fresh folder; the old commit mixed them in the first).
    #[test]
    fn concurrent_commits_into_one_folder_leave_one_whole_set() {
        let d = scratch("concurrent");
        for round in 0..10 {
            let dest = d.join(format!("out{round}"));
            let barrier = std::sync::Barrier::new(3);
            std::thread::scope(|sc| {
                for job in 0..3u8 {
                    let (dest, barrier) = (&dest, &barrier);
                    sc.spawn(move || {
                        let s = StagingDir::new(dest).unwrap();
                        for k in 0..20 {
                            write_atomic(&s.path(&format!("f{k:02}")), &[job]).unwrap();
                        }
                        barrier.wait();
                        s.commit().unwrap();
                    });
                }
            });
            let got: Vec<u8> = (0..20).map(|k| std::fs::read(dest.join(format!("f{k:02}"))).unwrap()[0]).collect();
            assert!(got.iter().all(|&j| j == got[0]), "round {round}: a mixed set {got:?}");
            assert_eq!(names(&dest).len(), 20, "round {round}: nothing else in the folder");
        }
        assert_eq!(names(&d).len(), 10, "no staging folder left");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
