//! Input preprocessing for drawings: the landmark model was trained on photos, where a figure's
//! edges are soft tone changes; a line drawing's hard, dark strokes on white paper leave it
//! unsure that a person is there. Lightening the strokes of a crop that is mostly paper (a gamma
//! under 1 on every channel) raises the pose flag and the PCK on ink and pencil drawings without
//! changing photos or flat-colour pictures, which are not mostly paper
//! (docs/benchmarks-history.md, "BlazePose input lightening and ROI retries"). A line drawing the
//! network still does not read as a person (pose flag under 0.5 at every ROI) gets one more try
//! with its enclosed regions filled gray ([`fill_enclosed`]), so that it reads as a silhouette
//! with lines, like a flat-colour picture.

/// Gamma applied to a paper crop's values in [0, 1] (`v^γ`, so mid grays get lighter, white stays
/// white and black stays black). Chosen on PARSE training photos 1–100 through the benchmark's
/// stylisations (`examples/landmark_roi.rs`).
pub const DRAWING_GAMMA: f32 = 0.4;

/// A crop counts as a drawing on paper when its median gray (channel mean) is at least this.
pub const PAPER_MEDIAN: f32 = 0.9;

/// Whether the crop (HWC RGB in [0, 1]) is mostly paper: its median gray ≥ [`PAPER_MEDIAN`].
pub fn is_paper(tensor: &[f32]) -> bool {
    let mut hist = [0usize; 256];
    let n = tensor.len() / 3;
    for p in tensor.chunks_exact(3) {
        let g = (p[0] + p[1] + p[2]) / 3.0;
        hist[(g * 255.0).round().clamp(0.0, 255.0) as usize] += 1;
    }
    let cut = (PAPER_MEDIAN * 255.0).round() as usize;
    hist[cut..].iter().sum::<usize>() * 2 >= n
}

/// Lightens `tensor` in place by [`DRAWING_GAMMA`] when it is mostly paper ([`is_paper`]);
/// returns whether it did.
pub fn lighten_drawing(tensor: &mut [f32]) -> bool {
    if !is_paper(tensor) {
        return false;
    }
    // Paper (exactly 1, most of a drawing's crop) stays 1 under any gamma.
    for v in tensor.iter_mut().filter(|v| **v != 1.0) {
        *v = v.max(0.0).powf(DRAWING_GAMMA);
    }
    true
}

/// [`fill_enclosed`]: a crop value (after [`lighten_drawing`]) under this is ink.
pub const FILL_INK: f32 = 0.8;

/// [`fill_enclosed`]: the ink is dilated by this radius (crop px at 256²) to close gaps between
/// strokes before the outside is flooded.
pub const FILL_CLOSE_PX: usize = 3;

/// [`fill_enclosed`]: the gray the figure's inside is painted (channels are capped at it).
pub const FILL_TONE: f32 = 0.75;

/// Paints the enclosed paper of a crop that is mostly paper ([`is_paper`]) gray: values under
/// [`FILL_INK`] are ink; paper that cannot be reached from the crop's border without crossing
/// the ink dilated by [`FILL_CLOSE_PX`] is inside the figure and has every channel capped at
/// [`FILL_TONE`]; strokes and the outside stay. `tensor` is HWC RGB in [0, 1] of a square crop
/// (`side`² × 3 values). Returns whether it painted anything. The three constants were chosen
/// on PARSE training photos 1–100 through the benchmark's stylisations
/// (`examples/landmark_roi.rs`, variants `pgamma0.4+fillT/D/C`).
pub fn fill_enclosed(tensor: &mut [f32], side: usize) -> bool {
    fill_enclosed_with(tensor, side, FILL_INK, FILL_CLOSE_PX, FILL_TONE)
}

