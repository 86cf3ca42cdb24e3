//! Fitting the facing model ([`sketchbody::detect::facing::FacingModel`]): a multinomial
//! logistic regression of the true facing (from a rendered figure's torso yaw,
//! [`torso_yaw_deg`]) on the facing
//! features of each sketch's evidence, with an L2 penalty on every coefficient but the bias.

use sketchbody::detect::facing::{Facing, FacingModel, FACING_MODEL_FORMAT, FEATURES, NUM_FEATURES};
use sketchbody::detect::figure::evidence_facing_features;
use sketchbody::error::{Error, Result};

use sketchbody::render::sketch::GroundTruth;
use sketchbody::skeleton::joint;

use super::backends::Sample;

/// The yaw in degrees of the posed figure's torso as the camera sees it (as
/// [`sketchbody::render::sketch::CameraAngles::yaw_deg`]: 0 facing the viewer, ±180 seen from
/// behind, −90 a left profile): the direction of (left shoulder − right shoulder) × (neck −
/// pelvis) in the camera's frame. The camera's own yaw is not the figure's when the pose turns
/// the body (a spin, a cartwheel). `None` for a truth without 15 joints or a degenerate torso.
pub fn torso_yaw_deg(t: &GroundTruth) -> Option<f64> {
    let j = &t.joints3d;
    if j.len() != sketchbody::skeleton::NUM_JOINTS {
        return None;
    }
    let d = |a: usize, b: usize| [j[a][0] - j[b][0], j[a][1] - j[b][1], j[a][2] - j[b][2]];
    let (s, u) = (d(joint::L_SHOULDER, joint::R_SHOULDER), d(joint::NECK, joint::PELVIS));
    let fwd = [s[1] * u[2] - s[2] * u[1], s[2] * u[0] - s[0] * u[2], s[0] * u[1] - s[1] * u[0]];
    let r = &t.camera.r;
    let c = |row: usize| r[row][0] * fwd[0] + r[row][1] * fwd[1] + r[row][2] * fwd[2];
    let (x, z) = (c(0), c(2));
    (x.hypot(z) > 1e-12).then(|| x.atan2(z).to_degrees())
}

/// Gradient steps of [`fit_multinomial`].
const STEPS: usize = 4000;

/// Fits the four-facing softmax model on features `x` (each row [`NUM_FEATURES`] long, the
/// first the bias 1) and classes `y` (0..4, [`sketchbody::detect::facing::FACINGS`]' order) with
/// penalty `ridge` (on the standardised features). Features are standardised for the fit and
/// the coefficients mapped back to raw features. Errors: `OutOfRange` when a class has no row.
pub fn fit_multinomial(x: &[[f64; NUM_FEATURES]], y: &[usize], ridge: f64) -> Result<Vec<Vec<f64>>> {
    let n = x.len();
    for k in 0..4 {
        if !y.contains(&k) {
            return Err(Error::OutOfRange { name: "facing rows", detail: format!("no row of class {k} in {n}") });
        }
    }
    let mut mean = [0.0; NUM_FEATURES];
    let mut sd = [1.0; NUM_FEATURES];
    for f in 1..NUM_FEATURES {
        mean[f] = x.iter().map(|r| r[f]).sum::<f64>() / n as f64;
        let v = x.iter().map(|r| (r[f] - mean[f]).powi(2)).sum::<f64>() / n as f64;
        sd[f] = if v > 1e-12 { v.sqrt() } else { 1.0 };
    }
    let z: Vec<[f64; NUM_FEATURES]> =
        x.iter().map(|r| std::array::from_fn(|f| if f == 0 { 1.0 } else { (r[f] - mean[f]) / sd[f] })).collect();
    let mut w = vec![[0.0; NUM_FEATURES]; 4];
    let rate = 0.5;
    for _ in 0..STEPS {
        let mut grad = vec![[0.0; NUM_FEATURES]; 4];
        for (r, &c) in z.iter().zip(y) {
            let s: Vec<f64> = w.iter().map(|wk| wk.iter().zip(r).map(|(a, b)| a * b).sum()).collect();
            let p = sketchbody::detect::facing::softmax(&s);
            for k in 0..4 {
                let e = p[k] - f64::from(u8::from(k == c));
                for f in 0..NUM_FEATURES {
                    grad[k][f] += e * r[f] / n as f64;
                }
            }
        }
        for k in 0..4 {
            for f in 0..NUM_FEATURES {
                let pen = if f == 0 { 0.0 } else { ridge * w[k][f] };
                w[k][f] -= rate * (grad[k][f] + pen);
            }
        }
    }
    Ok(w.iter()
        .map(|wk| {
            let mut raw = vec![0.0; NUM_FEATURES];
            raw[0] = wk[0];
            for f in 1..NUM_FEATURES {
                raw[f] = wk[f] / sd[f];
                raw[0] -= wk[f] * mean[f] / sd[f];
            }
            raw
        })
        .collect())
}

