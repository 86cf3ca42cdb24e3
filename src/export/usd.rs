//! USD (UsdSkel) text layer (.usda) of the rigged body, the same content as the glTF
//! ([`crate::export::gltf`]): a `SkelRoot` "body" holding the `Skeleton` (53 joints and any twist bones, their
//! bind transforms in skeleton space and rest transforms relative to their parents), a
//! `SkelAnimation` "pose" (the body's pose as the joints' local translations, rotations and
//! scales, unsampled: a static pose, not a keyed clip) bound as the skeleton's animation
//! source, the `Mesh` (polygons, per-vertex normals, face-varying `st` UVs, 4 joint indices and
//! weights per vertex through `SkelBindingAPI`) and a `UsdPreviewSurface` material reading the
//! texture `body_texture.png` beside the file (a text layer cannot embed it). Units and axes as
//! the [`ExportFrame`] chooses: `metersPerUnit` 1 (metres) or 0.01 (centimetres), `upAxis` "Y"
//! or "Z", every position, normal and transform written in that frame. docs/formats.md,
//! "body.usda".
use std::fmt::Write;
use std::path::Path;

use nalgebra::{Matrix4, UnitQuaternion, Vector3};

use crate::body::rig::{vertex_normals, RiggedMesh};
use crate::body::rig::{PoseAs, RigScene};
use crate::error::Result;
use crate::export::frame::{ExportFrame, UpAxis};
use crate::export::rigged::{bind_transform, check_scene, pose_locals};
use crate::fsutil::write_atomic;

/// The texture file the material reads, relative to the layer (the CLI writes it beside).
pub const TEXTURE_FILE: &str = "body_texture.png";

