//! Silhouette and depth rasteriser for posed triangle meshes under the weak-perspective camera
//! ([`WeakPerspective::project`]). It runs thousands of times per shape fit, so it keeps its
//! buffers in a reusable [`Rasterizer`] and allocates nothing per pixel or per triangle.
//!
//! Sampling: pixel (i, j) is covered when its centre (i + 0.5, j + 0.5) lies inside a projected
//! triangle. Vertices are snapped to 1/16384 pixel and the edge functions are evaluated exactly in
//! 64-bit integers over each triangle's clipped bounding box (each row's covered span is solved
//! exactly from the three edge functions, then filled), with the top-left fill rule
//! (a centre exactly on an edge belongs to the triangle whose edge is a top or a left edge in
//! the y-down image), so triangles sharing an edge never both cover, nor both miss, a centre on
//! it. Both windings are drawn (a silhouette has no back faces) unless
//! [`Rasterizer::rasterize_mask`] is asked for viewer-facing triangles only ([`Facing`]). The
//! mask-only path (`mask.rs`) rejects triangles whose bounding box holds no pixel centre before
//! any multiplication and tests narrow triangles centre by centre without divisions; it draws
//! exactly the pixels the general path does. Depth is the camera-frame
//! `(R X)_z` in metres (larger = nearer the viewer), interpolated linearly, nearest kept.
//!
//! A mesh whose projected bounding box misses the image entirely is reported as
//! [`Error::MeshOutsideImage`] (the buffers are cleared); a mesh that overlaps the image but
//! happens to cover no pixel centre gives an empty mask and `covered == 0`.

use crate::camera::WeakPerspective;
use crate::error::{Error, Result};

mod mask;
pub use mask::Facing;

/// Largest raster width or height, pixels.
pub const MAX_RASTER_SIDE: usize = 4096;
/// Sub-pixel precision: vertices are snapped to 1/`SUB` pixel (1/16384).
pub(crate) const SUB: i64 = 1 << SUB_BITS;
const SUB_BITS: u32 = 14;
const HALF: i64 = SUB / 2;
/// Projected vertices must lie within ±this many pixels of the image origin (8× the largest
/// raster side; keeps the integer edge functions exact in i64: |e| < 2^61).
pub const GUARD_BAND: f64 = 32_768.0;

/// What one rasterisation drew.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Pixels whose centre is covered.
    pub covered: usize,
    /// Triangles whose bounding box met the image and which were scanned.
    pub triangles_scanned: usize,
}

/// A reusable rasteriser: owns the mask, depth and per-vertex scratch buffers. Not shared
/// between threads while in use (each thread keeps its own); `Send`.
#[derive(Clone, Debug, Default)]
pub struct Rasterizer {
    width: usize,
    height: usize,
    mask: Vec<u8>,
    depth: Vec<f32>,
    /// Snapped projected vertices, 1/SUB px (|coordinate| <= 2^29 by the guard band).
    fixed: Vec<[i32; 2]>,
    z: Vec<f32>,
    bounds: Option<[usize; 4]>,
}

/// A projected, snapped triangle ready for scanning.
pub(crate) struct Setup {
    /// Pixel bounding box (inclusive), clipped to the image.
    pub i0: usize,
    pub i1: usize,
    pub j0: usize,
    pub j1: usize,
    /// Biased edge values at pixel (i0, j0) and their steps per pixel in x and y.
    pub e: [i64; 3],
    pub dx: [i64; 3],
    pub dy: [i64; 3],
    /// Depth plane: z(i, j) = z0 + zx * (i - i0) + zy * (j - j0), at pixel centres.
    pub z0: f32,
    pub zx: f32,
    pub zy: f32,
}

/// The biased edge functions of a positively oriented snapped triangle at the centre of pixel
/// (i0, j0), and their steps per pixel in x and y: edge k runs from vertex k to vertex k + 1,
/// inside is `>= 0`, and a centre exactly on an edge counts only for top and left edges (the
/// others are biased by −1).
#[inline(always)]
fn edge_functions(verts: [[i64; 2]; 3], i0: i64, j0: i64) -> ([i64; 3], [i64; 3], [i64; 3]) {
    let (px, py) = (i0 * SUB + HALF, j0 * SUB + HALF);
    let mut e = [0i64; 3];
    let mut dx = [0i64; 3];
    let mut dy = [0i64; 3];
    for k in 0..3 {
        let (s, t) = (verts[k], verts[(k + 1) % 3]);
        let (ex, ey) = (t[0] - s[0], t[1] - s[1]);
        let top_left = ey < 0 || (ey == 0 && ex > 0);
        e[k] = ex * (py - s[1]) - ey * (px - s[0]) - (!top_left) as i64;
        dx[k] = -ey * SUB;
        dy[k] = ex * SUB;
    }
    (e, dx, dy)
}

