//! The 3-D pose of a turnaround: the front view's estimate refined by every view's 2-D joints.
//!
//! Each extra view's camera is the front camera turned by its label's yaw about the body's
//! vertical axis ([`crate::view`]) with its own scale and translation (one scale for both axes:
//! the views may be drawn at different sizes). Starting from the front estimate's joints, the
//! fit alternates (a) each view's scale and translation in closed form, the first time from the
//! joints' vertical coordinates only (they do not depend on the depth the front view guesses),
//! and (b) every joint by linear least squares over the views that show it (the front camera
//! fixed: it sets the frame and the scale), with a weak pull toward the front estimate so that a
//! joint only one view shows keeps the front estimate's depth. With a side view, a joint's
//! depth is read from the side view's horizontal coordinate.
//!
//! Views that disagree (another pose, another character, a wrong label) leave a large
//! reprojection residual: [`ViewsPose::residual`] is each view's RMS reprojection error as a
//! fraction of that view's figure height, for the caller to report or refuse.
//!
//! A side view labelled with the wrong side (drawn facing image left but labelled
//! [`ViewLabel::Side`], or the reverse) fits its joints as well as the right label: weak
//! perspective projects both sides' views to mirror images, so the triangulation mirrors the
//! body's depth instead. [`side_facing`] triangulates such a view both ways and compares each
//! result's limbs with the front estimate's (whose depth comes from the pose dictionary): the
//! caller refuses a view whose other side agrees clearly better ([`SideFacing::mirrored`]).

use nalgebra::{Matrix3, Vector3};

use super::PoseEstimate;
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::skeleton::{Joints2, Joints3, BONES, LIMB_BONES, NUM_JOINTS};
use crate::view::ViewLabel;

/// Weight of the pull toward the front estimate, as a fraction of the front camera's vertical
/// scale (pixels of residual per metre of displacement): weak enough that two views decide.
const PRIOR_WEIGHT: f64 = 0.02;

/// Alternations of cameras and joints.
const ITERATIONS: usize = 40;

/// [`SideFacing::mirrored`]: the other side's limbs must agree with the front estimate's by at
/// least this many degrees more (mean over the limbs) than the labelled side's.
pub const MIRROR_MARGIN_DEG: f64 = 10.0;

/// [`SideFacing::mirrored`]: and by at most this fraction of the labelled side's disagreement.
pub const MIRROR_RATIO: f64 = 0.5;

/// One extra view's 2-D joints and label.
#[derive(Clone, Copy, Debug)]
pub struct ViewJoints<'a> {
    /// The view's label (not [`ViewLabel::Front`]: the front view is the estimate's).
    pub label: ViewLabel,
    /// The view's 2-D joints, pixels of its own image.
    pub joints: &'a Joints2,
}

/// The turnaround's pose. Owns its data.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewsPose {
    /// 3-D joints (model frame; the front estimate's metric scale and frame).
    pub joints: Joints3,
    /// Each extra view's camera, in the order given (image pixels of that view).
    pub cameras: Vec<WeakPerspective>,
    /// RMS reprojection error over each view's visible joints as a fraction of that view's
    /// figure height (the vertical extent of its visible joints): the front view first, then
    /// the extra views in order.
    pub residual: Vec<f64>,
    /// Each extra view's scale over the front camera's vertical scale (1: drawn at the same
    /// size).
    pub scale_ratio: Vec<f64>,
}

