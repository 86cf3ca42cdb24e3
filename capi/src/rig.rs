//! `skb_rig`: the production rig of a mesh as the rigged GLB writes it (MakeHuman's 53-bone
//! `game_engine` skeleton for the chosen bone names, rest pose and origin), for hosts that build
//! the rigged body in memory instead of importing the file: bone names, parents (the GLB's node
//! order), rest transforms, the posed local rotations, the rig's rest vertices, normals and
//! 53-bone skin weights. Also the mesh's UVs and normals. Every copy follows the mesh getters'
//! convention: the caller's buffer holds `dst_len` elements, at least the documented count, and
//! nothing is written on error.

use std::ffi::c_char;

use nalgebra::{UnitQuaternion, Vector3};

use sketchbody_core::body::rig::vertex_normals;
use sketchbody_core::body::rig::{RigPose, RigScene, NUM_RIG_BONES};
use sketchbody_core::error::Error;

use super::body::{copy_skin_weights, skb_mesh};
use super::error::fail;
use super::export::{rig_scene, skb_export_options};
use super::ptr::{free_box, give, opt_ref, out_slice, out_slot, try_ref, write_c_string, write_out};
use super::status::skb_status;

/// Number of bones of the production rig (MakeHuman's `game_engine` skeleton); a rig built with
/// twist bones (`skb_export_options_set_twist_bones`) has `SKB_NUM_RIG_BONES` +
/// `SKB_NUM_TWIST_BONES` (`skb_rig_bone_count`).
pub const SKB_NUM_RIG_BONES: u32 = 53;
/// Number of twist bones (upper arms, forearms, thighs) `skb_export_options_set_twist_bones`
/// adds after the 53.
pub const SKB_NUM_TWIST_BONES: u32 = 6;
/// Doubles per bone in `skb_rig_copy_rest_transforms`: translation x, y, z then rotation
/// quaternion x, y, z, w (glTF's order).
pub const SKB_RIG_TRANSFORM_LEN: u32 = 7;
const _: () = assert!(SKB_NUM_RIG_BONES as usize == NUM_RIG_BONES);
/// Number of IK target bones `skb_export_options_set_ik_targets` adds after the others.
pub const SKB_NUM_IK_BONES: u32 = 7;
const _: () = assert!(SKB_NUM_TWIST_BONES as usize == sketchbody_core::body::rig::twist::NUM_TWIST_BONES);
const _: () = assert!(SKB_NUM_IK_BONES as usize == sketchbody_core::body::rig::ik_targets::NUM_IK_BONES);

/// The rig of one mesh in one pose, a snapshot: what `skb_mesh_write_glb` writes for
/// the same mesh and options. Create with `skb_rig_new_from_mesh`, release with `skb_rig_free`; it does
/// not follow later `skb_mesh_pose` calls. Read-only, so several threads may use it at once.
pub struct skb_rig {
    scene: RigScene,
    /// Each bone's rest transform relative to its parent (the root's: to the model frame).
    rest_local: Vec<(Vector3<f64>, UnitQuaternion<f64>)>,
    /// Each bone's posed rotation relative to its parent (the GLB nodes' `rotation`).
    local: Vec<UnitQuaternion<f64>>,
}

/// Writes `rows` (`N` values each) into the caller's `dst` of `dst_len` elements (at least
/// `N × rows.len()`); nothing on error.
///
/// # Safety
/// `dst` must be NULL or valid for writes of `dst_len` elements of `T`.
unsafe fn copy_rows<T: Copy, const N: usize>(rows: &[[T; N]], dst: *mut T, dst_len: usize) -> skb_status {
    // SAFETY: the caller guarantees `dst` is NULL or valid for `dst_len` writes.
    let o = try_status!(unsafe { out_slice(dst, dst_len, N * rows.len(), "dst") });
    for (o, r) in o.chunks_exact_mut(N).zip(rows) {
        o.copy_from_slice(r);
    }
    skb_status::SKB_OK
}

