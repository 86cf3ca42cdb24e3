//! 2-D joint files (`sketchbody-joints2d`, version 1; docs/formats.md): the 15 canonical joints in
//! pixels (origin at the top-left image corner, y down) and an optional `missing` list of joints
//! whose positions are guesses; from a detection also the figure's `facing` and the
//! `alternatives` (the labelling with left and right swapped). Read by `sketchbody pose` and
//! `sketchbody run --joints`, written by `sketchbody detect` and `sketchbody run`.

use std::path::Path;

use serde_json::{json, Map, Value};

use crate::detect::facing::{Facing, FacingEstimate, FACINGS};
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

/// The `facing` object of a joints file: the decided facing (`front`, `back`, `left`, `right`
/// or `unknown`), the probability of each of the four, and whether the labelling rule swapped
/// the detector's left and right.
pub fn facing_json(f: &FacingEstimate) -> Value {
    let p: Map<String, Value> =
        FACINGS.iter().zip(f.probabilities).map(|(k, p)| (k.name().to_string(), json!(p))).collect();
    json!({"facing": f.facing.name(), "probabilities": p, "swapped": f.swapped})
}

/// The `alternatives` list of a joints file: the labelling with left and right swapped (its
/// joints, its score, the probability that it is the right labelling, and `"swap":
/// "left_right"`). Errors on a non-finite coordinate.
pub fn alternatives_json(f: &FacingEstimate) -> Result<Value> {
    let joints = joints2d_json(&f.alternative)?["joints"].take();
    Ok(json!([{"swap": "left_right", "score": f.alternative_score, "joints": joints}]))
}

/// One line on the facing for reports: the decided facing, the four probabilities, and a note
/// when the labelling rule swapped the detector's sides.
pub fn facing_summary(f: &FacingEstimate) -> String {
    let p = &f.probabilities;
    format!(
        "facing {} (front {:.2}, back {:.2}, left {:.2}, right {:.2}){}",
        f.facing.name(),
        p[0],
        p[1],
        p[2],
        p[3],
        if f.swapped { "; left and right swapped from the detector's labelling" } else { "" }
    )
}

/// The facing a joints file reports ([`facing_json`]), read back.
#[derive(Clone, Debug, PartialEq)]
pub struct ReportedFacing {
    /// The decided facing.
    pub facing: Facing,
    /// Probabilities of front, back, left and right.
    pub probabilities: [f64; 4],
    /// The labelling rule swapped the detector's sides.
    pub swapped: bool,
}

/// One alternative labelling of a joints file ([`alternatives_json`]), read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Alternative {
    /// What changed: `left_right`.
    pub swap: String,
    /// The probability that it is the right labelling, in [0, 1].
    pub score: f64,
    /// Its joints (the `missing` joints of the file as the main joints'), px.
    pub joints: Joints2,
}

/// The `facing` of a `sketchbody-joints2d` document, `None` when it has none. Errors
/// ([`Error::CorruptData`]): a malformed `facing` object.
pub fn parse_facing(v: &Value) -> Result<Option<ReportedFacing>> {
    let Some(f) = v.get("facing") else { return Ok(None) };
    let name = f.get("facing").and_then(Value::as_str).ok_or_else(|| bad("\"facing\" needs a \"facing\" name"))?;
    let facing = Facing::from_name(name).map_err(|e| bad(e.to_string()))?;
    let probs = f.get("probabilities").ok_or_else(|| bad("\"facing\" needs \"probabilities\""))?;
    let mut probabilities = [0.0; 4];
    for (k, face) in FACINGS.iter().enumerate() {
        probabilities[k] = probs
            .get(face.name())
            .and_then(Value::as_f64)
            .filter(|p| (0.0..=1.0).contains(p))
            .ok_or_else(|| bad(format!("facing probability {:?} must be a number in [0, 1]", face.name())))?;
    }
    let swapped = f.get("swapped").and_then(Value::as_bool).ok_or_else(|| bad("\"facing\" needs \"swapped\""))?;
    Ok(Some(ReportedFacing { facing, probabilities, swapped }))
}

