//! Capsule mannequins: a figure drawn as the outline of the union of capsules around its 2-D
//! bones and an ellipse head, on the renderer's paper with optional clutter — the schematic
//! figure type of `assets/examples/sketch.png` and of many gesture drawings, which the
//! MakeHuman contour renderer never draws. Used as extra detector-training positives
//! ([`crate::detect::train`]); a separate entry point with its own random stream, so no
//! existing sketch seed changes.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use sketchbody::render::sketch::canvas::{Canvas, Pen};
use sketchbody::render::sketch::paper;
use sketchbody::skeleton::{BONES, NUM_BONES, NUM_JOINTS};

/// Stream tag mixed into the seed.
const STREAM: u64 = 0x6D61_6E6E_6571_756E;

/// Capsule radius of each bone of [`BONES`] as a fraction of the figure's standing height
/// (bone 0, neck → head, is the head ellipse instead): the proportions of the bundled example.
const RADIUS: [f64; NUM_BONES] =
    [0.0, 0.030, 0.028, 0.023, 0.030, 0.028, 0.023, 0.070, 0.037, 0.040, 0.030, 0.037, 0.040, 0.030];

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (vx, vy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = vx * vx + vy * vy;
    let t = if len2 > 0.0 { (((p[0] - a[0]) * vx + (p[1] - a[1]) * vy) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - t * vx).hypot(p[1] - a[1] - t * vy)
}

/// Draws a mannequin around `joints` (pixels, canonical order) of a figure `height_px` tall
/// on a `width` × `height` page; deterministic in `seed`. Returns 8-bit gray pixels.
pub fn render_mannequin(
    joints: &[[f64; 2]; NUM_JOINTS],
    height_px: f64,
    width: usize,
    height: usize,
    seed: u64,
) -> Vec<u8> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM);
    let girth = rng.random_range(0.75..1.3);
    let radius: Vec<f64> = RADIUS.iter().map(|r| r * height_px * girth * rng.random_range(0.9..1.1)).collect();
    let (head, neck) = (joints[0], joints[1]);
    let axis = [head[0] - neck[0], head[1] - neck[1]];
    let axis_len = axis[0].hypot(axis[1]).max(1e-9);
    let (ux, uy) = (axis[0] / axis_len, axis[1] / axis_len);
    let (head_long, head_wide) =
        (0.077 * height_px * rng.random_range(0.85..1.15), 0.06 * height_px * rng.random_range(0.85..1.15));
    let half_width = rng.random_range(0.7..1.8);
    let belt = rng.random_bool(0.5);
    let (pelvis, r_hip, l_hip) = (joints[8], joints[9], joints[12]);
    let distance = |p: [f64; 2]| {
        let (dx, dy) = (p[0] - head[0], p[1] - head[1]);
        let (along, across) = (dx * ux + dy * uy, -dx * uy + dy * ux);
        let e = ((along / head_long).powi(2) + (across / head_wide).powi(2)).sqrt();
        let mut d = (e - 1.0) * head_wide;
        for (b, &(i, j)) in BONES.iter().enumerate().skip(1) {
            d = d.min(segment_distance(p, joints[i], joints[j]) - radius[b]);
        }
        d
    };
    let mut canvas = Canvas::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let d = distance(p);
            let mut ink = (1.0 - (d.abs() - half_width).max(0.0)).clamp(0.0, 1.0);
            if belt
                && d < 0.0
                && segment_distance(p, r_hip, l_hip).min(segment_distance(p, pelvis, r_hip)) < 0.02 * height_px
            {
                let line = (1.0 - ((p[1] - 0.5 * (r_hip[1] + l_hip[1]) + 0.02 * height_px).abs() - 0.6).max(0.0))
                    .clamp(0.0, 1.0);
                ink = ink.max(0.8 * line);
            }
            canvas.ink[y * width + x] = ink as f32;
        }
    }
    let unit = width.min(height) as f64 / 512.0;
    let pen = Pen { width: 1.2 * unit, ink: 0.7, wobble: 0.8 * unit, jitter: 0.3, taper: 0.3 };
    let (strays, scribbles) = (rng.random_range(0..4), rng.random_range(0..2));
    paper::clutter(&mut canvas, &pen, unit, strays, scribbles, 0, None, &mut rng);
    let tone = rng.random_range(0.85..1.0);
    let noise = rng.random_range(0.0..0.06);
    let dark = rng.random_range(0.65..0.9);
    paper::compose(&canvas, tone, noise, dark, &mut rng)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_an_outline_around_the_bones_and_is_deterministic() {
        let joints: [[f64; 2]; NUM_JOINTS] = [
            [128.0, 35.0],
            [128.0, 59.0],
            [107.0, 63.0],
            [95.0, 98.0],
            [88.0, 131.0],
            [149.0, 63.0],
            [163.0, 96.0],
            [176.0, 126.0],
            [128.0, 125.0],
            [117.0, 128.0],
            [114.0, 176.0],
            [111.0, 223.0],
            [139.0, 128.0],
            [144.0, 176.0],
            [150.0, 223.0],
        ];
        let a = render_mannequin(&joints, 215.0, 256, 256, 7);
        assert_eq!(a, render_mannequin(&joints, 215.0, 256, 256, 7));
        assert_ne!(a, render_mannequin(&joints, 215.0, 256, 256, 8));
        let at = |x: usize, y: usize| a[y * 256 + x];
        // Inside the torso and far from the figure: paper; the darkest pixel along a row
        // through the thighs lies near a leg's outline, not on the bone.
        assert!(at(128, 95) > 150 && at(10, 240) > 150, "{} {}", at(128, 95), at(10, 240));
        let row = 150;
        let darkest = (60..200).min_by_key(|&x| at(x, row)).unwrap();
        assert!(at(darkest, row) < 120, "no outline on row {row}");
        let bone_x = 0.5 * (joints[9][0] + joints[10][0]);
        assert!((darkest as f64 - bone_x).abs() > 3.0, "outline at {darkest} on the bone at {bone_x}");
    }
}