/// Builds the rig of a mesh in its current pose (the rest pose if never posed).
/// @param mesh the mesh, only read.
/// @param opts export options, only read; NULL: the defaults (project names, A-pose rest,
///             origin on the floor).
/// @param out receives a new rig the caller owns (release with `skb_rig_free`); not NULL.
/// @return SKB_OK; SKB_ERR_DEGENERATE_BONE for degenerate bones; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_new_from_mesh(
    mesh: *const skb_mesh,
    opts: *const skb_export_options,
    out: *mut *mut skb_rig,
) -> skb_status {
    ffi_boundary! {
        // SAFETY: `mesh` is NULL or a live mesh handle (the API's contract), only read here.
        let m = try_status!(unsafe { try_ref(mesh, "mesh") });
        // SAFETY: `opts` is NULL or live export options (the API's contract), only read.
        let o = unsafe { opt_ref(opts) };
        // SAFETY: `out` is NULL or valid for writing one pointer.
        let out = try_status!(unsafe { out_slot(out) });
        let (_, scene) = try_core!(rig_scene(m, o));
        let arm = &scene.armature;
        let rest_rot = RigPose::rest(arm.len()).local_rotations(arm);
        let rest_local = arm
            .parents
            .iter()
            .enumerate()
            .map(|(b, parent)| {
                let t = match *parent {
                    None => arm.heads[b],
                    Some(p) => arm.frames[p].inverse() * (arm.heads[b] - arm.heads[p]),
                };
                (t, rest_rot[b])
            })
            .collect();
        let local = scene.pose.local_rotations(arm);
        give(out, skb_rig { scene, rest_local, local })
    }
}

/// Releases a rig.
/// @param rig the rig to release; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_free(rig: *mut skb_rig) {
    // SAFETY: `rig` is NULL or a pointer from `skb_rig_new_from_mesh` not freed before.
    unsafe { free_box(rig) }
}

/// Number of bones: `SKB_NUM_RIG_BONES`, plus `SKB_NUM_TWIST_BONES` with twist bones and
/// `SKB_NUM_IK_BONES` with IK targets.
/// @param rig the rig, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_bone_count(rig: *const skb_rig, out: *mut usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        try_status!(unsafe { write_out(out, r.scene.names.len(), "out") });
        skb_status::SKB_OK
    }
}

/// Number of vertices of the rig's mesh (the mesh's, 13380).
/// @param rig the rig, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_vertex_count(rig: *const skb_rig, out: *mut usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        try_status!(unsafe { write_out(out, r.scene.rest_vertices.len(), "out") });
        skb_status::SKB_OK
    }
}

/// The byte length of a bone's name (UTF-8, without the terminating NUL).
/// @param rig the rig, only read.
/// @param bone the bone, 0 .. `skb_rig_bone_count`−1.
/// @param out receives the length; not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `bone` out of range; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_bone_name_length(rig: *const skb_rig, bone: usize, out: *mut usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        let name = try_status!(bone_name(r, bone));
        try_status!(unsafe { write_out(out, name.len(), "out") });
        skb_status::SKB_OK
    }
}

/// Bone `bone`'s name, or `SKB_ERR_OUT_OF_RANGE` with the message set.
fn bone_name(r: &skb_rig, bone: usize) -> Result<&str, skb_status> {
    r.scene
        .names
        .get(bone)
        .map(String::as_str)
        .ok_or_else(|| fail(&Error::OutOfRange { name: "bone", detail: format!("{bone} >= {}", r.scene.names.len()) }))
}

/// Copies a bone's name: the GLB node's name in the chosen convention.
/// @param rig the rig, only read.
/// @param bone the bone, 0 .. `skb_rig_bone_count`−1.
/// @param dst receives the name as NUL-terminated UTF-8.
/// @param dst_len the size of `dst` in bytes, at least `skb_rig_bone_name_length` + 1 (64 bytes
///                hold every name).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `bone` out of range; SKB_ERR_BUFFER_TOO_SMALL for a
///         short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_bone_name(
    rig: *const skb_rig,
    bone: usize,
    dst: *mut c_char,
    dst_len: usize,
) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        let name = try_status!(bone_name(r, bone));
        try_status!(unsafe { write_c_string(dst, dst_len, name, "dst") });
        skb_status::SKB_OK
    }
}

/// Copies each bone's parent index. Parents come before their children; the order is the GLB's
/// node and joint order.
/// @param rig the rig, only read.
/// @param dst receives one parent index per bone (−1 for the root, bone 0).
/// @param dst_len the element count of `dst` in integers, at least `skb_rig_bone_count`.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_parents(rig: *const skb_rig, dst: *mut i32, dst_len: usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        let parents = &r.scene.armature.parents;
        let o = try_status!(unsafe { out_slice(dst, dst_len, parents.len(), "dst") });
        for (o, parent) in o.iter_mut().zip(parents) {
            *o = parent.map_or(-1, |p| p as i32);
        }
        skb_status::SKB_OK
    }
}

