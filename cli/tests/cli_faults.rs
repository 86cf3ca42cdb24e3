//! File-system faults around `sketchbody run` (issue 20 item 5, the fault matrix in
//! docs/reliability.md): a full file system, a read-only folder, a missing folder, a file in the
//! way, symlinks, two runs to the same folder at once, `kill -9` during a run followed by a
//! rerun, and a closed standard output. Each row asserts the exit status, a specific one-line error, and that no half-written
//! output and no stray staging folder is left.
//!
//! A full and a read-only file system are real tmpfs mounts when the test may mount (root with
//! CAP_SYS_ADMIN, as on CI). Elsewhere they are simulated and say so: a full disk by a file-size
//! limit (`ulimit -f`, SIGXFSZ ignored, so writes fail with EFBIG like ENOSPC), a read-only
//! folder by its permission bits (as root, the run then drops to uid 65534 so the bits bind).

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const SKETCH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch.png");
const JOINTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");
const FAST: [&str; 8] = ["--samples", "16", "--iterations", "1", "--quiet", "--preview-size=64", "--raster-side", "64"];
/// What a successful run writes.
const OUTPUTS: [&str; 10] = [
    "body.glb",
    "body.mtl",
    "body.obj",
    "body_rest.obj",
    "body_texture.png",
    "joints2d.json",
    "overlay.png",
    "pose3d.json",
    "preview.png",
    "report.md",
];

fn outputs() -> Vec<String> {
    OUTPUTS.iter().map(|n| n.to_string()).collect()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-faults-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

fn run_cmd(out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sketchbody"));
    c.args(["run", SKETCH, "--joints", JOINTS, "--out", out.to_str().unwrap()]).args(FAST);
    c
}

/// A run that takes long (many samples and iterations): for refusals that must come before the
/// work, and for killing a run midway.
fn slow_cmd(out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sketchbody"));
    c.args(["run", SKETCH, "--joints", JOINTS, "--out", out.to_str().unwrap()]);
    c.args(["--samples", "2000", "--iterations", "50", "--quiet"]);
    c
}

fn one_line_error(out: &Output, expect: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(expect.iter().any(|e| err.contains(e)), "expected one of {expect:?} in {err}");
}

fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("Uid:")).map(|l| l.split_whitespace().nth(1) == Some("0")))
        .unwrap_or(false)
}

/// A tmpfs mounted at `dir` (unmounted on drop), or `None` when this process may not mount.
struct Mount(PathBuf);

