//! The ranked depth readings of `estimate_pose` and the flip of one limb's depth
//! (`sketchbody::pose::alternatives`, issue 46 item 3).

use nalgebra::{Rotation3, Vector3};
use sketchbody::camera::WeakPerspective;
use sketchbody::pose::alternatives::{has_depth, MAX_ALTERNATIVES, NO_DEPTH_SIN};
use sketchbody::pose::problem::Problem;
use sketchbody::pose::{
    dict_io, estimate_pose, flip_limb, pick_alternative, FlipStatus, Limb, PoseEstimate, PoseOptions,
};
use sketchbody::skeleton::{Joints2, Joints3, BONES, NUM_JOINTS};

/// How far an alternative's image may be from the estimate's, px: a flip keeps the image
/// exactly, so only rounding of metre-sized coordinates at a few hundred px per metre is left.
const IMAGE_TOL_PX: f64 = 1e-6;

fn v(x: &[f64; 3]) -> Vector3<f64> {
    Vector3::from(*x)
}

/// 2-D joints of dictionary exemplar `k` seen from `yaw_deg` (no noise).
fn view(k: usize, yaw_deg: f64) -> Joints2 {
    let d = dict_io::embedded().unwrap();
    let e = d.exemplars.column(k);
    let r = *Rotation3::from_euler_angles(0.1, yaw_deg.to_radians(), 0.0).matrix();
    let cam = WeakPerspective { sx: 285.0, sy: 285.0, r, t: [256.0, 300.0] };
    Joints2 {
        xy: std::array::from_fn(|p| cam.project(&Vector3::new(e[3 * p], e[3 * p + 1], e[3 * p + 2]))),
        visible: [true; NUM_JOINTS],
    }
}

fn estimate(j: &Joints2) -> PoseEstimate {
    estimate_pose(&dict_io::embedded().unwrap(), j, &PoseOptions::default()).unwrap()
}

fn max_diff(a: &Joints3, b: &Joints3) -> f64 {
    (0..NUM_JOINTS).map(|j| (v(&a[j]) - v(&b[j])).norm()).fold(0.0, f64::max)
}

/// Reprojection RMS of `x` under the estimate's camera on `j`, px.
fn rms(j: &Joints2, cam: &WeakPerspective, x: &Joints3) -> f64 {
    let d = dict_io::embedded().unwrap();
    let prob = Problem::new(&d, j, 0.0).unwrap();
    prob.rms(cam, &std::array::from_fn(|p| v(&x[p])))
}

#[test]
fn alternatives_are_ranked_finite_distinct_and_reproject_like_the_estimate() {
    for (k, yaw) in [(100, 20.0), (5000, -25.0), (12000, 60.0)] {
        let j = view(k, yaw);
        let est = estimate(&j);
        let alts = &est.alternatives;
        assert!(!alts.is_empty() && alts.len() <= MAX_ALTERNATIVES, "{}", alts.len());
        // The first is the estimate itself; the others best first.
        assert_eq!(alts[0].joints, est.joints);
        assert!(alts[0].flipped.is_empty());
        for w in alts[1..].windows(2) {
            assert!(w[0].score <= w[1].score, "{} > {}", w[0].score, w[1].score);
        }
        for (i, a) in alts.iter().enumerate() {
            assert!(a.score.is_finite() && a.joints.iter().flatten().all(|c| c.is_finite()), "alternative {i}");
            if i > 0 {
                assert!(!a.flipped.is_empty(), "alternative {i}");
            }
            // Same image, same bone lengths.
            let r = rms(&j, &est.camera, &a.joints);
            assert!((r - est.rms).abs() < IMAGE_TOL_PX, "alternative {i}: rms {r} vs {}", est.rms);
            for &(p, c) in BONES.iter() {
                let l = |x: &Joints3| (v(&x[c]) - v(&x[p])).norm();
                assert!((l(&a.joints) - l(&est.joints)).abs() < 1e-9);
            }
            // Distinct: flipped sets differ and so do the joints (a flipped bone has depth).
            for b in &alts[..i] {
                assert_ne!(a.flipped, b.flipped);
                assert!(max_diff(&a.joints, &b.joints) > 1e-3, "{i}");
            }
            // Each flipped limb had depth, and picking the alternative gives its joints.
            assert!(a.flipped.iter().all(|&l| has_depth(&est.joints, &est.camera.r, l)));
            let picked = pick_alternative(&est, i).unwrap();
            assert!(max_diff(&picked.joints, &a.joints) < 1e-12);
            assert!((picked.alternatives[0].score - a.score).abs() <= 1e-9 * a.score.abs().max(1.0));
        }
        assert!(pick_alternative(&est, alts.len()).is_none());
    }
}

