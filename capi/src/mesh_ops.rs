//! Mesh operations: the weak-perspective camera struct, the silhouette rasteriser
//! (`skb_rasterizer`, also on raw arrays), and posing, rasterising and exporting an `skb_mesh`.

use std::ffi::c_char;

use nalgebra::Matrix3;

use sketchbody_core::body::ik::{solve, IkOptions};
use sketchbody_core::body::rig::FaceUvs;
use sketchbody_core::body::skin::{skin, SkinMethod};
use sketchbody_core::camera::WeakPerspective;
use sketchbody_core::error::Error;
use sketchbody_core::export::obj::write_obj;
use sketchbody_core::image::save_png;
use sketchbody_core::raster::Rasterizer;
use sketchbody_core::render::preview::preview;
use sketchbody_core::skeleton::{Joints3, NUM_JOINTS};

use super::body::{skb_mesh, Posed};
use super::error::{fail, fail_with};
use super::ptr::*;
use super::status::skb_status;

/// The weak-perspective camera of paper eq. (1) (docs/design.md): a model point X (metres, +Y up,
/// +Z toward the viewer) maps to pixel `u = sx (R X)_x + t[0]`, `v = -sy (R X)_y + t[1]`.
/// `r` is the rotation, row-major (`r[3 * row + col]`). A plain struct: copy it freely; its
/// layout (104 bytes) is part of the ABI.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct skb_camera {
    /// Horizontal scale, pixels per metre (> 0).
    pub sx: f64,
    /// Vertical scale, pixels per metre (> 0).
    pub sy: f64,
    /// Rotation model -> camera, row-major, orthonormal with determinant +1.
    pub r: [f64; 9],
    /// Image position of the model origin, pixels.
    pub t: [f64; 2],
}

const _: () = assert!(std::mem::size_of::<skb_camera>() == 104);

impl From<&skb_camera> for WeakPerspective {
    fn from(c: &skb_camera) -> Self {
        WeakPerspective { sx: c.sx, sy: c.sy, r: Matrix3::from_row_slice(&c.r), t: c.t }
    }
}

/// A reusable silhouette rasteriser: keeps its buffers between calls so that repeated
/// rasterisation allocates nothing. Create with [`skb_rasterizer_new`], release with
/// [`skb_rasterizer_free`]. Not thread-safe: use one per thread (it may move between threads).
pub struct skb_rasterizer {
    inner: Rasterizer,
}

/// Creates a rasteriser.
/// @param out receives a new rasteriser the caller owns (free with [`skb_rasterizer_free`]);
///            not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL `out`.
#[no_mangle]
pub unsafe extern "C" fn skb_rasterizer_new(out: *mut *mut skb_rasterizer) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            give(out, skb_rasterizer { inner: Rasterizer::new() })
        }
    }
}

/// Releases a rasteriser made by [`skb_rasterizer_new`].
/// @param r the rasteriser to release; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_rasterizer_free(r: *mut skb_rasterizer) {
    unsafe { free_box(r) }
}

