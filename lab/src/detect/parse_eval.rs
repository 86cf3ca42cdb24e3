//! The PARSE evaluation protocol (`data/fmp/README.md`): PCK given the ground-truth person box.
//! For each image the highest-scoring candidate whose box of part centres covers more than 30 %
//! of the ground-truth box is taken (the authors' `testmodel_gtbox` / `bestoverlap`); a joint is
//! correct when within α · max(height, width) of the tight box around the labelled joints.

use std::path::Path;

use sketchbody::detect::model::{Model, NUM_PARSE_JOINTS, PARSE_JOINT_NAMES};
use sketchbody::detect::tree::Candidate;
use sketchbody::error::{Error, Result};
use sketchbody::image::ImageView;

/// One labelled PARSE image: file name and the 14 joints in 0-based pixel-index coordinates
/// (pixel centres at integers, as in the CSV).
#[derive(Clone, Debug, PartialEq)]
pub struct Labelled {
    /// Image file name, e.g. `im0101.jpg`.
    pub image: String,
    /// Joints (x, y), data-set order.
    pub joints: [[f64; 2]; NUM_PARSE_JOINTS],
}

/// Largest `labels.csv` [`read_labels`] accepts, in bytes (16 MiB; PARSE's is about 60 kB).
pub const MAX_LABELS_FILE_BYTES: u64 = 16 << 20;

/// Reads `labels.csv` (header `image,lank_x,lank_y,...`). Errors: `Io`, `CorruptData` naming
/// the line.
pub fn read_labels(path: &Path) -> Result<Vec<Labelled>> {
    let text = sketchbody::fsutil::read_capped_string(path, MAX_LABELS_FILE_BYTES)?;
    let bad = |line: usize, what: &str| Error::CorruptData(format!("{} line {line}: {what}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().ok_or_else(|| bad(1, "empty file"))?;
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    if cols.len() != 1 + 2 * NUM_PARSE_JOINTS || cols[1] != format!("{}_x", PARSE_JOINT_NAMES[0]) {
        return Err(bad(1, "unexpected header"));
    }
    let mut out = Vec::new();
    for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != cols.len() {
            return Err(bad(i + 2, &format!("{} fields, expected {}", f.len(), cols.len())));
        }
        let mut joints = [[0.0; 2]; NUM_PARSE_JOINTS];
        for j in 0..NUM_PARSE_JOINTS {
            for a in 0..2 {
                let v: f64 =
                    f[1 + 2 * j + a].parse().map_err(|_| bad(i + 2, &format!("bad number {:?}", f[1 + 2 * j + a])))?;
                if !v.is_finite() {
                    return Err(bad(i + 2, "non-finite coordinate"));
                }
                joints[j][a] = v;
            }
        }
        out.push(Labelled { image: f[0].to_owned(), joints });
    }
    Ok(out)
}

/// Tight box (x1, y1, x2, y2) around points.
pub fn tight_box(p: &[[f64; 2]]) -> [f64; 4] {
    p.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, q| {
        [b[0].min(q[0]), b[1].min(q[1]), b[2].max(q[0]), b[3].max(q[1])]
    })
}

/// The authors' `bestoverlap`: the highest-scoring candidate (list sorted best first) whose box
/// of part centres covers more than `overlap` of `gt` (pixel-index boxes, +1 inclusive areas).
/// Centres are compared in pixel-index coordinates (continuous − 0.5).
pub fn best_overlap(cands: &[Candidate], gt: [f64; 4], overlap: f64) -> Option<&Candidate> {
    let garea = (gt[2] - gt[0] + 1.0) * (gt[3] - gt[1] + 1.0);
    cands.iter().find(|c| {
        let centres: Vec<[f64; 2]> = c
            .parts
            .iter()
            .map(|p| {
                let q = p.centre();
                [q[0] - 0.5, q[1] - 0.5]
            })
            .collect();
        let b = tight_box(&centres);
        let w = (b[2].min(gt[2]) - b[0].max(gt[0]) + 1.0).max(0.0);
        let h = (b[3].min(gt[3]) - b[1].max(gt[1]) + 1.0).max(0.0);
        w * h / garea > overlap
    })
}

/// Which joints are within `alpha` · max(h, w) of the ground-truth box (`pred` in pixel-index
/// coordinates like `gt`).
pub fn correct_joints(
    pred: &[[f64; 2]; NUM_PARSE_JOINTS],
    gt: &[[f64; 2]; NUM_PARSE_JOINTS],
    alpha: f64,
) -> [bool; NUM_PARSE_JOINTS] {
    let b = tight_box(gt);
    let thr = alpha * (b[2] - b[0]).max(b[3] - b[1]);
    let mut ok = [false; NUM_PARSE_JOINTS];
    for j in 0..NUM_PARSE_JOINTS {
        let (dx, dy) = (pred[j][0] - gt[j][0], pred[j][1] - gt[j][1]);
        ok[j] = (dx * dx + dy * dy).sqrt() <= thr;
    }
    ok
}

