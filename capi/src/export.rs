//! `skb_export_options`: the production rig's export options (bone names, rest pose, origin,
//! twist bones, how the pose is carried, IK targets; the FBX and USD files' unit and up axis) for
//! `skb_mesh_write_glb`, `skb_mesh_write_fbx` and `skb_mesh_write_usd`. Opaque; set
//! through setters; each writer writes atomically.

use std::ffi::c_char;

use sketchbody_core::body::ik::Pose;
use sketchbody_core::body::rig::RiggedMesh;
use sketchbody_core::body::rig::{Naming, Placement, PoseAs, RestPose, RigOptions, RigScene};
use sketchbody_core::error::Error;
use sketchbody_core::export::fbx::write_fbx;
use sketchbody_core::export::frame::{ExportFrame, Units, UpAxis};
use sketchbody_core::export::gltf::write_glb;
use sketchbody_core::export::usd::write_usda;

use super::body::skb_mesh;
use super::error::fail;
use super::ptr::*;
use super::status::skb_status;

/// Bone names: the project's (`pelvis`, `spine`, `r_elbow`, …; the default).
pub const SKB_NAMING_PROJECT: u32 = 0;
/// Bone names: Mixamo's (`mixamorig:Hips`, `mixamorig:RightForeArm`, …).
pub const SKB_NAMING_MIXAMO: u32 = 1;
/// Bone names: Unreal-style, MakeHuman's `game_engine` (`root`, `pelvis`, `spine_01`, …).
pub const SKB_NAMING_UNREAL: u32 = 2;
/// Rest pose: MakeHuman's A-pose (the default).
pub const SKB_REST_A_POSE: u32 = 0;
/// Rest pose: MakeHuman's T-pose.
pub const SKB_REST_T_POSE: u32 = 1;
/// Origin on the floor between the feet (the default).
pub const SKB_ORIGIN_FLOOR: u32 = 0;
/// Origin at the rest pelvis joint.
pub const SKB_ORIGIN_PELVIS: u32 = 1;
/// The pose as an action (the default): the rest is the A- or T-pose, the bones stand in the
/// pose, also a one-frame clip "pose".
pub const SKB_POSE_AS_ACTION: u32 = 0;
/// The pose as the rest (bind) pose, no clip.
pub const SKB_POSE_AS_REST: u32 = 1;
/// The pose as the rest pose plus a one-frame clip "a_pose" / "t_pose" holding the A- or T-pose.
pub const SKB_POSE_AS_BOTH: u32 = 2;
/// FBX and USD length unit: metres (the default; one file unit is 1 m).
pub const SKB_UNITS_METRES: u32 = 0;
/// FBX and USD length unit: centimetres (one file unit is 1 cm; coordinates 100× the metres).
pub const SKB_UNITS_CENTIMETRES: u32 = 1;
/// FBX and USD up axis: +Y, the body facing +Z (the default; the library's model frame).
pub const SKB_UP_Y: u32 = 0;
/// FBX and USD up axis: +Z, the body facing −Y (the model frame turned +90° about X).
pub const SKB_UP_Z: u32 = 1;

/// Export options of the rigged body (docs/formats.md, "body.glb", "body.fbx", "body.usda").
/// Create with `skb_export_options_new` (defaults: project names, A-pose, floor, no twist bones,
/// the pose as an action, no IK targets, no shape keys, metres, Y up),
/// free with `skb_export_options_free`. Not shared between threads while being set.
pub struct skb_export_options {
    pub(crate) rig: RigOptions,
    /// Write the mesh's shape dimensions as shape keys ([`ShapeOrigin::keys`]).
    pub(crate) shape_keys: bool,
    /// Unit and up axis of the FBX and USD writers (the GLB is always metres, Y up).
    pub(crate) frame: ExportFrame,
}

/// Creates export options with the defaults.
/// @param out receives a new options handle the caller owns (release with
///            `skb_export_options_free`); not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL `out`.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_new(out: *mut *mut skb_export_options) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            give(out, skb_export_options { rig: RigOptions::default(), shape_keys: false, frame: ExportFrame::default() })
        }
    }
}

