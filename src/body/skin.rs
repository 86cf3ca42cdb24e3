//! Skinning: posed vertex positions from rest vertices, skin weights and a [`Pose`].
//!
//! Linear blend skinning (the paper's, Kavan et al. [15]) blends the bones' affine maps;
//! dual-quaternion skinning blends their rigid parts as unit dual quaternions instead, which
//! keeps volume at twisted or strongly bent joints (no "candy wrapper"). With retargeting the
//! bone stretches are blended linearly first and the rigid parts by dual quaternions.
//! Both run in parallel over vertices (rayon) for meshes above a few thousand vertices; every
//! vertex is computed independently, so the result does not depend on the number of threads.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use rayon::prelude::*;

use super::ik::Pose;
use super::rig::VertexWeights;
use crate::error::{Error, Result};
use crate::skeleton::{BONES, NUM_BONES};

/// Skinning method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SkinMethod {
    /// Linear blend skinning (default, as in the paper).
    #[default]
    Linear,
    /// Dual-quaternion skinning.
    DualQuaternion,
}

/// Per-bone data prepared once per pose (f32, for the per-vertex loop).
#[derive(Clone, Copy, Debug)]
struct BoneXf {
    /// Affine map of LBS: posed = m * rest + t.
    m: [[f32; 3]; 3],
    t: [f32; 3],
    /// Stretch about the bone's rest start: s * (x - o) + o (DQS only).
    s: [[f32; 3]; 3],
    o: [f32; 3],
    /// Rigid part as a dual quaternion (real, dual), each (w, x, y, z).
    real: [f32; 4],
    dual: [f32; 4],
}

fn m3(m: &Matrix3<f64>) -> [[f32; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = m[(r, c)] as f32;
        }
    }
    out
}

fn prepare(pose: &Pose) -> [BoneXf; NUM_BONES] {
    std::array::from_fn(|b| {
        let (m, t) = pose.bone_affine(b);
        let o = Vector3::from(pose.rest[BONES[b].0]);
        let q: UnitQuaternion<f64> = pose.rotations[b];
        // Rigid part: x -> R (x - o) + P_s, i.e. translation P_s - R o.
        let tr = Vector3::from(pose.joints[BONES[b].0]) - q * o;
        let qr = q.into_inner();
        let qd = Quaternion::new(0.0, tr.x, tr.y, tr.z) * qr * 0.5;
        BoneXf {
            m: m3(&m),
            t: [t.x as f32, t.y as f32, t.z as f32],
            s: m3(&pose.stretch_matrix(b)),
            o: [o.x as f32, o.y as f32, o.z as f32],
            real: [qr.w as f32, qr.i as f32, qr.j as f32, qr.k as f32],
            dual: [qd.w as f32, qd.i as f32, qd.j as f32, qd.k as f32],
        }
    })
}

fn apply(m: &[[f32; 3]; 3], p: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2])
}

fn lbs_vertex(bones: &[BoneXf; NUM_BONES], p: [f32; 3], w: &VertexWeights) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for (b, x) in w.influences() {
        let bx = &bones[b];
        let q = apply(&bx.m, p);
        for k in 0..3 {
            out[k] += x * (q[k] + bx.t[k]);
        }
    }
    out
}

fn dqs_vertex(bones: &[BoneXf; NUM_BONES], p: [f32; 3], w: &VertexWeights) -> [f32; 3] {
    // Stretch first (linear blend of the per-bone stretches about their start joints).
    let mut x = [0.0f32; 3];
    let (mut real, mut dual) = ([0.0f32; 4], [0.0f32; 4]);
    let mut pivot: Option<[f32; 4]> = None;
    for (b, wt) in w.influences() {
        let bx = &bones[b];
        let d = [p[0] - bx.o[0], p[1] - bx.o[1], p[2] - bx.o[2]];
        let s = apply(&bx.s, d);
        for k in 0..3 {
            x[k] += wt * (s[k] + bx.o[k]);
        }
        // Keep all quaternions in the hemisphere of the first influence.
        let first = *pivot.get_or_insert(bx.real);
        let dot: f32 = (0..4).map(|k| first[k] * bx.real[k]).sum();
        let sgn = if dot < 0.0 { -wt } else { wt };
        for k in 0..4 {
            real[k] += sgn * bx.real[k];
            dual[k] += sgn * bx.dual[k];
        }
    }
    let n = (real.iter().map(|c| c * c).sum::<f32>()).sqrt();
    if n < 1e-12 {
        return x;
    }
    let (r, d) = (
        Quaternion::new(real[0], real[1], real[2], real[3]) / n,
        Quaternion::new(dual[0], dual[1], dual[2], dual[3]) / n,
    );
    // Rotate by r and translate by 2 * d * conj(r).
    let rotated = UnitQuaternion::new_unchecked(r) * Vector3::new(x[0], x[1], x[2]);
    let t = (d * r.conjugate()) * 2.0;
    [rotated.x + t.i, rotated.y + t.j, rotated.z + t.k]
}

