//! `skb_context` (holds the body model) and `skb_mesh` (a body shape in the rest pose):
//! creation, release and read-only getters. Posing, rasterising and export live in `mesh_ops`.

use std::sync::Arc;

use sketchbody_core::body::ik::Pose;
use sketchbody_core::body::{BodyModel, Gender, RestShape, ShapeChoice, MAX_INFLUENCES};
use sketchbody_core::error::Error;
use sketchbody_core::pipeline::shape_keys::ShapeOrigin;
use sketchbody_core::skeleton::{NUM_BONES, NUM_JOINTS};

use super::error::fail;
use super::ptr::*;
use super::status::skb_status;

/// Female shape space (value of the `gender` arguments).
pub const SKB_GENDER_FEMALE: u32 = 0;
/// Male shape space (value of the `gender` arguments).
pub const SKB_GENDER_MALE: u32 = 1;
/// Number of canonical joints of every mesh.
pub const SKB_NUM_JOINTS: u32 = 15;
/// Number of canonical bones that skin weights refer to.
pub const SKB_NUM_BONES: u32 = 14;
/// Skin-weight slots per vertex.
pub const SKB_MAX_INFLUENCES: u32 = 4;
const _: () = assert!(SKB_NUM_JOINTS as usize == NUM_JOINTS && SKB_NUM_BONES as usize == NUM_BONES);
const _: () = assert!(SKB_MAX_INFLUENCES as usize == MAX_INFLUENCES);

/// The library context: holds the body model (the embedded one for [`skb_context_new`]) and the
/// embedded 2-D detector (decoded on first use by `skb_context_detect`). Create with `skb_context_new`,
/// release with `skb_context_free`. Immutable after creation (the detector is initialised once,
/// thread-safely), so one context may be used from several threads at once. Meshes keep the
/// model alive on their own: a context may be freed before the meshes made from it.
pub struct skb_context {
    pub(crate) model: Arc<BodyModel>,
    pub(crate) detector: std::sync::OnceLock<Result<sketchbody_core::detect::Model, String>>,
}

/// The pose of an `skb_mesh` and its skinned vertices.
pub(crate) struct Posed {
    pub(crate) pose: Pose,
    pub(crate) vertices: Vec<[f32; 3]>,
}

/// A body mesh: a shape of one gender in the rest pose (MakeHuman's A-pose), metres, model frame
/// (+Y up, +Z toward the viewer, the character's right at −X). Create with
/// `skb_mesh_new_from_shape`, release with `skb_mesh_free`. Getters only read it, so several
/// threads may call them at once; a function that changes a mesh needs exclusive use of it.
pub struct skb_mesh {
    pub(crate) model: Arc<BodyModel>,
    pub(crate) gender: Gender,
    pub(crate) rest: RestShape,
    /// How the rest shape was made: its space, the PCA shape weights (metres; may be shorter
    /// than the component count), bone-length factors and scale (for its shape keys).
    pub(crate) shape: ShapeOrigin,
    /// The current pose and posed vertices (`None`: rest pose), set by `skb_mesh_pose`.
    pub(crate) posed: Option<Box<Posed>>,
}

/// Creates a context holding the body model compiled into the library. Thread-safe.
/// @param out receives a new context the caller owns (release with `skb_context_free`);
///            untouched on failure; not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL `out`; the error of loading the embedded
///         model should it fail.
#[no_mangle]
pub unsafe extern "C" fn skb_context_new(out: *mut *mut skb_context) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            let model = try_core!(BodyModel::embedded());
            give(out, skb_context { model: Arc::new(model), detector: std::sync::OnceLock::new() })
        }
    }
}

/// Releases a context from `skb_context_new`. Meshes made from it stay valid.
/// @param ctx the context to release; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_context_free(ctx: *mut skb_context) {
    unsafe { free_box(ctx) }
}