/// A USD path element for bone name `name`: characters outside `[A-Za-z0-9_]` become `_`, and
/// a leading digit gets a `_` before it (the original names are kept in `jointNames`).
fn path_element(name: &str) -> String {
    let mut s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

/// Each joint's path: its ancestors' path elements and its own, joined by `/`.
fn joint_paths(names: &[String], parents: &[Option<usize>]) -> Vec<String> {
    let mut paths: Vec<String> = Vec::with_capacity(parents.len());
    for (b, parent) in parents.iter().enumerate() {
        let own = path_element(&names[b]);
        paths.push(match *parent {
            Some(p) => format!("{}/{own}", paths[p]),
            None => own,
        });
    }
    paths
}

fn list<T>(items: impl IntoIterator<Item = T>, f: impl Fn(T) -> String) -> String {
    let parts: Vec<String> = items.into_iter().map(f).collect();
    format!("[{}]", parts.join(", "))
}

fn quoted(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// A matrix in USD's row-vector layout (translation in the last row): nalgebra's columns are
/// USD's rows.
fn matrix(m: &Matrix4<f64>) -> String {
    let rows: Vec<String> =
        m.as_slice().chunks(4).map(|r| format!("({}, {}, {}, {})", r[0], r[1], r[2], r[3])).collect();
    format!("( {} )", rows.join(", "))
}

fn quat(q: &UnitQuaternion<f64>) -> String {
    let c = q.quaternion().coords.normalize(); // (i, j, k, w)
    format!("({}, {}, {}, {})", c[3] as f32, c[0] as f32, c[1] as f32, c[2] as f32)
}

fn extent(points: &[[f32; 3]]) -> String {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    format!("[({}, {}, {}), ({}, {}, {})]", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2])
}

/// `points` in `frame` (from metres in the model frame).
fn points_in(points: &[[f32; 3]], frame: &ExportFrame) -> Vec<[f32; 3]> {
    points.iter().map(|&p| frame.point_f32(p)).collect()
}

fn skeleton(out: &mut String, scene: &RigScene, frame: &ExportFrame) {
    let parents = &scene.armature.parents;
    let bones = parents.len();
    let paths = joint_paths(&scene.names, parents);
    let joints = list(&paths, |p| quoted(p));
    let global = |b: usize| frame.global(&bind_transform(scene, b));
    let bind = list(0..bones, |b| matrix(&global(b).to_homogeneous()));
    let rest = list(0..bones, |b| {
        let local = match parents[b] {
            Some(p) => global(p).inverse() * global(b),
            None => global(b),
        };
        matrix(&local.to_homogeneous())
    });
    let _ = write!(
        out,
        r#"    def Skeleton "skeleton" (
        prepend apiSchemas = ["SkelBindingAPI"]
    )
    {{
        uniform token[] joints = {joints}
        uniform token[] jointNames = {names}
        uniform matrix4d[] bindTransforms = {bind}
        uniform matrix4d[] restTransforms = {rest}
"#,
        names = list(&scene.names, |n| quoted(n)),
    );
    if let Some(clip) = &scene.clip {
        let locals: Vec<(Vector3<f64>, UnitQuaternion<f64>)> = pose_locals(scene, &clip.pose)
            .into_iter()
            .enumerate()
            .map(|(b, (t, q))| match parents[b] {
                None => frame.root_local(t, q),
                Some(_) => frame.child_local(t, q),
            })
            .collect();
        if scene.pose_as == PoseAs::Action {
            let _ = writeln!(out, "        rel skel:animationSource = </body/skeleton/{}>", clip.name);
        }
        let _ = write!(
            out,
            r#"
        def SkelAnimation "{name}"
        {{
            uniform token[] joints = {joints}
            float3[] translations = {translations}
            quatf[] rotations = {rotations}
            half3[] scales = {scales}{weights}
        }}
"#,
            name = clip.name,
            translations = list(&locals, |(t, _)| format!("({}, {}, {})", t.x as f32, t.y as f32, t.z as f32)),
            rotations = list(&locals, |(_, q)| quat(q)),
            scales = list(0..bones, |_| "(1, 1, 1)".to_string()),
            weights = animated_weights(scene),
        );
    }
    out.push_str("    }\n\n");
}

/// The animation's blend-shape attributes: every key at weight 0 (empty without keys).
fn animated_weights(scene: &RigScene) -> String {
    let keys = &scene.shape_keys;
    if keys.is_empty() {
        return String::new();
    }
    format!(
        "\n            uniform token[] blendShapes = {}\n            float[] blendShapeWeights = {}",
        list(keys, |k| quoted(&path_element(&k.name))),
        list(keys, |_| "0".to_string())
    )
}

fn mesh_prim(out: &mut String, mesh: &RiggedMesh, scene: &RigScene, frame: &ExportFrame) {
    let mut counts = Vec::with_capacity(mesh.quads.len());
    let mut indices = Vec::with_capacity(mesh.quads.len() * 4);
    let mut uv_indices = Vec::with_capacity(mesh.quads.len() * 4);
    for (f, q) in mesh.quads.iter().enumerate() {
        let n = if q[3] == q[2] { 3 } else { 4 };
        counts.push(n);
        indices.extend_from_slice(&q[..n]);
        if let Some(uv) = &mesh.uvs {
            uv_indices.extend_from_slice(&uv.quads[f][..n]);
        }
    }
    let v3 = |p: &[f32; 3]| format!("({}, {}, {})", p[0], p[1], p[2]);
    let normals: Vec<[f32; 3]> =
        vertex_normals(&scene.rest_vertices, &mesh.quads).into_iter().map(|n| frame.direction_f32(n)).collect();
    let rest = points_in(&scene.rest_vertices, frame);
    let mut joint_indices = Vec::with_capacity(scene.skin.len() * 4);
    let mut joint_weights = Vec::with_capacity(scene.skin.len() * 4);
    for w in &scene.skin {
        for k in 0..w.bones.len() {
            joint_indices.push(if w.weights[k] > 0.0 { w.bones[k] } else { 0 });
            joint_weights.push(w.weights[k]);
        }
    }
    let width = scene.skin.first().map_or(4, |w| w.bones.len());
    let _ = write!(
        out,
        r#"    def Mesh "mesh" (
        prepend apiSchemas = ["SkelBindingAPI", "MaterialBindingAPI"]
    )
    {{
        uniform token subdivisionScheme = "none"
        uniform token orientation = "rightHanded"
        float3[] extent = {extent}
        int[] faceVertexCounts = {counts}
        int[] faceVertexIndices = {indices}
        point3f[] points = {points}
        normal3f[] normals = {normals} (
            interpolation = "vertex"
        )
        int[] primvars:skel:jointIndices = {joint_indices} (
            elementSize = {width}
            interpolation = "vertex"
        )
        float[] primvars:skel:jointWeights = {joint_weights} (
            elementSize = {width}
            interpolation = "vertex"
        )
        matrix4d primvars:skel:geomBindTransform = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1) )
        rel skel:skeleton = </body/skeleton>
        rel material:binding = </body/materials/skin>
"#,
        extent = extent(&rest),
        counts = list(&counts, |c| c.to_string()),
        indices = list(&indices, |i| i.to_string()),
        points = list(&rest, v3),
        normals = list(&normals, v3),
        joint_indices = list(&joint_indices, |i| i.to_string()),
        joint_weights = list(&joint_weights, |w| w.to_string()),
    );
    if let Some(uv) = &mesh.uvs {
        let _ = write!(
            out,
            r#"        texCoord2f[] primvars:st = {coords} (
            interpolation = "faceVarying"
        )
        int[] primvars:st:indices = {uv_indices}
"#,
            coords = list(&uv.coords, |c| format!("({}, {})", c[0], c[1])),
            uv_indices = list(&uv_indices, |i| i.to_string()),
        );
    }
    blend_shapes(out, scene, frame);
    out.push_str("    }\n\n");
}

