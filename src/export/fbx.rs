//! Binary FBX 7.4 (.fbx) of the rigged body, the same content as the glTF
//! ([`crate::export::gltf`]): the rest mesh (polygons, normals, UVs) skinned to MakeHuman's
//! 53-bone armature (and any twist bones) with its bind pose, the bones in the body's pose, and the texture embedded
//! (and named `body_texture.png`, the file the CLI writes beside). Units and axes as the
//! [`ExportFrame`] chooses: metres (`UnitScaleFactor` 100, i.e. 1 unit = 100 cm) or centimetres
//! (`UnitScaleFactor` 1); Y up with Z front, or Z up with −Y front; X the third axis
//! (right-handed). docs/formats.md, "body.fbx".
use std::path::Path;

use crate::body::rig::RigScene;
use crate::body::rig::RiggedMesh;
use crate::error::Result;
use crate::export::frame::ExportFrame;
use crate::export::rigged::check_scene;
use crate::fsutil::write_atomic;

pub mod anim;
pub mod blend;
pub mod node;
pub mod scene;

/// The .fbx bytes of `scene` (built by [`RigScene::build`] from `mesh`), with faces and UVs
/// from `mesh` and, when given, `texture_png` (PNG bytes) as the diffuse texture, in `frame`'s
/// unit and axes ([`ExportFrame::default`]: metres, Y up). Errors: the mesh is invalid or its
/// vertex count differs from the scene's; a non-finite vertex; the file would exceed FBX 7.4's
/// 4 GiB offsets.
pub fn fbx_bytes(
    mesh: &RiggedMesh,
    scene: &RigScene,
    texture_png: Option<&[u8]>,
    frame: &ExportFrame,
) -> Result<Vec<u8>> {
    check_scene(mesh, scene)?;
    node::file_bytes(&scene::document(mesh, scene, texture_png, frame))
}

/// Writes [`fbx_bytes`] to `path` atomically (an error leaves nothing behind).
pub fn write_fbx(
    path: &Path,
    mesh: &RiggedMesh,
    scene: &RigScene,
    texture_png: Option<&[u8]>,
    frame: &ExportFrame,
) -> Result<()> {
    write_atomic(path, &fbx_bytes(mesh, scene, texture_png, frame)?)
}
