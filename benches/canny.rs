//! Criterion benchmarks of Canny and the Gaussian blur on synthetic line drawings.
//! `cargo bench --bench canny`. The OpenCV comparison is cpp_tests/canny_bench.cpp.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use sketchbody::image::{canny, gaussian_blur, CannyParams, GrayImage};

/// A white page with `strokes` dark horizontal/vertical strokes 2 px wide (deterministic).
fn drawing(n: usize, strokes: usize) -> GrayImage {
    let mut data = vec![245u8; n * n];
    let mut s: u64 = 99;
    for _ in 0..strokes {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let (x0, y0, len) = ((s >> 16) as usize % n, (s >> 36) as usize % n, 20 + (s >> 56) as usize);
        for t in 0..len {
            for k in 0..2 {
                let (x, y) = if s & 1 == 0 { ((x0 + t) % n, (y0 + k) % n) } else { ((x0 + k) % n, (y0 + t) % n) };
                data[y * n + x] = 30;
            }
        }
    }
    GrayImage::from_vec(n, n, data).expect("valid size")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("canny");
    for (n, strokes) in [(512, 200), (1024, 800)] {
        let img = drawing(n, strokes);
        for l2 in [false, true] {
            let params = CannyParams { l2_gradient: l2, ..CannyParams::default() };
            let id = BenchmarkId::new(if l2 { "L2" } else { "L1" }, n);
            group.bench_with_input(id, &img, |b, img| b.iter(|| canny(&img.view(), &params).expect("canny")));
        }
    }
    group.finish();
    let img = drawing(1024, 800);
    c.bench_function("gaussian_blur/1024/sigma1.4", |b| b.iter(|| gaussian_blur(&img.view(), 1.4).expect("blur")));
}

criterion_group!(benches, bench);
criterion_main!(benches);
