//! Tuning bench for the BlazePose backend's ROI and input preprocessing: PCK@0.1 / @0.2 of the
//! landmark backend (an image whose pose flag is under 0.5 counts as answered "no figure", PCK 0)
//! and the pose-flag distribution, per variant, on PARSE *training* photos (1–100, the
//! calibration's range; never the test photos 101–305) plain and through each stylisation, and
//! on blank, text and clutter pages (seed 11, as the calibration).
//!
//! Usage: cargo run --release --example landmark_roi -- PARSE_DIR VARIANT[,VARIANT...] [LAST]
//! Variants: `default` (the library's `detect_blazepose`), `onepass`, `noretry`, `nolight`,
//! `nofill`, `before` (neither retry, lightening nor filling), `pickACC@T/D/C` (the shipped
//! retries, then a filled try kept at a flag ≥ ACC), `noprep` (two passes by hand), `plain3` (a third
//! pass), and `PREP[+PREP][:ROIS]` built here (see [`generic`]).

use std::path::Path;

use rayon::prelude::*;
use sketchbody::body::BodyModel;
use sketchbody::detect::joints::parse_to_canonical;
use sketchbody::detect::landmark::{
    crop, joints, landmarks_of_tensor, prep, LandmarkNet, Roi, RoiLandmarks, NUM_POSE_LANDMARKS,
};
use sketchbody::detect::landmark::{
    detect_blazepose, landmarks_in_roi, roi, roi_from_landmarks, BlazePoseOptions, DEFAULT_RETRY_BELOW,
};
use sketchbody::image::{load_rgb_image, ImageView, RgbImage};
use sketchbody::render::sketch::mocap::MocapLibrary;
use sketchbody::render::sketch::SketchRenderer;
use sketchbody::skeleton::NUM_JOINTS;
use sketchbody_lab::detect::parse_eval::read_labels;
use sketchbody_lab::eval::detector::held_out_request;
use sketchbody_lab::eval::metrics::pck;
use sketchbody_lab::render::stylise::{negative_page, stylise, NegativePage, Stylisation};
use std::sync::Arc;

static WINS: std::sync::Mutex<Vec<usize>> = std::sync::Mutex::new(Vec::new());

type Truth = Option<[[f64; 2]; NUM_JOINTS]>;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = Path::new(&args[1]);
    let variants: Vec<String> = args[2].split(',').map(str::to_string).collect();
    let last: usize = args.get(3).map_or(100, |s| s.parse().expect("LAST"));
    let net = LandmarkNet::embedded().expect("net");
    let labels = read_labels(&dir.join("labels.csv")).expect("labels");
    let mut sets: Vec<(String, Vec<(RgbImage, Truth)>)> = Vec::new();
    let mocap = MocapLibrary::load_dir(&dir.join("../mocap/deepmimic")).ok();
    let renderer = SketchRenderer::new(Arc::new(BodyModel::embedded().expect("body")), mocap).expect("renderer");
    let synth = (0..60u64)
        .into_par_iter()
        .map(|i| {
            let s = renderer.render(&held_out_request(11, i, 512, None)).expect("render");
            let rgb = s.pixels.iter().flat_map(|&g| [g; 3]).collect();
            let truth: [[f64; 2]; NUM_JOINTS] = s.truth.joints2d.as_slice().try_into().expect("15");
            (RgbImage::from_vec(512, 512, rgb).expect("rgb"), Some(truth))
        })
        .collect();
    sets.push(("synth".into(), synth));
    for style in
        [None, Some(Stylisation::XdogInk), Some(Stylisation::PencilHatching), Some(Stylisation::PosterisedFlat)]
    {
        let imgs = (1..=last)
            .into_par_iter()
            .map(|i| {
                let name = format!("im{i:04}.jpg");
                let l = labels.iter().find(|l| l.image == name).expect("label");
                let img = load_rgb_image(&dir.join("images").join(&name)).expect("image");
                let img = match style {
                    Some(s) => stylise(&img.view(), s, i as u64).expect("stylise"),
                    None => img,
                };
                let (j, _) = parse_to_canonical(&l.joints, &[1.0; 14]);
                (img, Some(j.xy.map(|p| [p[0] + 0.5, p[1] + 0.5])))
            })
            .collect();
        sets.push((style.map_or("parse".into(), |s| s.name().to_string()), imgs));
    }
    for kind in NegativePage::ALL {
        let imgs = (0..40).map(|i| (negative_page(kind, 512, 512, 11 * 1000 + i).expect("page"), None)).collect();
        sets.push((kind.name().to_string(), imgs));
    }
    for v in &variants {
        let t0 = std::time::Instant::now();
        let mut line = format!("{v:<14}");
        for (name, imgs) in &sets {
            let res: Vec<(f64, [f64; 2])> = imgs
                .par_iter()
                .map(|(img, truth)| {
                    let pass = run_variant(v, &net, &img.view());
                    let flag = pass.as_ref().map_or(0.0, |p| p.pose_flag);
                    let score = match (truth, &pass) {
                        (Some(t), Some(p)) if flag >= 0.5 => {
                            let xy: Vec<[f64; 2]> = p.landmarks.iter().map(|l| [l.x, l.y]).collect();
                            let (j, _) = joints::to_canonical(&xy[..NUM_POSE_LANDMARKS], &[1.0; NUM_POSE_LANDMARKS]);
                            [pck(t, &j.xy, 0.1).unwrap(), pck(t, &j.xy, 0.2).unwrap()]
                        }
                        _ => [0.0; 2],
                    };
                    (flag, score)
                })
                .collect();
            let n = res.len() as f64;
            let answered = res.iter().filter(|r| r.0 >= 0.5).count() as f64 / n;
            let low = res.iter().filter(|r| r.0 >= 0.1).count() as f64 / n;
            if imgs[0].1.is_some() {
                let p: [f64; 2] = std::array::from_fn(|k| res.iter().map(|r| r.1[k]).sum::<f64>() / n);
                line += &format!(" | {name} {:.3}/{:.3} nf {:.1}%", p[0], p[1], 100.0 * (1.0 - answered));
            } else {
                line += &format!(" | {name} flag≥.5 {:.1}% ≥.1 {:.1}%", 100.0 * answered, 100.0 * low);
            }
        }
        let mut w = WINS.lock().unwrap();
        let mut hist = [0usize; 8];
        for &i in w.iter() {
            hist[i] += 1;
        }
        w.clear();
        println!("{line} | {:.0} s | wins {hist:?}", t0.elapsed().as_secs_f64());
    }
}

