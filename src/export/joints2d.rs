//! 2-D joint files (`sketchbody-joints2d`, version 1; docs/formats.md): the 15 canonical joints in
//! pixels (origin at the top-left image corner, y down) and an optional `missing` list of joints
//! whose positions are guesses. Read by `sketchbody pose` and `sketchbody run --joints`, written
//! by `sketchbody detect` and `sketchbody run`.

use std::path::Path;

use serde_json::{json, Map, Value};

use crate::detect::figure::Figure;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::skeleton::{joint_index, Joints2, JOINT_NAMES, NUM_JOINTS};

/// Format tag of the file.
pub const JOINTS2D_FORMAT: &str = "sketchbody-joints2d";

fn bad(m: impl std::fmt::Display) -> Error {
    Error::CorruptData(format!("2-D joints JSON: {m}"))
}

/// Parses a `sketchbody-joints2d` document. Errors ([`Error::CorruptData`]) name the problem:
/// wrong format tag or version, a missing, unknown or malformed joint, a bad `missing` list.
pub fn parse_joints2d(v: &Value) -> Result<Joints2> {
    if v.get("format").and_then(Value::as_str) != Some(JOINTS2D_FORMAT) {
        return Err(bad("not a sketchbody-joints2d file (\"format\" missing or different)"));
    }
    if v.get("version").and_then(Value::as_u64) != Some(1) {
        return Err(bad("unsupported version (expected 1)"));
    }
    let joints = v.get("joints").and_then(Value::as_object).ok_or_else(|| bad("\"joints\" must be an object"))?;
    let mut j = Joints2 { xy: [[f64::NAN; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    let mut seen = [false; NUM_JOINTS];
    for (name, xy) in joints {
        let k = joint_index(name).ok_or_else(|| bad(format!("unknown joint {name:?}")))?;
        let arr = xy.as_array().filter(|a| a.len() == 2).ok_or_else(|| bad(format!("{name} must be [x, y]")))?;
        let num = |i: usize| arr[i].as_f64().ok_or_else(|| bad(format!("{name}: coordinates must be numbers")));
        j.xy[k] = [num(0)?, num(1)?];
        seen[k] = true;
    }
    if let Some(missing) = seen.iter().position(|s| !s) {
        return Err(bad(format!(
            "joint {} is missing (all 15 are needed; mark unknown ones in \"missing\")",
            JOINT_NAMES[missing]
        )));
    }
    if let Some(list) = v.get("missing") {
        for name in list.as_array().ok_or_else(|| bad("\"missing\" must be a list of joint names"))? {
            let k = name
                .as_str()
                .and_then(joint_index)
                .ok_or_else(|| bad(format!("unknown joint {name} in \"missing\"")))?;
            j.visible[k] = false;
        }
    }
    Ok(j)
}

/// Parses the text of a `sketchbody-joints2d` file (a leading UTF-8 BOM skipped; an object
/// holding a key twice refused, see [`crate::strict_json`]). Errors: [`Error::CorruptData`].
pub fn parse_joints2d_text(text: &str) -> Result<Joints2> {
    let v: Value = crate::strict_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
    parse_joints2d(&v)
}

/// Reads a `sketchbody-joints2d` file (a regular file of at most
/// [`MAX_JOINTS_FILE_BYTES`](crate::export::joints::MAX_JOINTS_FILE_BYTES)); errors name the file.
pub fn load_joints2d(path: &Path) -> Result<Joints2> {
    let text = crate::fsutil::read_capped_string(path, crate::export::joints::MAX_JOINTS_FILE_BYTES)?;
    parse_joints2d_text(&text).map_err(|e| match e {
        Error::CorruptData(m) => Error::CorruptData(format!("{}: {m}", path.display())),
        other => other,
    })
}

/// The `sketchbody-joints2d` document of `j` (`missing` lists the invisible joints). Errors on a
/// non-finite coordinate.
pub fn joints2d_json(j: &Joints2) -> Result<Value> {
    let mut map = Map::new();
    for (k, name) in JOINT_NAMES.iter().enumerate() {
        if let Some(&c) = j.xy[k].iter().find(|c| !c.is_finite()) {
            return Err(Error::NonFinite { name: "joint coordinate", value: c });
        }
        map.insert((*name).into(), json!(j.xy[k]));
    }
    let missing: Vec<&str> = (0..NUM_JOINTS).filter(|&k| !j.visible[k]).map(|k| JOINT_NAMES[k]).collect();
    Ok(json!({"format": JOINTS2D_FORMAT, "version": 1, "joints": map, "missing": missing}))
}

/// The one-line hint shown with a low-confidence detection.
pub const LOW_CONFIDENCE_HINT: &str =
    "low detection confidence: look at overlay.png and correct the joints (edit joints2d.json, then pass it with --joints)";

/// The `detection` object of a joints file: the backend, the calibrated figure confidence (the
/// expected fraction of joints within 0.2 × the figure's size of the truth), the presence
/// probability, the low-confidence flag with its hint, each joint's calibrated confidence and the
/// joints that are both backends' mean.
pub fn detection_json(f: &Figure) -> Value {
    let conf: Map<String, Value> =
        JOINT_NAMES.iter().enumerate().map(|(k, n)| ((*n).to_string(), json!(f.joint_confidence[k]))).collect();
    let mut v = json!({
        "backend": f.backend.name(),
        "confidence": f.confidence,
        "presence": f.presence,
        "low_confidence": f.low_confidence,
        "joint_confidence": conf,
        "raw_score": f.raw_score,
        "other_figures": f.others.len(),
        "averaged_joints": JOINT_NAMES.iter().zip(&f.averaged).filter(|(_, a)| **a).map(|(n, _)| *n).collect::<Vec<_>>(),
    });
    if f.low_confidence {
        v["hint"] = json!(LOW_CONFIDENCE_HINT);
    }
    v
}

/// Writes [`joints2d_json`] to `path` atomically (pretty-printed, newline-terminated), with the
/// detection behind the joints as `detection` ([`detection_json`]) when given.
pub fn write_joints2d_with(path: &Path, j: &Joints2, detection: Option<&Figure>) -> Result<()> {
    let mut v = joints2d_json(j)?;
    if let Some(f) = detection {
        v["detection"] = detection_json(f);
    }
    let mut bytes = serde_json::to_vec_pretty(&v).map_err(|e| Error::CorruptData(e.to_string()))?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

/// Writes [`joints2d_json`] to `path` atomically (pretty-printed, newline-terminated).
pub fn write_joints2d(path: &Path, j: &Joints2) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(&joints2d_json(j)?).map_err(|e| Error::CorruptData(e.to_string()))?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_names_bad_input() {
        let mut j =
            Joints2 { xy: std::array::from_fn(|k| [10.0 + k as f64, 20.5 * k as f64]), visible: [true; NUM_JOINTS] };
        j.visible[4] = false;
        let v = joints2d_json(&j).unwrap();
        assert_eq!(v["missing"], json!(["r_wrist"]));
        assert_eq!(parse_joints2d(&v).unwrap(), j);
        let mut no_head = v.clone();
        no_head["joints"].as_object_mut().unwrap().remove("head");
        let e = parse_joints2d(&no_head).unwrap_err().to_string();
        assert!(e.contains("joint head is missing"), "{e}");
        let mut wrong = v.clone();
        wrong["format"] = json!("other");
        assert!(parse_joints2d(&wrong).unwrap_err().to_string().contains("not a sketchbody-joints2d"));
        let mut short = v.clone();
        short["joints"]["neck"] = json!([1.0]);
        assert!(parse_joints2d(&short).unwrap_err().to_string().contains("neck must be [x, y]"));
        let mut nan = j;
        nan.xy[0][0] = f64::NAN;
        assert!(matches!(joints2d_json(&nan), Err(Error::NonFinite { .. })));
        assert!(matches!(load_joints2d(Path::new("/nonexistent/j.json")), Err(Error::Io { .. })));
    }

    /// Issue 52 finding 11: a key given twice is refused (it used to take the last value
    /// silently), a leading UTF-8 BOM is accepted (it used to be "not JSON").
    #[test]
    fn duplicate_keys_are_refused_and_a_bom_accepted() {
        let j = Joints2 { xy: std::array::from_fn(|k| [k as f64, 2.0 * k as f64]), visible: [true; NUM_JOINTS] };
        let text = serde_json::to_string(&joints2d_json(&j).unwrap()).unwrap();
        assert_eq!(parse_joints2d_text(&format!("\u{feff}{text}")).unwrap(), j);
        let twice = text.replacen("\"neck\":", "\"neck\":[500.0,500.0],\"neck\":", 1);
        let e = parse_joints2d_text(&twice).unwrap_err().to_string();
        assert!(e.contains("duplicate key \"neck\""), "{e}");
        let twice = text.replacen("\"version\":1", "\"version\":1,\"version\":1", 1);
        assert!(parse_joints2d_text(&twice).unwrap_err().to_string().contains("duplicate key \"version\""));
    }
}
