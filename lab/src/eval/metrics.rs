//! Accuracy metrics of the paper's §III and of 3-D pose work: AED (eq. 10), MPJPE, PA-MPJPE
//! (Procrustes with scale) and PCK.

use nalgebra::{Matrix3, Vector3};

use sketchbody::error::{Error, Result};

fn check_pair<T>(name: &'static str, a: &[T], b: &[T]) -> Result<()> {
    if a.is_empty() || a.len() != b.len() {
        return Err(Error::OutOfRange {
            name,
            detail: format!("{} reference vs {} estimated points (need equal, non-zero)", a.len(), b.len()),
        });
    }
    Ok(())
}

fn check_height(h: f64) -> Result<()> {
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::OutOfRange { name: "reference height", detail: format!("{h} must be finite and > 0") });
    }
    Ok(())
}

fn v(p: &[f64; 3]) -> Vector3<f64> {
    Vector3::from(*p)
}

/// AED, eq. (10): the mean Euclidean distance between corresponding vertices, both meshes divided
/// by the reference height `height` (so the result is a fraction of the reference height).
/// No alignment. Errors: different or zero vertex counts, non-positive height, non-finite values.
pub fn aed(reference: &[[f64; 3]], estimate: &[[f64; 3]], height: f64) -> Result<f64> {
    check_pair("AED meshes", reference, estimate)?;
    check_height(height)?;
    let sum: f64 = reference.iter().zip(estimate).map(|(a, b)| (v(a) - v(b)).norm()).sum();
    let r = sum / reference.len() as f64 / height;
    if !r.is_finite() {
        return Err(Error::NonFinite { name: "AED", value: r });
    }
    Ok(r)
}

/// Height of a point set: its extent along +Y (the model frame's up axis), same units as the input.
/// Errors: no points, non-finite values.
pub fn height_of(points: &[[f64; 3]]) -> Result<f64> {
    if points.is_empty() {
        return Err(Error::OutOfRange { name: "mesh height", detail: "no vertices".into() });
    }
    let (lo, hi) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
    let h = hi - lo;
    if !h.is_finite() {
        return Err(Error::NonFinite { name: "mesh height", value: h });
    }
    Ok(h)
}

/// The estimate scaled uniformly about its feet to the reference height `height`: about the point
/// (0, lowest Y, 0) by `height / height_of(estimate)`, then moved along Y so its lowest point is at
/// the reference's lowest Y. A sketch does not fix the absolute size; this is the AED diagnostic
/// of a fit whose size is known. Errors: [`height_of`]'s, a flat estimate (height ≤ 1e-12),
/// non-positive reference height.
pub fn scale_to_height(reference: &[[f64; 3]], estimate: &[[f64; 3]], height: f64) -> Result<Vec<[f64; 3]>> {
    check_height(height)?;
    let he = height_of(estimate)?;
    if he <= 1e-12 {
        return Err(Error::OutOfRange { name: "estimated mesh", detail: format!("height {he} cannot be scaled") });
    }
    let low = |p: &[[f64; 3]]| p.iter().map(|x| x[1]).fold(f64::INFINITY, f64::min);
    let (le, lr) = (low(estimate), low(reference));
    let k = height / he;
    Ok(estimate.iter().map(|p| [p[0] * k, (p[1] - le) * k + lr, p[2] * k]).collect())
}

/// The points translated so that their centroid is at the origin.
pub fn centred(p: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let c = p.iter().fold(Vector3::zeros(), |s, x| s + v(x)) / p.len().max(1) as f64;
    p.iter().map(|x| (v(x) - c).into()).collect()
}

/// Mean per-joint position error (same units as the input) after moving the estimate's joint
/// `root` onto the reference's.
pub fn mpjpe(reference: &[[f64; 3]], estimate: &[[f64; 3]], root: usize) -> Result<f64> {
    check_pair("MPJPE joints", reference, estimate)?;
    if root >= reference.len() {
        return Err(Error::OutOfRange { name: "root joint", detail: format!("{root} >= {}", reference.len()) });
    }
    let d = v(&reference[root]) - v(&estimate[root]);
    let m = reference.iter().zip(estimate).map(|(a, b)| (v(a) - v(b) - d).norm()).sum::<f64>() / reference.len() as f64;
    if !m.is_finite() {
        return Err(Error::NonFinite { name: "MPJPE", value: m });
    }
    Ok(m)
}