/// Meshes of at most this many vertices are skinned on the calling thread (the shape fit's
/// proxy, skinned inside an already parallel loop); larger ones in parallel chunks.
const PARALLEL_MIN: usize = 4096;

/// Skins `rest` vertices (metres, model frame) with `weights` (one entry per vertex) into
/// `out` (resized to the vertex count). Errors when the lengths differ, and
/// [`Error::NonFinite`] when a skinned coordinate overflows to infinity or NaN (a pose with huge
/// joint positions): such a result is never reported as success. Parallel above
/// [`PARALLEL_MIN`] vertices; every vertex is computed alike either way (deterministic).
pub fn skin_into(
    rest: &[[f32; 3]],
    weights: &[VertexWeights],
    pose: &Pose,
    method: SkinMethod,
    out: &mut Vec<[f32; 3]>,
) -> Result<()> {
    if rest.len() != weights.len() {
        return Err(Error::OutOfRange {
            name: "skin weights",
            detail: format!("{} weight entries for {} vertices", weights.len(), rest.len()),
        });
    }
    if let Some(w) = weights.iter().find(|w| w.influences().any(|(b, _)| b >= NUM_BONES)) {
        return Err(Error::OutOfRange { name: "skin weights", detail: format!("bone index >= {NUM_BONES} in {w:?}") });
    }
    let bones = prepare(pose);
    out.resize(rest.len(), [0.0; 3]);
    // Skins a chunk; `true` when every coordinate it wrote is finite.
    let chunk = |o: &mut [[f32; 3]], r: &[[f32; 3]], w: &[VertexWeights]| {
        let mut finite = true;
        for ((o, &p), w) in o.iter_mut().zip(r).zip(w) {
            *o = match method {
                SkinMethod::Linear => lbs_vertex(&bones, p, w),
                SkinMethod::DualQuaternion => dqs_vertex(&bones, p, w),
            };
            finite &= o[0].is_finite() & o[1].is_finite() & o[2].is_finite();
        }
        finite
    };
    const CHUNK: usize = 1024;
    let finite = if rest.len() <= PARALLEL_MIN {
        chunk(out, rest, weights)
    } else {
        out.par_chunks_mut(CHUNK)
            .zip(rest.par_chunks(CHUNK).zip(weights.par_chunks(CHUNK)))
            .map(|(o, (r, w))| chunk(o, r, w))
            .reduce(|| true, |a, b| a & b)
    };
    if finite {
        return Ok(());
    }
    let c = out.iter().flatten().find(|c| !c.is_finite()).map_or(f64::NAN, |&c| c as f64);
    Err(Error::NonFinite { name: "skinned vertex coordinate", value: c })
}

