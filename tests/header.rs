//! The committed C header must equal a fresh cbindgen generation (cbindgen pinned in
//! Cargo.toml). Run with `SKB_BLESS_HEADER=1` (scripts/gen-header.sh) to rewrite it.

use std::path::Path;

#[test]
fn committed_header_matches_fresh_generation() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("cbindgen.toml parses");
    let bindings = cbindgen::Builder::new()
        .with_crate(root)
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