/// Sets up triangle (a, b, c) in fixed point for a `w`×`h` image; `None` when it is degenerate
/// or its bounding box contains no pixel centre of the image. The depth plane is computed only
/// when `with_depth` (otherwise it is 0).
pub(crate) fn setup(p: [[i64; 2]; 3], z: [f32; 3], w: usize, h: usize, with_depth: bool) -> Option<Setup> {
    let [a, mut b, mut c] = p;
    let [za, mut zb, mut zc] = z;
    let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if area == 0 {
        return None;
    }
    if area < 0 {
        std::mem::swap(&mut b, &mut c);
        std::mem::swap(&mut zb, &mut zc);
    }
    let area = area.abs();
    // Arithmetic shifts are floor divisions by SUB (a power of two).
    let lo = |v: i64| (v - HALF + SUB - 1) >> SUB_BITS; // first pixel whose centre >= v
    let hi = |v: i64| (v - HALF) >> SUB_BITS; // last pixel whose centre <= v
    let i0 = lo(a[0].min(b[0]).min(c[0])).max(0);
    let j0 = lo(a[1].min(b[1]).min(c[1])).max(0);
    let i1 = hi(a[0].max(b[0]).max(c[0])).min(w as i64 - 1);
    let j1 = hi(a[1].max(b[1]).max(c[1])).min(h as i64 - 1);
    if i0 > i1 || j0 > j1 {
        return None;
    }
    let (px, py) = (i0 * SUB + HALF, j0 * SUB + HALF);
    let verts = [a, b, c];
    let (e, dx, dy) = edge_functions(verts, i0, j0);
    if !with_depth {
        return Some(Setup {
            i0: i0 as usize,
            i1: i1 as usize,
            j0: j0 as usize,
            j1: j1 as usize,
            e,
            dx,
            dy,
            z0: 0.0,
            zx: 0.0,
            zy: 0.0,
        });
    }
    // Barycentric weight of vertex k is the edge opposite it: a <- e[1] (b->c), b <- e[2], c <- e[0].
    let inv = 1.0 / area as f64;
    let unbias = |k: usize| {
        let (s, t) = (verts[k], verts[(k + 1) % 3]);
        let (ex, ey) = (t[0] - s[0], t[1] - s[1]);
        (ex * (py - s[1]) - ey * (px - s[0])) as f64
    };
    let (wa, wb, wc) = (unbias(1) * inv, unbias(2) * inv, unbias(0) * inv);
    let (za, zb, zc) = (za as f64, zb as f64, zc as f64);
    let z0 = wa * za + wb * zb + wc * zc;
    let zx = (dx[1] as f64 * za + dx[2] as f64 * zb + dx[0] as f64 * zc) * inv;
    let zy = (dy[1] as f64 * za + dy[2] as f64 * zb + dy[0] as f64 * zc) * inv;
    Some(Setup {
        i0: i0 as usize,
        i1: i1 as usize,
        j0: j0 as usize,
        j1: j1 as usize,
        e,
        dx,
        dy,
        z0: z0 as f32,
        zx: zx as f32,
        zy: zy as f32,
    })
}

/// The covered pixels of one row: offsets `k` from `i0` (0 <= k < n) where every biased edge
/// value `e[m] + k * dx[m]` is >= 0, as an inclusive range (empty when `lo > hi`). Exact.
#[inline]
fn row_span(e: [i64; 3], dx: [i64; 3], n: i64) -> (i64, i64) {
    if n <= 4 {
        // Narrow rows: testing each pixel is cheaper than dividing.
        let inside = |k: i64| (0..3).all(|m| e[m] + k * dx[m] >= 0);
        let Some(lo) = (0..n).find(|&k| inside(k)) else { return (1, 0) };
        let hi = (lo..n).rev().find(|&k| inside(k)).unwrap_or(lo);
        return (lo, hi);
    }
    let (mut lo, mut hi) = (0, n - 1);
    for m in 0..3 {
        if dx[m] > 0 {
            if e[m] < 0 {
                lo = lo.max((-e[m] + dx[m] - 1) / dx[m]);
            }
        } else if e[m] < 0 {
            return (1, 0);
        } else if dx[m] < 0 {
            hi = hi.min(e[m] / -dx[m]);
        }
    }
    (lo, hi)
}

