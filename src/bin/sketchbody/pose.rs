//! `sketchbody pose JOINTS2D.json --out POSE3D.json`: 3-D pose and camera from 2-D joints
//! (formats in docs/formats.md).

use std::path::PathBuf;

use serde_json::{json, Map, Value};
use sketchbody::fsutil::write_atomic;
use sketchbody::pose::{dict_io, estimate_pose, PoseOptions};
use sketchbody::skeleton::{joint_index, Joints2, JOINT_NAMES, NUM_JOINTS};

use crate::CliError;

/// Arguments of `sketchbody pose`.
#[derive(clap::Args)]
pub struct Args {
    /// Input 2-D joints (JSON, format "sketchbody-joints2d").
    input: PathBuf,
    /// Output 3-D pose (JSON, format "sketchbody-pose3d").
    #[arg(long)]
    out: PathBuf,
    /// Pose dictionary file (default: the embedded one).
    #[arg(long)]
    dictionary: Option<PathBuf>,
    /// Relative limb-length tolerance κ (0 = equality).
    #[arg(long, default_value_t = PoseOptions::default().kappa)]
    kappa: f64,
    /// Pull of the camera rotation toward identity, α in [0, 1].
    #[arg(long, default_value_t = PoseOptions::default().alpha)]
    alpha: f64,
    /// Most bases to choose (0..=32).
    #[arg(long, default_value_t = PoseOptions::default().max_bases)]
    max_bases: usize,
    /// Stop adding bases at this reprojection RMS, pixels.
    #[arg(long, default_value_t = PoseOptions::default().tolerance)]
    tolerance: f64,
    /// Weight prior, metres (0 = the paper's eq. 3).
    #[arg(long, default_value_t = PoseOptions::default().prior)]
    prior: f64,
    /// Nearest-neighbour starts (exemplar poses tried; 0 = start from the mean pose, the paper).
    #[arg(long, default_value_t = PoseOptions::default().starts)]
    starts: usize,
    /// Limb candidates for recomposing exemplar starts (0 = whole exemplars).
    #[arg(long, default_value_t = PoseOptions::default().limb_candidates)]
    limb_candidates: usize,
    /// Blend temperature of the exemplar starts' hypotheses, px² per joint (0 = the best one).
    #[arg(long, default_value_t = PoseOptions::default().blend)]
    blend: f64,
    /// Skip the final Levenberg–Marquardt refinement.
    #[arg(long)]
    no_refine: bool,
}

fn bad(path: &std::path::Path, m: impl std::fmt::Display) -> CliError {
    CliError(format!("{}: {m}", path.display()))
}

/// Parses a "sketchbody-joints2d" document.
fn parse_joints(v: &Value, path: &std::path::Path) -> Result<Joints2, CliError> {
    if v.get("format").and_then(Value::as_str) != Some("sketchbody-joints2d") {
        return Err(bad(path, "not a sketchbody-joints2d file (\"format\" missing or different)"));
    }
    if v.get("version").and_then(Value::as_u64) != Some(1) {
        return Err(bad(path, "unsupported version (expected 1)"));
    }
    let joints = v.get("joints").and_then(Value::as_object).ok_or_else(|| bad(path, "\"joints\" must be an object"))?;
    let mut j = Joints2 { xy: [[f64::NAN; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    let mut seen = [false; NUM_JOINTS];
    for (name, xy) in joints {
        let k = joint_index(name).ok_or_else(|| bad(path, format!("unknown joint {name:?}")))?;
        let arr = xy.as_array().filter(|a| a.len() == 2).ok_or_else(|| bad(path, format!("{name} must be [x, y]")))?;
        let num = |i: usize| arr[i].as_f64().ok_or_else(|| bad(path, format!("{name}: coordinates must be numbers")));
        j.xy[k] = [num(0)?, num(1)?];
        seen[k] = true;
    }
    if let Some(missing) = seen.iter().position(|s| !s) {
        return Err(bad(path, format!("joint {} is missing (all 15 are needed; mark unknown ones in \"missing\")", JOINT_NAMES[missing])));
    }
    if let Some(list) = v.get("missing") {
        for name in list.as_array().ok_or_else(|| bad(path, "\"missing\" must be a list of joint names"))? {
            let n = name.as_str().unwrap_or("");
            let k = joint_index(n).ok_or_else(|| bad(path, format!("unknown joint {name} in \"missing\"")))?;
            j.visible[k] = false;
        }
    }
    Ok(j)
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let text = std::fs::read_to_string(&a.input).map_err(|e| bad(&a.input, e))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| bad(&a.input, format!("not JSON: {e}")))?;
    let joints = parse_joints(&v, &a.input)?;
    let dict = match &a.dictionary {
        Some(p) => dict_io::read(p)?,
        None => dict_io::embedded()?,
    };
    let opts = PoseOptions {
        kappa: a.kappa,
        alpha: a.alpha,
        max_bases: a.max_bases,
        tolerance: a.tolerance,
        refine: !a.no_refine,
        prior: a.prior,
        starts: a.starts,
        limb_candidates: a.limb_candidates,
        blend: a.blend,
    };
    let est = estimate_pose(&dict, &joints, &opts)?;
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
    let doc = json!({
        "format": "sketchbody-pose3d",
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
        "options": {"kappa": opts.kappa, "alpha": opts.alpha, "max_bases": opts.max_bases, "tolerance": opts.tolerance, "refine": opts.refine, "prior": opts.prior, "starts": opts.starts, "limb_candidates": opts.limb_candidates, "blend": opts.blend},
    });
    let mut bytes = serde_json::to_vec_pretty(&doc).map_err(|e| CliError(e.to_string()))?;
    bytes.push(b'\n');
    write_atomic(&a.out, &bytes)?;
    println!("{}: {} bases, reprojection RMS {:.3} px", a.out.display(), est.bases.len(), est.rms);
    Ok(())
}
