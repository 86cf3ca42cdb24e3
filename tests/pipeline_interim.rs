//! Interim bodies of a run (`run_pipeline_progressive`): what is shown before the final body,
//! in order, and a result equal to `run_pipeline`'s.

#[path = "common/example.rs"]
mod example;
use example::inputs;

use sketchbody::body::Gender;
use sketchbody::fit::FitOptions;
use sketchbody::pipeline::{
    run_pipeline, run_pipeline_progressive, GivenJoints, InterimBody, InterimStage, PipelineOptions,
};

/// What a test keeps of an interim body.
struct Seen {
    stage: InterimStage,
    gender: Gender,
    weights: Vec<f64>,
    rest: Vec<[f32; 3]>,
    posed: Vec<[f32; 3]>,
}

fn run(options: &PipelineOptions) -> (sketchbody::pipeline::PipelineResult, Vec<Seen>) {
    let (model, dict, sketch, j) = inputs();
    let mut seen = Vec::new();
    let mut show = |b: &InterimBody| {
        seen.push(Seen {
            stage: b.stage,
            gender: b.gender,
            weights: b.shape.weights.clone(),
            rest: b.rest.vertices.clone(),
            posed: b.posed_vertices.to_vec(),
        })
    };
    let mut fractions = Vec::new();
    let r = run_pipeline_progressive(
        &model,
        &dict,
        &sketch,
        &GivenJoints(j),
        options,
        &mut |f| {
            fractions.push(f);
            true
        },
        Some(&mut show),
    )
    .unwrap();
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]));
    (r, seen)
}

/// Automatic gender with given joints: the mean shape of the classifier's gender in the
/// estimated pose first, then the chosen gender's 4-dimension deciding fit, then the result,
/// which equals run_pipeline's.
#[test]
fn a_run_shows_the_mean_shape_then_the_deciding_fit_and_ends_as_run_pipeline() {
    let (model, dict, sketch, j) = inputs();
    let options = PipelineOptions {
        fit: FitOptions { samples: 24, max_iterations: 3, ..FitOptions::default() },
        ..PipelineOptions::default()
    };
    let (r, seen) = run(&options);
    let plain = run_pipeline(&model, &dict, &sketch, &GivenJoints(j), &options, &mut |_| true).unwrap();
    assert_eq!((r.weights.clone(), r.posed_vertices.clone()), (plain.weights, plain.posed_vertices));
    assert_eq!(seen.iter().map(|s| s.stage).collect::<Vec<_>>(), [InterimStage::MeanShape, InterimStage::DecidingFit]);
    let (mean, deciding) = (&seen[0], &seen[1]);
    // The mean shape: no weights, the model's mean rest shape of the classifier's gender, posed.
    let guess = if r.gender_evidence.male_probability > 0.5 { Gender::Male } else { Gender::Female };
    assert_eq!((mean.gender, mean.weights.len()), (guess, 0));
    assert_eq!(mean.rest, model.space(guess).synthesize(&[]).unwrap().vertices);
    assert_eq!(mean.posed.len(), mean.rest.len());
    assert_ne!(mean.posed, mean.rest, "posed, not the rest pose");
    // The deciding fit: the chosen gender's 4 leading dimensions, as the result's deciding fit.
    assert_eq!(deciding.gender, r.gender);
    let decided = &r.fits[r.gender.index()];
    assert_eq!(deciding.weights, decided.fit.as_ref().unwrap().weights);
    assert_eq!(deciding.weights.len(), 4);
    assert_ne!(deciding.posed, r.posed_vertices, "the final fit refines it");
}

/// A given gender decides nothing by fitting: only the mean shape (of that gender) comes
/// before the result.
#[test]
fn a_given_gender_shows_only_the_mean_shape() {
    let options = PipelineOptions {
        fit: FitOptions { samples: 24, max_iterations: 3, ..FitOptions::default() },
        gender: Some(Gender::Male),
        ..PipelineOptions::default()
    };
    let (r, seen) = run(&options);
    assert_eq!(seen.len(), 1);
    assert_eq!((seen[0].stage, seen[0].gender), (InterimStage::MeanShape, Gender::Male));
    assert_eq!(r.gender, Gender::Male);
}
