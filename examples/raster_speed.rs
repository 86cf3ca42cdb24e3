//! Rasteriser speed (one thread): the ~27k-triangle procedural capsule body at 256² and 512²,
//! mask only (both windings), with depth, and mask only drawing viewer-facing triangles; then
//! the MakeHuman mean female body (26756 triangles) and its fit proxy as the shape fit draws
//! them (256², 100 px/m). Figures are the fastest of 5 batches of thread CPU time per call.
//! Usage: cargo run --release --example raster_speed [SIZE ...] (default 256 512)

use nalgebra::Matrix3;
use sketchbody::body::procedural::{capsule_humanoid, rest_joints};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::camera::WeakPerspective;
use sketchbody::raster::{Facing, RasterStats, Rasterizer};

fn main() {
    let mesh = capsule_humanoid(&rest_joints(), 40, 24);
    let tris = mesh.triangles();
    let mut r = Rasterizer::new();
    let sizes: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let sizes = if sizes.is_empty() { vec![256, 512] } else { sizes };
    for size in sizes {
        let s = size as f64 * 0.8 / 1.7;
        let cam = WeakPerspective {
            sx: s,
            sy: s,
            r: Matrix3::identity(),
            t: [size as f64 / 2.0, size as f64 / 2.0 + 0.85 * s],
        };
        for (depth, facing) in [(false, Facing::Both), (true, Facing::Both), (false, Facing::Front)] {
            let (cpu, st) = time(|| draw(&mut r, &mesh.vertices, &tris, &cam, size, depth, facing));
            println!("raster {size}² capsules {} tris, depth {depth}, {facing:?} faces: {:.3} ms thread CPU per call ({} px covered, {} triangles scanned)", tris.len(), cpu * 1e3, st.covered, st.triangles_scanned);
        }
    }
    let model = BodyModel::embedded().expect("model");
    let proxy = model.fit_proxy().expect("proxy");
    let space = model.space(Gender::Female);
    let body = space.synthesize(&[]).expect("mean");
    let mut proxy_rest = Vec::new();
    proxy.space(Gender::Female).synthesize_into(space, &[], &mut proxy_rest).expect("proxy mean");
    let cam = WeakPerspective { sx: 100.0, sy: 100.0, r: Matrix3::identity(), t: [128.0, 131.0] };
    let full_tris = model.triangles();
    for (name, v, t, facing) in [
        ("MakeHuman body", &body.vertices, &full_tris[..], Facing::Both),
        ("MakeHuman body", &body.vertices, &full_tris[..], Facing::Front),
        ("fit proxy", &proxy_rest, proxy.triangles(), Facing::Both),
        ("fit proxy", &proxy_rest, proxy.triangles(), Facing::Front),
    ] {
        let (cpu, st) = time(|| draw(&mut r, v, t, &cam, 256, false, facing));
        println!("raster 256² {name} {} tris at 100 px/m, {facing:?} faces: {:.4} ms thread CPU per call ({} px covered, {} triangles scanned)", t.len(), cpu * 1e3, st.covered, st.triangles_scanned);
    }
}

#[allow(clippy::too_many_arguments)]
fn draw(
    r: &mut Rasterizer,
    v: &[[f32; 3]],
    t: &[[u32; 3]],
    cam: &WeakPerspective,
    size: usize,
    depth: bool,
    facing: Facing,
) -> RasterStats {
    if depth {
        r.rasterize(v, t, cam, size, size, true).expect("raster")
    } else {
        r.rasterize_mask(v, t, cam, size, size, facing).expect("raster")
    }
}

/// Fastest of 5 batches of 100 calls: thread CPU seconds per call, and the last call's stats.
fn time(mut f: impl FnMut() -> RasterStats) -> (f64, RasterStats) {
    let mut best = f64::INFINITY;
    let mut stats = RasterStats::default();
    for _ in 0..5 {
        let c0 = thread_cpu();
        for _ in 0..100 {
            stats = f();
        }
        best = best.min((thread_cpu() - c0) / 100.0);
    }
    (best, stats)
}

/// CPU time of this thread, seconds (wall time is unreliable on a shared machine).
fn thread_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
