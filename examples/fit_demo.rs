//! Fits shapes to outline sketches of known random bodies and prints AED (mean per-vertex
//! distance / reference height, rest pose) for the mean shape and each score, plus throughput.
//! `cargo run --release --example fit_demo -- [N] [SEED]`.

use nalgebra::Matrix3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::camera::WeakPerspective;
use sketchbody::fit::{fit_shape, FitOptions, FitProblem, MatchScore};
use sketchbody::image::{canny, CannyParams, GrayImage};
use sketchbody::raster::Rasterizer;

fn aed(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let height = {
        let ys = a.iter().map(|v| v[1] as f64);
        ys.clone().fold(f64::MIN, f64::max) - ys.fold(f64::MAX, f64::min)
    };
    let sum: f64 =
        a.iter().zip(b).map(|(p, q)| (0..3).map(|c| (p[c] as f64 - q[c] as f64).powi(2)).sum::<f64>().sqrt()).sum();
    sum / a.len() as f64 / height
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<u64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let (n, seed) = (args.first().copied().unwrap_or(4) as usize, args.get(1).copied().unwrap_or(7));
    let model = BodyModel::embedded()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let scores = [MatchScore::Paper, MatchScore::FilledIou, MatchScore::Chamfer];
    let mut totals = vec![0.0; scores.len() + 1];
    let (mut evals, mut seconds) = (0usize, 0.0f64);
    for i in 0..n {
        let gender = if i % 2 == 0 { Gender::Female } else { Gender::Male };
        let space = model.space(gender);
        let dims = space.default_dim();
        let truth_w = space.gmm().marginal(dims)?.sample(&mut rng);
        let truth = space.synthesize(&truth_w)?;
        let cam = WeakPerspective { sx: 200.0, sy: 200.0, r: Matrix3::identity(), t: [256.0, 262.0] };
        let mut raster = Rasterizer::new();
        raster.rasterize(&truth.vertices, &model.triangles(), &cam, 512, 512, false)?;
        let silhouette: Vec<u8> = raster.mask().iter().map(|&m| if m != 0 { 40 } else { 235 }).collect();
        let edges = canny(&GrayImage::from_vec(512, 512, silhouette)?.view(), &CannyParams::default())?;
        let mean = space.synthesize(&[])?;
        totals[0] += aed(&truth.vertices, &mean.vertices);
        print!("sample {i} ({gender:?}): mean shape AED {:.4}", aed(&truth.vertices, &mean.vertices));
        for (k, &score) in scores.iter().enumerate() {
            let problem = FitProblem {
                model: &model,
                gender: gender.into(),
                pose: &truth.joints,
                camera: &cam,
                edges: &edges,
                joints2d: None,
                views: &[],
            };
            let options = FitOptions { score, seed: 100 + i as u64, ..FitOptions::default() };
            let start = std::time::Instant::now();
            let result = fit_shape(&problem, &options, &mut |_| true)?;
            seconds += start.elapsed().as_secs_f64();
            evals += result.evaluations;
            let fitted = space.synthesize(&result.weights)?;
            let e = aed(&truth.vertices, &fitted.vertices);
            totals[k + 1] += e;
            print!(", {score:?} {e:.4} ({} it)", result.history.len());
        }
        println!();
    }
    println!(
        "mean AED/height over {n}: mean shape {:.4}, paper {:.4}, filled IoU {:.4}, chamfer {:.4}",
        totals[0] / n as f64,
        totals[1] / n as f64,
        totals[2] / n as f64,
        totals[3] / n as f64
    );
    println!(
        "{evals} sample evaluations in {seconds:.2} s: {:.0} per second ({} threads)",
        evals as f64 / seconds,
        rayon::current_num_threads()
    );
    Ok(())
}