/// Rasterises the silhouette of a triangle mesh given as raw arrays. On error nothing is
/// written. Arrays are only read during the call. Thread-safe with distinct rasterisers.
/// @param rasterizer the rasteriser whose buffers are reused (changed), or NULL (a temporary one
///                   is used).
/// @param verts `nverts` points as x, y, z floats (metres, model frame).
/// @param nverts the number of points in `verts` (3 floats each).
/// @param tris `ntris` triangles as three 0-based vertex indices.
/// @param ntris the number of triangles in `tris` (3 indices each).
/// @param cam the camera, only read.
/// @param w the mask width in pixels, 1..=4096.
/// @param h the mask height in pixels, 1..=4096.
/// @param mask receives `h` rows of `w` bytes: 255 where a pixel's centre (i + 0.5, j + 0.5)
///             lies inside a projected triangle (top-left fill rule, both windings), else 0.
/// @param mask_stride bytes between the starts of consecutive rows of `mask`.
/// @param mask_len the size of `mask` in bytes, at least `mask_stride * (h - 1) + w`.
/// @return SKB_OK; SKB_ERR_MESH_OUTSIDE_IMAGE when the projected mesh misses the image
///         entirely; SKB_ERR_BAD_STRIDE, SKB_ERR_BUFFER_TOO_SMALL, SKB_ERR_NON_FINITE
///         (non-finite vertices); errors for bad sizes, an invalid camera, an index out of
///         range or vertices projecting beyond ±32768 px; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rasterizer_rasterize_triangles(
    rasterizer: *mut skb_rasterizer,
    verts: *const f32,
    nverts: usize,
    tris: *const u32,
    ntris: usize,
    cam: *const skb_camera,
    w: u32,
    h: u32,
    mask: *mut u8,
    mask_stride: usize,
    mask_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let cam = WeakPerspective::from(try_status!(try_ref(cam, "cam")));
            let v3 = try_status!(try_slice_of(verts.cast::<[f32; 3]>(), nverts, "verts"));
            let t3 = try_status!(try_slice_of(tris.cast::<[u32; 3]>(), ntris, "tris"));
            let (w, h) = (w as usize, h as usize);
            try_core!(sketchbody_core::raster::check_size(w, h));
            if mask_stride < w {
                return fail(&sketchbody_core::Error::BadStride { stride: mask_stride, row_bytes: w });
            }
            let needed = try_status!(mask_stride.checked_mul(h - 1).and_then(|x| x.checked_add(w))
                .ok_or_else(|| fail_with(skb_status::SKB_ERR_OUT_OF_RANGE, "mask_stride is absurd")));
            if mask_len < needed {
                return fail(&sketchbody_core::Error::BufferTooSmall { name: "mask", len: mask_len, needed, unit: "bytes" });
            }
            let out = try_status!(try_slice_mut(mask, mask_len, "mask"));
            let mut temp = None;
            let r = match opt_mut(rasterizer) {
                Some(r) => &mut r.inner,
                None => temp.insert(Rasterizer::new()),
            };
            try_core!(r.rasterize(v3, t3, &cam, w, h, false));
            for (y, row) in r.mask().chunks_exact(w).enumerate() {
                out[y * mask_stride..y * mask_stride + w].copy_from_slice(row);
            }
            skb_status::SKB_OK
        }
    }
}

/// `skb_mesh_pose` flag: scale bones along their length so the joints land on the targets.
pub const SKB_POSE_RETARGET: u32 = 1;
/// `skb_mesh_pose` flag: dual-quaternion skinning instead of linear blend skinning.
pub const SKB_POSE_DUAL_QUATERNION: u32 = 2;

fn posed_vertices(m: &skb_mesh) -> &[[f32; 3]] {
    m.posed.as_ref().map_or(&m.rest.vertices, |p| &p.vertices)
}

/// Poses a mesh to 15 target joints by inverse kinematics and skinning. The pose replaces any
/// earlier one (the rest shape is kept; posing to the rest joints gives the rest pose). Needs
/// exclusive use of `mesh`; skinning runs on the rayon pool.
/// @param mesh the mesh, changed (unchanged on error).
/// @param joints x, y, z doubles per joint in canonical order, metres, model frame.
/// @param joints_len the element count of `joints`: 45.
/// @param flags 0 or a combination of `SKB_POSE_RETARGET` and `SKB_POSE_DUAL_QUATERNION`.
/// @return SKB_OK; SKB_ERR_NON_FINITE for non-finite joints; SKB_ERR_DEGENERATE_BONE for coincident
///         joints; SKB_ERR_OUT_OF_RANGE for unknown flags or a wrong length; argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_pose(
    mesh: *mut skb_mesh,
    joints: *const f64,
    joints_len: usize,
    flags: u32,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_mut(mesh, "mesh"));
            if joints_len != 3 * NUM_JOINTS {
                return fail(&Error::OutOfRange { name: "joints_len", detail: format!("{joints_len}, expected {}", 3 * NUM_JOINTS) });
            }
            let j = try_status!(try_slice_of(joints, joints_len, "joints"));
            if flags & !(SKB_POSE_RETARGET | SKB_POSE_DUAL_QUATERNION) != 0 {
                return fail(&Error::OutOfRange { name: "flags", detail: format!("unknown bits in {flags:#x}") });
            }
            let target: Joints3 = std::array::from_fn(|i| [j[3 * i], j[3 * i + 1], j[3 * i + 2]]);
            let pose = try_core!(solve(&m.rest.joints, &target, &IkOptions { retarget: flags & SKB_POSE_RETARGET != 0 }));
            let method = if flags & SKB_POSE_DUAL_QUATERNION != 0 { SkinMethod::DualQuaternion } else { SkinMethod::Linear };
            let vertices = try_core!(skin(&m.rest.vertices, m.model.skin_weights(), &pose, method));
            m.posed = Some(Box::new(Posed { pose, vertices }));
            skb_status::SKB_OK
        }
    }
}

