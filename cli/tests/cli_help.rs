//! `sketchbody --help` lists only the artist's commands (the research ones are `sketchbody-lab`'s),
//! and a bad numeric option fails at parse time (exit 2) naming the option, before any
//! input file is read (the inputs given here do not exist).

use std::process::{Command, Output};

fn sketchbody(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sketchbody")).args(args).output().unwrap()
}

/// The command names listed under `heading` (up to the next blank line).
fn listed(help: &str, heading: &str) -> Vec<String> {
    let start = help.find(heading).unwrap_or_else(|| panic!("no {heading:?} in\n{help}"));
    help[start + heading.len()..]
        .lines()
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().next().unwrap_or("").to_string())
        .collect()
}

#[test]
fn help_lists_only_the_artist_commands() {
    let out = sketchbody(&["--help"]);
    assert!(out.status.success(), "{out:?}");
    let help = String::from_utf8(out.stdout).unwrap();
    assert_eq!(listed(&help, "Commands:"), ["run", "detect", "pose", "body", "edges", "help"]);
    assert!(help.contains("--version"), "{help}");
    for research in ["run-dataset", "train-detector", "eval"] {
        let out = sketchbody(&[research, "--help"]);
        assert_eq!(out.status.code(), Some(2), "{research} is not a command of the artist's tool: {out:?}");
    }
}

#[test]
fn bad_numeric_options_fail_at_once_naming_the_option() {
    let cases: [(&[&str], &str); 8] = [
        (&["run", "missing.png", "--out", "/nonexistent/o", "--preview-size", "0"], "--preview-size"),
        (&["run", "missing.png", "--out", "/nonexistent/o", "--texture-size", "5000"], "--texture-size"),
        (&["run", "missing.png", "--out", "/nonexistent/o", "--samples", "1"], "--samples"),
        (&["run", "missing.png", "--out", "/nonexistent/o", "--height=0.05"], "--height"),
        (&["detect", "missing.png", "--out", "/nonexistent/o.json", "--max-side", "8"], "--max-side"),
        (&["detect", "missing.png", "--out", "/nonexistent/o.json", "--threshold=nan"], "--threshold"),
        (&["pose", "missing.json", "--out", "/nonexistent/o.json", "--alpha", "1.5"], "--alpha"),
        (&["pose", "missing.json", "--out", "/nonexistent/o.json", "--max-bases", "33"], "--max-bases"),
    ];
    for (args, option) in cases {
        let out = sketchbody(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(option), "{args:?}: the error should name {option}: {err}");
        assert!(!err.contains("missing."), "{args:?}: failed on the input file, not the option: {err}");
    }
}
