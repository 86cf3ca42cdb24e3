//! Float image helpers of the stylisations: planes in 0..=1, a separable Gaussian blur in `f32`
//! (XDoG needs differences far below one 8-bit level), an edge-preserving bilateral filter,
//! colour k-means and a label mode filter. Every function works on any size ≥ 1×1 and never
//! indexes outside its buffers.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use sketchbody::image::{over_white, ImageView};

/// An RGB pixel with channels in 0..=1.
pub type Rgb = [f32; 3];

/// Luminance (0..=1) of an RGB pixel with the Rec. 601 weights `to_gray` uses.
pub fn luma(p: Rgb) -> f32 {
    0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]
}

/// The pixels of a 1-, 3- or 4-channel view as RGB in 0..=1, row-major (gray expanded, RGBA
/// composited over white paper).
pub fn rgb_planes(src: &ImageView<'_>) -> Vec<Rgb> {
    let c = src.channels();
    let mut out = Vec::with_capacity(src.width() * src.height());
    for y in 0..src.height() {
        for p in src.row(y).chunks_exact(c) {
            let rgb = match c {
                1 => [p[0]; 3],
                4 => over_white([p[0], p[1], p[2], p[3]]),
                _ => [p[0], p[1], p[2]],
            };
            out.push(rgb.map(|v| v as f32 / 255.0));
        }
    }
    out
}

/// Index of `p` reflected into `0..len` without repeating the edge pixel (OpenCV's
/// `BORDER_REFLECT_101`; a length of 1 maps everything to 0).
fn reflect(p: isize, len: usize) -> usize {
    let n = len as isize;
    if n <= 1 {
        return 0;
    }
    let period = 2 * (n - 1);
    let m = p.rem_euclid(period);
    (if m < n { m } else { period - m }) as usize
}

/// Gaussian blur of a `w`×`h` float plane with standard deviation `sigma` pixels (kernel radius
/// `ceil(3σ)`, reflected borders). `sigma <= 0` returns a copy.
pub fn blur(src: &[f32], w: usize, h: usize, sigma: f64) -> Vec<f32> {
    if !(sigma > 0.0) || src.len() != w * h {
        return src.to_vec();
    }
    let r = (3.0 * sigma).ceil().max(1.0) as isize;
    let mut k: Vec<f32> = (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32).collect();
    let sum: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    let mut tmp = vec![0.0f32; w * h];
    for y in 0..h {
        let row = &src[y * w..(y + 1) * w];
        for x in 0..w {
            tmp[y * w + x] = k.iter().enumerate().map(|(i, c)| c * row[reflect(x as isize + i as isize - r, w)]).sum();
        }
    }
    let mut out = vec![0.0f32; w * h];
    for y in 0..h {
        let rows: Vec<usize> = (0..k.len()).map(|i| reflect(y as isize + i as isize - r, h) * w).collect();
        for x in 0..w {
            out[y * w + x] = k.iter().zip(&rows).map(|(c, &o)| c * tmp[o + x]).sum();
        }
    }
    out
}

/// One pass of a bilateral filter: each pixel becomes the mean of its `(2r+1)²` neighbours
/// weighted by a spatial Gaussian (`sigma_s` pixels) times a range Gaussian of the RGB distance
/// (`sigma_r`, in 0..=1 units), so flat areas smooth out and edges stay.
pub fn bilateral(src: &[Rgb], w: usize, h: usize, r: usize, sigma_s: f32, sigma_r: f32) -> Vec<Rgb> {
    let r = r as isize;
    let spatial: Vec<(isize, isize, f32)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(|&(dx, dy)| dx * dx + dy * dy <= r * r)
        .map(|(dx, dy)| (dx, dy, (-((dx * dx + dy * dy) as f32) / (2.0 * sigma_s * sigma_s)).exp()))
        .collect();
    let inv_r = 1.0 / (2.0 * sigma_r * sigma_r);
    let mut out = Vec::with_capacity(src.len());
    for y in 0..h {
        for x in 0..w {
            let c = src[y * w + x];
            let (mut acc, mut wsum) = ([0.0f32; 3], 0.0f32);
            for &(dx, dy, ws) in &spatial {
                let q = src[reflect(y as isize + dy, h) * w + reflect(x as isize + dx, w)];
                let d2 = (q[0] - c[0]).powi(2) + (q[1] - c[1]).powi(2) + (q[2] - c[2]).powi(2);
                let wt = ws * (-d2 * inv_r).exp();
                for (a, v) in acc.iter_mut().zip(q) {
                    *a += wt * v;
                }
                wsum += wt;
            }
            out.push(acc.map(|a| a / wsum.max(1e-12)));
        }
    }
    out
}

fn dist2(a: Rgb, b: Rgb) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// Index of the centre nearest to `p` (0 for an empty list).
pub fn nearest(p: Rgb, centres: &[Rgb]) -> usize {
    let mut best = (0, f32::INFINITY);
    for (i, &c) in centres.iter().enumerate() {
        let d = dist2(p, c);
        if d < best.1 {
            best = (i, d);
        }
    }
    best.0
}