/// Calls `visit(pixel_index, x, y, depth)` for every covered pixel centre of a set-up triangle
/// in a row-major `w`-wide image.
#[inline]
pub(crate) fn scan<F: FnMut(usize, usize, usize, f32)>(s: &Setup, w: usize, mut visit: F) {
    let mut row = s.e;
    let n = (s.i1 - s.i0 + 1) as i64;
    for j in s.j0..=s.j1 {
        let (lo, hi) = row_span(row, s.dx, n);
        let zr = s.z0 + s.zy * (j - s.j0) as f32;
        for k in lo..=hi {
            let i = s.i0 + k as usize;
            visit(j * w + i, i, j, zr + s.zx * k as f32);
        }
        for k in 0..3 {
            row[k] += s.dy[k];
        }
    }
}

/// Rounds to the nearest integer (ties away from zero) without a libm call or a branch.
#[inline(always)]
fn round_i64(x: f64) -> i64 {
    let t = x as i64; // truncates toward zero
    let frac = x - t as f64;
    t + (frac >= 0.5) as i64 - (frac <= -0.5) as i64
}

/// Checks a raster size: 1..=[`MAX_RASTER_SIDE`] a side.
pub fn check_size(width: usize, height: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::EmptyImage { width, height });
    }
    if width > MAX_RASTER_SIDE || height > MAX_RASTER_SIDE {
        return Err(Error::OutOfRange {
            name: "raster size",
            detail: format!("{width}x{height} exceeds {MAX_RASTER_SIDE} px a side"),
        });
    }
    Ok(())
}

impl Rasterizer {
    /// An empty rasteriser; buffers grow on first use and are then reused.
    pub fn new() -> Self {
        Self::default()
    }

    /// Width of the last raster, pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height of the last raster, pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Row-major mask of the last raster (`width` bytes a row): 255 covered, 0 not.
    pub fn mask(&self) -> &[u8] {
        &self.mask
    }

    /// Row-major depth of the last raster drawn with depth: camera-frame z in metres (larger
    /// = nearer), `f32::NEG_INFINITY` where nothing is covered. Empty when depth was off.
    pub fn depth(&self) -> &[f32] {
        &self.depth
    }

    /// A pixel box `[x0, y0, x1, y1]` (inclusive) of the last raster that contains every
    /// covered pixel (the projected vertices' bounding box clipped to the image), or `None`
    /// when the last call failed or covered nothing. Lets callers scan only that box.
    pub fn covered_bounds(&self) -> Option<[usize; 4]> {
        self.bounds
    }

    /// Projects `vertices` (metres, model frame) with `cam` into the snapped scratch buffers
    /// (and camera-frame depths when `with_depth`); returns the snapped bounding box
    /// `[min x, min y, max x, max y]` in 1/SUB px.
    fn project(&mut self, vertices: &[[f32; 3]], cam: &WeakPerspective, with_depth: bool) -> Result<[i64; 4]> {
        let (r, k) = (cam.r, SUB as f64);
        // Pixel coordinates times SUB: u = a . v + ta, w = b . v + tb.
        let a = [cam.sx * k * r[(0, 0)], cam.sx * k * r[(0, 1)], cam.sx * k * r[(0, 2)]];
        let b = [-cam.sy * k * r[(1, 0)], -cam.sy * k * r[(1, 1)], -cam.sy * k * r[(1, 2)]];
        let (ta, tb) = (cam.t[0] * k, cam.t[1] * k);
        let guard = GUARD_BAND * k;
        let mut bb = [i64::MAX, i64::MAX, i64::MIN, i64::MIN];
        self.fixed.clear();
        self.z.clear();
        for (i, v) in vertices.iter().enumerate() {
            let (x, y, z) = (v[0] as f64, v[1] as f64, v[2] as f64);
            let u = a[0] * x + a[1] * y + a[2] * z + ta;
            let w = b[0] * x + b[1] * y + b[2] * z + tb;
            // Also false for NaN: a non-finite vertex always gives a non-finite u or w.
            if !(u.abs() <= guard && w.abs() <= guard) {
                if let Some(&value) = v.iter().find(|c| !c.is_finite()) {
                    return Err(Error::NonFinite { name: "mesh vertex", value: value as f64 });
                }
                return Err(Error::OutOfRange {
                    name: "projected vertex",
                    detail: format!(
                        "vertex {i} projects to ({}, {}) px, beyond the ±{GUARD_BAND} px guard band",
                        u / k,
                        w / k
                    ),
                });
            }
            let (fu, fw) = (round_i64(u), round_i64(w));
            bb = [bb[0].min(fu), bb[1].min(fw), bb[2].max(fu), bb[3].max(fw)];
            // |fu|, |fw| <= 2^29 by the guard band.
            self.fixed.push([fu as i32, fw as i32]);
            if with_depth {
                self.z.push((r[(2, 0)] * x + r[(2, 1)] * y + r[(2, 2)] * z) as f32);
            }
        }
        Ok(bb)
    }

