//! The sketch as the body's texture, as `sketchbody run` makes `body_texture.png`: the sketch
//! projected through the estimated camera onto the posed mesh's UV layout
//! (`skb_result_project_texture`, `skb_mesh_project_texture`), a colour decoder
//! (`skb_rgb_image`: PNG/JPEG as the CLI reads the sketch, transparency over white) and the
//! library's PNG writer (`skb_image_write_png`), so a plug-in reproduces the CLI's file.

use std::ffi::c_char;

use sketchbody_core::body::rig::FaceUvs;
use sketchbody_core::camera::WeakPerspective;
use sketchbody_core::error::Error;
use sketchbody_core::export::texture::{check_texture_size, project_sketch};
use sketchbody_core::image::{load_rgb_image, save_png, RgbImage};

use super::body::skb_mesh;
use super::error::fail;
use super::image::{skb_image, view_of};
use super::mesh_ops::skb_camera;
use super::pipeline::skb_result;
use super::ptr::*;
use super::status::skb_status;

/// Largest texture side `skb_*_project_texture` accept, texels.
pub const SKB_MAX_TEXTURE_SIZE: u32 = 4096;
/// The texture side `sketchbody run` uses by default (`--texture-size`), texels.
pub const SKB_DEFAULT_TEXTURE_SIZE: u32 = 1024;

const _: () = assert!(SKB_MAX_TEXTURE_SIZE as usize == sketchbody_core::raster::MAX_RASTER_SIDE);
const _: () = assert!(SKB_DEFAULT_TEXTURE_SIZE as usize == sketchbody_core::export::texture::DEFAULT_TEXTURE_SIZE);

/// A decoded image file, 8-bit RGB (gray expanded, palettes resolved, transparency composited
/// over white, EXIF orientation applied): the sketch as `sketchbody run` reads it for the
/// texture. Create with `skb_rgb_image_new_from_file`, view with `skb_rgb_image_view`, free with
/// `skb_rgb_image_free`. Immutable: several threads may read it at once.
pub struct skb_rgb_image {
    inner: RgbImage,
}

/// Loads a PNG or JPEG file as 8-bit RGB. Thread-safe.
/// @param path the file path, NUL-terminated UTF-8.
/// @param out receives a new image the caller owns (free with `skb_rgb_image_free`); not NULL.
/// @return SKB_OK; SKB_ERR_IO (missing, unreadable, not a regular file); SKB_ERR_DECODE (not an
///         image, truncated); SKB_ERR_IMAGE_TOO_LARGE; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rgb_image_new_from_file(path: *const c_char, out: *mut *mut skb_rgb_image) -> skb_status {
    unsafe {
        ffi_boundary! {
            let p = try_status!(path_arg(path, "path"));
            let out = try_status!(out_slot(out));
            let inner = try_core!(load_rgb_image(p));
            give(out, skb_rgb_image { inner })
        }
    }
}

/// A borrowed 3-channel `skb_image` view of a decoded image.
/// @param img the image, only read.
/// @param out receives the view (rows packed, `stride` = 3 × `width`), valid while `img` lives;
///            not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_rgb_image_view(img: *const skb_rgb_image, out: *mut skb_image) -> skb_status {
    unsafe {
        ffi_boundary! {
            let i = &try_status!(try_ref(img, "img")).inner;
            let (w, h) = (i.width() as u32, i.height() as u32);
            let view = skb_image { data: i.as_bytes().as_ptr(), width: w, height: h, stride: 3 * w, channels: 3 };
            try_status!(write_out(out, view, "out"));
            skb_status::SKB_OK
        }
    }
}

/// Frees an image from `skb_rgb_image_new_from_file`.
/// @param img the image to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_rgb_image_free(img: *mut skb_rgb_image) {
    unsafe { free_box(img) }
}

/// Writes an image as an 8-bit PNG with the library's encoder, the one `sketchbody run` writes
/// `body_texture.png` with (same pixels, same bytes). Written atomically: on error nothing is
/// left at `path`. Thread-safe.
/// @param img the image, only read: 1 channel gray, 3 RGB, 4 RGBA; any stride.
/// @param path the output file path, NUL-terminated UTF-8.
/// @return SKB_OK; SKB_ERR_IO for an unwritable path; image and argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_image_write_png(img: *const skb_image, path: *const c_char) -> skb_status {
    unsafe {
        ffi_boundary! {
            let view = try_status!(view_of(img));
            let p = try_status!(path_arg(path, "path"));
            try_core!(save_png(&view, p));
            skb_status::SKB_OK
        }
    }
}

