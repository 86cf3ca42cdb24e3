//! `run --format glb,fbx,usd`: which rigged-body files a run writes (`body.glb`, `body.fbx`,
//! `body.usda`) and writing them into the run's staging folder.

use std::path::PathBuf;

use sketchbody::body::rig::RigScene;
use sketchbody::body::rig::RiggedMesh;
use sketchbody::export::fbx::write_fbx;
use sketchbody::export::gltf::write_glb;
use sketchbody::export::usd::write_usda;

/// A rigged-body file format of `--format`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Binary glTF 2.0: `body.glb`.
    Glb,
    /// Binary FBX 7.4: `body.fbx` (texture embedded).
    Fbx,
    /// USD text layer (UsdSkel): `body.usda` (texture read from `body_texture.png`).
    Usd,
}

impl Format {
    /// The file a run writes for this format.
    pub fn file_name(self) -> &'static str {
        match self {
            Format::Glb => "body.glb",
            Format::Fbx => "body.fbx",
            Format::Usd => "body.usda",
        }
    }
}

/// Writes each of `formats` once (first mention first) as `path(file name)`, the scene built
/// from `mesh`, with `texture_png` as the texture (the USD layer names `body_texture.png`,
/// which the caller writes beside it).
pub fn write_rigged(
    formats: &[Format],
    path: impl Fn(&str) -> PathBuf,
    mesh: &RiggedMesh,
    scene: &RigScene,
    texture_png: Option<&[u8]>,
) -> sketchbody::Result<()> {
    for (i, &f) in formats.iter().enumerate() {
        if formats[..i].contains(&f) {
            continue;
        }
        let p = path(f.file_name());
        match f {
            Format::Glb => write_glb(&p, mesh, scene, texture_png)?,
            Format::Fbx => write_fbx(&p, mesh, scene, texture_png)?,
            Format::Usd => write_usda(&p, mesh, scene, texture_png.is_some())?,
        }
    }
    Ok(())
}

/// The file names of `formats`, each once, comma-separated.
pub fn file_list(formats: &[Format]) -> String {
    let mut names: Vec<&str> = Vec::new();
    for f in formats {
        if !names.contains(&f.file_name()) {
            names.push(f.file_name());
        }
    }
    names.join(", ")
}