    /// Rasterises triangles `tris` (indices into `vertices`, metres, model frame) seen by `cam`
    /// into a `width`×`height` mask, and into the depth buffer when `with_depth`. Both windings
    /// are drawn. Errors: bad size, invalid camera, no triangles, an index out of range,
    /// non-finite vertices, vertices beyond the guard band, and [`Error::MeshOutsideImage`].
    #[rustfmt::skip]
    pub fn rasterize(&mut self, vertices: &[[f32; 3]], tris: &[[u32; 3]], cam: &WeakPerspective, width: usize, height: usize, with_depth: bool) -> Result<RasterStats> {
        self.draw(vertices, tris, cam, width, height, with_depth, Facing::Both)
    }

    /// Rasterises the mask only (no depth), drawing the triangles selected by `facing`
    /// ([`Facing::Front`] halves the work on a closed mesh). Same errors as
    /// [`Rasterizer::rasterize`]; with [`Facing::Both`] the mask is identical to it.
    #[rustfmt::skip]
    pub fn rasterize_mask(&mut self, vertices: &[[f32; 3]], tris: &[[u32; 3]], cam: &WeakPerspective, width: usize, height: usize, facing: Facing) -> Result<RasterStats> {
        self.draw(vertices, tris, cam, width, height, false, facing)
    }

    #[allow(clippy::too_many_arguments)]
    #[rustfmt::skip]
    fn draw(&mut self, vertices: &[[f32; 3]], tris: &[[u32; 3]], cam: &WeakPerspective, width: usize, height: usize, with_depth: bool, facing: Facing) -> Result<RasterStats> {
        check_size(width, height)?;
        cam.validate()?;
        self.width = width;
        self.height = height;
        self.bounds = None;
        self.mask.clear();
        self.mask.resize(width * height, 0);
        self.depth.clear();
        if with_depth {
            self.depth.resize(width * height, f32::NEG_INFINITY);
        }
        if tris.is_empty() {
            return Err(Error::OutOfRange { name: "triangles", detail: "no triangles to rasterise".into() });
        }
        let n = vertices.len();
        if let Some(t) = tris.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(Error::OutOfRange { name: "triangle index", detail: format!("triangle {t} indexes a vertex >= {n}") });
        }
        let bb = self.project(vertices, cam, with_depth)?;
        let (wf, hf) = (width as i64 * SUB, height as i64 * SUB);
        if bb[2] < 0 || bb[3] < 0 || bb[0] > wf || bb[1] > hf {
            return Err(Error::MeshOutsideImage { width, height });
        }
        let mut stats = RasterStats::default();
        let (fixed, z, mask, depth) = (&self.fixed, &self.z, &mut self.mask, &mut self.depth);
        if with_depth {
            let p64 = |i: u32| {
                let f = fixed[i as usize];
                [f[0] as i64, f[1] as i64]
            };
            for t in tris {
                let zz = [z[t[0] as usize], z[t[1] as usize], z[t[2] as usize]];
                let Some(s) = setup([p64(t[0]), p64(t[1]), p64(t[2])], zz, width, height, true) else { continue };
                stats.triangles_scanned += 1;
                scan(&s, width, |idx, _, _, d| {
                    mask[idx] = 255;
                    if d > depth[idx] {
                        depth[idx] = d;
                    }
                });
            }
        } else {
            stats.triangles_scanned = mask::draw_mask(fixed, tris, width, height, facing, mask);
        }
        // Every covered centre lies in the clipped bounding box of the projected vertices.
        let x0 = ((bb[0] - HALF + SUB - 1) >> SUB_BITS).max(0) as usize;
        let y0 = ((bb[1] - HALF + SUB - 1) >> SUB_BITS).max(0) as usize;
        let x1 = ((bb[2] - HALF) >> SUB_BITS).min(width as i64 - 1);
        let y1 = ((bb[3] - HALF) >> SUB_BITS).min(height as i64 - 1);
        if x1 >= x0 as i64 && y1 >= y0 as i64 {
            let (x1, y1) = (x1 as usize, y1 as usize);
            stats.covered = (y0..=y1)
                .map(|y| mask[y * width + x0..=y * width + x1].iter().map(|&m| (m != 0) as usize).sum::<usize>())
                .sum();
            if stats.covered > 0 {
                self.bounds = Some([x0, y0, x1, y1]);
            }
        }
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    fn cam(s: f64, tx: f64, ty: f64) -> WeakPerspective {
        WeakPerspective { sx: s, sy: s, r: Matrix3::identity(), t: [tx, ty] }
    }