/// [`fill_enclosed`] with its three constants given: values under `ink_below` are ink, the ink
/// dilated by `close_px` closes gaps, the inside is capped at `tone` (for tuning benches).
pub fn fill_enclosed_with(tensor: &mut [f32], side: usize, ink_below: f32, close_px: usize, tone: f32) -> bool {
    let n = side * side;
    if tensor.len() != 3 * n || n == 0 || !is_paper(tensor) {
        return false;
    }
    let ink: Vec<bool> = tensor.chunks_exact(3).map(|p| (p[0] + p[1] + p[2]) / 3.0 < ink_below).collect();
    let wall = dilate(&ink, side, close_px);
    let mut outside = vec![false; n];
    let mut stack: Vec<usize> = (0..side)
        .flat_map(|i| [i, (side - 1) * side + i, i * side, i * side + side - 1])
        .filter(|&k| !wall[k])
        .collect();
    while let Some(k) = stack.pop() {
        if outside[k] || wall[k] {
            continue;
        }
        outside[k] = true;
        stack.extend(neighbours(k, side));
    }
    // The flood stops `close_px` short of the strokes; grow it back over paper.
    for _ in 0..close_px {
        let before = outside.clone();
        for k in 0..n {
            if !before[k] && !ink[k] && neighbours(k, side).any(|j| before[j]) {
                outside[k] = true;
            }
        }
    }
    let mut painted = false;
    for (k, p) in tensor.chunks_exact_mut(3).enumerate() {
        if !outside[k] && !ink[k] {
            p.iter_mut().for_each(|c| *c = c.min(tone));
            painted = true;
        }
    }
    painted
}

/// The 4-neighbours of pixel `k` in a `side`-wide square grid.
fn neighbours(k: usize, side: usize) -> impl Iterator<Item = usize> {
    let (x, y) = (k % side, k / side);
    [(x > 0).then(|| k - 1), (x + 1 < side).then(|| k + 1), (y > 0).then(|| k - side), (y + 1 < side).then(|| k + side)]
        .into_iter()
        .flatten()
}

/// `mask` dilated by a disc of radius `r` px.
fn dilate(mask: &[bool], side: usize, r: usize) -> Vec<bool> {
    let r = r as isize;
    let offsets: Vec<(isize, isize)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(|(dx, dy)| dx * dx + dy * dy <= r * r)
        .collect();
    let s = side as isize;
    let mut out = vec![false; mask.len()];
    for (k, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
        let (x, y) = ((k % side) as isize, (k / side) as isize);
        for &(dx, dy) in &offsets {
            let (a, b) = (x + dx, y + dy);
            if a >= 0 && b >= 0 && a < s && b < s {
                out[(b * s + a) as usize] = true;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_crops_are_lightened_and_photos_kept() {
        // 70 % paper, 30 % pencil gray 0.4: lightened to 0.4^0.4, paper and black unchanged.
        let mut t: Vec<f32> = (0..100)
            .flat_map(|i| {
                [if i < 70 {
                    1.0
                } else if i < 99 {
                    0.4
                } else {
                    0.0
                }; 3]
            })
            .collect();
        assert!(lighten_drawing(&mut t));
        assert_eq!(t[0], 1.0);
        assert!((t[3 * 80] - 0.4f32.powf(DRAWING_GAMMA)).abs() < 1e-6 && t[3 * 80] > 0.69);
        assert_eq!(t[3 * 99], 0.0);
        // A photo-like crop (median 0.5) is left as it is.
        let mut photo: Vec<f32> = (0..100).flat_map(|i| [i as f32 / 99.0; 3]).collect();
        let before = photo.clone();
        assert!(!lighten_drawing(&mut photo));
        assert_eq!(photo, before);
    }

    /// A ring drawn on paper with a 2-px gap: its inside is painted, the outside and the
    /// strokes are not; a crop that is not mostly paper is left alone.
    #[test]
    fn the_inside_of_a_gapped_outline_is_filled() {
        let side = 64;
        let mut t = vec![1.0f32; side * side * 3];
        for y in 0..side {
            for x in 0..side {
                let d = ((x as f64 - 32.0).powi(2) + (y as f64 - 32.0).powi(2)).sqrt();
                if (15.0..17.0).contains(&d) && !(x > 46 && (31..33).contains(&y)) {
                    t[(y * side + x) * 3..][..3].fill(0.1);
                }
            }
        }
        assert!(fill_enclosed(&mut t, side));
        let at = |x: usize, y: usize| t[(y * side + x) * 3];
        assert_eq!(at(32, 32), FILL_TONE);
        assert_eq!(at(20, 32), FILL_TONE);
        assert_eq!(at(2, 2), 1.0);
        assert_eq!(at(60, 32), 1.0);
        assert_eq!(at(32, 16), 0.1);
        let mut photo: Vec<f32> = (0..side * side).flat_map(|i| [(i % 7) as f32 / 7.0; 3]).collect();
        let before = photo.clone();
        assert!(!fill_enclosed(&mut photo, side));
        assert_eq!(photo, before);
    }
}
