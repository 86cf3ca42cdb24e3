//! `sketchbody-lab stylise` and `sketchbody-lab negative-page` end to end: RGB PNGs of the right size,
//! the same bytes for the same seed, and one-line errors for a missing input, an unknown style
//! and a bad page size.

use std::path::PathBuf;
use std::process::Command;

fn cli() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sketchbody-lab"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skb-cli-stylise-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 60x50 photo-like PNG: gray wall, a dark disc, a red box.
fn write_photo(path: &std::path::Path) {
    let img = image::RgbImage::from_fn(60, 50, |x, y| {
        let (dx, dy) = (x as f32 - 20.0, y as f32 - 25.0);
        if dx * dx + dy * dy < 100.0 {
            image::Rgb([60, 60, 70])
        } else if (38..54).contains(&x) && (10..40).contains(&y) {
            image::Rgb([200, 40, 30])
        } else {
            image::Rgb([210, 210, 205])
        }
    });
    img.save(path).unwrap();
}

fn run_ok(args: &[&std::ffi::OsStr]) {
    let out = cli().args(args).output().unwrap();
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn fails(args: &[&str]) -> String {
    let out = cli().args(args).output().unwrap();
    assert!(!out.status.success(), "expected failure for {args:?}");
    String::from_utf8(out.stderr).unwrap()
}

#[test]
fn stylise_writes_each_style_deterministically() {
    let dir = scratch("ok");
    let input = dir.join("photo.png");
    write_photo(&input);
    for style in ["xdog", "pencil", "flat"] {
        let (a, b) = (dir.join(format!("{style}-a.png")), dir.join(format!("{style}-b.png")));
        for out in [&a, &b] {
            run_ok(&[
                "stylise".as_ref(),
                input.as_os_str(),
                out.as_os_str(),
                "--style".as_ref(),
                style.as_ref(),
                "--seed".as_ref(),
                "4".as_ref(),
            ]);
        }
        let img = image::open(&a).unwrap();
        assert_eq!((img.width(), img.height()), (60, 50), "{style}");
        assert!(matches!(img, image::DynamicImage::ImageRgb8(_)), "{style}: RGB output");
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "{style}: same seed, same file");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn negative_page_writes_pages_of_the_asked_size() {
    let dir = scratch("page");
    for kind in ["blank", "text", "clutter"] {
        let out = dir.join(format!("{kind}.png"));
        run_ok(&[
            "negative-page".as_ref(),
            out.as_os_str(),
            "--kind".as_ref(),
            kind.as_ref(),
            "--size".as_ref(),
            "96x64".as_ref(),
            "--seed".as_ref(),
            "2".as_ref(),
        ]);
        let img = image::open(&out).unwrap();
        assert_eq!((img.width(), img.height()), (96, 64), "{kind}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_arguments_fail_with_a_clear_message() {
    let dir = scratch("bad");
    let out = dir.join("o.png");
    let missing = dir.join("missing.png");
    let err = fails(&["stylise", missing.to_str().unwrap(), out.to_str().unwrap(), "--style", "xdog"]);
    assert!(err.contains("missing.png") && err.trim_end().lines().count() == 1, "{err}");
    let err = fails(&["stylise", missing.to_str().unwrap(), out.to_str().unwrap(), "--style", "oil"]);
    assert!(err.contains("oil") && err.contains("xdog, pencil, flat"), "{err}");
    let err = fails(&["negative-page", out.to_str().unwrap(), "--kind", "text", "--size", "96"]);
    assert!(err.contains("WIDTHxHEIGHT"), "{err}");
    let err = fails(&["negative-page", out.to_str().unwrap(), "--kind", "text", "--size", "0x5"]);
    assert!(err.contains("empty") && err.trim_end().lines().count() == 1, "{err}");
    assert!(!out.exists(), "nothing written on failure");
    std::fs::remove_dir_all(&dir).unwrap();
}
