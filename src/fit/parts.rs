//! Body parts of a fitted silhouette and how much of each the sketch supports: every boundary
//! pixel of the fitted body's silhouette belongs to the part whose projected bones lie nearest,
//! and a part's support is the share of its boundary within a few raster pixels of a stroke. A
//! part drawn as something other than a body (a cloak, a silhouette far wider than any human)
//! leaves the fitted body's outline there away from every stroke: a low support.

use crate::skeleton::{joint, NUM_JOINTS};

/// A body part for per-part support ([`PartSupport`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodyPart {
    /// Head and neck.
    Head,
    /// Chest, belly and pelvis (shoulders to hips).
    Torso,
    /// The figure's right upper arm, forearm and hand.
    RightArm,
    /// The figure's left upper arm, forearm and hand.
    LeftArm,
    /// The figure's right thigh, shin and foot.
    RightLeg,
    /// The figure's left thigh, shin and foot.
    LeftLeg,
}

impl BodyPart {
    /// Every part, in the order of [`PartSupport::support`].
    pub const ALL: [BodyPart; 6] =
        [BodyPart::Head, BodyPart::Torso, BodyPart::RightArm, BodyPart::LeftArm, BodyPart::RightLeg, BodyPart::LeftLeg];

    /// Lower-case name with underscores (`"right_arm"`), as in reports and JSON.
    pub fn name(self) -> &'static str {
        match self {
            BodyPart::Head => "head",
            BodyPart::Torso => "torso",
            BodyPart::RightArm => "right_arm",
            BodyPart::LeftArm => "left_arm",
            BodyPart::RightLeg => "right_leg",
            BodyPart::LeftLeg => "left_leg",
        }
    }

    /// The part's bones as pairs of joint indices ([`crate::skeleton::joint`]).
    fn bones(self) -> &'static [(usize, usize)] {
        use joint::*;
        match self {
            BodyPart::Head => &[(HEAD, NECK)],
            BodyPart::Torso => {
                &[(NECK, PELVIS), (R_SHOULDER, L_SHOULDER), (R_HIP, L_HIP), (R_SHOULDER, R_HIP), (L_SHOULDER, L_HIP)]
            }
            BodyPart::RightArm => &[(R_SHOULDER, R_ELBOW), (R_ELBOW, R_WRIST)],
            BodyPart::LeftArm => &[(L_SHOULDER, L_ELBOW), (L_ELBOW, L_WRIST)],
            BodyPart::RightLeg => &[(R_HIP, R_KNEE), (R_KNEE, R_ANKLE)],
            BodyPart::LeftLeg => &[(L_HIP, L_KNEE), (L_KNEE, L_ANKLE)],
        }
    }
}

/// Squared distance from `p` to the segment `a`–`b` (a point when `a` = `b`).
fn segment_distance_sq(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len_sq = dx * dx + dy * dy;
    let t = if len_sq > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len_sq).clamp(0.0, 1.0) } else { 0.0 };
    let (ex, ey) = (a[0] + t * dx - p[0], a[1] + t * dy - p[1]);
    ex * ex + ey * ey
}

/// The part whose projected bones lie nearest to `p` (`joints` and `p` in the same pixel
/// frame); `None` when a joint is not finite.
pub fn nearest_part(joints: &[[f64; 2]; NUM_JOINTS], p: [f64; 2]) -> Option<BodyPart> {
    if joints.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    BodyPart::ALL
        .iter()
        .map(|&part| {
            let d = part
                .bones()
                .iter()
                .map(|&(a, b)| segment_distance_sq(p, joints[a], joints[b]))
                .fold(f64::MAX, f64::min);
            (part, d)
        })
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map(|(part, _)| part)
}

/// How much of each part of a fitted silhouette's outline the sketch supports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartSupport {
    /// Per part of [`BodyPart::ALL`], the share (0..=1) of its outline pixels within the
    /// support radius of a stroke; `None` when the part has no outline pixel in view (hidden
    /// behind the others or outside the image).
    pub support: [Option<f64>; 6],
}

