//! Detector speed on one image: median wall time and process CPU time (all threads) of N calls
//! of `detect`, in one process, plus the best detection (score, part placements) so that runs of
//! two engine versions can be compared.
//!
//! Usage: cargo run --release --example detect_speed -- MODEL IMAGE [RUNS] [default|all|fMIN|MIN_CELL] [LEVELS]
//! `default` uses the documented sketch search (`DetectOptions::default()`), `all` every
//! pyramid level, `fMIN` figures of at least MIN × the shorter side (e.g. `f0.25`), a number
//! every level with cells of at least that many px. LEVELS: levels per octave (`model` = the
//! model's own, 10; default: that of `DetectOptions::default()`).

use sketchbody::detect::{conv, detect, prepare_image, pyramid, tree, DetectOptions, Model, SearchScales};
use sketchbody::image::load_rgb_image;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: detect_speed MODEL IMAGE [RUNS] [default|all|fMIN|MIN_CELL] [LEVELS|model]");
        std::process::exit(2);
    }
    let model = Model::load_any(std::path::Path::new(&args[1])).expect("model");
    let img = load_rgb_image(std::path::Path::new(&args[2])).expect("image");
    let runs: usize = args.get(3).map_or(5, |s| s.parse().expect("RUNS"));
    let mode = args.get(4).map_or("default", String::as_str);
    let mut opts = options(mode);
    match args.get(5).map(String::as_str) {
        None => {}
        Some("model") => opts.levels_per_octave = None,
        Some(n) => opts.levels_per_octave = Some(n.parse().expect("LEVELS")),
    }
    let levels = opts.levels_per_octave.unwrap_or(model.interval);
    let (mut walls, mut cpus, mut busiest) = (Vec::new(), Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..runs {
        let w0 = worker_cpu();
        let (t0, c0) = (std::time::Instant::now(), process_cpu());
        let d = detect(&img.view(), &model, &opts);
        walls.push(t0.elapsed().as_secs_f64() * 1e3);
        cpus.push((process_cpu() - c0) * 1e3);
        busiest.push(worker_cpu().iter().zip(&w0).map(|(a, b)| (a - b) * 1e3).fold(0.0, f64::max));
        last = Some(d);
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "detect {}x{} {mode}, {levels} levels per octave: median wall {:.1} ms, median CPU {:.1} ms (all threads) over {runs} runs, {} threads",
        img.width(),
        img.height(),
        med(&mut walls),
        med(&mut cpus),
        rayon::current_num_threads()
    );
    // The work runs on the pool's threads (this thread only waits): the busiest one's CPU time
    // is the wall time the detection needs on idle cores, whatever the machine's load.
    println!(
        "busiest pool thread: median CPU {:.1} ms per detect (the wall time on idle cores, ±rayon's idle spinning)",
        med(&mut busiest)
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
    compare_kernels(&model, &img, &opts);
}

/// One thread, the levels `opts` searches: the DP with the optimised kernels vs the plain
/// reference kernels (the engine before the speed work): thread CPU time and whether the best
/// candidate of every level is the same.
fn compare_kernels(model: &Model, img: &sketchbody::image::RgbImage, opts: &DetectOptions) {
    let (planes, _) = prepare_image(&img.view(), opts.max_side).expect("image");
    let (lo, hi) = opts.search.cell_range(model, planes.width, planes.height);
    let (lo, hi) = (lo.max(opts.min_cell_px), hi.min(opts.max_cell_px));
    let (padx, pady) = model.padding();
    let interval = opts.levels_per_octave.unwrap_or(model.interval);
    let pyr = pyramid::build(&planes, model.sbin, interval, padx, pady, lo, hi).expect("pyramid");
    let levels: Vec<_> = pyr.levels.iter().filter(|l| l.cell_px <= hi).collect();
    let mut cpu = [0f64; 2];
    let mut best: [Vec<tree::Candidate>; 2] = [Vec::new(), Vec::new()];
    // A one-thread pool, so that every parallel loop inside runs on the timed thread.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
    for (i, k) in [tree::Kernels::Optimised, tree::Kernels::Reference].into_iter().enumerate() {
        pool.install(|| {
            let c0 = thread_cpu();
            for l in &levels {
                best[i].extend(tree::detect_level_with(model, l, (padx, pady), f64::NEG_INFINITY, 1, &|_| true, k));
            }
            cpu[i] = (thread_cpu() - c0) * 1e3;
        });
    }
    // The filter responses alone, same pool.
    let mut conv = [0f64; 2];
    pool.install(|| {
        for (i, reference) in [false, true].into_iter().enumerate() {
            let c0 = thread_cpu();
            for l in &levels {
                let r = if reference {
                    conv::responses_reference(&l.feat, &model.filters)
                } else {
                    conv::responses(&l.feat, &model.filters)
                };
                std::hint::black_box(r);
            }
            conv[i] = (thread_cpu() - c0) * 1e3;
        }
    });
    println!(
        "one thread, filter responses alone: optimised {:.0} ms, reference {:.0} ms CPU ({:.2}x); the rest of the DP (distance transforms, messages, back-tracking): optimised {:.0} ms, reference {:.0} ms ({:.2}x)",
        conv[0],
        conv[1],
        conv[1] / conv[0],
        cpu[0] - conv[0],
        cpu[1] - conv[1],
        (cpu[1] - conv[1]) / (cpu[0] - conv[0])
    );
    let same = best[0].len() == best[1].len()
        && best[0].iter().zip(&best[1]).all(|(a, b)| {
            (a.score - b.score).abs() <= 1e-4 * b.score.abs().max(1.0)
                && a.parts.iter().zip(&b.parts).all(|(p, q)| (p.x1, p.y1, p.mixture) == (q.x1, q.y1, q.mixture))
        });
    let max_rel = best[0]
        .iter()
        .zip(&best[1])
        .map(|(a, b)| (a.score - b.score).abs() / b.score.abs().max(1.0))
        .fold(0.0, f64::max);
    println!(
        "one thread, {} levels (cells {:.2}..{:.2} px), DP incl. filter responses: optimised {:.0} ms, reference {:.0} ms CPU ({:.2}x); best per level identical: {same} (max relative score difference {max_rel:.1e})",
        levels.len(),
        levels.first().map_or(0.0, |l| l.cell_px),
        levels.last().map_or(0.0, |l| l.cell_px),
        cpu[0],
        cpu[1],
        cpu[1] / cpu[0]
    );
}

/// CPU time of this thread, seconds.
fn thread_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn options(mode: &str) -> DetectOptions {
    match mode {
        "default" => DetectOptions::default(),
        "all" => DetectOptions { search: SearchScales::All, ..Default::default() },
        f if f.starts_with('f') => DetectOptions {
            search: SearchScales::FigureFraction { min: f[1..].parse().expect("fMIN"), max: 1.0 },
            ..Default::default()
        },
        c => {
            DetectOptions { search: SearchScales::All, min_cell_px: c.parse().expect("MIN_CELL"), ..Default::default() }
        }
    }
}

/// CPU time of each thread of the global rayon pool, seconds (read on every thread at once).
fn worker_cpu() -> Vec<f64> {
    rayon::broadcast(|_| thread_cpu())
}

/// CPU time of this process (all threads), seconds.
fn process_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
