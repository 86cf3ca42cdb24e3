//! Plausibility priors of the 3-D pose step, each switchable ([`super::PoseOptions`]):
//!
//! - **Standing** ([`standing_in_image`], [`standing_residuals`]): for a figure the 2-D joints
//!   show standing on both feet (torso and both legs near the image vertical, legs nearly
//!   straight, ankles lowest and level), the free-joint step ([`super::joint_fit`]) adds linear
//!   residuals in the model frame — an upright torso (pelvis→neck without horizontal
//!   components), the head over the neck, both ankles under the pelvis in depth and at one
//!   height (a common ground plane) — and relaxes its pull toward the dictionary pose in depth,
//!   so that depth follows these priors instead of the dictionary's guess. The two ankle-depth
//!   residuals apply only when the dictionary estimate itself has the ankles within
//!   [`STANDING_MAX_STRIDE`] of each other in depth ([`stride_in_depth`]): from the front a
//!   walking stride looks like standing in the image (legs straight and vertical, feet level),
//!   and the dictionary's stride is then evidence the image does not contradict.
//! - **Knee limits** ([`unbend_knees`]): a knee bent backwards (the shin swung forward of the
//!   thigh, against the body's facing) gets the depth flip of its thigh, shin or whole leg that
//!   bends it forward: under weak perspective the image and every bone length are unchanged. (Elbows are left alone: their bending plane depends on the upper arm's
//!   twist, which 15 joints do not show.)

use nalgebra::{Matrix3, Vector3};

use crate::skeleton::{joint, NUM_JOINTS};

/// Largest angle, degrees, of the torso (pelvis→neck) and of each leg (hip→ankle) from the image
/// vertical for a standing figure.
pub const STANDING_MAX_TILT_DEG: f64 = 10.0;
/// Smallest 2-D knee angle (hip–knee–ankle), degrees, of a standing figure's straight legs.
pub const STANDING_MIN_KNEE_DEG: f64 = 170.0;
/// Largest height difference of the two ankles in the image, as a fraction of the leg's image
/// length, for a figure standing on both feet.
pub const STANDING_MAX_ANKLE_STEP: f64 = 0.05;

/// Largest depth difference of the two ankles, metres (model frame, along the body's facing),
/// in the dictionary estimate for which the standing prior still puts both ankles under the
/// pelvis ([`stride_in_depth`]). Chosen on a validation split of training motion (held-out
/// DeepMimic walk, run, dance_a, punch, jump, long_long_walk1 and CMU subjects 02, 07, 09, 14,
/// learned without them), above the bundled example's 0.13–0.18 m (docs/benchmarks-history.md,
/// "Held-out real motion, drawn proportions, plausibility priors").
pub const STANDING_MAX_STRIDE: f64 = 0.2;

/// Spread of the standing residuals, metres: the torso's horizontal offset (3° of lean on a
/// 0.5 m torso is 2.6 cm), the head's depth over the neck, each ankle's depth from the pelvis,
/// the height difference of the ankles.
pub const SIGMA_UPRIGHT: f64 = 0.02;
/// See [`SIGMA_UPRIGHT`].
pub const SIGMA_HEAD: f64 = 0.03;
/// See [`SIGMA_UPRIGHT`].
pub const SIGMA_FEET: f64 = 0.02;
/// See [`SIGMA_UPRIGHT`].
pub const SIGMA_GROUND: f64 = 0.02;
/// The free-joint step's pull toward the dictionary pose along the viewing direction for a
/// standing figure, metres (instead of [`super::joint_fit::SIGMA_3D`]).
pub const SIGMA_DEPTH_STANDING: f64 = 0.25;

/// One linear residual `c · (y_a − y_b) − t` (camera-frame joints `y`) with
/// weight `w` = 1/σ².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearResidual {
    /// First joint.
    pub a: usize,
    /// Second joint (subtracted).
    pub b: usize,
    /// Direction (camera frame).
    pub c: Vector3<f64>,
    /// Weight, 1/m².
    pub w: f64,
    /// Target value, metres: the residual is `c · (y_a − y_b) − t`.
    pub t: f64,
}

