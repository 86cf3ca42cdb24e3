//! Compares another BlazePose landmark ONNX file with the embedded asset, as our loader
//! (`LandmarkNet::from_onnx`, depthwise rewrite included) runs them: the largest landmark
//! difference (x, y in crop px at 256²) and pose-flag difference over both passes of the
//! landmark backend on each image. Checks an export path (`scripts/finetune-blazepose.py
//! export-identity`) before a fine-tuned model is measured.
//!
//! `cargo run --release --example landmark_model_diff -- MODEL.onnx IMAGE...`

use sketchbody::detect::landmark::crop::crop_tensor;
use sketchbody::detect::landmark::roi::ink_box;
use sketchbody::detect::landmark::{landmarks_of_tensor, prep, roi_from_landmarks, LandmarkNet, Roi};
use sketchbody::image::load_rgb_image;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((model, images)) = args.split_first() else {
        return Err("usage: landmark_model_diff MODEL.onnx IMAGE...".into());
    };
    let other = LandmarkNet::from_onnx(&std::fs::read(model)?)?;
    let shipped = LandmarkNet::embedded()?;
    let (mut worst, mut worst_flag) = (0.0f64, 0.0f64);
    for path in images {
        let img = load_rgb_image(std::path::Path::new(path))?;
        let Some(b) = ink_box(&img.view()) else { continue };
        let mut roi = Roi::from_box(b)?;
        for pass in 1..=2 {
            let mut t = crop_tensor(&img.view(), &roi);
            prep::lighten_drawing(&mut t);
            let a = landmarks_of_tensor(&shipped, &roi, t.clone(), false)?;
            let o = landmarks_of_tensor(&other, &roi, t, false)?;
            let px = 256.0 / roi.size;
            let d = a
                .landmarks
                .iter()
                .zip(&o.landmarks)
                .map(|(p, q)| (p.x - q.x).hypot(p.y - q.y) * px)
                .fold(0.0, f64::max);
            let df = (a.pose_flag - o.pose_flag).abs();
            println!(
                "{path} pass {pass}: max landmark difference {d:.5} px at 256², pose flag {:.4} vs {:.4}",
                a.pose_flag, o.pose_flag
            );
            worst = worst.max(d);
            worst_flag = worst_flag.max(df);
            roi = roi_from_landmarks(&a)?;
        }
    }
    println!("worst: {worst:.5} px at 256², pose flag within {worst_flag:.5}");
    Ok(())
}