/// Number of principal components of a gender's shape space (the most weights
/// `skb_mesh_new_from_shape` accepts). Thread-safe.
/// @param ctx the context, only read.
/// @param gender `SKB_GENDER_FEMALE` or `SKB_GENDER_MALE`.
/// @param out receives the count; not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for an unknown gender; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_context_component_count(
    ctx: *const skb_context,
    gender: u32,
    out: *mut usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let ctx = try_status!(try_ref(ctx, "ctx"));
            let g = try_core!(Gender::from_index(gender));
            try_status!(write_out(out, ctx.model.space(g).num_components(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// The default fitting dimension of a gender's shape space (components holding 96% of the
/// training variance). Thread-safe.
/// @param ctx the context, only read.
/// @param gender `SKB_GENDER_FEMALE` or `SKB_GENDER_MALE`.
/// @param out receives the dimension; not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for an unknown gender; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_context_default_dim(ctx: *const skb_context, gender: u32, out: *mut usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let ctx = try_status!(try_ref(ctx, "ctx"));
            let g = try_core!(Gender::from_index(gender));
            try_status!(write_out(out, ctx.model.space(g).default_dim(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Builds the rest-pose mesh of a gender with given PCA shape weights. Thread-safe.
/// @param ctx the context, only read.
/// @param gender `SKB_GENDER_FEMALE` or `SKB_GENDER_MALE`.
/// @param weights `weights[0..n]`, metres along unit basis vectors; missing trailing weights are
///                0; may be NULL when `n` is 0.
/// @param n the number of weights, at most `skb_context_component_count` (0: the mean shape).
/// @param out receives a new mesh the caller owns (release with `skb_mesh_free`); untouched on
///            failure; not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for an unknown gender or `n` above the component count;
///         SKB_ERR_NON_FINITE for a NaN or infinite weight; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_new_from_shape(
    ctx: *const skb_context,
    gender: u32,
    weights: *const f32,
    n: usize,
    out: *mut *mut skb_mesh,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let ctx = try_status!(try_ref(ctx, "ctx"));
            let out = try_status!(out_slot(out));
            let g = try_core!(Gender::from_index(gender));
            let space = ctx.model.space(g);
            if n > space.num_components() {
                return fail(&Error::OutOfRange {
                    name: "shape weight count",
                    detail: format!("got {n} weights, the shape space has {} components", space.num_components()),
                });
            }
            let w: Vec<f64> = if n == 0 {
                Vec::new()
            } else {
                try_status!(try_slice_of(weights, n, "weights")).iter().map(|&x| x as f64).collect()
            };
            let rest = try_core!(space.synthesize(&w));
            let shape = ShapeOrigin { space: ShapeChoice::Gendered(g), weights: w, proportions: None, scale: 1.0 };
            give(out, skb_mesh { model: Arc::clone(&ctx.model), gender: g, rest, shape, posed: None })
        }
    }
}

/// Releases a mesh.
/// @param mesh the mesh to release; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_free(mesh: *mut skb_mesh) {
    unsafe { free_box(mesh) }
}

/// The mesh's gender.
/// @param mesh the mesh, only read.
/// @param out receives `SKB_GENDER_FEMALE` or `SKB_GENDER_MALE`; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_gender(mesh: *const skb_mesh, out: *mut u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            try_status!(write_out(out, m.gender as u32, "out"));
            skb_status::SKB_OK
        }
    }
}

/// Number of vertices (13380).
/// @param mesh the mesh, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_vertex_count(mesh: *const skb_mesh, out: *mut usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            try_status!(write_out(out, m.rest.vertices.len(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Number of quad faces (13378); the triangle count is twice that.
/// @param mesh the mesh, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_face_count(mesh: *const skb_mesh, out: *mut usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            try_status!(write_out(out, m.model.faces().len(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Number of joints (always `SKB_NUM_JOINTS`).
/// @param mesh the mesh, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_joint_count(mesh: *const skb_mesh, out: *mut usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            try_status!(write_out(out, m.rest.joints.len(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Number of skin-weight slots, `vertex count × SKB_MAX_INFLUENCES`.
/// @param mesh the mesh, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_skin_weight_count(mesh: *const skb_mesh, out: *mut usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            try_status!(write_out(out, m.model.skin_weights().len() * MAX_INFLUENCES, "out"));
            skb_status::SKB_OK
        }
    }
}

/// Copies the rest-pose vertices. On error nothing is written.
/// @param mesh the mesh, only read.
/// @param dst receives x, y, z floats per vertex, metres.
/// @param dst_len the element count of `dst` in floats, at least 3 × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_vertices(mesh: *const skb_mesh, dst: *mut f32, dst_len: usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let out = try_status!(out_slice(dst, dst_len, 3 * m.rest.vertices.len(), "dst"));
            for (o, v) in out.chunks_exact_mut(3).zip(&m.rest.vertices) {
                o.copy_from_slice(v);
            }
            skb_status::SKB_OK
        }
    }
}

