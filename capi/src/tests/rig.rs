//! The rig options of issue 49 through the C API: twist bones, IK targets, the pose as the rest
//! and shape keys, as `skb_rig_new_from_mesh` reports them.

use std::ffi::CStr;
use std::ptr;

use crate::*;

fn last_error() -> String {
    // SAFETY: skb_last_error_message never returns NULL; the text lives until the next call.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

/// A male mesh of `weights`, its rest vertices; the caller frees the mesh.
fn mesh_of(ctx: *mut skb_context, weights: &[f32]) -> (*mut skb_mesh, Vec<f32>) {
    let mut mesh = ptr::null_mut();
    let mut v = vec![0f32; 3 * 13380];
    // SAFETY: a live context; `weights` and `v` hold the lengths passed.
    unsafe {
        let s = skb_mesh_new_from_shape(ctx, SKB_GENDER_MALE, weights.as_ptr(), weights.len(), &mut mesh);
        assert_eq!(s, skb_status::SKB_OK, "{}", last_error());
        assert_eq!(skb_mesh_copy_vertices(mesh, v.as_mut_ptr(), v.len()), skb_status::SKB_OK);
    }
    (mesh, v)
}

/// With every option on, the rig has 53 + 6 + 7 bones named as documented, one shape key per
/// shape weight, and key k at 1 moves each rest vertex as one standard deviation more of
/// weight k does (within 0.1 mm); with the pose as the rest the rest vertices are the posed
/// ones.
#[test]
fn twist_bones_ik_targets_and_shape_keys_reach_the_rig() {
    let mut ctx = ptr::null_mut();
    let mut opts = ptr::null_mut();
    // SAFETY: live locals.
    unsafe {
        assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
        assert_eq!(skb_export_options_new(&mut opts), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_naming(opts, SKB_NAMING_UNREAL), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_twist_bones(opts, true), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_ik_targets(opts, true), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_shape_keys(opts, true), skb_status::SKB_OK);
    }
    let weights = [0.3f32, -0.2, 0.1];
    let (mesh, base) = mesh_of(ctx, &weights);
    let mut rig = ptr::null_mut();
    let (mut bones, mut keys) = (0usize, 0usize);
    // SAFETY: live handles and locals.
    unsafe {
        assert_eq!(skb_rig_new_from_mesh(mesh, opts, &mut rig), skb_status::SKB_OK, "{}", last_error());
        assert_eq!(skb_rig_bone_count(rig, &mut bones), skb_status::SKB_OK);
        assert_eq!(skb_rig_shape_key_count(rig, &mut keys), skb_status::SKB_OK);
    }
    assert_eq!(bones, (SKB_NUM_RIG_BONES + SKB_NUM_TWIST_BONES + SKB_NUM_IK_BONES) as usize);
    assert_eq!(keys, weights.len());
    let name = |b: usize| {
        let mut buf = [0 as std::ffi::c_char; 64];
        // SAFETY: a live rig; `buf` holds 64 bytes.
        assert_eq!(unsafe { skb_rig_copy_bone_name(rig, b, buf.as_mut_ptr(), 64) }, skb_status::SKB_OK);
        // SAFETY: the library wrote a NUL-terminated name into `buf`.
        unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
    };
    let mut parents = vec![0i32; bones];
    // SAFETY: a live rig; `parents` holds `bones` integers.
    assert_eq!(unsafe { skb_rig_copy_parents(rig, parents.as_mut_ptr(), bones) }, skb_status::SKB_OK);
    assert_eq!(name(55), "upperarm_twist_01_l");
    assert_eq!(name(parents[55] as usize), "upperarm_l");
    assert_eq!(name(bones - 1), "ik_hand_l");
    assert_eq!(name(parents[bones - 1] as usize), "ik_hand_gun");
    let model = sketchbody_core::body::BodyModel::embedded().unwrap();
    let variances = model.space(sketchbody_core::body::Gender::Male).variances().to_vec();
    for k in 0..keys {
        let mut delta = vec![0f32; 3 * 13380];
        // SAFETY: a live rig; `delta` holds 3 × vertex count floats.
        let s = unsafe { skb_rig_copy_shape_key(rig, k, delta.as_mut_ptr(), delta.len()) };
        assert_eq!(s, skb_status::SKB_OK);
        let mut w = weights;
        w[k] = (w[k] as f64 + variances[k].sqrt()) as f32;
        let (moved_mesh, moved) = mesh_of(ctx, &w);
        // SAFETY: made above, freed once.
        unsafe { skb_mesh_free(moved_mesh) };
        let gap = (0..delta.len()).map(|i| (base[i] + delta[i] - moved[i]).abs()).fold(0f32, f32::max);
        let size = delta.iter().fold(0f32, |m, d| m.max(d.abs()));
        println!(
            "shape key {k}: within {gap:.2e} m of the body one standard deviation further (largest move {size:.3} m)"
        );
        assert!(gap < 1e-4 && size > 5e-3, "key {k}: gap {gap} m, largest displacement {size} m");
    }
    // SAFETY: live handles, each freed once.
    unsafe {
        assert_eq!(skb_rig_copy_shape_key(rig, keys, ptr::null_mut(), 0), skb_status::SKB_ERR_OUT_OF_RANGE);
        skb_rig_free(rig);
        skb_mesh_free(mesh);
        skb_export_options_free(opts);
        skb_context_free(ctx);
    }
}
