//! Runs Canny repeatedly on a synthetic drawing, for profilers:
//! `cargo run --release --example canny_profile -- [SIZE] [STROKES]` (default 1024, 700).
use sketchbody::image::{canny, CannyParams, GrayImage};

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let n = args.first().copied().unwrap_or(1024);
    let strokes = args.get(1).copied().unwrap_or(700);
    let mut data = vec![255u8; n * n];
    let mut s: u64 = 12345;
    for _ in 0..strokes {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let (x0, y0) = ((s >> 20) as usize % n, (s >> 40) as usize % n);
        let horizontal = s & 1 == 0;
        for t in 0..300 {
            let (x, y) = if horizontal { ((x0 + t) % n, y0) } else { (x0, (y0 + t) % n) };
            data[y * n + x] = 40;
        }
    }
    let img = GrayImage::from_vec(n, n, data).expect("valid image");
    let start = std::time::Instant::now();
    let mut count = 0;
    for _ in 0..50 {
        let e = canny(&img.view(), &CannyParams::default()).expect("canny");
        count += e.as_bytes().iter().filter(|&&v| v > 0).count();
    }
    println!("{:.2} ms per call ({count} edge pixels in total)", start.elapsed().as_secs_f64() * 1000.0 / 50.0);
}