/// Frees export options.
/// @param opts the options to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_free(opts: *mut skb_export_options) {
    unsafe { free_box(opts) }
}

unsafe fn set(opts: *mut skb_export_options, f: impl FnOnce(&mut RigOptions) -> Result<(), Error>) -> skb_status {
    unsafe { set_all(opts, |o| f(&mut o.rig)) }
}

/// Applies `f` to the options behind `opts`; `f` changes them only when it succeeds.
///
/// # Safety
/// `opts` is NULL or a live handle from `skb_export_options_new`, not used by another thread.
unsafe fn set_all(
    opts: *mut skb_export_options,
    f: impl FnOnce(&mut skb_export_options) -> Result<(), Error>,
) -> skb_status {
    unsafe {
        let o = try_status!(try_mut(opts, "opts"));
        match f(o) {
            Ok(()) => skb_status::SKB_OK,
            Err(e) => fail(&e),
        }
    }
}

/// Sets the bone names.
/// @param opts the options, changed.
/// @param naming `SKB_NAMING_PROJECT` (the default), `SKB_NAMING_MIXAMO` or `SKB_NAMING_UNREAL`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_naming(opts: *mut skb_export_options, naming: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set(opts, |o| {
                o.naming = *Naming::ALL.get(naming as usize).ok_or_else(|| Error::OutOfRange {
                    name: "bone naming",
                    detail: format!("{naming} (expected 0 project, 1 mixamo, 2 unreal)"),
                })?;
                Ok(())
            })
        }
    }
}

/// Sets the rest pose.
/// @param opts the options, changed.
/// @param rest `SKB_REST_A_POSE` (the default) or `SKB_REST_T_POSE`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_rest_pose(opts: *mut skb_export_options, rest: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set(opts, |o| {
                o.rest_pose = match rest {
                    SKB_REST_A_POSE => RestPose::APose,
                    SKB_REST_T_POSE => RestPose::TPose,
                    _ => return Err(Error::OutOfRange { name: "rest pose", detail: format!("{rest} (expected 0 A-pose, 1 T-pose)") }),
                };
                Ok(())
            })
        }
    }
}

/// Sets the origin.
/// @param opts the options, changed.
/// @param origin `SKB_ORIGIN_FLOOR` (the default) or `SKB_ORIGIN_PELVIS`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_origin(opts: *mut skb_export_options, origin: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set(opts, |o| {
                o.placement = match origin {
                    SKB_ORIGIN_FLOOR => Placement::Floor,
                    SKB_ORIGIN_PELVIS => Placement::Pelvis,
                    _ => return Err(Error::OutOfRange { name: "origin", detail: format!("{origin} (expected 0 floor, 1 pelvis)") }),
                };
                Ok(())
            })
        }
    }
}

/// Adds the twist bones or not (docs/formats.md, "Twist bones"). Every rigged writer and
/// `skb_rig_new_from_mesh` follow it.
/// @param opts the options, changed.
/// @param on true: upper arms, forearms and thighs, `SKB_NUM_TWIST_BONES` bones after the 53,
///           sharing the limbs' skin so that a twist spreads along the limb; false (the
///           default): MakeHuman's 53 bones.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_twist_bones(opts: *mut skb_export_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! {
            set(opts, |o| {
                o.twist_bones = on;
                Ok(())
            })
        }
    }
}

/// Sets how the pose is carried (docs/formats.md, "glTF 2.0 binary export", the pose). Every
/// rigged writer and `skb_rig_new_from_mesh` follow it.
/// @param opts the options, changed.
/// @param pose_as `SKB_POSE_AS_ACTION` (the default), `SKB_POSE_AS_REST` or `SKB_POSE_AS_BOTH`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_pose_as(opts: *mut skb_export_options, pose_as: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set(opts, |o| {
                o.pose_as = match pose_as {
                    SKB_POSE_AS_ACTION => PoseAs::Action,
                    SKB_POSE_AS_REST => PoseAs::Rest,
                    SKB_POSE_AS_BOTH => PoseAs::Both,
                    _ => return Err(Error::OutOfRange { name: "pose as", detail: format!("{pose_as} (expected 0 action, 1 rest, 2 both)") }),
                };
                Ok(())
            })
        }
    }
}