/// Refines `front`'s pose with the extra `views` (module doc). `front_joints` are the front
/// view's 2-D joints. Errors: a [`ViewLabel::Front`] among `views`, a view with fewer than two
/// visible joints or joints without vertical extent ([`Error::Degenerate`]), non-finite joints
/// ([`Error::NonFinite`]), a view whose joints fit the pose only upside down
/// ([`Error::ViewsDisagree`]).
pub fn triangulate(front: &PoseEstimate, front_joints: &Joints2, views: &[ViewJoints]) -> Result<ViewsPose> {
    check(front_joints, "front")?;
    for v in views {
        if v.label == ViewLabel::Front {
            return Err(Error::OutOfRange { name: "view label", detail: "the front view is the main image".into() });
        }
        check(v.joints, v.label.name())?;
    }
    if views.is_empty() {
        return Ok(assess(front.joints, Vec::new(), &front.camera, front_joints, views));
    }
    // The turnaround's axis: the front estimate's vertical, tilted where the views agree better
    // (coarse grid, then a finer one about the best; each tilt with a short alternation).
    let mut best = (f64::INFINITY, Matrix3::identity());
    let mut first_error = None;
    let mut search = |tilts: Vec<Matrix3<f64>>, best: &mut (f64, Matrix3<f64>)| {
        for axis in tilts {
            match solve_about(front, front_joints, views, &axis, ITERATIONS / 4) {
                Ok(p) => {
                    let cost = p.residual.iter().map(|r| r * r).sum::<f64>();
                    if cost < best.0 {
                        *best = (cost, axis);
                    }
                }
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
    };
    search(tilt_grid(&Matrix3::identity(), TILT_COARSE_DEG, 3), &mut best);
    let coarse = best.1;
    search(tilt_grid(&coarse, TILT_COARSE_DEG / 3.0, 2), &mut best);
    if !best.0.is_finite() {
        return Err(first_error.unwrap_or_else(|| Error::Degenerate("no tilt of the views fits".into())));
    }
    solve_about(front, front_joints, views, &best.1, ITERATIONS)
}

/// Step of the coarse grid of the turnaround axis's tilt, degrees (the fine grid's is a third).
const TILT_COARSE_DEG: f64 = 5.0;

/// Tilts `centre` by `(2n+1)²` rotations about the model's X and Z axes, `step_deg` apart.
fn tilt_grid(centre: &Matrix3<f64>, step_deg: f64, n: i32) -> Vec<Matrix3<f64>> {
    let mut out = Vec::with_capacity(((2 * n + 1) * (2 * n + 1)) as usize);
    for i in -n..=n {
        for j in -n..=n {
            let (a, b) = ((i as f64 * step_deg).to_radians(), (j as f64 * step_deg).to_radians());
            out.push(centre * nalgebra::Rotation3::from_euler_angles(a, 0.0, b).into_inner());
        }
    }
    out
}

/// The views' pose with the turnaround's axis `axis` (a rotation of the front estimate's model
/// frame; identity: its +Y), alternating `iterations` times between the joints and the views'
/// scales and translations.
fn solve_about(
    front: &PoseEstimate,
    front_joints: &Joints2,
    views: &[ViewJoints],
    axis: &Matrix3<f64>,
    iterations: usize,
) -> Result<ViewsPose> {
    let mut joints = front.joints;
    let mut cameras: Vec<WeakPerspective> =
        views.iter().map(|v| fit_view(&joints, &front.camera, axis, v, true)).collect::<Result<_>>()?;
    for _ in 0..iterations {
        joints = solve_joints(front, front_joints, views, &cameras)?;
        cameras = views.iter().map(|v| fit_view(&joints, &front.camera, axis, v, false)).collect::<Result<_>>()?;
    }
    Ok(assess(joints, cameras, &front.camera, front_joints, views))
}

/// The views of a given pose (e.g. the ground truth's): `front.joints` kept, each extra view's
/// scale and translation fitted to its joints, the residuals and scale ratios as
/// [`triangulate`]'s. Errors as [`triangulate`]'s.
pub fn view_pose_for(front: &PoseEstimate, front_joints: &Joints2, views: &[ViewJoints]) -> Result<ViewsPose> {
    check(front_joints, "front")?;
    for v in views {
        check(v.joints, v.label.name())?;
    }
    let joints = front.joints;
    let cameras: Vec<WeakPerspective> = views
        .iter()
        .map(|v| fit_view(&joints, &front.camera, &Matrix3::identity(), v, false))
        .collect::<Result<_>>()?;
    Ok(assess(joints, cameras, &front.camera, front_joints, views))
}

/// How a side view's two possible facings agree with the front estimate ([`side_facing`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SideFacing {
    /// Mean angle between the triangulated limbs and the front estimate's, degrees, with the
    /// view's label as given.
    pub as_labelled_deg: f64,
    /// The same with the view relabelled as the other side ([`ViewLabel::other_side`]).
    pub other_side_deg: f64,
}

impl SideFacing {
    /// `true` when the other side agrees clearly better ([`MIRROR_MARGIN_DEG`],
    /// [`MIRROR_RATIO`]): the view's depth comes out mirrored, its label is likely the wrong
    /// side.
    pub fn mirrored(&self) -> bool {
        self.other_side_deg + MIRROR_MARGIN_DEG < self.as_labelled_deg
            && self.other_side_deg < MIRROR_RATIO * self.as_labelled_deg
    }
}

/// For each of `views`, in order: for a side view ([`ViewLabel::Side`] or
/// [`ViewLabel::SideLeft`]) how its labelled and its other facing agree with `front`'s limbs
/// (module doc), the other views kept as labelled; `None` for a back view. `pose` is
/// [`triangulate`]'s result for the labels as given. Errors as [`triangulate`]'s.
pub fn side_facing(
    front: &PoseEstimate,
    front_joints: &Joints2,
    views: &[ViewJoints],
    pose: &ViewsPose,
) -> Result<Vec<Option<SideFacing>>> {
    let as_labelled_deg = limb_disagreement_deg(&pose.joints, &front.joints);
    let mut out = Vec::with_capacity(views.len());
    for (k, v) in views.iter().enumerate() {
        let Some(other) = v.label.other_side() else {
            out.push(None);
            continue;
        };
        let mut flipped = views.to_vec();
        flipped[k].label = other;
        let p = triangulate(front, front_joints, &flipped)?;
        out.push(Some(SideFacing { as_labelled_deg, other_side_deg: limb_disagreement_deg(&p.joints, &front.joints) }));
    }
    Ok(out)
}

/// Mean angle between the limb bones ([`LIMB_BONES`]) of `a` and `b`, degrees (one frame; a
/// bone of zero length counts 0).
pub fn limb_disagreement_deg(a: &Joints3, b: &Joints3) -> f64 {
    let angle = |bone: usize| {
        let (p, c) = BONES[bone];
        let da = Vector3::from(a[c]) - Vector3::from(a[p]);
        let db = Vector3::from(b[c]) - Vector3::from(b[p]);
        match da.norm() * db.norm() {
            n if n > 0.0 => (da.dot(&db) / n).clamp(-1.0, 1.0).acos().to_degrees(),
            _ => 0.0,
        }
    };
    LIMB_BONES.iter().map(|&bone| angle(bone)).sum::<f64>() / LIMB_BONES.len() as f64
}

/// The pose with its residuals and scale ratios.
fn assess(
    joints: Joints3,
    cameras: Vec<WeakPerspective>,
    front: &WeakPerspective,
    front_joints: &Joints2,
    views: &[ViewJoints],
) -> ViewsPose {
    let mut residual = vec![relative_residual(&joints, front, front_joints)];
    residual.extend(views.iter().zip(&cameras).map(|(v, c)| relative_residual(&joints, c, v.joints)));
    let scale_ratio = cameras.iter().map(|c| c.sy / front.sy).collect();
    ViewsPose { joints, cameras, residual, scale_ratio }
}

/// View `v`'s camera: the `front` camera turned by its label about `axis`'s +Y (`axis` a rotation
/// of the model frame), scale and translation fitted.
fn fit_view(
    joints: &Joints3,
    front: &WeakPerspective,
    axis: &Matrix3<f64>,
    v: &ViewJoints,
    vertical_only: bool,
) -> Result<WeakPerspective> {
    let turned = WeakPerspective { r: front.r * axis * v.label.turn() * axis.transpose(), ..*front };
    fit_camera_from(joints, v.label, &turned, v.joints, vertical_only)
}

/// At least two visible, finite joints with some vertical extent.
fn check(j: &Joints2, what: &str) -> Result<()> {
    let visible: Vec<[f64; 2]> = (0..NUM_JOINTS).filter(|&k| j.visible[k]).map(|k| j.xy[k]).collect();
    if let Some(v) = visible.iter().flatten().find(|v| !v.is_finite()) {
        return Err(Error::NonFinite { name: "view joint", value: *v });
    }
    if visible.len() < 2 || extent(j) <= 0.0 {
        return Err(Error::Degenerate(format!("the {what} view's joints: fewer than two visible or no height")));
    }
    Ok(())
}

/// Vertical extent of the visible joints, pixels.
fn extent(j: &Joints2) -> f64 {
    let ys = (0..NUM_JOINTS).filter(|&k| j.visible[k]).map(|k| j.xy[k][1]);
    ys.clone().fold(f64::MIN, f64::max) - ys.fold(f64::MAX, f64::min)
}

/// Scale (one for both axes) and translation of `turned` fitted in closed form so that
/// `joints` project onto the visible `target` joints; with `vertical_only` the scale and the
/// vertical translation come from the vertical coordinates alone (the horizontal translation
/// then centres the horizontal ones). Errors: [`Error::Degenerate`] for a non-finite scale,
/// [`Error::ViewsDisagree`] for a non-positive one (view `label`'s figure upside down).
fn fit_camera_from(
    joints: &Joints3,
    label: ViewLabel,
    turned: &WeakPerspective,
    target: &Joints2,
    vertical_only: bool,
) -> Result<WeakPerspective> {
    let pts: Vec<([f64; 2], [f64; 2])> = (0..NUM_JOINTS)
        .filter(|&k| target.visible[k])
        .map(|k| {
            let c = turned.r * Vector3::from(joints[k]);
            ([c.x, -c.y], target.xy[k])
        })
        .collect();
    let n = pts.len() as f64;
    type Pair = ([f64; 2], [f64; 2]);
    let mean = |f: &dyn Fn(&Pair) -> f64| pts.iter().map(f).sum::<f64>() / n;
    let (ma, mb, mu, mv) = (mean(&|p| p.0[0]), mean(&|p| p.0[1]), mean(&|p| p.1[0]), mean(&|p| p.1[1]));
    let (mut num, mut den) = (0.0, 0.0);
    for (ab, uv) in &pts {
        if !vertical_only {
            num += (ab[0] - ma) * (uv[0] - mu);
            den += (ab[0] - ma).powi(2);
        }
        num += (ab[1] - mb) * (uv[1] - mv);
        den += (ab[1] - mb).powi(2);
    }
    let s = num / den;
    if !s.is_finite() {
        return Err(Error::Degenerate(format!("a view's fitted scale is {s}")));
    }
    if s <= 0.0 {
        return Err(Error::ViewsDisagree(format!(
            "the {} view disagrees with the front view: its joints match the front view's pose only upside down \
                 (another figure or wrong joints)",
            label.name()
        )));
    }
    Ok(WeakPerspective { sx: s, sy: s, r: turned.r, t: [mu - s * ma, mv - s * mb] })
}

/// Every joint by least squares over the views that show it (module doc).
fn solve_joints(
    front: &PoseEstimate,
    front_joints: &Joints2,
    views: &[ViewJoints],
    cameras: &[WeakPerspective],
) -> Result<Joints3> {
    let lambda = PRIOR_WEIGHT * front.camera.sy;
    let mut out = front.joints;
    for (k, o) in out.iter_mut().enumerate() {
        let x0 = Vector3::from(front.joints[k]);
        let mut ata = Matrix3::identity() * lambda * lambda;
        let mut atb = x0 * lambda * lambda;
        let seen =
            std::iter::once((&front.camera, front_joints)).chain(cameras.iter().zip(views.iter().map(|v| v.joints)));
        for (cam, j2) in seen {
            if !j2.visible[k] {
                continue;
            }
            let rows = [
                (cam.r.row(0).transpose() * cam.sx, j2.xy[k][0] - cam.t[0]),
                (cam.r.row(1).transpose() * -cam.sy, j2.xy[k][1] - cam.t[1]),
            ];
            for (a, b) in rows {
                ata += a * a.transpose();
                atb += a * b;
            }
        }
        let x =
            ata.cholesky().ok_or_else(|| Error::Degenerate("a view's joint system is singular".into()))?.solve(&atb);
        if x.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { name: "triangulated joint", value: f64::NAN });
        }
        *o = [x.x, x.y, x.z];
    }
    Ok(out)
}

