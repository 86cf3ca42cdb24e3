//! The both-sexes shape space built at load time (`body::BlendedSpace`): it holds both gendered
//! mean shapes and their joints, gendered shapes, and its prior reaches the in-between.

use sketchbody::body::rig::y_extent;
use sketchbody::body::{BodyModel, Gender, BLEND_COMPONENTS};

fn aed(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (0..3).map(|c| (p[c] as f64 - q[c] as f64).powi(2)).sum::<f64>().sqrt()).sum::<f64>()
        / a.len() as f64
}

#[test]
fn blended_space_reproduces_both_mean_shapes_and_their_joints() {
    let model = BodyModel::embedded().unwrap();
    let b = model.blended().unwrap();
    let s = b.space();
    assert_eq!(s.num_components(), BLEND_COMPONENTS);
    for (g, t) in [(Gender::Female, 0.0), (Gender::Male, 1.0)] {
        let gendered = model.space(g);
        let w = s.project(gendered.mean(), s.num_components()).unwrap();
        assert!((b.gender_value(&w) - t).abs() < 1e-6, "{g:?}: gender value {}", b.gender_value(&w));
        let shape = s.synthesize(&w).unwrap();
        let err = aed(&shape.vertices, gendered.mean()) / y_extent(gendered.mean());
        assert!(err < 1e-4, "{g:?} mean shape rebuilt with AED/height {err}");
        let worst = shape
            .joints
            .iter()
            .zip(gendered.mean_joints())
            .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        assert!(worst < 0.003, "{g:?} mean joints off by {worst} m");
    }
}

#[test]
fn blended_space_holds_gendered_shapes_and_its_prior_covers_the_in_between() {
    let model = BodyModel::embedded().unwrap();
    let b = model.blended().unwrap();
    let s = b.space();
    // A gendered shape 1 sd along each of its first 4 components is rebuilt within 1.5 mm.
    for g in Gender::ALL {
        let gs = model.space(g);
        let wg: Vec<f64> = gs.variances()[..4].iter().map(|v| v.sqrt()).collect();
        let truth = gs.synthesize(&wg).unwrap();
        let rebuilt = s.synthesize(&s.project(&truth.vertices, s.num_components()).unwrap()).unwrap();
        let err = aed(&rebuilt.vertices, &truth.vertices);
        assert!(err < 0.0015, "{g:?}: rebuilt within {err} m");
    }
    // Prior samples: gender values at both ends and, with each population's spread along the
    // gender axis, continuously in between.
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let t: Vec<f64> = (0..4000).map(|_| b.gender_value(&s.gmm().sample(&mut rng))).collect();
    let frac = |lo: f64, hi: f64| t.iter().filter(|&&x| x >= lo && x < hi).count() as f64 / t.len() as f64;
    assert!(frac(-1.0, 0.2) > 0.2 && frac(0.8, 2.0) > 0.2, "ends {} {}", frac(-1.0, 0.2), frac(0.8, 2.0));
    assert!(frac(0.25, 0.75) > 0.02, "in-between {}", frac(0.25, 0.75));
    // The fit keeps weight 0 in the prior's 3-sd box, which holds both ends.
    let (lo, hi) = s.gmm().range(sketchbody::fit::PRIOR_RANGE_SD)[0];
    let (tlo, thi) = (b.gender_value(&[lo]), b.gender_value(&[hi]));
    assert!(tlo < 0.0 && thi > 1.0 && tlo > -5.0 && thi < 6.0, "gender value range {tlo}..{thi}");
    assert!((b.gender_value(&[b.gender_weight(0.3)]) - 0.3).abs() < 1e-12);
}

#[test]
fn a_per_sketch_male_mass_moves_the_prior_to_that_end() {
    use rand::SeedableRng;
    let model = BodyModel::embedded().unwrap();
    let b = model.blended().unwrap();
    let male_share = |p: f64| {
        let gmm = b.prior_with_male_mass(p).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        (0..4000).filter(|_| b.gender_value(&gmm.sample(&mut rng)) > 0.5).count() as f64 / 4000.0
    };
    // Each end's population spreads across 0.5 (about 30 % of the other side's), so the shares
    // of samples above 0.5 move less than the masses.
    let (low, even, high) = (male_share(0.1), male_share(0.5), male_share(0.9));
    assert!(low < 0.35 && (0.4..0.6).contains(&even) && high > 0.62, "male shares {low} {even} {high}");
    // 0.5 is the space's own prior.
    let same = b.prior_with_male_mass(0.5).unwrap();
    for (a, w) in same.weights().iter().zip(b.space().gmm().weights()) {
        assert!((a - w).abs() < 1e-12);
    }
    assert!(b.prior_with_male_mass(f64::NAN).is_err());
    // Out-of-range masses are clamped so neither end is ruled out.
    assert!(b.prior_with_male_mass(1.0).unwrap().weights().iter().all(|&w| w > 0.0));
}