fn run_variant(v: &str, net: &LandmarkNet, image: &ImageView<'_>) -> Option<RoiLandmarks> {
    match v {
        "default" => detect_blazepose(net, image, &BlazePoseOptions { min_pose_flag: 0.0, ..Default::default() })
            .ok()
            .map(|d| d.pass),
        "onepass" | "noretry" | "nolight" | "before" | "nofill" => {
            let o = BlazePoseOptions {
                min_pose_flag: 0.0,
                passes: if v == "onepass" { 1 } else { 2 },
                retry_below: if v == "noretry" || v == "before" { 0.0 } else { DEFAULT_RETRY_BELOW },
                lighten_drawings: !(v == "nolight" || v == "before"),
                fill_drawings: !(v == "before" || v == "nofill"),
                ..Default::default()
            };
            detect_blazepose(net, image, &o).ok().map(|d| d.pass)
        }
        "noprep" | "plain3" => {
            let ink = roi::ink_box(image)?;
            let mut p = landmarks_in_roi(net, image, &roi::Roi::from_box(ink).ok()?, true).ok()?;
            let n = if v == "plain3" { 2 } else { 1 };
            for _ in 0..n {
                if let Ok(r) = roi_from_landmarks(&p) {
                    p = landmarks_in_roi(net, image, &r, true).ok()?;
                }
            }
            Some(p)
        }
        other => match other.strip_prefix("pick").and_then(|x| x.split_once('@')) {
            // `pickACC@FILL`: the shipped path, then, when its flag is under 0.5, the lightened
            // crop with `fillFILL` at the ink box; the filled pass wins with a higher flag ≥ ACC.
            Some((acc, fill)) => {
                let base = generic("pgamma0.4:multiA0.5r0.9", net, image)?;
                if base.pose_flag >= 0.5 {
                    return Some(base);
                }
                let acc: f64 = acc.parse().unwrap();
                match generic(&format!("pgamma0.4+fill{fill}"), net, image) {
                    Some(alt) if alt.pose_flag > base.pose_flag && alt.pose_flag >= acc => Some(alt),
                    _ => Some(base),
                }
            }
            None => generic(other, net, image),
        },
    }
}

