//! The artist's commands of the `sketchbody` tool (`run`, `detect`, `pose`, `body`, `edges`) and
//! their shared argument groups, as a library so that the research tool `sketchbody-lab` runs the
//! same pipeline with the same options. Each command module exposes an `Args` struct (clap) and
//! `run(args) -> Result<(), CliError>`.

pub mod body;
pub mod detect;
pub mod edges;
pub mod export_formats;
pub mod fit_args;
pub mod pose;
pub mod ranges;
pub mod rig_args;
pub mod run;
pub mod search_args;
pub mod sheet;

/// A failure to report: one line of text.
pub struct CliError(pub String);

impl From<sketchbody::Error> for CliError {
    fn from(e: sketchbody::Error) -> Self {
        CliError(e.to_string())
    }
}

/// A closed standard output (`sketchbody … | head`) ends the process quietly, as it does other
/// Unix tools, instead of a panic in `println!` (Rust's runtime ignores SIGPIPE, so the write
/// fails with EPIPE). Every command writes its files before its last stdout line, and `run`
/// commits its outputs atomically before it prints. Call first in `main`, before any thread
/// starts.
pub fn default_sigpipe() {
    // SAFETY: called first in `main`, before any thread starts; restores the default disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Runs a command's result to an exit status: 0, or the error printed as one line
/// `PROGRAM: message` on standard error and status 1.
pub fn exit_code(program: &str, result: Result<(), CliError>) -> std::process::ExitCode {
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(CliError(msg)) => {
            eprintln!("{program}: {msg}");
            std::process::ExitCode::from(1)
        }
    }
}
