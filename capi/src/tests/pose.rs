//! Posing, rasterising and exporting an `skb_mesh` and rasterising raw triangles, through the
//! C API as a C host would.

use std::ffi::{CStr, CString};
use std::ptr;

use crate::*;
use rand::SeedableRng;
use sketchbody_core::body::procedural::random_pose;

fn last_error() -> String {
    // SAFETY: skb_last_error_message never returns NULL; the text lives until the next call.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

fn camera(size: f64) -> skb_camera {
    skb_camera {
        sx: size / 2.2,
        sy: size / 2.2,
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        t: [size / 2.0, size / 2.0],
    }
}

#[test]
fn mesh_poses_rasterises_and_exports() {
    let mut ctx = ptr::null_mut();
    let mut mesh = ptr::null_mut();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK, "{}", last_error());
        assert_eq!(skb_mesh_new_from_shape(ctx, SKB_GENDER_FEMALE, ptr::null(), 0, &mut mesh), skb_status::SKB_OK);
        skb_context_free(ctx);
    }
    let mut rest = [0.0f64; 45];
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    assert_eq!(unsafe { skb_mesh_copy_posed_joints(mesh, rest.as_mut_ptr(), 45) }, skb_status::SKB_OK);
    let rest_j: [[f64; 3]; 15] = std::array::from_fn(|i| [rest[3 * i], rest[3 * i + 1], rest[3 * i + 2]]);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let target = random_pose(&rest_j, &mut rng, 0.1);
    let flat: Vec<f64> = target.iter().flatten().copied().collect();
    let mut nv = 0usize;
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe { skb_mesh_vertex_count(mesh, &mut nv) };
    let mut verts = vec![0.0f32; 3 * nv];
    for flags in [0, SKB_POSE_DUAL_QUATERNION, SKB_POSE_RETARGET, SKB_POSE_RETARGET | SKB_POSE_DUAL_QUATERNION] {
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        assert_eq!(unsafe { skb_mesh_pose(mesh, flat.as_ptr(), 45, flags) }, skb_status::SKB_OK, "{}", last_error());
        let mut posed = [0.0f64; 45];
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        assert_eq!(unsafe { skb_mesh_copy_posed_joints(mesh, posed.as_mut_ptr(), 45) }, skb_status::SKB_OK);
        if flags & SKB_POSE_RETARGET != 0 {
            let err = posed.iter().zip(&flat).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-6, "retargeted joints off by {err} m");
        }
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        assert_eq!(unsafe { skb_mesh_copy_posed_vertices(mesh, verts.as_mut_ptr(), verts.len()) }, skb_status::SKB_OK);
        assert!(verts.iter().all(|c| c.is_finite()));
    }
    // The posed silhouette equals the raw-array raster of the posed vertices.
    let mut nf = 0usize;
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe { skb_mesh_face_count(mesh, &mut nf) };
    let mut tris = vec![0u32; 6 * nf];
    assert_eq!(
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe { skb_mesh_copy_triangles(mesh, tris.as_mut_ptr(), tris.len()) },
        skb_status::SKB_OK,
        "{}",
        last_error()
    );
    let cam = camera(128.0);
    let (mut a, mut b) = (vec![0u8; 128 * 128], vec![0u8; 130 * 128]);
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(
            skb_mesh_rasterize(mesh, ptr::null_mut(), &cam, 128, 128, a.as_mut_ptr(), 128, a.len()),
            skb_status::SKB_OK,
            "{}",
            last_error()
        );
        let mut r = ptr::null_mut();
        assert_eq!(skb_rasterizer_new(&mut r), skb_status::SKB_OK);
        let st = skb_rasterizer_rasterize_triangles(
            r,
            verts.as_ptr(),
            nv,
            tris.as_ptr(),
            tris.len() / 3,
            &cam,
            128,
            128,
            b.as_mut_ptr(),
            130,
            b.len(),
        );
        assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
        skb_rasterizer_free(r);
        skb_rasterizer_free(ptr::null_mut());
    }
    for y in 0..128 {
        assert_eq!(&a[y * 128..y * 128 + 128], &b[y * 130..y * 130 + 128], "row {y}");
    }
    assert!(a.iter().filter(|&&m| m == 255).count() > 500);
    // Exports.
    let dir = std::env::temp_dir().join(format!("skb-capi-pose-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |n: &str| CString::new(dir.join(n).to_str().unwrap()).unwrap();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(skb_mesh_write_glb(mesh, p("a.glb").as_ptr(), ptr::null()), skb_status::SKB_OK, "{}", last_error());
        assert_eq!(skb_mesh_write_obj(mesh, p("a.obj").as_ptr(), true), skb_status::SKB_OK, "{}", last_error());
        assert_eq!(skb_mesh_write_preview(mesh, p("a.png").as_ptr(), 64), skb_status::SKB_OK, "{}", last_error());
        assert_eq!(skb_mesh_write_obj(mesh, p("missing/a.obj").as_ptr(), false), skb_status::SKB_ERR_IO);
        assert_eq!(skb_mesh_write_glb(mesh, ptr::null(), ptr::null()), skb_status::SKB_ERR_NULL_POINTER);
        // Export options: Mixamo names, T-pose, pelvis origin; out-of-range values are specific
        // errors that leave the options as they were.
        let mut o: *mut skb_export_options = ptr::null_mut();
        assert_eq!(skb_export_options_new(&mut o), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_naming(o, SKB_NAMING_MIXAMO), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_rest_pose(o, SKB_REST_T_POSE), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_origin(o, SKB_ORIGIN_PELVIS), skb_status::SKB_OK);
        assert_eq!(skb_export_options_set_naming(o, 3), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_export_options_set_rest_pose(o, 2), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_export_options_set_origin(o, 9), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_export_options_set_naming(ptr::null_mut(), 0), skb_status::SKB_ERR_NULL_POINTER);
        let st = skb_mesh_write_glb(mesh, p("m.glb").as_ptr(), o);
        assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
        skb_export_options_free(o);
        skb_export_options_free(ptr::null_mut());
    }
    let glb = std::fs::read(dir.join("m.glb")).unwrap();
    let text = String::from_utf8_lossy(&glb[..4000.min(glb.len())]).to_string()
        + &String::from_utf8_lossy(&glb[20..20 + u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize]);
    assert!(text.contains("\"mixamorig:Hips\"") && text.contains("\"mixamorig:RightForeArm\""));
    let plain = std::fs::read(dir.join("a.glb")).unwrap();
    assert!(String::from_utf8_lossy(&plain).contains("\"r_elbow\""));
    for f in ["a.glb", "a.obj", "a.png"] {
        assert!(std::fs::metadata(dir.join(f)).unwrap().len() > 1000, "{f}");
    }
    assert!(!dir.join("missing").exists());
    std::fs::remove_dir_all(&dir).unwrap();
    // Bad input: specific errors, pose unchanged.
    let mut bad = flat.clone();
    bad[7] = f64::NAN;
    let mut coincident = flat.clone();
    coincident.copy_within(12..15, 9); // r_elbow onto r_wrist
    let mut before = vec![0.0f32; 3 * nv];
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        skb_mesh_copy_posed_vertices(mesh, before.as_mut_ptr(), before.len());
        assert_eq!(skb_mesh_pose(mesh, bad.as_ptr(), 45, 0), skb_status::SKB_ERR_NON_FINITE);
        assert_eq!(skb_mesh_pose(mesh, coincident.as_ptr(), 45, 0), skb_status::SKB_ERR_DEGENERATE_BONE);
        assert!(last_error().contains("r_elbow"), "{}", last_error());
        assert_eq!(skb_mesh_pose(mesh, flat.as_ptr(), 44, 0), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_mesh_pose(mesh, flat.as_ptr(), 45, 8), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_mesh_pose(ptr::null_mut(), flat.as_ptr(), 45, 0), skb_status::SKB_ERR_NULL_POINTER);
        skb_mesh_copy_posed_vertices(mesh, verts.as_mut_ptr(), verts.len());
        assert_eq!(before, verts);
        let far = skb_camera { t: [5000.0, 5000.0], ..cam };
        assert_eq!(
            skb_mesh_rasterize(mesh, ptr::null_mut(), &far, 128, 128, a.as_mut_ptr(), 128, a.len()),
            skb_status::SKB_ERR_MESH_OUTSIDE_IMAGE
        );
        assert_eq!(
            skb_mesh_rasterize(mesh, ptr::null_mut(), &cam, 128, 128, a.as_mut_ptr(), 127, a.len()),
            skb_status::SKB_ERR_BAD_STRIDE
        );
        assert_eq!(
            skb_mesh_rasterize(mesh, ptr::null_mut(), &cam, 128, 128, a.as_mut_ptr(), 128, 100),
            skb_status::SKB_ERR_BUFFER_TOO_SMALL
        );
        assert_eq!(
            skb_mesh_rasterize(mesh, ptr::null_mut(), &cam, 5000, 128, a.as_mut_ptr(), 5000, a.len()),
            skb_status::SKB_ERR_OUT_OF_RANGE
        );
        let bad_cam = skb_camera { sx: -1.0, ..cam };
        assert_eq!(
            skb_mesh_rasterize(mesh, ptr::null_mut(), &bad_cam, 128, 128, a.as_mut_ptr(), 128, a.len()),
            skb_status::SKB_ERR_OUT_OF_RANGE
        );
        assert_eq!(
            skb_rasterizer_rasterize_triangles(
                ptr::null_mut(),
                verts.as_ptr(),
                nv,
                [0u32, 1, 99_999_999].as_ptr(),
                1,
                &cam,
                8,
                8,
                a.as_mut_ptr(),
                8,
                64
            ),
            skb_status::SKB_ERR_OUT_OF_RANGE
        );
        skb_mesh_free(mesh);
    }
}
