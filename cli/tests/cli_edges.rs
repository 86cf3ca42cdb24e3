//! `sketchbody edges` end to end: a real edge map, and one-line errors naming the file for a
//! missing input, a non-image, a truncated PNG and an unwritable output, with nothing left behind.

use std::path::{Path, PathBuf};
use std::process::Command;

fn cli() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sketchbody"));
    c.arg("edges");
    c
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-edges-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 40x30 PNG: black left half, white right half.
fn write_step_png(path: &Path) {
    let mut img = image::GrayImage::new(40, 30);
    for (x, _, p) in img.enumerate_pixels_mut() {
        p.0[0] = if x < 20 { 0 } else { 255 };
    }
    img.save(path).unwrap();
}

/// Runs the CLI expecting failure; returns its single stderr line.
fn fails(args: &[&std::ffi::OsStr]) -> String {
    let out = cli().args(args).output().unwrap();
    assert!(!out.status.success(), "expected failure for {args:?}");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one line expected, got {err:?}");
    err
}

#[test]
fn edges_writes_the_step_edge() {
    let dir = scratch("ok");
    let (input, output) = (dir.join("step.png"), dir.join("edges.png"));
    write_step_png(&input);
    let status = cli().args([input.as_os_str(), output.as_os_str()]).arg("--l2").status().unwrap();
    assert!(status.success());
    let edges = image::open(&output).unwrap().to_luma8();
    for (x, y, p) in edges.enumerate_pixels() {
        assert_eq!(p.0[0], if x == 19 { 255 } else { 0 }, "pixel ({x}, {y})");
    }
}

#[test]
fn edges_reports_bad_files_in_one_line() {
    let dir = scratch("bad");
    let out = dir.join("out.png");
    let missing = dir.join("missing.png");
    let err = fails(&[missing.as_os_str(), out.as_os_str()]);
    assert!(err.contains("missing.png") && err.contains("No such file"), "{err}");

    let text = dir.join("notes.png");
    std::fs::write(&text, "not an image at all").unwrap();
    let err = fails(&[text.as_os_str(), out.as_os_str()]);
    assert!(err.contains("notes.png") && err.contains("not a readable image"), "{err}");

    let good = dir.join("good.png");
    write_step_png(&good);
    let bytes = std::fs::read(&good).unwrap();
    let truncated = dir.join("truncated.png");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let err = fails(&[truncated.as_os_str(), out.as_os_str()]);
    assert!(err.contains("truncated.png") && err.contains("not a readable image"), "{err}");

    let unwritable = dir.join("no-such-dir").join("edges.png");
    let err = fails(&[good.as_os_str(), unwritable.as_os_str()]);
    assert!(err.contains("edges.png"), "{err}");

    let err = fails(&[good.as_os_str(), out.as_os_str(), "--aperture".as_ref(), "4".as_ref()]);
    assert!(err.contains("aperture"), "{err}");
    assert!(!out.exists(), "no output may be left after failures");
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}