/// The facing model fitted on `samples` (those with a yaw and evidence of a figure). Errors:
/// as [`fit_multinomial`].
pub fn fit_facing(samples: &[Sample], ridge: f64, provenance: &str) -> Result<FacingModel> {
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for s in samples {
        let Some(yaw) = s.yaw_deg else { continue };
        if s.evidence.sketch.is_none() && s.evidence.blazepose.is_none() {
            continue;
        }
        x.push(evidence_facing_features(&s.evidence));
        y.push(Facing::of_yaw(yaw).index().unwrap_or(0));
    }
    Ok(FacingModel {
        format: FACING_MODEL_FORMAT.into(),
        version: 1,
        provenance: provenance.into(),
        features: FEATURES.iter().map(|f| f.to_string()).collect(),
        weights: fit_multinomial(&x, &y, ridge)?,
    })
}

/// The decided facing ([`sketchbody::detect::facing::decided`]) of `model` against the true one
/// on `samples` with a yaw: `table[true][decided]`, true in front, back, left, right, decided the
/// same then `unknown`.
pub fn confusion(samples: &[Sample], model: &FacingModel) -> [[usize; 5]; 4] {
    let mut t = [[0usize; 5]; 4];
    for s in samples {
        let Some(yaw) = s.yaw_deg else { continue };
        if s.evidence.sketch.is_none() && s.evidence.blazepose.is_none() {
            continue;
        }
        let p = model.probabilities(&evidence_facing_features(&s.evidence));
        let d = sketchbody::detect::facing::decided(&p).index().unwrap_or(4);
        t[Facing::of_yaw(yaw).index().unwrap_or(0)][d] += 1;
    }
    t
}

/// A sketch whose facing `model` gets wrong or leaves undecided ([`misread`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Misread {
    /// Its index in the samples.
    pub index: usize,
    /// Its torso's yaw, degrees.
    pub yaw_deg: f64,
    /// The facing decided (`Unknown` when none).
    pub decided: Facing,
    /// The four probabilities.
    pub probabilities: [f64; 4],
    /// Its facing features.
    pub features: [f64; NUM_FEATURES],
}

/// The samples with a yaw and evidence of a figure whose facing under `model`, as the detector
/// acts on it ([`sketchbody::detect::figure::facing_acted_on`]: no back view on a photo-like
/// image), is not the true one.
pub fn misread(samples: &[Sample], model: &FacingModel) -> Vec<Misread> {
    let mut out = Vec::new();
    for (index, s) in samples.iter().enumerate() {
        let Some(yaw_deg) = s.yaw_deg else { continue };
        if s.evidence.sketch.is_none() && s.evidence.blazepose.is_none() {
            continue;
        }
        let features = evidence_facing_features(&s.evidence);
        let probabilities = model.probabilities(&features);
        let decided = sketchbody::detect::figure::facing_acted_on(&s.evidence, &probabilities);
        if decided != Facing::of_yaw(yaw_deg) {
            out.push(Misread { index, yaw_deg, decided, probabilities, features });
        }
    }
    out
}

/// The columns of [`dump_rows`].
pub const DUMP_HEADER: &str = "set,index,yaw_deg,true_facing,features,p_front,p_back,p_left,p_right,decided,\
blazepose_filled,blazepose_flag,sketch_recognised,off_backend,off_handedness,off_pck,off_swapped_pck,on_pck,on_swapped,\
tone_paper,tone_mid,tone_saturation,tone_edges,tone_edges_outside";

