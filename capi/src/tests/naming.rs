//! The C API's naming and idiom rules (docs/c-api.md, "Names and idioms"), checked on every
//! function the committed header declares, so that a new export cannot break them unnoticed.

use std::collections::BTreeSet;
use std::path::Path;

/// One declared function: return type, name and parameters as (type, name).
struct Prototype {
    ret: String,
    name: String,
    params: Vec<(String, String)>,
}

/// The header's text without comments and preprocessor lines.
fn header_code() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("include/sketchbody.h")).expect("read include/sketchbody.h");
    let mut code = String::new();
    let mut rest = text.as_str();
    while let Some(start) = rest.find("/*") {
        code.push_str(&rest[..start]);
        rest = rest[start..].split_once("*/").map_or("", |(_, after)| after);
    }
    code.push_str(rest);
    code.lines().filter(|l| !l.trim_start().starts_with('#')).collect::<Vec<_>>().join("\n")
}

/// Every `skb_*` function prototype of the header.
fn prototypes(code: &str) -> Vec<Prototype> {
    let mut out = Vec::new();
    for stmt in code.split(';') {
        let stmt = stmt.split_whitespace().collect::<Vec<_>>().join(" ");
        let stmt = stmt.rsplit(['{', '}']).next().unwrap_or("").trim().to_string();
        if stmt.starts_with("typedef") || !stmt.ends_with(')') {
            continue;
        }
        let Some(open) = stmt.find("skb_").and_then(|i| stmt[i..].find('(').map(|j| i + j)) else {
            continue;
        };
        let head = &stmt[..open];
        let Some(name_start) =
            head.rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).map(|i| i + 1).or(Some(0))
        else {
            continue;
        };
        let name = head[name_start..].to_string();
        if !name.starts_with("skb_") {
            continue;
        }
        let args = &stmt[open + 1..stmt.len() - 1];
        let params = if args.trim() == "void" {
            Vec::new()
        } else {
            args.split(',')
                .map(|p| {
                    let p = p.trim();
                    let cut = p.rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).map_or(0, |i| i + 1);
                    (p[..cut].trim().to_string(), p[cut..].to_string())
                })
                .collect()
        };
        out.push(Prototype { ret: head[..name_start].trim().to_string(), name, params });
    }
    out
}

/// The handle and value types the header defines (`skb_` stripped).
fn type_names(code: &str) -> BTreeSet<String> {
    code.split_whitespace()
        .collect::<Vec<_>>()
        .windows(2)
        .filter(|w| w[0] == "struct" && w[1].starts_with("skb_"))
        .map(|w| w[1].trim_start_matches("skb_").trim_end_matches(['{', ';', '*']).to_string())
        .collect()
}

/// The subject of a name: the longest known type (or pipeline/status word) it starts with.
fn subject<'a>(name: &str, subjects: &'a BTreeSet<String>) -> Option<&'a String> {
    let rest = name.strip_prefix("skb_")?;
    subjects.iter().filter(|s| rest == s.as_str() || rest.starts_with(&format!("{s}_"))).max_by_key(|s| s.len())
}

#[test]
fn every_function_follows_the_naming_and_idiom_rules() {
    let code = header_code();
    let protos = prototypes(&code);
    assert!(protos.len() > 150, "the parser found only {} prototypes", protos.len());
    let types = type_names(&code);
    let handles: BTreeSet<String> =
        types.iter().filter(|t| code.contains(&format!("typedef struct skb_{t} skb_{t};"))).cloned().collect();
    let mut subjects = types.clone();
    subjects.extend(["pipeline", "status", "last_error", "version"].map(String::from));
    let names: BTreeSet<&str> = protos.iter().map(|p| p.name.as_str()).collect();
    let mut broken = Vec::new();
    for p in &protos {
        let Some(subj) = subject(&p.name, &subjects) else {
            broken.push(format!("{}: does not start with a type or topic (noun first)", p.name));
            continue;
        };
        let verb = p.name.trim_start_matches("skb_").trim_start_matches(subj.as_str()).trim_start_matches('_');
        let last = p.params.last().map(|(t, n)| (t.as_str(), n.as_str()));
        if verb == "new" || verb.starts_with("new_") {
            let want = format!("struct skb_{subj} **");
            if last != Some((want.as_str(), "out")) {
                broken.push(format!("{}: a constructor of skb_{subj} must end with `{want}out`", p.name));
            }
            if !names.contains(format!("skb_{subj}_free").as_str()) {
                broken.push(format!("{}: skb_{subj} has no skb_{subj}_free", p.name));
            }
        }
        if verb == "free" && (p.ret != "void" || !handles.contains(subj)) {
            broken.push(format!("{}: a destructor returns void and frees a handle type", p.name));
        }
        if (verb.ends_with("count") || verb.ends_with("length")) && last != Some(("size_t *", "out")) {
            broken.push(format!("{}: a count or length ends with `size_t *out`", p.name));
        }
        if verb.starts_with("copy_") {
            let lens = p.params.iter().filter(|(t, n)| t == "size_t" && (n == "dst_len" || n == "len")).count();
            if lens != 1 {
                broken.push(format!("{}: a copy takes one `dst_len` (or `len` for parallel buffers)", p.name));
            }
        }
        if verb.starts_with("num_") || verb.contains("_with_") {
            broken.push(format!("{}: counts are `_count`; options are handles, not `_with_` variants", p.name));
        }
        if p.params.iter().any(|(t, n)| t == "int" && (n == "on" || n.starts_with("is_"))) {
            broken.push(format!("{}: flags are bool", p.name));
        }
    }
    for h in &handles {
        if !names.contains(format!("skb_{h}_free").as_str()) {
            broken.push(format!("skb_{h}: a handle type without skb_{h}_free"));
        }
    }
    assert!(broken.is_empty(), "{} rule breaks:\n{}", broken.len(), broken.join("\n"));
}

#[test]
fn the_rules_catch_what_they_forbid() {
    let code = "typedef struct skb_mesh skb_mesh;\ntypedef struct skb_rig skb_rig;\n\
        skb_status skb_mesh_rig_new(const struct skb_mesh *mesh, struct skb_rig **out);\n\
        skb_status skb_estimate_pose(const struct skb_mesh *m);\n";
    let protos = prototypes(code);
    assert_eq!(protos.len(), 2);
    assert_eq!(protos[0].params[1], ("struct skb_rig **".to_string(), "out".to_string()));
    let mut subjects = type_names(code);
    subjects.insert("pipeline".into());
    assert_eq!(subject("skb_mesh_rig_new", &subjects).map(String::as_str), Some("mesh"));
    assert_eq!(subject("skb_estimate_pose", &subjects), None);
}
