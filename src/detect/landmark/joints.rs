//! MediaPipe's 33 pose landmarks to the canonical 15 joints (`skeleton::JOINT_NAMES`).
//!
//! MediaPipe names sides from the person's view (`left_shoulder` = the figure's left), as the
//! canonical `l_*` joints do, so sides map directly. Derived joints:
//! - head = midpoint of the ears (7, 8): the centre of the head, like the canonical head
//!   (PARSE's midpoint of head top and chin);
//! - neck = [`NECK_TOWARD_MOUTH`] of the way from the shoulders' midpoint to the mouth's
//!   midpoint (9, 10): where the neck meets the head;
//! - pelvis = midpoint of the hips (23, 24).
//!
//! Confidence of a joint = visibility × presence of its landmark (sigmoids of the network's
//! logits); derived joints take the mean of their sources.

use crate::skeleton::{joint, Joints2, NUM_JOINTS};

/// Fraction of the way from the shoulders' midpoint to the mouth's midpoint taken as the neck.
pub const NECK_TOWARD_MOUTH: f64 = 0.5;

/// MediaPipe landmark indices used here.
mod mp {
    pub const L_EAR: usize = 7;
    pub const R_EAR: usize = 8;
    pub const MOUTH_L: usize = 9;
    pub const MOUTH_R: usize = 10;
    pub const L_SHOULDER: usize = 11;
    pub const R_SHOULDER: usize = 12;
    pub const L_ELBOW: usize = 13;
    pub const R_ELBOW: usize = 14;
    pub const L_WRIST: usize = 15;
    pub const R_WRIST: usize = 16;
    pub const L_HIP: usize = 23;
    pub const R_HIP: usize = 24;
    pub const L_KNEE: usize = 25;
    pub const R_KNEE: usize = 26;
    pub const L_ANKLE: usize = 27;
    pub const R_ANKLE: usize = 28;
}

/// The canonical joints (all marked visible) and their confidences from landmark positions
/// `xy` (image px) and confidences `conf` (at least the 33 pose landmarks).
pub fn to_canonical(xy: &[[f64; 2]], conf: &[f64]) -> (Joints2, [f64; NUM_JOINTS]) {
    let mut out = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    let mut c = [0.0; NUM_JOINTS];
    let mid = |a: usize, b: usize| [0.5 * (xy[a][0] + xy[b][0]), 0.5 * (xy[a][1] + xy[b][1])];
    let direct = [
        (joint::R_SHOULDER, mp::R_SHOULDER),
        (joint::R_ELBOW, mp::R_ELBOW),
        (joint::R_WRIST, mp::R_WRIST),
        (joint::L_SHOULDER, mp::L_SHOULDER),
        (joint::L_ELBOW, mp::L_ELBOW),
        (joint::L_WRIST, mp::L_WRIST),
        (joint::R_HIP, mp::R_HIP),
        (joint::R_KNEE, mp::R_KNEE),
        (joint::R_ANKLE, mp::R_ANKLE),
        (joint::L_HIP, mp::L_HIP),
        (joint::L_KNEE, mp::L_KNEE),
        (joint::L_ANKLE, mp::L_ANKLE),
    ];
    let mut set = |j: usize, p: [f64; 2], conf: f64| {
        out.xy[j] = p;
        c[j] = conf;
    };
    for (name, i) in direct {
        set(name, xy[i], conf[i]);
    }
    set(joint::HEAD, mid(mp::L_EAR, mp::R_EAR), 0.5 * (conf[mp::L_EAR] + conf[mp::R_EAR]));
    let (sh, mouth) = (mid(mp::L_SHOULDER, mp::R_SHOULDER), mid(mp::MOUTH_L, mp::MOUTH_R));
    let t = NECK_TOWARD_MOUTH;
    let neck = [sh[0] + t * (mouth[0] - sh[0]), sh[1] + t * (mouth[1] - sh[1])];
    let neck_conf = (conf[mp::L_SHOULDER] + conf[mp::R_SHOULDER] + conf[mp::MOUTH_L] + conf[mp::MOUTH_R]) / 4.0;
    set(joint::NECK, neck, neck_conf);
    set(joint::PELVIS, mid(mp::L_HIP, mp::R_HIP), 0.5 * (conf[mp::L_HIP] + conf[mp::R_HIP]));
    (out, c)
}

/// The canonical joints' depths from the landmarks' depths `z` (at least the 33 pose
/// landmarks; px, smaller is nearer the camera): the same mapping as [`to_canonical`] (direct
/// joints take their landmark's depth, derived joints the same midpoints and interpolations).
pub fn canonical_depth(z: &[f64]) -> [f64; NUM_JOINTS] {
    let as_xy: Vec<[f64; 2]> = z.iter().map(|&d| [d, 0.0]).collect();
    let (j, _) = to_canonical(&as_xy, &vec![0.0; z.len()]);
    std::array::from_fn(|k| j.xy[k][0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_and_derived_joints() {
        let xy: Vec<[f64; 2]> = (0..33).map(|i| [i as f64, 2.0 * i as f64]).collect();
        let conf: Vec<f64> = (0..33).map(|i| i as f64 / 100.0).collect();
        let (j, c) = to_canonical(&xy, &conf);
        let at = |n: &str| crate::skeleton::joint_index(n).unwrap();
        assert_eq!(j.xy[at("r_wrist")], [16.0, 32.0]);
        assert_eq!(j.xy[at("l_ankle")], [27.0, 54.0]);
        assert_eq!(j.xy[at("head")], [7.5, 15.0]);
        assert_eq!(j.xy[at("pelvis")], [23.5, 47.0]);
        assert_eq!(j.xy[at("neck")], [0.5 * 11.5 + 0.5 * 9.5, 0.5 * 23.0 + 0.5 * 19.0]);
        assert!((c[at("pelvis")] - 0.235).abs() < 1e-12);
        assert!(j.visible.iter().all(|&v| v));
        let z: Vec<f64> = (0..33).map(|i| -(i as f64)).collect();
        let d = canonical_depth(&z);
        assert_eq!(d[at("r_wrist")], -16.0);
        assert_eq!(d[at("pelvis")], -23.5);
        assert_eq!(d[at("neck")], -(0.5 * 11.5 + 0.5 * 9.5));
    }

    /// A derived joint's confidence is the mean of its landmarks' (head: the ears; neck: both
    /// shoulders and both mouth corners; pelvis: the hips), a direct joint's its landmark's.
    #[test]
    fn derived_joint_confidences_are_the_means_of_their_sources() {
        let xy = vec![[0.0; 2]; 33];
        let mut conf = vec![0.0; 33];
        for (i, c) in [(7, 0.2), (8, 0.6), (9, 0.1), (10, 0.3), (11, 0.5), (12, 0.9), (23, 0.4), (24, 0.8), (16, 0.7)] {
            conf[i] = c;
        }
        let (_, c) = to_canonical(&xy, &conf);
        let at = |n: &str| crate::skeleton::joint_index(n).unwrap();
        for (name, want) in [("head", 0.4), ("neck", 0.45), ("pelvis", 0.6), ("r_wrist", 0.7), ("l_wrist", 0.0)] {
            assert!((c[at(name)] - want).abs() < 1e-12, "{name}: {} vs {want}", c[at(name)]);
        }
    }
}
