//! File-system helpers: capped reads of regular files, atomic writes (a unique temporary file
//! in the same directory, then rename) and staging folders whose files appear in their
//! destination together or not at all.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::error::{Error, Result};

/// An `Error::Io` naming `path`, of `kind`, with `msg`.
fn io_error(path: &Path, kind: std::io::ErrorKind, msg: String) -> Error {
    Error::Io { path: path.to_path_buf(), source: std::io::Error::new(kind, msg) }
}

/// Opens the regular file at `path` (symlinks followed) for reading, with its metadata. The
/// file is opened without blocking (`O_NONBLOCK` on Unix, cleared once the open file is known
/// to be regular) and the open file itself is checked (`fstat`), so a path that is, or is
/// swapped for, a FIFO, a device (`/dev/zero`) or a folder is refused and never blocks.
/// Errors ([`Error::Io`], naming the path): missing or unreadable; not a regular file.
pub fn open_regular(path: &Path) -> Result<(std::fs::File, std::fs::Metadata)> {
    let io = |source| Error::Io { path: path.to_path_buf(), source };
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(rustix::fs::OFlags::NONBLOCK.bits() as i32);
    }
    let f = options.open(path).map_err(io)?;
    let meta = f.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(io_error(path, std::io::ErrorKind::InvalidInput, "not a regular file".into()));
    }
    #[cfg(unix)]
    {
        let flags = rustix::fs::fcntl_getfl(&f).map_err(|e| io(e.into()))?;
        rustix::fs::fcntl_setfl(&f, flags - rustix::fs::OFlags::NONBLOCK).map_err(|e| io(e.into()))?;
    }
    Ok((f, meta))
}

/// Reads the whole of the regular file at `path` (opened by [`open_regular`]), at most `cap`
/// bytes. Errors ([`Error::Io`], naming the path): those of [`open_regular`]; larger than `cap`
/// bytes (checked from the open file's size and again while reading).
pub fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>> {
    let io = |source| Error::Io { path: path.to_path_buf(), source };
    let (f, meta) = open_regular(path)?;
    let too_big = || io_error(path, std::io::ErrorKind::InvalidData, format!("larger than the {cap}-byte limit"));
    if meta.len() > cap {
        return Err(too_big());
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    f.take(cap + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > cap {
        return Err(too_big());
    }
    Ok(bytes)
}

/// [`read_capped`] as UTF-8 text; invalid UTF-8 is an [`Error::Io`] of kind `InvalidData`.
pub fn read_capped_string(path: &Path, cap: u64) -> Result<String> {
    String::from_utf8(read_capped(path, cap)?)
        .map_err(|_| io_error(path, std::io::ErrorKind::InvalidData, "not valid UTF-8 text".into()))
}

/// A name for a temporary file or folder no other call (in this process or another) uses:
/// `PREFIX-PID-THREAD-N`, `N` a process-wide counter.
fn unique_tag(prefix: &str) -> String {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let thread = format!("{:?}", std::thread::current().id());
    let thread: String = thread.chars().filter(char::is_ascii_digit).collect();
    format!("{prefix}-{}-{thread}-{n}", std::process::id())
}

/// Writes `bytes` to `path` atomically: a sibling temporary file (created exclusively, unique
/// per call, so threads writing the same path never collide) is written, flushed and renamed
/// over `path`. Only a regular file is ever replaced: when `path` is a symlink, a device, a FIFO
/// or a folder the call fails with [`Error::Io`] (kind `InvalidInput`) and nothing is written.
/// On failure the temporary file is removed and `path` is untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let io_err = |source| Error::Io { path: path.to_path_buf(), source };
    let file_name = path
        .file_name()
        .ok_or_else(|| io_err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "output path has no file name")))?;
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.file_type().is_file() => {
            return Err(io_error(
                path,
                std::io::ErrorKind::InvalidInput,
                "exists and is not a regular file (symlinks, devices and folders are never replaced)".into(),
            ));
        }
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(io_err(e)),
    }
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(file_name);
    tmp_name.push(unique_tag(".tmp"));
    let tmp: PathBuf = path.with_file_name(tmp_name);
    let mut created = false;
    let result = (|| {
        let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        created = true;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        if created {
            let _ = std::fs::remove_file(&tmp);
        }
        return Err(io_err(e));
    }
    Ok(())
}

/// The prefix of every staging folder's name.
const STAGING_PREFIX: &str = ".sketchbody-tmp";

