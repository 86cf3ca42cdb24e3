//! `pipeline::repose`: re-posing a finished result (a depth reading, a flipped limb, moved 2-D
//! joints) keeps its fitted shape (issue 46 item 3, issue 50 item 2).

use std::path::Path;

use nalgebra::Vector3;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::export::joints2d::load_joints2d;
use sketchbody::fit::FitOptions;
use sketchbody::image::load_image;
use sketchbody::pipeline::{
    repose, run_pipeline, GivenJoints, PipelineOptions, PipelineResult, ReposeOutcome, ReposeRequest,
};
use sketchbody::pose::alternatives::has_depth;
use sketchbody::pose::{dict_io, Limb};
use sketchbody::skeleton::{joint, Joints3};
use sketchbody::Error;

/// Largest vertex distance between two meshes, metres.
fn max_diff(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|k| (p[k] as f64 - q[k] as f64).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max)
}

/// Largest joint distance between two skeletons, metres.
fn joint_diff(a: &Joints3, b: &Joints3) -> f64 {
    a.iter().zip(b).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()).fold(0.0, f64::max)
}

fn example() -> PipelineResult {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let model = BodyModel::embedded().unwrap();
    let dict = dict_io::embedded().unwrap();
    let sketch = load_image(&root.join("assets/examples/sketch.png")).unwrap();
    let j = load_joints2d(&root.join("assets/examples/sketch_joints.json")).unwrap();
    let o = PipelineOptions {
        fit: FitOptions { samples: 24, max_iterations: 3, ..FitOptions::default() },
        gender: Some(Gender::Female),
        ..PipelineOptions::default()
    };
    run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &o, &mut |_| true).unwrap()
}

/// The parts of a result a re-pose must keep.
fn shape_of(r: &PipelineResult) -> (Vec<f64>, Vec<[f32; 3]>, Joints3) {
    (r.weights.clone(), r.mesh.vertices.clone(), r.mesh.joints)
}

#[test]
fn reposing_keeps_the_shape_and_the_unchanged_joints_give_the_runs_mesh() {
    let dict = dict_io::embedded().unwrap();
    let original = example();
    let shape = shape_of(&original);
    let mut r = original.clone();
    // The unchanged (given) joints re-estimate the run's own pose: IK and skinning are
    // deterministic, so the mesh is the run's to f32 rounding (1 µm allowed).
    let j = r.joints2d;
    assert_eq!(repose(&mut r, &dict, ReposeRequest::Joints(&j)).unwrap(), ReposeOutcome::Reposed);
    assert_eq!(r.pose.joints, original.pose.joints);
    assert!(max_diff(&r.posed_vertices, &original.posed_vertices) <= 1e-6);
    assert_eq!(shape_of(&r), shape);

    // A flip changes the body's pose, not its shape; flipping back restores the mesh.
    let alts = original.pose.alternatives.clone();
    assert!(alts.len() >= 2, "{}", alts.len());
    let limb = alts[1].flipped[0];
    assert_eq!(repose(&mut r, &dict, ReposeRequest::Flip(limb)).unwrap(), ReposeOutcome::Reposed);
    assert!(max_diff(&r.posed_vertices, &original.posed_vertices) > 1e-3);
    assert_eq!(shape_of(&r), shape);
    assert_eq!(repose(&mut r, &dict, ReposeRequest::Flip(limb)).unwrap(), ReposeOutcome::Reposed);
    assert!(max_diff(&r.posed_vertices, &original.posed_vertices) <= 1e-6);

    // Picking an alternative poses its joints.
    assert_eq!(repose(&mut r, &dict, ReposeRequest::Alternative(1)).unwrap(), ReposeOutcome::Reposed);
    // (r's pose was flipped there and back: its joints are the run's within rounding.)
    assert!(joint_diff(&r.pose.joints, &alts[1].joints) < 1e-12);
    assert_eq!(r.pose.alternatives[0].joints, r.pose.joints);
    assert_eq!(shape_of(&r), shape);
    assert!(matches!(
        repose(&mut r, &dict, ReposeRequest::Alternative(99)),
        Err(Error::OutOfRange { name: "alternative", .. })
    ));
    assert_eq!(repose(&mut r, &dict, ReposeRequest::Alternative(0)).unwrap(), ReposeOutcome::Reposed);
}

#[test]
fn a_joint_dragged_outside_or_onto_another_gives_a_status_and_changes_nothing() {
    let dict = dict_io::embedded().unwrap();
    let original = example();
    let mut r = original.clone();
    let mut outside = r.joints2d;
    outside.xy[joint::L_WRIST] = [-20.0, 100.0];
    let o = repose(&mut r, &dict, ReposeRequest::Joints(&outside)).unwrap();
    assert_eq!(o, ReposeOutcome::JointOutsideImage { joint: "l_wrist" });
    assert!(o.message().contains("l_wrist"));
    let mut onto = r.joints2d;
    onto.xy[joint::L_WRIST] = onto.xy[joint::L_HIP];
    assert_eq!(
        repose(&mut r, &dict, ReposeRequest::Joints(&onto)).unwrap(),
        ReposeOutcome::JointsCoincide { a: "l_wrist", b: "l_hip" }
    );
    // All joints on a line: no plausible body.
    let mut line = r.joints2d;
    for (k, p) in line.xy.iter_mut().enumerate() {
        *p = [100.0 + 7.0 * k as f64, 100.0 + 13.0 * k as f64];
    }
    assert_eq!(repose(&mut r, &dict, ReposeRequest::Joints(&line)).unwrap(), ReposeOutcome::Implausible);
    assert_eq!(r.posed_vertices, original.posed_vertices);
    assert_eq!(r.pose, original.pose);
    assert_eq!(r.joints2d, original.joints2d);

    // A limb in the picture plane: the result's right forearm turned into it (the wrist at the
    // elbow's depth in the camera frame, same length and image direction) has no depth to flip.
    let cam_r = r.pose.camera.r;
    let (e, w) = (joint::R_ELBOW, joint::R_WRIST);
    let (y_e, y_w) = (cam_r * Vector3::from(r.pose.joints[e]), cam_r * Vector3::from(r.pose.joints[w]));
    let len = (y_w - y_e).norm();
    let dir = Vector3::new(y_w.x - y_e.x, y_w.y - y_e.y, 0.0).normalize();
    r.pose.joints[w] = (cam_r.transpose() * (y_e + dir * len)).into();
    assert!(!has_depth(&r.pose.joints, &cam_r, Limb::RForearm));
    let flat = r.clone();
    let o = repose(&mut r, &dict, ReposeRequest::Flip(Limb::RForearm)).unwrap();
    assert_eq!(o, ReposeOutcome::NoDepth);
    assert!(o.message().contains("picture plane"));
    assert_eq!(r.posed_vertices, flat.posed_vertices);
    assert_eq!(r.pose, flat.pose);
}
