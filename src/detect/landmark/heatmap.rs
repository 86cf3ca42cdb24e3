//! MediaPipe's landmark refinement from the network's heatmap (`RefineLandmarksFromHeatmap` in
//! MediaPipe's pose graph, `tensors_to_pose_landmarks_and_segmentation.pbtxt`, kernel 7 and the
//! calculator's default confidence 0.5): each landmark's x and y become the sigmoid-weighted
//! mean of the heatmap cells in a 7 × 7 window around it, when the window's highest
//! confidence reaches 0.5. Depth, visibility and presence are left as the regression head gave
//! them.

use super::crop::INPUT_SIDE;
use super::model::{HEATMAP_SIDE, LANDMARK_VALUES, NUM_OUTPUT_LANDMARKS};
use crate::error::{Error, Result};

/// Window side in heatmap cells (MediaPipe's pose graph: 7).
pub const KERNEL_SIZE: usize = 7;

/// A landmark moves only when the window's highest cell confidence (sigmoid of its logit)
/// reaches this (the calculator's default, which the pose graph keeps).
pub const MIN_CONFIDENCE_TO_REFINE: f32 = 0.5;

fn sigmoid(v: f32) -> f32 {
    1.0 / (1.0 + (-v).exp())
}

/// Refines `landmarks` (x, y in px of the 256² crop, as [`super::model::RawOutput`] holds them;
/// the first `landmarks.len()` of the network's, landmark k read from heatmap channel k) in
/// place from `heatmap` ([`HEATMAP_SIDE`]² × [`NUM_OUTPUT_LANDMARKS`] logits, HWC). Follows
/// MediaPipe's calculator to the cell: the window is centred on the cell the landmark's
/// normalised position truncates to, cut at the heatmap's border, and the refined position is
/// the weighted mean of the cells' indices over the side (so a cell's index, not its centre,
/// is its position); landmarks whose column falls outside the heatmap, or whose row is above
/// it, keep their position (as there, a row below it is not checked: its window is the border's
/// rows when they are within reach). Errors: `OutOfRange` for more landmarks than channels or a
/// heatmap of another length.
pub fn refine(landmarks: &mut [[f32; LANDMARK_VALUES]], heatmap: &[f32]) -> Result<()> {
    let (side, channels) = (HEATMAP_SIDE, NUM_OUTPUT_LANDMARKS);
    if landmarks.len() > channels || heatmap.len() != side * side * channels {
        return Err(Error::OutOfRange {
            name: "heatmap refinement",
            detail: format!("{} landmarks and {} heatmap values", landmarks.len(), heatmap.len()),
        });
    }
    let crop = INPUT_SIDE as f32;
    let offset = (KERNEL_SIZE as i64 - 1) / 2;
    for (k, l) in landmarks.iter_mut().enumerate() {
        // Truncation toward zero, as C++'s float-to-int conversion (a landmark just left of
        // the crop lands in column 0).
        let col = (l[0] / crop * side as f32) as i64;
        let row = (l[1] / crop * side as f32) as i64;
        if col < 0 || col >= side as i64 || row < 0 {
            continue;
        }
        let (c0, c1) = ((col - offset).max(0), (col + offset + 1).min(side as i64));
        let (r0, r1) = ((row - offset).max(0), (row + offset + 1).min(side as i64));
        let (mut sum, mut wc, mut wr, mut max) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for r in r0..r1 {
            for c in c0..c1 {
                let conf = sigmoid(heatmap[(r as usize * side + c as usize) * channels + k]);
                sum += conf;
                max = max.max(conf);
                wc += c as f32 * conf;
                wr += r as f32 * conf;
            }
        }
        if max >= MIN_CONFIDENCE_TO_REFINE && sum > 0.0 {
            l[0] = wc / side as f32 / sum * crop;
            l[1] = wr / side as f32 / sum * crop;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heatmap_with(peaks: &[(usize, usize, usize, f32)]) -> Vec<f32> {
        let mut h = vec![-20.0; HEATMAP_SIDE * HEATMAP_SIDE * NUM_OUTPUT_LANDMARKS];
        for &(k, r, c, logit) in peaks {
            h[(r * HEATMAP_SIDE + c) * NUM_OUTPUT_LANDMARKS + k] = logit;
        }
        h
    }

    #[test]
    fn a_confident_peak_pulls_the_landmark_to_its_cell() {
        // Landmark 3 at crop px (41, 83) → cell (row 20, col 10); a confident peak at (22, 12).
        let mut lm = vec![[0.0f32; LANDMARK_VALUES]; NUM_OUTPUT_LANDMARKS];
        lm[3] = [41.0, 83.0, 7.0, 1.0, 2.0];
        lm[5] = [41.0, 83.0, 7.0, 1.0, 2.0];
        let h = heatmap_with(&[(3, 22, 12, 5.0), (5, 22, 12, -1.0)]);
        refine(&mut lm, &h).unwrap();
        // Every other cell has confidence ≈ 2e-9: the mean is the peak's indices over 64.
        assert!((lm[3][0] - 12.0 * 4.0).abs() < 1e-3 && (lm[3][1] - 22.0 * 4.0).abs() < 1e-3, "{:?}", lm[3]);
        assert_eq!(&lm[3][2..], &[7.0, 1.0, 2.0], "depth, visibility and presence untouched");
        // Landmark 5's window peaks at σ(−1) ≈ 0.27 < 0.5: unchanged.
        assert_eq!(lm[5], [41.0, 83.0, 7.0, 1.0, 2.0]);
    }

    /// A window whose highest confidence is exactly [`MIN_CONFIDENCE_TO_REFINE`] (logit 0)
    /// refines the landmark ("reaches"), one just under it does not.
    #[test]
    fn a_window_reaching_the_threshold_exactly_refines() {
        let mut lm = vec![[41.0f32, 83.0, 0.0, 0.0, 0.0]; 2];
        let h = heatmap_with(&[(0, 22, 12, 0.0), (1, 22, 12, -0.01)]);
        refine(&mut lm, &h).unwrap();
        assert!((lm[0][0] - 12.0 * 4.0).abs() < 1e-3 && (lm[0][1] - 22.0 * 4.0).abs() < 1e-3, "{:?}", lm[0]);
        assert_eq!(lm[1], [41.0, 83.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn peaks_outside_the_window_and_landmarks_outside_the_heatmap_are_ignored() {
        let mut lm = vec![[128.0f32, 128.0, 0.0, 0.0, 0.0]; NUM_OUTPUT_LANDMARKS];
        lm[0] = [-10.0, 128.0, 0.0, 0.0, 0.0];
        lm[1] = [300.0, 128.0, 0.0, 0.0, 0.0];
        lm[2] = [128.0, -10.0, 0.0, 0.0, 0.0];
        // Landmark 4 (cell 32, 32) has a peak 4 cells away: outside its 7 × 7 window.
        let h = heatmap_with(&[(0, 32, 0, 5.0), (1, 32, 63, 5.0), (2, 0, 32, 5.0), (4, 32, 36, 5.0)]);
        let before = lm.clone();
        refine(&mut lm, &h).unwrap();
        assert_eq!(lm, before);
    }

    #[test]
    fn two_equal_peaks_meet_halfway_and_the_border_cuts_the_window() {
        let mut lm = vec![[0.0f32; LANDMARK_VALUES]; NUM_OUTPUT_LANDMARKS];
        lm[7] = [128.0, 128.0, 0.0, 0.0, 0.0]; // cell (32, 32)
        lm[8] = [1.0, 1.0, 0.0, 0.0, 0.0]; // cell (0, 0): window rows and columns 0..=3
        let h = heatmap_with(&[(7, 30, 31, 6.0), (7, 34, 35, 6.0), (8, 3, 3, 6.0)]);
        refine(&mut lm, &h).unwrap();
        assert!((lm[7][0] - 33.0 * 4.0).abs() < 1e-3 && (lm[7][1] - 32.0 * 4.0).abs() < 1e-3, "{:?}", lm[7]);
        assert!((lm[8][0] - 12.0).abs() < 1e-3 && (lm[8][1] - 12.0).abs() < 1e-3, "{:?}", lm[8]);
    }

    #[test]
    fn wrong_lengths_are_errors() {
        let mut lm = vec![[0.0f32; LANDMARK_VALUES]; NUM_OUTPUT_LANDMARKS];
        assert!(matches!(refine(&mut lm, &[0.0; 10]), Err(Error::OutOfRange { .. })));
        let mut many = vec![[0.0f32; LANDMARK_VALUES]; NUM_OUTPUT_LANDMARKS + 1];
        let h = heatmap_with(&[]);
        assert!(matches!(refine(&mut many, &h), Err(Error::OutOfRange { .. })));
        let mut first_three = vec![[128.0f32, 128.0, 0.0, 0.0, 0.0]; 3];
        refine(&mut first_three, &heatmap_with(&[(2, 33, 33, 6.0), (5, 33, 33, 6.0)])).unwrap();
        assert_eq!(first_three[2][..2], [132.0, 132.0], "landmark k reads channel k");
        assert_eq!(first_three[1][..2], [128.0, 128.0]);
    }
}
