//! The README's main-job command, `cargo run --release -- run ...`, needs exactly one binary
//! among the workspace's default members (cargo refuses to choose otherwise); that binary must be
//! the artist's `sketchbody`.

use std::path::Path;
use std::process::Command;

#[test]
fn cargo_run_in_the_workspace_runs_the_artists_cli() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(readme.lines().any(|l| l.starts_with("cargo run --release -- run ")), "README's main-job command changed");
    let out = Command::new(env!("CARGO"))
        .args(["metadata", "--offline", "--locked", "--no-deps", "--format-version", "1"])
        .current_dir(&root)
        .output()
        .unwrap();
    assert!(out.status.success(), "cargo metadata: {}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let defaults: Vec<&str> =
        meta["workspace_default_members"].as_array().unwrap().iter().map(|m| m.as_str().unwrap()).collect();
    let bins: Vec<&str> = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| defaults.contains(&p["id"].as_str().unwrap()))
        .flat_map(|p| p["targets"].as_array().unwrap().iter())
        .filter(|t| t["kind"].as_array().unwrap().iter().any(|k| k == "bin"))
        .map(|t| t["name"].as_str().unwrap())
        .collect();
    assert_eq!(bins, ["sketchbody"], "binaries among the default members");
}
