//! The HOG feature pyramid as Yang & Ramanan's `featpyramid.m` builds it: `interval` levels per
//! octave (scale step 2^(−1/interval)); the first octave uses cells of sbin/2 pixels (the same as
//! upsampling the image ×2), the second cells of sbin on the same resized images, and further
//! octaves halve the image repeatedly. Every map is padded by (pad + 1) cells of zeros whose
//! truncation feature is 1. Resizing is the area-averaging of the DPM code's `resize.cc`.

use rayon::prelude::*;

#[cfg(test)]
use super::hog::hog;
use super::hog::{gradients, hog_from_gradients, FeatureMap, Planes};
use super::model::FEAT_DIM;
use crate::error::{Error, Result};

/// Most bytes the HOG features of a pyramid's kept levels may take together (1 GiB; the sketch
/// default on a 1024 px image needs a few MB, every level of the PARSE model's about 200 MB).
/// A search beyond it (many levels per octave over every scale, a model of huge filters, whose
/// padding grows every level) is refused before any level is built.
pub const MAX_PYRAMID_BYTES: u64 = 1 << 30;
use crate::image::ImageView;

/// One pyramid level.
#[derive(Clone, Debug)]
pub struct Level {
    /// The padded feature map.
    pub feat: FeatureMap,
    /// Size of one cell in input-image pixels.
    pub cell_px: f64,
}

/// A feature pyramid with its padding (cells added on each side beyond the 1-cell border).
#[derive(Clone, Debug)]
pub struct Pyramid {
    /// Levels, finest first.
    pub levels: Vec<Level>,
    /// Padding in cells along x (the map has `padx + 1` padding cells left and right).
    pub padx: usize,
    /// Padding in cells along y.
    pub pady: usize,
}

/// Converts an 8-bit view (1, 3 or 4 channels; alpha ignored) to planes with values 0..=255.
/// A colour image whose three channels are equal everywhere (a gray sketch stored as RGB) gives
/// one plane: the HOG takes the channel of largest gradient, so one copy gives the same features
/// at a third of the gradient and resizing work.
pub fn planes_from_view(img: &ImageView<'_>) -> Planes {
    let (w, h, ch) = (img.width(), img.height(), img.channels());
    let gray = ch == 1 || (0..h).all(|y| img.row(y)[..w * ch].chunks_exact(ch).all(|p| p[0] == p[1] && p[1] == p[2]));
    let channels = if gray { 1 } else { 3 };
    let mut data = vec![0f32; channels * w * h];
    for y in 0..h {
        let row = img.row(y);
        for x in 0..w {
            for c in 0..channels {
                data[c * w * h + y * w + x] = row[x * ch + c] as f32;
            }
        }
    }
    Planes { width: w, height: h, channels, data }
}

/// Area-averaging 1-D weights of `resize.cc`: for each destination index, (source index, weight).
fn resize_weights(src_len: usize, dst_len: usize) -> Vec<Vec<(usize, f32)>> {
    let scale = dst_len as f64 / src_len as f64;
    let inv = src_len as f64 / dst_len as f64;
    (0..dst_len)
        .map(|d| {
            let f1 = d as f64 * inv;
            let f2 = f1 + inv;
            let s1 = f1.ceil() as usize;
            let s2 = f2.floor() as usize;
            let mut v = Vec::new();
            if s1 as f64 - f1 > 1e-3 && s1 >= 1 {
                v.push((s1 - 1, ((s1 as f64 - f1) * scale) as f32));
            }
            for s in s1..s2.min(src_len) {
                v.push((s, scale as f32));
            }
            if f2 - s2 as f64 > 1e-3 && s2 < src_len {
                v.push((s2, ((f2 - s2 as f64) * scale) as f32));
            }
            v
        })
        .collect()
}

