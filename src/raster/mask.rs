//! The mask-only triangle loop of the rasteriser, tuned for meshes whose triangles mostly cover
//! a handful of pixel centres (a 27k-triangle body at 256²). Same sampling, snapping and
//! top-left fill rule as [`super::setup`] / [`super::scan`] (so the masks are identical), with:
//! the bounding-box reject before any multiplication, optional back-face culling, a
//! division-free branchless path for triangles at most [`NARROW`] pixels wide (every candidate
//! centre is tested with the sign of the OR of the three edge values), and exact per-row spans
//! (integer divisions) for wider triangles.

use super::{edge_functions, row_span, HALF, SUB, SUB_BITS};

/// Triangles whose bounding box holds at most this many pixel columns are tested centre by
/// centre instead of solving each row's span.
const NARROW: i64 = 8;

/// Which triangles a mask draws.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Facing {
    /// Both windings (the exact silhouette of any triangle soup). Default.
    #[default]
    Both,
    /// Only triangles facing the viewer: counter-clockwise seen from the camera's +z (the
    /// body's faces are counter-clockwise seen from outside). For a closed mesh this draws the
    /// same silhouette (up to pixel centres exactly on an outline edge) from about half the
    /// triangles; an open mesh may show holes where only inner faces are visible.
    Front,
}

/// Triangles whose bounding box spans fewer than this many pixel centres in x and in y are
/// drawn by testing a fixed 2×2 or BLOCK×BLOCK block of centres without branches.
const BLOCK: i64 = 4;

/// Sets to 255 the pixels of an N×N block at `base` (row pitch `w`) whose centres
/// lie inside the triangle with biased edge values `e` at the block's first centre and steps
/// `dx`, `dy` (all three non-negative <=> their OR is non-negative).
#[inline(always)]
fn cover_block<const N: usize>(mask: &mut [u8], base: usize, w: usize, e: [i64; 3], dx: [i64; 3], dy: [i64; 3]) {
    let mut row = e;
    for r in 0..N {
        let line: &mut [u8; N] = (&mut mask[base + r * w..base + r * w + N]).try_into().expect("N bytes");
        for (k, px) in line.iter_mut().enumerate() {
            let k = k as i64;
            let v = (row[0] + k * dx[0]) | (row[1] + k * dx[1]) | (row[2] + k * dx[2]);
            *px |= ((v >= 0) as u8).wrapping_neg();
        }
        row = [row[0] + dy[0], row[1] + dy[1], row[2] + dy[2]];
    }
}

/// First pixel whose centre is >= `v` (fixed point); arithmetic shifts floor-divide by SUB.
#[inline(always)]
fn lo(v: i64) -> i64 {
    (v - HALF + SUB - 1) >> SUB_BITS
}

/// Last pixel whose centre is <= `v` (fixed point).
#[inline(always)]
fn hi(v: i64) -> i64 {
    (v - HALF) >> SUB_BITS
}