#[test]
fn flipping_a_limb_twice_returns_the_original() {
    let j = view(5000, -25.0);
    let est = estimate(&j);
    let mut flipped_any = false;
    for limb in Limb::ALL {
        let (once, status) = flip_limb(&est, limb);
        if status == FlipStatus::NoDepth {
            assert_eq!(once, est);
            continue;
        }
        flipped_any = true;
        assert!(max_diff(&once.joints, &est.joints) > 1e-3, "{limb:?}");
        // The flipped estimate's own alternatives hold the original reading.
        assert!(
            once.alternatives.iter().any(|a| max_diff(&a.joints, &est.joints) < 1e-12)
                || once.alternatives.len() == MAX_ALTERNATIVES
        );
        let (twice, status2) = flip_limb(&once, limb);
        assert_eq!(status2, FlipStatus::Flipped);
        assert!(max_diff(&twice.joints, &est.joints) < 1e-12, "{limb:?}");
        assert!(max_diff(&twice.base, &est.base) < 1e-12);
        assert_eq!(twice.depth_costs, est.depth_costs);
        assert_eq!(twice.alternatives.len(), est.alternatives.len());
        for (a, b) in twice.alternatives.iter().zip(&est.alternatives) {
            assert_eq!(a.flipped, b.flipped);
            assert_eq!(a.score, b.score);
            assert!(max_diff(&a.joints, &b.joints) < 1e-12);
        }
        assert_eq!((twice.camera, twice.rms, twice.plausible), (est.camera, est.rms, est.plausible));
    }
    assert!(flipped_any);
}

#[test]
fn a_limb_in_the_picture_plane_has_no_depth_to_flip() {
    let j = view(100, 20.0);
    let mut est = estimate(&j);
    // Put the right forearm in the picture plane: the wrist at the elbow's depth (camera frame),
    // same length.
    let r = est.camera.r;
    let (e, w) = (3, 4);
    let y_e = r * v(&est.joints[e]);
    let mut y_w = r * v(&est.joints[w]);
    let len = (y_w - y_e).norm();
    y_w.z = y_e.z + 0.5 * NO_DEPTH_SIN * len;
    let dir = Vector3::new(y_w.x - y_e.x, y_w.y - y_e.y, 0.0).normalize();
    let planar =
        y_e + dir * (len * len - (0.5 * NO_DEPTH_SIN * len).powi(2)).sqrt() + Vector3::z() * 0.5 * NO_DEPTH_SIN * len;
    est.joints[w] = (r.transpose() * planar).into();
    assert!(!has_depth(&est.joints, &r, Limb::RForearm));
    let (out, status) = flip_limb(&est, Limb::RForearm);
    assert_eq!(status, FlipStatus::NoDepth);
    assert_eq!(out, est);
}

#[test]
fn alternatives_are_deterministic() {
    let j = view(12000, 60.0);
    let (a, b) = (estimate(&j), estimate(&j));
    assert_eq!(a.alternatives, b.alternatives);
    assert_eq!(a.depth_costs, b.depth_costs);
}

#[test]
fn limb_names_round_trip() {
    for (i, l) in Limb::ALL.into_iter().enumerate() {
        assert_eq!(Limb::parse(l.name()), Some(l));
        assert_eq!(Limb::from_index(i), Some(l));
        assert_eq!(l.index(), i);
    }
    assert_eq!(Limb::parse("l_forearm"), Some(Limb::LForearm));
    assert_eq!(Limb::parse("forearm"), None);
    assert_eq!(Limb::from_index(8), None);
}
