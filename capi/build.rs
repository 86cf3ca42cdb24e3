//! Gives the shared library its versioned SONAME on ELF targets (`libsketchbody.so.MAJOR`, from
//! this crate's version), so programs linked against it record `libsketchbody.so.0` and keep
//! working across compatible updates. `cmake --install` installs the file as
//! `libsketchbody.so.MAJOR.MINOR.PATCH` with the `.so.MAJOR` and `.so` symlinks. In cargo's own
//! output folder the script also places the `libsketchbody.so.MAJOR -> libsketchbody.so` symlink,
//! so `-L target/release -lsketchbody` plus `LD_LIBRARY_PATH=target/release` keeps running.

use std::env;
use std::path::{Path, PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let elf = !matches!(os.as_str(), "macos" | "ios" | "windows" | "");
    if !elf {
        return;
    }
    let major = env::var("CARGO_PKG_VERSION_MAJOR").expect("cargo sets CARGO_PKG_VERSION_MAJOR");
    let soname = format!("libsketchbody.so.{major}");
    println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,{soname}");
    if let Some(dir) = profile_dir() {
        link_soname(&dir, &soname);
    }
}

/// The folder cargo puts the final artifacts in: OUT_DIR is `<profile dir>/build/<pkg>-<hash>/out`.
fn profile_dir() -> Option<PathBuf> {
    let out = PathBuf::from(env::var_os("OUT_DIR")?);
    out.ancestors().nth(3).map(Path::to_path_buf)
}

/// `<dir>/<soname> -> libsketchbody.so` (relative, so the folder can move); kept when present.
#[cfg(unix)]
fn link_soname(dir: &Path, soname: &str) {
    let link = dir.join(soname);
    if link.symlink_metadata().is_ok() {
        return;
    }
    if let Err(e) = std::os::unix::fs::symlink("libsketchbody.so", &link) {
        println!("cargo:warning=could not create {}: {e}", link.display());
    }
}

/// Cross-building for an ELF target from a non-Unix host: no symlink (install creates them).
#[cfg(not(unix))]
fn link_soname(_dir: &Path, _soname: &str) {}
