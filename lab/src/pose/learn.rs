//! Learning the default dictionary from a motion folder and BVH files: clip selection (held-out
//! and excluded clips) and the provenance text stored in the dictionary file.
//!
//! The committed asset `assets/pose_dictionary.skbpd` is rebuilt with
//! `sketchbody-lab learn-poses --mocap ../shared/data/mocap/deepmimic --mocap ../shared/data/mocap/cmu --out assets/pose_dictionary.skbpd`
//! which is [`learn_from_sources`] with [`LearnSpec::library_default`].
//!
//! **Joint convention (retargeting).** A motion clip's joints follow its capture skeleton
//! (DeepMimic's: shoulders level with the neck, pelvis level with the hips, long arms), while
//! every later stage — the renderer's ground truth, the IK of the body rig, the shape fit —
//! uses the body model's rig joints (shoulders ~10 cm below the neck, pelvis above the hips,
//! a longer torso, shorter arms and thighs). With [`LearnSpec::retarget`] set, each training
//! frame is first retargeted onto one of the given rest skeletons exactly as the renderer poses
//! a body ([`sketchbody::body::retarget::retarget_directions`]: every bone keeps the frame's
//! direction and takes the skeleton's length; the girdle bones turn with the chest and hip
//! frames), frame `i` of a clip onto skeleton `i mod n`; the dictionary is then learned in the
//! rig's convention. [`LearnSpec::library_default`] uses the body model's female and male mean
//! skeletons.

use std::path::{Path, PathBuf};

use super::bvh::Bvh;
use sketchbody::body::retarget::retarget_directions;
use sketchbody::body::{BodyModel, Gender};
use sketchbody::error::{Error, Result};
use sketchbody::pose::dictionary::{Dictionary, LearnParams};
use sketchbody::pose::motion::read_motion_csv;
use sketchbody::skeleton::Joints3;

