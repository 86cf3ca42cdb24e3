//! The figure's facing (issue 51): front, back, left or right profile, decided from the evidence
//! the image holds, and the left/right labelling that follows from it. The evidence
//! ([`facing_features`]): how far apart each backend put the two sides (small for a profile),
//! BlazePose's face landmarks (their visibility, the nose beside the ears) and its depth of the
//! shoulders, and the ink inside the head, the direction of its strokes and how many of them
//! lines across and along the head cross ([`head_ink`]: hair drawn over a head seen from behind,
//! or a face). Which side a backend labelled left is not evidence: both label a faceless outline
//! either way. A multinomial logistic model ([`FacingModel`], fitted by `sketchbody-lab fit-facing` on rendered
//! sketches of every yaw, embedded from `assets/facing_model.json`) turns them into the four
//! probabilities; under [`DECIDE`] the facing is [`Facing::Unknown`], except a back view that
//! the front hardly competes with ([`decided`]).
//!
//! The labelling rule ([`target_handedness`]): a figure read as seen from behind gets the back
//! view's labelling, every other figure whose front or back dominates its profiles the front's:
//! with no evidence either way a figure faces the viewer, and a labelling that implies a back
//! view without evidence of one is swapped back.

use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::image::ImageView;
use crate::skeleton::{joint, Joints2, MIRROR, NUM_JOINTS};

/// The embedded facing model (`assets/facing_model.json`).
pub static EMBEDDED_FACING_MODEL: &str = include_str!("../../assets/facing_model.json");

/// The format tag of a facing model file.
pub const FACING_MODEL_FORMAT: &str = "sketchbody-facing-model";

/// The smallest probability of the likeliest facing for it to be decided; under it the facing
/// is [`Facing::Unknown`] (the probabilities are still reported).
pub const DECIDE: f64 = 0.6;

/// The smallest probability of a likeliest back view decided under [`DECIDE`] ([`decided`]).
pub const BACK_DECIDE: f64 = 0.5;

/// The smallest share of the front's and back's probability a back view under [`DECIDE`] must
/// hold to be decided ([`decided`]).
pub const BACK_OVER_FRONT: f64 = 0.9;

/// The smallest |handedness| ([`handedness`]) at which a labelling is swapped to the target's
/// side: under it the shoulders and hips overlap in the image (a profile) and the sign says
/// nothing.
pub const MIN_HANDEDNESS: f64 = 0.05;

/// The four facings, in the order of [`FacingEstimate::probabilities`].
pub const FACINGS: [Facing; 4] = [Facing::Front, Facing::Back, Facing::Left, Facing::Right];

/// Which way the figure faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Facing {
    /// Toward the viewer (the character's right on the image's left).
    Front,
    /// Away from the viewer (the character's right on the image's right).
    Back,
    /// A left profile: the character's left side toward the viewer (it looks toward the
    /// image's left).
    Left,
    /// A right profile: the character's right side toward the viewer.
    Right,
    /// The evidence does not decide (no facing reaches [`DECIDE`], [`decided`]).
    Unknown,
}

impl Facing {
    /// The name in files and reports: `front`, `back`, `left`, `right`, `unknown`.
    pub fn name(self) -> &'static str {
        match self {
            Facing::Front => "front",
            Facing::Back => "back",
            Facing::Left => "left",
            Facing::Right => "right",
            Facing::Unknown => "unknown",
        }
    }

    /// The facing named `s` ([`Facing::name`]). Errors: `CorruptData` for another name.
    pub fn from_name(s: &str) -> Result<Facing> {
        FACINGS
            .into_iter()
            .chain([Facing::Unknown])
            .find(|f| f.name() == s)
            .ok_or_else(|| Error::CorruptData(format!("facing {s:?}: expected front, back, left, right or unknown")))
    }

    /// The facing of a camera yaw in degrees (the renderers' `Rz(roll) Rx(pitch) Ry(yaw)`, yaw 0
    /// a front view): front within ±45°, back beyond ±135°, left profile toward −90°, right toward
    /// +90°. For labelling rendered sketches.
    pub fn of_yaw(yaw_deg: f64) -> Facing {
        let y = (yaw_deg + 180.0).rem_euclid(360.0) - 180.0;
        if y.abs() <= 45.0 {
            Facing::Front
        } else if y.abs() >= 135.0 {
            Facing::Back
        } else if y < 0.0 {
            Facing::Left
        } else {
            Facing::Right
        }
    }

    /// Index in [`FACINGS`] (`None` for `Unknown`).
    pub fn index(self) -> Option<usize> {
        FACINGS.iter().position(|&f| f == self)
    }
}

