//! Real-pose positives (issue 15, item 5): PARSE *training* photos through the drawing-like
//! training filters ([`crate::render::photo_npr`], never the benchmark's stylisations), with
//! their labelled joints. Only photos 1..=`last` are read, `last` ≤ 100: photos 101–305 are the
//! proxy benchmark's test split and are refused.

use rayon::prelude::*;

use crate::detect::parse_eval::read_labels;
use crate::detect::train::examples::{Geometry, Positive};
use crate::render::photo_npr::{photo_npr, PhotoNpr};
use sketchbody::detect::hog::Planes;
use sketchbody::detect::joints::parse_to_canonical;
use sketchbody::error::{Error, Result};
use sketchbody::image::load_rgb_image;
use sketchbody::render::sketch::truth::sample_seed;
use sketchbody::skeleton::{joint, NUM_JOINTS};

/// Last PARSE photo of the training split.
pub const LAST_TRAINING_PHOTO: usize = 100;

/// Which PARSE photos, and how many filtered copies of each.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseSource {
    /// The PARSE folder (`labels.csv`, `images/`).
    pub dir: std::path::PathBuf,
    /// Last photo used (1..=100).
    pub last: usize,
    /// Filtered copies per photo (1..=8), filters in turn from a per-photo offset.
    pub variants: usize,
}

/// The number of a PARSE image name `imNNNN.ext`.
fn photo_number(name: &str) -> Option<usize> {
    name.strip_prefix("im")?.split('.').next()?.parse().ok()
}

/// Standing height (px) of a PARSE figure from its canonical joints: head (twice head-centre to
/// neck), neck to the hips' midpoint and the longer leg, times 1.04 for the feet; at least
/// 6.5 head heights (seated or foreshortened figures).
pub fn standing_height(j: &[[f64; 2]; NUM_JOINTS]) -> f64 {
    let d = |a: usize, b: usize| (j[a][0] - j[b][0]).hypot(j[a][1] - j[b][1]);
    let head = 2.0 * d(joint::HEAD, joint::NECK);
    let torso = d(joint::NECK, joint::PELVIS);
    let leg = (d(joint::R_HIP, joint::R_KNEE) + d(joint::R_KNEE, joint::R_ANKLE))
        .max(d(joint::L_HIP, joint::L_KNEE) + d(joint::L_KNEE, joint::L_ANKLE));
    ((head + torso + leg) * 1.04).max(6.5 * head)
}

/// Bilinear upscaling of a gray plane by `f` ≥ 1 (pixel centres aligned).
fn upscale(im: &Planes, f: f64) -> Planes {
    let (w, h) = (((im.width as f64) * f).round() as usize, ((im.height as f64) * f).round() as usize);
    let (sx, sy) = (im.width as f64 / w as f64, im.height as f64 / h as f64);
    let at = |x: usize, y: usize| im.data[y * im.width + x];
    let mut data = Vec::with_capacity(w * h);
    for y in 0..h {
        let fy = ((y as f64 + 0.5) * sy - 0.5).clamp(0.0, (im.height - 1) as f64);
        let (y0, ty) = (fy.floor() as usize, (fy - fy.floor()) as f32);
        let y1 = (y0 + 1).min(im.height - 1);
        for x in 0..w {
            let fx = ((x as f64 + 0.5) * sx - 0.5).clamp(0.0, (im.width - 1) as f64);
            let (x0, tx) = (fx.floor() as usize, (fx - fx.floor()) as f32);
            let x1 = (x0 + 1).min(im.width - 1);
            let top = at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx;
            let bot = at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx;
            data.push(top * (1.0 - ty) + bot * ty);
        }
    }
    Planes { width: w, height: h, channels: 1, data }
}