/// Whether process `pid` is alive. Only answers on Linux (`/proc`); elsewhere every process is
/// assumed alive, so nothing is ever removed by mistake.
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Removes staging folders in `dir` left by processes that died before committing (killed
/// runs): entries named `.sketchbody-tmp-PID-...` whose PID is no longer running. Errors are
/// ignored (another run may be cleaning the same folder).
fn remove_stale_staging(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(STAGING_PREFIX)).and_then(|r| r.strip_prefix('-'))
        else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else { continue };
        if pid != std::process::id() && !process_alive(pid) && e.file_type().is_ok_and(|t| t.is_dir()) {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// A folder of outputs written as a unit: files go into a hidden temporary folder and
/// [`StagingDir::commit`] moves them into the destination, so a failed or cancelled job leaves
/// nothing in it. Dropping an uncommitted staging folder removes it and everything inside.
///
/// When the destination does not exist, the temporary folder is created beside it and renamed
/// onto it (one atomic step); when it exists, the temporary folder is created inside it (hidden,
/// `.sketchbody-tmp-PID-THREAD-N`) and each file is renamed into place (each file atomically).
/// Staging folders of processes that died (a killed run) are removed by the next `new` that
/// stages in the same place.
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
        let io = |path: &Path, source| Error::Io { path: path.to_path_buf(), source };
        let tag = unique_tag(STAGING_PREFIX);
        let dest_existed = dest.exists();
        let tmp = if dest_existed {
            if !dest.is_dir() {
                return Err(io(
                    dest,
                    std::io::Error::new(std::io::ErrorKind::AlreadyExists, "exists and is not a folder"),
                ));
            }
            remove_stale_staging(dest);
            dest.join(tag)
        } else {
            let name = dest.file_name().ok_or_else(|| {
                io(dest, std::io::Error::new(std::io::ErrorKind::InvalidInput, "output folder has no name"))
            })?;
            let parent = dest.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
            remove_stale_staging(parent);
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

    /// Moves every staged file into the destination. Only regular files are replaced: when a
    /// destination entry of the same name is a symlink, a folder, a device or a FIFO, the commit
    /// fails ([`Error::Io`], "not a regular file") before anything is moved. When another job
    /// created the destination folder after [`StagingDir::new`] (two runs to the same new
    /// folder), the files are moved into it one by one like into any existing folder. On error
    /// the files already moved are removed again, so the destination holds none of this job's
    /// files.
    pub fn commit(mut self) -> Result<()> {
        let io = |path: &Path, source| Error::Io { path: path.to_path_buf(), source };
        if !self.dest_existed {
            match std::fs::rename(&self.tmp, &self.dest) {
                Ok(()) => {
                    self.committed = true;
                    return Ok(());
                }
                // Created meanwhile by another job: merge into it file by file.
                Err(_) if std::fs::symlink_metadata(&self.dest).is_ok_and(|m| m.is_dir()) => {}
                Err(e) => return Err(io(&self.dest, e)),
            }
        }
        let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(&self.tmp)
            .map_err(|e| io(&self.tmp, e))?
            .filter_map(|e| e.ok().map(|e| e.file_name()))
            .collect();
        names.sort();
        for name in &names {
            let target = self.dest.join(name);
            if std::fs::symlink_metadata(&target).is_ok_and(|m| !m.file_type().is_file()) {
                return Err(io_error(
                    &target,
                    std::io::ErrorKind::InvalidInput,
                    "exists and is not a regular file (symlinks, devices and folders are never replaced)".into(),
                ));
            }
        }
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
        let left: Vec<_> = std::fs::read_dir(&dest).unwrap().flatten().map(|e| e.file_name()).collect();
        assert_eq!(left, ["b.glb"], "a.json was not moved in and the staging folder is gone");
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
        assert_eq!(std::fs::read_dir(&fresh).unwrap().count(), 2);
        assert_eq!(std::fs::read_dir(&root).unwrap().count(), 3, "out, elsewhere.glb, fresh: no staging left");
        std::fs::remove_dir_all(&root).unwrap();
    }

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

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("skb-fsutil-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Finding 3: only regular files are read, through the cap; `/dev/zero` and a FIFO fail fast.
    #[test]
    fn capped_reads_refuse_devices_fifos_and_oversized_files() {
        let d = scratch("read");
        let f = d.join("a.bin");
        std::fs::write(&f, [1u8; 100]).unwrap();
        assert_eq!(read_capped(&f, 100).unwrap().len(), 100);
        let e = read_capped(&f, 99).unwrap_err();
        assert!(e.to_string().contains("99-byte limit"), "{e}");
        let e = read_capped(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        assert!(read_capped(&d, 1 << 20).unwrap_err().to_string().contains("not a regular file"));
        let fifo = d.join("fifo");
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            let e = read_capped(&fifo, 1 << 20).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        } else {
            println!("mkfifo unavailable: FIFO case skipped");
        }
        std::fs::write(&f, [0xff, 0xfe]).unwrap();
        assert!(read_capped_string(&f, 10).unwrap_err().to_string().contains("UTF-8"));
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Issue 52 finding 7: a path swapped between a regular file and a FIFO while it is read
    /// never blocks the reader (the check used to come before `open`, which then blocked on
    /// the FIFO until a writer came). Reads go on until 100 gave the file's bytes and 100 were
    /// refused as not a regular file (so the swap raced them); a read that has not returned
    /// after a minute fails the test.
    #[test]
    fn a_path_swapped_for_a_fifo_never_blocks() {
        let d = scratch("swap");
        let (path, spare, tmp) = (d.join("in.json"), d.join("spare"), d.join("tmp"));
        std::fs::write(&path, b"{}").unwrap();
        if !std::process::Command::new("mkfifo").arg(&spare).status().is_ok_and(|s| s.success()) {
            eprintln!("skipped: mkfifo unavailable");
            return;
        }
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let swapper = {
            let (path, spare, tmp, stop) = (path.clone(), spare.clone(), tmp.clone(), stop.clone());
            std::thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    std::fs::rename(&path, &tmp).unwrap();
                    std::fs::rename(&spare, &path).unwrap();
                    std::fs::rename(&tmp, &spare).unwrap();
                    std::thread::yield_now();
                }
            })
        };
        let (tx, rx) = std::sync::mpsc::channel();
        let reader_path = path.clone();
        let reader_stop = stop.clone();
        std::thread::spawn(move || {
            while !reader_stop.load(Ordering::Relaxed) {
                let r = read_capped(&reader_path, 100);
                if tx.send(r.map_err(|e| e.to_string())).is_err() {
                    break;
                }
            }
        });
        let (mut read, mut refused, mut attempts) = (0, 0, 0);
        while (read < 100 || refused < 100) && attempts < 1_000_000 {
            match rx.recv_timeout(std::time::Duration::from_secs(60)) {
                Ok(Ok(bytes)) => {
                    assert_eq!(bytes, b"{}");
                    read += 1;
                }
                Ok(Err(e)) => refused += usize::from(e.contains("not a regular file")),
                Err(_) => panic!("read_capped blocked on the FIFO swapped in ({read} reads, {refused} refused)"),
            }
            attempts += 1;
        }
        stop.store(true, Ordering::Relaxed);
        swapper.join().unwrap();
        assert!(read >= 100 && refused >= 100, "the swap never raced: {read} reads, {refused} refused");
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Finding 5: a symlink, a folder or a device at the output path is never replaced.
    #[test]
    fn atomic_writer_replaces_only_regular_files() {
        let d = scratch("kinds");
        let target = d.join("target.txt");
        std::fs::write(&target, b"keep").unwrap();
        let link = d.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = write_atomic(&link, b"new").unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
        std::fs::create_dir(d.join("sub")).unwrap();
        assert!(write_atomic(&d.join("sub"), b"x").is_err());
        // A special file (FIFO here: a device node needs root to create) stays what it is.
        let fifo = d.join("fifo");
        let mut expected = 3;
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            use std::os::unix::fs::FileTypeExt;
            assert!(write_atomic(&fifo, b"x").is_err());
            assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
            expected += 1;
        }
        write_atomic(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        let names: Vec<_> = std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), expected, "no temporaries left: {names:?}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Finding 6: 8 threads x 5 writes to one path all succeed, one of the payloads wins whole.
    #[test]
    fn same_path_writes_from_threads_all_succeed() {
        let d = scratch("threads");
        let path = d.join("out.bin");
        std::thread::scope(|s| {
            for t in 0..8u8 {
                let path = &path;
                s.spawn(move || {
                    for _ in 0..5 {
                        write_atomic(path, &[t; 4096]).unwrap();
                    }
                });
            }
        });
        let got = std::fs::read(&path).unwrap();
        assert_eq!(got.len(), 4096);
        assert!(got.iter().all(|&b| b == got[0]), "one whole payload");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1, "no temporaries left");
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Finding 7: a staging folder of a dead process is removed by the next run; live ones stay.
    #[test]
    fn stale_staging_folders_of_dead_processes_are_removed() {
        let d = scratch("stale");
        let dest = d.join("out");
        std::fs::create_dir(&dest).unwrap();
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let stale = dest.join(format!("{STAGING_PREFIX}-{dead}-1-0"));
        std::fs::create_dir(&stale).unwrap();
        std::fs::write(stale.join("half.glb"), b"half").unwrap();
        let beside = d.join(format!("{STAGING_PREFIX}-{dead}-1-1-new"));
        std::fs::create_dir(&beside).unwrap();
        let live = dest.join(format!("{STAGING_PREFIX}-{}-1-9", std::process::id()));
        std::fs::create_dir(&live).unwrap();
        let s = StagingDir::new(&dest).unwrap();
        assert!(!stale.exists(), "stale staging inside the destination removed");
        assert!(live.exists(), "this process's folders are left alone");
        drop(s);
        let s = StagingDir::new(&d.join("new")).unwrap();
        assert!(!beside.exists(), "stale staging beside the destination removed");
        drop(s);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
