//! Motion-capture poses for the sketch renderer: the 15-joint CSV clips of
//! `data/mocap/deepmimic/*.csv` (metres, +Y up, one row per frame), and the normalisation of a
//! frame into the model frame (pelvis at the origin, facing +Z).
//!
//! Concept sketches show standing figures, so [`MocapLibrary::load_dir`] keeps only *upright*
//! frames: the spine (pelvis → neck) within [`MAX_SPINE_TILT_DEG`] of +Y. That drops the lying and
//! upside-down parts of crawl, roll, getup_*, backflip, cartwheel and sideflip without naming
//! clips.

use std::path::Path;

use nalgebra::{UnitQuaternion, Vector3};
use rand::Rng;

use crate::error::{Error, Result};
use crate::skeleton::{joint, Joints3, JOINT_NAMES, NUM_JOINTS};

/// Frames whose spine leans more than this from vertical (degrees) are dropped.
pub const MAX_SPINE_TILT_DEG: f64 = 35.0;

/// One kept frame: its clip name, frame index and joints (as in the file).
#[derive(Clone, Debug, PartialEq)]
pub struct MocapFrame {
    /// Clip file stem, e.g. `walk`.
    pub clip: String,
    /// Row index in the clip (0 = first data row).
    pub frame: usize,
    /// The 15 joints, metres, the file's frame.
    pub joints: Joints3,
}

/// The upright frames of a directory of clips. Immutable; `Send + Sync`.
#[derive(Clone, Debug, Default)]
pub struct MocapLibrary {
    frames: Vec<MocapFrame>,
    /// Start index of each clip's frames in `frames` (frames are grouped by clip).
    clips: Vec<usize>,
}

fn spine_tilt_deg(j: &Joints3) -> f64 {
    let s = Vector3::from(j[joint::NECK]) - Vector3::from(j[joint::PELVIS]);
    if s.norm() < 1e-9 {
        return 180.0;
    }
    (s.y / s.norm()).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Parses one clip (CSV with the header `head_x,head_y,head_z,...`). Errors name the line.
pub fn parse_clip(text: &str, what: &str) -> Result<Vec<Joints3>> {
    let mut lines = text.lines();
    let header = lines.next().ok_or_else(|| Error::CorruptData(format!("{what}: empty file")))?;
    let cols: Vec<&str> = header.trim().split(',').collect();
    if cols.len() != 3 * NUM_JOINTS || cols[0] != format!("{}_x", JOINT_NAMES[0]) {
        return Err(Error::CorruptData(format!("{what}: header is not the 15-joint x,y,z header")));
    }
    let mut out = Vec::new();
    for (i, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let vals: Vec<f64> = line
            .trim()
            .split(',')
            .map(|v| v.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| Error::CorruptData(format!("{what}: line {}: {e}", i + 2)))?;
        if vals.len() != 3 * NUM_JOINTS || vals.iter().any(|v| !v.is_finite()) {
            return Err(Error::CorruptData(format!("{what}: line {}: expected 45 finite numbers", i + 2)));
        }
        let mut j = [[0.0; 3]; NUM_JOINTS];
        for (k, p) in j.iter_mut().enumerate() {
            *p = [vals[3 * k], vals[3 * k + 1], vals[3 * k + 2]];
        }
        out.push(j);
    }
    Ok(out)
}

impl MocapLibrary {
    /// Loads every `*.csv` in `dir` (sorted by name, so the frame order is fixed) and keeps the
    /// upright frames. Errors: unreadable directory or file, malformed CSV, no upright frame.
    pub fn load_dir(dir: &Path) -> Result<MocapLibrary> {
        let io = |source| Error::Io { path: dir.to_path_buf(), source };
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .map_err(io)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "csv"))
            .collect();
        files.sort();
        let mut frames = Vec::new();
        for f in &files {
            let text = std::fs::read_to_string(f).map_err(|source| Error::Io { path: f.clone(), source })?;
            let clip = f.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            for (frame, joints) in parse_clip(&text, &f.display().to_string())?.into_iter().enumerate() {
                if spine_tilt_deg(&joints) <= MAX_SPINE_TILT_DEG {
                    frames.push(MocapFrame { clip: clip.clone(), frame, joints });
                }
            }
        }
        Self::from_frames(frames)
            .map_err(|_| Error::CorruptData(format!("{}: no upright mocap frame in any *.csv", dir.display())))
    }

    /// A library from given frames (kept as they are). Errors when `frames` is empty.
    pub fn from_frames(frames: Vec<MocapFrame>) -> Result<MocapLibrary> {
        if frames.is_empty() {
            return Err(Error::OutOfRange { name: "mocap frames", detail: "no frames".into() });
        }
        let clips = (0..frames.len()).filter(|&i| i == 0 || frames[i].clip != frames[i - 1].clip).collect();
        Ok(MocapLibrary { frames, clips })
    }

    /// Number of kept frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// `true` when no frame is held (only for `Default`).
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// A random kept frame: a clip uniformly, then one of its frames uniformly, so that long
    /// clips (the walks) do not crowd out the short ones. `None` when empty.
    pub fn random<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<&MocapFrame> {
        if self.clips.is_empty() {
            return None;
        }
        let c = rng.random_range(0..self.clips.len());
        let (start, end) = (self.clips[c], self.clips.get(c + 1).copied().unwrap_or(self.frames.len()));
        Some(&self.frames[rng.random_range(start..end)])
    }

    /// Number of clips with at least one kept frame.
    pub fn num_clips(&self) -> usize {
        self.clips.len()
    }
}

