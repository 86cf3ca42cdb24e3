//! From part boxes to joints: the 14 PARSE joints (centre of the part named by the model's
//! `part_to_joint`, as the authors' evaluation does) and the canonical 15 joints.
//!
//! Mapping to the canonical skeleton (`skeleton::joint`), with PARSE names:
//! - PARSE's `l*` joints lie on the image's left (the character's right for a figure facing the
//!   viewer: 37 of the first 38 PARSE labels have `lsho` left of `rsho`), so `lank, lkne, lhip,
//!   lwr, lelb, lsho` give `r_ankle, r_knee, r_hip, r_wrist, r_elbow, r_shoulder` and the `r*`
//!   joints give the `l_*` ones;
//! - head = midpoint of `htop` and `hbot` (centre of the head);
//! - neck = `hbot` (bottom of the head, where the neck meets it);
//! - pelvis = midpoint of the two hips.
//!
//! Confidence of a joint = logistic(local filter response) of its part, in (0, 1); derived joints
//! take the mean of their sources.

use super::model::NUM_PARSE_JOINTS;
use super::tree::Candidate;
use crate::skeleton::{joint, Joints2, NUM_JOINTS};

/// PARSE joint indices (the data set's order).
mod pj {
    pub const LANK: usize = 0;
    pub const LKNE: usize = 1;
    pub const LHIP: usize = 2;
    pub const RHIP: usize = 3;
    pub const RKNE: usize = 4;
    pub const RANK: usize = 5;
    pub const LWR: usize = 6;
    pub const LELB: usize = 7;
    pub const LSHO: usize = 8;
    pub const RSHO: usize = 9;
    pub const RELB: usize = 10;
    pub const RWR: usize = 11;
    pub const HBOT: usize = 12;
    pub const HTOP: usize = 13;
}

/// The 14 PARSE joints of a candidate, px (continuous image coordinates), with confidences.
pub fn parse_joints(
    c: &Candidate,
    part_to_joint: &[usize; NUM_PARSE_JOINTS],
) -> ([[f64; 2]; NUM_PARSE_JOINTS], [f64; NUM_PARSE_JOINTS]) {
    let mut xy = [[0.0; 2]; NUM_PARSE_JOINTS];
    let mut conf = [0.0; NUM_PARSE_JOINTS];
    for (j, &p) in part_to_joint.iter().enumerate() {
        if let Some(b) = c.parts.get(p) {
            xy[j] = b.centre();
            conf[j] = 1.0 / (1.0 + (-(b.local as f64)).exp());
        }
    }
    (xy, conf)
}

/// Converts PARSE joints (and confidences) to the canonical 15 (see the module notes).
pub fn parse_to_canonical(
    xy: &[[f64; 2]; NUM_PARSE_JOINTS],
    conf: &[f64; NUM_PARSE_JOINTS],
) -> (Joints2, [f64; NUM_JOINTS]) {
    let mid =
        |a: usize, b: usize| ([(xy[a][0] + xy[b][0]) / 2.0, (xy[a][1] + xy[b][1]) / 2.0], (conf[a] + conf[b]) / 2.0);
    let one = |a: usize| (xy[a], conf[a]);
    let table = [
        (joint::HEAD, mid(pj::HTOP, pj::HBOT)),
        (joint::NECK, one(pj::HBOT)),
        (joint::R_SHOULDER, one(pj::LSHO)),
        (joint::R_ELBOW, one(pj::LELB)),
        (joint::R_WRIST, one(pj::LWR)),
        (joint::L_SHOULDER, one(pj::RSHO)),
        (joint::L_ELBOW, one(pj::RELB)),
        (joint::L_WRIST, one(pj::RWR)),
        (joint::PELVIS, mid(pj::LHIP, pj::RHIP)),
        (joint::R_HIP, one(pj::LHIP)),
        (joint::R_KNEE, one(pj::LKNE)),
        (joint::R_ANKLE, one(pj::LANK)),
        (joint::L_HIP, one(pj::RHIP)),
        (joint::L_KNEE, one(pj::RKNE)),
        (joint::L_ANKLE, one(pj::RANK)),
    ];
    let mut j2 = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    let mut c = [0.0; NUM_JOINTS];
    for (k, (p, cf)) in table {
        j2.xy[k] = p;
        c[k] = cf;
    }
    (j2, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_mapping() {
        let mut xy = [[0.0; 2]; NUM_PARSE_JOINTS];
        for (j, p) in xy.iter_mut().enumerate() {
            *p = [j as f64, 100.0 + j as f64];
        }
        let conf = [0.5; NUM_PARSE_JOINTS];
        let (j, c) = parse_to_canonical(&xy, &conf);
        assert_eq!(j.xy[joint::HEAD], [12.5, 112.5]);
        assert_eq!(j.xy[joint::NECK], [12.0, 112.0]);
        assert_eq!(j.xy[joint::PELVIS], [2.5, 102.5]);
        assert_eq!(j.xy[joint::R_ANKLE], [0.0, 100.0]);
        assert_eq!(j.xy[joint::L_WRIST], [11.0, 111.0]);
        assert_eq!(j.xy[joint::R_SHOULDER], [8.0, 108.0]);
        assert!(c.iter().all(|&v| v == 0.5));
    }
}
