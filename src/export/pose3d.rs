//! 3-D pose files (`sketchbody-pose3d`, version 1; docs/formats.md): the 15 estimated 3-D joints
//! (metres of a 1.75 m person, model frame), the weak-perspective camera, the chosen dictionary
//! bases, the reprojection RMS, the drawn proportions (per-group bone factors), the plausibility
//! flag and the solver options. Written by `sketchbody pose` and
//! `sketchbody run`.

use serde_json::{json, Map, Value};

use crate::pose::figure::GROUP_NAMES;
use crate::pose::{Dictionary, PoseEstimate, PoseOptions};
use crate::skeleton::JOINT_NAMES;

/// Format tag of the file.
pub const POSE3D_FORMAT: &str = "sketchbody-pose3d";

/// The `sketchbody-pose3d` document of an estimate made with `dict` and `opts`.
pub fn pose3d_json(est: &PoseEstimate, dict: &Dictionary, opts: &PoseOptions) -> Value {
    let mut j3 = Map::new();
    for (k, name) in JOINT_NAMES.iter().enumerate() {
        j3.insert(name.to_string(), json!(est.joints[k]));
    }
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
        "options": {"kappa": opts.kappa, "alpha": opts.alpha, "alpha_target": opts.alpha_target.name(), "equal_scales": opts.equal_scales, "max_bases": opts.max_bases, "tolerance": opts.tolerance, "refine": opts.refine, "prior": opts.prior, "starts": opts.starts, "limb_candidates": opts.limb_candidates, "blend": opts.blend, "joint_noise": opts.joint_noise, "proportions": opts.proportions, "depth_prior": opts.depth_prior, "straight_limbs": opts.straight_limbs},
    })
}
