//! Separable Sobel passes with OpenCV's kernels (`cv::getDerivKernels`, unnormalised) and
//! `BORDER_REPLICATE`, written so the inner loops auto-vectorise.

/// Smoothing kernel of a Sobel aperture (binomial).
pub(crate) fn smooth_kernel(aperture: usize) -> &'static [i32] {
    match aperture {
        3 => &[1, 2, 1],
        5 => &[1, 4, 6, 4, 1],
        _ => &[1, 6, 15, 20, 15, 6, 1],
    }
}

/// First-derivative kernel of a Sobel aperture, in correlation order (`dst(x) = Σ k[i] src(x+i-r)`).
pub(crate) fn deriv_kernel(aperture: usize) -> &'static [i32] {
    match aperture {
        3 => &[-1, 0, 1],
        5 => &[-1, -2, 0, 2, 1],
        _ => &[-1, -4, -5, 0, 5, 4, 1],
    }
}

/// Horizontal pass of one row with replicated borders: `smooth[x] = Σ ks[i] src[clamp(x+i-r)]`
/// and `deriv[x] = Σ kd[i] src[clamp(x+i-r)]`. All slices have the row's length.
pub(crate) fn horizontal_pass(src: &[u8], ks: &[i32], kd: &[i32], smooth: &mut [i32], deriv: &mut [i32]) {
    let w = src.len();
    let k = ks.len();
    let r = k / 2;
    let at = |x: isize| src[x.clamp(0, w as isize - 1) as usize] as i32;
    let clamped = |x: usize, smooth: &mut [i32], deriv: &mut [i32]| {
        let (mut s, mut d) = (0, 0);
        for i in 0..k {
            let p = at(x as isize + i as isize - r as isize);
            s += ks[i] * p;
            d += kd[i] * p;
        }
        smooth[x] = s;
        deriv[x] = d;
    };
    if w <= 2 * r {
        for x in 0..w {
            clamped(x, smooth, deriv);
        }
        return;
    }
    let n = w - 2 * r;
    let (s_in, d_in) = (&mut smooth[r..r + n], &mut deriv[r..r + n]);
    s_in.fill(0);
    d_in.fill(0);
    for i in 0..k {
        let (cs, cd) = (ks[i], kd[i]);
        let taps = &src[i..i + n];
        if cs != 0 {
            for (o, &p) in s_in.iter_mut().zip(taps) {
                *o += cs * p as i32;
            }
        }
        if cd != 0 {
            for (o, &p) in d_in.iter_mut().zip(taps) {
                *o += cd * p as i32;
            }
        }
    }
    for x in (0..r).chain(w - r..w) {
        clamped(x, smooth, deriv);
    }
}

/// Vertical pass: `out[x] = Σ kernel[i] rows[i][x]` over `kernel.len()` rows.
pub(crate) fn vertical_pass(rows: &[&[i32]], kernel: &[i32], out: &mut [i32]) {
    out.fill(0);
    for (row, &c) in rows.iter().zip(kernel) {
        if c == 0 {
            continue;
        }
        for (o, &v) in out.iter_mut().zip(row.iter()) {
            *o += c * v;
        }
    }
}

/// `round_half_even(v / 16)`: OpenCV's aperture-7 Canny scales the Sobel response by 1/16 and
/// rounds with `cvRound`; every intermediate is exact in `float`, so this integer form is exact.
#[inline]
pub(crate) fn div16_round_even(v: i32) -> i32 {
    let q = v >> 4;
    let rem = v & 15;
    q + ((rem > 8) | ((rem == 8) & (q & 1 == 1))) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn div16_rounds_half_to_even() {
        for (v, want) in [(8, 0), (24, 2), (-8, 0), (-24, -2), (9, 1), (-9, -1), (7, 0), (40, 2), (-40, -2), (41, 3)] {
            assert_eq!(div16_round_even(v), want, "v = {v}");
        }
    }

    #[test]
    fn horizontal_pass_replicates_borders() {
        let src = [10u8, 20, 40];
        let (mut s, mut d) = ([0; 3], [0; 3]);
        horizontal_pass(&src, smooth_kernel(3), deriv_kernel(3), &mut s, &mut d);
        assert_eq!(s, [50, 90, 140]);
        assert_eq!(d, [10, 30, 20]);
    }
}