/// Clips held out of the default dictionary for measurement (`bench-pose`): six DeepMimic
/// clips and four whole CMU subjects (`SS_*`: 06 basketball and 08 walks on the Character
/// Creator and Daz skeletons, 13 jumps and reaches, 16 jumps on the ASF skeleton).
pub fn default_held_out() -> Vec<String> {
    [
        "dance_b",
        "jog",
        "kick",
        "long_long_walk3",
        "long_long_walk3_mirror",
        "long_stealthy_walk1",
        "06_*",
        "08_*",
        "13_*",
        "16_*",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// Whether clip `name` matches a held-out or excluded entry: the same name, or for an entry
/// ending in `*` (a whole CMU subject, `06_*`) a name starting with what precedes it.
pub fn clip_matches(entry: &str, name: &str) -> bool {
    match entry.strip_suffix('*') {
        Some(prefix) => name.starts_with(prefix),
        None => entry == name,
    }
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
    /// Named rest skeletons (metres, any placement) to retarget the frames onto before
    /// learning (module doc); empty = learn in the clips' own joint convention. Recorded as
    /// `retarget:` in the provenance.
    pub retarget: Vec<(String, Joints3)>,
}

impl Default for LearnSpec {
    /// [`default_held_out`], nothing else excluded, [`LearnParams::default`], no retargeting
    /// (the clips' own joint convention).
    fn default() -> Self {
        LearnSpec {
            held_out: default_held_out(),
            excluded: Vec::new(),
            params: LearnParams::default(),
            retarget: Vec::new(),
        }
    }
}

impl LearnSpec {
    /// The spec of the committed dictionary: [`LearnSpec::default`] retargeted onto the
    /// embedded body model's mean skeletons ([`body_model_skeletons`]). Errors: the embedded
    /// model's.
    pub fn library_default() -> Result<LearnSpec> {
        Ok(LearnSpec { retarget: body_model_skeletons(&BodyModel::embedded()?), ..LearnSpec::default() })
    }
}

/// The mean rest skeletons of `model`, female then male, named by gender.
pub fn body_model_skeletons(model: &BodyModel) -> Vec<(String, Joints3)> {
    Gender::ALL.iter().map(|&g| (g.name().to_string(), *model.space(g).mean_joints())).collect()
}

/// The frames of one clip retargeted onto `skeletons` (frame `i` onto skeleton `i mod n`);
/// unchanged when `skeletons` is empty. Errors: [`retarget_directions`]' (non-finite joints,
/// zero-length bones), naming the clip and frame.
pub fn retarget_frames(clip: &str, frames: Vec<Joints3>, skeletons: &[(String, Joints3)]) -> Result<Vec<Joints3>> {
    if skeletons.is_empty() {
        return Ok(frames);
    }
    frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            retarget_directions(&skeletons[i % skeletons.len()].1, f)
                .map_err(|e| Error::CorruptData(format!("clip {clip}, frame {i}: cannot retarget: {e}")))
        })
        .collect()
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

/// Reads the clips of the `mocap` folders of motion tables (clip names must differ across
/// folders) and the `bvh` files, drops the held-out and excluded ones ([`clip_matches`]), and
/// learns the dictionary. The provenance lists the clips used
/// (file stems), the held-out and excluded names and the parameters, one `key: value` per line.
pub fn learn_from_sources(mocap: &[PathBuf], bvh: &[PathBuf], spec: &LearnSpec) -> Result<Dictionary> {
    let mut clips: Vec<(String, Vec<Joints3>)> = Vec::new();
    let skip = |name: &str| spec.held_out.iter().chain(&spec.excluded).any(|h| clip_matches(h, name));
    for dir in mocap {
        for f in motion_files(dir)? {
            let name = stem(&f);
            if !skip(&name) {
                let frames = retarget_frames(&name, read_motion_csv(&f)?, &spec.retarget)?;
                clips.push((name, frames));
            }
        }
    }
    for f in bvh {
        let name = stem(f);
        if !skip(&name) {
            let frames = retarget_frames(&name, Bvh::read(f)?.canonical_frames()?, &spec.retarget)?;
            clips.push((name, frames));
        }
    }
    let used: Vec<&str> = clips.iter().map(|c| c.0.as_str()).collect();
    let p = &spec.params;
    let provenance = format!(
        "sketchbody pose dictionary\nclips: {}\nheld_out: {}\nexcluded: {}\nparams: max_per_action={} energy={} mirror={} exemplar_spacing={}\n{}",
        used.join(","),
        spec.held_out.join(","),
        spec.excluded.join(","),
        p.max_per_action,
        p.energy,
        p.mirror,
        p.exemplar_spacing,
        if spec.retarget.is_empty() {
            String::new()
        } else {
            format!("retarget: {}\n", spec.retarget.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(","))
        }
    );
    Dictionary::learn(&clips, p, provenance)
}

/// The `retarget:` skeleton names recorded in a dictionary's provenance (empty when it was
/// learned in the clips' own joint convention).
pub fn retarget_of(d: &Dictionary) -> Vec<String> {
    d.provenance
        .lines()
        .find_map(|l| l.strip_prefix("retarget: "))
        .map(|s| s.split(',').filter(|x| !x.is_empty()).map(str::to_string).collect())
        .unwrap_or_default()
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
        let spec = LearnSpec {
            held_out: vec!["heldout".into()],
            excluded: vec![],
            params: LearnParams::default(),
            retarget: vec![],
        };
        let d = learn_from_sources(&[], &[a.clone(), b.clone()], &spec).unwrap();
        assert_eq!(d.actions.len(), 1);
        assert_eq!(d.actions[0].name, "swing");
        assert!(d.provenance.contains("clips: swing\n"));
        assert_eq!(held_out_of(&d), vec!["heldout".to_string()]);
        std::fs::write(&a, "HIERARCHY\nROOT x\n{").unwrap();
        assert!(learn_from_sources(&[], &[a], &spec).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn retargeting_takes_each_skeletons_lengths_alternately_and_is_recorded() {
        use sketchbody::skeleton::{joint, BONES};
        let dist =
            |a: &[f64; 3], b: &[f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        let model = BodyModel::embedded().unwrap();
        let skel = body_model_skeletons(&model);
        assert_eq!(skel.iter().map(|s| s.0.as_str()).collect::<Vec<_>>(), ["female", "male"]);
        // A source skeleton of another convention: long arms, level shoulders, one bent elbow per frame.
        let frames: Vec<Joints3> = (0..4)
            .map(|f| {
                let mut x = *model.space(Gender::Male).mean_joints();
                x[joint::R_SHOULDER][1] = x[joint::NECK][1];
                x[joint::L_SHOULDER][1] = x[joint::NECK][1];
                x[joint::R_WRIST] =
                    [x[joint::R_ELBOW][0] - 0.3, x[joint::R_ELBOW][1] + 0.1 * f as f64, x[joint::R_ELBOW][2] + 0.2];
                x
            })
            .collect();
        let out = retarget_frames("t", frames.clone(), &skel).unwrap();
        for (i, x) in out.iter().enumerate() {
            let rest = &skel[i % 2].1;
            for &(a, b) in &BONES {
                assert!((dist(&x[a], &x[b]) - dist(&rest[a], &rest[b])).abs() < 1e-9, "frame {i} bone {a}-{b}");
            }
            // A limb bone keeps the source's direction.
            let (s, e) = (frames[i][joint::R_ELBOW], frames[i][joint::R_WRIST]);
            let ds: Vec<f64> = (0..3).map(|k| (e[k] - s[k]) / dist(&s, &e)).collect();
            let de: Vec<f64> = (0..3)
                .map(|k| (x[joint::R_WRIST][k] - x[joint::R_ELBOW][k]) / dist(&x[joint::R_ELBOW], &x[joint::R_WRIST]))
                .collect();
            assert!(ds.iter().zip(&de).all(|(a, b)| (a - b).abs() < 1e-9), "frame {i}");
        }
        assert_eq!(retarget_frames("t", frames.clone(), &[]).unwrap(), frames);
        let mut bad = frames.clone();
        bad[1][joint::R_WRIST] = bad[1][joint::R_ELBOW];
        let e = retarget_frames("clipname", bad, &skel).unwrap_err().to_string();
        assert!(e.contains("clipname, frame 1"), "{e}");
        // The provenance names the skeletons; without retargeting there is no such line.
        let dir = std::env::temp_dir().join(format!("skb-learn-rt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let header: Vec<String> = sketchbody::skeleton::JOINT_NAMES
            .iter()
            .flat_map(|n| ["x", "y", "z"].map(|a| format!("{n}_{a}")))
            .collect();
        let rows: Vec<String> =
            frames.iter().map(|x| x.iter().flatten().map(|v| v.to_string()).collect::<Vec<_>>().join(",")).collect();
        std::fs::write(dir.join("bend.csv"), format!("{}\n{}\n", header.join(","), rows.join("\n"))).unwrap();
        let spec = LearnSpec { retarget: skel, held_out: vec![], ..LearnSpec::default() };
        let d = learn_from_sources(std::slice::from_ref(&dir), &[], &spec).unwrap();
        assert_eq!(retarget_of(&d), vec!["female".to_string(), "male".to_string()]);
        let plain = learn_from_sources(
            std::slice::from_ref(&dir),
            &[],
            &LearnSpec { held_out: vec![], ..LearnSpec::default() },
        )
        .unwrap();
        assert!(retarget_of(&plain).is_empty());
        // Learned bone lengths are the skeletons' (normalised), not the source's long arms.
        let b = 3; // r_elbow -> r_wrist
        assert!(
            (d.bone_lengths[b] - plain.bone_lengths[b]).abs() > 0.02,
            "{} vs {}",
            d.bone_lengths[b],
            plain.bone_lengths[b]
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