/// Draws (255) every pixel centre of a row-major `w`×`h` `mask` covered by a triangle of
/// `tris` (indices into `fixed`, vertices snapped to 1/SUB px, already range-checked). Returns
/// how many triangles were scanned (bounding box met a pixel centre, non-degenerate, and
/// facing as asked).
pub(super) fn draw_mask(
    fixed: &[[i32; 2]],
    tris: &[[u32; 3]],
    w: usize,
    h: usize,
    facing: Facing,
    mask: &mut [u8],
) -> usize {
    let (last_i, last_j) = (w as i64 - 1, h as i64 - 1);
    let mut scanned = 0;
    for t in tris {
        let (a, b, c) = (fixed[t[0] as usize], fixed[t[1] as usize], fixed[t[2] as usize]);
        let (ax, bx, cx) = (a[0] as i64, b[0] as i64, c[0] as i64);
        let i0 = lo(ax.min(bx).min(cx)).max(0);
        let i1 = hi(ax.max(bx).max(cx)).min(last_i);
        let (ay, by, cy) = (a[1] as i64, b[1] as i64, c[1] as i64);
        let j0 = lo(ay.min(by).min(cy)).max(0);
        let j1 = hi(ay.max(by).max(cy)).min(last_j);
        let area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
        // In the y-down image a viewer-facing (counter-clockwise) triangle has negative area.
        if facing == Facing::Front && area > 0 {
            continue;
        }
        let (span_i, span_j) = (i1 - i0, j1 - j0);
        if span_i < BLOCK && span_j < BLOCK && i0 + BLOCK - 1 <= last_i && j0 + BLOCK - 1 <= last_j {
            // At most BLOCK x BLOCK candidate centres (maybe none): test a fixed block of
            // centres from (i0, j0) without branching (centres outside the bounding box test
            // as outside; a degenerate triangle covers nothing since one of its edges is
            // always biased).
            let (b, c) = if area < 0 { ([cx, cy], [bx, by]) } else { ([bx, by], [cx, cy]) };
            let (e, dx, dy) = edge_functions([[ax, ay], b, c], i0, j0);
            let base = j0 as usize * w + i0 as usize;
            if span_i < 2 && span_j < 2 {
                cover_block::<2>(mask, base, w, e, dx, dy);
            } else {
                cover_block::<{ BLOCK as usize }>(mask, base, w, e, dx, dy);
            }
            scanned += (i0 <= i1 && j0 <= j1 && area != 0) as usize;
            continue;
        }
        if i0 > i1 || j0 > j1 {
            continue;
        }
        if area == 0 {
            continue;
        }
        scanned += 1;
        let (b, c) = if area < 0 { ([cx, cy], [bx, by]) } else { ([bx, by], [cx, cy]) };
        let (mut e, dx, dy) = edge_functions([[ax, ay], b, c], i0, j0);
        let n = i1 - i0 + 1;
        let mut base = j0 as usize * w + i0 as usize;
        if n <= NARROW && i0 + NARROW <= last_i + 1 {
            // Always test NARROW centres a row (fixed trip count, no branches; centres right
            // of the box test as outside and leave the mask unchanged).
            for _ in j0..=j1 {
                let row: &mut [u8; NARROW as usize] =
                    (&mut mask[base..base + NARROW as usize]).try_into().expect("NARROW bytes");
                for (k, px) in row.iter_mut().enumerate() {
                    let k = k as i64;
                    let v = (e[0] + k * dx[0]) | (e[1] + k * dx[1]) | (e[2] + k * dx[2]);
                    *px |= ((v >= 0) as u8).wrapping_neg();
                }
                e = [e[0] + dy[0], e[1] + dy[1], e[2] + dy[2]];
                base += w;
            }
        } else if n <= NARROW {
            for _ in j0..=j1 {
                let mut v = e;
                for px in &mut mask[base..base + n as usize] {
                    // All three non-negative <=> their OR is non-negative.
                    *px |= (((v[0] | v[1] | v[2]) >= 0) as u8).wrapping_neg();
                    v = [v[0] + dx[0], v[1] + dx[1], v[2] + dx[2]];
                }
                e = [e[0] + dy[0], e[1] + dy[1], e[2] + dy[2]];
                base += w;
            }
        } else {
            for _ in j0..=j1 {
                let (l, r) = row_span(e, dx, n);
                if l <= r {
                    mask[base + l as usize..=base + r as usize].fill(255);
                }
                e = [e[0] + dy[0], e[1] + dy[1], e[2] + dy[2]];
                base += w;
            }
        }
    }
    scanned
}

#[cfg(test)]
mod tests {
    use super::super::{scan, setup, Rasterizer};
    use super::*;
    use crate::camera::WeakPerspective;
    use nalgebra::{Matrix3, Rotation3};
    use rand::{Rng, SeedableRng};

