//! `sketchbody-lab eval-parse --model M --data DIR`: PCK of the detector on the PARSE test images
//! with the ground-truth person box (protocol of `data/fmp/README.md`), per joint group and mean,
//! with the time per image.

use std::path::PathBuf;
use std::time::Instant;

use sketchbody::detect::{Model, NUM_PARSE_JOINTS, PARSE_JOINT_NAMES};
use sketchbody::image::load_rgb_image;
use sketchbody_lab::detect::parse_eval::{evaluate_image, read_labels, PCK_GROUPS};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab eval-parse`.
#[derive(clap::Args)]
pub struct Args {
    /// Detector model: the PARSE JSON or a binary `.skbd` model.
    #[arg(long)]
    model: PathBuf,
    /// PARSE folder holding `labels.csv` and `images/`.
    #[arg(long)]
    data: PathBuf,
    /// First image number evaluated (the test split is 101..=305).
    #[arg(long, default_value_t = 101)]
    first: usize,
    /// Last image number evaluated.
    #[arg(long, default_value_t = 305)]
    last: usize,
    /// PCK tolerance as a fraction of the longer side of the ground-truth box.
    #[arg(long, default_value_t = 0.1)]
    alpha: f64,
    /// Print one line per image.
    #[arg(long)]
    verbose: bool,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let model = Model::load_any(&a.model)?;
    let labels = read_labels(&a.data.join("labels.csv"))?;
    let wanted: Vec<_> = labels
        .iter()
        .filter(|l| {
            let n: Option<usize> = l.image.trim_start_matches("im").split('.').next().and_then(|s| s.parse().ok());
            n.is_some_and(|n| n >= a.first && n <= a.last)
        })
        .collect();
    if wanted.is_empty() {
        return Err(CliError(format!("no labelled images numbered {}..={} in {}", a.first, a.last, a.data.display())));
    }
    let mut hits = [0usize; NUM_PARSE_JOINTS];
    let mut times = Vec::with_capacity(wanted.len());
    let mut missed = 0;
    for l in &wanted {
        let img = load_rgb_image(&a.data.join("images").join(&l.image))?;
        let t0 = Instant::now();
        let (ok, score) = evaluate_image(&img.view(), &model, &l.joints, a.alpha)?;
        let dt = t0.elapsed().as_secs_f64() * 1e3;
        times.push(dt);
        missed += usize::from(score.is_none());
        for j in 0..NUM_PARSE_JOINTS {
            hits[j] += usize::from(ok[j]);
        }
        if a.verbose {
            let n = ok.iter().filter(|&&b| b).count();
            println!(
                "{} {}x{} {:.0} ms score {} correct {n}/14",
                l.image,
                img.width(),
                img.height(),
                dt,
                score.map_or("none".into(), |s| format!("{s:.3}"))
            );
        }
    }
    let n = wanted.len() as f64;
    let pck = |j: usize| 100.0 * hits[j] as f64 / n;
    println!(
        "PARSE PCK@{} with the ground-truth box: {} images (im{:04}..im{:04}), model {}",
        a.alpha,
        wanted.len(),
        a.first,
        a.last,
        a.model.display()
    );
    println!(
        "per joint: {}",
        (0..NUM_PARSE_JOINTS).map(|j| format!("{} {:.1}", PARSE_JOINT_NAMES[j], pck(j))).collect::<Vec<_>>().join(", ")
    );
    let header: Vec<String> = PCK_GROUPS.iter().map(|(g, _)| format!("{g:>8}")).collect();
    println!("{} {:>8}", header.join(" "), "mean");
    let vals: Vec<String> =
        PCK_GROUPS.iter().map(|(_, [l, r])| format!("{:>8.1}", (pck(*l) + pck(*r)) / 2.0)).collect();
    let mean = (0..NUM_PARSE_JOINTS).map(pck).sum::<f64>() / NUM_PARSE_JOINTS as f64;
    println!("{} {:>8.1}", vals.join(" "), mean);
    times.sort_by(f64::total_cmp);
    let total: f64 = times.iter().sum();
    println!(
        "time per image: mean {:.0} ms, median {:.0} ms, max {:.0} ms ({} threads); {missed} images without an overlapping candidate",
        total / n,
        times[times.len() / 2],
        times[times.len() - 1],
        rayon::current_num_threads()
    );
    Ok(())
}
