//! The figure's facing (front, back, left or right profile, or unknown) with its probabilities,
//! and the labelling with left and right swapped: `skb_context_detect_facing` (a detection with its
//! facing), `skb_result_facing` (the facing behind a pipeline result's detected joints) and
//! `skb_joints2d_swap_sides` (the other labelling of any joints, in one call).

use sketchbody_core::detect::facing::{swap_sides, Facing, FacingEstimate};
use sketchbody_core::error::Error;

use super::body::skb_context;
use super::detect::{detect_figure_into, skb_detect_options, skb_figure_info};
use super::image::skb_image;
use super::pipeline::skb_result;
use super::pose::{joints_in, skb_joints2d};
use super::ptr::*;
use super::status::skb_status;

/// Facing: toward the viewer (the character's right on the image's left).
pub const SKB_FACING_FRONT: u32 = 0;
/// Facing: away from the viewer (the character's right on the image's right).
pub const SKB_FACING_BACK: u32 = 1;
/// Facing: a left profile (the character's left side toward the viewer).
pub const SKB_FACING_LEFT: u32 = 2;
/// Facing: a right profile (the character's right side toward the viewer).
pub const SKB_FACING_RIGHT: u32 = 3;
/// Facing: undecided (no facing reaches probability 0.6, a back view 0.5 with the front ruled
/// out; or a back view in a photo-like image); the joints carry the front's labelling unless a
/// profile is likelier than front and back together.
pub const SKB_FACING_UNKNOWN: u32 = 4;

/// The facing of a detected figure. Plain data, 304 bytes; its layout is part of the ABI.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct skb_facing_info {
    /// `SKB_FACING_*`.
    pub facing: u32,
    /// 1 when the joints are the detector's with left and right swapped (a labelling that
    /// implied a back view without evidence of one, or the reverse), else 0.
    pub swapped: u32,
    /// Probabilities of front, back, left and right profile, summing to 1.
    pub probabilities: [f64; 4],
    /// The probability that `alternative` is the right labelling, in [0, 1].
    pub alternative_score: f64,
    /// The joints with left and right swapped (pass them to `skb_run` with given joints, or to
    /// the pose step, to take them).
    pub alternative: skb_joints2d,
}

const _: () = assert!(std::mem::size_of::<skb_facing_info>() == 304);

/// The C value of a facing.
fn facing_code(f: Facing) -> u32 {
    match f {
        Facing::Front => SKB_FACING_FRONT,
        Facing::Back => SKB_FACING_BACK,
        Facing::Left => SKB_FACING_LEFT,
        Facing::Right => SKB_FACING_RIGHT,
        Facing::Unknown => SKB_FACING_UNKNOWN,
    }
}

/// The C struct of joints.
fn joints_out(j: &sketchbody_core::skeleton::Joints2) -> skb_joints2d {
    skb_joints2d { xy: j.xy, visible: j.visible.map(u8::from), reserved: 0 }
}

/// The info struct of a facing estimate.
pub(crate) fn facing_info(f: &FacingEstimate) -> skb_facing_info {
    skb_facing_info {
        facing: facing_code(f.facing),
        swapped: u32::from(f.swapped),
        probabilities: f.probabilities,
        alternative_score: f.alternative_score,
        alternative: joints_out(&f.alternative),
    }
}