    /// The mask path draws exactly the pixels of the general set-up/scan path, on random
    /// triangles of every size, many with vertices exactly on pixel centres or edges.
    #[test]
    fn mask_path_matches_the_general_scan_exactly() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (w, h) = (37usize, 23usize);
        let mut total = 0;
        for case in 0..3000 {
            let size = [1.5, 3.0, 8.0, 40.0][case % 4];
            let snap = case % 3 == 0;
            let centre = [rng.random_range(-5.0..w as f64 + 5.0), rng.random_range(-5.0..h as f64 + 5.0)];
            let p: [[i32; 2]; 3] = std::array::from_fn(|_| {
                let mut q = [centre[0] + rng.random_range(-size..size), centre[1] + rng.random_range(-size..size)];
                if snap {
                    // Halves land vertices on pixel centres and edges on centre rows/columns.
                    q = [(q[0] * 2.0).round() / 2.0, (q[1] * 2.0).round() / 2.0];
                }
                [(q[0] * SUB as f64).round() as i32, (q[1] * SUB as f64).round() as i32]
            });
            let mut fast = vec![0u8; w * h];
            let scanned = draw_mask(&p, &[[0, 1, 2]], w, h, Facing::Both, &mut fast);
            let mut slow = vec![0u8; w * h];
            let p64 = p.map(|v| [v[0] as i64, v[1] as i64]);
            let set = setup(p64, [0.0; 3], w, h, false);
            assert_eq!(scanned, set.is_some() as usize, "case {case}");
            if let Some(s) = set {
                scan(&s, w, |idx, _, _, _| slow[idx] = 255);
            }
            assert_eq!(fast, slow, "case {case}: {p:?}");
            total += fast.iter().filter(|&&m| m != 0).count();
        }
        assert!(total > 10_000, "the cases cover pixels: {total}");
    }

    /// On a closed mesh (a box seen obliquely) the viewer-facing triangles draw the same
    /// silhouette as both windings, from half the triangles: those whose normal faces the camera.
    #[test]
    fn front_faces_of_a_closed_mesh_draw_the_same_silhouette() {
        // Unit cube, faces counter-clockwise seen from outside.
        let v: Vec<[f32; 3]> =
            (0..8).map(|i| [(i & 1) as f32 - 0.5, ((i >> 1) & 1) as f32 - 0.5, ((i >> 2) & 1) as f32 - 0.5]).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let tris: Vec<[u32; 3]> = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
        let r: Matrix3<f64> = *Rotation3::from_euler_angles(0.4, 0.7, 0.1).matrix();
        let cam = WeakPerspective { sx: 21.3, sy: 19.7, r, t: [32.1, 31.7] };
        let mut ras = Rasterizer::new();
        let both = ras.rasterize_mask(&v, &tris, &cam, 64, 64, Facing::Both).unwrap();
        let both_mask = ras.mask().to_vec();
        let front = ras.rasterize_mask(&v, &tris, &cam, 64, 64, Facing::Front).unwrap();
        assert_eq!(ras.mask(), &both_mask[..]);
        assert!(both.covered > 400, "{both:?}");
        assert_eq!(front.covered, both.covered);
        assert!(front.triangles_scanned == 6 && both.triangles_scanned == 12, "{front:?} {both:?}");
        // Exactly the triangles whose normal points toward the viewer (camera +z) are drawn.
        for t in &tris {
            let p = t.map(|i| nalgebra::Vector3::from(v[i as usize].map(|c| c as f64)));
            let facing_viewer = (r * (p[1] - p[0]).cross(&(p[2] - p[0]))).z > 0.0;
            let covers = ras.rasterize_mask(&v, &[*t], &cam, 64, 64, Facing::Front).unwrap().triangles_scanned == 1;
            assert_eq!(covers, facing_viewer, "{t:?}");
        }
        assert_eq!(ras.rasterize_mask(&v, &[[0, 2, 3]], &cam, 64, 64, Facing::Front).unwrap().covered, 0);
        assert_eq!(ras.covered_bounds(), None);
        // The depth path draws the same mask, and the covered box holds every covered pixel.
        ras.rasterize(&v, &tris, &cam, 64, 64, true).unwrap();
        assert_eq!(ras.mask(), &both_mask[..]);
        let [x0, y0, x1, y1] = ras.covered_bounds().unwrap();
        for (i, &m) in ras.mask().iter().enumerate() {
            if m != 0 {
                assert!((x0..=x1).contains(&(i % 64)) && (y0..=y1).contains(&(i / 64)), "pixel {i} outside the box");
            }
        }
        assert!(x1 - x0 < 40 && y1 - y0 < 40);
    }
}
