//! Scoring one results folder against a dataset (layout in `docs/dataset.md`).
//!
//! For sample `STEM` the results folder may hold `STEM.json` (`joints2d`: 15 × [x, y] pixels;
//! `joints3d`: 15 × [x, y, z] posed joints; `camera_r`: 3 × 3 rotation, row-major, that takes
//! `joints3d` and the posed mesh into the camera frame — omit it when they already are in the
//! camera frame), `STEM_rest.obj` and `STEM_posed.obj` (the body model's vertices, same count and
//! order). Each metric is computed when its inputs exist.
//!
//! - AED rest: eq. (10) between the rest meshes, divided by the reference rest height, no
//!   alignment (both are in the model frame).
//! - AED rest centred (diagnostic): the same with each mesh centred on its centroid. The rest
//!   mesh's place in the model frame follows from how the shape is built (a taller PCA body
//!   grows about the model origin, longer legs about the pelvis), which an image does not show;
//!   this column drops that translation, as the posed AED does.
//! - AED rest at height (diagnostic): the same after scaling the estimate about its feet to the
//!   reference height ([`scale_to_height`]); height ratio: estimate's rest height (Y extent) /
//!   the reference height. A sketch alone does not fix the absolute size; these two columns
//!   split the rest AED into its size and its shape part.
//! - AED posed: eq. (10) between the posed meshes in the camera frame, each centred on its
//!   centroid (a sketch does not fix the global position).
//! - MPJPE: joints in the camera frame, the estimate scaled about its pelvis to the reference's
//!   total bone length and moved so the pelvises coincide; millimetres of the reference body
//!   (whose height is `height_m` of the ground truth).
//! - PA-MPJPE: after a similarity Procrustes alignment; millimetres.
//! - PCK@α: fraction of the 15 joints within α × (longer side of the reference 2-D joint box).

use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

use super::metrics::{aed, centred, height_of, mpjpe, pa_mpjpe, pck, scale_to_height, scale_to_reference};
use sketchbody::error::{Error, Result};
use sketchbody::render::sketch::truth::{parse_mesh, GroundTruth};
use sketchbody::skeleton::{joint, BONES, NUM_JOINTS};

/// A method's output for one sample; every part optional.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// 15 joints, pixels.
    pub joints2d: Option<Vec<[f64; 2]>>,
    /// 15 posed joints, metres (any scale is accepted: it is normalised).
    pub joints3d: Option<Vec<[f64; 3]>>,
    /// Rotation into the camera frame (identity when absent).
    pub camera_r: Option<[[f64; 3]; 3]>,
    /// Rest-pose vertices.
    pub rest: Option<Vec<[f64; 3]>>,
    /// Posed vertices.
    pub posed: Option<Vec<[f64; 3]>>,
}

#[derive(Deserialize)]
struct EstimateJson {
    joints2d: Option<Vec<[f64; 2]>>,
    joints3d: Option<Vec<[f64; 3]>>,
    camera_r: Option<[[f64; 3]; 3]>,
}

/// Per-sample scores (`None`: not computable from what the results hold).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SampleScore {
    /// Sample stem.
    pub sample: String,
    /// AED between rest meshes, fraction of the reference height.
    pub aed_rest: Option<f64>,
    /// AED between rest meshes each centred on its centroid, fraction of the reference height
    /// (diagnostic).
    pub aed_rest_centred: Option<f64>,
    /// AED between rest meshes after scaling the estimate about its feet to the reference
    /// height, fraction of the reference height (diagnostic).
    pub aed_rest_at_height: Option<f64>,
    /// Estimated rest height / reference height (diagnostic).
    pub height_ratio: Option<f64>,
    /// AED between posed meshes, fraction of the reference height.
    pub aed_posed: Option<f64>,
    /// MPJPE, mm.
    pub mpjpe_mm: Option<f64>,
    /// PA-MPJPE, mm.
    pub pa_mpjpe_mm: Option<f64>,
    /// PCK@0.1.
    pub pck10: Option<f64>,
    /// PCK@0.2.
    pub pck20: Option<f64>,
}

/// Metric names in the order of [`SampleScore::values`].
pub const METRICS: [&str; 9] = [
    "aed_rest",
    "aed_rest_centred",
    "aed_rest_at_height",
    "height_ratio",
    "aed_posed",
    "mpjpe_mm",
    "pa_mpjpe_mm",
    "pck@0.1",
    "pck@0.2",
];

/// Decimals each metric is printed with, [`METRICS`] order.
pub const METRIC_DECIMALS: [usize; 9] = [4, 4, 4, 3, 4, 1, 1, 3, 3];

