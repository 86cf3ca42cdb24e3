//! Replacing a set of files as a unit: every staged file is moved over its target, and when
//! one move fails every target already replaced gets its previous file back, so a failed job
//! leaves the previous outputs exactly as they were (same inode, contents and times). Used by
//! [`StagingDir::commit`](super::StagingDir::commit) and [`OutputSet`] (outputs in several
//! folders, such as `sketchbody body --out a.obj --preview b.png`).

use std::path::{Path, PathBuf};

use super::{io_error, unique_tag, write_atomic};
use crate::error::{Error, Result};

/// The error for an existing target that is not a regular file.
pub(super) fn not_regular(path: &Path) -> Error {
    io_error(
        path,
        std::io::ErrorKind::InvalidInput,
        "exists and is not a regular file (symlinks, devices and folders are never replaced)".into(),
    )
}

/// Whether `path` exists (not following a symlink at it); an existing entry that is not a
/// regular file is an error.
pub(super) fn check_replaceable(path: &Path) -> Result<bool> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_file() => Ok(true),
        Ok(_) => Err(not_regular(path)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(Error::Io { path: path.to_path_buf(), source: e }),
    }
}

/// A hidden sibling of `path` no other call uses: `.NAME.TAG-PID-THREAD-N`.
pub(super) fn sibling(path: &Path, tag: &str) -> Result<PathBuf> {
    let name = path
        .file_name()
        .ok_or_else(|| io_error(path, std::io::ErrorKind::InvalidInput, "output path has no file name".into()))?;
    let mut t = std::ffi::OsString::from(".");
    t.push(name);
    t.push(unique_tag(tag));
    Ok(path.with_file_name(t))
}

/// One step done by [`replace_all`], for the rollback.
struct Done {
    target: PathBuf,
    backup: Option<PathBuf>,
    staged: PathBuf,
}

