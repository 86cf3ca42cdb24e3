//! `sketchbody-lab --help` lists the research commands (and none of the artist's), and a bad
//! numeric option fails at parse time (exit 2) naming the option, before any input is read.

use std::process::{Command, Output};

fn lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sketchbody-lab")).args(args).output().unwrap()
}

#[test]
fn help_lists_the_research_commands() {
    let out = lab(&["--help"]);
    assert!(out.status.success(), "{out:?}");
    let help = String::from_utf8(out.stdout).unwrap();
    let start = help.find("Commands:").unwrap_or_else(|| panic!("{help}"));
    let listed: Vec<&str> = help[start..]
        .lines()
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().next().unwrap_or(""))
        .collect();
    for name in ["run-dataset", "learn-poses", "bench-pose", "build-model", "train-detector", "make-dataset", "eval"] {
        assert!(listed.contains(&name), "{name} missing from {listed:?}");
    }
    for name in ["run", "detect", "pose", "body", "edges"] {
        assert!(!listed.contains(&name), "{name} is the artist's command: {listed:?}");
    }
}

#[test]
fn bad_numeric_options_fail_at_once_naming_the_option() {
    let cases: [(&[&str], &str); 6] = [
        (&["train-detector", "--out", "/nonexistent/m.skbd", "--art-styles", "1.5"], "--art-styles"),
        (&["train-detector", "--out", "/nonexistent/m.skbd", "--parse-last", "101"], "--parse-last"),
        (&["train-detector", "--out", "/nonexistent/m.skbd", "--parse-variants", "0"], "--parse-variants"),
        (&["train-detector", "--out", "/nonexistent/m.skbd", "--max-passes", "0"], "--max-passes"),
        (&["eval-detector", "--sets", "parse", "--parse-range", "90-80"], "--parse-range"),
        (&["eval-detector", "--sets", "parse", "--parse-range", "0-80"], "--parse-range"),
    ];
    for (args, option) in cases {
        let out = lab(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(option), "{args:?}: the error should name {option}: {err}");
    }
}
