//! `sketchbody-lab shape-floor DATASET [--dims 4,10]`: the floor of the shape fit on a dataset:
//! each sample's true rest mesh projected (least squares) onto its true gender's shape space of
//! the body model at a few dimension counts, scored as `eval` scores a fit (rest AED centred and
//! at the true height, over the true height), beside the gender's mean shape. No fit reaches
//! below its dimension count's row; a floor near the mean shape's row says the model cannot
//! express the set's bodies.
//!
//! `--axes xy` (or `x`) fits only those coordinates of the rest mesh, and `--axes outline` only
//! the offsets across the true rest mesh's front-view contour: what a front view could at best
//! tell (issue 47, "where the limit is"): heights and widths, not depths; `--axes
//! outline+side` adds a side view's contour (a turnaround, issue 48). With less than every
//! coordinate the least squares may leave a component's depth free, so `--noise-mm S` makes it
//! the posterior mean under the space's prior (each weight's variance) with an error of S mm per
//! fitted value; 0 (the default) is plain least squares.

use std::path::PathBuf;

use sketchbody::body::rig::vertex_normals;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::render::sketch::truth::{parse_mesh, GroundTruth};
use sketchbody_lab::eval::metrics::{aed, centred, scale_to_height};
use sketchbody_lab::eval::score::dataset_samples;

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab shape-floor`.
#[derive(clap::Args)]
pub struct Args {
    /// Dataset folder (make-dataset or scripts/make-blender-set.sh layout).
    dataset: PathBuf,
    /// Dimension counts to project onto (comma-separated; each at most the space's components).
    #[arg(long, value_delimiter = ',', default_value = "4,10")]
    dims: Vec<usize>,
    /// Coordinates of the rest mesh the projection fits: `xyz` (all), `xy` (every vertex's
    /// height and width), `x` (widths only), `outline` (the front-view contour's offsets),
    /// `outline+side` (the front and side views' contours).
    #[arg(long, default_value = "xyz")]
    axes: String,
    /// Error per fitted coordinate (mm) of the posterior-mean projection; 0 = least squares.
    #[arg(long, default_value_t = 0.0)]
    noise_mm: f64,
}

/// Which coordinates of the true rest mesh a projection fits (`--axes`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Axes {
    /// Every coordinate: the model's own floor.
    Xyz,
    /// Heights and widths (x, y) of every vertex: more than a front view shows.
    Xy,
    /// Widths (x) only.
    X,
    /// The front outline: at each vertex on the true rest mesh's front-view contour (its normal
    /// within [`OUTLINE_MAX_NZ`] of the picture plane), the offset along the contour's 2-D normal
    /// only, as a silhouette tells it (occlusion ignored).
    Outline,
    /// The front outline and a side view's (seen along x: the contour where the normal is
    /// within [`OUTLINE_MAX_NZ`] of the y-z plane, offsets along its y-z direction), as a
    /// turnaround's front and side drawings tell it (issue 48).
    OutlineSide,
}

/// Largest |n · view direction| of a unit vertex normal counted as on a view's contour.
const OUTLINE_MAX_NZ: f64 = 0.2;

/// The contour rows of the view along axis `view` (0 = x, 2 = z): each vertex whose unit normal
/// `n` has |n[view]| ≤ [`OUTLINE_MAX_NZ`], with the direction of `n` with that component removed.
fn contour_rows(normals: &[[f32; 3]], view: usize) -> impl Iterator<Item = (usize, [f64; 3])> + '_ {
    normals.iter().enumerate().filter(move |(_, n)| (n[view] as f64).abs() <= OUTLINE_MAX_NZ).map(move |(i, n)| {
        let mut d = n.map(|c| c as f64);
        d[view] = 0.0;
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        (i, d.map(|c| c / l))
    })
}

/// The constraints a projection fits: (vertex, unit direction) pairs, each asking the model's
/// vertex to match the truth's along the direction.
fn constraints(axes: Axes, rest: &[[f32; 3]], faces: &[[u32; 4]]) -> Vec<(usize, [f64; 3])> {
    let unit = |c: usize| {
        let mut d = [0.0; 3];
        d[c] = 1.0;
        d
    };
    let per_vertex = |cs: &[usize]| (0..rest.len()).flat_map(|i| cs.iter().map(move |&c| (i, unit(c)))).collect();
    match axes {
        Axes::Xyz => per_vertex(&[0, 1, 2]),
        Axes::Xy => per_vertex(&[0, 1]),
        Axes::X => per_vertex(&[0]),
        Axes::Outline => contour_rows(&vertex_normals(rest, faces), 2).collect(),
        Axes::OutlineSide => {
            let normals = vertex_normals(rest, faces);
            contour_rows(&normals, 2).chain(contour_rows(&normals, 0)).collect()
        }
    }
}

/// The weights of `space`'s first `dims` components that best meet `rows` for the true rest
/// mesh `rest`: least squares, or the posterior mean under the space's prior (each weight's
/// variance) when `noise_m` > 0 (the error of each constraint, metres).
fn project_rows(
    space: &sketchbody::body::ShapeSpace,
    rest: &[[f32; 3]],
    dims: usize,
    rows: &[(usize, [f64; 3])],
    noise_m: f64,
) -> Result<Vec<f64>, CliError> {
    let mean = space.mean();
    let basis: Vec<&[f32]> = (0..dims)
        .map(|k| space.basis_vector(k).ok_or_else(|| CliError(format!("the space has no component {k}"))))
        .collect::<Result<_, _>>()?;
    let mut g = nalgebra::DMatrix::<f64>::zeros(dims, dims);
    let mut b = nalgebra::DVector::<f64>::zeros(dims);
    let mut row = vec![0.0f64; dims];
    for &(i, d) in rows {
        let target: f64 = (0..3).map(|c| d[c] * (rest[i][c] as f64 - mean[i][c] as f64)).sum();
        for (r, bk) in row.iter_mut().zip(&basis) {
            *r = (0..3).map(|c| d[c] * bk[3 * i + c] as f64).sum();
        }
        for k in 0..dims {
            b[k] += row[k] * target;
            for l in 0..dims {
                g[(k, l)] += row[k] * row[l];
            }
        }
    }
    if noise_m > 0.0 {
        for k in 0..dims {
            g[(k, k)] += noise_m * noise_m / space.variances()[k];
        }
    }
    let w = g
        .cholesky()
        .ok_or_else(|| CliError("the projection's normal equations are singular (try --noise-mm)".into()))?
        .solve(&b);
    Ok(w.iter().copied().collect())
}

/// The three AEDs of a rest estimate against the truth: centred; scaled to the true height; and
/// scaled to the true height, then centred (what `run-dataset --true-height` is scored by).
fn rest_aeds(reference: &[[f64; 3]], estimate: &[[f64; 3]], height: f64) -> Result<[f64; 3], CliError> {
    let at_height = scale_to_height(reference, estimate, height)?;
    Ok([
        aed(&centred(reference), &centred(estimate), height)?,
        aed(reference, &at_height, height)?,
        aed(&centred(reference), &centred(&at_height), height)?,
    ])
}

fn to_f64(v: &[[f32; 3]]) -> Vec<[f64; 3]> {
    v.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect()
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let model = BodyModel::embedded()?;
    let axes = match a.axes.as_str() {
        "xyz" => Axes::Xyz,
        "xy" => Axes::Xy,
        "x" => Axes::X,
        "outline" => Axes::Outline,
        "outline+side" => Axes::OutlineSide,
        other => return Err(CliError(format!("--axes {other}: expected xyz, xy, x, outline or outline+side"))),
    };
    if !(a.noise_mm.is_finite() && a.noise_mm >= 0.0) {
        return Err(CliError(format!("--noise-mm {}: expected a finite value ≥ 0", a.noise_mm)));
    }
    let stems = dataset_samples(&a.dataset)?;
    if stems.is_empty() {
        return Err(CliError(format!("{}: no samples (STEM.json with STEM.mesh)", a.dataset.display())));
    }
    // Per row (the mean shape, then each dimension count): sums of the two AEDs.
    let mut sums = vec![[0.0f64; 3]; 1 + a.dims.len()];
    for stem in &stems {
        let jp = a.dataset.join(format!("{stem}.json"));
        let text = std::fs::read_to_string(&jp).map_err(|e| CliError(format!("{}: {e}", jp.display())))?;
        let truth = GroundTruth::from_json(&text, &jp.display().to_string())?;
        let mp = a.dataset.join(format!("{stem}.mesh"));
        let bytes = std::fs::read(&mp).map_err(|e| CliError(format!("{}: {e}", mp.display())))?;
        let rest = parse_mesh(&bytes, &mp.display().to_string())?.0;
        let space = model.space(Gender::parse(&truth.gender)?);
        let rows = constraints(axes, &rest, model.faces());
        let reference = to_f64(&rest);
        let mean = rest_aeds(&reference, &to_f64(space.mean()), truth.height_m)?;
        let mut row = vec![mean];
        for &d in &a.dims {
            let w = if axes == Axes::Xyz && a.noise_mm == 0.0 {
                space.project(&rest, d)?
            } else {
                project_rows(space, &rest, d, &rows, a.noise_mm / 1000.0)?
            };
            let shape = space.synthesize(&w)?;
            row.push(rest_aeds(&reference, &to_f64(&shape.vertices), truth.height_m)?);
        }
        for (s, r) in sums.iter_mut().zip(&row) {
            for (a, b) in s.iter_mut().zip(r) {
                *a += b;
            }
        }
    }
    let n = stems.len() as f64;
    println!("{} samples of {}; axes {}, noise {} mm", stems.len(), a.dataset.display(), a.axes, a.noise_mm);
    println!("| shape | rest centred | × mean | rest at height | centred at height | × mean |");
    println!("|---|---:|---:|---:|---:|---:|");
    let (mean_centred, mean_at_height) = (sums[0][0] / n, sums[0][2] / n);
    let labels =
        std::iter::once("mean shape".to_string()).chain(a.dims.iter().map(|d| format!("truth projected, {d} dims")));
    for (label, s) in labels.zip(&sums) {
        println!(
            "| {label} | {:.4} | {:.3} | {:.4} | {:.4} | {:.3} |",
            s[0] / n,
            s[0] / n / mean_centred,
            s[1] / n,
            s[2] / n,
            s[2] / n / mean_at_height
        );
    }
    Ok(())
}