/// The mesh's blend shapes (one `BlendShape` child per shape key: its displacements of every
/// point, in `frame`) and the binding attributes naming them; nothing without keys.
fn blend_shapes(out: &mut String, scene: &RigScene, frame: &ExportFrame) {
    let keys = &scene.shape_keys;
    if keys.is_empty() {
        return;
    }
    let _ = write!(
        out,
        "        uniform token[] skel:blendShapes = {}\n        rel skel:blendShapeTargets = {}\n",
        list(keys, |k| quoted(&path_element(&k.name))),
        list(keys, |k| format!("</body/mesh/{}>", path_element(&k.name))),
    );
    for k in keys {
        let offsets = list(&points_in(&k.deltas, frame), |p| format!("({}, {}, {})", p[0], p[1], p[2]));
        let _ = write!(
            out,
            "\n        def BlendShape \"{}\"\n        {{\n            uniform vector3f[] offsets = {offsets}\n        }}\n",
            path_element(&k.name)
        );
    }
}

fn material(out: &mut String, textured: bool) {
    let base = "/body/materials/skin";
    let diffuse = if textured {
        format!("color3f inputs:diffuseColor.connect = <{base}/texture.outputs:rgb>")
    } else {
        "color3f inputs:diffuseColor = (0.8, 0.7, 0.65)".to_string()
    };
    let _ = write!(
        out,
        r#"    def Scope "materials"
    {{
        def Material "skin"
        {{
            token outputs:surface.connect = <{base}/surface.outputs:surface>

            def Shader "surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                {diffuse}
                float inputs:metallic = 0
                float inputs:roughness = 0.8
                token outputs:surface
            }}
"#
    );
    if textured {
        let _ = write!(
            out,
            r#"
            def Shader "texture"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @{TEXTURE_FILE}@
                float2 inputs:st.connect = <{base}/uv.outputs:result>
                token inputs:wrapS = "clamp"
                token inputs:wrapT = "clamp"
                float3 outputs:rgb
            }}

            def Shader "uv"
            {{
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }}
"#
        );
    }
    out.push_str("        }\n    }\n");
}

/// The .usda text of `scene` (built by [`RigScene::build`] from `mesh`), with faces and UVs from
/// `mesh`; `textured`: the material reads [`TEXTURE_FILE`] (write it beside the layer),
/// otherwise a plain skin colour; in `frame`'s unit and axes ([`ExportFrame::default`]: metres,
/// Y up). Errors: the mesh is invalid or its vertex count differs from the scene's; a
/// non-finite vertex.
pub fn usda_string(mesh: &RiggedMesh, scene: &RigScene, textured: bool, frame: &ExportFrame) -> Result<String> {
    check_scene(mesh, scene)?;
    let up = match frame.up {
        UpAxis::Y => "Y",
        UpAxis::Z => "Z",
    };
    let mut out = String::new();
    let _ = write!(
        out,
        r#"#usda 1.0
(
    defaultPrim = "body"
    doc = "sketchbody {version}"
    metersPerUnit = {meters}
    upAxis = "{up}"
)

def SkelRoot "body" (
    kind = "component"
)
{{
    float3[] extent = {extent}

"#,
        version = crate::VERSION,
        meters = frame.units.metres(),
        extent = extent(&points_in(&scene.posed_vertices, frame)),
    );
    skeleton(&mut out, scene, frame);
    mesh_prim(&mut out, mesh, scene, frame);
    material(&mut out, textured && mesh.uvs.is_some());
    out.push_str("}\n");
    Ok(out)
}

/// Writes [`usda_string`] to `path` (a `.usda` file) atomically (an error leaves nothing
/// behind).
pub fn write_usda(path: &Path, mesh: &RiggedMesh, scene: &RigScene, textured: bool, frame: &ExportFrame) -> Result<()> {
    write_atomic(path, usda_string(mesh, scene, textured, frame)?.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Translation3, Vector3};

    /// Matrices are written in USD's row-vector layout: a transform's translation is the last
    /// row, and a point times the matrix (row vector on the left) is the transformed point.
    #[test]
    fn matrices_are_written_as_usd_row_vectors() {
        let m = Isometry3::from_parts(
            Translation3::new(1.0, 2.0, 3.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2),
        )
        .to_homogeneous();
        let text = matrix(&m);
        let rows: Vec<Vec<f64>> = text
            .trim_matches(|c| c == '(' || c == ')' || c == ' ')
            .split("), (")
            .map(|r| r.split(", ").map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 4, "{text}");
        assert_eq!(rows[3], [1.0, 2.0, 3.0, 1.0], "{text}");
        // (1, 0, 0, 1) · M: the x axis turned a quarter about z (to +y), then moved.
        let p: Vec<f64> = (0..4).map(|c| rows[0][c] + rows[3][c]).collect();
        assert!((p[0] - 1.0).abs() < 1e-12 && (p[1] - 3.0).abs() < 1e-12 && (p[2] - 3.0).abs() < 1e-12, "{p:?}");
    }
}
