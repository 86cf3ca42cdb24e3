//! The committed learned factor prior must equal a fresh `train-factor-prior` build from the
//! shared motion data byte for byte.

#[path = "../../tests/common/mod.rs"]
mod common;

use sketchbody::body::BodyModel;
use sketchbody::pose::dict_io;
use sketchbody::pose::factor_prior::EMBEDDED_FACTOR_PRIOR;
use sketchbody_lab::pose::factor_train::{train_from_mocap, TrainParams};
use sketchbody_lab::pose::learn::{body_model_skeletons, default_held_out};

#[test]
fn rebuilt_factor_prior_matches_the_committed_asset() {
    let Some(data) = common::shared_data("factor prior rebuild") else { return };
    let prior = train_from_mocap(
        &[data.join("mocap/deepmimic"), data.join("mocap/cmu")],
        &default_held_out(),
        &body_model_skeletons(&BodyModel::embedded().unwrap()),
        &dict_io::embedded().unwrap().bone_lengths,
        "the embedded dictionary",
        &TrainParams::default(),
        |_, _| (),
    )
    .unwrap();
    let fresh = prior.to_json() + "\n";
    assert!(
        fresh == EMBEDDED_FACTOR_PRIOR,
        "assets/factor_prior.json differs from a fresh build ({} vs {} bytes): rerun `sketchbody-lab \
         train-factor-prior --mocap ../shared/data/mocap/deepmimic --mocap ../shared/data/mocap/cmu --out \
         assets/factor_prior.json`",
        fresh.len(),
        EMBEDDED_FACTOR_PRIOR.len()
    );
    assert!(prior.provenance.contains(
        "held_out: dance_b,jog,kick,long_long_walk3,long_long_walk3_mirror,long_stealthy_walk1,06_*,08_*,13_*,16_*"
    ));
}
