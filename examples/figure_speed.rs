//! Single-figure detector speed per backend on one image: `detect_figure` with the sketch model
//! (`fmp`), BlazePose and `auto`, called in turn (interleaved, so that the machine's load hits
//! all three alike) after one warm-up call each. Prints each backend's median wall time, median
//! process CPU time (all threads) and the ratio of medians to `fmp`, plus the figure found.
//!
//! Usage: cargo run --release --example figure_speed -- IMAGE [RUNS]

use std::time::Instant;

use sketchbody::detect::figure::{Backend, FigureOptions};
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::image::load_rgb_image;
use sketchbody::pipeline::figure::detect_figure;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 2 {
        eprintln!("usage: figure_speed IMAGE [RUNS]");
        std::process::exit(2);
    }
    let img = load_rgb_image(std::path::Path::new(&args[1])).expect("image");
    let runs: usize = args.get(2).map_or(9, |s| s.parse().expect("RUNS"));
    let model = Model::embedded().expect("sketch model");
    let net = LandmarkNet::embedded().expect("landmark network");
    let backends = [Backend::Fmp, Backend::BlazePose, Backend::Auto];
    let mut wall = vec![Vec::new(); backends.len()];
    let mut cpu = vec![Vec::new(); backends.len()];
    for round in 0..=runs {
        for (i, &backend) in backends.iter().enumerate() {
            let options = FigureOptions { backend, ..FigureOptions::default() };
            let (t0, c0) = (Instant::now(), process_cpu());
            let f = detect_figure(&img.view(), &model, &net, &options, None);
            let (w, c) = (t0.elapsed().as_secs_f64() * 1e3, (process_cpu() - c0) * 1e3);
            if round == 0 {
                match f {
                    Ok(f) => println!(
                        "{:<9} figure from {}, confidence {:.3}, presence {:.3}",
                        backend.name(),
                        f.backend.name(),
                        f.confidence,
                        f.presence
                    ),
                    Err(e) => println!("{:<9} {e}", backend.name()),
                }
                continue;
            }
            wall[i].push(w);
            cpu[i].push(c);
        }
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let base = med(&mut wall[0].clone());
    println!(
        "{}x{}, {runs} interleaved runs after a warm-up, {} pool threads:",
        img.width(),
        img.height(),
        rayon::current_num_threads()
    );
    for (i, b) in backends.iter().enumerate() {
        let w = med(&mut wall[i]);
        println!(
            "{:<9} median wall {:7.1} ms  median CPU {:7.1} ms  wall / fmp {:.2}",
            b.name(),
            w,
            med(&mut cpu[i]),
            w / base
        );
    }
}

/// CPU time of this process (all threads), seconds.
fn process_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
