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

/// One malloc arena for the whole process (glibc only; elsewhere a no-op). A command runs one
/// job, and glibc's default of up to eight arenas per core lets each worker thread keep its own
/// freed memory: on the bundled example `run` peaks at 152 MiB resident with the default and
/// 120 MiB with one arena, and is no slower (docs/benchmarks.md, issue 50). Call first in
/// `main`, before any thread starts. The library itself never changes the host's allocator.
pub fn one_malloc_arena() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; called before any thread starts.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

/// Hands the allocator's free pages back to the system (glibc's `malloc_trim`; elsewhere a
/// no-op). With [`one_malloc_arena`] freed memory stays in the process until trimmed, so `run`
/// calls this between the fit and writing its files: the writing's buffers then reuse the
/// returned pages instead of adding to the detection's high-water mark (docs/benchmarks.md,
/// issue 50).
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free pages of the allocator's own heap to the system.
    unsafe {
        libc::malloc_trim(0);
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