/// The similarity transform (scale `s`, rotation `r`, translation `t`) that best maps `estimate`
/// onto `reference` in least squares (Umeyama 1991), applied to `estimate`.
pub fn procrustes_align(reference: &[[f64; 3]], estimate: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
    check_pair("Procrustes points", reference, estimate)?;
    let n = reference.len() as f64;
    let mr = reference.iter().fold(Vector3::zeros(), |s, x| s + v(x)) / n;
    let me = estimate.iter().fold(Vector3::zeros(), |s, x| s + v(x)) / n;
    let mut cov = Matrix3::zeros();
    let mut var_e = 0.0;
    for (a, b) in reference.iter().zip(estimate) {
        let (x, y) = (v(a) - mr, v(b) - me);
        cov += x * y.transpose();
        var_e += y.norm_squared();
    }
    if !(var_e.is_finite() && var_e > 1e-18) || cov.iter().any(|c| !c.is_finite()) {
        return Err(Error::OutOfRange {
            name: "Procrustes points",
            detail: "the estimate is degenerate (all points coincide) or not finite".into(),
        });
    }
    let svd = cov.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => return Err(Error::OutOfRange { name: "Procrustes points", detail: "SVD failed".into() }),
    };
    let mut sgn = Matrix3::identity();
    if (u * vt).determinant() < 0.0 {
        sgn[(2, 2)] = -1.0;
    }
    let r = u * sgn * vt;
    let s = (svd.singular_values.component_mul(&Vector3::new(sgn[(0, 0)], sgn[(1, 1)], sgn[(2, 2)]))).sum() / var_e;
    Ok(estimate.iter().map(|b| (mr + s * r * (v(b) - me)).into()).collect())
}

/// PA-MPJPE: mean per-joint error after [`procrustes_align`].
pub fn pa_mpjpe(reference: &[[f64; 3]], estimate: &[[f64; 3]]) -> Result<f64> {
    let aligned = procrustes_align(reference, estimate)?;
    Ok(reference.iter().zip(&aligned).map(|(a, b)| (v(a) - v(b)).norm()).sum::<f64>() / reference.len() as f64)
}

