//! Ground truth of a sketch and its files. A sample `STEM` is three files written atomically in
//! this order: `STEM.mesh` (rest and posed vertices, binary), `STEM.json` ([`GroundTruth`]) and
//! `STEM.png` (the gray sketch); a sample is complete when all three exist. Layout in
//! `docs/dataset.md`.
//!
//! `.mesh` format (little-endian): magic `SKBSMESH`, u32 version = 1, u32 V, V × 3 f32 rest
//! vertices, V × 3 f32 posed vertices (metres, model frame), u32 CRC-32 of every byte before it.
//! Faces are the body model's (`BodyModel::faces`), the same for every sample.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::scene::CameraAngles;
use super::style::SketchStyle;
use super::{Sketch, SketchRequest};
use crate::body::Gender;
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::skeleton::{Joints2, Joints3};

/// Format tag of the ground-truth JSON.
pub const TRUTH_FORMAT: &str = "sketchbody-sketch-truth-1";
/// Magic of the `.mesh` file.
pub const MESH_MAGIC: &[u8; 8] = b"SKBSMESH";

/// The camera in JSON: eq. (1) `u = sx (R X)_x + tx`, `v = −sy (R X)_y + ty`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraJson {
    /// Pixels per metre, x.
    pub sx: f64,
    /// Pixels per metre, y.
    pub sy: f64,
    /// Rotation, row-major.
    pub r: [[f64; 3]; 3],
    /// Image position of the model origin, pixels.
    pub t: [f64; 2],
    /// The angles that made `r`.
    pub angles: CameraAngles,
}

impl CameraJson {
    /// Back to a camera (validated).
    pub fn to_camera(&self) -> Result<WeakPerspective> {
        let r = nalgebra::Matrix3::from_fn(|i, j| self.r[i][j]);
        let c = WeakPerspective { sx: self.sx, sy: self.sy, r, t: self.t };
        c.validate()?;
        Ok(c)
    }
}

/// Everything known about one sketch (the `.json` file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GroundTruth {
    /// [`TRUTH_FORMAT`].
    pub format: String,
    /// The request's seed.
    pub seed: u64,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// `female` or `male`.
    pub gender: String,
    /// PCA shape weights (metres) of the body before proportions.
    pub shape_weights: Vec<f64>,
    /// 15 joints in the image, pixels (docs/design.md image frame, canonical order).
    pub joints2d: Vec<[f64; 2]>,
    /// Whether each joint is visible (not hidden by another body part, inside the image).
    pub visible: Vec<bool>,
    /// 15 posed joints, metres, model frame (pelvis at the origin); `camera` projects them.
    pub joints3d: Vec<[f64; 3]>,
    /// 15 rest joints (proportions applied), metres, model frame.
    pub rest_joints3d: Vec<[f64; 3]>,
    /// The camera.
    pub camera: CameraJson,
    /// Height of the rest mesh (max y − min y), metres: the normaliser of AED and MPJPE.
    pub height_m: f64,
    /// `mocap:CLIP:FRAME`, `procedural` or `given`.
    pub pose_source: String,
    /// The drawing style (includes proportions, costume and hair).
    pub style: SketchStyle,
    /// A turnaround's other views of the same posed body (the sample's own image and truth are
    /// the front view); empty (and absent from the JSON) for a single-view sample.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub views: Vec<ViewTruth>,
}

/// One extra view of a turnaround sample ([`GroundTruth::views`]): the same posed body with the
/// camera turned `yaw_deg` about the body's vertical axis (model +Y), so its rotation is the
/// front camera's times R_y(`yaw_deg`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewTruth {
    /// `side` (yaw +90°: the body's right side, facing image right) or `back` (yaw +180°).
    pub label: String,
    /// The view's yaw relative to the front view, degrees.
    pub yaw_deg: f64,
    /// The view's gray sketch, a file name in the sample's folder (`STEM_LABEL.png`).
    pub image: String,
    /// 15 joints in the view's image, pixels (canonical order).
    pub joints2d: Vec<[f64; 2]>,
    /// Whether each joint is visible in the view.
    pub visible: Vec<bool>,
    /// The view's camera (projects [`GroundTruth::joints3d`]).
    pub camera: CameraJson,
}

impl GroundTruth {
    /// Assembles the ground truth of a rendered request.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        req: &SketchRequest,
        gender: Gender,
        shape_weights: Vec<f64>,
        j2: Joints2,
        joints: &Joints3,
        rest: &Joints3,
        cam: &WeakPerspective,
        angles: CameraAngles,
        height_m: f64,
        pose_source: String,
        style: SketchStyle,
    ) -> GroundTruth {
        GroundTruth {
            format: TRUTH_FORMAT.into(),
            seed: req.seed,
            width: req.width,
            height: req.height,
            gender: gender.name().into(),
            shape_weights,
            joints2d: j2.xy.to_vec(),
            visible: j2.visible.to_vec(),
            joints3d: joints.to_vec(),
            rest_joints3d: rest.to_vec(),
            camera: CameraJson {
                sx: cam.sx,
                sy: cam.sy,
                r: std::array::from_fn(|i| std::array::from_fn(|j| cam.r[(i, j)])),
                t: cam.t,
                angles,
            },
            height_m,
            pose_source,
            style,
            views: Vec::new(),
        }
    }

    /// Parses and checks a ground-truth JSON (format tag, 15 joints each, positive height).
    pub fn from_json(text: &str, what: &str) -> Result<GroundTruth> {
        let t: GroundTruth = serde_json::from_str(text).map_err(|e| Error::CorruptData(format!("{what}: {e}")))?;
        if t.format != TRUTH_FORMAT {
            return Err(Error::CorruptData(format!("{what}: format is {:?}, expected {TRUTH_FORMAT:?}", t.format)));
        }
        if t.joints2d.len() != 15 || t.visible.len() != 15 || t.joints3d.len() != 15 || t.rest_joints3d.len() != 15 {
            return Err(Error::CorruptData(format!("{what}: joint lists must hold 15 entries")));
        }
        if !(t.height_m.is_finite() && t.height_m > 0.0) {
            return Err(Error::CorruptData(format!("{what}: height_m {} is not positive", t.height_m)));
        }
        for v in &t.views {
            if v.joints2d.len() != 15 || v.visible.len() != 15 {
                return Err(Error::CorruptData(format!("{what}: view {}: joint lists must hold 15 entries", v.label)));
            }
            if v.image.contains(['/', '\\']) || v.image.is_empty() {
                return Err(Error::CorruptData(format!(
                    "{what}: view {}: image {:?} is not a file name",
                    v.label, v.image
                )));
            }
        }
        Ok(t)
    }
}