/// The facing decided for a figure and its labelling.
#[derive(Clone, Debug, PartialEq)]
pub struct FacingEstimate {
    /// The likeliest facing when its probability reaches [`DECIDE`], else `Unknown`.
    pub facing: Facing,
    /// Probabilities of front, back, left and right profile ([`FACINGS`]'s order), summing to 1.
    pub probabilities: [f64; 4],
    /// The reported joints are the chosen backend's with left and right swapped (the labelling
    /// rule corrected it).
    pub swapped: bool,
    /// The other labelling: the reported joints with left and right swapped, px.
    pub alternative: Joints2,
    /// The probability that the other labelling is the right one: the probability of the facing
    /// its handedness implies (front or back) plus half the profiles' (which do not decide the
    /// sides), in [0, 1].
    pub alternative_score: f64,
}

/// The facing model: one coefficient row per facing over [`FEATURES`], `p = softmax(W x)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FacingModel {
    /// `sketchbody-facing-model`.
    pub format: String,
    /// 1.
    pub version: u32,
    /// How it was fitted (command, sets).
    pub provenance: String,
    /// The feature names, [`FEATURES`].
    pub features: Vec<String>,
    /// Coefficients of front, back, left and right, each of [`FEATURES`]'s length.
    pub weights: Vec<Vec<f64>>,
}

/// The features of [`facing_features`], in order.
pub const FEATURES: [&str; 14] = [
    "bias",
    "sketch_present",
    "sketch_spread",
    "blazepose_present",
    "blazepose_spread",
    "nose_visibility",
    "eye_mouth_visibility",
    "ear_asymmetry",
    "nose_offset",
    "shoulder_depth",
    "head_ink",
    "head_strokes_along",
    "head_runs_across",
    "head_runs_along",
];

/// Number of [`FEATURES`].
pub const NUM_FEATURES: usize = FEATURES.len();

impl FacingModel {
    /// Parses a facing model JSON. Errors: `CorruptData` for bad JSON, another format, version
    /// or feature list, or coefficients of the wrong shape or not finite.
    pub fn from_json(text: &str) -> Result<FacingModel> {
        let m: FacingModel =
            crate::strict_json::from_str(text).map_err(|e| Error::CorruptData(format!("facing model: {e}")))?;
        if m.format != FACING_MODEL_FORMAT || m.version != 1 {
            return Err(Error::CorruptData(format!("facing model: format {:?} version {}", m.format, m.version)));
        }
        if m.features.iter().map(String::as_str).ne(FEATURES) {
            return Err(Error::CorruptData(format!("facing model: features {:?}, expected {FEATURES:?}", m.features)));
        }
        if m.weights.len() != FACINGS.len()
            || m.weights.iter().any(|w| w.len() != NUM_FEATURES || w.iter().any(|v| !v.is_finite()))
        {
            return Err(Error::CorruptData("facing model: 4 rows of finite coefficients, one per feature".into()));
        }
        Ok(m)
    }

    /// The embedded model, parsed once per process.
    pub fn embedded() -> Result<&'static FacingModel> {
        static MODEL: OnceLock<std::result::Result<FacingModel, String>> = OnceLock::new();
        MODEL
            .get_or_init(|| FacingModel::from_json(EMBEDDED_FACING_MODEL).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| Error::CorruptData(e.clone()))
    }

    /// The model as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The four probabilities (front, back, left, right) of features `x`.
    pub fn probabilities(&self, x: &[f64; NUM_FEATURES]) -> [f64; 4] {
        let z: Vec<f64> = self.weights.iter().map(|w| w.iter().zip(x).map(|(a, b)| a * b).sum()).collect();
        softmax(&z)
    }
}

/// softmax of four scores (shifted by their maximum, so it never overflows).
pub fn softmax(z: &[f64]) -> [f64; 4] {
    let m = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut p = [0.0; 4];
    for (k, v) in z.iter().take(4).enumerate() {
        p[k] = (v - m).exp();
    }
    let s: f64 = p.iter().sum();
    p.map(|v| v / s)
}

