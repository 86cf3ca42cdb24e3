//! `sketchbody body`: a body of the embedded shape model, optionally posed to a 3-D joints file,
//! written as .glb (MakeHuman's 53-bone rig, one posed scene) or .obj, with an optional preview PNG;
//! the outputs replace their targets together or not at all (`fsutil::OutputSet`).

use std::path::PathBuf;

use sketchbody::body::ik::{solve, IkOptions, Pose};
use sketchbody::body::rig::RigScene;
use sketchbody::body::rig::RiggedMesh;
use sketchbody::body::skin::{skin, SkinMethod};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::export::gltf::write_glb;
use sketchbody::export::joints::load_joints3_json;
use sketchbody::export::obj::write_obj;
use sketchbody::fsutil::OutputSet;
use sketchbody::image::save_png;
use sketchbody::pipeline::shape_keys::ShapeOrigin;
use sketchbody::render::preview::preview;

use crate::rig_args::RigArgs;
use crate::CliError;

/// Arguments of `sketchbody body`.
#[derive(clap::Args)]
pub struct Args {
    /// Shape space: f (female) or m (male).
    #[arg(long)]
    gender: String,
    /// PCA shape weights, comma-separated (metres along unit basis vectors; missing trailing
    /// weights are 0, none gives the mean shape).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    weights: Vec<f64>,
    /// 3-D joints file to pose the body to (JSON, see docs/formats.md); rest pose without it.
    #[arg(long)]
    pose: Option<PathBuf>,
    /// Scale bones so the joints land exactly on the pose file's joints.
    #[arg(long)]
    retarget: bool,
    /// Dual-quaternion skinning instead of linear blend skinning (for OBJ and the preview).
    #[arg(long)]
    dqs: bool,
    /// Output: .glb (rest mesh on the rig, posed, one scene) or .obj (posed mesh).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    rig: RigArgs,
    /// Also write front and side views of the posed mesh as a PNG.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// Side of each preview view, pixels (1..=4096).
    #[arg(long, default_value_t = 512)]
    preview_size: usize,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let ext = a.out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("glb" | "obj")) {
        return Err(CliError(format!("{}: output must end in .glb or .obj", a.out.display())));
    }
    let gender = Gender::parse(&a.gender)?;
    let rig_options = a.rig.options()?;
    let model = BodyModel::embedded()?;
    let mesh = RiggedMesh::from_model(&model, gender, &a.weights)?;
    let pose = match &a.pose {
        Some(p) => solve(&mesh.joints, &load_joints3_json(p)?, &IkOptions { retarget: a.retarget })
            .map_err(|e| CliError(format!("{}: {e}", p.display())))?,
        None => Pose::rest(&mesh.joints),
    };
    let method = if a.dqs { SkinMethod::DualQuaternion } else { SkinMethod::Linear };
    let posed = skin(&mesh.vertices, &mesh.weights, &pose, method)?;
    // Render the preview first so that a bad size fails before any file is written.
    let image = match &a.preview {
        Some(_) => Some(preview(&posed, &mesh.triangles(), a.preview_size)?),
        None => None,
    };
    // Every output is staged, then all replace their targets together (or none does).
    let mut outputs = OutputSet::new();
    let out = outputs.stage(&a.out)?;
    if ext.as_deref() == Some("glb") {
        let keys = if a.rig.shape_keys() {
            let origin =
                ShapeOrigin { space: gender.into(), weights: a.weights.clone(), proportions: None, scale: 1.0 };
            origin.keys(&model)?
        } else {
            Vec::new()
        };
        let scene = RigScene::build_with_shape_keys(model.rig(), &mesh, &pose, &rig_options, &keys)?;
        write_glb(&out, &mesh, &scene, None)?;
    } else {
        write_obj(&out, &posed, &mesh.quads, mesh.uvs.as_ref())?;
    }
    if let (Some(p), Some(img)) = (&a.preview, &image) {
        save_png(&img.view(), &outputs.stage(p)?)?;
    }
    outputs.commit()?;
    Ok(())
}