/// As `skb_context_detect_figure` (the same arguments and statuses), with the figure's facing
/// and the swapped labelling as well. On any failure nothing is written. Thread-safe.
/// @param ctx the context, only read.
/// @param image the sketch, as in `skb_context_detect_figure`.
/// @param opts detection options, or NULL for the defaults.
/// @param joints_xy receives the 15 joints as (x, y) pixel pairs in `joints_xy[0..30]`; not NULL.
/// @param joints_len the element count of `joints_xy`, at least 30.
/// @param confidence receives the 15 joint confidences in `confidence[0..15]`; not NULL.
/// @param confidence_len the element count of `confidence`, at least 15.
/// @param info receives the figure info, as in `skb_context_detect_figure`.
/// @param facing receives the facing and the swapped labelling; not NULL.
/// @return the statuses of `skb_context_detect_figure`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn skb_context_detect_facing(
    ctx: *const skb_context,
    image: *const skb_image,
    opts: *const skb_detect_options,
    joints_xy: *mut f64,
    joints_len: usize,
    confidence: *mut f64,
    confidence_len: usize,
    info: *mut skb_figure_info,
    facing: *mut skb_facing_info,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            detect_figure_into(ctx, image, opts, joints_xy, joints_len, confidence, confidence_len, info, Some(facing))
        }
    }
}

/// The facing of the figure behind `result`'s detected joints, with the swapped labelling.
/// Thread-safe on a shared result.
/// @param result the pipeline result, only read.
/// @param facing receives the facing info; not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE when the result's joints were given, not detected
///         (nothing written); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_facing(result: *const skb_result, facing: *mut skb_facing_info) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let facing = try_status!(try_mut(facing, "facing"));
            match &r.detection {
                Some(f) => {
                    *facing = facing_info(&f.facing);
                    skb_status::SKB_OK
                }
                None => super::error::fail(&Error::OutOfRange {
                    name: "detection",
                    detail: "the 2-D joints were given, not detected".into(),
                }),
            }
        }
    }
}

/// `*joints` with left and right swapped: each joint takes its mirror's position and
/// visibility; head, neck and pelvis stay. Thread-safe.
/// @param joints the joints, only read.
/// @param out receives the swapped joints; may be `joints` itself; not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL argument.
#[no_mangle]
pub unsafe extern "C" fn skb_joints2d_swap_sides(joints: *const skb_joints2d, out: *mut skb_joints2d) -> skb_status {
    unsafe {
        ffi_boundary! {
            let j = joints_in(try_status!(try_ref(joints, "joints")));
            if out.is_null() {
                return null("out");
            }
            try_status!(write_out(out, joints_out(&swap_sides(&j)), "out"));
            skb_status::SKB_OK
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> skb_joints2d {
        let j = sketchbody_core::export::joints2d::load_joints2d(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../assets/examples/sketch_joints.json"
        )))
        .unwrap();
        joints_out(&j)
    }

    /// The swap exchanges each side's joints and their visibility, in place too, and twice is
    /// the identity.
    #[test]
    fn swapping_sides_exchanges_left_and_right() {
        let mut j = example();
        j.visible[4] = 0;
        let mut out = example();
        // SAFETY: live values.
        assert_eq!(unsafe { skb_joints2d_swap_sides(&j, &mut out) }, skb_status::SKB_OK);
        assert_eq!(out.xy[7], j.xy[4]);
        assert_eq!(out.xy[0], j.xy[0]);
        assert_eq!((out.visible[7], out.visible[4]), (0, 1));
        let mut twice = out;
        let p: *mut skb_joints2d = &mut twice;
        // SAFETY: the same live struct as input and output, which the contract allows.
        assert_eq!(unsafe { skb_joints2d_swap_sides(p, p) }, skb_status::SKB_OK);
        assert_eq!((twice.xy, twice.visible), (j.xy, j.visible));
    }

    /// The codes and the info struct follow the core's estimate.
    #[test]
    fn the_info_struct_reports_the_estimate() {
        let j = joints_in(&example());
        let e = sketchbody_core::detect::facing::estimate(&j, [0.1, 0.7, 0.1, 0.1], true);
        let i = facing_info(&e);
        assert_eq!((i.facing, i.swapped), (SKB_FACING_BACK, 1));
        assert_eq!(i.probabilities, [0.1, 0.7, 0.1, 0.1]);
        assert_eq!(i.alternative.xy, swap_sides(&j).xy);
        assert_eq!(facing_code(Facing::Unknown), SKB_FACING_UNKNOWN);
    }
}
