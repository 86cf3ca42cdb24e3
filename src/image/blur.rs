//! Gaussian blur compatible with OpenCV 4.x `cv::GaussianBlur(src, dst, Size(0, 0), sigma)` on
//! 8-bit gray images: kernel size `round(6σ + 1) | 1`, the bit-exact Gaussian kernel quantised to
//! 8 fractional bits with error diffusion (so it sums to exactly 256), a separable fixed-point
//! filter (row sums exact in 16 bits, column sums in 32 bits, one final rounding) and
//! `BORDER_REFLECT_101` borders. A dimension of 1 pixel is not filtered along (as in OpenCV).

use super::view::{GrayImage, ImageView};
use crate::error::{ensure_finite, Error, Result};

/// Kernel size OpenCV derives from `sigma` for 8-bit images: `round(6σ + 1) | 1`.
pub fn gaussian_kernel_size(sigma: f64) -> usize {
    (((sigma * 6.0 + 1.0).round_ties_even() as i64) | 1).max(1) as usize
}

/// Largest accepted sigma, in pixels (a kernel of about 6 * 1024 + 1 taps).
const MAX_SIGMA: f64 = 1024.0;

/// The Gaussian kernel in double precision, normalised as OpenCV's `getGaussianKernelBitExact`.
fn gaussian_kernel(n: usize, sigma: f64) -> Vec<f64> {
    let scale2 = -0.125 / (sigma * sigma);
    let half = (n - 1) / 2;
    let mut values = Vec::with_capacity(half);
    let mut sum = 0.0;
    let mut x = 1 - n as i64;
    for _ in 0..half {
        let t = ((x * x) as f64 * scale2).exp();
        values.push(t);
        sum += t;
        x += 2;
    }
    sum = sum * 2.0 + 1.0;
    let mul = 1.0 / sum;
    let mut k = vec![0.0; n];
    for (i, v) in values.iter().enumerate() {
        k[i] = v * mul;
        k[n - 1 - i] = v * mul;
    }
    k[half] = mul;
    k
}

/// Quantises a symmetric odd kernel to integers summing to 256 (OpenCV's error diffusion).
fn fixed_point_kernel(k: &[f64]) -> Vec<u32> {
    let n = k.len();
    let half = n / 2;
    let mut out = vec![0u32; n];
    let mut err = 0.0;
    let mut sum: i64 = 0;
    for i in 0..half {
        let adj = k[i] * 256.0 + err;
        let v = adj.round_ties_even() as i64;
        err = adj - v as f64;
        out[i] = v as u32;
        out[n - 1 - i] = v as u32;
        sum += v;
    }
    out[half] = (256 - 2 * sum) as u32;
    out
}

/// OpenCV's `borderInterpolate` for `BORDER_REFLECT_101`.
fn reflect101(mut p: isize, len: usize) -> usize {
    let len = len as isize;
    if len == 1 {
        return 0;
    }
    while p < 0 || p >= len {
        p = if p < 0 { -p } else { 2 * len - 2 - p };
    }
    p as usize
}

/// Blurs a gray view with a Gaussian of standard deviation `sigma` pixels (`0 < sigma <= 1024`).
/// Errors: non-finite or out-of-range sigma, non-gray input.
pub fn gaussian_blur(src: &ImageView<'_>, sigma: f64) -> Result<GrayImage> {
    ensure_finite("sigma", sigma)?;
    if !(sigma > 0.0 && sigma <= MAX_SIGMA) {
        return Err(Error::OutOfRange { name: "sigma", detail: format!("{sigma} is not in (0, {MAX_SIGMA}]") });
    }
    if src.channels() != 1 {
        return Err(Error::UnsupportedChannels(src.channels()));
    }
    let (w, h) = (src.width(), src.height());
    let n = gaussian_kernel_size(sigma);
    let kernel = fixed_point_kernel(&gaussian_kernel(n, sigma));
    let r = (n / 2) as isize;
    let (kx, kx_r) = if w == 1 { (vec![256u32], 0) } else { (kernel.clone(), r) };
    let (ky, ky_r) = if h == 1 { (vec![256u32], 0) } else { (kernel, r) };
    // Row pass: exact integer sums (8 fractional bits).
    let xmap: Vec<usize> = (-kx_r..w as isize + kx_r).map(|p| reflect101(p, w)).collect();
    let mut rows = vec![0u32; w * h];
    for y in 0..h {
        let src_row = src.row(y);
        let padded: Vec<u32> = xmap.iter().map(|&i| src_row[i] as u32).collect();
        let out = &mut rows[y * w..(y + 1) * w];
        for (i, &c) in kx.iter().enumerate() {
            for (o, &p) in out.iter_mut().zip(&padded[i..i + w]) {
                *o += c * p;
            }
        }
    }
    // Column pass: 16 fractional bits, rounded once.
    let mut data = vec![0u8; w * h];
    let mut acc = vec![0u32; w];
    for y in 0..h {
        acc.fill(0);
        for (i, &c) in ky.iter().enumerate() {
            let sy = reflect101(y as isize + i as isize - ky_r, h);
            for (a, &v) in acc.iter_mut().zip(&rows[sy * w..(sy + 1) * w]) {
                *a += c * v;
            }
        }
        for (d, &a) in data[y * w..(y + 1) * w].iter_mut().zip(&acc) {
            *d = ((a + (1 << 15)) >> 16).min(255) as u8;
        }
    }
    GrayImage::from_vec(w, h, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_size_follows_opencv_rule() {
        assert_eq!(gaussian_kernel_size(1.0), 7);
        assert_eq!(gaussian_kernel_size(0.5), 5);
        assert_eq!(gaussian_kernel_size(2.0), 13);
        assert_eq!(gaussian_kernel_size(0.1), 3);
    }

    #[test]
    fn fixed_point_kernel_sums_to_256_and_is_symmetric() {
        for sigma in [0.3, 0.8, 1.0, 1.7, 3.0, 9.0] {
            let k = fixed_point_kernel(&gaussian_kernel(gaussian_kernel_size(sigma), sigma));
            assert_eq!(k.iter().sum::<u32>(), 256, "sigma {sigma}");
            assert!(k.iter().eq(k.iter().rev()), "sigma {sigma}: {k:?}");
        }
    }

    #[test]
    fn reflect101_matches_opencv() {
        assert_eq!(reflect101(-1, 5), 1);
        assert_eq!(reflect101(5, 5), 3);
        assert_eq!(reflect101(-7, 3), 1);
        assert_eq!(reflect101(4, 1), 0);
    }

    #[test]
    fn constant_image_stays_constant_and_bad_sigma_is_rejected() {
        let img = GrayImage::filled(9, 4, 77).unwrap();
        let out = gaussian_blur(&img.view(), 1.3).unwrap();
        assert!(out.as_bytes().iter().all(|&v| v == 77));
        assert!(matches!(gaussian_blur(&img.view(), f64::NAN), Err(Error::NonFinite { .. })));
        assert!(matches!(gaussian_blur(&img.view(), 0.0), Err(Error::OutOfRange { .. })));
    }
}
