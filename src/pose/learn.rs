//! Learning the default dictionary from a motion folder and BVH files: clip selection (held-out
//! and excluded clips) and the provenance text stored in the dictionary file.
//!
//! The committed asset `assets/pose_dictionary.skbpd` is rebuilt with
//! `sketchbody learn-poses --mocap ../shared/data/mocap/deepmimic --out assets/pose_dictionary.skbpd`
//! which is [`learn_from_sources`] with [`LearnSpec::default`].

use std::path::{Path, PathBuf};

use super::bvh::Bvh;
use super::dictionary::{Dictionary, LearnParams};
use super::motion::read_motion_csv;
use crate::error::{Error, Result};
use crate::skeleton::Joints3;

/// Clips held out of the default dictionary for measurement (`bench-pose`).
pub fn default_held_out() -> Vec<String> {
    ["dance_b", "jog", "kick", "long_long_walk3", "long_long_walk3_mirror", "long_stealthy_walk1"]
        .iter()
        .map(|s| s.to_string())
        .collect()
}

/// The clips with lying or upside-down poses (data/mocap/README.md).
pub fn lying_clips() -> Vec<String> {
    ["backflip", "cartwheel", "crawl", "getup_facedown", "getup_faceup", "roll", "sideflip"]
        .iter()
        .map(|s| s.to_string())
        .collect()
}

/// What to learn from.
#[derive(Clone, Debug, PartialEq)]
pub struct LearnSpec {
    /// Clip names (file stems) kept out for measurement; recorded as `held_out:`.
    pub held_out: Vec<String>,
    /// Clip names left out for other reasons; recorded as `excluded:`.
    pub excluded: Vec<String>,
    /// PCA parameters.
    pub params: LearnParams,
}

impl Default for LearnSpec {
    /// [`default_held_out`], nothing else excluded, [`LearnParams::default`].
    fn default() -> Self {
        LearnSpec { held_out: default_held_out(), excluded: Vec::new(), params: LearnParams::default() }
    }
}

/// The sorted `*.csv` files of a folder.
pub fn motion_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let io = |source| Error::Io { path: dir.to_path_buf(), source };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    files.sort();
    Ok(files)
}

fn stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Reads the clips of `mocap` (a folder of motion tables, optional) and `bvh` files, drops the
/// held-out and excluded ones, and learns the dictionary. The provenance lists the clips used
/// (file stems), the held-out and excluded names and the parameters, one `key: value` per line.
pub fn learn_from_sources(mocap: Option<&Path>, bvh: &[PathBuf], spec: &LearnSpec) -> Result<Dictionary> {
    let mut clips: Vec<(String, Vec<Joints3>)> = Vec::new();
    let skip = |name: &str| spec.held_out.iter().chain(&spec.excluded).any(|h| h == name);
    if let Some(dir) = mocap {
        for f in motion_files(dir)? {
            let name = stem(&f);
            if !skip(&name) {
                clips.push((name, read_motion_csv(&f)?));
            }
        }
    }
    for f in bvh {
        let name = stem(f);
        if !skip(&name) {
            clips.push((name, Bvh::read(f)?.canonical_frames()?));
        }
    }
    let used: Vec<&str> = clips.iter().map(|c| c.0.as_str()).collect();
    let p = &spec.params;
    let provenance = format!(
        "sketchbody pose dictionary\nclips: {}\nheld_out: {}\nexcluded: {}\nparams: max_per_action={} energy={} mirror={} exemplar_spacing={}\n",
        used.join(","),
        spec.held_out.join(","),
        spec.excluded.join(","),
        p.max_per_action,
        p.energy,
        p.mirror,
        p.exemplar_spacing
    );
    Dictionary::learn(&clips, p, provenance)
}

/// The `held_out:` names recorded in a dictionary's provenance (empty if none).
pub fn held_out_of(d: &Dictionary) -> Vec<String> {
    d.provenance
        .lines()
        .find_map(|l| l.strip_prefix("held_out: ").or(if l == "held_out:" { Some("") } else { None }))
        .map(|s| s.split(',').filter(|x| !x.is_empty()).map(str::to_string).collect())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::bvh::tests::mixamo_bvh;

    #[test]
    fn learns_from_bvh_files_and_skips_held_out_clips() {
        let dir = std::env::temp_dir().join(format!("skb-learn-bvh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let frames: Vec<[f64; 6]> = (0..12).map(|f| [0.0, 0.0, 0.0, 3.0 * f as f64, 0.0, 10.0 * f as f64]).collect();
        let text = mixamo_bvh(&frames);
        // Bend the right knee differently per frame so the action has variance.
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        let n = lines.len();
        for (i, line) in lines.iter_mut().skip(n - 12).enumerate() {
            let mut v: Vec<String> = line.split(' ').map(str::to_string).collect();
            let len = v.len();
            v[len - 10] = (5.0 * i as f64).to_string();
            v[len - 20] = (-4.0 * i as f64).to_string();
            *line = v.join(" ");
        }
        let (a, b) = (dir.join("swing.bvh"), dir.join("heldout.bvh"));
        std::fs::write(&a, lines.join("\n")).unwrap();
        std::fs::write(&b, lines.join("\n")).unwrap();
        let spec = LearnSpec { held_out: vec!["heldout".into()], excluded: vec![], params: LearnParams::default() };
        let d = learn_from_sources(None, &[a.clone(), b.clone()], &spec).unwrap();
        assert_eq!(d.actions.len(), 1);
        assert_eq!(d.actions[0].name, "swing");
        assert!(d.provenance.contains("clips: swing\n"));
        assert_eq!(held_out_of(&d), vec!["heldout".to_string()]);
        std::fs::write(&a, "HIERARCHY\nROOT x\n{").unwrap();
        assert!(learn_from_sources(None, &[a], &spec).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
