//! The model's input tensor: the ROI resampled to 256×256 RGB in [0, 1] by bilinear
//! interpolation, white outside the image, as MediaPipe's CPU `ImageToTensorCalculator` does
//! it with OpenCV: the ROI's corners map to the tensor's corners (tensor pixel `(u, v)` samples
//! the ROI at normalised `(u / 256, v / 256)`), and sample positions are quantised the way
//! OpenCV's `warpAffine` quantises them (the affine map in 1/1024 px fixed point, positions
//! rounded to 1/32 px, bilinear weights of those 1/32 steps). The network's landmarks move by up
//! to a few tenths of a pixel when the crop is sampled at exact positions instead, so the
//! reference cross-check (`tests/blazepose_reference.rs`) needs the same quantisation.

use super::roi::Roi;
use crate::image::{over_white, ImageView};

/// Side of the landmark model's square input, px.
pub const INPUT_SIDE: usize = 256;

/// OpenCV's fixed-point precision of the affine map (`AB_BITS`): 1/1024 px.
const AB_BITS: u32 = 10;
/// OpenCV's sub-pixel precision of bilinear sample positions (`INTER_BITS`): 1/32 px.
const INTER_BITS: u32 = 5;

/// RGB of a gray, RGB or RGBA pixel (RGBA composited over white).
pub(crate) fn rgb_of(p: &[u8]) -> [u8; 3] {
    match p.len() {
        1 => [p[0]; 3],
        3 => [p[0], p[1], p[2]],
        _ => over_white([p[0], p[1], p[2], p[3]]),
    }
}

/// The inverse affine map of the crop, `[m00, m01, m02, m10, m11, m12]`: tensor pixel `(u, v)`
/// → image pixel-centre coordinates `(m00 u + m01 v + m02, m10 u + m11 v + m12)` (pixel `i`'s
/// centre at `i`), as `cv::warpAffine(..., WARP_INVERSE_MAP)` takes it.
pub fn inverse_map(roi: &Roi) -> [f64; 6] {
    let (s, c) = roi.rotation.sin_cos();
    let n = INPUT_SIDE as f64;
    let a = [roi.size * c / n, -roi.size * s / n, roi.size * s / n, roi.size * c / n];
    let h = n / 2.0;
    let t0 = roi.cx - (a[0] * h + a[1] * h) - 0.5;
    let t1 = roi.cy - (a[2] * h + a[3] * h) - 0.5;
    [a[0], a[1], t0, a[2], a[3], t1]
}

/// `v` in OpenCV's affine fixed point (`saturate_cast<int>(v * AB_SCALE)`: round half to even,
/// saturated).
fn fixed(v: f64) -> i64 {
    (v * (1 << AB_BITS) as f64).round_ties_even().clamp(i32::MIN as f64, i32::MAX as f64) as i64
}