/// One CSV row per sample of `samples` (set `label`) with a figure: its facing features (space
/// separated, [`sketchbody::detect::facing::FEATURES`] without the bias) and probabilities
/// under `model`, BlazePose's kept pass (on the filled drawing, its pose flag), whether the
/// sketch model's best figure reaches its own threshold (it recognises a drawing), and `auto`'s
/// answer with `options` without and with the labelling rule: the backend, its handedness and
/// PCK@0.2 of it and of its left/right swap (NaN for no answer). For choosing a labelling rule
/// offline. Errors: the metrics' and [`decide`]'s but `NoFigure`.
pub fn dump_rows(
    label: &str,
    samples: &[Sample],
    model: &FacingModel,
    cal: &sketchbody::detect::calibration::Calibration,
    options: &sketchbody::detect::figure::FigureOptions,
) -> Result<Vec<String>> {
    use sketchbody::detect::facing::{handedness, swap_sides};
    let answer = |s: &Sample, rule: bool| {
        let o = sketchbody::detect::figure::FigureOptions { facing_rule: rule, ..options.clone() };
        match sketchbody::pipeline::figure::decide(&s.evidence, cal, &o, None) {
            Ok(f) => Ok(Some(f)),
            Err(Error::NoFigure { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    };
    let mut rows = Vec::new();
    for (i, s) in samples.iter().enumerate() {
        let Some(t) = &s.truth else { continue };
        let x = evidence_facing_features(&s.evidence);
        let p = model.probabilities(&x);
        let (off, on) = (answer(s, false)?, answer(s, true)?);
        let pck2 = |j: &[[f64; 2]; sketchbody::skeleton::NUM_JOINTS]| super::metrics::pck(t, j, 0.2);
        let (off_h, off_pck, off_sw) = match &off {
            Some(f) => (handedness(&f.joints), pck2(&f.joints.xy)?, pck2(&swap_sides(&f.joints).xy)?),
            None => (f64::NAN, f64::NAN, f64::NAN),
        };
        let (on_pck, on_swapped) = match &on {
            Some(f) => (pck2(&f.joints.xy)?, f.facing.swapped),
            None => (f64::NAN, false),
        };
        let feats: Vec<String> = x[1..].iter().map(|v| format!("{v:.4}")).collect();
        let bp = s.evidence.blazepose.as_ref();
        let tone = s.evidence.tone.map_or([f64::NAN; 5], |t| [t.paper, t.mid, t.saturation, t.edges, t.edges_outside]);
        let tone: Vec<String> = tone.iter().map(|v| format!("{v:.4}")).collect();
        rows.push(format!(
            "{},{i},{},{},{},{:.4},{:.4},{:.4},{:.4},{},{},{:.4},{},{},{off_h:.4},{off_pck:.4},{off_sw:.4},{on_pck:.4},{on_swapped},{}",
            label.replace(',', ";"),
            s.yaw_deg.map_or("".into(), |y| format!("{y:.1}")),
            s.yaw_deg.map_or("", |y| Facing::of_yaw(y).name()),
            feats.join(" "),
            p[0],
            p[1],
            p[2],
            p[3],
            sketchbody::detect::facing::decided(&p).name(),
            bp.is_some_and(|b| b.filled),
            bp.map_or(f64::NAN, |b| b.score),
            s.evidence.sketch.as_ref().and_then(|v| v.first()).is_some_and(|d| d.score
                >= options.sketch.threshold.unwrap_or(s.evidence.sketch_threshold)),
            off.as_ref().map_or("none", |f| f.backend.name()),
            tone.join(","),
        ));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A procedural (upright, unturned) figure's torso yaw is the camera's.
    #[test]
    fn the_torso_yaw_follows_the_camera_of_an_unturned_figure() {
        use sketchbody::render::sketch::{CameraAngles, SketchRenderer, SketchRequest};
        let r =
            SketchRenderer::new(std::sync::Arc::new(sketchbody::body::BodyModel::embedded().unwrap()), None).unwrap();
        for (seed, yaw) in [(1u64, 0.0f64), (2, 180.0), (3, -90.0), (4, 60.0)] {
            let req = SketchRequest {
                camera: Some(CameraAngles { yaw_deg: yaw, pitch_deg: 0.0, roll_deg: 0.0 }),
                ..SketchRequest::random(seed, 128)
            };
            let t = r.render(&req).unwrap().truth;
            let got = torso_yaw_deg(&t).unwrap();
            let diff = (got - yaw + 540.0).rem_euclid(360.0) - 180.0;
            assert!(diff.abs() < 25.0, "camera yaw {yaw}: torso yaw {got}");
            assert_eq!(Facing::of_yaw(got), Facing::of_yaw(yaw));
        }
        let mut t = r.render(&SketchRequest::random(5, 64)).unwrap().truth;
        t.joints3d.pop();
        assert_eq!(torso_yaw_deg(&t), None);
    }

    /// Classes separated by one feature are recovered, the probabilities follow it, and a
    /// class without rows is refused.
    #[test]
    fn the_fit_separates_classes_by_their_feature() {
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in 0..200 {
            let c = i % 4;
            let mut r = [0.0; NUM_FEATURES];
            r[0] = 1.0;
            r[2] = [1.0, -1.0, 0.0, 0.0][c] + 0.01 * (i as f64 % 7.0);
            r[10] = [0.0, 0.0, -1.0, 1.0][c];
            x.push(r);
            y.push(c);
        }
        let w = fit_multinomial(&x, &y, 1e-3).unwrap();
        let m = FacingModel {
            format: FACING_MODEL_FORMAT.into(),
            version: 1,
            provenance: "test".into(),
            features: FEATURES.iter().map(|f| f.to_string()).collect(),
            weights: w,
        };
        for (r, &c) in x.iter().zip(&y) {
            let p = m.probabilities(r);
            assert!(p[c] > 0.8, "class {c}: {p:?}");
        }
        assert!(fit_multinomial(&x[..1], &y[..1], 1e-3).is_err());
    }
}
