//! A BVH (Biovision hierarchy) reader: parses the skeleton and motion, runs forward kinematics
//! and maps the rig's joints onto the 15 canonical joints.
//!
//! Assumed frame: right-handed, +Y up (the BVH convention of CMU, Mixamo and Rokoko exports);
//! units and facing direction do not matter because [`sketchbody::pose::motion::normalize_pose`] removes
//! scale and heading. Rotation channels are degrees, composed in the order listed
//! (`Zrotation Xrotation Yrotation` means `R = Rz · Rx · Ry`, applied to child offsets).
//!
//! Joint-name mapping. A rig name is matched after lower-casing, dropping everything up to the
//! last `:` (`mixamorig:Hips` → `hips`), dropping a `mixamorig` or `bip01` prefix and removing
//! `_`, ` `, `-`, `.`. The first alias (in this order) that the rig has is used:
//!
//! | canonical  | aliases (normalised)                                                           |
//! |------------|--------------------------------------------------------------------------------|
//! | pelvis     | hips, root, pelvis, hip                                                        |
//! | neck       | neck, lowerneck, neck1                                                         |
//! | head       | head (centre = midpoint of the head joint and its first child or end site)     |
//! | r_shoulder | rightarm, rhumerus, rightupperarm, ruparm                                      |
//! | r_elbow    | rightforearm, rradius, rightlowerarm, rightelbow, rforearm, relbow             |
//! | r_wrist    | righthand, rwrist, rightwrist, rhand                                           |
//! | r_hip      | rightupleg, rfemur, rightthigh, rightupperleg, rthigh, righthip                |
//! | r_knee     | rightleg, rtibia, rightshin, rightlowerleg, rightknee, rshin, rknee            |
//! | r_ankle    | rightfoot, rfoot, rightankle, rankle                                           |
//!
//! and the same with `left`/`l` for the left side. CMU's `RightShoulder`/`rclavicle` and
//! Mixamo's `RightShoulder` are clavicles and deliberately not mapped.

use std::path::Path;

use nalgebra::{Matrix3, Rotation3, Vector3};

use sketchbody::error::{Error, Result};
use sketchbody::skeleton::{Joints3, JOINT_NAMES, NUM_JOINTS};

/// Most joints accepted in one hierarchy (a sanity cap against corrupt files).
const MAX_NODES: usize = 1024;
/// Most frames accepted in one file.
const MAX_FRAMES: usize = 1_000_000;

#[derive(Clone, Copy, Debug)]
enum Channel {
    Pos(usize),
    Rot(usize),
}

#[derive(Debug)]
struct Node {
    name: String,
    parent: Option<usize>,
    offset: Vector3<f64>,
    channels: Vec<Channel>,
    first_child: Option<usize>,
}

/// A parsed BVH file: its hierarchy and the motion values of every frame.
#[derive(Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    frames: Vec<Vec<f64>>,
}

fn aliases(j: usize) -> Vec<String> {
    let side = |names: &[&str]| -> Vec<String> {
        let (long, short) = if JOINT_NAMES[j].starts_with("r_") { ("right", "r") } else { ("left", "l") };
        names.iter().map(|n| n.replace("SIDE", long).replace("S", short)).collect()
    };
    match JOINT_NAMES[j] {
        "pelvis" => vec!["hips".into(), "root".into(), "pelvis".into(), "hip".into()],
        "neck" => vec!["neck".into(), "lowerneck".into(), "neck1".into()],
        "head" => vec!["head".into()],
        "r_shoulder" | "l_shoulder" => side(&["SIDEarm", "Shumerus", "SIDEupperarm", "Suparm"]),
        "r_elbow" | "l_elbow" => side(&["SIDEforearm", "Sradius", "SIDElowerarm", "SIDEelbow", "Sforearm", "Selbow"]),
        "r_wrist" | "l_wrist" => side(&["SIDEhand", "Swrist", "SIDEwrist", "Shand"]),
        "r_hip" | "l_hip" => side(&["SIDEupleg", "Sfemur", "SIDEthigh", "SIDEupperleg", "Sthigh", "SIDEhip"]),
        "r_knee" | "l_knee" => side(&["SIDEleg", "Stibia", "SIDEshin", "SIDElowerleg", "SIDEknee", "Sshin", "Sknee"]),
        _ => side(&["SIDEfoot", "Sfoot", "SIDEankle", "Sankle"]),
    }
}