/// Adds the IK target bones or not (docs/formats.md, "IK targets"). Every rigged writer and
/// `skb_rig_new_from_mesh` follow it.
/// @param opts the options, changed.
/// @param on true: `SKB_NUM_IK_BONES` non-deforming bones at the hands and feet under
///           `ik_hand_root` / `ik_foot_root`, after the other bones; false: none (the default).
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_ik_targets(opts: *mut skb_export_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! {
            set(opts, |o| {
                o.ik_targets = on;
                Ok(())
            })
        }
    }
}

/// Adds the mesh's shape dimensions as shape keys or not (glTF morph targets, FBX blend shapes,
/// USD BlendShapes, all at 0; docs/formats.md, "Shape keys"). Every rigged writer and
/// `skb_rig_new_from_mesh` follow it (`skb_rig_shape_key_count`).
/// @param opts the options, changed.
/// @param on true: one key `shape_01`, `shape_02`, … per PCA weight of the mesh, or the
///           space's default count for the mean shape, each the displacement one standard
///           deviation of its component makes, through the body's bone-length factors and its
///           scaling to its height; false: none (the default).
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_shape_keys(opts: *mut skb_export_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! {
            set_all(opts, |o| {
                o.shape_keys = on;
                Ok(())
            })
        }
    }
}

/// Sets the unit of the FBX and USD files. The GLB is always in metres (glTF's specification)
/// and `skb_rig_new_from_mesh` in the model frame.
/// @param opts the options, changed.
/// @param units `SKB_UNITS_METRES` (the default) or `SKB_UNITS_CENTIMETRES`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_units(opts: *mut skb_export_options, units: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set_all(opts, |o| {
                o.frame.units = match units {
                    SKB_UNITS_METRES => Units::Metres,
                    SKB_UNITS_CENTIMETRES => Units::Centimetres,
                    _ => return Err(Error::OutOfRange { name: "units", detail: format!("{units} (expected 0 metres, 1 centimetres)") }),
                };
                Ok(())
            })
        }
    }
}

/// Sets the up axis of the FBX and USD files. The GLB is always Y up (glTF's specification)
/// and `skb_rig_new_from_mesh` in the model frame.
/// @param opts the options, changed.
/// @param up `SKB_UP_Y` (the default) or `SKB_UP_Z` (the model frame turned +90° about X: Z
///           up, the body facing −Y).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_export_options_set_up_axis(opts: *mut skb_export_options, up: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set_all(opts, |o| {
                o.frame.up = match up {
                    SKB_UP_Y => UpAxis::Y,
                    SKB_UP_Z => UpAxis::Z,
                    _ => return Err(Error::OutOfRange { name: "up axis", detail: format!("{up} (expected 0 Y, 1 Z)") }),
                };
                Ok(())
            })
        }
    }
}

/// The rigged mesh of `m` and its scene in the mesh's current pose (the rest pose if never
/// posed) with `opts` (`None`: the defaults), with the mesh's shape keys when asked. Errors:
/// the scene's and the keys'.
pub(crate) fn rig_scene(
    m: &skb_mesh,
    opts: Option<&skb_export_options>,
) -> sketchbody_core::Result<(RiggedMesh, RigScene)> {
    let options = opts.map_or_else(RigOptions::default, |o| o.rig);
    let keys = match opts {
        Some(o) if o.shape_keys => m.shape.keys(&m.model)?,
        _ => Vec::new(),
    };
    let rest_pose = Pose::rest(&m.rest.joints);
    let pose = m.posed.as_ref().map_or(&rest_pose, |p| &p.pose);
    let rigged = RiggedMesh::from_rest(&m.model, &m.rest);
    let scene = RigScene::build_with_shape_keys(m.model.rig(), &rigged, pose, &options, &keys)?;
    Ok((rigged, scene))
}