/// RMS reprojection error of the visible joints over their vertical extent.
fn relative_residual(joints: &Joints3, cam: &WeakPerspective, j2: &Joints2) -> f64 {
    let errs: Vec<f64> = (0..NUM_JOINTS)
        .filter(|&k| j2.visible[k])
        .map(|k| {
            let p = cam.project(&Vector3::from(joints[k]));
            (p[0] - j2.xy[k][0]).powi(2) + (p[1] - j2.xy[k][1]).powi(2)
        })
        .collect();
    (errs.iter().sum::<f64>() / errs.len() as f64).sqrt() / extent(j2)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::pose::figure::BodyFactors;
    use crate::skeleton::joint;

    /// A walking pose (metres, model frame: right side at −X, facing +Z): arms and legs swing in
    /// depth, which one front view cannot see.
    pub(crate) fn walking() -> Joints3 {
        [
            [0.0, 0.65, 0.02],
            [0.0, 0.5, 0.0],
            [-0.18, 0.47, 0.0],
            [-0.2, 0.2, -0.12],
            [-0.22, -0.02, -0.05],
            [0.18, 0.47, 0.0],
            [0.21, 0.22, 0.1],
            [0.23, 0.0, 0.2],
            [0.0, 0.0, 0.0],
            [-0.1, -0.02, 0.0],
            [-0.11, -0.42, 0.15],
            [-0.12, -0.82, 0.05],
            [0.1, -0.02, 0.0],
            [0.11, -0.43, -0.1],
            [0.12, -0.8, -0.3],
        ]
    }

    pub(crate) fn project(j: &Joints3, cam: &WeakPerspective) -> Joints2 {
        Joints2 { xy: std::array::from_fn(|k| cam.project(&Vector3::from(j[k]))), visible: [true; NUM_JOINTS] }
    }

    pub(crate) fn estimate(joints: Joints3, camera: WeakPerspective) -> PoseEstimate {
        PoseEstimate {
            joints,
            camera,
            bases: Vec::new(),
            weights: Vec::new(),
            rms: 0.0,
            length_excess: 0.0,
            base: joints,
            base_parts: None,
            factors: BodyFactors::default(),
            plausible: true,
            alternatives: Vec::new(),
            depth_costs: None,
        }
    }

    pub(crate) fn front_camera() -> WeakPerspective {
        let r = nalgebra::Rotation3::from_euler_angles(0.05, 0.3, 0.02).into_inner();
        WeakPerspective { sx: 200.0, sy: 200.0, r, t: [256.0, 250.0] }
    }

    #[test]
    fn a_side_view_gives_the_depth_the_front_view_guesses() {
        let truth = walking();
        let cam = front_camera();
        let front = project(&truth, &cam);
        // The side view drawn at 0.8 times the front's size, elsewhere on its page.
        let side_cam =
            WeakPerspective { sx: 160.0, sy: 160.0, t: [300.0, 210.0], ..ViewLabel::Side.camera_from_front(&cam) };
        let side = project(&truth, &side_cam);
        // The front estimate has the right image but flat depth.
        let flat: Joints3 = std::array::from_fn(|k| {
            let c = cam.r * Vector3::from(truth[k]);
            let x = cam.r.transpose() * Vector3::new(c.x, c.y, 0.0);
            [x.x, x.y, x.z]
        });
        let views = [ViewJoints { label: ViewLabel::Side, joints: &side }];
        let p = triangulate(&estimate(flat, cam), &front, &views).unwrap();
        // No view measures where the body stands along the front camera's axis (the side
        // camera's translation absorbs it): compare the joints after their mean offset.
        let offset: Vector3<f64> =
            (0..NUM_JOINTS).map(|k| Vector3::from(p.joints[k]) - Vector3::from(truth[k])).sum::<Vector3<f64>>()
                / NUM_JOINTS as f64;
        for k in 0..NUM_JOINTS {
            let e = (Vector3::from(p.joints[k]) - offset - Vector3::from(truth[k])).norm();
            assert!(e < 2e-3, "joint {k} is {e} m off");
        }
        assert!((p.scale_ratio[0] - 0.8).abs() < 1e-3, "scale ratio {}", p.scale_ratio[0]);
        assert!(p.residual.iter().all(|r| *r < 1e-3), "residuals {:?}", p.residual);
        assert!((p.cameras[0].t[1] - 210.0).abs() < 0.5, "side camera {:?}", p.cameras[0].t);
        // Only the front view: nothing to triangulate with, the estimate stays.
        let alone = triangulate(&estimate(flat, cam), &front, &[]).unwrap();
        assert_eq!(alone.joints.map(|j| j.map(|v| (v * 1e6).round())), flat.map(|j| j.map(|v| (v * 1e6).round())));
    }

    #[test]
    fn a_side_view_of_another_pose_leaves_a_large_residual() {
        let cam = front_camera();
        let truth = walking();
        let front = project(&truth, &cam);
        // The other character: arms raised, legs together.
        let mut other = truth;
        other[joint::R_WRIST] = [-0.25, 0.9, 0.0];
        other[joint::L_WRIST] = [0.25, 0.9, 0.0];
        other[joint::R_ELBOW] = [-0.22, 0.7, 0.0];
        other[joint::L_ELBOW] = [0.22, 0.7, 0.0];
        let side = project(&other, &ViewLabel::Side.camera_from_front(&cam));
        let views = [ViewJoints { label: ViewLabel::Side, joints: &side }];
        let p = triangulate(&estimate(truth, cam), &front, &views).unwrap();
        let consistent = project(&truth, &ViewLabel::Side.camera_from_front(&cam));
        let q =
            triangulate(&estimate(truth, cam), &front, &[ViewJoints { label: ViewLabel::Side, joints: &consistent }])
                .unwrap();
        assert!(p.residual[1] > 0.05, "residual {:?}", p.residual);
        assert!(q.residual[1] < 0.005, "residual {:?}", q.residual);
    }

    #[test]
    fn a_side_view_labelled_with_the_wrong_side_is_found_mirrored() {
        let truth = walking();
        let cam = front_camera();
        let front = project(&truth, &cam);
        // The front estimate: the truth's depth roughly (each joint 3 cm off in depth, so its
        // limbs point some 10° off the truth's).
        let rough: Joints3 = std::array::from_fn(|k| {
            let j = truth[k];
            [j[0], j[1], j[2] + if k % 2 == 0 { 0.03 } else { -0.03 }]
        });
        let est = estimate(rough, cam);
        for (drawn, label) in [(ViewLabel::Side, ViewLabel::Side), (ViewLabel::SideLeft, ViewLabel::SideLeft)] {
            let side = project(&truth, &drawn.camera_from_front(&cam));
            let right = [ViewJoints { label, joints: &side }];
            let p = triangulate(&est, &front, &right).unwrap();
            let f = side_facing(&est, &front, &right, &p).unwrap()[0].unwrap();
            assert!(!f.mirrored() && f.as_labelled_deg < 15.0, "{label:?} drawn {drawn:?}: {f:?}");
            // The same drawing under the other side's label fits its joints as well, but its
            // depth comes out mirrored.
            let wrong = [ViewJoints { label: label.other_side().unwrap(), joints: &side }];
            let q = triangulate(&est, &front, &wrong).unwrap();
            assert!(q.residual[1] < 0.02, "the mirrored fit leaves {:?}", q.residual);
            let g = side_facing(&est, &front, &wrong, &q).unwrap()[0].unwrap();
            assert!(g.mirrored(), "labelled {:?}, drawn {drawn:?}: {g:?}", wrong[0].label);
            assert!((g.other_side_deg - f.as_labelled_deg).abs() < 1e-6);
        }
        // A back view has no other facing.
        let back = project(&truth, &ViewLabel::Back.camera_from_front(&cam));
        let views = [ViewJoints { label: ViewLabel::Back, joints: &back }];
        let p = triangulate(&est, &front, &views).unwrap();
        assert_eq!(side_facing(&est, &front, &views, &p).unwrap(), vec![None]);
    }

    #[test]
    fn bad_views_are_errors() {
        let cam = front_camera();
        let truth = walking();
        let front = project(&truth, &cam);
        let est = estimate(truth, cam);
        let front_label = [ViewJoints { label: ViewLabel::Front, joints: &front }];
        assert!(matches!(triangulate(&est, &front, &front_label), Err(Error::OutOfRange { .. })));
        let mut hidden = front;
        hidden.visible = [false; NUM_JOINTS];
        hidden.visible[0] = true;
        let one = [ViewJoints { label: ViewLabel::Side, joints: &hidden }];
        assert!(matches!(triangulate(&est, &front, &one), Err(Error::Degenerate(_))));
        let mut nan = front;
        nan.xy[3][0] = f64::NAN;
        let bad = [ViewJoints { label: ViewLabel::Back, joints: &nan }];
        assert!(matches!(triangulate(&est, &front, &bad), Err(Error::NonFinite { .. })));
    }
}
