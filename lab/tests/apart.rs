//! The lab stays apart from what a C consumer and an artist build: `cargo tree` of the C API
//! crate and of the artist's CLI (normal dependencies, offline, locked) lists no
//! `sketchbody-lab`, the core's source tree holds none of the lab's modules, and no core file
//! names the lab's crate.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The package names in `cargo tree -p package -e normal` (one per line, no prefix).
fn tree(package: &str) -> Vec<String> {
    let out = Command::new(env!("CARGO"))
        .args(["tree", "--offline", "--locked", "-e", "normal", "--prefix", "none", "-p", package])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(out.status.success(), "cargo tree -p {package}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(String::from)
        .collect()
}

#[test]
fn the_c_consumer_and_the_artist_cli_do_not_build_the_lab() {
    assert!(tree("sketchbody-lab").iter().any(|p| p == "sketchbody-lab"), "the lab's own tree names it");
    for package in ["sketchbody-capi", "sketchbody-cli", "sketchbody"] {
        let deps = tree(package);
        assert!(deps.iter().any(|p| p == "sketchbody"), "{package}: {deps:?}");
        assert!(!deps.iter().any(|p| p == "sketchbody-lab"), "{package} depends on the lab: {deps:?}");
    }
    let capi = tree("sketchbody-capi");
    for cli_only in ["clap", "sketchbody-cli", "zip", "sha2"] {
        assert!(!capi.iter().any(|p| p == cli_only), "the C API builds {cli_only}: {capi:?}");
    }
}

/// The lab's modules, as paths the core had them at.
const LAB_MODULES: [&str; 12] = [
    "src/eval",
    "src/detect/train",
    "src/detect/parse_eval.rs",
    "src/pose/factor_train.rs",
    "src/pose/learn.rs",
    "src/pose/bvh.rs",
    "src/pose/metrics.rs",
    "src/render/stylise",
    "src/render/photo_npr.rs",
    "src/render/sketch/mannequin.rs",
    "src/pose/mlp_train.rs",
    "src/detect/calibration_fit.rs",
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn the_core_source_tree_holds_none_of_the_lab() {
    let root = root();
    for m in LAB_MODULES {
        assert!(!root.join(m).exists(), "{m} is the lab's (lab/{})", m.trim_start_matches("src/"));
    }
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    rust_files(&root.join("capi/src"), &mut files);
    rust_files(&root.join("cli/src"), &mut files);
    assert!(files.len() > 100, "{} files", files.len());
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        assert!(!text.contains("sketchbody_lab"), "{} uses the lab", f.display());
        for train in ["fn train(", "fn train_", "fn fit_logistic("] {
            assert!(!text.contains(train), "{}: training ({train}) is the lab's", f.display());
        }
    }
}