fn angle_from_vertical(d: [f64; 2]) -> f64 {
    d[0].abs().atan2(d[1].abs()).to_degrees()
}

/// Whether the 2-D joints (pixels, y down) show a figure standing on both feet (module doc;
/// thresholds [`STANDING_MAX_TILT_DEG`], [`STANDING_MIN_KNEE_DEG`], [`STANDING_MAX_ANKLE_STEP`]).
/// Every joint of the torso and legs must be visible.
pub fn standing_in_image(uv: &[[f64; 2]; NUM_JOINTS], visible: &[bool; NUM_JOINTS]) -> bool {
    use joint::*;
    let needed = [NECK, PELVIS, R_HIP, R_KNEE, R_ANKLE, L_HIP, L_KNEE, L_ANKLE];
    if !needed.iter().all(|&j| visible[j]) {
        return false;
    }
    let d = |a: usize, b: usize| [uv[b][0] - uv[a][0], uv[b][1] - uv[a][1]];
    let torso = d(PELVIS, NECK);
    if !(torso[1] < 0.0) || angle_from_vertical(torso) > STANDING_MAX_TILT_DEG {
        return false;
    }
    let mut legs = 0.0;
    for (h, k, a) in [(R_HIP, R_KNEE, R_ANKLE), (L_HIP, L_KNEE, L_ANKLE)] {
        let leg = d(h, a);
        if !(leg[1] > 0.0) || angle_from_vertical(leg) > STANDING_MAX_TILT_DEG {
            return false;
        }
        let (u, v) = (d(k, h), d(k, a));
        let (nu, nv) = (u[0].hypot(u[1]), v[0].hypot(v[1]));
        if !(nu > 0.0 && nv > 0.0) {
            return false;
        }
        let cos = ((u[0] * v[0] + u[1] * v[1]) / (nu * nv)).clamp(-1.0, 1.0);
        if cos.acos().to_degrees() < STANDING_MIN_KNEE_DEG {
            return false;
        }
        legs += 0.5 * leg[0].hypot(leg[1]);
    }
    (uv[R_ANKLE][1] - uv[L_ANKLE][1]).abs() <= STANDING_MAX_ANKLE_STEP * legs
}

/// Depth difference of the two ankles, metres, of the camera-frame joints `y` under the camera
/// rotation `r` (model → camera): the model-frame z (the body's facing) of right ankle − left
/// ankle, absolute.
pub fn stride_in_depth(y: &[Vector3<f64>; NUM_JOINTS], r: &Matrix3<f64>) -> f64 {
    r.column(2).dot(&(y[joint::R_ANKLE] - y[joint::L_ANKLE])).abs()
}

/// The standing residuals (module doc) for the camera rotation `r` (model → camera): model
/// component `k` of a camera-frame vector `v` is `r.column(k) · v`. `feet`: with the two
/// ankle-depth residuals (both ankles under the pelvis), which [`super::joint_fit`] leaves out
/// when the estimate's [`stride_in_depth`] exceeds [`STANDING_MAX_STRIDE`].
pub fn standing_residuals(r: &Matrix3<f64>, feet: bool) -> Vec<LinearResidual> {
    use joint::*;
    let (x, y, z) = (r.column(0).into_owned(), r.column(1).into_owned(), r.column(2).into_owned());
    let w = |s: f64| 1.0 / (s * s);
    let mut out = vec![
        LinearResidual { a: NECK, b: PELVIS, c: x, w: w(SIGMA_UPRIGHT), t: 0.0 },
        LinearResidual { a: NECK, b: PELVIS, c: z, w: w(SIGMA_UPRIGHT), t: 0.0 },
        LinearResidual { a: HEAD, b: NECK, c: z, w: w(SIGMA_HEAD), t: 0.0 },
        LinearResidual { a: R_ANKLE, b: L_ANKLE, c: y, w: w(SIGMA_GROUND), t: 0.0 },
    ];
    if feet {
        out.push(LinearResidual { a: R_ANKLE, b: PELVIS, c: z, w: w(SIGMA_FEET), t: 0.0 });
        out.push(LinearResidual { a: L_ANKLE, b: PELVIS, c: z, w: w(SIGMA_FEET), t: 0.0 });
    }
    out
}

