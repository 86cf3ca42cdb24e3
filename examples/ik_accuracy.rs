//! IK accuracy over random plausible poses made by rotating the rig (docs/benchmarks.md,
//! "Posing and raster"): mean and max angle between posed and target bone directions, and with
//! bone-length retargeting (bones also scaled by up to ±15%) the max joint position error. Rigs:
//! the embedded MakeHuman mean female and male, and the procedural capsule rig.
//! Usage: cargo run --release --example ik_accuracy [N=500] [SEED=1]

use nalgebra::Vector3;
use rand::SeedableRng;
use sketchbody::body::ik::{solve, IkOptions};
use sketchbody::body::procedural::{random_pose, rest_joints};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::skeleton::{Joints3, BONES, NUM_JOINTS};

fn dir(j: &Joints3, b: usize) -> Vector3<f64> {
    let (s, c) = BONES[b];
    (Vector3::from(j[c]) - Vector3::from(j[s])).normalize()
}

fn main() {
    let args: Vec<u64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let n = args.first().copied().unwrap_or(500) as usize;
    let seed = args.get(1).copied().unwrap_or(1);
    let model = BodyModel::embedded().expect("embedded model");
    let rigs = [
        ("MakeHuman mean female", *model.space(Gender::Female).mean_joints()),
        ("MakeHuman mean male", *model.space(Gender::Male).mean_joints()),
        ("procedural 1.7 m A-pose", rest_joints()),
    ];
    for (name, rest) in rigs {
        measure(name, &rest, n, seed);
    }
}

fn measure(name: &str, rest: &Joints3, n: usize, seed: u64) {
    let rest = *rest;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut sum, mut max, mut count) = (0.0f64, 0.0f64, 0usize);
    let mut max_pos = 0.0f64;
    let t0 = std::time::Instant::now();
    for _ in 0..n {
        let target = random_pose(&rest, &mut rng, 0.0);
        let pose = solve(&rest, &target, &IkOptions::default()).expect("valid pose");
        for b in 0..BONES.len() {
            // Posed bone direction from the posed joints (what skinning uses).
            let (p, t) = (dir(&pose.joints, b), dir(&target, b));
            let a = p.cross(&t).norm().atan2(p.dot(&t)).to_degrees();
            sum += a;
            max = max.max(a);
            count += 1;
        }
        let stretched = random_pose(&rest, &mut rng, 0.15);
        let pose = solve(&rest, &stretched, &IkOptions { retarget: true }).expect("valid pose");
        for j in 0..NUM_JOINTS {
            max_pos = max_pos.max((Vector3::from(pose.joints[j]) - Vector3::from(stretched[j])).norm());
        }
    }
    let dt = t0.elapsed().as_secs_f64();
    println!("IK over {n} random poses (seed {seed}), {name} rig:");
    println!("  bone direction error: mean {:.2e} deg, max {:.2e} deg (goal <= 0.1 deg)", sum / count as f64, max);
    println!(
        "  retargeted (bone lengths x U[0.85, 1.15]): max joint position error {:.2e} mm (goal <= 1 mm)",
        max_pos * 1e3
    );
    println!("  {:.1} us per solve", dt / (2 * n) as f64 * 1e6);
}