/// The torso's length (neck to pelvis, at least 1 px) and the image direction across it, unit,
/// pointing to the image's right for an upright figure.
fn torso_frame(j: &Joints2) -> (f64, [f64; 2]) {
    let (n, p) = (j.xy[joint::NECK], j.xy[joint::PELVIS]);
    let up = [n[0] - p[0], n[1] - p[1]];
    let len = up[0].hypot(up[1]);
    if !(len >= 1.0) {
        return (1.0, [1.0, 0.0]);
    }
    (len, [-up[1] / len, up[0] / len])
}

/// Which way a labelling `j` has the figure face: the character's left shoulder and hip minus its
/// right ones across the torso (toward the image's right of an upright figure), over the
/// torso's length, clamped to ±1. Positive: the left side on the image's right, as a figure
/// facing the viewer; negative: as one seen from behind; near 0: a profile.
pub fn handedness(j: &Joints2) -> f64 {
    let (len, across) = torso_frame(j);
    let d = |l: usize, r: usize| (j.xy[l][0] - j.xy[r][0]) * across[0] + (j.xy[l][1] - j.xy[r][1]) * across[1];
    let h = 0.5 * (d(joint::L_SHOULDER, joint::R_SHOULDER) + d(joint::L_HIP, joint::R_HIP)) / len;
    if h.is_finite() {
        h.clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// `j` with left and right swapped: each joint takes its mirror's position and visibility.
pub fn swap_sides(j: &Joints2) -> Joints2 {
    Joints2 { xy: mirror_values(&j.xy), visible: mirror_values(&j.visible) }
}

/// Per-joint values with left and right swapped ([`MIRROR`]).
pub fn mirror_values<T: Copy>(v: &[T; NUM_JOINTS]) -> [T; NUM_JOINTS] {
    std::array::from_fn(|k| v[MIRROR[k]])
}

/// BlazePose's landmarks the features read.
mod mp {
    pub const NOSE: usize = 0;
    pub const EYES_MOUTH: [usize; 8] = [1, 2, 3, 4, 5, 6, 9, 10];
    pub const L_EAR: usize = 7;
    pub const R_EAR: usize = 8;
    pub const L_SHOULDER: usize = 11;
    pub const R_SHOULDER: usize = 12;
}

/// What [`facing_features`] reads: each backend's labelling and BlazePose's landmarks.
#[derive(Clone, Copy, Debug)]
pub struct FacingInput<'a> {
    /// The sketch model's best figure.
    pub sketch: Option<&'a Joints2>,
    /// BlazePose's figure.
    pub blazepose: Option<&'a Joints2>,
    /// BlazePose's landmarks (at least the 33 pose landmarks), image px.
    pub landmarks: Option<&'a [super::landmark::Landmark]>,
    /// The ink inside the head ([`head_ink`]).
    pub head_ink: Option<HeadInk>,
}

/// The features of [`FEATURES`] (absent evidence as 0, the strokes' direction as 0.5; each
/// backend's presence as 1 or 0). None of them reads which side a backend labelled left: a
/// backend's labelling of a faceless outline is no evidence of its facing.
pub fn facing_features(input: &FacingInput<'_>) -> [f64; NUM_FEATURES] {
    let mut x = [0.0; NUM_FEATURES];
    x[0] = 1.0;
    if let Some(s) = input.sketch {
        (x[1], x[2]) = (1.0, handedness(s).abs());
    }
    if let Some(b) = input.blazepose {
        (x[3], x[4]) = (1.0, handedness(b).abs());
    }
    if let (Some(l), Some(b)) = (input.landmarks, input.blazepose) {
        if l.len() >= super::landmark::NUM_POSE_LANDMARKS {
            let (len, across) = torso_frame(b);
            x[5] = l[mp::NOSE].visibility;
            x[6] = mp::EYES_MOUTH.iter().map(|&i| l[i].visibility).sum::<f64>() / mp::EYES_MOUTH.len() as f64;
            x[7] = l[mp::L_EAR].visibility - l[mp::R_EAR].visibility;
            let ears = [0.5 * (l[mp::L_EAR].x + l[mp::R_EAR].x), 0.5 * (l[mp::L_EAR].y + l[mp::R_EAR].y)];
            let off = ((l[mp::NOSE].x - ears[0]) * across[0] + (l[mp::NOSE].y - ears[1]) * across[1]) / (0.25 * len);
            x[8] = if off.is_finite() { off.clamp(-2.0, 2.0) } else { 0.0 };
            let dz = (l[mp::L_SHOULDER].z - l[mp::R_SHOULDER].z) / len;
            x[9] = if dz.is_finite() { dz.clamp(-2.0, 2.0) } else { 0.0 };
        }
    }
    let head = input.head_ink.unwrap_or(HeadInk::EMPTY);
    (x[10], x[11], x[12], x[13]) = (head.ink, head.along, head.runs_across, head.runs_along);
    x
}

/// The ink inside a figure's head ([`head_ink`]): where a face, or hair drawn over the back of
/// the head, is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadInk {
    /// The fraction of dark pixels (gray under 128), in [0, 1].
    pub ink: f64,
    /// The share of the gray gradient's magnitude across the head's axis (neck to head): strokes
    /// running along the axis, as hair seen from behind, give values near 1, the horizontal
    /// strokes of eyes, brows and mouth low ones; 0.5 without gradient. In [0, 1].
    pub along: f64,
    /// Strokes crossed per line across the head's axis ([`RUN_LINES`] lines): many for strands
    /// of hair, few for a face.
    pub runs_across: f64,
    /// Strokes crossed per line along the head's axis: eyes, brows and mouth cross these.
    pub runs_along: f64,
}

