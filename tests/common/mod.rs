//! Shared helpers for integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The repository's top folder: the package's own folder for the core's tests, its parent for
/// the workspace members' (`capi/`, `cli/`, `lab/`).
pub fn repo_root() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if dir.join("assets").is_dir() {
        dir
    } else {
        dir.join("..")
    }
}

/// The reference data folder (`../shared/data` beside the repository, or `$SKB_SHARED_DATA`).
/// When it is missing: panics if `SKB_REQUIRE_SHARED_DATA` is set (CI sets it in `.ci/run`),
/// otherwise prints a SKIPPED line naming `what` and returns `None`.
pub fn shared_data(what: &str) -> Option<PathBuf> {
    let dir =
        std::env::var_os("SKB_SHARED_DATA").map(PathBuf::from).unwrap_or_else(|| repo_root().join("../shared/data"));
    if dir.is_dir() {
        return Some(dir);
    }
    if std::env::var_os("SKB_REQUIRE_SHARED_DATA").is_some() {
        panic!("{what}: reference data not found at {} but SKB_REQUIRE_SHARED_DATA is set", dir.display());
    }
    eprintln!("SKIPPED {what}: reference data not found at {}", dir.display());
    None
}

/// Mean and worst distance (px) between two sets of the 15 canonical joints, with the worst
/// joint's name.
pub fn joint_errors(got: &[[f64; 2]; 15], want: &[[f64; 2]; 15]) -> (f64, f64, &'static str) {
    let mut sum = 0.0;
    let mut worst = (0.0f64, "");
    for (k, name) in sketchbody::skeleton::JOINT_NAMES.iter().enumerate() {
        let d = (got[k][0] - want[k][0]).hypot(got[k][1] - want[k][1]);
        sum += d;
        if d > worst.0 {
            worst = (d, name);
        }
    }
    (sum / 15.0, worst.0, worst.1)
}
