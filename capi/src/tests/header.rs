//! The committed C header must equal a fresh cbindgen generation (cbindgen pinned in
//! Cargo.toml). Run with `SKB_BLESS_HEADER=1` (scripts/gen-header.sh) to rewrite it.

use std::path::Path;

#[test]
fn committed_header_matches_fresh_generation() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = crate_dir.join("..");
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("capi/cbindgen.toml parses");
    let bindings = cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header");
    let mut fresh = Vec::new();
    bindings.write(&mut fresh);
    let path = root.join("include/sketchbody.h");
    if std::env::var_os("SKB_BLESS_HEADER").is_some() {
        std::fs::write(&path, &fresh).expect("write include/sketchbody.h");
        return;
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "include/sketchbody.h differs from a fresh cbindgen generation: run scripts/gen-header.sh and commit it"
    );
}

/// cbindgen exports every `pub const` of the crate; core constants must be listed in
/// cbindgen.toml's `exclude` so that the C header only defines the C API's own `SKB_` names
/// (plus its include guard) and never pollutes a plug-in's namespace.
#[test]
fn header_defines_only_skb_names() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let header = std::fs::read_to_string(root.join("include/sketchbody.h")).expect("read include/sketchbody.h");
    let foreign: Vec<&str> = header
        .lines()
        .filter_map(|l| l.strip_prefix("#define "))
        .filter_map(|rest| rest.split_whitespace().next())
        .filter(|name| !name.starts_with("SKB_") && *name != "SKETCHBODY_H")
        .collect();
    assert!(
        foreign.is_empty(),
        "the C header defines non-SKB_ names {foreign:?}: add them to cbindgen.toml's exclude list"
    );
}