impl HeadInk {
    /// No ink: an empty head.
    pub const EMPTY: HeadInk = HeadInk { ink: 0.0, along: 0.5, runs_across: 0.0, runs_along: 0.0 };
}

/// Lines of each direction [`head_runs`] scans, evenly spaced over the middle of the head.
pub const RUN_LINES: usize = 7;

/// The dark runs (gray under 128, entered from a light pixel) met on [`RUN_LINES`] lines
/// running in `dir` (unit) through the disk at `c` of radius `r`, spaced across `dir` over
/// ±0.75 `r`, sampled every pixel: their mean per line.
fn head_runs(image: &ImageView<'_>, c: [f64; 2], r: f64, dir: [f64; 2]) -> f64 {
    let normal = [-dir[1], dir[0]];
    let mut runs = 0usize;
    for k in 0..RUN_LINES {
        let off = r * 0.75 * (2.0 * k as f64 / (RUN_LINES - 1) as f64 - 1.0);
        let half = (r * r - off * off).max(0.0).sqrt();
        let steps = (2.0 * half).floor() as usize;
        let mut dark_before = true;
        for i in 0..=steps {
            let t = -half + i as f64;
            let (x, y) = (c[0] + off * normal[0] + t * dir[0], c[1] + off * normal[1] + t * dir[1]);
            let dark = match pixel_at(image, x, y) {
                Some(g) => g < 128,
                None => true,
            };
            runs += usize::from(dark && !dark_before);
            dark_before = dark;
        }
    }
    runs as f64 / RUN_LINES as f64
}

/// The gray value at image point (`x`, `y`) (the pixel holding it), `None` outside the image.
fn pixel_at(image: &ImageView<'_>, x: f64, y: f64) -> Option<u8> {
    if !(x >= 0.0 && y >= 0.0) {
        return None;
    }
    let (xi, yi) = (x as usize, y as usize);
    (xi < image.width() && yi < image.height()).then(|| gray_at(image, xi, yi))
}

/// The ink of `image` inside the disk at the head joint of `j` whose radius is 0.3 × the
/// head-to-neck distance: the inside of the head, not its outline. `None` for a disk of under
/// 2 px radius or one with no pixel inside the image.
pub fn head_ink(image: &ImageView<'_>, j: &Joints2) -> Option<HeadInk> {
    let (h, n) = (j.xy[joint::HEAD], j.xy[joint::NECK]);
    let len = (h[0] - n[0]).hypot(h[1] - n[1]);
    let r = 0.3 * len;
    if !(r >= 2.0) || !h[0].is_finite() || !h[1].is_finite() {
        return None;
    }
    let axis = [(h[0] - n[0]) / len, (h[1] - n[1]) / len];
    let (w, hgt) = (image.width(), image.height());
    let lo = |c: f64| (c - r).floor().max(0.0) as usize;
    let hi = |c: f64, m: usize| ((c + r).ceil().max(0.0) as usize).min(m);
    let (mut ink, mut all, mut across, mut along_axis) = (0usize, 0usize, 0.0, 0.0);
    for y in lo(h[1])..hi(h[1], hgt) {
        for x in lo(h[0])..hi(h[0], w) {
            if (x as f64 + 0.5 - h[0]).hypot(y as f64 + 0.5 - h[1]) > r {
                continue;
            }
            all += 1;
            ink += usize::from(gray_at(image, x, y) < 128);
            if x == 0 || y == 0 || x + 1 >= w || y + 1 >= hgt {
                continue;
            }
            let gx = f64::from(gray_at(image, x + 1, y)) - f64::from(gray_at(image, x - 1, y));
            let gy = f64::from(gray_at(image, x, y + 1)) - f64::from(gray_at(image, x, y - 1));
            along_axis += (gx * axis[0] + gy * axis[1]).abs();
            across += (gx * axis[1] - gy * axis[0]).abs();
        }
    }
    let total = across + along_axis;
    let normal = [-axis[1], axis[0]];
    (all > 0).then(|| HeadInk {
        ink: ink as f64 / all as f64,
        along: if total > 0.0 { across / total } else { 0.5 },
        runs_across: head_runs(image, h, r, normal),
        runs_along: head_runs(image, h, r, axis),
    })
}