/// Bend of a knee: `(knee − hip) × (ankle − knee)` along the body's left, over the two bones'
/// length product (> 0 forward, the natural bend; < 0 backwards).
fn knee_bend(h: &Vector3<f64>, k: &Vector3<f64>, a: &Vector3<f64>, left: &Vector3<f64>) -> f64 {
    let (t, s) = (k - h, a - k);
    let scale = t.norm() * s.norm();
    if scale > 0.0 {
        t.cross(&s).dot(left) / scale
    } else {
        0.0
    }
}

/// Unbends every backwards-bent knee of the camera-frame joints `y` (module doc): a knee whose
/// bend ([`knee_bend`]; the body's left from the hips and shoulders) is below −0.05 gets the
/// depth flip (camera z, so the image and bone lengths are unchanged) of its thigh, its shin or
/// its whole leg that bends it forward (bend > 0.05) with the least depth change of knee and ankle. Returns
/// how many knees were changed.
pub fn unbend_knees(y: &mut [Vector3<f64>; NUM_JOINTS]) -> usize {
    use joint::*;
    let left = (y[L_HIP] - y[R_HIP]) + 0.5 * (y[L_SHOULDER] - y[R_SHOULDER]);
    let Some(left) = left.try_normalize(1e-9) else { return 0 };
    let mut n = 0;
    for (h, k, a) in [(R_HIP, R_KNEE, R_ANKLE), (L_HIP, L_KNEE, L_ANKLE)] {
        let (ph, pk, pa) = (y[h], y[k], y[a]);
        if knee_bend(&ph, &pk, &pa, &left) >= -0.05 {
            continue;
        }
        let flip = |p: Vector3<f64>, about: f64| Vector3::new(p.x, p.y, 2.0 * about - p.z);
        let thigh_k = flip(pk, ph.z);
        let candidates = [
            (thigh_k, pa + (thigh_k - pk)),   // the thigh (the shin follows)
            (pk, flip(pa, pk.z)),             // the shin
            (flip(pk, ph.z), flip(pa, ph.z)), // the whole leg
        ];
        let best = candidates.iter().filter(|(k2, a2)| knee_bend(&ph, k2, a2, &left) > 0.05).min_by(|x, z| {
            let cost = |c: &(Vector3<f64>, Vector3<f64>)| (c.0.z - pk.z).abs() + (c.1.z - pa.z).abs();
            cost(x).total_cmp(&cost(z))
        });
        if let Some(&(k2, a2)) = best {
            y[k] = k2;
            y[a] = a2;
            n += 1;
        }
    }
    n
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A figure standing on both feet, 422 px tall (y down): the fixture of the standing prior
    /// and of `detect::figure`'s tests.
    pub(crate) fn standing_uv() -> [[f64; 2]; NUM_JOINTS] {
        use joint::*;
        let mut uv = [[0.0; 2]; NUM_JOINTS];
        for (j, p) in [
            (HEAD, [250.0, 60.0]),
            (NECK, [250.0, 120.0]),
            (R_SHOULDER, [210.0, 130.0]),
            (R_ELBOW, [200.0, 200.0]),
            (R_WRIST, [195.0, 260.0]),
            (L_SHOULDER, [290.0, 130.0]),
            (L_ELBOW, [300.0, 200.0]),
            (L_WRIST, [305.0, 260.0]),
            (PELVIS, [250.0, 270.0]),
            (R_HIP, [230.0, 275.0]),
            (R_KNEE, [228.0, 380.0]),
            (R_ANKLE, [226.0, 480.0]),
            (L_HIP, [270.0, 275.0]),
            (L_KNEE, [272.0, 380.0]),
            (L_ANKLE, [274.0, 482.0]),
        ] {
            uv[j] = p;
        }
        uv
    }

    #[test]
    fn standing_is_detected_only_for_upright_straight_legs_on_level_feet() {
        let uv = standing_uv();
        let vis = [true; NUM_JOINTS];
        assert!(standing_in_image(&uv, &vis));
        let mut step = uv;
        step[joint::L_ANKLE][1] = 420.0;
        assert!(!standing_in_image(&step, &vis));
        let mut bent = uv;
        bent[joint::R_KNEE][0] = 180.0;
        assert!(!standing_in_image(&bent, &vis));
        let mut hidden = vis;
        hidden[joint::L_KNEE] = false;
        assert!(!standing_in_image(&uv, &hidden));
        let lying: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|j| [uv[j][1], uv[j][0]]);
        assert!(!standing_in_image(&lying, &vis));
        // A torso leaning 20° from the vertical, or upside down (neck under the pelvis).
        let mut leaning = uv;
        leaning[joint::NECK][0] = 250.0 + 150.0 * 20f64.to_radians().tan();
        assert!(!standing_in_image(&leaning, &vis));
        let mut upside_down = uv;
        upside_down[joint::NECK][1] = 300.0;
        assert!(!standing_in_image(&upside_down, &vis));
        // 9° is within the limit.
        let mut upright = uv;
        upright[joint::NECK][0] = 250.0 + 150.0 * 9f64.to_radians().tan();
        assert!(standing_in_image(&upright, &vis));
    }

    #[test]
    fn the_ankle_depth_residuals_follow_the_estimates_stride() {
        use joint::*;
        // A quarter turn: the model's facing (z) is the camera's x.
        let r = *nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2).matrix();
        let mut y = [Vector3::zeros(); NUM_JOINTS];
        y[R_ANKLE] = r * Vector3::new(-0.1, -0.9, 0.15);
        y[L_ANKLE] = r * Vector3::new(0.1, -0.9, -0.15);
        assert!((stride_in_depth(&y, &r) - 0.3).abs() < 1e-12);
        let feet =
            |v: &[LinearResidual]| v.iter().filter(|q| q.b == PELVIS && (q.a == R_ANKLE || q.a == L_ANKLE)).count();
        assert_eq!(feet(&standing_residuals(&r, true)), 2);
        assert_eq!(feet(&standing_residuals(&r, false)), 0);
        // The torso, head and ground residuals stay either way.
        assert_eq!(standing_residuals(&r, false).len(), 4);
    }

    /// The bend is the sine of the knee's angle (shin against the thigh's line), positive with
    /// the ankle behind the knee, whatever the two bones' lengths; 0 for a bone of no length.
    #[test]
    fn knee_bend_is_the_sine_of_the_knee_angle_whatever_the_bone_lengths() {
        // Body facing +z, left +x: the shin swung back (−z) by `theta` from the thigh's line.
        let left = Vector3::x();
        let hip = Vector3::new(0.1, 0.9, 0.05);
        for (thigh, shin) in [(0.45, 0.38), (0.2, 0.6), (1.0, 1.0)] {
            let knee = hip + Vector3::new(0.0, -thigh, 0.0);
            for theta in [0.3f64, 1.0, -0.5, 1.5] {
                let ankle = knee + shin * Vector3::new(0.0, -theta.cos(), -theta.sin());
                let bend = knee_bend(&hip, &knee, &ankle, &left);
                assert!((bend - theta.sin()).abs() < 1e-12, "{thigh}/{shin} at {theta}: {bend}");
            }
        }
        assert_eq!(knee_bend(&hip, &hip, &Vector3::zeros(), &left), 0.0);
    }

    /// Of the thigh's, the shin's and the whole leg's depth flips that bend a backwards knee
    /// forward, the one moving knee and ankle least in depth is taken; the image and both bone
    /// lengths stay. The body's left counts the shoulders as well as the hips (here the hips are
    /// 5 cm apart: the shoulders' line decides it).
    #[test]
    fn a_backwards_knee_takes_the_cheapest_flip_that_bends_it_forward() {
        use joint::*;
        // (knee z − hip z, ankle z − knee z) → (knee z, ankle z) after; the hip at z = 0.
        for (tz, sz, want) in [(-0.05, -0.02, (0.05, 0.03)), (0.02, 0.1, (0.02, -0.08))] {
            let mut y = [Vector3::zeros(); NUM_JOINTS];
            y[R_HIP] = Vector3::new(-0.025, 0.0, 0.0);
            y[L_HIP] = Vector3::new(0.025, 0.0, 0.0);
            y[R_SHOULDER] = Vector3::new(-0.18, 0.45, 0.0);
            y[L_SHOULDER] = Vector3::new(0.18, 0.45, 0.0);
            y[L_KNEE] = Vector3::new(0.025, -0.4, 0.0);
            y[L_ANKLE] = Vector3::new(0.025, -0.8, -0.05);
            y[R_KNEE] = Vector3::new(-0.025, -0.4, tz);
            y[R_ANKLE] = Vector3::new(-0.025, -0.8, tz + sz);
            let before = y;
            assert_eq!(unbend_knees(&mut y), 1, "{tz} {sz}");
            assert!((y[R_KNEE].z - want.0).abs() < 1e-12 && (y[R_ANKLE].z - want.1).abs() < 1e-12, "{tz} {sz}: {y:?}");
            for (a, b) in [(R_HIP, R_KNEE), (R_KNEE, R_ANKLE)] {
                assert!(((y[b] - y[a]).norm() - (before[b] - before[a]).norm()).abs() < 1e-12);
                assert_eq!(y[b].xy(), before[b].xy());
            }
            assert_eq!((y[L_KNEE], y[L_ANKLE]), (before[L_KNEE], before[L_ANKLE]));
        }
    }

    #[test]
    fn a_backwards_knee_is_mirrored_keeping_image_and_lengths() {
        use joint::*;
        // Camera frame, body facing the viewer (+z): left at +x, up +y.
        let mut y = [Vector3::zeros(); NUM_JOINTS];
        y[R_HIP] = Vector3::new(-0.1, 0.0, 0.0);
        y[L_HIP] = Vector3::new(0.1, 0.0, 0.0);
        y[NECK] = Vector3::new(0.0, 0.5, 0.0);
        y[R_SHOULDER] = Vector3::new(-0.18, 0.45, 0.0);
        y[L_SHOULDER] = Vector3::new(0.18, 0.45, 0.0);
        // Right knee behind the hip-ankle line (bent backwards), left knee in front (fine).
        y[R_KNEE] = Vector3::new(-0.1, -0.4, -0.1);
        y[R_ANKLE] = Vector3::new(-0.1, -0.8, 0.0);
        y[L_KNEE] = Vector3::new(0.1, -0.4, 0.1);
        y[L_ANKLE] = Vector3::new(0.1, -0.8, 0.0);
        let before = y;
        assert_eq!(unbend_knees(&mut y), 1);
        let left = Vector3::x();
        assert!(knee_bend(&y[R_HIP], &y[R_KNEE], &y[R_ANKLE], &left) > 0.0, "{:?}", y[R_KNEE]);
        for j in [R_KNEE, R_ANKLE] {
            assert!((y[j].xy() - before[j].xy()).norm() < 1e-12);
        }
        for (a, b) in [(R_HIP, R_KNEE), (R_KNEE, R_ANKLE)] {
            assert!(((y[b] - y[a]).norm() - (before[b] - before[a]).norm()).abs() < 1e-12);
        }
        assert_eq!(y[L_KNEE], before[L_KNEE]);
        assert_eq!(unbend_knees(&mut y), 0);
    }
}