/// Copies the quad faces. On error nothing is written.
/// @param mesh the mesh, only read.
/// @param dst receives 4 vertex indices per face, counter-clockwise seen from outside.
/// @param dst_len the element count of `dst` in integers, at least 4 × face count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_faces(mesh: *const skb_mesh, dst: *mut u32, dst_len: usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let faces = m.model.faces();
            let out = try_status!(out_slice(dst, dst_len, 4 * faces.len(), "dst"));
            for (o, f) in out.chunks_exact_mut(4).zip(faces) {
                o.copy_from_slice(f);
            }
            skb_status::SKB_OK
        }
    }
}

/// Copies the faces split into triangles: (a,b,c), (a,c,d) per quad. On error nothing is
/// written.
/// @param mesh the mesh, only read.
/// @param dst receives 3 vertex indices per triangle.
/// @param dst_len the element count of `dst` in integers, at least 6 × face count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_triangles(mesh: *const skb_mesh, dst: *mut u32, dst_len: usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let faces = m.model.faces();
            let out = try_status!(out_slice(dst, dst_len, 6 * faces.len(), "dst"));
            for (o, &[a, b, c, d]) in out.chunks_exact_mut(6).zip(faces) {
                o.copy_from_slice(&[a, b, c, a, c, d]);
            }
            skb_status::SKB_OK
        }
    }
}

/// Copies the 15 rest-pose joints. On error nothing is written.
/// @param mesh the mesh, only read.
/// @param dst receives x, y, z doubles per joint, canonical order, metres.
/// @param dst_len the element count of `dst` in doubles, at least 45.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_joints(mesh: *const skb_mesh, dst: *mut f64, dst_len: usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let out = try_status!(out_slice(dst, dst_len, 3 * NUM_JOINTS, "dst"));
            for (o, j) in out.chunks_exact_mut(3).zip(&m.rest.joints) {
                o.copy_from_slice(j);
            }
            skb_status::SKB_OK
        }
    }
}

/// Copies the skin weights: for vertex v, slots `4v .. 4v+3` of both buffers (unused slots
/// have bone 0, weight 0). On error nothing is written.
/// @param mesh the mesh, only read.
/// @param bones receives bone indices 0..13, docs/design.md's bone order.
/// @param weights receives the weights, summing to 1 per vertex.
/// @param len the element count of each buffer, at least `SKB_MAX_INFLUENCES` × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for short buffers; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_skin_weights(
    mesh: *const skb_mesh,
    bones: *mut u32,
    weights: *mut f32,
    len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            copy_skin_weights(m.model.skin_weights(), bones, weights, len)
        }
    }
}

/// Writes skin weights into the caller's `bones`/`weights` arrays of `len` elements each (slots
/// `4v .. 4v+3` per vertex); shared by the mesh and result getters.
///
/// # Safety
/// `bones` and `weights` must be NULL or valid for writes of `len` elements.
pub(crate) unsafe fn copy_skin_weights(
    skin: &[sketchbody_core::body::VertexWeights],
    bones: *mut u32,
    weights: *mut f32,
    len: usize,
) -> skb_status {
    unsafe {
        let needed = MAX_INFLUENCES * skin.len();
        let b = try_status!(out_slice(bones, len, needed, "bones"));
        let w = try_status!(out_slice(weights, len, needed, "weights"));
        for ((bo, wo), s) in b.chunks_exact_mut(MAX_INFLUENCES).zip(w.chunks_exact_mut(MAX_INFLUENCES)).zip(skin) {
            for k in 0..MAX_INFLUENCES {
                bo[k] = s.bones[k] as u32;
                wo[k] = s.weights[k];
            }
        }
        skb_status::SKB_OK
    }
}

/// Number of PCA shape weights the mesh was made from (as given to `skb_mesh_new_from_shape`,
/// or found by `skb_context_fit_shape`).
/// @param mesh the mesh, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_shape_weight_count(mesh: *const skb_mesh, out: *mut usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            try_status!(write_out(out, m.shape.weights.len(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Copies the mesh's PCA shape weights. On error nothing is written.
/// @param mesh the mesh, only read.
/// @param dst receives `skb_mesh_shape_weight_count` doubles, metres.
/// @param dst_len the element count of `dst` in doubles, at least the shape weight count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_copy_shape_weights(
    mesh: *const skb_mesh,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let w = &m.shape.weights;
            let out = try_status!(out_slice(dst, dst_len, w.len(), "dst"));
            out[..w.len()].copy_from_slice(w);
            skb_status::SKB_OK
        }
    }
}