/// The gray value of pixel (`x`, `y`) of a 1, 3 or 4 channel image.
fn gray_at(image: &ImageView<'_>, x: usize, y: usize) -> u8 {
    let c = image.channels();
    let p = &image.row(y)[x * c..];
    if c == 1 {
        p[0]
    } else {
        crate::image::rgb_to_gray_pixel(p[0], p[1], p[2])
    }
}

/// The handedness sign the labelling rule asks for given the facing probabilities `p`: −1 for a
/// figure decided as seen from behind, +1 for every other figure whose front and back outweigh
/// its profiles (no evidence either way reads as facing the viewer), 0 (keep the backend's
/// labelling) for a likely profile.
pub fn target_handedness(facing: Facing, p: &[f64; 4]) -> f64 {
    if facing == Facing::Back {
        -1.0
    } else if p[0] + p[1] >= p[2] + p[3] {
        1.0
    } else {
        0.0
    }
}

/// The facing of probabilities `p`: the likeliest when it reaches [`DECIDE`], else `Unknown`;
/// a likeliest back view is also decided from [`BACK_DECIDE`] when it holds [`BACK_OVER_FRONT`]
/// of the front's and back's probability. Such a figure is split between a back view and a
/// profile (a back turned 20° reads as either); undecided, it would get the front's labelling
/// ([`target_handedness`]: its front and back outweigh its profiles), the one reading its
/// probabilities rule out.
pub fn decided(p: &[f64; 4]) -> Facing {
    let k = (0..4).max_by(|&a, &b| p[a].total_cmp(&p[b])).unwrap_or(0);
    let back = k == 1 && p[1] >= BACK_DECIDE && p[1] >= BACK_OVER_FRONT * (p[0] + p[1]);
    if p[k] >= DECIDE || back {
        FACINGS[k]
    } else {
        Facing::Unknown
    }
}

/// Whether labelling `j` should be swapped for the `target` handedness sign
/// ([`target_handedness`]): its handedness has the other sign and at least [`MIN_HANDEDNESS`].
pub fn needs_swap(j: &Joints2, target: f64) -> bool {
    let h = handedness(j);
    target != 0.0 && h.abs() >= MIN_HANDEDNESS && h.signum() != target
}