/// Copies each bone's rest transform relative to its parent. The rest is the rig's (A- or
/// T-pose, placed at the chosen origin): the GLB's bind pose. Composing `parent · T(t) · R(q)`
/// from the root gives each bone's rest frame and head.
/// @param rig the rig, only read.
/// @param dst receives `SKB_RIG_TRANSFORM_LEN` doubles per bone: translation x, y, z (metres, in
///            the parent bone's frame; the root's in the model frame, +Y up) then the rotation as a
///            unit quaternion x, y, z, w (parent bone frame → this bone's frame; bone frames have Y
///            along the bone, X the bend axis MakeHuman's roll gives).
/// @param dst_len the element count of `dst` in doubles, at least 7 × `skb_rig_bone_count`.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_rest_transforms(
    rig: *const skb_rig,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        let o = try_status!(unsafe { out_slice(dst, dst_len, 7 * r.rest_local.len(), "dst") });
        for (o, (t, q)) in o.chunks_exact_mut(7).zip(&r.rest_local) {
            o[..3].copy_from_slice(t.as_slice());
            o[3..].copy_from_slice(q.quaternion().coords.as_slice());
        }
        skb_status::SKB_OK
    }
}

/// Copies the posed rotation of each bone relative to its parent: the GLB nodes' `rotation`,
/// what a DCC shows as the pose bones' rotations. With the rest translations of
/// `skb_rig_copy_rest_transforms` (the root's plus `skb_rig_copy_root_translation`) they give
/// the posed skeleton.
/// @param rig the rig, only read.
/// @param dst receives 4 doubles per bone: unit quaternion x, y, z, w (the root's relative to the
///            model frame).
/// @param dst_len the element count of `dst` in doubles, at least 4 × `skb_rig_bone_count`.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_local_rotations(
    rig: *const skb_rig,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        let rows: Vec<[f64; 4]> = r.local.iter().map(|q| q.quaternion().coords.into()).collect();
        unsafe { copy_rows(&rows, dst, dst_len) }
    }
}

/// Copies the root's translation in the pose: non-zero only with the origin on the floor, where
/// it keeps the posed body's lowest point at y = 0.
/// @param rig the rig, only read.
/// @param dst receives x, y, z doubles, metres, model frame.
/// @param dst_len the element count of `dst` in doubles, at least 3.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_root_translation(
    rig: *const skb_rig,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        unsafe { copy_rows(&[r.scene.pose.root_translation.into()], dst, dst_len) }
    }
}

/// Copies the posed bone heads as the library computes them (the rig's forward kinematics, what
/// a glTF viewer shows).
/// @param rig the rig, only read.
/// @param dst receives x, y, z doubles per bone, metres, the export's frame.
/// @param dst_len the element count of `dst` in doubles, at least 3 × `skb_rig_bone_count`.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_posed_heads(rig: *const skb_rig, dst: *mut f64, dst_len: usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        let rows: Vec<[f64; 3]> = r.scene.pose.heads(&r.scene.armature).into_iter().map(Into::into).collect();
        unsafe { copy_rows(&rows, dst, dst_len) }
    }
}

/// Copies the translation from the mesh's model frame to the export's frame: the rig's rest =
/// the mesh's rest + this, before any T-pose.
/// @param rig the rig, only read.
/// @param dst receives x, y, z doubles, metres.
/// @param dst_len the element count of `dst` in doubles, at least 3.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_offset(rig: *const skb_rig, dst: *mut f64, dst_len: usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        unsafe { copy_rows(&[r.scene.offset.into()], dst, dst_len) }
    }
}

/// Copies the rig's rest vertices: the bind pose, the mesh's rest placed at the chosen origin,
/// skinned into the T-pose when asked. Faces are the mesh's (`skb_mesh_copy_faces`,
/// `skb_mesh_copy_triangles`).
/// @param rig the rig, only read.
/// @param dst receives x, y, z floats per vertex, metres.
/// @param dst_len the element count of `dst` in floats, at least 3 × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_rest_vertices(rig: *const skb_rig, dst: *mut f32, dst_len: usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        unsafe { copy_rows(&r.scene.rest_vertices, dst, dst_len) }
    }
}

/// Number of shape keys (0 unless the options asked for them,
/// `skb_export_options_set_shape_keys`).
/// @param rig the rig, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_shape_key_count(rig: *const skb_rig, out: *mut usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        // SAFETY: `out` is NULL or valid for writing one `usize`.
        try_status!(unsafe { write_out(out, r.scene.shape_keys.len(), "out") });
        skb_status::SKB_OK
    }
}