/// `prep[:roi]`: prep in none | stretchT (ink percentile lifted to 0 when lighter than T) |
/// gammaG | blurS | stretchT+blurS; roi in two (default) | multiT (other ROIs when the flag < T).
fn generic(v: &str, net: &LandmarkNet, image: &ImageView<'_>) -> Option<RoiLandmarks> {
    let (prep, roi_mode) = v.split_once(':').unwrap_or((v, "two"));
    let run = |r: &Roi| -> Option<RoiLandmarks> {
        let mut t = crop::crop_tensor(image, r);
        for step in prep.split('+') {
            apply(step, &mut t);
        }
        landmarks_of_tensor(net, r, t, true).ok()
    };
    let two = |r: &Roi| -> Option<RoiLandmarks> {
        let p = run(r)?;
        match roi_from_landmarks(&p) {
            Ok(r2) => run(&r2),
            Err(_) => Some(p),
        }
    };
    let ink = roi::ink_box(image)?;
    let first = two(&Roi::from_box(ink).ok()?)?;
    if let Some(m) = roi_mode.strip_prefix("multi") {
        let (set, t) = m.split_at(1);
        let (t, acc) = t.split_once('r').unwrap_or((t, "0"));
        let (t, acc): (f64, f64) = (t.parse().unwrap(), acc.parse().unwrap());
        if first.pose_flag >= t {
            return Some(first);
        }
        let mut best = first;
        let c = [0.5 * (ink[0] + ink[2]), 0.5 * (ink[1] + ink[3])];
        let side = (ink[2] - ink[0]).max(ink[3] - ink[1]);
        let cands: Vec<(f64, f64, f64)> = match set {
            "A" => vec![(0.8, 0.0, 0.0), (1.0, 0.0, 0.0), (1.6, 0.0, 0.0)],
            "B" => vec![
                (0.6, 0.0, 0.0),
                (0.8, 0.0, 0.0),
                (1.0, 0.0, 0.0),
                (1.6, 0.0, 0.0),
                (1.0, 0.0, -0.15),
                (1.0, 0.0, 0.15),
            ],
            "C" => vec![(0.8, 0.0, 0.0), (1.0, 0.0, 0.0)],
            "D" => vec![(0.8, 0.0, 0.0), (1.0, 0.0, 0.0), (1.6, 0.0, 0.0), (0.7, 0.0, -0.15), (0.7, 0.0, 0.15)],
            "E" => vec![(0.8, 0.0, 0.0), (1.0, 0.0, 0.0), (1.6, 0.0, 0.0), (2.2, 0.0, 0.0)],
            "F" => vec![(0.8, 0.0, 0.0), (1.6, 0.0, 0.0), (2.2, 0.0, 0.0), (1.0, 0.0, -0.15)],
            "G" => vec![(0.8, 0.0, 0.0), (1.6, 0.0, 0.0), (2.2, 0.0, 0.0), (3.0, 0.0, 0.0)],
            _ => panic!("set {set}"),
        };
        let mut win = 0;
        for (i, &(k, dx, dy)) in cands.iter().enumerate() {
            let r = Roi { cx: c[0] + dx * side, cy: c[1] + dy * side, size: k * side, rotation: 0.0 };
            if let Some(p) = two(&r) {
                if p.pose_flag > best.pose_flag && p.pose_flag >= acc {
                    best = p;
                    win = i + 1;
                }
            }
        }
        WINS.lock().unwrap().push(win);
        return Some(best);
    }
    Some(first)
}

fn apply(step: &str, t: &mut [f32]) {
    if step == "none" {
    } else if let Some(x) = step.strip_prefix("stretch") {
        let thr: f32 = x.parse().unwrap();
        let mut g: Vec<f32> = t.chunks(3).map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
        g.sort_by(f32::total_cmp);
        let lo = g[g.len() / 100];
        let hi = g[g.len() * 95 / 100];
        if lo > thr && hi - lo > 0.05 {
            for v in t.iter_mut() {
                *v = ((*v - lo) / (hi - lo)).clamp(0.0, 1.0);
            }
        }
    } else if let Some(x) = step.strip_prefix("pgamma") {
        // gamma only on paper-dominated crops (median gray >= 0.9)
        let g: f32 = x.parse().unwrap();
        let mut gr: Vec<f32> = t.chunks(3).map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
        gr.sort_by(f32::total_cmp);
        if gr[gr.len() / 2] >= 0.9 {
            for v in t.iter_mut() {
                *v = v.powf(g);
            }
        }
    } else if let Some(x) = step.strip_prefix("fill") {
        let v: Vec<f32> = x.split('/').map(|p| p.parse().unwrap()).collect();
        prep::fill_enclosed_with(t, crop::INPUT_SIDE, v[0], v[1] as usize, v[2]);
    } else if let Some(x) = step.strip_prefix("gamma") {
        let g: f32 = x.parse().unwrap();
        for v in t.iter_mut() {
            *v = v.powf(g);
        }
    } else if let Some(x) = step.strip_prefix("blur") {
        let s: f32 = x.parse().unwrap();
        let r = (3.0 * s).ceil() as isize;
        let k: Vec<f32> = (-r..=r).map(|i| (-(i * i) as f32 / (2.0 * s * s)).exp()).collect();
        let ks: f32 = k.iter().sum();
        let n = crop::INPUT_SIDE as isize;
        for pass in 0..2 {
            let src = t.to_vec();
            for y in 0..n {
                for x in 0..n {
                    for c in 0..3 {
                        let mut acc = 0.0;
                        for (i, &kv) in k.iter().enumerate() {
                            let d = i as isize - r;
                            let (xx, yy) =
                                if pass == 0 { ((x + d).clamp(0, n - 1), y) } else { (x, (y + d).clamp(0, n - 1)) };
                            acc += kv * src[((yy * n + xx) * 3 + c) as usize];
                        }
                        t[((y * n + x) * 3 + c) as usize] = acc / ks;
                    }
                }
            }
        }
    } else {
        panic!("unknown step {step}");
    }
}