/// Downscales `im` by `factor` (≤ 1) to round(size × factor) pixels by area averaging.
pub fn resize(im: &Planes, factor: f64) -> Planes {
    let dw = ((im.width as f64 * factor).round() as usize).max(1);
    let dh = ((im.height as f64 * factor).round() as usize).max(1);
    if dw == im.width && dh == im.height {
        return im.clone();
    }
    let wx = resize_weights(im.width, dw);
    let wy = resize_weights(im.height, dh);
    let mut data = vec![0f32; im.channels * dw * dh];
    let mut tmp = vec![0f32; dw * im.height];
    for c in 0..im.channels {
        let src = im.plane(c);
        for y in 0..im.height {
            let row = &src[y * im.width..(y + 1) * im.width];
            for (dx, ws) in wx.iter().enumerate() {
                tmp[y * dw + dx] = ws.iter().map(|&(s, a)| a * row[s]).sum();
            }
        }
        let dst = &mut data[c * dw * dh..(c + 1) * dw * dh];
        for (dy, ws) in wy.iter().enumerate() {
            let out = &mut dst[dy * dw..(dy + 1) * dw];
            for &(s, a) in ws {
                let r = &tmp[s * dw..(s + 1) * dw];
                for (o, v) in out.iter_mut().zip(r) {
                    *o += a * v;
                }
            }
        }
    }
    Planes { width: dw, height: dh, channels: im.channels, data }
}

/// Pads a map by `padx + 1` / `pady + 1` cells of zeros with the truncation feature set to 1.
pub fn pad(f: &FeatureMap, padx: usize, pady: usize) -> FeatureMap {
    let (px, py) = (padx + 1, pady + 1);
    let (rows, cols) = (f.rows + 2 * py, f.cols + 2 * px);
    let mut data = vec![0f32; rows * cols * FEAT_DIM];
    for y in 0..rows {
        for x in 0..cols {
            let d = &mut data[(y * cols + x) * FEAT_DIM..][..FEAT_DIM];
            if y >= py && y < py + f.rows && x >= px && x < px + f.cols {
                d.copy_from_slice(f.cell(x - px, y - py));
            } else {
                d[FEAT_DIM - 1] = 1.0;
            }
        }
    }
    FeatureMap { rows, cols, data }
}

