//! 3-D pose files (`sketchbody-pose3d`, version 1; docs/formats.md): the 15 estimated 3-D joints
//! (metres of a 1.75 m person, model frame), the weak-perspective camera, the chosen dictionary
//! bases, the reprojection RMS, the drawn proportions (per-group bone factors), the plausibility
//! flag, the ranked depth readings (`alternatives`, [`crate::pose::alternatives`]) and the
//! solver options. Written by `sketchbody pose` and `sketchbody run`; [`parse_pose3d`] reads the
//! joints and the alternatives back.

use serde_json::{json, Map, Value};

use crate::error::{Error, Result};
use crate::export::joints::parse_joint_object;
use crate::pose::figure::GROUP_NAMES;
use crate::pose::{Alternative, Dictionary, Limb, PoseEstimate, PoseOptions};
use crate::skeleton::{Joints3, JOINT_NAMES};

/// Format tag of the file.
pub const POSE3D_FORMAT: &str = "sketchbody-pose3d";

/// The `sketchbody-pose3d` document of an estimate made with `dict` and `opts`.
pub fn pose3d_json(est: &PoseEstimate, dict: &Dictionary, opts: &PoseOptions) -> Value {
    let joint_object = |x: &Joints3| -> Map<String, Value> {
        JOINT_NAMES.iter().enumerate().map(|(k, name)| (name.to_string(), json!(x[k]))).collect()
    };
    let j3 = joint_object(&est.joints);
    let alternatives: Vec<Value> = est
        .alternatives
        .iter()
        .map(|a| {
            json!({"joints": joint_object(&a.joints), "score": a.score,
                   "flipped": a.flipped.iter().map(|l| l.name()).collect::<Vec<_>>()})
        })
        .collect();
    let r = est.camera.r;
    let bases: Vec<Value> = est
        .bases
        .iter()
        .zip(&est.weights)
        .map(|(&b, &w)| json!({"index": b, "action": dict.action_of(b).unwrap_or(""), "weight": w}))
        .collect();
    let factors: Map<String, Value> =
        GROUP_NAMES.iter().zip(&est.factors.k).map(|(n, k)| (n.to_string(), json!(k))).collect();
    json!({
        "format": POSE3D_FORMAT,
        "version": 1,
        "units": "metres",
        "joints": j3,
        "camera": {
            "sx": est.camera.sx, "sy": est.camera.sy,
            "r": [[r[(0, 0)], r[(0, 1)], r[(0, 2)]], [r[(1, 0)], r[(1, 1)], r[(1, 2)]], [r[(2, 0)], r[(2, 1)], r[(2, 2)]]],
            "t": est.camera.t,
        },
        "bases": bases,
        "reprojection_rms_px": est.rms,
        "length_excess": est.length_excess,
        "base_exemplars": est.base_parts,
        "proportions": factors,
        "plausible": est.plausible,
        "alternatives": alternatives,
        "options": {"kappa": opts.kappa, "alpha": opts.alpha, "alpha_target": opts.alpha_target.name(), "equal_scales": opts.equal_scales, "max_bases": opts.max_bases, "tolerance": opts.tolerance, "refine": opts.refine, "prior": opts.prior, "starts": opts.starts, "limb_candidates": opts.limb_candidates, "blend": opts.blend, "joint_noise": opts.joint_noise, "proportions": opts.proportions, "depth_prior": opts.depth_prior, "learned_depth_sd": opts.learned_depth_sd, "bone_length_sd": opts.bone_length_sd, "limb_depth_sd": opts.limb_depth_sd, "bend_prior": opts.bend_prior, "straight_limbs": opts.straight_limbs},
    })
}

/// What [`parse_pose3d`] reads of a `sketchbody-pose3d` document.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose3dDoc {
    /// The estimate's 15 joints, metres.
    pub joints: Joints3,
    /// The ranked alternatives (empty when the document has none: files written before they
    /// existed).
    pub alternatives: Vec<Alternative>,
}

/// Reads the joints and the alternatives of a `sketchbody-pose3d` document (format and version
/// checked; a key twice refused). Errors: `CorruptData` naming what is missing or malformed (an
/// unknown limb name, a non-finite score).
pub fn parse_pose3d(text: &str) -> Result<Pose3dDoc> {
    let bad = |m: String| Error::CorruptData(format!("pose3d JSON: {m}"));
    let doc: Value = crate::strict_json::from_str(text).map_err(|e| bad(e.to_string()))?;
    if doc.get("format").and_then(Value::as_str) != Some(POSE3D_FORMAT) {
        return Err(bad(format!("format {:?} (expected {POSE3D_FORMAT:?})", doc.get("format"))));
    }
    if doc.get("version").and_then(Value::as_u64) != Some(1) {
        return Err(bad(format!("version {:?} (expected 1)", doc.get("version"))));
    }
    let joints = parse_joint_object(doc.get("joints").ok_or_else(|| bad("no \"joints\"".into()))?, "pose3d JSON")?;
    let mut alternatives = Vec::new();
    if let Some(alts) = doc.get("alternatives") {
        let alts = alts.as_array().ok_or_else(|| bad("\"alternatives\" is not an array".into()))?;
        for (i, a) in alts.iter().enumerate() {
            let what = format!("pose3d JSON: alternative {i}");
            let j = parse_joint_object(
                a.get("joints").ok_or_else(|| bad(format!("alternative {i} has no joints")))?,
                &what,
            )?;
            let score = a
                .get("score")
                .and_then(Value::as_f64)
                .filter(|s| s.is_finite())
                .ok_or_else(|| bad(format!("alternative {i}: score missing or not a finite number")))?;
            let flipped = a
                .get("flipped")
                .and_then(Value::as_array)
                .ok_or_else(|| bad(format!("alternative {i}: \"flipped\" missing")))?
                .iter()
                .map(|n| {
                    n.as_str().and_then(Limb::parse).ok_or_else(|| bad(format!("alternative {i}: unknown limb {n}")))
                })
                .collect::<Result<Vec<Limb>>>()?;
            alternatives.push(Alternative { joints: j, score, flipped });
        }
    }
    Ok(Pose3dDoc { joints, alternatives })
}
