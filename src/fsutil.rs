//! File-system helpers: atomic writes (temporary file in the same directory, then rename) and
//! staging folders whose files appear in their destination together or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Writes `bytes` to `path` atomically: a sibling temporary file is written, flushed and renamed
/// over `path`. On failure the temporary file is removed and `path` is untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let io_err = |source| Error::Io { path: path.to_path_buf(), source };
    let file_name = path
        .file_name()
        .ok_or_else(|| io_err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "output path has no file name")))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(file_name);
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp: PathBuf = path.with_file_name(tmp_name);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io_err(e));
    }
    Ok(())
}

/// A folder of outputs written as a unit: files go into a hidden temporary folder and
/// [`StagingDir::commit`] moves them into the destination, so a failed or cancelled job leaves
/// nothing in it. Dropping an uncommitted staging folder removes it and everything inside.
///
/// When the destination does not exist, the temporary folder is created beside it and renamed
/// onto it (one atomic step); when it exists, the temporary folder is created inside it (hidden,
/// `.sketchbody-tmp-PID-N`) and each file is renamed into place (each file atomically).
#[derive(Debug)]
pub struct StagingDir {
    tmp: PathBuf,
    dest: PathBuf,
    dest_existed: bool,
    committed: bool,
}

impl StagingDir {
    /// Prepares a staging folder for `dest`, creating `dest`'s parent folders when missing.
    /// Errors ([`Error::Io`], naming the path): `dest` is a file, or a folder cannot be created
    /// (unwritable location, a file in the way).
    pub fn new(dest: &Path) -> Result<StagingDir> {
        static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let io = |path: &Path, source| Error::Io { path: path.to_path_buf(), source };
        let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tag = format!(".sketchbody-tmp-{}-{n}", std::process::id());
        let dest_existed = dest.exists();
        let tmp = if dest_existed {
            if !dest.is_dir() {
                return Err(io(
                    dest,
                    std::io::Error::new(std::io::ErrorKind::AlreadyExists, "exists and is not a folder"),
                ));
            }
            dest.join(tag)
        } else {
            let name = dest.file_name().ok_or_else(|| {
                io(dest, std::io::Error::new(std::io::ErrorKind::InvalidInput, "output folder has no name"))
            })?;
            let parent = dest.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
            let mut t = std::ffi::OsString::from(&tag);
            t.push("-");
            t.push(name);
            parent.join(t)
        };
        std::fs::create_dir(&tmp).map_err(|e| io(&tmp, e))?;
        Ok(StagingDir { tmp, dest: dest.to_path_buf(), dest_existed, committed: false })
    }

    /// Where to write the output file `name` (inside the staging folder).
    pub fn path(&self, name: &str) -> PathBuf {
        self.tmp.join(name)
    }

    /// The destination folder.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Moves every staged file into the destination. On error the files already moved are
    /// removed again, so the destination holds none of this job's files.
    pub fn commit(mut self) -> Result<()> {
        let io = |path: &Path, source| Error::Io { path: path.to_path_buf(), source };
        if !self.dest_existed {
            std::fs::rename(&self.tmp, &self.dest).map_err(|e| io(&self.dest, e))?;
            self.committed = true;
            return Ok(());
        }
        let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(&self.tmp)
            .map_err(|e| io(&self.tmp, e))?
            .filter_map(|e| e.ok().map(|e| e.file_name()))
            .collect();
        names.sort();
        let mut moved = Vec::new();
        for name in names {
            let target = self.dest.join(&name);
            if let Err(e) = std::fs::rename(self.tmp.join(&name), &target) {
                for m in &moved {
                    let _ = std::fs::remove_file(m);
                }
                return Err(io(&target, e));
            }
            moved.push(target);
        }
        let _ = std::fs::remove_dir(&self.tmp);
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

    #[test]
    fn staging_commits_whole_or_leaves_nothing() {
        let root = std::env::temp_dir().join(format!("skb-staging-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        // New destination: renamed as a whole.
        let dest = root.join("a/out");
        let s = StagingDir::new(&dest).unwrap();
        write_atomic(&s.path("x.txt"), b"1").unwrap();
        assert!(!dest.exists());
        s.commit().unwrap();
        assert_eq!(std::fs::read(dest.join("x.txt")).unwrap(), b"1");
        // Existing destination: files moved in, staging folder gone.
        let s = StagingDir::new(&dest).unwrap();
        write_atomic(&s.path("y.txt"), b"2").unwrap();
        s.commit().unwrap();
        let names: Vec<_> = std::fs::read_dir(&dest).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 2, "{names:?}");
        // Dropped without commit: nothing left anywhere.
        let s = StagingDir::new(&root.join("b")).unwrap();
        write_atomic(&s.path("z.txt"), b"3").unwrap();
        drop(s);
        assert_eq!(std::fs::read_dir(&root).unwrap().count(), 1);
        // A file in the way is an I/O error naming it.
        assert!(matches!(StagingDir::new(&dest.join("x.txt")), Err(Error::Io { .. })));
        assert!(matches!(StagingDir::new(&dest.join("x.txt/sub")), Err(Error::Io { .. })));
        std::fs::remove_dir_all(&root).unwrap();
    }
}
