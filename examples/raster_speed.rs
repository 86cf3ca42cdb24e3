//! Rasteriser speed on the ~27k-triangle procedural body: mean time per call at 256² and
//! 512², mask only and with depth (one thread), and mask only drawing viewer-facing triangles.
//! Usage: cargo run --release --example raster_speed [SIZE ...] (default 256 512)

use nalgebra::Matrix3;
use sketchbody::body::procedural::{capsule_humanoid, rest_joints};
use sketchbody::camera::WeakPerspective;
use sketchbody::render::raster::{Facing, Rasterizer};

fn main() {
    let mesh = capsule_humanoid(&rest_joints(), 40, 24);
    let tris = mesh.triangles();
    let mut r = Rasterizer::new();
    let sizes: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let sizes = if sizes.is_empty() { vec![256, 512] } else { sizes };
    for size in sizes {
        let s = size as f64 * 0.8 / 1.7;
        let cam = WeakPerspective { sx: s, sy: s, r: Matrix3::identity(), t: [size as f64 / 2.0, size as f64 / 2.0 + 0.85 * s] };
        for (depth, facing) in [(false, Facing::Both), (true, Facing::Both), (false, Facing::Front)] {
            let n = 200;
            let (t0, c0) = (std::time::Instant::now(), thread_cpu());
            let (mut covered, mut scanned) = (0, 0);
            for _ in 0..n {
                let st = if depth {
                    r.rasterize(&mesh.vertices, &tris, &cam, size, size, true)
                } else {
                    r.rasterize_mask(&mesh.vertices, &tris, &cam, size, size, facing)
                }
                .expect("raster");
                covered = st.covered;
                scanned = st.triangles_scanned;
            }
            let dt = t0.elapsed().as_secs_f64() / n as f64;
            let cpu = (thread_cpu() - c0) / n as f64;
            println!("raster {size}² {} tris, depth {depth}, {facing:?} faces: {:.3} ms wall, {:.3} ms thread CPU per call ({covered} px covered, {scanned} triangles scanned)", tris.len(), dt * 1e3, cpu * 1e3);
        }
    }
}

/// CPU time of this thread, seconds (wall time is unreliable on a shared machine).
fn thread_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
