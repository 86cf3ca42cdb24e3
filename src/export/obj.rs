//! Wavefront OBJ: positions (metres), per-vertex normals, optional per-corner UVs, quads kept;
//! optionally a material library (`.mtl`) naming a base-colour texture beside it.

use std::fmt::Write as _;
use std::path::Path;

use crate::body::rig::{vertex_normals, FaceUvs};
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;

/// OBJ text of a quad mesh: `v` (metres, model frame), `vn` (area-weighted vertex normals),
/// `vt` when `uvs` is given, and one `f` per quad (1-based `v/vt/vn`); a quad whose last corner
/// repeats its third is written as a triangle. Errors on out-of-range indices.
pub fn obj_string(vertices: &[[f32; 3]], quads: &[[u32; 4]], uvs: Option<&FaceUvs>) -> Result<String> {
    obj_string_with_material(vertices, quads, uvs, None)
}

/// [`obj_string`] with, when `mtl` is given, `mtllib MTL` and `usemtl skin` lines before the
/// faces (the material of [`mtl_string`]).
pub fn obj_string_with_material(
    vertices: &[[f32; 3]],
    quads: &[[u32; 4]],
    uvs: Option<&FaceUvs>,
    mtl: Option<&str>,
) -> Result<String> {
    let n = vertices.len();
    if let Some(c) = vertices.iter().flatten().find(|c| !c.is_finite()) {
        return Err(Error::NonFinite { name: "vertex coordinate", value: *c as f64 });
    }
    if let Some(f) = quads.iter().position(|q| q.iter().any(|&i| i as usize >= n)) {
        return Err(Error::OutOfRange { name: "face index", detail: format!("face {f} indexes a vertex >= {n}") });
    }
    if let Some(uv) = uvs {
        let m = uv.coords.len();
        if uv.quads.len() != quads.len() || uv.quads.iter().any(|q| q.iter().any(|&i| i as usize >= m)) {
            return Err(Error::OutOfRange {
                name: "UV faces",
                detail: format!("{} UV faces for {} faces, {m} UVs", uv.quads.len(), quads.len()),
            });
        }
    }
    let normals = vertex_normals(vertices, quads);
    let mut s = String::with_capacity(n * 80 + quads.len() * 40);
    s.push_str("# sketchbody OBJ: metres, +Y up, +Z front\n");
    for v in vertices {
        let _ = writeln!(s, "v {} {} {}", v[0], v[1], v[2]);
    }
    if let Some(uv) = uvs {
        for t in &uv.coords {
            let _ = writeln!(s, "vt {} {}", t[0], t[1]);
        }
    }
    for v in &normals {
        let _ = writeln!(s, "vn {} {} {}", v[0], v[1], v[2]);
    }
    if let Some(lib) = mtl {
        let _ = writeln!(s, "mtllib {lib}\nusemtl skin");
    }
    for (f, q) in quads.iter().enumerate() {
        let corners = if q[3] == q[2] { 3 } else { 4 };
        s.push('f');
        for k in 0..corners {
            let v = q[k] + 1;
            match uvs {
                Some(uv) => {
                    let _ = write!(s, " {v}/{}/{v}", uv.quads[f][k] + 1);
                }
                None => {
                    let _ = write!(s, " {v}//{v}");
                }
            }
        }
        s.push('\n');
    }
    Ok(s)
}

/// The material library of a textured OBJ: one material `skin`, white diffuse modulated by the
/// PNG `texture` (a file name beside the `.mtl`).
pub fn mtl_string(texture: &str) -> String {
    format!("# sketchbody material\nnewmtl skin\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\nmap_Kd {texture}\n")
}

/// Writes [`obj_string_with_material`] to `path` atomically.
pub fn write_obj_with_material(
    path: &Path,
    vertices: &[[f32; 3]],
    quads: &[[u32; 4]],
    uvs: Option<&FaceUvs>,
    mtl: Option<&str>,
) -> Result<()> {
    write_atomic(path, obj_string_with_material(vertices, quads, uvs, mtl)?.as_bytes())
}

/// Writes [`obj_string`] to `path` atomically.
pub fn write_obj(path: &Path, vertices: &[[f32; 3]], quads: &[[u32; 4]], uvs: Option<&FaceUvs>) -> Result<()> {
    write_atomic(path, obj_string(vertices, quads, uvs)?.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Finding 4: non-finite vertices are refused, never written as `v inf inf inf`.
    #[test]
    fn non_finite_vertices_are_refused() {
        let quads = [[0u32, 1, 2, 3]];
        let mut v = [[0.0f32; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(obj_string(&v, &quads, None).is_ok());
        v[2][1] = f32::INFINITY;
        assert!(matches!(obj_string(&v, &quads, None), Err(Error::NonFinite { .. })));
        v[2][1] = f32::NAN;
        let dir = std::env::temp_dir().join(format!("skb-obj-nan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert!(write_obj(&dir.join("a.obj"), &v, &quads, None).is_err());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing written");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn quads_uvs_and_normals_are_written_and_bad_indices_rejected() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0]];
        let quads = [[0, 1, 2, 3], [1, 4, 2, 2]];
        let uvs = FaceUvs {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            quads: vec![[0, 1, 2, 3], [1, 0, 2, 2]],
        };
        let s = obj_string(&v, &quads, Some(&uvs)).unwrap();
        assert!(s.contains("\nf 1/1/1 2/2/2 3/3/3 4/4/4\n"), "{s}");
        assert!(s.contains("\nf 2/2/2 5/1/5 3/3/3\n"), "{s}");
        assert!(s.contains("\nvn 0 0 1\n"));
        assert_eq!(s.matches("\nvt ").count(), 4);
        let s = obj_string(&v, &quads, None).unwrap();
        assert!(s.contains("\nf 1//1 2//2 3//3 4//4\n"));
        let m = obj_string_with_material(&v, &quads, Some(&uvs), Some("body.mtl")).unwrap();
        assert!(m.contains("\nmtllib body.mtl\nusemtl skin\nf 1/1/1"), "{m}");
        assert!(mtl_string("t.png").contains("\nmap_Kd t.png\n"));
        assert!(obj_string(&v, &[[0, 1, 2, 9]], None).is_err());
        let dir = std::env::temp_dir().join(format!("skb-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        write_obj(&dir.join("a.obj"), &v, &quads, None).unwrap();
        assert!(std::fs::read_to_string(dir.join("a.obj")).unwrap().starts_with("# sketchbody"));
        assert!(write_obj(&dir.join("missing/a.obj"), &v, &quads, None).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