/// The 256×256×3 crop of `image` inside `roi`, row-major HWC, values in [0, 1]. Points outside the
/// image read as white, so ROIs partly outside the image are padded.
pub fn crop_tensor(image: &ImageView<'_>, roi: &Roi) -> Vec<f32> {
    let (w, h, ch) = (image.width() as i64, image.height() as i64, image.channels());
    let unit: [f32; 256] = std::array::from_fn(|c| c as f32 / 255.0);
    // Pixel `x` of `row` in [0, 1]; white outside the image.
    let tap = |row: &[u8], x: usize| rgb_of(&row[x * ch..(x + 1) * ch]).map(|c| unit[c as usize]);
    let pixel = |x: i64, y: i64| -> [f32; 3] {
        if x < 0 || y < 0 || x >= w || y >= h {
            return [1.0; 3];
        }
        tap(image.row(y as usize), x as usize)
    };
    let m = inverse_map(roi);
    let round_delta = 1i64 << (AB_BITS - INTER_BITS - 1);
    let tab = (1i64 << INTER_BITS) as f32;
    let mask = (1i64 << INTER_BITS) - 1;
    // The column terms of the fixed-point map, the same for every row (OpenCV's `adelta`,
    // `bdelta`).
    let dx: Vec<i64> = (0..INPUT_SIDE).map(|u| fixed(m[0] * u as f64)).collect();
    let dy: Vec<i64> = (0..INPUT_SIDE).map(|u| fixed(m[3] * u as f64)).collect();
    let mut out = vec![0.0f32; INPUT_SIDE * INPUT_SIDE * 3];
    for (v, out_row) in out.chunks_exact_mut(INPUT_SIDE * 3).enumerate() {
        let x0 = fixed(m[1] * v as f64 + m[2]) + round_delta;
        let y0 = fixed(m[4] * v as f64 + m[5]) + round_delta;
        for (u, o) in out_row.chunks_exact_mut(3).enumerate() {
            let x = (x0 + dx[u]) >> (AB_BITS - INTER_BITS);
            let y = (y0 + dy[u]) >> (AB_BITS - INTER_BITS);
            let (ix, iy) = (x >> INTER_BITS, y >> INTER_BITS);
            let (fx, fy) = ((x & mask) as f32 / tab, (y & mask) as f32 / tab);
            let [a, b, c, d] = if ix >= 0 && iy >= 0 && ix + 1 < w && iy + 1 < h {
                // All four taps inside: read the two rows directly.
                let (r0, r1, x) = (image.row(iy as usize), image.row(iy as usize + 1), ix as usize);
                [tap(r0, x), tap(r0, x + 1), tap(r1, x), tap(r1, x + 1)]
            } else {
                [pixel(ix, iy), pixel(ix + 1, iy), pixel(ix, iy + 1), pixel(ix + 1, iy + 1)]
            };
            let wts = [(1.0 - fy) * (1.0 - fx), (1.0 - fy) * fx, fy * (1.0 - fx), fy * fx];
            for k in 0..3 {
                o[k] = a[k] * wts[0] + b[k] * wts[1] + c[k] * wts[2] + d[k] * wts[3];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_image_is_resampled_exactly_and_padded_white_outside() {
        // A 128² ramp x + y sampled by a ROI covering the image: tensor pixel (u, v) reads the
        // continuous point (u / 2, v / 2), i.e. pixel-centre coordinates (u / 2 - 0.5, v / 2 - 0.5),
        // multiples of 1/32 px where the quantised bilinear interpolation of a linear image is
        // exact.
        let s = 128;
        let px: Vec<u8> = (0..s * s).map(|i| (i % s + i / s) as u8).collect();
        let img = ImageView::gray(&px, s, s).unwrap();
        let roi = Roi { cx: 64.0, cy: 64.0, size: 128.0, rotation: 0.0 };
        let t = crop_tensor(&img, &roi);
        for v in 1..INPUT_SIDE - 2 {
            for u in 1..INPUT_SIDE - 2 {
                let want = ((u as f32 / 2.0 - 0.5) + (v as f32 / 2.0 - 0.5)) / 255.0;
                let got = t[3 * (v * INPUT_SIDE + u)];
                assert!((got - want).abs() < 1e-5, "u {u} v {v}: {got} vs {want}");
            }
        }
        let far = Roi { cx: -1000.0, cy: -1000.0, size: 10.0, rotation: 0.3 };
        assert!(crop_tensor(&img, &far).iter().all(|&v| v == 1.0));
    }

    /// The crop reads the four taps of every sample straight from the rows where they are all
    /// inside the image; it equals, bit for bit, the per-tap definition (white outside) on gray,
    /// RGB and RGBA images and rotated ROIs that cross every border.
    #[test]
    fn inner_samples_equal_the_per_tap_definition() {
        let (w, h) = (37usize, 23usize);
        for ch in [1usize, 3, 4] {
            let px: Vec<u8> = (0..w * h * ch).map(|i| ((i * 7919 + 13) % 251) as u8).collect();
            let img = ImageView::new(&px, w, h, ch, w * ch).unwrap();
            for roi in [
                Roi { cx: 18.0, cy: 11.0, size: 30.0, rotation: 0.4 },
                Roi { cx: 5.0, cy: 20.0, size: 50.0, rotation: -2.0 },
                Roi { cx: 18.5, cy: 11.5, size: 8.0, rotation: 0.0 },
            ] {
                let m = inverse_map(&roi);
                let t = crop_tensor(&img, &roi);
                let tap = |x: i64, y: i64, k: usize| -> f32 {
                    if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                        return 1.0;
                    }
                    let at = (y as usize * w + x as usize) * ch;
                    rgb_of(&px[at..at + ch])[k] as f32 / 255.0
                };
                for v in 0..INPUT_SIDE {
                    for u in (0..INPUT_SIDE).step_by(3) {
                        let q = |a: f64, b: f64, c: f64| {
                            (fixed(a * u as f64) + fixed(b * v as f64 + c) + 16) >> (AB_BITS - INTER_BITS)
                        };
                        let (x, y) = (q(m[0], m[1], m[2]), q(m[3], m[4], m[5]));
                        let (ix, iy, fx, fy) = (x >> 5, y >> 5, (x & 31) as f32 / 32.0, (y & 31) as f32 / 32.0);
                        for k in 0..3 {
                            let want = tap(ix, iy, k) * ((1.0 - fy) * (1.0 - fx))
                                + tap(ix + 1, iy, k) * ((1.0 - fy) * fx)
                                + tap(ix, iy + 1, k) * (fy * (1.0 - fx))
                                + tap(ix + 1, iy + 1, k) * (fy * fx);
                            assert_eq!(t[3 * (v * INPUT_SIDE + u) + k].to_bits(), want.to_bits(), "{ch} {u} {v} {k}");
                        }
                    }
                }
            }
        }
    }

    /// Sample positions snap to the nearest 1/32 px, as in OpenCV's `warpAffine`: on a ramp
    /// 0.01 px reads as 0 and 0.02 px as 1/32.
    #[test]
    fn sample_positions_are_rounded_to_a_32nd_of_a_pixel() {
        let s = 64;
        let px: Vec<u8> = (0..s * s).map(|i| (i % s) as u8).collect();
        let img = ImageView::gray(&px, s, s).unwrap();
        let at = |offset: f64| {
            let roi = Roi { cx: 128.0 + 0.5 + offset, cy: 128.0, size: 256.0, rotation: 0.0 };
            crop_tensor(&img, &roi)[3 * (20 * INPUT_SIDE + 10)] * 255.0
        };
        assert!((at(0.01) - 10.0).abs() < 1e-4, "{}", at(0.01));
        assert!((at(0.02) - (10.0 + 1.0 / 32.0)).abs() < 1e-4, "{}", at(0.02));
        assert_eq!(
            inverse_map(&Roi { cx: 128.0, cy: 128.0, size: 256.0, rotation: 0.0 }),
            [1.0, 0.0, -0.5, 0.0, 1.0, -0.5]
        );
    }
}