/// The normaliser of [`pck`]: the longer side of the reference joints' bounding box, pixels.
pub fn pck_normaliser(reference: &[[f64; 2]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in reference {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (hi[0] - lo[0]).max(hi[1] - lo[1])
}

/// PCK@`alpha`: the fraction of joints whose estimate lies within `alpha` × [`pck_normaliser`]
/// of the reference (all joints, visible or not).
pub fn pck(reference: &[[f64; 2]], estimate: &[[f64; 2]], alpha: f64) -> Result<f64> {
    check_pair("PCK joints", reference, estimate)?;
    let thr = alpha * pck_normaliser(reference);
    if !(thr.is_finite() && thr > 0.0) {
        return Err(Error::OutOfRange {
            name: "PCK threshold",
            detail: format!("{thr} (alpha {alpha}, joints all at one point?)"),
        });
    }
    let hit = reference
        .iter()
        .zip(estimate)
        .filter(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() <= thr)
        .count();
    Ok(hit as f64 / reference.len() as f64)
}

/// Scales `estimate` about its joint `root` so that its total bone length equals the
/// reference's (`bones` as joint pairs): a sketch fixes the size only up to a factor.
pub fn scale_to_reference(
    reference: &[[f64; 3]],
    estimate: &[[f64; 3]],
    bones: &[(usize, usize)],
    root: usize,
) -> Result<Vec<[f64; 3]>> {
    check_pair("joints", reference, estimate)?;
    let total = |p: &[[f64; 3]]| bones.iter().map(|&(a, b)| (v(&p[a]) - v(&p[b])).norm()).sum::<f64>();
    let (lr, le) = (total(reference), total(estimate));
    if !(le.is_finite() && le > 1e-12 && lr.is_finite()) || root >= estimate.len() {
        return Err(Error::OutOfRange {
            name: "estimated joints",
            detail: format!("total bone length {le} cannot be scaled"),
        });
    }
    let k = lr / le;
    let o = v(&estimate[root]);
    Ok(estimate.iter().map(|p| (o + (v(p) - o) * k).into()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn pts() -> Vec<[f64; 3]> {
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0], [1.0, 1.0, 1.0]]
    }

    #[test]
    fn identical_meshes_score_zero_and_translation_scores_its_length() {
        let a = pts();
        assert_eq!(aed(&a, &a, 1.7).unwrap(), 0.0);
        // Translation by (0.3, 0.4, 0) has length 0.5; over a 2 m reference that is 0.25.
        let b: Vec<[f64; 3]> = a.iter().map(|p| [p[0] + 0.3, p[1] + 0.4, p[2]]).collect();
        assert!((aed(&a, &b, 2.0).unwrap() - 0.25).abs() < 1e-12);
        assert!((aed(&centred(&a), &centred(&b), 2.0).unwrap()).abs() < 1e-12, "centring removes it");
        assert!(mpjpe(&a, &b, 0).unwrap() < 1e-12, "root alignment removes a translation");
        // One joint off by (0, 0, 0.5) after root alignment: mean 0.5 / 5 = 0.1.
        let mut c = a.clone();
        c[4][2] += 0.5;
        assert!((mpjpe(&a, &c, 0).unwrap() - 0.1).abs() < 1e-12);
        assert!(aed(&a, &b[..4], 1.0).is_err());
        assert!(aed(&a, &b, 0.0).is_err());
    }

    #[test]
    fn height_scaled_aed_removes_the_size_error_only() {
        // A box 2 m tall (y from -1 to 1) and the same box at half size, lifted by 3 m.
        let a = vec![[1.0, -1.0, 0.0], [-1.0, -1.0, 0.0], [0.0, 1.0, 1.0], [0.0, 1.0, -1.0]];
        let b: Vec<[f64; 3]> = a.iter().map(|p| [p[0] * 0.5, p[1] * 0.5 + 3.0, p[2] * 0.5]).collect();
        assert_eq!(height_of(&a).unwrap(), 2.0);
        assert_eq!(height_of(&b).unwrap(), 1.0);
        let s = scale_to_height(&a, &b, 2.0).unwrap();
        assert!(aed(&a, &s, 2.0).unwrap() < 1e-12, "{s:?}");
        // A shape error survives: widen the first vertex by 0.2 m at half size -> 0.4 m at full
        // size, one of four vertices, over a 2 m reference: 0.4 / 4 / 2 = 0.05.
        let mut c = b.clone();
        c[0][0] += 0.2;
        assert!((aed(&a, &scale_to_height(&a, &c, 2.0).unwrap(), 2.0).unwrap() - 0.05).abs() < 1e-12);
        assert!(scale_to_height(&a, &[[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], 2.0).is_err(), "flat");
        assert!(scale_to_height(&a, &b, -1.0).is_err());
        assert!(height_of(&[]).is_err());
    }

    #[test]
    fn procrustes_removes_rotation_scale_and_translation() {
        let a = pts();
        let r = Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let b: Vec<[f64; 3]> =
            a.iter().map(|p| (r * Vector3::from(*p) * 2.5 + Vector3::new(1.0, -2.0, 0.5)).into()).collect();
        assert!(mpjpe(&a, &b, 0).unwrap() > 0.5);
        let e = pa_mpjpe(&a, &b).unwrap();
        assert!(e < 1e-9, "PA-MPJPE after a similarity transform: {e}");
        // A reflection cannot be undone by a rotation.
        let m: Vec<[f64; 3]> = a.iter().map(|p| [-p[0], p[1], p[2]]).collect();
        assert!(pa_mpjpe(&a, &m).unwrap() > 0.05);
        assert!(pa_mpjpe(&a, &[[1.0, 1.0, 1.0]; 5]).is_err());
        let s = scale_to_reference(&a, &b, &[(0, 1), (0, 2)], 0).unwrap();
        let len = |p: &[[f64; 3]]| {
            (Vector3::from(p[1]) - Vector3::from(p[0])).norm() + (Vector3::from(p[2]) - Vector3::from(p[0])).norm()
        };
        assert!((len(&s) - len(&a)).abs() < 1e-9);
    }

    #[test]
    fn pck_counts_joints_within_the_box_fraction() {
        // Box 100 x 50: normaliser 100; threshold at 0.1 is 10 px.
        let r = vec![[0.0, 0.0], [100.0, 50.0], [50.0, 25.0], [10.0, 10.0]];
        let e = vec![[5.0, 0.0], [100.0, 62.0], [50.0, 25.0], [30.0, 10.0]];
        assert_eq!(pck_normaliser(&r), 100.0);
        assert_eq!(pck(&r, &e, 0.1).unwrap(), 0.5);
        assert_eq!(pck(&r, &e, 0.2).unwrap(), 1.0);
        assert!(pck(&[[1.0, 1.0]; 3], &[[1.0, 1.0]; 3], 0.1).is_err());
    }
}