/// Normalises a rig joint name for matching (see the module doc).
pub fn normalize_name(name: &str) -> String {
    let lower = name.to_lowercase();
    let tail = lower.rsplit(':').next().unwrap_or("");
    let mut s: String = tail.chars().filter(|c| !matches!(c, '_' | ' ' | '-' | '.')).collect();
    for prefix in ["mixamorig", "bip01"] {
        if let Some(rest) = s.strip_prefix(prefix) {
            s = rest.to_string();
        }
    }
    s
}

impl Bvh {
    /// Parses BVH text; `what` names the source in errors.
    pub fn parse(text: &str, what: &str) -> Result<Bvh> {
        let bad = |m: String| Error::CorruptData(format!("{what}: {m}"));
        let mut tok = text.split_whitespace().peekable();
        if tok.next() != Some("HIERARCHY") {
            return Err(bad("does not start with HIERARCHY".into()));
        }
        let mut nodes: Vec<Node> = Vec::new();
        let mut stack: Vec<usize> = Vec::new();
        let mut n_channels = 0usize;
        let num = |t: Option<&str>| -> Result<f64> {
            let t = t.ok_or_else(|| bad("unexpected end of file".into()))?;
            t.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| bad(format!("{t:?} is not a finite number")))
        };
        loop {
            let t = tok.next().ok_or_else(|| bad("unexpected end of hierarchy".into()))?;
            match t {
                "ROOT" | "JOINT" | "End" => {
                    let name = match t {
                        "End" => {
                            tok.next();
                            format!("{}_end", stack.last().map(|&p| nodes[p].name.as_str()).unwrap_or(""))
                        }
                        _ => tok.next().ok_or_else(|| bad("joint without a name".into()))?.to_string(),
                    };
                    if t == "ROOT" && !nodes.is_empty() {
                        return Err(bad("more than one ROOT".into()));
                    }
                    if t != "ROOT" && stack.is_empty() {
                        return Err(bad(format!("{t} {name} outside ROOT")));
                    }
                    if tok.next() != Some("{") {
                        return Err(bad(format!("expected {{ after {name}")));
                    }
                    if tok.next() != Some("OFFSET") {
                        return Err(bad(format!("expected OFFSET in {name}")));
                    }
                    let offset = Vector3::new(num(tok.next())?, num(tok.next())?, num(tok.next())?);
                    let parent = stack.last().copied();
                    let idx = nodes.len();
                    if idx >= MAX_NODES {
                        return Err(bad(format!("more than {MAX_NODES} joints")));
                    }
                    if let Some(p) = parent {
                        nodes[p].first_child.get_or_insert(idx);
                    }
                    nodes.push(Node { name, parent, offset, channels: Vec::new(), first_child: None });
                    stack.push(idx);
                }
                "CHANNELS" => {
                    let &cur = stack.last().ok_or_else(|| bad("CHANNELS outside a joint".into()))?;
                    let n = num(tok.next())?;
                    if !(0.0..=6.0).contains(&n) || n.fract() != 0.0 {
                        return Err(bad(format!("bad channel count {n}")));
                    }
                    for _ in 0..n as usize {
                        let c = tok.next().ok_or_else(|| bad("truncated CHANNELS".into()))?;
                        let axis = match c.as_bytes().first().map(|b| b.to_ascii_lowercase()) {
                            Some(b'x') => 0,
                            Some(b'y') => 1,
                            Some(b'z') => 2,
                            _ => return Err(bad(format!("unknown channel {c}"))),
                        };
                        let ch = match &c.to_lowercase()[1..] {
                            "position" => Channel::Pos(axis),
                            "rotation" => Channel::Rot(axis),
                            _ => return Err(bad(format!("unknown channel {c}"))),
                        };
                        nodes[cur].channels.push(ch);
                        n_channels += 1;
                    }
                }
                "}" => {
                    stack.pop().ok_or_else(|| bad("unbalanced }".into()))?;
                    if stack.is_empty() {
                        break;
                    }
                }
                other => return Err(bad(format!("unexpected token {other:?} in hierarchy"))),
            }
        }
        if tok.next() != Some("MOTION") || tok.next() != Some("Frames:") {
            return Err(bad("expected MOTION and Frames:".into()));
        }
        let n_frames = num(tok.next())?;
        if !(1.0..=MAX_FRAMES as f64).contains(&n_frames) || n_frames.fract() != 0.0 {
            return Err(bad(format!("bad frame count {n_frames}")));
        }
        if tok.next() != Some("Frame") || tok.next() != Some("Time:") {
            return Err(bad("expected Frame Time:".into()));
        }
        num(tok.next())?;
        let mut frames = Vec::with_capacity(n_frames as usize);
        for f in 0..n_frames as usize {
            let mut v = Vec::with_capacity(n_channels);
            for _ in 0..n_channels {
                v.push(num(tok.next()).map_err(|_| bad(format!("frame {} is truncated or not numeric", f + 1)))?);
            }
            frames.push(v);
        }
        Ok(Bvh { nodes, frames })
    }

    /// Reads and parses a BVH file.
    pub fn read(path: &Path) -> Result<Bvh> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
        Bvh::parse(&text, &path.display().to_string())
    }

    /// Number of frames.
    pub fn num_frames(&self) -> usize {
        self.frames.len()
    }

    /// Global positions of every node in frame `f` (units of the file).
    fn positions(&self, f: usize) -> Vec<Vector3<f64>> {
        let mut rot: Vec<Matrix3<f64>> = Vec::with_capacity(self.nodes.len());
        let mut pos: Vec<Vector3<f64>> = Vec::with_capacity(self.nodes.len());
        let values = &self.frames[f];
        let mut k = 0;
        for n in &self.nodes {
            let mut local_t = n.offset;
            let mut local_r = Matrix3::identity();
            for ch in &n.channels {
                let v = values[k];
                k += 1;
                match *ch {
                    Channel::Pos(a) => local_t[a] = n.offset[a] + v,
                    Channel::Rot(a) => {
                        let axis = Vector3::ith_axis(a);
                        local_r *= Rotation3::from_axis_angle(&axis, v.to_radians()).into_inner();
                    }
                }
            }
            let (r, p) = match n.parent {
                Some(p) => (rot[p] * local_r, pos[p] + rot[p] * local_t),
                None => (local_r, local_t),
            };
            rot.push(r);
            pos.push(p);
        }
        pos
    }

    /// Index of the node for each canonical joint (see the module doc for the mapping).
    pub fn joint_map(&self) -> Result<[usize; NUM_JOINTS]> {
        let names: Vec<String> = self.nodes.iter().map(|n| normalize_name(&n.name)).collect();
        let mut map = [0usize; NUM_JOINTS];
        for (j, m) in map.iter_mut().enumerate() {
            *m = aliases(j).iter().find_map(|a| names.iter().position(|n| n == a)).ok_or_else(|| {
                Error::CorruptData(format!(
                    "BVH rig has no joint for canonical {} (looked for {:?})",
                    JOINT_NAMES[j],
                    aliases(j)
                ))
            })?;
        }
        Ok(map)
    }

    /// The canonical 15 joints of every frame, in the file's units and frame.
    pub fn canonical_frames(&self) -> Result<Vec<Joints3>> {
        let map = self.joint_map()?;
        let head = map[0];
        let head_tip = self.nodes[head].first_child;
        Ok((0..self.frames.len())
            .map(|f| {
                let p = self.positions(f);
                let mut x = [[0.0; 3]; NUM_JOINTS];
                for (j, &n) in map.iter().enumerate() {
                    let q = if j == 0 { head_tip.map_or(p[n], |c| 0.5 * (p[n] + p[c])) } else { p[n] };
                    x[j] = [q.x, q.y, q.z];
                }
                x
            })
            .collect())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A Mixamo-style rig: every canonical joint, offsets in centimetres.
    pub(crate) fn mixamo_bvh(frames: &[[f64; 6]]) -> String {
        let leaf = |name: &str, off: &str, inner: &str| {
            format!("JOINT {name}\n{{\nOFFSET {off}\nCHANNELS 3 Zrotation Xrotation Yrotation\n{inner}}}\n")
        };
        let end = "End Site\n{\nOFFSET 0 10 0\n}\n";
        let arm = |s: &str, x: f64| {
            leaf(
                &format!("mixamorig:{s}Shoulder"),
                &format!("{x} 0 0"),
                &leaf(
                    &format!("mixamorig:{s}Arm"),
                    &format!("{x} 0 0"),
                    &leaf(
                        &format!("mixamorig:{s}ForeArm"),
                        "0 -28 0",
                        &leaf(&format!("mixamorig:{s}Hand"), "0 -25 0", end),
                    ),
                ),
            )
        };
        let leg = |s: &str, x: f64| {
            leaf(
                &format!("mixamorig:{s}UpLeg"),
                &format!("{x} -5 0"),
                &leaf(&format!("mixamorig:{s}Leg"), "0 -42 0", &leaf(&format!("mixamorig:{s}Foot"), "0 -40 0", end)),
            )
        };
        let neck = leaf(
            "mixamorig:Neck",
            "0 50 0",
            &format!("{}{}{}", leaf("mixamorig:Head", "0 10 0", end), arm("Right", -8.0), arm("Left", 8.0)),
        );
        let mut s = format!(
            "HIERARCHY\nROOT mixamorig:Hips\n{{\nOFFSET 0 100 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n{neck}{}{}}}\nMOTION\nFrames: {}\nFrame Time: 0.0333\n",
            leg("Right", -10.0), leg("Left", 10.0), frames.len()
        );
        let n_joints = s.matches("CHANNELS 3").count();
        for f in frames {
            let mut row: Vec<String> = f.iter().map(|v| v.to_string()).collect();
            row.extend(std::iter::repeat_n("0".to_string(), 3 * n_joints));
            s.push_str(&row.join(" "));
            s.push('\n');
        }
        s
    }

    #[test]
    fn forward_kinematics_and_mapping() {
        let text = mixamo_bvh(&[[0.0; 6], [1.0, 2.0, 3.0, 0.0, 0.0, 90.0]]);
        let bvh = Bvh::parse(&text, "test").unwrap();
        assert_eq!(bvh.num_frames(), 2);
        let f = bvh.canonical_frames().unwrap();
        // Frame 0: rest pose.
        assert_eq!(f[0][8], [0.0, 100.0, 0.0]);
        assert_eq!(f[0][2], [-16.0, 150.0, 0.0]); // r_shoulder = RightArm, not the clavicle
        assert_eq!(f[0][0], [0.0, 165.0, 0.0]); // head centre between Head and its end site
        assert_eq!(f[0][11], [-10.0, 13.0, 0.0]);
        // Frame 1: translated by (1, 2, 3) and turned 90° about +Y: local +X goes to -Z.
        let r_sh = f[1][2];
        assert!(
            (r_sh[0] - 1.0).abs() < 1e-9 && (r_sh[1] - 152.0).abs() < 1e-9 && (r_sh[2] - 19.0).abs() < 1e-9,
            "{r_sh:?}"
        );
    }

    #[test]
    fn names_and_errors() {
        assert_eq!(normalize_name("mixamorig:RightUpLeg"), "rightupleg");
        assert_eq!(normalize_name("Bip01 R_Thigh"), "rthigh");
        assert_eq!(normalize_name("Right_Fore-Arm"), "rightforearm");
        let text = mixamo_bvh(&[[0.0; 6]]);
        assert!(Bvh::parse(&text.replace("mixamorig:LeftFoot", "mixamorig:LeftToe"), "t")
            .unwrap()
            .canonical_frames()
            .is_err());
        assert!(Bvh::parse(&text[..text.len() - 10], "t").is_err());
        assert!(Bvh::parse("HIERARCHY\nROOT a\n{\nOFFSET 0 0 nan\n}", "t").is_err());
        assert!(Bvh::parse("nonsense", "t").is_err());
    }
}