/// A core writer of the rigged scene: path, rigged mesh, scene, the FBX/USD frame.
type RiggedWriter = fn(&std::path::Path, &RiggedMesh, &RigScene, &ExportFrame) -> sketchbody_core::Result<()>;

/// The shared body of the rigged-body writers: checks `mesh` and `path`, builds the scene of
/// the mesh's current pose (the rest pose if never posed) with `opts` (NULL: the defaults) and
/// hands it to `write`.
///
/// # Safety
/// `mesh`, `path` and `opts` are NULL or valid as the calling export function's header says.
unsafe fn write_rigged(
    mesh: *const skb_mesh,
    path: *const c_char,
    opts: *const skb_export_options,
    write: RiggedWriter,
) -> skb_status {
    // SAFETY: the caller's contract (above); the ptr.rs helpers check NULL and lengths before each borrow.
    unsafe {
        ffi_boundary! {
            let m = try_status!(try_ref(mesh, "mesh"));
            let path = try_status!(path_arg(path, "path"));
            let o = opt_ref(opts);
            let (rigged, scene) = try_core!(rig_scene(m, o));
            let frame = o.map_or_else(ExportFrame::default, |o| o.frame);
            try_core!(write(path, &rigged, &scene, &frame));
            skb_status::SKB_OK
        }
    }
}

/// Writes the mesh as binary glTF 2.0: one scene, the rest mesh skinned to MakeHuman's 53-bone
/// rig (plus the twist bones and IK targets the options add), posed by the current pose (the
/// rest pose if never posed) as bone rotations with the root's translation, plus a one-frame
/// clip "pose" (or the pose as the rest, as the options say; the options' shape keys as morph
/// targets). See docs/formats.md. Written atomically.
/// @param mesh the mesh, only read.
/// @param path the output file path, NUL-terminated UTF-8.
/// @param opts export options, only read, or NULL for the defaults.
/// @return SKB_OK; SKB_ERR_IO when the file cannot be written (none is left behind); argument
///         errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_write_glb(
    mesh: *const skb_mesh,
    path: *const c_char,
    opts: *const skb_export_options,
) -> skb_status {
    unsafe { write_rigged(mesh, path, opts, |p, m, s, _| write_glb(p, m, s, None)) }
}

/// Writes the mesh as binary FBX 7.4: the same rigged, posed body as `skb_mesh_write_glb` (the
/// bones' local transforms hold the pose, the clusters and the bind pose the rest), in the
/// options' unit and up axis (default metres, Y up), a plain skin-colour material. See
/// docs/formats.md, "body.fbx". Written atomically.
/// @param mesh the mesh, only read.
/// @param path the output file path, NUL-terminated UTF-8.
/// @param opts export options, only read, or NULL for the defaults.
/// @return SKB_OK; SKB_ERR_IO when the file cannot be written (none is left behind); argument
///         errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_write_fbx(
    mesh: *const skb_mesh,
    path: *const c_char,
    opts: *const skb_export_options,
) -> skb_status {
    unsafe { write_rigged(mesh, path, opts, |p, m, s, f| write_fbx(p, m, s, None, f)) }
}

/// Writes the mesh as a USD text layer (UsdSkel, `.usda`): the same rigged, posed body as
/// `skb_mesh_write_glb` (a Skeleton with bind and rest transforms, the pose as a static
/// SkelAnimation), in the options' unit and up axis (default metres, Y up: `metersPerUnit`,
/// `upAxis`), a plain skin-colour material. See docs/formats.md, "body.usda". Written
/// atomically.
/// @param mesh the mesh, only read.
/// @param path the output file path, NUL-terminated UTF-8.
/// @param opts export options, only read, or NULL for the defaults.
/// @return SKB_OK; SKB_ERR_IO when the file cannot be written (none is left behind); argument
///         errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_write_usd(
    mesh: *const skb_mesh,
    path: *const c_char,
    opts: *const skb_export_options,
) -> skb_status {
    unsafe { write_rigged(mesh, path, opts, |p, m, s, f| write_usda(p, m, s, false, f)) }
}