/// Predicted PARSE joints of a candidate in pixel-index coordinates (continuous − 0.5).
pub fn predicted_joints(c: &Candidate, model: &Model) -> [[f64; 2]; NUM_PARSE_JOINTS] {
    let (mut xy, _) = sketchbody::detect::joints::parse_joints(c, &model.part_to_joint);
    for p in &mut xy {
        p[0] -= 0.5;
        p[1] -= 0.5;
    }
    xy
}

/// Test-time threshold of the protocol: min(model threshold, −2), as the authors' demo sets it.
pub fn protocol_threshold(model: &Model) -> f64 {
    model.thresh.min(-2.0)
}

/// Runs the protocol on one image: all candidates above [`protocol_threshold`], the best one
/// overlapping the ground-truth box, and which joints it gets right at `alpha` (all wrong when no
/// candidate overlaps). Also returns the chosen candidate's score.
pub fn evaluate_image(
    image: &ImageView<'_>,
    model: &Model,
    gt: &[[f64; 2]; NUM_PARSE_JOINTS],
    alpha: f64,
) -> Result<([bool; NUM_PARSE_JOINTS], Option<f64>)> {
    let planes = sketchbody::detect::pyramid::planes_from_view(image);
    let gtbox = tight_box(gt);
    // Per level only the best overlapping candidate can win.
    let accept = |c: &Candidate| best_overlap(std::slice::from_ref(c), gtbox, 0.3).is_some();
    let cands = sketchbody::detect::candidates(
        &planes,
        model,
        model.interval,
        protocol_threshold(model),
        0.0,
        f64::INFINITY,
        1,
        &accept,
    )?;
    Ok(match cands.first() {
        Some(c) => (correct_joints(&predicted_joints(c, model), gt, alpha), Some(c.score)),
        None => ([false; NUM_PARSE_JOINTS], None),
    })
}

/// Joint groups of the PCK table: name and the (left, right) PARSE joints averaged.
pub const PCK_GROUPS: [(&str, [usize; 2]); 7] = [
    ("head", [12, 13]),
    ("shoulder", [8, 9]),
    ("elbow", [7, 10]),
    ("wrist", [6, 11]),
    ("hip", [2, 3]),
    ("knee", [1, 4]),
    ("ankle", [0, 5]),
];

#[cfg(test)]
mod tests {
    use super::*;
    use sketchbody::detect::tree::PartBox;

    #[test]
    fn pck_threshold_uses_the_longer_box_side() {
        let mut gt = [[0.0; 2]; NUM_PARSE_JOINTS];
        gt[13] = [50.0, 100.0]; // box 50 x 100 -> threshold 10 px at alpha 0.1
        let mut pred = gt;
        pred[0] = [9.9, 0.0];
        pred[1] = [0.0, 10.1];
        let ok = correct_joints(&pred, &gt, 0.1);
        assert!(ok[0] && !ok[1] && ok[2]);
    }

    #[test]
    fn best_overlap_skips_higher_scores_elsewhere() {
        let mk = |score: f64, x: f64| Candidate {
            score,
            cell_px: 1.0,
            parts: vec![
                PartBox { x1: x, y1: 0.0, x2: x + 2.0, y2: 2.0, mixture: 0, local: 0.0 },
                PartBox { x1: x + 40.0, y1: 40.0, x2: x + 42.0, y2: 42.0, mixture: 0, local: 0.0 },
            ],
        };
        let cands = vec![mk(3.0, 200.0), mk(2.0, 0.0), mk(1.0, 1.0)];
        let got = best_overlap(&cands, [0.0, 0.0, 40.0, 40.0], 0.3).unwrap();
        assert_eq!(got.score, 2.0);
        assert!(best_overlap(&cands[..1], [0.0, 0.0, 40.0, 40.0], 0.3).is_none());
    }

    #[test]
    fn labels_errors_name_the_line() {
        let dir = std::env::temp_dir().join(format!("skb_labels_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("labels.csv");
        let mut header = String::from("image");
        for n in PARSE_JOINT_NAMES {
            header += &format!(",{n}_x,{n}_y");
        }
        let row = |v: &str| format!("im.jpg{}", format!(",{v}").repeat(28));
        std::fs::write(&p, format!("{header}\n{}\n", row("1.5"))).unwrap();
        let l = read_labels(&p).unwrap();
        assert_eq!(l.len(), 1);
        assert_eq!(l[0].joints[13], [1.5, 1.5]);
        std::fs::write(&p, format!("{header}\n{}\n{}\n", row("1"), row("x"))).unwrap();
        assert!(matches!(read_labels(&p), Err(Error::CorruptData(s)) if s.contains("line 3")));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
