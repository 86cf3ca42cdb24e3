//! Full shape-fit samples per second: synthesis of a random shape from the embedded model, IK to
//! a random pose, linear blend skinning and a 256² silhouette raster, in parallel over samples on
//! the rayon pool (one rasteriser per thread). Also prints samples per CPU-second (process CPU
//! time), which a shared machine distorts less than wall time. Usage:
//! cargo run --release --example sample_throughput [N=400] [THREADS=2]

use nalgebra::Matrix3;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use sketchbody::body::ik::{solve, IkOptions};
use sketchbody::body::procedural::random_pose;
use sketchbody::body::skin::{skin_into, SkinMethod};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::camera::WeakPerspective;
use sketchbody::raster::Rasterizer;

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let n = args.first().copied().unwrap_or(400);
    let threads = args.get(1).copied().unwrap_or(2);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    let model = BodyModel::embedded().expect("embedded model");
    let space = model.space(Gender::Female);
    let tris = model.triangles();
    let sd: Vec<f64> = space.variances().iter().take(space.default_dim()).map(|v| v.sqrt()).collect();
    let target = random_pose(space.mean_joints(), &mut rand_chacha::ChaCha8Rng::seed_from_u64(1), 0.0);
    let cam = WeakPerspective { sx: 120.0, sy: 120.0, r: Matrix3::identity(), t: [128.0, 128.0] };
    let (t0, c0) = (std::time::Instant::now(), process_cpu());
    let covered: usize = pool.install(|| {
        (0..n)
            .into_par_iter()
            .map_init(
                || (Rasterizer::new(), Vec::new()),
                |(r, posed), i| {
                    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(100 + i as u64);
                    let w: Vec<f64> = sd.iter().map(|s| s * rng.random_range(-2.0..2.0)).collect();
                    let rest = space.synthesize(&w).expect("weights");
                    let pose = solve(&rest.joints, &target, &IkOptions { retarget: true }).expect("pose");
                    skin_into(&rest.vertices, model.skin_weights(), &pose, SkinMethod::Linear, posed).expect("skin");
                    r.rasterize(posed, &tris, &cam, 256, 256, false).map(|s| s.covered).unwrap_or(0)
                },
            )
            .sum()
    });
    let (dt, dc) = (t0.elapsed().as_secs_f64(), process_cpu() - c0);
    println!(
        "{n} samples (synthesis of {} PCA weights + IK + LBS + 256² raster, {} triangles) on {threads} threads: {:.1} samples/s ({:.2} ms each; mean {} px covered); {:.0} per CPU-second",
        sd.len(),
        tris.len(),
        n as f64 / dt,
        dt / n as f64 * 1e3,
        covered / n,
        n as f64 / dc
    );
}

/// CPU time of the whole process (all threads), seconds.
fn process_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