/// `k` colour centres of `pixels` by k-means (k-means++ seeding and a sample of at most
/// `max_sample` pixels drawn from `seed`, then `iters` Lloyd iterations). Returns fewer centres
/// when the sample has fewer distinct colours; an empty input gives white.
pub fn kmeans_colours(pixels: &[Rgb], k: usize, iters: usize, max_sample: usize, seed: u64) -> Vec<Rgb> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    if pixels.is_empty() || k == 0 {
        return vec![[1.0; 3]];
    }
    let sample: Vec<Rgb> = if pixels.len() <= max_sample {
        pixels.to_vec()
    } else {
        (0..max_sample).map(|_| pixels[rng.random_range(0..pixels.len())]).collect()
    };
    let mut centres = vec![sample[rng.random_range(0..sample.len())]];
    let mut d: Vec<f32> = sample.iter().map(|&p| dist2(p, centres[0])).collect();
    while centres.len() < k {
        let total: f64 = d.iter().map(|&v| v as f64).sum();
        if total <= 1e-12 {
            break;
        }
        let mut t = rng.random_range(0.0..total);
        let mut pick = sample.len() - 1;
        for (i, &v) in d.iter().enumerate() {
            if t < v as f64 {
                pick = i;
                break;
            }
            t -= v as f64;
        }
        let c = sample[pick];
        centres.push(c);
        for (dv, &p) in d.iter_mut().zip(&sample) {
            *dv = dv.min(dist2(p, c));
        }
    }
    for _ in 0..iters {
        let mut sums = vec![([0.0f64; 3], 0usize); centres.len()];
        for &p in &sample {
            let s = &mut sums[nearest(p, &centres)];
            for (a, v) in s.0.iter_mut().zip(p) {
                *a += v as f64;
            }
            s.1 += 1;
        }
        for (c, (s, n)) in centres.iter_mut().zip(&sums) {
            if *n > 0 {
                *c = s.map(|v| (v / *n as f64) as f32);
            }
        }
    }
    centres
}

/// Edge-preserving smoothing of a photo: `passes` bilateral passes of radius `max(2, 2u)` px
/// (`u` the image's length unit), spatial sigma 0.75 × radius, range sigma `sigma_r`.
pub fn smooth_photo(rgb: &[Rgb], w: usize, h: usize, u: f64, passes: usize, sigma_r: f32) -> Vec<Rgb> {
    let r = (2.0 * u).round().max(2.0) as usize;
    let mut out = rgb.to_vec();
    for _ in 0..passes {
        out = bilateral(&out, w, h, r, r as f32 * 0.75, sigma_r);
    }
    out
}

/// 8-connected components of `mask` (`w` wide): a label per pixel (`u32::MAX` off the mask)
/// and the size of each component in pixels.
pub fn components(mask: &[bool], w: usize) -> (Vec<u32>, Vec<usize>) {
    let h = mask.len().checked_div(w).unwrap_or(0);
    let mut labels = vec![u32::MAX; mask.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for s in 0..w * h {
        if !mask[s] || labels[s] != u32::MAX {
            continue;
        }
        let id = sizes.len() as u32;
        labels[s] = id;
        stack.push(s);
        let mut n = 0;
        while let Some(i) = stack.pop() {
            n += 1;
            let (x, y) = (i % w, i / w);
            for ny in y.saturating_sub(1)..(y + 2).min(h) {
                for nx in x.saturating_sub(1)..(x + 2).min(w) {
                    let j = ny * w + nx;
                    if mask[j] && labels[j] == u32::MAX {
                        labels[j] = id;
                        stack.push(j);
                    }
                }
            }
        }
        sizes.push(n);
    }
    (labels, sizes)
}

/// One pass of a 3×3 mode filter on a label image: a pixel takes the label most of its nine
/// neighbours carry when that label holds at least five of them (removes specks and jaggies).
pub fn mode_filter(labels: &[u8], w: usize, h: usize) -> Vec<u8> {
    let mut out = labels.to_vec();
    for y in 0..h {
        for x in 0..w {
            let mut counts = [0u8; 256];
            for dy in -1..=1isize {
                for dx in -1..=1isize {
                    counts[labels[reflect(y as isize + dy, h) * w + reflect(x as isize + dx, w)] as usize] += 1;
                }
            }
            let (best, n) =
                counts.iter().enumerate().max_by_key(|&(i, &n)| (n, std::cmp::Reverse(i))).unwrap_or((0, &0));
            if *n >= 5 {
                out[y * w + x] = best as u8;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blur_keeps_the_mean_and_reflects_borders() {
        assert_eq!(reflect(-1, 5), 1);
        assert_eq!(reflect(5, 5), 3);
        assert_eq!(reflect(-7, 1), 0);
        let src: Vec<f32> = (0..30).map(|i| (i % 7) as f32 / 7.0).collect();
        let b = blur(&src, 6, 5, 1.0);
        assert_eq!(b.len(), 30);
        let flat = blur(&[0.5; 12], 4, 3, 2.0);
        assert!(flat.iter().all(|v| (v - 0.5).abs() < 1e-6));
        assert!((blur(&[0.25], 1, 1, 3.0)[0] - 0.25).abs() < 1e-6);
    }

    #[test]
    fn kmeans_finds_two_colours_and_mode_filter_removes_a_speck() {
        let px: Vec<Rgb> = (0..100).map(|i| if i < 50 { [0.1, 0.2, 0.9] } else { [0.9, 0.8, 0.1] }).collect();
        let c = kmeans_colours(&px, 4, 5, 64, 1);
        assert!(
            c.len() <= 2 || c.iter().filter(|c| dist2(**c, px[0]) < 1e-6 || dist2(**c, px[99]) < 1e-6).count() >= 2
        );
        assert_eq!(kmeans_colours(&[], 3, 5, 10, 1), vec![[1.0; 3]]);
        let mut labels = vec![0u8; 25];
        labels[12] = 3;
        assert_eq!(mode_filter(&labels, 5, 5), vec![0u8; 25]);
    }
}