/// The estimate for the reported joints `joints` (already labelled by the rule), the
/// probabilities `p` and whether the rule swapped them.
pub fn estimate(joints: &Joints2, p: [f64; 4], swapped: bool) -> FacingEstimate {
    let alternative = swap_sides(joints);
    let profiles = 0.5 * (p[2] + p[3]);
    let h = handedness(&alternative);
    let alternative_score = if h > 0.0 {
        p[0] + profiles
    } else if h < 0.0 {
        p[1] + profiles
    } else {
        0.5
    };
    FacingEstimate { facing: decided(&p), probabilities: p, swapped, alternative, alternative_score }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A figure 400 px tall facing the viewer: its right side on the image's left.
    pub(crate) fn front() -> Joints2 {
        let mut xy = [[0.0; 2]; NUM_JOINTS];
        let set = |xy: &mut [[f64; 2]; NUM_JOINTS], j: usize, p: [f64; 2]| xy[j] = p;
        for (j, p) in [
            (joint::HEAD, [200.0, 50.0]),
            (joint::NECK, [200.0, 100.0]),
            (joint::R_SHOULDER, [160.0, 105.0]),
            (joint::R_ELBOW, [150.0, 170.0]),
            (joint::R_WRIST, [145.0, 230.0]),
            (joint::L_SHOULDER, [240.0, 105.0]),
            (joint::L_ELBOW, [250.0, 170.0]),
            (joint::L_WRIST, [255.0, 230.0]),
            (joint::PELVIS, [200.0, 240.0]),
            (joint::R_HIP, [180.0, 240.0]),
            (joint::R_KNEE, [178.0, 330.0]),
            (joint::R_ANKLE, [176.0, 420.0]),
            (joint::L_HIP, [220.0, 240.0]),
            (joint::L_KNEE, [222.0, 330.0]),
            (joint::L_ANKLE, [224.0, 420.0]),
        ] {
            set(&mut xy, j, p);
        }
        Joints2 { xy, visible: [true; NUM_JOINTS] }
    }

    #[test]
    fn handedness_reads_the_labelling_and_swapping_reverses_it() {
        let f = front();
        let h = handedness(&f);
        assert!((h - 60.0 / 140.0).abs() < 1e-12, "{h}");
        let b = swap_sides(&f);
        assert!((handedness(&b) + h).abs() < 1e-12);
        assert_eq!(swap_sides(&b), f);
        assert_eq!(b.xy[joint::R_WRIST], f.xy[joint::L_WRIST]);
        assert_eq!(b.xy[joint::HEAD], f.xy[joint::HEAD]);
        // Upside down (neck under the pelvis), the across direction turns with the torso.
        let mut flipped = f;
        for p in &mut flipped.xy {
            p[1] = 500.0 - p[1];
            p[0] = 400.0 - p[0];
        }
        assert!((handedness(&flipped) - h).abs() < 1e-12, "a rotation by 180° keeps the labelling's facing");
        // A degenerate torso gives a finite value.
        let mut flat = f;
        flat.xy = [[1.0, 1.0]; NUM_JOINTS];
        assert_eq!(handedness(&flat), 0.0);
    }

    #[test]
    fn yaw_names_the_facing_and_the_rule_labels_front_unless_back_is_decided() {
        assert_eq!(Facing::of_yaw(10.0), Facing::Front);
        assert_eq!(Facing::of_yaw(-170.0), Facing::Back);
        assert_eq!(Facing::of_yaw(190.0), Facing::Back);
        assert_eq!(Facing::of_yaw(-90.0), Facing::Left);
        assert_eq!(Facing::of_yaw(80.0), Facing::Right);
        for f in FACINGS.into_iter().chain([Facing::Unknown]) {
            assert_eq!(Facing::from_name(f.name()).unwrap(), f);
        }
        assert!(Facing::from_name("up").is_err());
        assert_eq!(decided(&[0.55, 0.45, 0.0, 0.0]), Facing::Unknown);
        assert_eq!(decided(&[0.1, 0.7, 0.1, 0.1]), Facing::Back);
        // A back view split with a profile, the front ruled out: decided; not when the front
        // competes, or under a half.
        assert_eq!(decided(&[0.02, 0.55, 0.42, 0.01]), Facing::Back);
        assert_eq!(decided(&[0.35, 0.57, 0.05, 0.03]), Facing::Unknown);
        assert_eq!(decided(&[0.01, 0.45, 0.44, 0.1]), Facing::Unknown);
        assert_eq!(decided(&[0.02, 0.42, 0.55, 0.01]), Facing::Unknown);
        assert_eq!(decided(&[f64::NAN; 4]), Facing::Unknown);
        // Undecided between front and back: the front's labelling.
        let even = [0.45, 0.45, 0.05, 0.05];
        assert_eq!(target_handedness(decided(&even), &even), 1.0);
        let back = [0.1, 0.8, 0.05, 0.05];
        assert_eq!(target_handedness(decided(&back), &back), -1.0);
        let profile = [0.1, 0.1, 0.7, 0.1];
        assert_eq!(target_handedness(decided(&profile), &profile), 0.0);
        let f = front();
        assert!(needs_swap(&swap_sides(&f), 1.0) && !needs_swap(&f, 1.0) && needs_swap(&f, -1.0));
        assert!(!needs_swap(&f, 0.0));
    }

    #[test]
    fn the_estimate_scores_the_alternative_by_the_facing_it_implies() {
        let f = front();
        let e = estimate(&f, [0.7, 0.2, 0.06, 0.04], true);
        assert_eq!((e.facing, e.swapped), (Facing::Front, true));
        assert_eq!(e.alternative, swap_sides(&f));
        assert!((e.alternative_score - 0.25).abs() < 1e-12, "{}", e.alternative_score);
        let e = estimate(&swap_sides(&f), [0.1, 0.8, 0.06, 0.04], false);
        assert!((e.alternative_score - 0.15).abs() < 1e-12);
    }

    #[test]
    fn features_read_the_spread_the_face_and_the_head_ink() {
        let f = front();
        let b = swap_sides(&f);
        let x =
            facing_features(&FacingInput { sketch: Some(&f), blazepose: Some(&b), landmarks: None, head_ink: None });
        assert_eq!(x[0], 1.0);
        assert_eq!((x[1], x[3]), (1.0, 1.0));
        // Either labelling gives the same features: only the spread of the sides is read.
        assert!(x[2] > 0.4 && x[2] == x[4]);
        assert_eq!(x[11], 0.5);
        let head = HeadInk { ink: 0.3, along: 0.8, runs_across: 4.0, runs_along: 1.5 };
        let none =
            facing_features(&FacingInput { sketch: None, blazepose: None, landmarks: None, head_ink: Some(head) });
        assert_eq!(none[1..10], [0.0; 9]);
        assert_eq!(none[10..], [0.3, 0.8, 4.0, 1.5]);
        // The head's inside: an empty circle outline is no ink, a filled head all ink.
        let (w, h) = (400usize, 460usize);
        let mut px = vec![255u8; w * h];
        let c = f.xy[joint::HEAD];
        for y in 0..h {
            for x in 0..w {
                let d = (x as f64 + 0.5 - c[0]).hypot(y as f64 + 0.5 - c[1]);
                if (d - 30.0).abs() < 1.5 {
                    px[y * w + x] = 0;
                }
            }
        }
        let v = ImageView::gray(&px, w, h).unwrap();
        assert_eq!(head_ink(&v, &f), Some(HeadInk { ink: 0.0, ..HeadInk::EMPTY }));
        let filled: Vec<u8> = px.iter().map(|_| 0).collect();
        assert_eq!(
            head_ink(&ImageView::gray(&filled, w, h).unwrap(), &f),
            Some(HeadInk { ink: 1.0, ..HeadInk::EMPTY })
        );
        // Strokes along the head's axis (hair seen from behind) and across it (a mouth, brows).
        let stripes = |vertical: bool| -> Vec<u8> {
            (0..w * h).map(|i| if (if vertical { i % w } else { i / w }) % 6 == 0 { 0 } else { 255 }).collect()
        };
        let (v_px, h_px) = (stripes(true), stripes(false));
        let along = head_ink(&ImageView::gray(&v_px, w, h).unwrap(), &f).unwrap();
        let across = head_ink(&ImageView::gray(&h_px, w, h).unwrap(), &f).unwrap();
        assert!(along.along > 0.99 && across.along < 0.01, "{along:?} {across:?}");
        assert!((along.ink - 1.0 / 6.0).abs() < 0.05);
        // Strands along the axis are crossed by the lines across it (the head's 30 px width
        // holds 5 of them, its shorter chords 3 or 4), not by the lines along it; a mouth and
        // brows the other way round.
        assert!(along.runs_across >= 3.0 && along.runs_along < 0.5, "{along:?}");
        assert!(across.runs_along >= 3.0 && across.runs_across < 0.5, "{across:?}");
        let mut tiny = f;
        tiny.xy[joint::NECK] = [c[0], c[1] + 3.0];
        assert_eq!(head_ink(&v, &tiny), None);
    }

    #[test]
    fn the_embedded_model_loads_and_bad_models_are_refused() {
        let m = FacingModel::embedded().unwrap();
        assert_eq!(FacingModel::from_json(&m.to_json()).unwrap(), *m);
        let p = m.probabilities(&[0.0; NUM_FEATURES]);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let mut bad = m.clone();
        bad.weights[2].pop();
        assert!(FacingModel::from_json(&bad.to_json()).is_err());
        let mut bad = m.clone();
        bad.features[3] = "other".into();
        assert!(FacingModel::from_json(&bad.to_json()).is_err());
        assert!(FacingModel::from_json("{}").is_err());
        let s = softmax(&[1000.0, 0.0, -1000.0, 0.0]);
        assert!((s[0] - 1.0).abs() < 1e-12 && s.iter().all(|v| v.is_finite()));
    }
}
