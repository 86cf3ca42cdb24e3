//! The 26-part tree of the trained detector (the PARSE layout of Yang & Ramanan) and the part
//! points derived from the 15 canonical joints.
//!
//! Points, in part order (image-left "l" side = the character's right for a figure facing the
//! viewer, as `detect::joints` maps PARSE joints): 0 head top (head + (head − neck)), 1 neck
//! (bottom of the head), then per side (parts 2–13 for the character's right, 14–25 for the
//! left): shoulder, upper-arm midpoint, elbow, forearm midpoint, wrist, torso points at 1/3 and
//! 2/3 from shoulder to hip, hip, thigh midpoint, knee, shin midpoint, ankle.
//! The joints of `detect::joints::parse_to_canonical` come back exactly from the box centres of
//! parts 0 (htop), 1 (hbot), and the shoulder, elbow, wrist, hip, knee and ankle parts.

use sketchbody::detect::model::NUM_PARSE_JOINTS;
use sketchbody::skeleton::{joint, MIRROR, NUM_JOINTS};

/// Number of parts.
pub const NUM_PARTS: usize = 26;

/// Parent of each part (`None` for the root, part 0), as in the PARSE model.
pub const PARENT: [Option<usize>; NUM_PARTS] = [
    None,
    Some(0),
    Some(1),
    Some(2),
    Some(3),
    Some(4),
    Some(5),
    Some(2),
    Some(7),
    Some(8),
    Some(9),
    Some(10),
    Some(11),
    Some(12),
    Some(1),
    Some(14),
    Some(15),
    Some(16),
    Some(17),
    Some(14),
    Some(19),
    Some(20),
    Some(21),
    Some(22),
    Some(23),
    Some(24),
];

/// For each PARSE joint (data-set order `lank, lkne, lhip, rhip, rkne, rank, lwr, lelb, lsho,
/// rsho, relb, rwr, hbot, htop`), the part whose box centre gives it.
pub const PART_TO_JOINT: [usize; NUM_PARSE_JOINTS] = [13, 11, 9, 21, 23, 25, 6, 4, 2, 14, 16, 18, 1, 0];

/// One side's chain of points: (shoulder, elbow, wrist, hip, knee, ankle) joints.
fn side_points(
    j: &[[f64; 2]; NUM_JOINTS],
    sho: usize,
    elb: usize,
    wri: usize,
    hip: usize,
    kne: usize,
    ank: usize,
) -> [[f64; 2]; 12] {
    let lerp = |a: usize, b: usize, t: f64| [j[a][0] + (j[b][0] - j[a][0]) * t, j[a][1] + (j[b][1] - j[a][1]) * t];
    [
        j[sho],
        lerp(sho, elb, 0.5),
        j[elb],
        lerp(elb, wri, 0.5),
        j[wri],
        lerp(sho, hip, 1.0 / 3.0),
        lerp(sho, hip, 2.0 / 3.0),
        j[hip],
        lerp(hip, kne, 0.5),
        j[kne],
        lerp(kne, ank, 0.5),
        j[ank],
    ]
}

/// The 26 part points (px) of a figure with canonical joints `j` (px).
pub fn part_points(j: &[[f64; 2]; NUM_JOINTS]) -> [[f64; 2]; NUM_PARTS] {
    use joint::*;
    let mut p = [[0.0; 2]; NUM_PARTS];
    let (h, n) = (j[HEAD], j[NECK]);
    p[0] = [2.0 * h[0] - n[0], 2.0 * h[1] - n[1]];
    p[1] = n;
    p[2..14].copy_from_slice(&side_points(j, R_SHOULDER, R_ELBOW, R_WRIST, R_HIP, R_KNEE, R_ANKLE));
    p[14..26].copy_from_slice(&side_points(j, L_SHOULDER, L_ELBOW, L_WRIST, L_HIP, L_KNEE, L_ANKLE));
    p
}

/// Joints of the horizontally mirrored image (`width` px wide): x → width − x, and left/right
/// labels swapped so that the character's "right" stays on the same image side.
pub fn mirror_joints(j: &[[f64; 2]; NUM_JOINTS], width: f64) -> [[f64; 2]; NUM_JOINTS] {
    std::array::from_fn(|k| {
        let s = j[MIRROR[k]];
        [width - s[0], s[1]]
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use sketchbody::detect::joints::parse_to_canonical;

    fn figure() -> [[f64; 2]; NUM_JOINTS] {
        std::array::from_fn(|k| [10.0 + 7.0 * k as f64 + (k * k) as f64, 200.0 - 11.0 * k as f64])
    }

    #[test]
    fn box_centres_give_back_the_canonical_joints() {
        let j = figure();
        let p = part_points(&j);
        let xy: [[f64; 2]; NUM_PARSE_JOINTS] = std::array::from_fn(|k| p[PART_TO_JOINT[k]]);
        let (back, _) = parse_to_canonical(&xy, &[0.5; NUM_PARSE_JOINTS]);
        for k in 0..NUM_JOINTS {
            if k == joint::PELVIS {
                // The detector's pelvis is the hips' midpoint.
                let m =
                    [(j[joint::R_HIP][0] + j[joint::L_HIP][0]) / 2.0, (j[joint::R_HIP][1] + j[joint::L_HIP][1]) / 2.0];
                assert!((back.xy[k][0] - m[0]).abs() < 1e-9 && (back.xy[k][1] - m[1]).abs() < 1e-9);
                continue;
            }
            assert!((back.xy[k][0] - j[k][0]).abs() < 1e-9 && (back.xy[k][1] - j[k][1]).abs() < 1e-9, "joint {k}");
        }
        assert!(PARENT.iter().enumerate().skip(1).all(|(i, p)| p.is_some_and(|q| q < i)));
    }

    #[test]
    fn mirroring_twice_is_the_identity_and_swaps_sides() {
        let j = figure();
        let m = mirror_joints(&j, 300.0);
        assert_eq!(m[joint::R_WRIST], [300.0 - j[joint::L_WRIST][0], j[joint::L_WRIST][1]]);
        assert_eq!(m[joint::HEAD], [300.0 - j[joint::HEAD][0], j[joint::HEAD][1]]);
        assert_eq!(mirror_joints(&m, 300.0), j);
    }

    #[test]
    fn the_embedded_model_has_the_trained_layout() {
        let m = sketchbody::detect::Model::embedded().unwrap();
        assert_eq!(m.parts.len(), NUM_PARTS);
        assert_eq!(m.part_to_joint, PART_TO_JOINT);
        assert_eq!((m.sbin, m.interval), (4, 10));
        assert!(m.thresh.is_finite());
    }
}