/// Moves a frame into the model frame: pelvis at the origin and turned about +Y so that the hip
/// line points along +X (the character faces +Z, its right at −X).
pub fn normalize_frame(j: &Joints3) -> Joints3 {
    let p = Vector3::from(j[joint::PELVIS]);
    let hips = Vector3::from(j[joint::L_HIP]) - Vector3::from(j[joint::R_HIP]);
    let heading = hips.z.atan2(hips.x); // angle of the hip line from +X toward +Z
    let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), heading);
    let mut out = [[0.0; 3]; NUM_JOINTS];
    for (o, q) in out.iter_mut().zip(j) {
        *o = (turn * (Vector3::from(*q) - p)).into();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_rejects_bad_rows_and_normalize_faces_plus_z() {
        let header: Vec<String> =
            JOINT_NAMES.iter().flat_map(|n| ["x", "y", "z"].map(|a| format!("{n}_{a}"))).collect();
        let mut row = vec![0.0f64; 45];
        // Hips along -Z (character faces -X), pelvis at (1, 1, 1).
        for (k, v) in [
            (joint::PELVIS, [1.0, 1.0, 1.0]),
            (joint::R_HIP, [1.0, 1.0, 1.1]),
            (joint::L_HIP, [1.0, 1.0, 0.9]),
            (joint::NECK, [1.0, 1.5, 1.0]),
        ] {
            row[3 * k..3 * k + 3].copy_from_slice(&v);
        }
        let line = row.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(",");
        let text = format!("{}\n{}\n", header.join(","), line);
        let clip = parse_clip(&text, "t").unwrap();
        assert_eq!(clip.len(), 1);
        let n = normalize_frame(&clip[0]);
        assert!(n[joint::PELVIS].iter().all(|c| c.abs() < 1e-12));
        let hip = Vector3::from(n[joint::L_HIP]) - Vector3::from(n[joint::R_HIP]);
        assert!((hip.x - 0.2).abs() < 1e-9 && hip.z.abs() < 1e-9, "hip line {hip:?}");
        assert!(parse_clip(&format!("{}\n1,2\n", header.join(",")), "t").is_err());
        assert!(parse_clip("a,b\n", "t").is_err());
        assert!((spine_tilt_deg(&clip[0])).abs() < 1e-9);
    }
}
