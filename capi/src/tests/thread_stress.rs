//! Thread stress: 8 threads on shared handles (one context, one read-only mesh, one image)
//! give results bit-identical to a single-threaded run.

use std::ffi::CStr;
use std::ptr;

use crate::*;

fn last_error() -> String {
    // SAFETY: test code; live handles and locals of the documented sizes, shared ones only read.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

/// Raw handles shared read-only between the threads (the header documents both as shareable).
#[derive(Clone, Copy)]
struct Shared {
    ctx: *mut skb_context,
    mesh: *mut skb_mesh,
}
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// One unit of work, its outputs as raw bits: a new posed mesh from the shared context (shape
/// `k`), the shared mesh's vertices, and Canny edges of a shared image.
fn work(s: Shared, k: usize, image: &[u8]) -> (Vec<u32>, Vec<u32>, Vec<u8>) {
    // SAFETY: test code; live handles and locals of the documented sizes, shared ones only read.
    unsafe {
        let weights = [0.1 * k as f32, -0.05 * k as f32];
        let mut mesh = ptr::null_mut();
        assert_eq!(skb_mesh_new_from_shape(s.ctx, SKB_GENDER_MALE, weights.as_ptr(), 2, &mut mesh), skb_status::SKB_OK);
        let mut joints = [0f64; 45];
        assert_eq!(skb_mesh_copy_joints(mesh, joints.as_mut_ptr(), 45), skb_status::SKB_OK);
        for (i, j) in joints.iter_mut().enumerate() {
            *j += if i % 3 == 0 { 0.05 * k as f64 } else { 0.0 };
        }
        joints[3 * 7 + 2] += 0.2; // move one joint off the rigid motion so the IK really solves
        let s_pose = skb_mesh_pose(mesh, joints.as_ptr(), 45, SKB_POSE_DUAL_QUATERNION);
        assert_eq!(s_pose, skb_status::SKB_OK, "{}", last_error());
        let mut nv = 0;
        assert_eq!(skb_mesh_vertex_count(mesh, &mut nv), skb_status::SKB_OK);
        let mut posed = vec![0f32; 3 * nv];
        assert_eq!(skb_mesh_copy_posed_vertices(mesh, posed.as_mut_ptr(), posed.len()), skb_status::SKB_OK);
        skb_mesh_free(mesh);
        let mut shared = vec![0f32; 3 * nv];
        assert_eq!(skb_mesh_copy_vertices(s.mesh, shared.as_mut_ptr(), shared.len()), skb_status::SKB_OK);
        let im = skb_image { data: image.as_ptr(), width: 128, height: 96, stride: 128, channels: 1 };
        let mut edges = vec![0u8; 128 * 96];
        let s_canny =
            skb_image_canny(&im, 40.0, 120.0, 3 + 2 * (k % 3) as i32, k % 2 == 1, edges.as_mut_ptr(), 128, edges.len());
        assert_eq!(s_canny, skb_status::SKB_OK, "{}", last_error());
        (posed.iter().map(|x| x.to_bits()).collect(), shared.iter().map(|x| x.to_bits()).collect(), edges)
    }
}

#[test]
fn eight_threads_on_shared_handles_match_single_threaded_bits() {
    const THREADS: usize = 8;
    const ROUNDS: usize = 3;
    const SHAPES: usize = 4;
    let image: Vec<u8> =
        (0..128 * 96).map(|i: usize| ((i % 128 / 16 + i / 128 / 12) % 2 * 180 + i % 7) as u8).collect();
    let mut s = Shared { ctx: ptr::null_mut(), mesh: ptr::null_mut() };
    // SAFETY: test code; live handles and locals of the documented sizes, shared ones only read.
    unsafe {
        assert_eq!(skb_context_new(&mut s.ctx), skb_status::SKB_OK);
        assert_eq!(skb_mesh_new_from_shape(s.ctx, SKB_GENDER_FEMALE, ptr::null(), 0, &mut s.mesh), skb_status::SKB_OK);
    }
    let reference: Vec<_> = (0..SHAPES).map(|k| work(s, k, &image)).collect();
    assert_ne!(reference[0].0, reference[1].0, "different shapes give different meshes");
    std::thread::scope(|scope| {
        for t in 0..THREADS {
            let (image, reference) = (&image, &reference);
            scope.spawn(move || {
                for r in 0..ROUNDS {
                    let k = (t + r) % SHAPES;
                    assert!(work(s, k, image) == reference[k], "thread {t} round {r} shape {k} differs");
                }
            });
        }
    });
    // SAFETY: test code; live handles and locals of the documented sizes, shared ones only read.
    unsafe {
        skb_mesh_free(s.mesh);
        skb_context_free(s.ctx);
    }
}