/// Copies a shape key's displacement of each rest vertex (the key at value 1 adds them, the base
/// is the fitted body). Key `k` is named `shape_NN` with NN = k + 1 in two digits (the GLB's
/// `extras.targetNames`, the FBX and USD shapes' names).
/// @param rig the rig, only read.
/// @param key the shape key, below `skb_rig_shape_key_count`.
/// @param dst receives x, y, z floats per vertex, metres, `skb_rig_copy_rest_vertices`' order
///            and frame.
/// @param dst_len the element count of `dst` in floats, at least 3 × vertex count.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `key` ≥ `skb_rig_shape_key_count`;
///         SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_shape_key(
    rig: *const skb_rig,
    key: usize,
    dst: *mut f32,
    dst_len: usize,
) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        let keys = &r.scene.shape_keys;
        let Some(k) = keys.get(key) else {
            return fail(&Error::OutOfRange { name: "shape key", detail: format!("{key} >= {}", keys.len()) });
        };
        unsafe { copy_rows(&k.deltas, dst, dst_len) }
    }
}

/// Copies the rig's posed vertices: the rig's own linear blend skinning of the rest vertices,
/// as a glTF viewer shows the GLB.
/// @param rig the rig, only read.
/// @param dst receives x, y, z floats per vertex, metres.
/// @param dst_len the element count of `dst` in floats, at least 3 × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_posed_vertices(rig: *const skb_rig, dst: *mut f32, dst_len: usize) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        unsafe { copy_rows(&r.scene.posed_vertices, dst, dst_len) }
    }
}

/// Copies the skin weights to the rig's bones: for vertex v, slots `4v .. 4v+3` of both buffers
/// (unused slots bone 0, weight 0).
/// @param rig the rig, only read.
/// @param bones receives indices into the rig's bone order.
/// @param weights receives the weights, summing to 1 per vertex.
/// @param len the element count of each buffer, at least `SKB_MAX_INFLUENCES` × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for short buffers; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rig_copy_skin_weights(
    rig: *const skb_rig,
    bones: *mut u32,
    weights: *mut f32,
    len: usize,
) -> skb_status {
    ffi_boundary! {
        let r = try_status!(unsafe { try_ref(rig, "rig") });
        // SAFETY: `bones` and `weights` are NULL or valid for writes of `len` elements each.
        unsafe { copy_skin_weights(&r.scene.skin, bones, weights, len) }
    }
}

/// Number of UV coordinates of the mesh (texture corners shared by faces; more than the
/// vertices, because seams split them).
/// @param mesh the mesh, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_uv_count(mesh: *const skb_mesh, out: *mut usize) -> skb_status {
    ffi_boundary! {
        let m = try_status!(unsafe { try_ref(mesh, "mesh") });
        try_status!(unsafe { write_out(out, m.model.uvs().len(), "out") });
        skb_status::SKB_OK
    }
}

/// Copies the UV coordinates.
/// @param mesh the mesh, only read.
/// @param dst receives u, v floats each, v up as in OBJ and MakeHuman (glTF's v is 1 − v).
/// @param dst_len the element count of `dst` in floats, at least 2 × `skb_mesh_uv_count`.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_uvs(mesh: *const skb_mesh, dst: *mut f32, dst_len: usize) -> skb_status {
    ffi_boundary! {
        let m = try_status!(unsafe { try_ref(mesh, "mesh") });
        unsafe { copy_rows(m.model.uvs(), dst, dst_len) }
    }
}

/// Copies, for each quad face, the UV index of each of its 4 corners.
/// @param mesh the mesh, only read.
/// @param dst receives UV indices (into `skb_mesh_copy_uvs`), 4 per face, in the corner order of
///            `skb_mesh_copy_faces`.
/// @param dst_len the element count of `dst` in integers, at least 4 × face count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_face_uvs(mesh: *const skb_mesh, dst: *mut u32, dst_len: usize) -> skb_status {
    ffi_boundary! {
        let m = try_status!(unsafe { try_ref(mesh, "mesh") });
        unsafe { copy_rows(m.model.face_uvs(), dst, dst_len) }
    }
}

/// Copies unit vertex normals: area-weighted face normals, outward, as the GLB writes.
/// @param mesh the mesh, only read.
/// @param posed true: of the posed vertices (the current `skb_mesh_pose`, the rest before any);
///              false: of the rest vertices.
/// @param dst receives x, y, z floats per vertex.
/// @param dst_len the element count of `dst` in floats, at least 3 × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_normals(
    mesh: *const skb_mesh,
    posed: bool,
    dst: *mut f32,
    dst_len: usize,
) -> skb_status {
    ffi_boundary! {
        let m = try_status!(unsafe { try_ref(mesh, "mesh") });
        let v = match (&m.posed, posed) {
            (Some(p), true) => &p.vertices,
            _ => &m.rest.vertices,
        };
        unsafe { copy_rows(&vertex_normals(v, m.model.faces()), dst, dst_len) }
    }
}