/// [`skin_into`] into a new vector.
pub fn skin(rest: &[[f32; 3]], weights: &[VertexWeights], pose: &Pose, method: SkinMethod) -> Result<Vec<[f32; 3]>> {
    let mut out = Vec::new();
    skin_into(rest, weights, pose, method, &mut out)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::ik::{solve, IkOptions};
    use crate::body::procedural::{capsule_humanoid, random_pose, rest_joints};
    use rand::SeedableRng;

    fn max_dist(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
        a.iter().zip(b).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f32>().sqrt()).fold(0.0, f32::max)
    }

    /// A turn of vertices at the largest f32 overflows to infinity: a non-finite error, never a
    /// result, on a mesh skinned on the calling thread and on one skinned in parallel chunks.
    #[test]
    fn overflowing_coordinates_are_an_error_at_any_mesh_size() {
        let rest = rest_joints();
        let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.7);
        let mut target = rest;
        for p in target.iter_mut() {
            let q = turn * Vector3::from(*p);
            *p = [q.x, q.y, q.z];
        }
        let pose = solve(&rest, &target, &IkOptions::default()).unwrap();
        for (rings, segs) in [(12, 8), (64, 48)] {
            let mut mesh = capsule_humanoid(&rest, rings, segs);
            assert_eq!(mesh.vertices.len() > PARALLEL_MIN, rings == 64, "{}", mesh.vertices.len());
            mesh.vertices.iter_mut().for_each(|v| *v = [f32::MAX; 3]);
            for method in [SkinMethod::Linear, SkinMethod::DualQuaternion] {
                let got = skin(&mesh.vertices, &mesh.weights, &pose, method);
                assert!(matches!(got, Err(Error::NonFinite { name: "skinned vertex coordinate", .. })), "{got:?}");
            }
        }
    }

    #[test]
    fn rest_pose_and_rigid_motion_are_reproduced_by_both_methods() {
        let rest = rest_joints();
        let mesh = capsule_humanoid(&rest, 12, 8);
        let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.7);
        let mut target = rest;
        for p in target.iter_mut() {
            let q = turn * Vector3::from(*p) + Vector3::new(0.1, 0.2, -0.3);
            *p = [q.x, q.y, q.z];
        }
        for method in [SkinMethod::Linear, SkinMethod::DualQuaternion] {
            let pose = solve(&rest, &rest, &IkOptions::default()).unwrap();
            let out = skin(&mesh.vertices, &mesh.weights, &pose, method).unwrap();
            assert!(max_dist(&out, &mesh.vertices) < 1e-5, "{method:?} rest");
            let pose = solve(&rest, &target, &IkOptions::default()).unwrap();
            let out = skin(&mesh.vertices, &mesh.weights, &pose, method).unwrap();
            let expect: Vec<[f32; 3]> = mesh
                .vertices
                .iter()
                .map(|p| {
                    let q = turn * Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) + Vector3::new(0.1, 0.2, -0.3);
                    [q.x as f32, q.y as f32, q.z as f32]
                })
                .collect();
            assert!(max_dist(&out, &expect) < 1e-5, "{method:?} rigid: {}", max_dist(&out, &expect));
        }
    }

    #[test]
    fn single_bone_vertices_follow_their_bone_and_methods_agree_there() {
        let rest = rest_joints();
        let mesh = capsule_humanoid(&rest, 12, 8);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let target = random_pose(&rest, &mut rng, 0.15);
        let pose = solve(&rest, &target, &IkOptions { retarget: true }).unwrap();
        let lbs = skin(&mesh.vertices, &mesh.weights, &pose, SkinMethod::Linear).unwrap();
        let dqs = skin(&mesh.vertices, &mesh.weights, &pose, SkinMethod::DualQuaternion).unwrap();
        let mut rigid = 0;
        for (i, w) in mesh.weights.iter().enumerate() {
            if w.weights[0] > 0.99999 {
                let (m, t) = pose.bone_affine(w.bones[0] as usize);
                let p = mesh.vertices[i];
                let e = m * Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) + t;
                for (name, got) in [("lbs", lbs[i]), ("dqs", dqs[i])] {
                    let err = (Vector3::new(got[0] as f64, got[1] as f64, got[2] as f64) - e).norm();
                    assert!(err < 2e-5, "{name} vertex {i} off by {err} m");
                }
                rigid += 1;
            }
        }
        assert!(rigid > 100);
        // Deterministic: same input, bit-identical output.
        assert_eq!(lbs, skin(&mesh.vertices, &mesh.weights, &pose, SkinMethod::Linear).unwrap());
        assert!(skin(&mesh.vertices[1..], &mesh.weights, &pose, SkinMethod::Linear).is_err());
    }

    /// A quaternion and its negation are the same rotation: flipping the sign of every other
    /// bone's stored rotation must not change dual-quaternion skinning (the blend keeps every
    /// influence in the first one's hemisphere), here on a rigid motion of the whole body.
    #[test]
    fn dual_quaternion_blend_ignores_quaternion_sign() {
        let rest = rest_joints();
        let mesh = capsule_humanoid(&rest, 12, 8);
        let turn = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 1.1);
        let target = rest.map(|p| {
            let q = turn * Vector3::from(p) + Vector3::new(-0.2, 0.1, 0.4);
            [q.x, q.y, q.z]
        });
        let pose = solve(&rest, &target, &IkOptions::default()).unwrap();
        let want = skin(&mesh.vertices, &mesh.weights, &pose, SkinMethod::DualQuaternion).unwrap();
        let mut flipped = pose.clone();
        for (b, q) in flipped.rotations.iter_mut().enumerate() {
            if b % 2 == 1 {
                *q = UnitQuaternion::new_unchecked(-q.into_inner());
            }
        }
        let got = skin(&mesh.vertices, &mesh.weights, &flipped, SkinMethod::DualQuaternion).unwrap();
        let blended = mesh.weights.iter().filter(|w| w.weights[0] < 0.9).count();
        assert!(blended > 50, "the mesh has blended vertices: {blended}");
        assert!(max_dist(&got, &want) < 1e-5, "sign flips moved vertices by {} m", max_dist(&got, &want));
    }
}