impl Mount {
    fn tmpfs(dir: &Path, options: &str) -> Option<Mount> {
        if !is_root() {
            return None;
        }
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", options, "tmpfs", dir.to_str().unwrap()])
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        ok.then(|| Mount(dir.to_path_buf()))
    }
    fn remount(&self, options: &str) {
        let s = Command::new("mount").args(["-o", options, self.0.to_str().unwrap()]).status().unwrap();
        assert!(s.success(), "remount {options}");
    }
}

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// Full file system: the run fails with the OS's error, and neither outputs nor the staging
/// folder are left on it.
#[test]
fn full_file_system_fails_and_leaves_nothing() {
    let dir = scratch("full");
    let fs = dir.join("fs");
    std::fs::create_dir(&fs).unwrap();
    let out_dir = fs.join("out");
    let mount = Mount::tmpfs(&fs, "size=256k");
    let out = if mount.is_some() {
        run_cmd(&out_dir).output().unwrap()
    } else {
        println!("full_file_system: cannot mount tmpfs here; simulating a full disk with ulimit -f 256 (EFBIG)");
        let mut c = Command::new("sh");
        c.arg("-c").arg("trap '' XFSZ; ulimit -f 256; exec \"$0\" \"$@\"").arg(env!("CARGO_BIN_EXE_sketchbody"));
        c.args(["run", SKETCH, "--joints", JOINTS, "--out", out_dir.to_str().unwrap()]).args(FAST);
        c.output().unwrap()
    };
    one_line_error(&out, &["No space left on device", "File too large"]);
    assert_eq!(names(&fs), Vec::<String>::new(), "nothing left on the full file system");
    drop(mount);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Read-only folder: refused before the work (no fit runs), the folder's own file untouched.
#[test]
fn read_only_folder_is_refused_up_front() {
    let dir = scratch("ro");
    let fs = dir.join("fs");
    std::fs::create_dir(&fs).unwrap();
    let mount = Mount::tmpfs(&fs, "size=1m");
    let out_dir = fs.join("out");
    std::fs::create_dir(&out_dir).unwrap();
    std::fs::write(out_dir.join("keep.txt"), "k").unwrap();
    // The samples are many: an up-front refusal returns at once, a late one would take long.
    let mut cmd = slow_cmd(&out_dir);
    match &mount {
        Some(m) => m.remount("remount,ro"),
        None => {
            println!("read_only_folder: cannot mount tmpfs here; using permission bits instead");
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&out_dir, std::fs::Permissions::from_mode(0o555)).unwrap();
            if is_root() {
                cmd.uid(65534).gid(65534);
            }
        }
    }
    let t = Instant::now();
    let out = cmd.output().unwrap();
    one_line_error(&out, &["cannot write the output folder"]);
    assert!(t.elapsed() < Duration::from_secs(60), "refused only after {:?}", t.elapsed());
    assert_eq!(names(&out_dir), ["keep.txt"]);
    drop(mount);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Missing folders: the output's parents are created; a missing joints file is an error that
/// creates nothing.
#[test]
fn missing_folders_are_created_and_missing_inputs_named() {
    let dir = scratch("missing");
    let out_dir = dir.join("a/b/out");
    let out = run_cmd(&out_dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(names(&out_dir), outputs());
    assert_eq!(names(&dir.join("a/b")), ["out"], "no staging folder left beside the output");
    let other = dir.join("c/out");
    let missing = dir.join("nowhere/joints.json");
    let out = Command::new(env!("CARGO_BIN_EXE_sketchbody"))
        .args(["run", SKETCH, "--joints", missing.to_str().unwrap(), "--out", other.to_str().unwrap()])
        .args(FAST)
        .output()
        .unwrap();
    one_line_error(&out, &["No such file or directory"]);
    assert!(!dir.join("c").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A file where the folder should be, and a folder where an output file should be.
#[test]
fn a_file_or_folder_in_the_way_is_refused_untouched() {
    let dir = scratch("inway");
    let file = dir.join("out.txt");
    std::fs::write(&file, "mine").unwrap();
    one_line_error(&run_cmd(&file).output().unwrap(), &["exists and is not a folder"]);
    assert_eq!(std::fs::read(&file).unwrap(), b"mine");
    let out_dir = dir.join("out");
    std::fs::create_dir_all(out_dir.join("body.glb")).unwrap();
    std::fs::write(out_dir.join("body.glb/inside.txt"), "x").unwrap();
    one_line_error(&run_cmd(&out_dir).output().unwrap(), &["not a regular file"]);
    assert_eq!(names(&out_dir), ["body.glb"], "nothing moved in, no staging left");
    assert_eq!(names(&out_dir.join("body.glb")), ["inside.txt"]);
    assert_eq!(names(&dir), ["out", "out.txt"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An output name that is a symlink is not followed or replaced; an output folder that is a
/// symlink to a folder is written through.
#[test]
fn symlinks_are_never_replaced() {
    let dir = scratch("link");
    let out_dir = dir.join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let target = dir.join("precious.glb");
    std::fs::write(&target, "precious").unwrap();
    std::os::unix::fs::symlink(&target, out_dir.join("body.glb")).unwrap();
    one_line_error(&run_cmd(&out_dir).output().unwrap(), &["not a regular file"]);
    assert_eq!(names(&out_dir), ["body.glb"]);
    assert!(std::fs::symlink_metadata(out_dir.join("body.glb")).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read(&target).unwrap(), b"precious");
    let real = dir.join("real");
    std::fs::create_dir(&real).unwrap();
    let linked = dir.join("linked");
    std::os::unix::fs::symlink(&real, &linked).unwrap();
    let out = run_cmd(&linked).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(names(&real), outputs());
    assert!(std::fs::symlink_metadata(&linked).unwrap().file_type().is_symlink());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Two runs into the same new folder at once: both succeed and the folder holds one complete
/// set of outputs and nothing else.
#[test]
fn two_runs_to_the_same_folder_both_succeed() {
    let dir = scratch("same");
    let out_dir = dir.join("out");
    let a = run_cmd(&out_dir).stderr(Stdio::piped()).spawn().unwrap();
    let b = run_cmd(&out_dir).stderr(Stdio::piped()).spawn().unwrap();
    for child in [a, b] {
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    assert_eq!(names(&out_dir), outputs());
    assert_eq!(names(&dir), ["out"]);
    let glb = std::fs::read(out_dir.join("body.glb")).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len(), "a whole GLB");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `kill -9` during a run leaves its staging folder (nothing can run in a killed process) and
/// no output; the next run into the same place removes it and writes a complete set.
#[test]
fn kill_9_then_rerun_cleans_up() {
    let dir = scratch("kill");
    let out_dir = dir.join("out");
    let mut slow = slow_cmd(&out_dir);
    slow.stderr(Stdio::null());
    let mut child = slow.spawn().unwrap();
    let t = Instant::now();
    while !names(&dir).iter().any(|n| n.starts_with(".sketchbody-tmp-")) {
        assert!(t.elapsed() < Duration::from_secs(30), "no staging folder appeared");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(200));
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let left = names(&dir);
    assert!(left.len() == 1 && left[0].starts_with(".sketchbody-tmp-"), "{left:?}");
    assert!(!out_dir.exists(), "no partial output");
    let out = run_cmd(&out_dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(names(&dir), ["out"], "the dead run's staging folder was removed");
    assert_eq!(names(&out_dir), outputs());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A closed standard output (`sketchbody run … | head -0`): the run's outputs are committed
/// before it prints its summary line, then the process ends by SIGPIPE as other Unix tools do,
/// without a panic message.
#[test]
fn a_closed_stdout_ends_the_run_quietly_after_its_outputs() {
    let dir = scratch("sigpipe");
    let out = dir.join("out");
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = run_cmd(&out).stdout(writer).stderr(Stdio::piped()).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(o.status.signal(), Some(libc::SIGPIPE), "{o:?}");
    assert_eq!(names(&out), outputs(), "every output written before the summary line");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 52 finding 2: a rerun into a folder whose `overlay.png` cannot be replaced
/// (`chattr +i`, as root on a file system with the attribute) fails, and every output of the
/// earlier run is left exactly as it was (the same files: inode and bytes), with no staging
/// folder or backup beside them. It deleted the earlier `body.glb`, `body.obj`, ... before.
#[test]
fn a_failed_rerun_leaves_the_previous_outputs_as_they_were() {
    use std::os::unix::fs::MetadataExt;
    let dir = scratch("rerun");
    let out_dir = dir.join("out");
    let first = run_cmd(&out_dir).output().unwrap();
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let snapshot = || -> Vec<(String, u64, Vec<u8>)> {
        names(&out_dir)
            .into_iter()
            .map(|n| {
                let p = out_dir.join(&n);
                (n, std::fs::metadata(&p).unwrap().ino(), std::fs::read(&p).unwrap())
            })
            .collect()
    };
    let before = snapshot();
    let overlay = out_dir.join("overlay.png");
    let immutable = Command::new("chattr").arg("+i").arg(&overlay).stderr(Stdio::null()).status();
    if !immutable.is_ok_and(|s| s.success()) {
        println!("SKIPPED: chattr +i is not available here (needs root and a file system with the attribute)");
        std::fs::remove_dir_all(&dir).unwrap();
        return;
    }
    let mut again = run_cmd(&out_dir);
    let second = again.args(["--seed", "2"]).output().unwrap();
    let _ = Command::new("chattr").arg("-i").arg(&overlay).status();
    one_line_error(&second, &["overlay.png"]);
    assert_eq!(snapshot(), before, "the earlier outputs, unchanged");
    assert_eq!(names(&dir), ["out"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 52 finding 3: a run in another PID namespace (`unshare --pid --fork --mount-proc`,
/// as root; elsewhere the row says SKIPPED) beside a live run into the same folder leaves the
/// live run's staging folder alone (its PID means nothing there, its lock does): both succeed.
/// The first failed before ("body.glb: No such file or directory").
#[test]
fn a_run_in_another_pid_namespace_keeps_a_live_runs_staging() {
    let dir = scratch("pidns");
    let out_dir = dir.join("out");
    let first = run_cmd(&out_dir).output().unwrap();
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let probe =
        Command::new("unshare").args(["--pid", "--fork", "--mount-proc", "true"]).stderr(Stdio::null()).status();
    if !probe.is_ok_and(|s| s.success()) {
        println!("SKIPPED: unshare --pid needs root");
        std::fs::remove_dir_all(&dir).unwrap();
        return;
    }
    let mut live = Command::new(env!("CARGO_BIN_EXE_sketchbody"));
    live.args(["run", SKETCH, "--joints", JOINTS, "--out", out_dir.to_str().unwrap()]);
    let live = live.args(["--samples", "300", "--iterations", "6", "--quiet"]).stderr(Stdio::piped()).spawn().unwrap();
    let t = Instant::now();
    while !names(&out_dir).iter().any(|n| n.starts_with(".sketchbody-tmp-")) {
        assert!(t.elapsed() < Duration::from_secs(30), "no staging folder appeared");
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut other = Command::new("unshare");
    other.args(["--pid", "--fork", "--mount-proc", env!("CARGO_BIN_EXE_sketchbody")]);
    other.args(["run", SKETCH, "--joints", JOINTS, "--out", out_dir.to_str().unwrap()]).args(FAST);
    let o = other.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let l = live.wait_with_output().unwrap();
    assert!(l.status.success(), "the live run: {}", String::from_utf8_lossy(&l.stderr));
    assert_eq!(names(&out_dir), outputs());
    std::fs::remove_dir_all(&dir).unwrap();
}