impl SampleScore {
    /// The metrics in [`METRICS`] order.
    pub fn values(&self) -> [Option<f64>; 9] {
        [
            self.aed_rest,
            self.aed_rest_centred,
            self.aed_rest_at_height,
            self.height_ratio,
            self.aed_posed,
            self.mpjpe_mm,
            self.pa_mpjpe_mm,
            self.pck10,
            self.pck20,
        ]
    }
}

/// Mean and count of each metric over the scored samples, and how many samples there were.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Samples in the dataset.
    pub samples: usize,
    /// (mean, count) per metric, [`METRICS`] order; mean is NaN when count is 0.
    pub metrics: [(f64, usize); 9],
}

impl Summary {
    /// Summarises per-sample scores of a dataset of `samples` samples.
    pub fn new(scores: &[SampleScore], samples: usize) -> Summary {
        let metrics = std::array::from_fn(|k| {
            let vals: Vec<f64> = scores.iter().filter_map(|s| s.values()[k]).collect();
            let mean = if vals.is_empty() { f64::NAN } else { vals.iter().sum::<f64>() / vals.len() as f64 };
            (mean, vals.len())
        });
        Summary { samples, metrics }
    }
}

/// Reads the `v` lines of an OBJ file.
pub fn read_obj_vertices(path: &Path) -> Result<Vec<[f64; 3]>> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        if it.next() != Some("v") {
            continue;
        }
        let c: Vec<f64> = it
            .take(3)
            .map(|x| x.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| Error::CorruptData(format!("{}: line {}: {e}", path.display(), i + 1)))?;
        if c.len() != 3 || c.iter().any(|x| !x.is_finite()) {
            return Err(Error::CorruptData(format!(
                "{}: line {}: a vertex needs 3 finite numbers",
                path.display(),
                i + 1
            )));
        }
        out.push([c[0], c[1], c[2]]);
    }
    Ok(out)
}

/// Loads the estimate of sample `stem` from `dir`; `None` when none of its files exists.
pub fn load_estimate(dir: &Path, stem: &str) -> Result<Option<Estimate>> {
    let json = dir.join(format!("{stem}.json"));
    let (rest, posed) = (dir.join(format!("{stem}_rest.obj")), dir.join(format!("{stem}_posed.obj")));
    if !json.is_file() && !rest.is_file() && !posed.is_file() {
        return Ok(None);
    }
    let mut e = Estimate::default();
    if json.is_file() {
        let text = std::fs::read_to_string(&json).map_err(|source| Error::Io { path: json.clone(), source })?;
        let j: EstimateJson =
            serde_json::from_str(&text).map_err(|err| Error::CorruptData(format!("{}: {err}", json.display())))?;
        for (name, n) in
            [("joints2d", j.joints2d.as_ref().map(|v| v.len())), ("joints3d", j.joints3d.as_ref().map(|v| v.len()))]
        {
            if n.is_some_and(|n| n != NUM_JOINTS) {
                return Err(Error::CorruptData(format!("{}: {name} must hold 15 joints", json.display())));
            }
        }
        (e.joints2d, e.joints3d, e.camera_r) = (j.joints2d, j.joints3d, j.camera_r);
    }
    if rest.is_file() {
        e.rest = Some(read_obj_vertices(&rest)?);
    }
    if posed.is_file() {
        e.posed = Some(read_obj_vertices(&posed)?);
    }
    Ok(Some(e))
}

fn rotate(r: &Matrix3<f64>, p: &[[f64; 3]]) -> Vec<[f64; 3]> {
    p.iter().map(|x| (r * Vector3::from(*x)).into()).collect()
}

fn to_f64(v: &[[f32; 3]]) -> Vec<[f64; 3]> {
    v.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect()
}

