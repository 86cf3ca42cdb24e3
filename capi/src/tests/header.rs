//! The committed C header must equal a fresh cbindgen generation (cbindgen pinned in
//! Cargo.toml) with a banner before each topic's functions. Run with `SKB_BLESS_HEADER=1`
//! (scripts/gen-header.sh) to rewrite it.

use std::path::Path;

/// The header's sections: each C-API module (capi/src/NAME.rs) and the banner put before its
/// first function, in the order lib.rs declares the modules (cbindgen keeps it).
const SECTIONS: &[(&str, &str)] = &[
    ("status", "Status codes and their text"),
    ("error", "Error messages"),
    ("version", "Version"),
    ("image", "Image functions: Canny, Gaussian blur"),
    ("body", "The body model (skb_context) and meshes (skb_mesh)"),
    ("mesh_ops", "Posing, rasterising and writing meshes"),
    ("export", "Export options; FBX and USD"),
    ("rig", "The rig in memory (skb_rig)"),
    ("pose", "The 3-D pose: dictionaries, options, estimates and alternatives"),
    ("joints_io", "2-D joints files"),
    ("detect", "2-D detection"),
    ("facing", "The figure's facing"),
    ("fit", "The shape fit"),
    ("pipeline", "Gray images; the main job (skb_pipeline_run) and its result"),
    ("views", "Turnarounds: several views of one character"),
    ("texture", "Colour images; the sketch as the body's texture"),
    ("sketch", "Synthetic sketches"),
];

/// `header` with a banner comment before the first function of every section.
fn with_sections(header: &str, crate_dir: &Path) -> String {
    let mut out = header.to_string();
    for (module, title) in SECTIONS {
        let src = std::fs::read_to_string(crate_dir.join(format!("src/{module}.rs")))
            .unwrap_or_else(|e| panic!("capi/src/{module}.rs: {e}"));
        let first = src
            .lines()
            .find_map(|l| l.split_once("extern \"C\" fn ").filter(|(head, _)| head.starts_with("pub ")))
            .and_then(|(_, rest)| rest.split('(').next())
            .unwrap_or_else(|| panic!("capi/src/{module}.rs exports no function"));
        let proto = out
            .lines()
            .scan(0usize, |at, l| {
                let start = *at;
                *at += l.len() + 1;
                Some((start, l))
            })
            .find(|(_, l)| {
                !l.starts_with(' ')
                    && l.find(&format!("{first}(")).is_some_and(|i| i > 0 && matches!(l.as_bytes()[i - 1], b' ' | b'*'))
            })
            .map(|(start, _)| start)
            .unwrap_or_else(|| panic!("{first} is not declared in the generated header"));
        let doc = out[..proto].rfind("/**").filter(|&d| !out[d..proto].contains(';')).unwrap_or(proto);
        out.insert_str(doc, &format!("/* ===== {title} ===== */\n\n"));
    }
    out
}

#[test]
fn every_module_has_a_header_section() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lib = std::fs::read_to_string(crate_dir.join("src/lib.rs")).expect("read capi/src/lib.rs");
    let modules: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("mod ")?.strip_suffix(';'))
        .filter(|m| !matches!(*m, "panic" | "ptr" | "tests"))
        .collect();
    let sections: Vec<&str> = SECTIONS.iter().map(|(m, _)| *m).collect();
    assert_eq!(modules, sections, "capi/src/lib.rs's modules and the header's sections (tests/header.rs)");
}

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
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let fresh = with_sections(&String::from_utf8(generated).expect("cbindgen writes UTF-8"), crate_dir).into_bytes();
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

/// The `skb_*` functions the header declares, in header order.
fn declared_functions(header: &str) -> Vec<String> {
    let mut names = Vec::new();
    for line in header.lines().filter(|l| !l.starts_with(' ') && !l.starts_with("//") && !l.starts_with('#')) {
        if let Some(open) = line.find('(') {
            let head = &line[..open];
            let name = head.rsplit(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).next().unwrap_or("");
            if name.starts_with("skb_") && !names.iter().any(|n| n == name) {
                names.push(name.to_string());
            }
        }
    }
    names
}

/// The `extern "C" fn skb_*` definitions of the crate's sources (outside tests), with whether
/// each is `pub` and `#[no_mangle]` (what makes it a symbol of the library).
fn defined_functions() -> Vec<(String, bool)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out = Vec::new();
    for entry in std::fs::read_dir(&src).expect("read capi/src") {
        let path = entry.expect("dir entry").path();
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("read source");
        let text = text.split("#[cfg(test)]").next().unwrap_or("");
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let Some(at) = line.find("extern \"C\" fn skb_") else { continue };
            let name: String = line[at + "extern \"C\" fn ".len()..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            let attrs = lines[..i].iter().rev().take_while(|l| l.trim_start().starts_with("#["));
            let exported = line.starts_with("pub ") && attrs.into_iter().any(|l| l.trim() == "#[no_mangle]");
            out.push((name, exported));
        }
    }
    out
}

/// Every `skb_*` function defined in Rust is exported (`pub`, `#[no_mangle]`) and declared in
/// the header, and every declared one is defined: the header and the library list the same
/// functions. The header opens with the status, error and version functions.
#[test]
fn header_declares_exactly_the_exported_functions() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let header = std::fs::read_to_string(root.join("include/sketchbody.h")).expect("read include/sketchbody.h");
    let declared = declared_functions(&header);
    let defined = defined_functions();
    let hidden: Vec<&str> = defined.iter().filter(|(_, e)| !e).map(|(n, _)| n.as_str()).collect();
    assert!(hidden.is_empty(), "skb_ functions without `pub` + #[no_mangle]: {hidden:?}");
    let defined: std::collections::BTreeSet<&str> = defined.iter().map(|(n, _)| n.as_str()).collect();
    let declared_set: std::collections::BTreeSet<&str> = declared.iter().map(String::as_str).collect();
    let undeclared: Vec<_> = defined.difference(&declared_set).collect();
    let undefined: Vec<_> = declared_set.difference(&defined).collect();
    assert!(undeclared.is_empty(), "exported but not in the header: {undeclared:?}");
    assert!(undefined.is_empty(), "in the header but not defined in Rust: {undefined:?}");
    assert!(declared.len() > 100, "parsed only {} declarations", declared.len());
    assert_eq!(declared[..3], ["skb_status_str", "skb_last_error_message", "skb_version"], "header order");
}
