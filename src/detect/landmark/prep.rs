//! Input preprocessing for drawings: the landmark model was trained on photos, where a figure's
//! edges are soft tone changes; a line drawing's hard, dark strokes on white paper leave it
//! unsure that a person is there. Lightening the strokes of a crop that is mostly paper (a gamma
//! under 1 on every channel) raised the pose flag and the PCK on ink and pencil drawings without
//! changing photos or flat-colour pictures, which are not mostly paper (docs/benchmarks.md,
//! "Detector backends"). Darkening light pencil instead (levels stretch, gamma over 1) lowered
//! both.

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
    for v in tensor.iter_mut() {
        *v = v.max(0.0).powf(DRAWING_GAMMA);
    }
    true
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
}