/// Scores one estimate against its ground truth and reference meshes (see the module doc).
pub fn score_sample(
    stem: &str,
    truth: &GroundTruth,
    rest_ref: &[[f32; 3]],
    posed_ref: &[[f32; 3]],
    est: &Estimate,
) -> Result<SampleScore> {
    let h = truth.height_m;
    let r_gt = truth.camera.to_camera()?.r;
    let r_est = match est.camera_r {
        Some(r) => {
            let m = Matrix3::from_fn(|i, j| r[i][j]);
            if m.iter().any(|x| !x.is_finite()) || (m.transpose() * m - Matrix3::identity()).norm() > 1e-3 {
                return Err(Error::OutOfRange { name: "camera_r", detail: format!("sample {stem}: not a rotation") });
            }
            m
        }
        None => Matrix3::identity(),
    };
    let mut s = SampleScore { sample: stem.to_string(), ..Default::default() };
    if let Some(rest) = &est.rest {
        let reference = to_f64(rest_ref);
        s.aed_rest = Some(aed(&reference, rest, h)?);
        s.aed_rest_centred = Some(aed(&centred(&reference), &centred(rest), h)?);
        s.aed_rest_at_height = Some(aed(&reference, &scale_to_height(&reference, rest, h)?, h)?);
        s.height_ratio = Some(height_of(rest)? / h);
    }
    if let Some(posed) = &est.posed {
        let a = centred(&rotate(&r_gt, &to_f64(posed_ref)));
        let b = centred(&rotate(&r_est, posed));
        s.aed_posed = Some(aed(&a, &b, h)?);
    }
    if let Some(j3) = &est.joints3d {
        let a = rotate(&r_gt, &truth.joints3d);
        let b = scale_to_reference(&a, &rotate(&r_est, j3), &BONES, joint::PELVIS)?;
        s.mpjpe_mm = Some(1000.0 * mpjpe(&a, &b, joint::PELVIS)?);
        s.pa_mpjpe_mm = Some(1000.0 * pa_mpjpe(&a, &b)?);
    }
    if let Some(j2) = &est.joints2d {
        s.pck10 = Some(pck(&truth.joints2d, j2, 0.1)?);
        s.pck20 = Some(pck(&truth.joints2d, j2, 0.2)?);
    }
    Ok(s)
}

/// The sample stems of a dataset folder: every `STEM.json` with a `STEM.mesh` beside it, sorted.
pub fn dataset_samples(dataset: &Path) -> Result<Vec<String>> {
    let rd = std::fs::read_dir(dataset).map_err(|source| Error::Io { path: dataset.to_path_buf(), source })?;
    let mut stems: Vec<String> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json") && p.with_extension("mesh").is_file())
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    stems.sort();
    Ok(stems)
}

/// Scores every sample of `dataset` that `results` holds an estimate for. Returns the scores
/// and the number of dataset samples. Errors: unreadable folders or files, damaged ground truth.
pub fn score_dataset(dataset: &Path, results: &Path) -> Result<(Vec<SampleScore>, usize)> {
    if !results.is_dir() {
        return Err(Error::Io {
            path: results.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "results folder not found"),
        });
    }
    let stems = dataset_samples(dataset)?;
    let mut out = Vec::new();
    for stem in &stems {
        let Some(est) = load_estimate(results, stem)? else { continue };
        let jp = dataset.join(format!("{stem}.json"));
        let text = std::fs::read_to_string(&jp).map_err(|source| Error::Io { path: jp.clone(), source })?;
        let truth = GroundTruth::from_json(&text, &jp.display().to_string())?;
        let mp = dataset.join(format!("{stem}.mesh"));
        let bytes = std::fs::read(&mp).map_err(|source| Error::Io { path: mp.clone(), source })?;
        let (rest, posed) = parse_mesh(&bytes, &mp.display().to_string())?;
        out.push(score_sample(stem, &truth, &rest, &posed, &est)?);
    }
    Ok((out, stems.len()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sketchbody::render::sketch::{SketchRenderer, SketchRequest};

    /// A rest estimate that is the reference moved by 5 cm along Y and 2 cm along X: the
    /// unaligned AED is the shift over the height, the centred one 0, the at-height one 0
    /// after its feet are moved onto the reference's, apart from the X part.
    #[test]
    fn rest_aeds_split_the_translation_from_the_shape() {
        let r =
            SketchRenderer::new(std::sync::Arc::new(sketchbody::body::BodyModel::embedded().unwrap()), None).unwrap();
        let s = r.render(&SketchRequest::random(3, 64)).unwrap();
        let h = s.truth.height_m;
        let rest: Vec<[f64; 3]> =
            s.rest_vertices.iter().map(|v| [v[0] as f64 + 0.02, v[1] as f64 + 0.05, v[2] as f64]).collect();
        let est = Estimate { rest: Some(rest), ..Estimate::default() };
        let sc = score_sample("x", &s.truth, &s.rest_vertices, &s.posed_vertices, &est).unwrap();
        let shift = (0.02f64.hypot(0.05)) / h;
        assert!((sc.aed_rest.unwrap() - shift).abs() < 1e-6, "{:?} vs {shift}", sc.aed_rest);
        assert!(sc.aed_rest_centred.unwrap() < 1e-6, "{:?}", sc.aed_rest_centred);
        assert!((sc.aed_rest_at_height.unwrap() - 0.02 / h).abs() < 1e-6, "{:?}", sc.aed_rest_at_height);
        assert!((sc.height_ratio.unwrap() - 1.0).abs() < 1e-6);
        assert_eq!((sc.aed_posed, sc.mpjpe_mm, sc.pck10), (None, None, None));
    }
}
