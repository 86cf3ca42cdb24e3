//! The body part of the C API, called through its `extern "C"` functions as a C host would.

use std::ffi::CStr;
use std::ptr;

use crate::*;

fn last_error() -> String {
    // SAFETY: skb_last_error_message never returns NULL; the text lives until the next call.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

struct Ctx(*mut skb_context);
impl Drop for Ctx {
    fn drop(&mut self) {
        // SAFETY: `self.0` came from skb_context_new and is freed only here.
        unsafe { skb_context_free(self.0) }
    }
}

fn context() -> Ctx {
    let mut ctx = ptr::null_mut();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    assert_eq!(unsafe { skb_context_new(&mut ctx) }, skb_status::SKB_OK, "{}", last_error());
    assert!(!ctx.is_null());
    Ctx(ctx)
}

#[test]
fn mesh_from_shape_reports_counts_and_copies_data() {
    let ctx = context();
    let (mut k, mut d) = (0usize, 0usize);
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(skb_context_component_count(ctx.0, SKB_GENDER_MALE, &mut k), skb_status::SKB_OK);
        assert_eq!(skb_context_default_dim(ctx.0, SKB_GENDER_MALE, &mut d), skb_status::SKB_OK);
    }
    assert!(k >= 10 && (1..=k).contains(&d), "components {k}, default dim {d}");
    let weights = [0.3f32, -0.2, 0.1];
    let mut mesh = ptr::null_mut();
    assert_eq!(
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe { skb_mesh_new_from_shape(ctx.0, SKB_GENDER_MALE, weights.as_ptr(), 3, &mut mesh) },
        skb_status::SKB_OK
    );
    drop(ctx); // meshes outlive their context
    let (mut nv, mut nf, mut nj, mut ns, mut g) = (0usize, 0usize, 0usize, 0usize, 9u32);
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(skb_mesh_vertex_count(mesh, &mut nv), skb_status::SKB_OK);
        assert_eq!(skb_mesh_face_count(mesh, &mut nf), skb_status::SKB_OK);
        assert_eq!(skb_mesh_joint_count(mesh, &mut nj), skb_status::SKB_OK);
        assert_eq!(skb_mesh_skin_weight_count(mesh, &mut ns), skb_status::SKB_OK);
        assert_eq!(skb_mesh_gender(mesh, &mut g), skb_status::SKB_OK);
    }
    assert_eq!((nv, nf, nj, ns, g), (13380, 13378, 15, 4 * 13380, SKB_GENDER_MALE));
    let mut verts = vec![0f32; 3 * nv];
    let mut faces = vec![0u32; 4 * nf];
    let mut tris = vec![0u32; 6 * nf];
    let mut joints = [0f64; 45];
    let mut bones = vec![0u32; ns];
    let mut w = vec![0f32; ns];
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(skb_mesh_copy_vertices(mesh, verts.as_mut_ptr(), verts.len()), skb_status::SKB_OK);
        assert_eq!(skb_mesh_copy_faces(mesh, faces.as_mut_ptr(), faces.len()), skb_status::SKB_OK);
        assert_eq!(skb_mesh_copy_triangles(mesh, tris.as_mut_ptr(), tris.len()), skb_status::SKB_OK);
        assert_eq!(skb_mesh_copy_joints(mesh, joints.as_mut_ptr(), joints.len()), skb_status::SKB_OK);
        assert_eq!(skb_mesh_copy_skin_weights(mesh, bones.as_mut_ptr(), w.as_mut_ptr(), ns), skb_status::SKB_OK);
    }
    // Same as the Rust API.
    let model = sketchbody_core::body::BodyModel::embedded().unwrap();
    let rest = model
        .space(sketchbody_core::body::Gender::Male)
        .synthesize(&[0.3f32 as f64, -0.2f32 as f64, 0.1f32 as f64])
        .unwrap();
    assert_eq!(&verts[..3], &rest.vertices[0]);
    assert_eq!(&joints[42..45], &rest.joints[14]);
    assert_eq!(&faces[..4], &model.faces()[0]);
    assert_eq!(&tris[3..6], &[faces[0], faces[2], faces[3]]);
    assert!(faces.iter().all(|&i| (i as usize) < nv) && bones.iter().all(|&b| b < SKB_NUM_BONES));
    for v in 0..nv {
        let s: f32 = w[4 * v..4 * v + 4].iter().sum();
        assert!((s - 1.0).abs() < 1e-4, "vertex {v} skin weights sum to {s} (eps 1e-4)");
    }
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe { skb_mesh_free(mesh) };
}

