//! Shape-fit throughput exactly as `fit_shape` does it: sample evaluations per second (proxy
//! synthesis + IK + skinning + raster + score, in parallel over samples) and the whole fit's
//! time with default options, on outline sketches (512², Canny edges of a known body's
//! silhouette) of `N` random bodies, genders alternating. The fit proxy is built once before
//! timing (its build time is printed). Times are wall clock; process CPU time is printed too,
//! and "per CPU-second" is what each busy core delivers (robust on a shared machine).
//! The fit gets the body's projected joints as its 2-D joints (the pipeline's joint term), and
//! every body is fitted three times, on the old path (the problem's camera, PCA weights only,
//! temperature 2), with the defaults but `FitOptions::estimate_proportions` off, and with the
//! defaults (per-sample cameras `FitOptions::sample_camera`, bone factors
//! `FitOptions::proportion_sd` centred on their closed-form estimate), so the paths' rates are
//! compared in one process.
//! Usage: cargo run --release --example fit_throughput [N=6] [THREADS=2] [SEED=3]

use nalgebra::Matrix3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::camera::WeakPerspective;
use sketchbody::fit::{fit_shape, FitOptions, FitProblem};
use sketchbody::image::{canny, CannyParams, GrayImage};
use sketchbody::raster::Rasterizer;
use sketchbody::skeleton::{Joints2, NUM_JOINTS};

/// Totals of one path: evaluations, wall and CPU seconds, whole-fit wall times.
#[derive(Default)]
struct Totals {
    evals: usize,
    wall: f64,
    cpu: f64,
    fit_times: Vec<f64>,
}

impl Totals {
    fn print(&mut self, label: &str, threads: usize) -> f64 {
        let n = self.fit_times.len();
        self.fit_times.sort_by(f64::total_cmp);
        let median = 0.5 * (self.fit_times[(n - 1) / 2] + self.fit_times[n / 2]);
        println!(
            "{n} fits, {label}, on {threads} threads: {:.0} evaluations/s wall ({} in {:.2} s), {:.0} per CPU-second; whole fit median {:.1} ms, max {:.1} ms",
            self.evals as f64 / self.wall,
            self.evals,
            self.wall,
            self.evals as f64 / self.cpu,
            median * 1e3,
            self.fit_times[n - 1] * 1e3
        );
        self.evals as f64 / self.cpu
    }
}

fn process_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<u64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let n = args.first().copied().unwrap_or(6) as usize;
    let threads = args.get(1).copied().unwrap_or(2) as usize;
    let seed = args.get(2).copied().unwrap_or(3);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let model = BodyModel::embedded()?;
    let (t0, c0) = (std::time::Instant::now(), process_cpu());
    let proxy = model.fit_proxy()?;
    println!(
        "fit proxy: {} of {} vertices, {} triangles, built in {:.1} ms wall, {:.1} ms CPU",
        proxy.kept().len(),
        model.num_vertices(),
        proxy.triangles().len(),
        t0.elapsed().as_secs_f64() * 1e3,
        (process_cpu() - c0) * 1e3
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut totals = [Totals::default(), Totals::default(), Totals::default()];
    for i in 0..n {
        let gender = if i % 2 == 0 { Gender::Female } else { Gender::Male };
        let space = model.space(gender);
        let truth = space.synthesize(&space.gmm().marginal(space.default_dim())?.sample(&mut rng))?;
        let cam = WeakPerspective { sx: 200.0, sy: 200.0, r: Matrix3::identity(), t: [256.0, 262.0] };
        let mut raster = Rasterizer::new();
        raster.rasterize(&truth.vertices, &model.triangles(), &cam, 512, 512, false)?;
        let drawing: Vec<u8> = raster.mask().iter().map(|&m| if m != 0 { 40 } else { 235 }).collect();
        let edges = canny(&GrayImage::from_vec(512, 512, drawing)?.view(), &CannyParams::default())?;
        let joints2d = Joints2 {
            xy: std::array::from_fn(|k| cam.project(&nalgebra::Vector3::from(truth.joints[k]))),
            visible: [true; NUM_JOINTS],
        };
        let problem = FitProblem {
            model: &model,
            gender: gender.into(),
            pose: &truth.joints,
            camera: &cam,
            edges: &edges,
            joints2d: Some(&joints2d),
            views: &[],
        };
        let old = FitOptions { sample_camera: false, proportion_sd: 0.0, temperature: 2.0, ..FitOptions::default() };
        let no_estimate = FitOptions { estimate_proportions: false, ..FitOptions::default() };
        for (path, base) in [old, no_estimate, FitOptions::default()].into_iter().enumerate() {
            let sample_camera = base.sample_camera;
            let options = FitOptions { seed: 100 + i as u64, ..base };
            let (start, c0) = (std::time::Instant::now(), process_cpu());
            let result = pool.install(|| fit_shape(&problem, &options, &mut |_| true))?;
            let (dt, dc) = (start.elapsed().as_secs_f64(), process_cpu() - c0);
            println!(
                "fit {i} ({gender:?}, sample camera {sample_camera}): {} evaluations in {} iterations, {:.1} ms wall, {:.1} ms CPU: {:.0} evaluations/s",
                result.evaluations,
                result.history.len(),
                dt * 1e3,
                dc * 1e3,
                result.evaluations as f64 / dt
            );
            let t = &mut totals[path];
            t.evals += result.evaluations;
            t.wall += dt;
            t.cpu += dc;
            t.fit_times.push(dt);
        }
    }
    let old = totals[0].print("old path (problem camera, PCA only, temperature 2)", threads);
    let previous = totals[1].print("defaults without the proportion estimate", threads);
    let new = totals[2].print("defaults (per-sample cameras, bone factors centred on their estimate)", threads);
    println!("defaults / old path, evaluations per CPU-second: {:.3}", new / old);
    println!("defaults / without the proportion estimate, evaluations per CPU-second: {:.3}", new / previous);
    Ok(())
}
