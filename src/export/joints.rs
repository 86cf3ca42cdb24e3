//! 3-D joint files (JSON): `{"units": "m", "joints": {"head": [x, y, z], ...}}` with all 15
//! canonical joint names ([`JOINT_NAMES`]), metres, model frame (+Y up, +Z toward the viewer,
//! the character's right at −X). Used by `sketchbody body --pose`.

use std::path::Path;

use serde_json::{json, Map, Value};

use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::skeleton::{Joints3, JOINT_NAMES, NUM_JOINTS};

/// Parses a joints JSON document (a leading UTF-8 BOM skipped; a key twice refused, see
/// [`crate::strict_json`]). Errors name the missing, unknown or malformed joint.
pub fn parse_joints3_json(text: &str) -> Result<Joints3> {
    let doc: Value = crate::strict_json::from_str(text).map_err(|e| Error::CorruptData(format!("joints JSON: {e}")))?;
    if let Some(u) = doc.get("units") {
        if u != "m" {
            return Err(Error::CorruptData(format!("joints JSON: units {u} (expected \"m\")")));
        }
    }
    let joints = doc.get("joints").ok_or_else(|| Error::CorruptData("joints JSON: no \"joints\" object".into()))?;
    parse_joint_object(joints, "joints JSON")
}

/// The 15 joints of a joint object `{"head": [x, y, z], ...}` (every canonical name once, no
/// other key); errors name `what` and the missing, unknown or malformed joint.
pub fn parse_joint_object(joints: &Value, what: &str) -> Result<Joints3> {
    let joints =
        joints.as_object().ok_or_else(|| Error::CorruptData(format!("{what}: the joints are not an object")))?;
    if let Some(name) = joints.keys().find(|n| !JOINT_NAMES.contains(&n.as_str())) {
        return Err(Error::CorruptData(format!("{what}: unknown joint {name:?}")));
    }
    let mut out = [[0.0; 3]; NUM_JOINTS];
    for (j, name) in JOINT_NAMES.iter().enumerate() {
        let v = joints
            .get(*name)
            .and_then(Value::as_array)
            .ok_or_else(|| Error::CorruptData(format!("{what}: joint {name:?} missing")))?;
        if v.len() != 3 {
            return Err(Error::CorruptData(format!("{what}: joint {name:?} has {} coordinates, expected 3", v.len())));
        }
        for (k, c) in v.iter().enumerate() {
            out[j][k] = c
                .as_f64()
                .ok_or_else(|| Error::CorruptData(format!("{what}: joint {name:?} coordinate {k} is not a number")))?;
        }
    }
    Ok(out)
}

/// Largest joints JSON file (3-D or 2-D joints) the loaders read, in bytes (1 MiB; a joints file
/// is about 2 kB). Larger files, and anything but a regular file, are `Error::Io`.
pub const MAX_JOINTS_FILE_BYTES: u64 = 1 << 20;

/// Reads a joints JSON file (a regular file of at most [`MAX_JOINTS_FILE_BYTES`]).
pub fn load_joints3_json(path: &Path) -> Result<Joints3> {
    let text = crate::fsutil::read_capped_string(path, MAX_JOINTS_FILE_BYTES)?;
    parse_joints3_json(&text).map_err(|e| match e {
        Error::CorruptData(m) => Error::CorruptData(format!("{}: {m}", path.display())),
        other => other,
    })
}

/// Writes joints as JSON to `path` atomically. Errors on non-finite coordinates.
pub fn write_joints3_json(path: &Path, joints: &Joints3) -> Result<()> {
    let mut map = Map::new();
    for (j, name) in JOINT_NAMES.iter().enumerate() {
        if let Some(&c) = joints[j].iter().find(|c| !c.is_finite()) {
            return Err(Error::NonFinite { name: "joint coordinate", value: c });
        }
        map.insert((*name).into(), json!(joints[j]));
    }
    let text = serde_json::to_string_pretty(&json!({"units": "m", "joints": map}))
        .map_err(|e| Error::CorruptData(e.to_string()))?;
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::procedural::rest_joints;

    #[test]
    fn round_trips_and_rejects_bad_files() {
        let j = rest_joints();
        let dir = std::env::temp_dir().join(format!("skb-joints-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("j.json");
        write_joints3_json(&p, &j).unwrap();
        assert_eq!(load_joints3_json(&p).unwrap(), j);
        assert!(matches!(load_joints3_json(&dir.join("none.json")), Err(Error::Io { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
        for bad in ["{", "{\"joints\": {}}", "{\"units\": \"cm\", \"joints\": {}}", "{\"joints\": {\"head\": [1, 2]}}"]
        {
            assert!(matches!(parse_joints3_json(bad), Err(Error::CorruptData(_))), "{bad}");
        }
    }

    /// Issue 52 finding 11: an unknown joint name is refused as the 2-D reader refuses it, a key
    /// given twice is refused, a leading UTF-8 BOM is accepted.
    #[test]
    fn unknown_names_and_duplicate_keys_are_refused_and_a_bom_accepted() {
        let text = serde_json::to_string(&json!({"units": "m", "joints": rest_joints()
            .iter()
            .zip(JOINT_NAMES)
            .map(|(p, n)| (n.to_string(), json!(p)))
            .collect::<Map<String, Value>>()}))
        .unwrap();
        assert_eq!(parse_joints3_json(&format!("\u{feff}{text}")).unwrap(), rest_joints());
        let extra = text.replacen("\"head\":", "\"tail\":[0,0,0],\"head\":", 1);
        let e = parse_joints3_json(&extra).unwrap_err().to_string();
        assert!(e.contains("unknown joint \"tail\""), "{e}");
        let twice = text.replacen("\"head\":", "\"head\":[9,9,9],\"head\":", 1);
        let e = parse_joints3_json(&twice).unwrap_err().to_string();
        assert!(e.contains("duplicate key \"head\""), "{e}");
    }
}
