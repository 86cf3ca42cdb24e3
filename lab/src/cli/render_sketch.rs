//! `sketchbody-lab render-sketch --out X.png`: one synthetic concept sketch, with its ground truth
//! (`X.json`) and meshes (`X.mesh`, and with `--obj` also `X_rest.obj` / `X_posed.obj`) beside it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rand::SeedableRng;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::render::sketch::truth::write_sample;
use sketchbody::render::sketch::{CameraAngles, MocapLibrary, SketchRenderer, SketchRequest, SketchStyle};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab render-sketch`.
#[derive(clap::Args)]
pub struct Args {
    /// Output image; must end in `.png`. The ground truth goes beside it.
    #[arg(long)]
    out: PathBuf,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Gender: f or m (random when omitted).
    #[arg(long)]
    gender: Option<String>,
    /// Image size: N (square) or WxH, pixels, 1..=4096.
    #[arg(long, default_value = "512")]
    size: String,
    /// Folder of mocap clips (default: $SKB_SHARED_DATA/mocap/deepmimic or
    /// ../shared/data/mocap/deepmimic; procedural poses when neither exists).
    #[arg(long)]
    mocap: Option<PathBuf>,
    /// Clean style (no costume, hair, shading or clutter) instead of a random one.
    #[arg(long)]
    clean: bool,
    /// Also write the rest and posed meshes as OBJ.
    #[arg(long)]
    obj: bool,
    /// Camera yaw in degrees, ±180 (0 a front view, 180 a back view, −90 a left profile), pitch
    /// and roll 0, instead of random near-frontal angles.
    #[arg(long, allow_negative_numbers = true)]
    yaw: Option<f64>,
    /// Hair style (none, short, long, spiky, bun, ponytail) instead of the style's own (a
    /// random style is then drawn from the seed).
    #[arg(long)]
    hair: Option<String>,
}

/// Parses `N` or `WxH`.
pub fn parse_size(s: &str) -> Result<(usize, usize), CliError> {
    let bad = || CliError(format!("--size {s:?}: expected N or WxH with 1..=4096 pixels a side"));
    let (w, h) = match s.split_once(['x', 'X']) {
        Some((w, h)) => (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?),
        None => {
            let n: usize = s.trim().parse().map_err(|_| bad())?;
            (n, n)
        }
    };
    if !(1..=4096).contains(&w) || !(1..=4096).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

/// Loads the mocap library from `dir`, or from the default places; `None` (procedural poses)
/// with a note on stderr when no default exists.
pub fn load_mocap(dir: Option<&Path>) -> Result<Option<MocapLibrary>, CliError> {
    if let Some(d) = dir {
        return Ok(Some(MocapLibrary::load_dir(d)?));
    }
    let base =
        std::env::var_os("SKB_SHARED_DATA").map(PathBuf::from).unwrap_or_else(|| PathBuf::from("../shared/data"));
    let d = base.join("mocap/deepmimic");
    if d.is_dir() {
        return Ok(Some(MocapLibrary::load_dir(&d)?));
    }
    eprintln!("sketchbody: no mocap folder at {}; using procedural poses (pass --mocap DIR)", d.display());
    Ok(None)
}

/// The renderer over the embedded body model.
pub fn renderer(mocap: Option<&Path>) -> Result<SketchRenderer, CliError> {
    Ok(SketchRenderer::new(Arc::new(BodyModel::embedded()?), load_mocap(mocap)?)?)
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let (width, height) = parse_size(&a.size)?;
    let gender = a.gender.as_deref().map(Gender::parse).transpose()?;
    if a.out.extension().is_none_or(|e| e != "png") {
        return Err(CliError(format!("--out {}: must end in .png", a.out.display())));
    }
    let dir = match a.out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(CliError(format!("{}: output folder does not exist", dir.display())));
    }
    let stem = a.out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let r = renderer(a.mocap.as_deref())?;
    let mut req =
        SketchRequest { gender, style: a.clean.then(SketchStyle::default), ..SketchRequest::random(a.seed, width) };
    if let Some(hair) = a.hair.as_deref().map(crate::train_detector::parse_hair).transpose()?.flatten() {
        let mut style =
            req.style.unwrap_or_else(|| SketchStyle::random(&mut rand_chacha::ChaCha8Rng::seed_from_u64(a.seed)));
        style.hair = hair;
        req.style = Some(style);
    }
    if let Some(yaw_deg) = a.yaw {
        req.camera = Some(CameraAngles { yaw_deg, pitch_deg: 0.0, roll_deg: 0.0 });
    }
    let req = SketchRequest { width, height, ..req };
    let t0 = std::time::Instant::now();
    let s = r.render(&req)?;
    let dt = t0.elapsed().as_secs_f64();
    write_sample(&dir, &stem, &s)?;
    if a.obj {
        let faces = r.model().faces();
        sketchbody::export::obj::write_obj(&dir.join(format!("{stem}_rest.obj")), &s.rest_vertices, faces, None)?;
        sketchbody::export::obj::write_obj(&dir.join(format!("{stem}_posed.obj")), &s.posed_vertices, faces, None)?;
    }
    println!(
        "{}: {} {}x{} pose {} in {:.0} ms",
        a.out.display(),
        s.truth.gender,
        width,
        height,
        s.truth.pose_source,
        dt * 1000.0
    );
    Ok(())
}