/// Builds the pyramid of `im` for cells of `sbin` pixels, `interval` levels per octave and the
/// given padding. The number of levels is `interval + max_scale` with
/// max_scale = 1 + ⌊log(min side / (5 sbin)) / log 2^(1/interval)⌋ (at least 1).
/// Only levels with cells of `min_cell_px` to `max_cell_px` pixels (inclusive) are computed and
/// returned: the others' HOG is never built (the image is still halved through skipped levels
/// when a coarser kept level needs it). Errors: [`Error::OutOfRange`] when the kept levels'
/// features would exceed [`MAX_PYRAMID_BYTES`].
pub fn build(
    im: &Planes,
    sbin: usize,
    interval: usize,
    padx: usize,
    pady: usize,
    min_cell_px: f64,
    max_cell_px: f64,
) -> Result<Pyramid> {
    let sc = 2f64.powf(1.0 / interval as f64);
    let min_side = im.width.min(im.height) as f64;
    let max_scale = (1.0 + ((min_side / (5.0 * sbin as f64)).ln() / sc.ln()).floor()).max(1.0) as usize;
    // Jobs: (level index, image scale factor, cell size) — the halvings chain from the octave base.
    struct Job {
        base: usize,
        halvings: usize,
        sbin: usize,
        level: usize,
        cell_px: f64,
    }
    let mut jobs = Vec::new();
    for i in 0..interval {
        let s = sc.powi(i as i32);
        jobs.push(Job { base: i, halvings: 0, sbin: sbin / 2, level: i, cell_px: sbin as f64 * s / 2.0 });
        jobs.push(Job { base: i, halvings: 0, sbin, level: i + interval, cell_px: sbin as f64 * s });
        // featpyramid.m: for j = i+interval : interval : max_scale (1-based), level j+interval.
        let mut j1 = i + 1 + interval;
        let mut h = 0;
        while j1 <= max_scale {
            h += 1;
            jobs.push(Job {
                base: i,
                halvings: h,
                sbin,
                level: j1 + interval - 1,
                cell_px: sbin as f64 * s * 2f64.powi(h as i32),
            });
            j1 += interval;
        }
    }
    let kept = |j: &Job| j.cell_px >= min_cell_px && j.cell_px <= max_cell_px;
    // Each kept level's padded map, from the cell size (to within a cell of the real map).
    let bytes: f64 = jobs
        .iter()
        .filter(|j| kept(j))
        .map(|j| {
            let cells = |side: usize, pad: usize| side as f64 / j.cell_px + 2.0 * (pad + 1) as f64 + 1.0;
            cells(im.width, padx) * cells(im.height, pady) * (FEAT_DIM * 4) as f64
        })
        .sum();
    if bytes > MAX_PYRAMID_BYTES as f64 {
        return Err(Error::OutOfRange {
            name: "detector search",
            detail: format!(
                "its feature pyramid would take {:.0} MB (at most {} MB): search fewer scales or levels per octave",
                bytes / 1e6,
                MAX_PYRAMID_BYTES / 1_000_000
            ),
        });
    }
    let n_levels = jobs.iter().map(|j| j.level + 1).max().unwrap_or(0);
    // Resize once per octave base, then halve; run bases in parallel.
    let per_base: Vec<Vec<(usize, Level)>> = (0..interval)
        .into_par_iter()
        .map(|i| {
            let mine: Vec<&Job> = jobs.iter().filter(|j| j.base == i && kept(j)).collect();
            let mut out = Vec::new();
            if mine.is_empty() {
                return out;
            }
            let max_h = mine.iter().map(|j| j.halvings).max().unwrap_or(0);
            let mut scaled = resize(im, 1.0 / sc.powi(i as i32));
            for h in 0..=max_h {
                if h > 0 {
                    scaled = resize(&scaled, 0.5);
                }
                let here: Vec<&&Job> = mine.iter().filter(|j| j.halvings == h).collect();
                if here.is_empty() {
                    continue;
                }
                // Both cell sizes of one image share its gradients.
                let g = gradients(&scaled);
                for j in here {
                    let f = hog_from_gradients(&g, j.sbin);
                    out.push((j.level, Level { feat: pad(&f, padx, pady), cell_px: j.cell_px }));
                }
            }
            out
        })
        .collect();
    let mut slots: Vec<Option<Level>> = (0..n_levels).map(|_| None).collect();
    for (l, lev) in per_base.into_iter().flatten() {
        slots[l] = Some(lev);
    }
    Ok(Pyramid { levels: slots.into_iter().flatten().collect(), padx, pady })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_resize_preserves_mean_and_halves_exactly() {
        let im = Planes { width: 6, height: 4, channels: 1, data: (0..24).map(|v| v as f32).collect() };
        let r = resize(&im, 0.5);
        assert_eq!((r.width, r.height), (3, 2));
        // Each output is the mean of a 2x2 block.
        assert!((r.data[0] - (0.0 + 1.0 + 6.0 + 7.0) / 4.0).abs() < 1e-5);
        let r = resize(&im, 1.0 / 1.5);
        let mean = |p: &Planes| p.data.iter().sum::<f32>() / p.data.len() as f32;
        assert!((mean(&r) - mean(&im)).abs() < 1e-3, "{} vs {}", mean(&r), mean(&im));
    }

    #[test]
    fn gray_colour_images_give_one_plane_with_the_same_features() {
        let (w, h) = (40, 36);
        let gray: Vec<u8> = (0..w * h).map(|i| ((i * 37) % 251) as u8).collect();
        let rgb: Vec<u8> = gray.iter().flat_map(|&v| [v, v, v]).collect();
        let g = planes_from_view(&ImageView::gray(&gray, w, h).unwrap());
        let c = planes_from_view(&ImageView::new(&rgb, w, h, 3, 3 * w).unwrap());
        assert_eq!((g.channels, c.channels), (1, 1));
        assert_eq!(g, c);
        // Three planes kept, identical HOG: the gray plane is the largest gradient everywhere.
        let three =
            Planes { channels: 3, data: [g.data.clone(), g.data.clone(), g.data.clone()].concat(), ..g.clone() };
        assert_eq!(hog(&three, 4), hog(&g, 4));
        let mut tinted = rgb.clone();
        tinted[3 * 17 + 2] ^= 1;
        assert_eq!(planes_from_view(&ImageView::new(&tinted, w, h, 3, 3 * w).unwrap()).channels, 3);
    }

    #[test]
    fn levels_scales_and_padding() {
        let im = Planes { width: 200, height: 150, channels: 1, data: vec![10.0; 200 * 150] };
        let p = build(&im, 4, 10, 3, 3, 0.0, f64::INFINITY).unwrap();
        // max_scale = 1 + floor(log(150/20)/log(2^0.1)) = 1 + 29 = 30 -> 40 levels.
        assert_eq!(p.levels.len(), 40);
        assert!((p.levels[0].cell_px - 2.0).abs() < 1e-12);
        assert!((p.levels[10].cell_px - 4.0).abs() < 1e-12);
        assert!((p.levels[20].cell_px - 8.0).abs() < 1e-12);
        assert!(p.levels.windows(2).all(|w| w[1].cell_px > w[0].cell_px));
        let f = &p.levels[10].feat;
        // round(150/4) = 38 cells - 2 + 2*4 padding = 44 rows; 200/4 = 50 - 2 + 8 = 56 cols.
        assert_eq!((f.rows, f.cols), (44, 56));
        assert_eq!(f.cell(0, 0)[31], 1.0);
        assert_eq!(f.cell(3, 20)[31], 1.0);
        assert_eq!(f.cell(4, 20)[31], 0.0);
        assert_eq!(f.cell(51, 20)[31], 0.0);
        assert_eq!(f.cell(52, 20)[31], 1.0);
        let skipped = build(&im, 4, 10, 3, 3, 3.9, f64::INFINITY).unwrap();
        assert_eq!(skipped.levels.len(), 30);
        // Coarse levels are skipped too; the kept ones are the same maps as in the full pyramid.
        let band = build(&im, 4, 10, 3, 3, 3.9, 8.0).unwrap();
        assert_eq!(band.levels.len(), 11);
        assert!((band.levels[0].cell_px - 4.0).abs() < 1e-12 && (band.levels[10].cell_px - 8.0).abs() < 1e-12);
        assert_eq!(band.levels[10].feat.data, p.levels[20].feat.data);
        // Five levels per octave are every other level of ten.
        let five = build(&im, 4, 5, 3, 3, 0.0, f64::INFINITY).unwrap();
        assert!(five.levels.len() >= 19, "{}", five.levels.len());
        for (k, l) in five.levels.iter().enumerate() {
            assert!((l.cell_px - p.levels[2 * k].cell_px).abs() < 1e-9, "level {k}");
            assert_eq!(l.feat.data, p.levels[2 * k].feat.data, "level {k}");
        }
    }

    /// Issue 52 finding 10: a search whose features would exceed [`MAX_PYRAMID_BYTES`] (100
    /// levels per octave over every scale of a 1024 px image with a huge filter's padding) is
    /// refused before any level is built; the same image with the sketch model's settings is not.
    #[test]
    fn a_pyramid_beyond_the_memory_bound_is_refused_before_it_is_built() {
        let im = Planes { width: 1024, height: 1024, channels: 1, data: vec![10.0; 1024 * 1024] };
        let e = build(&im, 8, 100, 62, 62, 0.0, f64::INFINITY).unwrap_err();
        assert!(matches!(&e, Error::OutOfRange { name: "detector search", .. }), "{e}");
        let p = build(&im, 8, 7, 3, 3, 16.0, f64::INFINITY).unwrap();
        let bytes: usize = p.levels.iter().map(|l| l.feat.data.len() * 4).sum();
        assert!(bytes > 0 && (bytes as u64) < MAX_PYRAMID_BYTES);
    }
}