    #[test]
    fn square_covers_exactly_its_pixel_centres_once() {
        // Unit square [1, 5) x [1, 5) px as two triangles; identity camera at 1 px per metre, y flipped.
        let v = [[1.0, -1.0, 0.0], [5.0, -1.0, 0.0], [5.0, -5.0, 0.0], [1.0, -5.0, 0.0]];
        let mut r = Rasterizer::new();
        for tris in [[[0, 1, 2], [0, 2, 3]], [[0, 2, 1], [3, 2, 0]]] {
            let stats = r.rasterize(&v, &tris, &cam(1.0, 0.0, 0.0), 8, 8, true).unwrap();
            assert_eq!(stats.covered, 16);
            for j in 0..8 {
                for i in 0..8 {
                    let inside = (1..5).contains(&i) && (1..5).contains(&j);
                    assert_eq!(r.mask()[j * 8 + i] != 0, inside, "pixel {i},{j}");
                }
            }
        }
        // Edges through pixel centres: the square [0.5, 2.5] covers centres 0.5, 1.5 on the
        // top/left edges but not 2.5 on the bottom/right ones.
        let v = [[0.5, -0.5, 0.0], [2.5, -0.5, 0.0], [2.5, -2.5, 0.0], [0.5, -2.5, 0.0]];
        let s = r.rasterize(&v, &[[0, 1, 2], [0, 2, 3]], &cam(1.0, 0.0, 0.0), 4, 4, false).unwrap();
        assert_eq!(s.covered, 4);
        assert_eq!(&r.mask()[..3], &[255, 255, 0]);
    }

    #[test]
    fn shared_edges_cover_each_centre_exactly_once() {
        // A fan of triangles around a centre, with many edges through pixel centres.
        let mut v = vec![[8.5f32, -8.5, 0.0]];
        for k in 0..16 {
            let a = k as f32 / 16.0 * std::f32::consts::TAU;
            v.push([8.5 + 6.0 * a.cos(), -8.5 - 6.0 * a.sin(), 0.0]);
        }
        let tris: Vec<[u32; 3]> = (0..16).map(|k| [0, 1 + k, 1 + (k + 1) % 16]).collect();
        let mut counts = vec![0u32; 17 * 17];
        let mut r = Rasterizer::new();
        for t in &tris {
            r.rasterize(&v, &[*t], &cam(1.0, 0.0, 0.0), 17, 17, false).unwrap();
            for (c, &m) in counts.iter_mut().zip(r.mask()) {
                *c += (m != 0) as u32;
            }
        }
        assert!(counts.iter().all(|&c| c <= 1), "a centre covered twice");
        assert_eq!(counts[8 * 17 + 8], 1, "the shared vertex centre is covered once");
    }

    #[test]
    fn depth_keeps_the_nearest_surface_and_errors_are_specific() {
        let v =
            [[-1.0, 1.0, 0.2], [1.0, 1.0, 0.2], [0.0, -1.0, 0.2], [-1.0, 1.0, 0.5], [1.0, 1.0, 0.5], [0.0, -1.0, 0.5]];
        let c = cam(10.0, 16.0, 16.0);
        let mut r = Rasterizer::new();
        r.rasterize(&v, &[[0, 1, 2], [3, 4, 5]], &c, 32, 32, true).unwrap();
        let d = r.depth()[16 * 32 + 16];
        assert!((d - 0.5).abs() < 1e-6, "{d}");
        let far = cam(10.0, 500.0, 16.0);
        assert!(matches!(r.rasterize(&v, &[[0, 1, 2]], &far, 32, 32, false), Err(Error::MeshOutsideImage { .. })));
        assert!(r.mask().iter().all(|&m| m == 0));
        assert!(matches!(r.rasterize(&v, &[[0, 1, 9]], &c, 32, 32, false), Err(Error::OutOfRange { .. })));
        assert!(matches!(r.rasterize(&v, &[[0, 1, 2]], &c, 0, 32, false), Err(Error::EmptyImage { .. })));
        assert!(r.rasterize(&v, &[[0, 1, 2]], &c, 4097, 32, false).is_err());
        let mut nan = v;
        nan[1][0] = f32::NAN;
        assert!(matches!(r.rasterize(&nan, &[[0, 1, 2]], &c, 32, 32, false), Err(Error::NonFinite { .. })));
    }
}