/// The texture of `posed` vertices (model frame, metres) with the body model's faces and UVs,
/// seen through `camera` in `sketch`, copied into the caller's `dst`; the counts into `texels`
/// and `visible` when not NULL.
///
/// # Safety
/// `sketch`, `dst`, `texels`, `visible` are NULL or valid as the calling function's header says.
#[allow(clippy::too_many_arguments)]
unsafe fn project_into(
    sketch: *const skb_image,
    posed: &[[f32; 3]],
    quads: &[[u32; 4]],
    uvs: &FaceUvs,
    camera: &WeakPerspective,
    size: u32,
    dst: *mut u8,
    dst_stride: usize,
    dst_len: usize,
    texels: *mut u64,
    visible: *mut u64,
) -> skb_status {
    // SAFETY: the caller's contract (above); `view_of` and the ptr.rs helpers check NULL and lengths before each
    // borrow.
    unsafe {
        let view = try_status!(view_of(sketch));
        let side = size as usize;
        try_core!(check_texture_size(side));
        let row = 3 * side;
        if dst_stride < row {
            return fail(&Error::BadStride { stride: dst_stride, row_bytes: row });
        }
        let Some(needed) = dst_stride.checked_mul(side - 1).and_then(|n| n.checked_add(row)) else {
            return fail(&Error::OutOfRange {
                name: "dst_stride",
                detail: format!("{dst_stride} bytes × {} rows overflows", side - 1),
            });
        };
        let out = try_status!(try_slice_mut(dst, dst_len, "dst"));
        if out.len() < needed {
            return fail(&Error::BufferTooSmall { name: "dst", len: out.len(), needed, unit: "bytes" });
        }
        let rgb = try_core!(RgbImage::from_view(&view));
        let (img, stats) = try_core!(project_sketch(&rgb, posed, quads, uvs, camera, side));
        for (y, src) in img.as_bytes().chunks_exact(row).enumerate() {
            out[y * dst_stride..y * dst_stride + row].copy_from_slice(src);
        }
        write_opt(texels, stats.texels as u64);
        write_opt(visible, stats.visible as u64);
        skb_status::SKB_OK
    }
}

/// The texture `sketchbody run` writes as `body_texture.png` for this result: the sketch
/// projected through the result's camera onto its posed mesh, into MakeHuman's UV layout
/// (`skb_mesh_copy_uvs`, v up; texture row 0 is v = 1). Every texel whose surface point the
/// camera sees (facing it, not hidden by another part of the body, within 1 cm of the nearest
/// surface) takes the sketch's colour there (bilinear); texels the sketch does not see are
/// light grey (190, 190, 190); seen texels grow 2 texels into the unused space around UV
/// islands.
///
/// Nothing is written on error. Thread-safe (the result is only read).
/// @param result the result, only read.
/// @param sketch the colour image the result was computed from (the same pixels; 3 channels as
///               `skb_rgb_image_new_from_file` gives them reproduce the CLI exactly; 1 channel
///               is taken as gray, 4 with alpha ignored).
/// @param size the texture side in texels, 1..=`SKB_MAX_TEXTURE_SIZE` (the CLI's default
///             `SKB_DEFAULT_TEXTURE_SIZE`).
/// @param dst receives `size` rows of `size` RGB pixels (3 bytes each).
/// @param dst_stride bytes between the starts of consecutive rows of `dst`, at least 3 × `size`.
/// @param dst_len the size of `dst` in bytes, at least `dst_stride * (size - 1) + 3 * size`.
/// @param texels receives the number of texels inside the UV layout; may be NULL.
/// @param visible receives the number of those the sketch coloured; may be NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE (size, or a result mesh without a UV layout);
///         SKB_ERR_BAD_STRIDE; SKB_ERR_BUFFER_TOO_SMALL; the image errors; SKB_ERR_NULL_POINTER.
#[no_mangle]
pub unsafe extern "C" fn skb_result_project_texture(
    result: *const skb_result,
    sketch: *const skb_image,
    size: u32,
    dst: *mut u8,
    dst_stride: usize,
    dst_len: usize,
    texels: *mut u64,
    visible: *mut u64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let Some(uvs) = r.mesh.uvs.as_ref() else {
                return fail(&Error::OutOfRange { name: "result", detail: "its mesh has no UV layout".into() });
            };
            project_into(sketch, &r.posed_vertices, &r.mesh.quads, uvs, &r.pose.camera, size, dst, dst_stride, dst_len, texels, visible)
        }
    }
}

/// The same projection as `skb_result_project_texture` for a mesh and a camera of the host's
/// own: the sketch seen through `cam` projected onto the mesh in its current pose
/// (`skb_mesh_pose`; the rest pose if never posed). For a mesh from `skb_mesh_new_from_result`
/// and the result's camera this is exactly `skb_result_project_texture`.
/// @param mesh the mesh, only read.
/// @param sketch as in `skb_result_project_texture`.
/// @param cam model metres → sketch pixels, as `skb_result_camera` gives it.
/// @param size as in `skb_result_project_texture`.
/// @param dst as in `skb_result_project_texture`.
/// @param dst_stride as in `skb_result_project_texture`.
/// @param dst_len as in `skb_result_project_texture`.
/// @param texels as in `skb_result_project_texture` (may be NULL).
/// @param visible as in `skb_result_project_texture` (may be NULL).
/// @return the statuses of `skb_result_project_texture`, plus SKB_ERR_NON_FINITE /
///         SKB_ERR_OUT_OF_RANGE for an invalid camera (non-finite, scales not positive, rotation
///         not orthonormal).
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_project_texture(
    mesh: *const skb_mesh,
    sketch: *const skb_image,
    cam: *const skb_camera,
    size: u32,
    dst: *mut u8,
    dst_stride: usize,
    dst_len: usize,
    texels: *mut u64,
    visible: *mut u64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let camera = WeakPerspective::from(try_status!(try_ref(cam, "cam")));
            let posed = m.posed.as_ref().map_or(&m.rest.vertices, |p| &p.vertices);
            let uvs = FaceUvs { coords: m.model.uvs().to_vec(), quads: m.model.face_uvs().to_vec() };
            project_into(sketch, posed, m.model.faces(), &uvs, &camera, size, dst, dst_stride, dst_len, texels, visible)
        }
    }
}