/// The positives (each with its mirror) of PARSE photos 1..=`src.last`, `src.variants` filtered
/// copies each (filter `PhotoNpr::ALL[(n + v) % 3]`, seeded from `seed`, the photo and the
/// copy); a figure smaller than canonical is upscaled first. Returns the positives and the number
/// of photos read. Errors: `OutOfRange` for `last` outside 1..=100 (the test split) or `variants`
/// outside 1..=8; reading or decoding errors; `CorruptData` when a wanted photo has no label.
pub fn parse_positives(src: &ParseSource, geo: &Geometry, seed: u64) -> Result<(Vec<Positive>, usize)> {
    if !(1..=LAST_TRAINING_PHOTO).contains(&src.last) {
        return Err(Error::OutOfRange {
            name: "parse_last",
            detail: format!("{} not in 1..={LAST_TRAINING_PHOTO} (PARSE photos 101-305 are the test split)", src.last),
        });
    }
    if !(1..=8).contains(&src.variants) {
        return Err(Error::OutOfRange { name: "parse_variants", detail: format!("{} not in 1..=8", src.variants) });
    }
    let labels = read_labels(&src.dir.join("labels.csv"))?;
    let mut wanted: Vec<(usize, &crate::detect::parse_eval::Labelled)> = labels
        .iter()
        .filter_map(|l| photo_number(&l.image).filter(|&n| (1..=src.last).contains(&n)).map(|n| (n, l)))
        .collect();
    wanted.sort_by_key(|w| w.0);
    for n in 1..=src.last {
        if wanted.iter().all(|w| w.0 != n) {
            return Err(Error::CorruptData(format!(
                "{}: no label for photo {n}",
                src.dir.join("labels.csv").display()
            )));
        }
    }
    let got: Vec<Vec<Positive>> = wanted
        .par_iter()
        .map(|&(n, l)| {
            let img = load_rgb_image(&src.dir.join("images").join(&l.image))?;
            let (j, _) = parse_to_canonical(&l.joints, &[1.0; 14]);
            // PARSE labels are pixel indices (centres at integers); the library's frame is continuous.
            let j: [[f64; 2]; NUM_JOINTS] = j.xy.map(|p| [p[0] + 0.5, p[1] + 0.5]);
            let height = standing_height(&j);
            let mut out = Vec::new();
            for v in 0..src.variants {
                let filter = PhotoNpr::ALL[(n + v) % PhotoNpr::ALL.len()];
                let px = photo_npr(&img.view(), filter, sample_seed(seed ^ 0x5041_5253, (n * 16 + v) as u64))?;
                let gray = Planes {
                    width: img.width(),
                    height: img.height(),
                    channels: 1,
                    data: px.iter().map(|&g| g as f32).collect(),
                };
                let f = (1.25 * geo.figure_px / height).max(1.0);
                let big = if f > 1.0 { upscale(&gray, f) } else { gray };
                let (fx, fy) = (big.width as f64 / img.width() as f64, big.height as f64 / img.height() as f64);
                let jb: [[f64; 2]; NUM_JOINTS] = j.map(|p| [p[0] * fx, p[1] * fy]);
                if let Some(pair) = geo.positive_pair(&big, &jb, height * fy) {
                    out.extend(pair);
                }
            }
            Ok(out)
        })
        .collect::<Result<_>>()?;
    Ok((got.into_iter().flatten().collect(), wanted.len()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sketchbody::image::{save_png, GrayImage};
    use std::path::Path;

    /// A folder with photos 1..=3 and 101 labelled, where photo 101's file is garbage.
    fn fixture(dir: &Path) {
        std::fs::create_dir_all(dir.join("images")).unwrap();
        let mut csv = String::from("image");
        for n in sketchbody::detect::PARSE_JOINT_NAMES {
            csv += &format!(",{n}_x,{n}_y");
        }
        csv += "\n";
        // lank lkne lhip rhip rkne rank lwr lelb lsho rsho relb rwr hbot htop
        let pts = [
            [40, 180],
            [40, 140],
            [42, 100],
            [58, 100],
            [60, 140],
            [60, 180],
            [25, 100],
            [30, 75],
            [38, 50],
            [62, 50],
            [70, 75],
            [75, 100],
            [50, 42],
            [50, 18],
        ];
        for n in [1, 2, 3, 101] {
            let row: Vec<String> = pts.iter().flat_map(|p| [p[0].to_string(), p[1].to_string()]).collect();
            csv += &format!("im{n:04}.jpg,{}\n", row.join(","));
            if n <= 3 {
                let px: Vec<u8> = (0..100 * 200)
                    .map(|k| if (30..70).contains(&(k % 100)) && (20..180).contains(&(k / 100)) { 60 } else { 220 })
                    .collect();
                save_png(&GrayImage::from_vec(100, 200, px).unwrap().view(), &dir.join(format!("images/im{n:04}.jpg")))
                    .unwrap();
            } else {
                std::fs::write(dir.join(format!("images/im{n:04}.jpg")), b"not an image").unwrap();
            }
        }
        std::fs::write(dir.join("labels.csv"), csv).unwrap();
    }

    #[test]
    fn reads_only_the_training_photos_and_refuses_the_test_split() {
        let dir = std::env::temp_dir().join(format!("skb_parse_pos_{}", std::process::id()));
        fixture(&dir);
        let geo = Geometry { sbin: 4, side: 5, figure_px: 160.0 };
        let src = ParseSource { dir: dir.clone(), last: 3, variants: 2 };
        let (pos, read) = parse_positives(&src, &geo, 1).unwrap();
        assert_eq!(read, 3, "photos 1-3 only (101's file is garbage and never opened)");
        assert_eq!(pos.len(), 3 * 2 * 2, "2 filtered copies of 3 photos, each mirrored");
        let (again, _) = parse_positives(&src, &geo, 1).unwrap();
        assert!(pos.iter().zip(&again).all(|(a, b)| a.feat.data == b.feat.data && a.cells == b.cells));
        // Upscaled to the canonical height: the head-top to ankle span is about 160 / 1.04 px.
        let span = pos[0].points[13][1] - pos[0].points[0][1];
        assert!(span > 110.0 && span < 160.0, "{span}");
        for last in [0, 101, 305] {
            let e = parse_positives(&ParseSource { last, ..src.clone() }, &geo, 1).unwrap_err();
            assert!(e.to_string().contains("parse_last"), "{e}");
        }
        assert!(parse_positives(&ParseSource { variants: 0, ..src.clone() }, &geo, 1).is_err());
        // Asking for photo 4, which has no label, is an error rather than a silent skip.
        assert!(parse_positives(&ParseSource { last: 4, ..src }, &geo, 1).unwrap_err().to_string().contains("photo 4"));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn standing_height_and_upscale() {
        let j: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|k| [0.0, 10.0 * k as f64]);
        assert!(standing_height(&j) > 0.0);
        let im = Planes { width: 2, height: 1, channels: 1, data: vec![0.0, 100.0] };
        let u = upscale(&im, 2.0);
        assert_eq!((u.width, u.height), (4, 2));
        assert_eq!(u.data[..4], [0.0, 25.0, 75.0, 100.0]);
    }
}