/// Encodes the `.mesh` file (module doc).
pub fn mesh_bytes(rest: &[[f32; 3]], posed: &[[f32; 3]]) -> Result<Vec<u8>> {
    if rest.len() != posed.len() {
        return Err(Error::OutOfRange {
            name: "mesh",
            detail: format!("{} rest vs {} posed vertices", rest.len(), posed.len()),
        });
    }
    let mut b = Vec::with_capacity(20 + rest.len() * 24);
    b.extend_from_slice(MESH_MAGIC);
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&(rest.len() as u32).to_le_bytes());
    for v in rest.iter().chain(posed) {
        for c in v {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    let crc = crc32fast::hash(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    Ok(b)
}

/// Decodes a `.mesh` file into (rest, posed). Errors ([`Error::CorruptData`]): magic, version,
/// length, CRC, non-finite values.
#[allow(clippy::type_complexity)] // (rest vertices, posed vertices)
pub fn parse_mesh(b: &[u8], what: &str) -> Result<(Vec<[f32; 3]>, Vec<[f32; 3]>)> {
    let bad = |m: &str| Error::CorruptData(format!("{what}: {m}"));
    if b.len() < 20 || &b[..8] != MESH_MAGIC {
        return Err(bad("not a sketchbody .mesh file"));
    }
    let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
    if u32_at(8) != 1 {
        return Err(bad(&format!("version {} is not 1", u32_at(8))));
    }
    let n = u32_at(12) as usize;
    if b.len() as u64 != 20 + 24 * n as u64 {
        return Err(bad(&format!("length {} does not match {n} vertices", b.len())));
    }
    if crc32fast::hash(&b[..b.len() - 4]) != u32_at(b.len() - 4) {
        return Err(bad("CRC mismatch"));
    }
    let f = |k: usize| f32::from_le_bytes([b[16 + 4 * k], b[17 + 4 * k], b[18 + 4 * k], b[19 + 4 * k]]);
    let mut vs: Vec<[f32; 3]> = Vec::with_capacity(2 * n);
    for i in 0..2 * n {
        let v = [f(3 * i), f(3 * i + 1), f(3 * i + 2)];
        if v.iter().any(|x| !x.is_finite()) {
            return Err(bad(&format!("vertex {i} is not finite")));
        }
        vs.push(v);
    }
    let posed = vs.split_off(n);
    Ok((vs, posed))
}

/// The three files of sample `stem` in `dir`: (mesh, json, png).
pub fn sample_paths(dir: &Path, stem: &str) -> [PathBuf; 3] {
    [dir.join(format!("{stem}.mesh")), dir.join(format!("{stem}.json")), dir.join(format!("{stem}.png"))]
}

/// `true` when all three files of the sample exist.
pub fn sample_complete(dir: &Path, stem: &str) -> bool {
    sample_paths(dir, stem).iter().all(|p| p.is_file())
}

/// Writes a sample's three files atomically, the PNG last.
pub fn write_sample(dir: &Path, stem: &str, s: &Sketch) -> Result<()> {
    let [mesh, json, png] = sample_paths(dir, stem);
    write_atomic(&mesh, &mesh_bytes(&s.rest_vertices, &s.posed_vertices)?)?;
    let text =
        serde_json::to_string_pretty(&s.truth).map_err(|e| Error::CorruptData(format!("ground truth JSON: {e}")))?;
    write_atomic(&json, text.as_bytes())?;
    let img = crate::image::GrayImage::from_vec(s.truth.width, s.truth.height, s.pixels.clone())?;
    crate::image::save_png(&img.view(), &png)
}

/// The seed of sample `index` of a dataset made with `seed` (SplitMix64 of both), independent of
/// the order or thread in which samples are made.
pub fn sample_seed(seed: u64, index: u64) -> u64 {
    fn mix(mut z: u64) -> u64 {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    mix(mix(seed) ^ index)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mesh_round_trips_and_rejects_damage() {
        let rest = vec![[1.0f32, 2.0, 3.0], [4.0, 5.0, 6.0]];
        let posed = vec![[0.5f32, 0.0, -1.0], [7.0, 8.0, 9.0]];
        let b = mesh_bytes(&rest, &posed).unwrap();
        assert_eq!(parse_mesh(&b, "t").unwrap(), (rest.clone(), posed.clone()));
        let mut bad = b.clone();
        bad[20] ^= 1;
        assert!(parse_mesh(&bad, "t").unwrap_err().to_string().contains("CRC"));
        assert!(parse_mesh(&b[..b.len() - 1], "t").is_err());
        assert!(mesh_bytes(&rest, &posed[..1]).is_err());
        assert_ne!(sample_seed(1, 0), sample_seed(1, 1));
        assert_ne!(sample_seed(1, 0), sample_seed(2, 0));
        assert_eq!(sample_seed(5, 7), sample_seed(5, 7));
    }
}
