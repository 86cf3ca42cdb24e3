//! `run --format glb,fbx,usd --units m|cm --up y|z`: which rigged-body files a run writes
//! (`body.glb`, `body.fbx`, `body.usda`), the unit and up axis of the FBX and USD files, and
//! writing them into the run's staging folder.

use std::path::PathBuf;

use sketchbody::body::rig::RigScene;
use sketchbody::body::rig::RiggedMesh;
use sketchbody::export::fbx::write_fbx;
use sketchbody::export::frame::{ExportFrame, Units, UpAxis};
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

/// Parses `--units` (`m` or `cm`); the error names the value and the choices.
pub fn parse_units(s: &str) -> Result<Units, String> {
    Units::parse(s).map_err(|e| e.to_string())
}

/// Parses `--up` (`y` or `z`); the error names the value and the choices.
pub fn parse_up(s: &str) -> Result<UpAxis, String> {
    UpAxis::parse(s).map_err(|e| e.to_string())
}

/// Writes each of `formats` once (first mention first) as `path(file name)`, the scene built
/// from `mesh`, with `texture_png` as the texture (the USD layer names `body_texture.png`,
/// which the caller writes beside it); FBX and USD in `frame`'s unit and axes, the GLB always
/// in metres, Y up (glTF's own).
pub fn write_rigged(
    formats: &[Format],
    path: impl Fn(&str) -> PathBuf,
    mesh: &RiggedMesh,
    scene: &RigScene,
    texture_png: Option<&[u8]>,
    frame: &ExportFrame,
) -> sketchbody::Result<()> {
    for (i, &f) in formats.iter().enumerate() {
        if formats[..i].contains(&f) {
            continue;
        }
        let p = path(f.file_name());
        match f {
            Format::Glb => write_glb(&p, mesh, scene, texture_png)?,
            Format::Fbx => write_fbx(&p, mesh, scene, texture_png, frame)?,
            Format::Usd => write_usda(&p, mesh, scene, texture_png.is_some(), frame)?,
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
