//! Mesh operations on raw arrays: the weak-perspective camera struct and the silhouette
//! rasteriser (`skb_rasterizer`).

use nalgebra::Matrix3;

use crate::camera::WeakPerspective;
use crate::render::raster::Rasterizer;

use super::error::{fail, fail_with};
use super::ptr::{try_ref, try_slice_mut, try_slice_of};
use super::status::skb_status;

/// The weak-perspective camera of paper eq. (1) (DESIGN.md): a model point X (metres, +Y up,
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

/// Creates a rasteriser and stores it in `*out` (caller owns it; free with
/// [`skb_rasterizer_free`]).
#[no_mangle]
pub unsafe extern "C" fn skb_rasterizer_new(out: *mut *mut skb_rasterizer) -> skb_status {
    ffi_boundary! {
        if out.is_null() {
            return fail_with(skb_status::SKB_ERR_NULL_POINTER, "out is NULL");
        }
        *out = Box::into_raw(Box::new(skb_rasterizer { inner: Rasterizer::new() }));
        skb_status::SKB_OK
    }
}

/// Releases a rasteriser made by [`skb_rasterizer_new`]; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_rasterizer_free(r: *mut skb_rasterizer) {
    if !r.is_null() {
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| drop(Box::from_raw(r))));
    }
}

/// Rasterises the silhouette of a triangle mesh given as raw arrays: `verts` holds `nverts`
/// points as x, y, z floats (metres, model frame), `tris` holds `ntris` triangles as three
/// 0-based vertex indices. Pixel (i, j) is set to 255 when its centre (i + 0.5, j + 0.5) lies
/// inside a projected triangle (top-left fill rule, both windings), else 0. Writes `h` rows of
/// `w` bytes into `mask`, rows `mask_stride` bytes apart; `mask_len` must be at least
/// `mask_stride * (h - 1) + w`. Sizes 1..=4096 a side. Errors: NULL pointers, bad sizes or
/// strides, an invalid camera, index out of range, non-finite vertices, vertices projecting
/// beyond ±32768 px, and `SKB_ERR_MESH_OUTSIDE_IMAGE` when the projected mesh misses the image
/// entirely. On error nothing is written. `rasterizer` may be NULL (a temporary one is used).
/// Arrays are only read during the call. Thread-safe with distinct rasterisers.
#[no_mangle]
pub unsafe extern "C" fn skb_rasterize_triangles(
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
    ffi_boundary! {
        let cam = WeakPerspective::from(try_status!(try_ref(cam, "cam")));
        let v3 = try_status!(try_slice_of(verts.cast::<[f32; 3]>(), nverts, "verts"));
        let t3 = try_status!(try_slice_of(tris.cast::<[u32; 3]>(), ntris, "tris"));
        let (w, h) = (w as usize, h as usize);
        try_core!(crate::render::raster::check_size(w, h));
        if mask_stride < w {
            return fail(&crate::Error::BadStride { stride: mask_stride, row_bytes: w });
        }
        let needed = try_status!(mask_stride.checked_mul(h - 1).and_then(|x| x.checked_add(w))
            .ok_or_else(|| fail_with(skb_status::SKB_ERR_OUT_OF_RANGE, "mask_stride is absurd")));
        if mask_len < needed {
            return fail(&crate::Error::BufferTooSmall { len: mask_len, needed });
        }
        let out = try_status!(try_slice_mut(mask, mask_len, "mask"));
        let mut temp = None;
        let r = if rasterizer.is_null() { temp.insert(Rasterizer::new()) } else { &mut (*rasterizer).inner };
        try_core!(r.rasterize(v3, t3, &cam, w, h, false));
        for (y, row) in r.mask().chunks_exact(w).enumerate() {
            out[y * mask_stride..y * mask_stride + w].copy_from_slice(row);
        }
        skb_status::SKB_OK
    }
}
