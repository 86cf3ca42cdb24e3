//! Draws `assets/examples/sketch.png`: a front-facing figure in outline strokes on paper tone,
//! built from capsules around the canonical bones (a stand-in concept sketch for the README and
//! tests) and its 2-D joints: the very joint positions the figure is drawn around, written as a
//! `sketchbody-joints2d` file. Deterministic. Run:
//! `cargo run --release --example make_example_sketch -- OUT.png [JOINTS.json]`.

use sketchbody::export::joints2d::write_joints2d;
use sketchbody::image::{save_png, GrayImage};
use sketchbody::skeleton::{Joints2, BONES, NUM_JOINTS};

/// Joint positions in pixels (512x512 image), canonical order, the figure's right on image left.
const JOINTS: [[f64; 2]; NUM_JOINTS] = [
    [256.0, 70.0],  // head
    [256.0, 118.0], // neck
    [214.0, 126.0], // r_shoulder
    [190.0, 196.0], // r_elbow
    [176.0, 262.0], // r_wrist
    [298.0, 126.0], // l_shoulder
    [326.0, 192.0], // l_elbow
    [352.0, 252.0], // l_wrist
    [256.0, 250.0], // pelvis
    [234.0, 256.0], // r_hip
    [228.0, 352.0], // r_knee
    [222.0, 446.0], // r_ankle
    [278.0, 256.0], // l_hip
    [288.0, 352.0], // l_knee
    [300.0, 446.0], // l_ankle
];

/// Capsule radius of each bone in BONES order, pixels.
const RADII: [f64; 14] = [9.0, 13.0, 12.0, 10.0, 13.0, 12.0, 10.0, 30.0, 16.0, 17.0, 13.0, 16.0, 17.0, 13.0];

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (vx, vy) = (b[0] - a[0], b[1] - a[1]);
    let t = (((p[0] - a[0]) * vx + (p[1] - a[1]) * vy) / (vx * vx + vy * vy)).clamp(0.0, 1.0);
    ((p[0] - a[0] - t * vx).powi(2) + (p[1] - a[1] - t * vy).powi(2)).sqrt()
}

/// Signed distance to the figure: negative inside.
fn figure_distance(p: [f64; 2]) -> f64 {
    let head =
        ((p[0] - JOINTS[0][0]).powi(2) / 26.0f64.powi(2) + (p[1] - JOINTS[0][1]).powi(2) / 33.0f64.powi(2)).sqrt();
    let mut d = (head - 1.0) * 28.0;
    for (b, &(i, j)) in BONES.iter().enumerate().skip(1) {
        d = d.min(segment_distance(p, JOINTS[i], JOINTS[j]) - RADII[b]);
    }
    d
}

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "assets/examples/sketch.png".into());
    let n = 512;
    let mut data = vec![0u8; n * n];
    let mut noise: u32 = 2024;
    for y in 0..n {
        for x in 0..n {
            noise = noise.wrapping_mul(1664525).wrapping_add(1013904223);
            let paper = 236.0 + (noise >> 28) as f64;
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let d = figure_distance(p);
            // Outline stroke ~2.4 px wide with soft edges; a belt line across the hips.
            let stroke = (1.0 - ((d.abs() - 1.2).max(0.0))).clamp(0.0, 1.0);
            let belt = if d < 0.0 && (p[1] - 240.0).abs() < 1.5 { 0.8 } else { 0.0 };
            let ink = stroke.max(belt);
            data[y * n + x] = (paper * (1.0 - ink) + 35.0 * ink).round() as u8;
        }
    }
    let img = GrayImage::from_vec(n, n, data).expect("512x512 image");
    if let Err(e) = save_png(&img.view(), std::path::Path::new(&out)) {
        eprintln!("make_example_sketch: {e}");
        std::process::exit(1);
    }
    if let Some(path) = std::env::args().nth(2) {
        let joints = Joints2 { xy: JOINTS, visible: [true; NUM_JOINTS] };
        if let Err(e) = write_joints2d(std::path::Path::new(&path), &joints) {
            eprintln!("make_example_sketch: {e}");
            std::process::exit(1);
        }
    }
}
