//! Detector speed on one image: median wall time and process CPU time (all threads) of N calls
//! of `detect`, in one process, plus the best detection (score, part placements) so that runs of
//! two engine versions can be compared.
//!
//! Usage: cargo run --release --example detect_speed -- MODEL IMAGE [RUNS] [default|all|fMIN|MIN_CELL]
//! `default` uses the documented sketch search range (`DetectOptions::default()`), `all` every
//! pyramid level, `fMIN` figures of at least MIN × the shorter side (e.g. `f0.5`), a number
//! every level with cells of at least that many px.

use sketchbody::detect::{detect, DetectOptions, Model, SearchScales};
use sketchbody::image::load_rgb_image;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: detect_speed MODEL IMAGE [RUNS] [default|all|fMIN|MIN_CELL]");
        std::process::exit(2);
    }
    let model = Model::load_any(std::path::Path::new(&args[1])).expect("model");
    let img = load_rgb_image(std::path::Path::new(&args[2])).expect("image");
    let runs: usize = args.get(3).map_or(5, |s| s.parse().expect("RUNS"));
    let mode = args.get(4).map_or("default", String::as_str);
    let opts = options(mode);
    let (mut walls, mut cpus) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..runs {
        let (t0, c0) = (std::time::Instant::now(), process_cpu());
        let d = detect(&img.view(), &model, &opts);
        walls.push(t0.elapsed().as_secs_f64() * 1e3);
        cpus.push((process_cpu() - c0) * 1e3);
        last = Some(d);
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "detect {}x{} {mode}: median wall {:.1} ms, median CPU {:.1} ms (all threads) over {runs} runs, {} threads",
        img.width(),
        img.height(),
        med(&mut walls),
        med(&mut cpus),
        rayon::current_num_threads()
    );
    match last.expect("runs ≥ 1") {
        Ok(d) => {
            let b = d.best();
            println!("best score {:.6}, {} detections", b.score, d.all.len());
            let parts: Vec<String> = b.parts.iter().map(|p| format!("{:.1},{:.1},{}", p.x1, p.y1, p.mixture)).collect();
            println!("parts {}", parts.join(" "));
        }
        Err(e) => println!("no detection: {e}"),
    }
}

fn options(mode: &str) -> DetectOptions {
    match mode {
        "default" => DetectOptions::default(),
        "all" => DetectOptions { search: SearchScales::All, ..Default::default() },
        f if f.starts_with('f') => {
            DetectOptions { search: SearchScales::FigureFraction { min: f[1..].parse().expect("fMIN"), max: 1.0 }, ..Default::default() }
        }
        c => DetectOptions { search: SearchScales::All, min_cell_px: c.parse().expect("MIN_CELL"), ..Default::default() },
    }
}

/// CPU time of this process (all threads), seconds.
fn process_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