/// Moves each `(staged, target)` file over its target, in order. Every target must be absent
/// or a regular file (checked for all before anything moves). A target that exists is first
/// renamed to a hidden backup beside it; the backups are removed once every file is in place.
/// On the first failure the files already moved go back to their staged paths and the backups
/// back to their targets, and the error names the path that failed. Staged and target paths
/// of a pair must be on one file system (renames).
pub(super) fn replace_all(moves: &[(PathBuf, PathBuf)]) -> Result<()> {
    for (_, target) in moves {
        check_replaceable(target)?;
    }
    let mut done: Vec<Done> = Vec::with_capacity(moves.len());
    let mut failure = None;
    for (staged, target) in moves {
        let step = (|| {
            let backup = if check_replaceable(target)? {
                let b = sibling(target, ".bak")?;
                std::fs::rename(target, &b).map_err(|e| Error::Io { path: target.clone(), source: e })?;
                Some(b)
            } else {
                None
            };
            if let Err(e) = std::fs::rename(staged, target) {
                if let Some(b) = &backup {
                    let _ = std::fs::rename(b, target);
                }
                return Err(Error::Io { path: target.clone(), source: e });
            }
            Ok(Done { target: target.clone(), backup, staged: staged.clone() })
        })();
        match step {
            Ok(d) => done.push(d),
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
    }
    if let Some(e) = failure {
        for d in done.iter().rev() {
            let _ = std::fs::rename(&d.target, &d.staged);
            if let Some(b) = &d.backup {
                let _ = std::fs::rename(b, &d.target);
            }
        }
        return Err(e);
    }
    for b in done.iter().filter_map(|d| d.backup.as_ref()) {
        let _ = std::fs::remove_file(b);
    }
    Ok(())
}

/// Output files in any folders, written as a unit: each is written to a hidden staging file
/// beside its target ([`OutputSet::stage`]) and [`OutputSet::commit`] moves them all into place,
/// or, when one cannot be, puts back every file it replaced. Dropping an uncommitted set removes
/// its staging files, so a failed command leaves none of its outputs.
#[derive(Debug, Default)]
pub struct OutputSet {
    moves: Vec<(PathBuf, PathBuf)>,
    committed: bool,
}

impl OutputSet {
    /// An empty set.
    pub fn new() -> OutputSet {
        OutputSet::default()
    }

    /// Registers the output `target` and returns the staging path to write it to (any writer;
    /// it is moved over `target` at commit). Errors ([`Error::Io`], naming `target`): `target`
    /// exists and is not a regular file (a symlink, device such as `/dev/full`, FIFO or
    /// folder), has no file name, or is already in the set.
    pub fn stage(&mut self, target: &Path) -> Result<PathBuf> {
        check_replaceable(target)?;
        if self.moves.iter().any(|(_, t)| t == target) {
            return Err(io_error(target, std::io::ErrorKind::InvalidInput, "named twice as an output".into()));
        }
        let staged = sibling(target, ".stage")?;
        self.moves.push((staged.clone(), target.to_path_buf()));
        Ok(staged)
    }

    /// [`OutputSet::stage`] `target` and write `bytes` to its staging path.
    pub fn write(&mut self, target: &Path, bytes: &[u8]) -> Result<()> {
        let staged = self.stage(target)?;
        write_atomic(&staged, bytes)
    }

    /// Moves every staged file over its target (see the type's doc). Errors: a target that is
    /// not a regular file, a staged file that was not written, a failed rename ([`Error::Io`]).
    pub fn commit(mut self) -> Result<()> {
        replace_all(&self.moves)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.committed {
            for (staged, _) in &self.moves {
                let _ = std::fs::remove_file(staged);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("skb-replace-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn listing(d: &Path) -> Vec<(String, Vec<u8>)> {
        let mut v: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .flatten()
            .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap_or_default()))
            .collect();
        v.sort();
        v
    }

    /// Issue 52 finding 2: when the third of three moves fails, the two targets already replaced
    /// get their previous files back (same inode), the staged files are where they were, and no
    /// backup is left; a successful pass replaces all three and leaves no backup.
    #[test]
    fn a_failed_move_puts_every_previous_file_back() {
        use std::os::unix::fs::MetadataExt;
        let d = scratch("rollback");
        let (old, new) = (d.join("old"), d.join("new"));
        std::fs::create_dir_all(&old).unwrap();
        std::fs::create_dir_all(&new).unwrap();
        for n in ["a", "b", "c"] {
            std::fs::write(old.join(n), format!("old {n}")).unwrap();
        }
        std::fs::write(new.join("a"), "new a").unwrap();
        std::fs::write(new.join("b"), "new b").unwrap();
        let inode = std::fs::metadata(old.join("a")).unwrap().ino();
        let before = listing(&old);
        // "c" was never staged: its move fails after "a" and "b" were replaced.
        let moves: Vec<_> = ["a", "b", "c"].iter().map(|n| (new.join(n), old.join(n))).collect();
        let e = replace_all(&moves).unwrap_err().to_string();
        assert!(e.contains("c"), "{e}");
        assert_eq!(listing(&old), before, "previous files back, no backup left");
        assert_eq!(std::fs::metadata(old.join("a")).unwrap().ino(), inode, "the very same file");
        assert_eq!(listing(&new), [("a".into(), b"new a".to_vec()), ("b".into(), b"new b".to_vec())]);
        std::fs::write(new.join("c"), "new c").unwrap();
        replace_all(&moves).unwrap();
        let got: Vec<_> = listing(&old).into_iter().map(|(n, b)| (n, String::from_utf8(b).unwrap())).collect();
        assert_eq!(got, [("a".into(), "new a".into()), ("b".into(), "new b".into()), ("c".into(), "new c".into())]);
        assert!(listing(&new).is_empty());
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Issue 52 finding 9: an output set with one unwritable target (`/dev/full`, a folder)
    /// writes none of its files; dropped uncommitted, it leaves no staging file.
    #[test]
    fn an_output_set_commits_all_or_nothing() {
        let d = scratch("set");
        let (a, b) = (d.join("a.obj"), d.join("sub/b.png"));
        std::fs::create_dir_all(d.join("sub")).unwrap();
        std::fs::write(&a, "old a").unwrap();
        let mut set = OutputSet::new();
        set.write(&a, b"new a").unwrap();
        let e = set.stage(Path::new("/dev/full")).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        drop(set);
        assert_eq!(listing(&d), [("a.obj".into(), b"old a".to_vec()), ("sub".into(), vec![])]);
        let mut set = OutputSet::new();
        set.write(&a, b"new a").unwrap();
        assert!(set.stage(&a).is_err(), "one target named twice");
        set.write(&b, b"new b").unwrap();
        assert!(!b.exists(), "nothing in place before the commit");
        set.commit().unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"new a");
        assert_eq!(listing(&d.join("sub")), [("b.png".into(), b"new b".to_vec())]);
        // A target turned into a folder after staging: the commit fails and changes nothing.
        let mut set = OutputSet::new();
        set.write(&a, b"newer a").unwrap();
        set.write(&b, b"newer b").unwrap();
        std::fs::remove_file(&b).unwrap();
        std::fs::create_dir(&b).unwrap();
        assert!(set.commit().unwrap_err().to_string().contains("not a regular file"));
        assert_eq!(std::fs::read(&a).unwrap(), b"new a");
        assert_eq!(listing(&d).len(), 2, "no staging file left");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
