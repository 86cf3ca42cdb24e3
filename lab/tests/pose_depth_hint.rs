//! The pose step's depth hint (`pose::depth_hint`): a stride seen from the front is ambiguous
//! (either leg forward projects almost alike); relative depths from an image cue decide it.

#[path = "../../tests/common/mod.rs"]
mod common;

use nalgebra::Vector3;
use sketchbody::body::BodyModel;
use sketchbody::camera::WeakPerspective;
use sketchbody::pose::motion::{normalize_pose, read_motion_csv};
use sketchbody::pose::{dict_io, estimate_pose, estimate_pose_hinted, DepthHint, PoseOptions};
use sketchbody::skeleton::{joint, Joints2, Joints3, NUM_JOINTS};
use sketchbody_lab::pose::learn::{body_model_skeletons, retarget_frames};

/// Camera-frame depth of joint `j` (toward the viewer, metres).
fn depth(cam: &WeakPerspective, x: &Joints3, j: usize) -> f64 {
    (cam.r * Vector3::from(x[j])).z
}

#[test]
fn a_depth_hint_decides_which_leg_is_forward_in_a_frontal_stride() {
    let Some(data) = common::shared_data("depth hint on a walking frame") else { return };
    let dict = dict_io::embedded().unwrap();
    let skeletons = body_model_skeletons(&BodyModel::embedded().unwrap());
    let frames =
        retarget_frames("walk", read_motion_csv(&data.join("mocap/deepmimic/walk.csv")).unwrap(), &skeletons).unwrap();
    // The frame of the longest stride along the depth axis.
    let stride = |p: &Joints3| p[joint::R_ANKLE][2] - p[joint::L_ANKLE][2];
    let gt =
        frames.iter().filter_map(normalize_pose).max_by(|a, b| stride(a).abs().total_cmp(&stride(b).abs())).unwrap();
    assert!(stride(&gt).abs() > 0.3, "stride {} m", stride(&gt));
    let cam = WeakPerspective { sx: 250.0, sy: 250.0, r: nalgebra::Matrix3::identity(), t: [256.0, 256.0] };
    let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    for p in 0..NUM_JOINTS {
        j.xy[p] = cam.project(&Vector3::from(gt[p]));
    }
    let opts = PoseOptions::default();
    let truth: [f64; NUM_JOINTS] = std::array::from_fn(|p| cam.sx * gt[p][2]);
    let forward = |hint: Option<&DepthHint>| {
        let e = estimate_pose_hinted(&dict, &j, &opts, hint).unwrap();
        assert!(e.joints.iter().flatten().all(|v| v.is_finite()));
        assert!(e.rms < 5.0, "reprojection RMS {} px", e.rms);
        depth(&e.camera, &e.joints, joint::R_ANKLE) - depth(&e.camera, &e.joints, joint::L_ANKLE)
    };
    let right = DepthHint { depth: truth, known: [true; NUM_JOINTS], weight: 0.3 };
    let mirrored = DepthHint { depth: truth.map(|d| -d), ..right };
    let (with_truth, with_mirror) = (forward(Some(&right)), forward(Some(&mirrored)));
    assert!(
        with_truth * stride(&gt) > 0.0,
        "the true depths put the right leg forward: {with_truth} vs {}",
        stride(&gt)
    );
    assert!(with_mirror * stride(&gt) < 0.0, "mirrored depths put the other leg forward: {with_mirror}");
    // Without an image cue the learned depths take the right leg forward too.
    let learned = forward(None);
    assert!(learned * stride(&gt) > 0.0, "the learned depths put the right leg forward: {learned}");
    // No hint and a zero weight are the plain solver (with its learned depths), bit for bit.
    let plain = estimate_pose(&dict, &j, &opts).unwrap();
    let inert = DepthHint { weight: 0.0, ..right };
    assert_eq!(estimate_pose_hinted(&dict, &j, &opts, None).unwrap(), plain);
    assert_eq!(estimate_pose_hinted(&dict, &j, &opts, Some(&inert)).unwrap(), plain);
    // A bad hint is refused.
    let bad = DepthHint { weight: f64::NAN, ..right };
    assert!(estimate_pose_hinted(&dict, &j, &opts, Some(&bad)).is_err());
}