#[test]
fn bad_arguments_give_specific_statuses_and_write_nothing() {
    let ctx = context();
    let mut mesh = ptr::null_mut();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(skb_context_new(ptr::null_mut()), skb_status::SKB_ERR_NULL_POINTER);
        assert_eq!(
            skb_mesh_new_from_shape(ptr::null(), 0, ptr::null(), 0, &mut mesh),
            skb_status::SKB_ERR_NULL_POINTER
        );
        assert_eq!(skb_mesh_new_from_shape(ctx.0, 2, ptr::null(), 0, &mut mesh), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert!(last_error().contains("gender"), "{}", last_error());
        assert_eq!(skb_mesh_new_from_shape(ctx.0, 0, ptr::null(), 1, &mut mesh), skb_status::SKB_ERR_NULL_POINTER);
        let too_many = [0f32; 1000];
        assert_eq!(
            skb_mesh_new_from_shape(ctx.0, 0, too_many.as_ptr(), 1000, &mut mesh),
            skb_status::SKB_ERR_OUT_OF_RANGE
        );
        let nan = [0.0f32, f32::NAN];
        assert_eq!(skb_mesh_new_from_shape(ctx.0, 0, nan.as_ptr(), 2, &mut mesh), skb_status::SKB_ERR_NON_FINITE);
        assert!(mesh.is_null(), "no mesh on failure");
        assert_eq!(skb_mesh_new_from_shape(ctx.0, SKB_GENDER_FEMALE, ptr::null(), 0, &mut mesh), skb_status::SKB_OK);
        let mut small = [7f32; 5];
        assert_eq!(skb_mesh_copy_vertices(mesh, small.as_mut_ptr(), small.len()), skb_status::SKB_ERR_BUFFER_TOO_SMALL);
        assert_eq!(small, [7f32; 5], "nothing written on error");
        let mut nv = 0usize;
        assert_eq!(skb_mesh_vertex_count(mesh, &mut nv), skb_status::SKB_OK);
        assert_eq!(last_error(), "", "a success clears the message");
        assert_eq!(skb_mesh_copy_vertices(mesh, small.as_mut_ptr(), small.len()), skb_status::SKB_ERR_BUFFER_TOO_SMALL);
        assert_eq!(last_error(), format!("buffer `dst` holds 5 elements, {} needed", 3 * nv));
        assert_eq!(skb_mesh_copy_joints(mesh, ptr::null_mut(), 45), skb_status::SKB_ERR_NULL_POINTER);
        let mut n = 0usize;
        assert_eq!(skb_mesh_vertex_count(ptr::null(), &mut n), skb_status::SKB_ERR_NULL_POINTER);
        assert_eq!(skb_mesh_vertex_count(mesh, ptr::null_mut()), skb_status::SKB_ERR_NULL_POINTER);
        skb_mesh_free(mesh);
        skb_mesh_free(ptr::null_mut());
        skb_context_free(ptr::null_mut());
    }
}

/// Issue 20 finding 8: a length whose byte size exceeds `isize::MAX` (a caller passing
/// `SIZE_MAX` for "big enough") is refused before any slice is built, and nothing is written.
#[test]
fn absurd_buffer_lengths_are_refused() {
    let ctx = context();
    let mut mesh = ptr::null_mut();
    let mut small = [7f32; 6];
    let mut faces = [9u32; 4];
    // SAFETY: `ctx.0` is a live context, `mesh` a local slot; the buffers are live locals (the
    // absurd lengths are what the test checks are refused before any access).
    unsafe {
        assert_eq!(skb_mesh_new_from_shape(ctx.0, SKB_GENDER_MALE, ptr::null(), 0, &mut mesh), skb_status::SKB_OK);
        assert_eq!(skb_mesh_copy_vertices(mesh, small.as_mut_ptr(), usize::MAX), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert!(last_error().contains("dst"), "{}", last_error());
        assert_eq!(
            skb_mesh_copy_faces(mesh, faces.as_mut_ptr(), isize::MAX as usize / 4 + 1),
            skb_status::SKB_ERR_OUT_OF_RANGE
        );
        skb_mesh_free(mesh);
    }
    assert_eq!(small, [7f32; 6], "nothing written");
    assert_eq!(faces, [9u32; 4], "nothing written");
}