impl PartSupport {
    /// From per-part (supported, total) outline pixel counts in [`BodyPart::ALL`]'s order.
    pub fn from_counts(counts: &[(usize, usize)]) -> PartSupport {
        let mut support = [None; 6];
        for (s, &(near, n)) in support.iter_mut().zip(counts) {
            *s = (n > 0).then(|| near as f64 / n as f64);
        }
        PartSupport { support }
    }

    /// The support of one part (`None`: not in view).
    pub fn of(&self, part: BodyPart) -> Option<f64> {
        BodyPart::ALL.iter().position(|&p| p == part).and_then(|k| self.support[k])
    }

    /// The parts in view whose support is below `threshold`, in [`BodyPart::ALL`]'s order.
    pub fn below(&self, threshold: f64) -> Vec<BodyPart> {
        BodyPart::ALL.iter().copied().filter(|&p| self.of(p).is_some_and(|s| s < threshold)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A T-posed skeleton in pixels (image y down): head at the top, arms out, legs down.
    fn t_pose() -> [[f64; 2]; NUM_JOINTS] {
        let mut j = [[0.0; 2]; NUM_JOINTS];
        use joint::*;
        for (k, p) in [
            (HEAD, [50.0, 5.0]),
            (NECK, [50.0, 15.0]),
            (R_SHOULDER, [40.0, 18.0]),
            (R_ELBOW, [25.0, 18.0]),
            (R_WRIST, [10.0, 18.0]),
            (L_SHOULDER, [60.0, 18.0]),
            (L_ELBOW, [75.0, 18.0]),
            (L_WRIST, [90.0, 18.0]),
            (PELVIS, [50.0, 50.0]),
            (R_HIP, [44.0, 50.0]),
            (R_KNEE, [44.0, 70.0]),
            (R_ANKLE, [44.0, 90.0]),
            (L_HIP, [56.0, 50.0]),
            (L_KNEE, [56.0, 70.0]),
            (L_ANKLE, [56.0, 90.0]),
        ] {
            j[k] = p;
        }
        j
    }

    /// Points beside each bone belong to its part: above the head, beside the chest, along
    /// each arm and leg (the figure's right is the image's left when it faces the viewer).
    #[test]
    fn points_take_the_part_of_the_nearest_bone() {
        let j = t_pose();
        let at = |x: f64, y: f64| nearest_part(&j, [x, y]).unwrap();
        assert_eq!(at(50.0, 1.0), BodyPart::Head);
        assert_eq!(at(38.0, 35.0), BodyPart::Torso);
        assert_eq!(at(15.0, 22.0), BodyPart::RightArm);
        assert_eq!(at(5.0, 18.0), BodyPart::RightArm, "past the wrist: the hand");
        assert_eq!(at(85.0, 14.0), BodyPart::LeftArm);
        assert_eq!(at(40.0, 80.0), BodyPart::RightLeg);
        assert_eq!(at(60.0, 95.0), BodyPart::LeftLeg, "past the ankle: the foot");
        let mut bad = j;
        bad[joint::L_KNEE][0] = f64::NAN;
        assert_eq!(nearest_part(&bad, [50.0, 50.0]), None);
    }

    /// Counts become shares; a part without outline pixels is not in view; `below` lists the
    /// parts in view under the threshold only.
    #[test]
    fn support_is_the_share_and_below_skips_hidden_parts() {
        let s = PartSupport::from_counts(&[(9, 10), (50, 50), (0, 0), (2, 10), (10, 10), (7, 10)]);
        assert_eq!(s.of(BodyPart::Head), Some(0.9));
        assert_eq!(s.of(BodyPart::RightArm), None);
        assert_eq!(s.of(BodyPart::LeftArm), Some(0.2));
        assert_eq!(s.below(0.5), vec![BodyPart::LeftArm]);
        assert_eq!(s.below(0.95), vec![BodyPart::Head, BodyPart::LeftArm, BodyPart::LeftLeg]);
    }
}
