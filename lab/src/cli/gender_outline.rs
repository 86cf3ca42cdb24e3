//! `sketchbody-lab gender-outline DATASET --out FILE`: the gender classifier's features of each
//! sample measured two ways, for comparing outline evidence across renderers (issue 47): on the
//! sketch's Canny edges as the pipeline measures them (rays to the first stroke), and on the
//! outline of the filled figure ([`SketchEvidence::figure`] at the image's own resolution), where
//! interior strokes (creases, hatching) no longer stop a ray. Ground-truth 2-D joints, pose and
//! camera; one JSON line per sample: `{"stem", "gender", "first": [...], "filled": [...]}` (the
//! features in [`GENDER_FEATURE_NAMES`] order, `null` where missing).

use std::io::Write as _;
use std::path::PathBuf;

use sketchbody::fit::gender_evidence::GENDER_FEATURE_NAMES;
use sketchbody::fit::{gender_features, SketchEvidence};
use sketchbody::image::{canny, load_image, CannyParams, GrayImage};
use sketchbody::render::sketch::truth::GroundTruth;
use sketchbody::skeleton::{Joints2, Joints3, BONES, NUM_JOINTS};
use sketchbody_cli::CliError;
use sketchbody_lab::eval::score::dataset_samples;

/// Arguments of `sketchbody-lab gender-outline`.
#[derive(clap::Args)]
pub struct Args {
    /// Dataset folder (make-dataset or the Blender set: STEM.png and STEM.json).
    dataset: PathBuf,
    /// Output file, one JSON line per sample.
    #[arg(long)]
    out: PathBuf,
    /// Thicken the strokes by this many pixels (a square dilation) before filling the figure,
    /// closing the gaps of sketchy outlines.
    #[arg(long, default_value_t = 0)]
    close: usize,
}

/// `edges` with every stroke pixel grown by `r` pixels in x and y (a square dilation).
fn dilated(edges: &GrayImage, r: usize) -> Result<GrayImage, CliError> {
    let (w, h) = (edges.width(), edges.height());
    let src = edges.as_bytes();
    let mut rows = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            if src[y * w + x] != 0 {
                rows[y * w + x.saturating_sub(r)..=y * w + (x + r).min(w - 1)].fill(255);
            }
        }
    }
    let mut out = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            if rows[y * w + x] != 0 {
                for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                    out[yy * w + x] = 255;
                }
            }
        }
    }
    Ok(GrayImage::from_vec(w, h, out)?)
}

/// The outline of the filled figure of `edges` (255 on figure pixels with a 4-neighbour
/// outside it or on the image border), the figure chosen by points along the visible bones of
/// `joints`.
fn filled_outline(edges: &GrayImage, joints: &Joints2) -> Result<GrayImage, CliError> {
    let (w, h) = (edges.width(), edges.height());
    let skeleton: Vec<[f64; 2]> = BONES
        .iter()
        .filter(|&&(a, b)| joints.visible[a] && joints.visible[b])
        .flat_map(|&(a, b)| {
            let (pa, pb) = (joints.xy[a], joints.xy[b]);
            (0..=8).map(move |i| {
                let t = i as f64 / 8.0;
                [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
            })
        })
        .collect();
    let evidence = SketchEvidence::new(edges, w, h, &skeleton)?;
    let figure = evidence.figure();
    let inside =
        |x: i64, y: i64| x >= 0 && y >= 0 && x < w as i64 && y < h as i64 && figure[y as usize * w + x as usize] != 0;
    let mut out = vec![0u8; w * h];
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            if inside(x, y) && [(-1, 0), (1, 0), (0, -1), (0, 1)].iter().any(|&(dx, dy)| !inside(x + dx, y + dy)) {
                out[y as usize * w + x as usize] = 255;
            }
        }
    }
    Ok(GrayImage::from_vec(w, h, out)?)
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let mut file = std::fs::File::create(&a.out).map_err(|e| CliError(format!("{}: {e}", a.out.display())))?;
    let mut n = 0;
    for stem in dataset_samples(&a.dataset)? {
        let tp = a.dataset.join(format!("{stem}.json"));
        let text = std::fs::read_to_string(&tp).map_err(|e| CliError(format!("{}: {e}", tp.display())))?;
        let truth = GroundTruth::from_json(&text, &tp.display().to_string())?;
        let sketch = load_image(&a.dataset.join(format!("{stem}.png")))?;
        let edges = canny(&sketch.view(), &CannyParams::default())?;
        let mut joints = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [false; NUM_JOINTS] };
        for k in 0..NUM_JOINTS.min(truth.joints2d.len()) {
            joints.xy[k] = truth.joints2d[k];
            joints.visible[k] = truth.visible.get(k).copied().unwrap_or(false);
        }
        let pose: Joints3 = truth
            .joints3d
            .as_slice()
            .try_into()
            .map_err(|_| CliError(format!("{}: joints3d must hold {NUM_JOINTS} joints", tp.display())))?;
        let camera = truth.camera.to_camera()?;
        let first = gender_features(&joints, &edges, &pose, &camera)?;
        let closed = if a.close > 0 { Some(dilated(&edges, a.close)?) } else { None };
        let filled =
            gender_features(&joints, &filled_outline(closed.as_ref().unwrap_or(&edges), &joints)?, &pose, &camera)?;
        let line = serde_json::json!({
            "stem": stem, "gender": truth.gender, "first": first.values, "filled": filled.values,
        });
        writeln!(file, "{line}").map_err(|e| CliError(format!("{}: {e}", a.out.display())))?;
        n += 1;
    }
    println!("{n} samples; features {}", GENDER_FEATURE_NAMES.join(", "));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square outline with a stroke across its inside: the filled figure's outline is the
    /// square alone (the interior stroke no longer stops a ray), and a dilation grows one stroke
    /// pixel into a (2r + 1)² block.
    #[test]
    fn the_filled_outline_drops_interior_strokes_and_dilation_grows_strokes() {
        let (w, h) = (40, 40);
        let mut px = vec![0u8; w * h];
        for k in 5..=35 {
            for (x, y) in [(k, 5), (k, 35), (5, k), (35, k)] {
                px[y * w + x] = 255;
            }
        }
        for y in 10..=30 {
            px[y * w + 20] = 255;
        }
        let edges = GrayImage::from_vec(w, h, px).unwrap();
        let mut joints = Joints2 { xy: [[12.0, 20.0]; NUM_JOINTS], visible: [false; NUM_JOINTS] };
        joints.visible[BONES[0].0] = true;
        joints.visible[BONES[0].1] = true;
        joints.xy[BONES[0].1] = [28.0, 20.0];
        let outline = filled_outline(&edges, &joints).unwrap_or_else(|e| panic!("{}", e.0));
        let at = |img: &GrayImage, x: usize, y: usize| img.as_bytes()[y * w + x];
        assert_eq!(at(&outline, 20, 20), 0, "the interior stroke is inside the figure");
        assert_eq!(at(&outline, 5, 20), 255, "the square's side is its outline");
        assert_eq!(at(&outline, 12, 20), 0);
        let mut one = vec![0u8; w * h];
        one[20 * w + 20] = 255;
        let grown = dilated(&GrayImage::from_vec(w, h, one).unwrap(), 2).unwrap_or_else(|e| panic!("{}", e.0));
        assert_eq!(grown.as_bytes().iter().filter(|&&v| v != 0).count(), 25);
        assert_eq!((at(&grown, 18, 18), at(&grown, 22, 22), at(&grown, 23, 20)), (255, 255, 0));
    }
}
