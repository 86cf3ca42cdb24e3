//! File-system helpers: capped reads of regular files, atomic writes (a unique temporary file
//! in the same directory, then rename) and staging folders whose files appear in their
//! destination together or not at all ([`StagingDir`]), and sets of outputs in any folders
//! replaced together or not at all ([`OutputSet`]).

use std::io::{Read, Write};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::error::{Error, Result};

mod replace;
mod staging;

pub use replace::OutputSet;
pub use staging::StagingDir;

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
    write_atomic_parts(path, &[bytes])
}

/// [`write_atomic`] of the concatenation of `parts`, written one after the other (no joined copy
/// in memory).
pub fn write_atomic_parts(path: &Path, parts: &[&[u8]]) -> Result<()> {
    let io_err = |source| Error::Io { path: path.to_path_buf(), source };
    replace::check_replaceable(path)?;
    let tmp = replace::sibling(path, ".tmp")?;
    let mut created = false;
    let result = (|| {
        let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        created = true;
        for part in parts {
            f.write_all(part)?;
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

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
}