/// The `alternatives` of a `sketchbody-joints2d` document (empty when it has none). Errors
/// ([`Error::CorruptData`]): a malformed list, alternative or joint.
pub fn parse_alternatives(v: &Value) -> Result<Vec<Alternative>> {
    let Some(list) = v.get("alternatives") else { return Ok(Vec::new()) };
    let list = list.as_array().ok_or_else(|| bad("\"alternatives\" must be a list"))?;
    list.iter()
        .map(|a| {
            let swap = a.get("swap").and_then(Value::as_str).ok_or_else(|| bad("an alternative needs \"swap\""))?;
            let score = a
                .get("score")
                .and_then(Value::as_f64)
                .filter(|s| (0.0..=1.0).contains(s))
                .ok_or_else(|| bad("an alternative's \"score\" must be a number in [0, 1]"))?;
            let mut doc = json!({"format": JOINTS2D_FORMAT, "version": 1, "joints": a.get("joints").cloned().unwrap_or(Value::Null)});
            if let Some(m) = v.get("missing") {
                doc["missing"] = m.clone();
            }
            Ok(Alternative { swap: swap.to_string(), score, joints: parse_joints2d(&doc)? })
        })
        .collect()
}

/// Writes [`joints2d_json`] to `path` atomically (pretty-printed, newline-terminated), with the
/// detection behind the joints as `detection` ([`detection_json`]), its `facing`
/// ([`facing_json`]) and `alternatives` ([`alternatives_json`]) when given.
pub fn write_joints2d_with(path: &Path, j: &Joints2, detection: Option<&Figure>) -> Result<()> {
    let mut v = joints2d_json(j)?;
    if let Some(f) = detection {
        v["detection"] = detection_json(f);
        v["facing"] = facing_json(&f.facing);
        v["alternatives"] = alternatives_json(&f.facing)?;
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

    /// The facing and the swapped labelling round-trip through their readers, which name a
    /// malformed entry; a file without them reads as having none.
    #[test]
    fn facing_and_alternatives_round_trip() {
        let j = Joints2 {
            xy: std::array::from_fn(|k| [100.0 + 3.0 * k as f64, 20.0 * k as f64]),
            visible: [true; NUM_JOINTS],
        };
        let e = crate::detect::facing::estimate(&j, [0.7, 0.1, 0.15, 0.05], true);
        let mut v = joints2d_json(&j).unwrap();
        assert_eq!(parse_facing(&v).unwrap(), None);
        assert!(parse_alternatives(&v).unwrap().is_empty());
        v["facing"] = facing_json(&e);
        v["alternatives"] = alternatives_json(&e).unwrap();
        let text = serde_json::to_string_pretty(&v).unwrap();
        let back: Value = crate::strict_json::from_str(&text).unwrap();
        assert_eq!(parse_joints2d(&back).unwrap(), j, "the joints' reader ignores the facing");
        let f = parse_facing(&back).unwrap().unwrap();
        assert_eq!(f, ReportedFacing { facing: Facing::Front, probabilities: [0.7, 0.1, 0.15, 0.05], swapped: true });
        let alts = parse_alternatives(&back).unwrap();
        assert_eq!(
            alts,
            vec![Alternative { swap: "left_right".into(), score: e.alternative_score, joints: e.alternative }]
        );
        assert_eq!(alts[0].joints.xy[crate::skeleton::joint::L_WRIST], j.xy[crate::skeleton::joint::R_WRIST]);
        let mut wrong = back.clone();
        wrong["facing"]["facing"] = json!("up");
        assert!(parse_facing(&wrong).unwrap_err().to_string().contains("facing \"up\""));
        let mut wrong = back.clone();
        wrong["facing"]["probabilities"]["back"] = json!(1.5);
        assert!(parse_facing(&wrong).unwrap_err().to_string().contains("\"back\""));
        let mut wrong = back.clone();
        wrong["alternatives"][0]["joints"]["neck"] = json!([1.0]);
        assert!(parse_alternatives(&wrong).unwrap_err().to_string().contains("neck must be [x, y]"));
        let mut wrong = back;
        wrong["alternatives"] = json!({});
        assert!(parse_alternatives(&wrong).is_err());
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