/// Copies the posed vertices (the rest vertices before any `skb_mesh_pose`). On error nothing
/// is written.
/// @param mesh the mesh, only read.
/// @param dst receives x, y, z floats per vertex, metres.
/// @param dst_len the element count of `dst` in floats, at least 3 × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_posed_vertices(
    mesh: *const skb_mesh,
    dst: *mut f32,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let v = posed_vertices(m);
            let out = try_status!(out_slice(dst, dst_len, 3 * v.len(), "dst"));
            for (o, p) in out.chunks_exact_mut(3).zip(v) {
                o.copy_from_slice(p);
            }
            skb_status::SKB_OK
        }
    }
}

/// Copies the posed joints (the rest joints before any `skb_mesh_pose`).
/// @param mesh the mesh, only read.
/// @param dst receives 15 × x, y, z doubles, metres.
/// @param dst_len the element count of `dst` in doubles, at least 45.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_posed_joints(
    mesh: *const skb_mesh,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let j = m.posed.as_ref().map_or(&m.rest.joints, |p| &p.pose.joints);
            let out = try_status!(out_slice(dst, dst_len, 3 * NUM_JOINTS, "dst"));
            for (o, p) in out.chunks_exact_mut(3).zip(j) {
                o.copy_from_slice(p);
            }
            skb_status::SKB_OK
        }
    }
}

/// Rasterises the silhouette of the posed mesh (rules, sizes and errors as in
/// [`skb_rasterizer_rasterize_triangles`]).
/// @param mesh the mesh, only read.
/// @param rasterizer the rasteriser whose buffers are reused (changed), or NULL.
/// @param cam the camera, only read.
/// @param w the mask width in pixels, 1..=4096.
/// @param h the mask height in pixels, 1..=4096.
/// @param mask receives `h` rows of `w` bytes: 255 where a pixel's centre (i + 0.5, j + 0.5)
///             lies inside a projected triangle (top-left fill rule, both windings), else 0.
/// @param mask_stride bytes between the starts of consecutive rows of `mask`.
/// @param mask_len the size of `mask` in bytes, at least `mask_stride * (h - 1) + w`.
/// @return the statuses of [`skb_rasterizer_rasterize_triangles`].
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_rasterize(
    mesh: *const skb_mesh,
    rasterizer: *mut skb_rasterizer,
    cam: *const skb_camera,
    w: u32,
    h: u32,
    mask: *mut u8,
    mask_stride: usize,
    mask_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let v = posed_vertices(m);
            let t = m.model.triangles();
            skb_rasterizer_rasterize_triangles(rasterizer, v.as_ptr().cast(), v.len(), t.as_ptr().cast(), t.len(), cam, w, h, mask, mask_stride, mask_len)
        }
    }
}

/// Writes the mesh as Wavefront OBJ: normals, MakeHuman UVs, quads. Written atomically: on
/// error no file is left.
/// @param mesh the mesh, only read.
/// @param path the output file path, NUL-terminated UTF-8.
/// @param posed true: the posed vertices; false: the rest pose.
/// @return SKB_OK; SKB_ERR_IO when the file cannot be written; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_write_obj(mesh: *const skb_mesh, path: *const c_char, posed: bool) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let path = try_status!(path_arg(path, "path"));
            let v = if posed { posed_vertices(m) } else { &m.rest.vertices };
            let uvs = FaceUvs { coords: m.model.uvs().to_vec(), quads: m.model.face_uvs().to_vec() };
            try_core!(write_obj(path, v, m.model.faces(), Some(&uvs)));
            skb_status::SKB_OK
        }
    }
}

/// Writes a preview PNG of the posed mesh: front and right-side views side by side. Written
/// atomically.
/// @param mesh the mesh, only read.
/// @param path the output file path, NUL-terminated UTF-8.
/// @param size the side of each view in pixels, 1..=4096 (each view is `size`×`size`).
/// @return SKB_OK; SKB_ERR_EMPTY_IMAGE for a `size` of 0, SKB_ERR_OUT_OF_RANGE above 4096;
///         SKB_ERR_IO when the file cannot be written; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_write_preview(mesh: *const skb_mesh, path: *const c_char, size: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let path = try_status!(path_arg(path, "path"));
            let img = try_core!(preview(posed_vertices(m), &m.model.triangles(), size as usize));
            try_core!(save_png(&img.view(), path));
            skb_status::SKB_OK
        }
    }
}
