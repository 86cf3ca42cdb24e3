//! Ink-box normalisation: a drawing scanned or exported at a large size is cropped to a square
//! around its ink and downscaled so that the figure fills the working image about as the
//! training sketches fill theirs (≈ 0.8 of a 512² canvas). Without it a 4000×3000 page reaches
//! the detector at 1024 px, where the strokes and the figure's size in cells differ from what
//! the model learned, and limbs can come out crossed.

use super::hog::Planes;
use super::pyramid;
use crate::image::ImageView;

/// Fraction of the square crop's side the ink box's longer side fills.
pub const FIGURE_FILL: f64 = 0.8;
/// A pixel is ink when its gray level is this far below the paper's (0..=255 levels).
pub const INK_CONTRAST: f64 = 60.0;
/// Fraction of the ink pixels ignored at each end of the box in x and in y, so a speck or a
/// signature in a corner does not stretch it.
pub const INK_TRIM: f64 = 0.002;

/// Ink bounding box of `image` as `[x0, y0, x1, y1]` (pixels, inclusive), or `None` for a page
/// without ink. The paper's level is the 90th percentile of the gray levels; ink is darker by
/// [`INK_CONTRAST`]; [`INK_TRIM`] of the ink is trimmed at each end of each axis.
pub fn ink_box(image: &ImageView<'_>) -> Option<[usize; 4]> {
    let (w, h, ch) = (image.width(), image.height(), image.channels());
    let gray = |row: &[u8], x: usize| -> u8 {
        if ch >= 3 {
            ((row[x * ch] as u32 + row[x * ch + 1] as u32 + row[x * ch + 2] as u32) / 3) as u8
        } else {
            row[x * ch]
        }
    };
    let mut hist = [0usize; 256];
    for y in 0..h {
        let row = image.row(y);
        for x in 0..w {
            hist[gray(row, x) as usize] += 1;
        }
    }
    let paper = percentile_level(&hist, 0.9 * (w * h) as f64) as f64;
    let cut = paper - INK_CONTRAST;
    if cut <= 0.0 {
        return None;
    }
    let (mut cols, mut rows) = (vec![0usize; w], vec![0usize; h]);
    let mut total = 0;
    for (y, r) in rows.iter_mut().enumerate() {
        let row = image.row(y);
        for (x, c) in cols.iter_mut().enumerate() {
            if (gray(row, x) as f64) < cut {
                *c += 1;
                *r += 1;
                total += 1;
            }
        }
    }
    if total == 0 {
        return None;
    }
    let trim = (INK_TRIM * total as f64).floor() as usize;
    let (x0, x1) = trimmed_span(&cols, trim);
    let (y0, y1) = trimmed_span(&rows, trim);
    Some([x0, y0, x1, y1])
}

/// The gray level at which the cumulative histogram first reaches `count`.
fn percentile_level(hist: &[usize; 256], count: f64) -> usize {
    let mut acc = 0usize;
    for (level, &n) in hist.iter().enumerate() {
        acc += n;
        if acc as f64 >= count {
            return level;
        }
    }
    255
}

/// First and last index of `counts` after skipping `trim` counted items at each end.
fn trimmed_span(counts: &[usize], trim: usize) -> (usize, usize) {
    let first = |it: &mut dyn Iterator<Item = (usize, &usize)>| {
        let mut acc = 0;
        for (i, &n) in it {
            acc += n;
            if acc > trim {
                return i;
            }
        }
        0
    };
    let lo = first(&mut counts.iter().enumerate());
    let hi = first(&mut counts.iter().enumerate().rev());
    (lo, hi.max(lo))
}

/// The working image of a normalised detection: planes, input pixels per working pixel, and the
/// input position of working pixel (0, 0).
pub struct Normalised {
    /// The cropped, downscaled image.
    pub planes: Planes,
    /// Input pixels per working pixel (> 1).
    pub scale: f64,
    /// Input coordinates (x, y) of the working image's top-left corner (may be negative: the
    /// crop is padded with white paper beyond the page).
    pub offset: [f64; 2],
}

