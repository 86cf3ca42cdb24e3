//! The model's input tensor: the ROI resampled to 256×256 RGB in [0, 1] by bilinear
//! interpolation, white outside the image (MediaPipe's `ImageToTensorCalculator` with the
//! corners of the ROI mapped to the tensor's corners: tensor pixel `(u, v)` samples the ROI at
//! normalised `(u / 256, v / 256)`).

use super::roi::Roi;
use crate::image::{over_white, ImageView};

/// Side of the landmark model's square input, px.
pub const INPUT_SIDE: usize = 256;

/// RGB of a gray, RGB or RGBA pixel (RGBA composited over white).
pub(crate) fn rgb_of(p: &[u8]) -> [u8; 3] {
    match p.len() {
        1 => [p[0]; 3],
        3 => [p[0], p[1], p[2]],
        _ => over_white([p[0], p[1], p[2], p[3]]),
    }
}

/// The 256×256×3 crop of `image` inside `roi`, row-major HWC, values in [0, 1]. Points outside the
/// image read as white, so ROIs partly outside the image are padded.
pub fn crop_tensor(image: &ImageView<'_>, roi: &Roi) -> Vec<f32> {
    let (w, h, ch) = (image.width() as i64, image.height() as i64, image.channels());
    let pixel = |x: i64, y: i64| -> [f32; 3] {
        if x < 0 || y < 0 || x >= w || y >= h {
            return [1.0; 3];
        }
        let row = image.row(y as usize);
        rgb_of(&row[x as usize * ch..(x as usize + 1) * ch]).map(|c| c as f32 / 255.0)
    };
    let n = INPUT_SIDE as f64;
    let mut out = Vec::with_capacity(INPUT_SIDE * INPUT_SIDE * 3);
    for v in 0..INPUT_SIDE {
        for u in 0..INPUT_SIDE {
            let [x, y] = roi.to_image(u as f64 / n, v as f64 / n);
            // Continuous coordinates to pixel-centre coordinates for the interpolation.
            let (x, y) = (x - 0.5, y - 0.5);
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let (a, b, c, d) = (pixel(x0, y0), pixel(x0 + 1, y0), pixel(x0, y0 + 1), pixel(x0 + 1, y0 + 1));
            for k in 0..3 {
                let top = a[k] + (b[k] - a[k]) * fx;
                let bottom = c[k] + (d[k] - c[k]) * fx;
                out.push(top + (bottom - top) * fy);
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
        // where bilinear interpolation of a linear image is exact.
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
}
