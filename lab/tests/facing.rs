//! The figure's facing and its labelling rule (issue 51) on the team renderer's sketches: a
//! faceless front outline reads as facing the viewer with the front's labelling; the same
//! evidence with both backends' left and right swapped (a labelling that implies a back view
//! without evidence of one) is swapped back; a back view drawn with hair over the head reads as
//! seen from behind with the back's labelling; the reported alternative is the other labelling.

use std::sync::Arc;

use sketchbody::body::BodyModel;
use sketchbody::detect::calibration::Calibration;
use sketchbody::detect::facing::{handedness, swap_sides, Facing};
use sketchbody::detect::figure::{gather, Backend, Evidence, FigureOptions};
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::image::ImageView;
use sketchbody::pipeline::figure::decide;
use sketchbody::render::sketch::{CameraAngles, Hair, SketchRenderer, SketchRequest, SketchStyle};
use sketchbody_lab::eval::backends::is_swap;
use sketchbody_lab::eval::metrics::pck;

/// A sketch of `seed` seen at `yaw_deg` (pitch and roll 0), clean lines with `hair`, 384 px; its
/// evidence from both backends and its true joints.
fn evidence(seed: u64, yaw_deg: f64, hair: Hair) -> (Evidence, [[f64; 2]; 15]) {
    let renderer = SketchRenderer::new(Arc::new(BodyModel::embedded().unwrap()), None).unwrap();
    let req = SketchRequest {
        camera: Some(CameraAngles { yaw_deg, pitch_deg: 0.0, roll_deg: 0.0 }),
        style: Some(SketchStyle { hair, ..SketchStyle::default() }),
        ..SketchRequest::random(seed, 384)
    };
    let s = renderer.render(&req).unwrap();
    let view = ImageView::gray(&s.pixels, 384, 384).unwrap();
    let e = gather(
        &view,
        &Model::embedded().unwrap(),
        &LandmarkNet::embedded().unwrap(),
        Backend::Auto,
        &FigureOptions::default(),
    )
    .unwrap();
    (e, s.truth.joints2d.as_slice().try_into().unwrap())
}

/// The evidence with both backends' left and right swapped.
fn mirrored_labels(e: &Evidence) -> Evidence {
    let mut m = e.clone();
    for d in m.sketch.iter_mut().flatten() {
        d.joints = swap_sides(&d.joints);
        d.confidence = sketchbody::detect::facing::mirror_values(&d.confidence);
    }
    if let Some(b) = &mut m.blazepose {
        b.joints = swap_sides(&b.joints);
        b.confidence = sketchbody::detect::facing::mirror_values(&b.confidence);
    }
    m
}

#[test]
fn a_faceless_front_outline_faces_the_viewer_and_a_mirrored_labelling_is_swapped_back() {
    let cal = Calibration::embedded().unwrap();
    let o = FigureOptions::default();
    let (e, truth) = evidence(41, 0.0, Hair::None);
    let f = decide(&e, cal, &o, None).unwrap();
    assert!(handedness(&f.joints) > 0.1, "front labelling: {}", handedness(&f.joints));
    assert!(!is_swap(&truth, &f.joints) && pck(&truth, &f.joints.xy, 0.2).unwrap() >= 0.9);
    assert!(f.facing.facing == Facing::Front || f.facing.facing == Facing::Unknown, "{:?}", f.facing);
    assert!(f.facing.probabilities[0] > f.facing.probabilities[1], "{:?}", f.facing.probabilities);
    assert_eq!(f.facing.alternative, swap_sides(&f.joints));
    assert!(f.facing.alternative_score < 0.5, "{}", f.facing.alternative_score);

    // Both backends labelled as seen from behind: no evidence of a back view, swapped back.
    let m = mirrored_labels(&e);
    let g = decide(&m, cal, &o, None).unwrap();
    assert!(g.facing.swapped, "{:?}", g.facing);
    assert!(handedness(&g.joints) > 0.1 && !is_swap(&truth, &g.joints));
    assert!(pck(&truth, &g.joints.xy, 0.2).unwrap() >= 0.9);
    // Without the rule the backends' labelling stays: a swap of the truth.
    let kept = decide(&m, cal, &FigureOptions { facing_rule: false, ..o.clone() }, None).unwrap();
    assert!(is_swap(&truth, &kept.joints) && !kept.facing.swapped);
}

#[test]
fn a_back_view_with_hair_over_the_head_reads_as_seen_from_behind() {
    let cal = Calibration::embedded().unwrap();
    let (e, truth) = evidence(43, 180.0, Hair::Long);
    let f = decide(&e, cal, &FigureOptions::default(), None).unwrap();
    assert_eq!(f.facing.facing, Facing::Back, "{:?}", f.facing.probabilities);
    assert!(handedness(&f.joints) < -0.1 && !is_swap(&truth, &f.joints), "{}", handedness(&f.joints));
    assert!(pck(&truth, &f.joints.xy, 0.2).unwrap() >= 0.8);
}