/// The square crop around `image`'s ink box (its longer side at [`FIGURE_FILL`] of the crop,
/// padded with white beyond the page), downscaled to `target`² — or `None` when there is no ink
/// or the crop is not larger than `target` (the image is then searched as it is: upscaling adds
/// nothing the detector can use).
pub fn normalise(image: &ImageView<'_>, target: usize) -> Option<Normalised> {
    let [x0, y0, x1, y1] = ink_box(image)?;
    let long = ((x1 - x0 + 1).max(y1 - y0 + 1)) as f64;
    let side = (long / FIGURE_FILL).ceil() as usize;
    if side <= target {
        return None;
    }
    let (cx, cy) = ((x0 + x1 + 1) as f64 / 2.0, (y0 + y1 + 1) as f64 / 2.0);
    let (ox, oy) = ((cx - side as f64 / 2.0).round() as i64, (cy - side as f64 / 2.0).round() as i64);
    let full = pyramid::planes_from_view(image);
    let (w, h) = (full.width as i64, full.height as i64);
    let mut data = vec![255f32; full.channels * side * side];
    for c in 0..full.channels {
        let src = full.plane(c);
        let dst = &mut data[c * side * side..(c + 1) * side * side];
        for j in 0..side as i64 {
            let y = oy + j;
            if y < 0 || y >= h {
                continue;
            }
            let (xa, xb) = ((-ox).clamp(0, side as i64), (w - ox).clamp(0, side as i64));
            if xa >= xb {
                continue;
            }
            let s = (y * w + ox + xa) as usize;
            let d = (j * side as i64 + xa) as usize;
            let n = (xb - xa) as usize;
            dst[d..d + n].copy_from_slice(&src[s..s + n]);
        }
    }
    let crop = Planes { width: side, height: side, channels: full.channels, data };
    let planes = pyramid::resize(&crop, target as f64 / side as f64);
    let scale = side as f64 / planes.width as f64;
    Some(Normalised { planes, scale, offset: [ox as f64, oy as f64] })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::GrayImage;

    fn page(w: usize, h: usize, ink: &[[usize; 4]]) -> GrayImage {
        let mut d = vec![250u8; w * h];
        for &[x0, y0, x1, y1] in ink {
            // A 2-px outline, as a line drawing is (a solid block would lose its first and last
            // rows to the trim).
            for y in y0..=y1 {
                for x in x0..=x1 {
                    if x < x0 + 2 || x + 2 > x1 || y < y0 + 2 || y + 2 > y1 {
                        d[y * w + x] = 20;
                    }
                }
            }
        }
        GrayImage::from_vec(w, h, d).unwrap()
    }

    #[test]
    fn the_ink_box_ignores_paper_and_specks() {
        let mut img = page(400, 300, &[[100, 50, 180, 250]]);
        assert_eq!(ink_box(&img.view()), Some([100, 50, 180, 250]));
        // One dark speck far away (< INK_TRIM of the ink) does not move the box.
        img = page(400, 300, &[[100, 50, 180, 250], [390, 5, 390, 5]]);
        assert_eq!(ink_box(&img.view()), Some([100, 50, 180, 250]));
        assert_eq!(ink_box(&page(64, 64, &[]).view()), None);
    }

    #[test]
    fn a_large_page_is_cropped_around_the_ink_and_downscaled() {
        // A 2000×1500 page with ink 800 px tall: crop side 1000, working 512², 1000/512 input px
        // per working px, the crop centred on the ink.
        let img = page(2000, 1500, &[[900, 300, 1100, 1099]]);
        let n = normalise(&img.view(), 512).unwrap();
        assert_eq!((n.planes.width, n.planes.height), (512, 512));
        assert!((n.scale - 1000.0 / 512.0).abs() < 1e-9);
        assert_eq!(n.offset, [501.0, 200.0]); // the box centre is x 1000.5
                                              // The ink's top edge (y 300 → (300 − 200) · 512/1000 = 51) is dark; its inside and the margin white.
        let at = |x: usize, y: usize| n.planes.plane(0)[y * 512 + x];
        assert!(at(256, 51) < 128.0 && at(256, 256) > 240.0 && at(10, 256) > 240.0);
        // Ink near the page's edge: the crop reaches past it and is padded white.
        let img = page(2000, 1500, &[[0, 600, 100, 1499]]);
        let n = normalise(&img.view(), 512).unwrap();
        assert!(n.offset[0] < 0.0 && n.planes.plane(0)[0] > 240.0);
        // A figure already small enough is left to the plain search.
        assert!(normalise(&page(512, 512, &[[150, 100, 350, 450]]).view(), 512).is_none());
    }
}
