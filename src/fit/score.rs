//! Match scores between a sample's projected silhouette and the sketch (paper eq. 7 and ours).
//! Everything here works at the raster resolution: the sketch's edge map is max-pooled to it once
//! per fit ([`SketchEvidence::new`]), then every sample's mask is scored against it.

use crate::error::{Error, Result};
use crate::image::GrayImage;

/// Which match score weighs the samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MatchScore {
    /// Paper eq. (7): |mask ∩ edges| / |mask ∪ edges| against the Canny edge map.
    Paper,
    /// IoU of the mask with the figure region recovered from the sketch: pixels enclosed by
    /// strokes (not reachable from the image border without crossing an edge, after closing
    /// 1-px gaps) in the regions that contain the projected skeleton.
    FilledIou,
    /// Mean distance (raster px, capped at [`CHAMFER_CAP`]) from the mask's boundary pixels to
    /// the nearest edge pixel, as a cost.
    Chamfer,
    /// [`MatchScore::Chamfer`] plus the mean distance (raster px, capped) from every edge pixel
    /// to the mask (0 for edges inside it), as a cost. The second term penalises silhouettes
    /// that leave the sketch's outer strokes uncovered; without it interior strokes (creases,
    /// costume lines, hatching) let a shrunken silhouette score well.
    TwoSidedChamfer,
}

/// Distances above this many raster pixels count as this much in [`MatchScore::Chamfer`].
pub const CHAMFER_CAP: f32 = 12.0;

/// The sketch at raster resolution: edges, their distance transform and the filled figure.
pub struct SketchEvidence {
    width: usize,
    height: usize,
    edges: Vec<u8>,
    edge_count: usize,
    distance: Vec<f32>,
    figure: Vec<u8>,
    figure_count: usize,
    /// 1 where a pixel is not reachable from the image border without crossing a stroke (the
    /// drawing's outer outline filled: body and clothing alike).
    inside: Vec<u8>,
    /// Per pixel, the distance a mask boundary pixel there costs in the chamfer: `distance`
    /// capped at the inside cap ([`SketchEvidence::with_inside_cap`]) inside the outline, at
    /// [`CHAMFER_CAP`] outside it.
    chamfer_cost: Vec<f32>,
}

impl SketchEvidence {
    /// Max-pools `edge_map` (non-zero = edge) to `width`×`height` and derives the distance
    /// transform and the figure region; `skeleton_px` are points on the projected skeleton at
    /// raster resolution (bone samples), used to keep the enclosed regions that belong to the
    /// figure.
    pub fn new(edge_map: &GrayImage, width: usize, height: usize, skeleton_px: &[[f64; 2]]) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::EmptyImage { width, height });
        }
        let (sw, sh) = (edge_map.width(), edge_map.height());
        let mut edges = vec![0u8; width * height];
        for (y, row) in edge_map.as_bytes().chunks_exact(sw).enumerate() {
            let ty = (y * height / sh).min(height - 1);
            // Edge maps are mostly empty: skip eight empty pixels at a time.
            for (k, chunk) in row.chunks(8).enumerate() {
                if chunk.len() == 8 && u64::from_ne_bytes(chunk.try_into().expect("8 bytes")) == 0 {
                    continue;
                }
                for (i, &v) in chunk.iter().enumerate() {
                    if v != 0 {
                        let x = 8 * k + i;
                        edges[ty * width + (x * width / sw).min(width - 1)] = 1;
                    }
                }
            }
        }
        let edge_count = edges.iter().filter(|&&e| e != 0).count();
        if edge_count == 0 {
            return Err(Error::OutOfRange {
                name: "sketch",
                detail: "the edge map has no edges: blank or too faint".into(),
            });
        }
        let distance = distance_transform(&edges, width, height);
        let (figure, inside) = filled_figure(&edges, width, height, skeleton_px);
        let figure_count = figure.iter().filter(|&&f| f != 0).count();
        let chamfer_cost = distance.iter().map(|d| d.min(CHAMFER_CAP)).collect();
        Ok(Self { width, height, edges, edge_count, distance, figure, figure_count, inside, chamfer_cost })
    }

    /// The clothing-robust chamfer: a mask boundary pixel inside the drawing's outer outline
    /// costs its distance to the nearest stroke capped at `cap` raster pixels, one outside it
    /// the full distance (capped at [`CHAMFER_CAP`]). Strokes under loose clothing are often
    /// missing, so a body boundary far inside the outline is weak evidence; a boundary outside
    /// every stroke is strong evidence against the shape. Interior strokes (creases, muscle
    /// lines, costume seams) count like any other stroke. `cap` ≥ [`CHAMFER_CAP`] (or not
    /// finite / not positive) keeps the plain chamfer.
    pub fn with_inside_cap(mut self, cap: f64) -> Self {
        let inside_cap = if cap.is_finite() && cap > 0.0 { (cap as f32).min(CHAMFER_CAP) } else { CHAMFER_CAP };
        for ((c, &d), &inside) in self.chamfer_cost.iter_mut().zip(&self.distance).zip(&self.inside) {
            *c = d.min(if inside != 0 { inside_cap } else { CHAMFER_CAP });
        }
        self
    }

    /// Fraction of a mask's boundary pixels within `radius` raster pixels of a stroke (0 for an
    /// empty mask): how much of a fitted silhouette the sketch actually supports.
    pub fn edge_support(&self, mask: &[u8], bounds: Option<[usize; 4]>, radius: f64) -> f64 {
        let (mut near, mut n) = (0usize, 0usize);
        self.for_each_boundary(mask, bounds, |i| {
            n += 1;
            near += (self.distance[i] as f64 <= radius) as usize;
        });
        if n == 0 {
            0.0
        } else {
            near as f64 / n as f64
        }
    }

    /// Edge support per label: every boundary pixel of `mask` is given a label by `label(x, y)`
    /// (raster pixels; `None` skips it); returns, per label below `labels`, (boundary pixels
    /// within `radius` raster pixels of a stroke, boundary pixels). Labels at or above `labels`
    /// are skipped.
    pub fn edge_support_counts(
        &self,
        mask: &[u8],
        bounds: Option<[usize; 4]>,
        radius: f64,
        labels: usize,
        label: impl Fn(usize, usize) -> Option<usize>,
    ) -> Vec<(usize, usize)> {
        let mut counts = vec![(0usize, 0usize); labels];
        let w = self.width;
        self.for_each_boundary(mask, bounds, |i| {
            if let Some(c) = label(i % w, i / w).and_then(|k| counts.get_mut(k)) {
                c.1 += 1;
                c.0 += (self.distance[i] as f64 <= radius) as usize;
            }
        });
        counts
    }

    /// Calls `f` with the index of every boundary pixel of `mask` inside `bounds`, in row-major
    /// order: a non-zero pixel on the raster's edge or with a zero 4-neighbour.
    fn for_each_boundary(&self, mask: &[u8], bounds: Option<[usize; 4]>, f: impl FnMut(usize)) {
        if let Some([x0, y0, x1, y1]) = bounds {
            for_each_boundary_in(mask, self.width, self.height, [x0, y0, x1, y1], f);
        }
    }

    /// Raster width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Raster height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }
    /// The recovered figure region (1 inside), row-major.
    pub fn figure(&self) -> &[u8] {
        &self.figure
    }

    /// Scores a mask (non-zero inside, `width`×`height`): higher is better for every kind
    /// (the chamfer cost is negated).
    pub fn score(&self, mask: &[u8], kind: MatchScore) -> f64 {
        self.score_in(mask, Some([0, 0, self.width - 1, self.height - 1]), kind)
    }

    /// [`SketchEvidence::score`] of a mask whose non-zero pixels all lie in the inclusive box
    /// `bounds = [x0, y0, x1, y1]` (`None`: the mask is empty), e.g.
    /// [`crate::raster::Rasterizer::covered_bounds`]; only that box is scanned, and
    /// the result equals `score`'s.
    pub fn score_in(&self, mask: &[u8], bounds: Option<[usize; 4]>, kind: MatchScore) -> f64 {
        let b = bounds.map(|[x0, y0, x1, y1]| [x0, y0, x1.min(self.width - 1), y1.min(self.height - 1)]);
        match kind {
            MatchScore::Paper => self.iou(mask, b, &self.edges, self.edge_count),
            MatchScore::FilledIou => self.iou(mask, b, &self.figure, self.figure_count),
            MatchScore::Chamfer => -self.boundary_chamfer(mask, b),
            MatchScore::TwoSidedChamfer => -(self.boundary_chamfer(mask, b) + self.uncovered_edges(mask)),
        }
    }

    /// Mean over edge pixels of the distance to the nearest mask pixel (0 inside), capped.
    fn uncovered_edges(&self, mask: &[u8]) -> f64 {
        if !mask.iter().any(|&m| m != 0) {
            return CHAMFER_CAP as f64;
        }
        let d = distance_transform(mask, self.width, self.height);
        let sum: f64 =
            self.edges.iter().zip(&d).filter(|(&e, _)| e != 0).map(|(_, &x)| x.min(CHAMFER_CAP) as f64).sum();
        sum / self.edge_count as f64
    }

    fn boundary_chamfer(&self, mask: &[u8], bounds: Option<[usize; 4]>) -> f64 {
        let (mut sum, mut n) = (0.0f64, 0usize);
        self.for_each_boundary(mask, bounds, |i| {
            sum += self.chamfer_cost[i] as f64;
            n += 1;
        });
        if n == 0 {
            CHAMFER_CAP as f64
        } else {
            sum / n as f64
        }
    }

    /// |mask ∩ b| / |mask ∪ b| for 0/non-zero images, given |b| and a box holding the mask.
    fn iou(&self, mask: &[u8], bounds: Option<[usize; 4]>, b: &[u8], b_count: usize) -> f64 {
        let (mut inter, mut a_count) = (0usize, 0usize);
        if let Some([x0, y0, x1, y1]) = bounds {
            for y in y0..=y1 {
                let row = y * self.width;
                for (&x, &y) in mask[row + x0..=row + x1].iter().zip(&b[row + x0..=row + x1]) {
                    let ax = (x != 0) as usize;
                    a_count += ax;
                    inter += ax & (y != 0) as usize;
                }
            }
        }
        let union = a_count + b_count - inter;
        if union == 0 {
            0.0
        } else {
            inter as f64 / union as f64
        }
    }
}

/// Calls `f` with the index of every boundary pixel of the row-major `w`×`h` `mask` in the
/// inclusive box `[x0, y0, x1, y1]` (clipped to the raster), in row-major order: a non-zero pixel
/// on the raster's edge or with a zero 4-neighbour. Eight pixels at a time where the whole
/// group and its neighbours lie inside the raster (one word per neighbour, skipped when none of
/// the eight is a boundary pixel), pixel by pixel elsewhere.
fn for_each_boundary_in(mask: &[u8], w: usize, h: usize, [x0, y0, x1, y1]: [usize; 4], mut f: impl FnMut(usize)) {
    let (x1, y1) = (x1.min(w - 1), y1.min(h - 1));
    let set = |i: usize| mask[i] != 0;
    for y in y0..=y1 {
        let row = y * w;
        let mut x = x0;
        if y > 0 && y + 1 < h {
            // Groups of 8 need x - 1 >= 0 and x + 8 <= w - 1 (both horizontal neighbours inside).
            if x == 0 {
                if set(row) {
                    f(row);
                }
                x = 1;
            }
            while x + 8 <= x1 + 1 && x + 9 <= w {
                let word = |i: usize| u64::from_le_bytes(mask[i..i + 8].try_into().expect("8 bytes"));
                let centre = nonzero_bytes(word(row + x));
                if centre != 0 {
                    let interior = nonzero_bytes(word(row + x - 1))
                        & nonzero_bytes(word(row + x + 1))
                        & nonzero_bytes(word(row + x - w))
                        & nonzero_bytes(word(row + x + w));
                    let mut boundary = centre & !interior;
                    while boundary != 0 {
                        f(row + x + (boundary.trailing_zeros() / 8) as usize);
                        boundary &= boundary - 1;
                    }
                }
                x += 8;
            }
        }
        for x in x..=x1 {
            let i = row + x;
            if !set(i) {
                continue;
            }
            let border = x == 0 || y == 0 || x + 1 == w || y + 1 == h;
            if border || !set(i - 1) || !set(i + 1) || !set(i - w) || !set(i + w) {
                f(i);
            }
        }
    }
}

/// The high bit of every non-zero byte of `v`, the other bits clear.
#[inline(always)]
fn nonzero_bytes(v: u64) -> u64 {
    const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    (((v & LOW7) + LOW7) | v) & !LOW7
}

/// Exact Euclidean distance (pixels) from every pixel to the nearest non-zero pixel of `src`
/// (Felzenszwalb & Huttenlocher's separable lower-envelope transform).
pub fn distance_transform(src: &[u8], w: usize, h: usize) -> Vec<f32> {
    const FAR: f64 = 1e12;
    let mut f: Vec<f64> = src.iter().map(|&v| if v != 0 { 0.0 } else { FAR }).collect();
    let mut line = Vec::new();
    let mut out = Vec::new();
    for x in 0..w {
        line.clear();
        line.extend((0..h).map(|y| f[y * w + x]));
        dt_1d(&line, &mut out);
        for y in 0..h {
            f[y * w + x] = out[y];
        }
    }
    for y in 0..h {
        line.clear();
        line.extend_from_slice(&f[y * w..(y + 1) * w]);
        dt_1d(&line, &mut out);
        f[y * w..(y + 1) * w].copy_from_slice(&out);
    }
    f.iter().map(|&d| d.sqrt() as f32).collect()
}

/// 1-D squared distance transform of sampled function `f` into `out`.
fn dt_1d(f: &[f64], out: &mut Vec<f64>) {
    let n = f.len();
    out.clear();
    out.resize(n, 0.0);
    let mut v = vec![0usize; n];
    let mut z = vec![0f64; n + 1];
    let mut k = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        loop {
            let p = v[k];
            let s = ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
            if s <= z[k] && k > 0 {
                k -= 1;
                continue;
            }
            if s <= z[k] {
                v[0] = q;
                z[0] = f64::NEG_INFINITY;
                z[1] = f64::INFINITY;
                break;
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f64::INFINITY;
            break;
        }
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        *o = (q as f64 - p as f64).powi(2) + f[p];
    }
}

/// The figure region: dilate edges by one pixel (closing small gaps), flood the background from
/// the border through non-edge pixels, and keep the enclosed components (plus their strokes)
/// that contain a skeleton point. Falls back to all enclosed pixels when no skeleton point lands
/// in one. Also returns the outline's inside (every pixel not reachable from the border).
fn filled_figure(edges: &[u8], w: usize, h: usize, skeleton_px: &[[f64; 2]]) -> (Vec<u8>, Vec<u8>) {
    let mut wall = edges.to_vec();
    for y in 0..h {
        for x in 0..w {
            if edges[y * w + x] != 0 {
                for (dx, dy) in [(-1isize, 0isize), (1, 0), (0, -1), (0, 1)] {
                    let (nx, ny) = (x as isize + dx, y as isize + dy);
                    if nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h {
                        wall[ny as usize * w + nx as usize] = 1;
                    }
                }
            }
        }
    }
    // Label 0 = unvisited, 1 = wall, 2 = background, 3.. = enclosed components.
    let mut label: Vec<u32> = wall.iter().map(|&v| v as u32).collect();
    let mut stack = Vec::new();
    let flood = |label: &mut Vec<u32>, seed: usize, id: u32, stack: &mut Vec<usize>| {
        label[seed] = id;
        stack.push(seed);
        while let Some(i) = stack.pop() {
            let (x, y) = (i % w, i / w);
            let mut visit = |j: usize| {
                if label[j] == 0 {
                    label[j] = id;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < w {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - w);
            }
            if y + 1 < h {
                visit(i + w);
            }
        }
    };
    for x in 0..w {
        for i in [x, (h - 1) * w + x] {
            if label[i] == 0 {
                flood(&mut label, i, 2, &mut stack);
            }
        }
    }
    for y in 0..h {
        for i in [y * w, y * w + w - 1] {
            if label[i] == 0 {
                flood(&mut label, i, 2, &mut stack);
            }
        }
    }
    let mut next = 3;
    for i in 0..w * h {
        if label[i] == 0 {
            flood(&mut label, i, next, &mut stack);
            next += 1;
        }
    }
    let mut keep = vec![false; next as usize];
    for p in skeleton_px {
        let (x, y) = (p[0].floor(), p[1].floor());
        if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
            let l = label[y as usize * w + x as usize];
            if l >= 3 {
                keep[l as usize] = true;
            }
        }
    }
    let any_kept = keep.iter().any(|&k| k);
    let mut figure: Vec<u8> = label.iter().map(|&l| (l >= 3 && (!any_kept || keep[l as usize])) as u8).collect();
    // The strokes around kept regions belong to the figure: grow (8-connected) into wall pixels by the
    // dilation (1 px) plus the stroke itself (1 px).
    for _ in 0..2 {
        let grown = figure.clone();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if label[i] == 1 && grown[i] == 0 {
                    let near = (y.saturating_sub(1)..(y + 2).min(h))
                        .any(|ny| (x.saturating_sub(1)..(x + 2).min(w)).any(|nx| grown[ny * w + nx] != 0));
                    figure[i] = near as u8;
                }
            }
        }
    }
    let inside = label.iter().map(|&l| (l != 2) as u8).collect();
    (figure, inside)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An edge raster of `n`×`n` with the given strokes (inclusive pixel rectangles).
    fn strokes(n: usize, rects: &[[usize; 4]]) -> GrayImage {
        let img = (0..n * n)
            .map(|i| {
                let (x, y) = (i % n, i / n);
                let on = rects.iter().any(|&[x0, y0, x1, y1]| (x0..=x1).contains(&x) && (y0..=y1).contains(&y));
                on as u8 * 255
            })
            .collect();
        GrayImage::from_vec(n, n, img).unwrap()
    }

    /// The outline of the square 10..=29 on an `n`×`n` raster.
    fn square_outline(n: usize) -> GrayImage {
        strokes(n, &[[10, 10, 29, 10], [10, 29, 29, 29], [10, 10, 10, 29], [29, 10, 29, 29]])
    }

    #[test]
    fn distance_transform_is_exact_on_a_point() {
        let (w, h) = (7, 5);
        let mut src = vec![0u8; w * h];
        src[2 * w + 3] = 1;
        let d = distance_transform(&src, w, h);
        for y in 0..h {
            for x in 0..w {
                let want = ((x as f64 - 3.0).powi(2) + (y as f64 - 2.0).powi(2)).sqrt() as f32;
                assert!((d[y * w + x] - want).abs() < 1e-5, "({x},{y}): {} vs {want}", d[y * w + x]);
            }
        }
    }

    /// A drawn square outline: the filled figure is the square, IoU with the exact square mask is
    /// high, the paper score of the same mask is low (edges are thin), and a shifted mask scores
    /// worse on every kind.
    #[test]
    fn scores_prefer_the_aligned_mask() {
        let n = 40;
        let ev = SketchEvidence::new(&square_outline(n), n, n, &[[20.0, 20.0]]).unwrap();
        let square = |ox: usize| {
            let mut m = vec![0u8; n * n];
            for y in 10..30 {
                for x in 10 + ox..30 + ox {
                    m[y * n + x] = 1;
                }
            }
            m
        };
        let (good, bad) = (square(0), square(6));
        assert!(ev.score(&good, MatchScore::FilledIou) > 0.99);
        for kind in [MatchScore::Paper, MatchScore::FilledIou, MatchScore::Chamfer] {
            assert!(ev.score(&good, kind) > ev.score(&bad, kind), "{kind:?}");
        }
        // Scanning only a box that holds the mask gives the same scores.
        let empty = vec![0u8; n * n];
        for kind in [MatchScore::Paper, MatchScore::FilledIou, MatchScore::Chamfer] {
            assert_eq!(ev.score_in(&good, Some([10, 10, 29, 29]), kind), ev.score(&good, kind), "{kind:?}");
            assert_eq!(ev.score_in(&bad, Some([14, 8, 36, 31]), kind), ev.score(&bad, kind), "{kind:?}");
            assert_eq!(ev.score_in(&empty, None, kind), ev.score(&empty, kind), "{kind:?}");
        }
        assert_eq!(ev.score_in(&empty, None, MatchScore::Chamfer), -(CHAMFER_CAP as f64));
        assert!((ev.score(&good, MatchScore::Paper) - 76.0 / 400.0).abs() < 1e-12);
        assert_eq!(ev.score(&good, MatchScore::Chamfer), 0.0);
    }

    /// The boundary of a mask is its pixels with a 4-neighbour outside it, and a mask pixel on
    /// the raster's edge is always boundary (the raster ends there): a mask filling the whole
    /// raster has exactly the raster's outer ring as boundary, a rectangle inside it its own ring.
    #[test]
    fn boundary_pixels_are_the_mask_edge_and_the_raster_edge() {
        let (w, h) = (9, 6);
        let mut img = vec![0u8; w * h];
        img[2 * w + 4] = 255;
        let ev = SketchEvidence::new(&GrayImage::from_vec(w, h, img).unwrap(), w, h, &[]).unwrap();
        let boundary = |mask: &[u8], bounds: Option<[usize; 4]>| {
            let mut got = Vec::new();
            ev.for_each_boundary(mask, bounds, |i| got.push(i));
            got
        };
        let ring = |x0: usize, y0: usize, x1: usize, y1: usize| -> Vec<usize> {
            (0..w * h)
                .filter(|&i| {
                    let (x, y) = (i % w, i / w);
                    (x0..=x1).contains(&x) && (y0..=y1).contains(&y) && (x == x0 || x == x1 || y == y0 || y == y1)
                })
                .collect()
        };
        assert_eq!(boundary(&vec![1u8; w * h], Some([0, 0, w - 1, h - 1])), ring(0, 0, w - 1, h - 1));
        let rect: Vec<u8> =
            (0..w * h).map(|i| ((2..=6).contains(&(i % w)) && (1..=4).contains(&(i / w))) as u8).collect();
        assert_eq!(boundary(&rect, Some([2, 1, 6, 4])), ring(2, 1, 6, 4));
        assert!(boundary(&rect, None).is_empty(), "no box: the mask is empty by contract");
    }

    /// The word-at-a-time boundary scan visits exactly the pixels, in the order, of the
    /// pixel-by-pixel definition, on random masks of any values in random boxes (touching the
    /// raster's edges or not).
    #[test]
    fn boundary_scan_matches_the_definition() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for case in 0..400 {
            let (w, h) = (rng.random_range(1..40usize), rng.random_range(1..30usize));
            let density = [0.2, 0.6, 0.95][case % 3];
            let mask: Vec<u8> =
                (0..w * h).map(|_| if rng.random_bool(density) { rng.random_range(1..=255u8) } else { 0 }).collect();
            let (xa, xb) = (rng.random_range(0..w), rng.random_range(0..w));
            let (ya, yb) = (rng.random_range(0..h), rng.random_range(0..h));
            let bounds = [xa.min(xb), ya.min(yb), xa.max(xb) + rng.random_range(0..3), ya.max(yb)];
            let set = |x: usize, y: usize| mask[y * w + x] != 0;
            let mut want = Vec::new();
            for y in bounds[1]..=bounds[3].min(h - 1) {
                for x in bounds[0]..=bounds[2].min(w - 1) {
                    let border = x == 0 || y == 0 || x + 1 == w || y + 1 == h;
                    if set(x, y) && (border || !set(x - 1, y) || !set(x + 1, y) || !set(x, y - 1) || !set(x, y + 1)) {
                        want.push(y * w + x);
                    }
                }
            }
            let mut got = Vec::new();
            for_each_boundary_in(&mask, w, h, bounds, |i| got.push(i));
            assert_eq!(got, want, "case {case}: {w}x{h} {bounds:?}");
        }
    }

    /// Edge support is the fraction of the mask's boundary within the radius of a stroke: 1 for
    /// the drawn square itself, the exact share for a shifted square (its left and right sides
    /// away from the strokes), 0 for an empty mask.
    #[test]
    fn edge_support_is_the_share_of_the_boundary_near_strokes() {
        let n = 40;
        let ev = SketchEvidence::new(&square_outline(n), n, n, &[[20.0, 20.0]]).unwrap();
        let square = |ox: usize| -> Vec<u8> {
            (0..n * n).map(|k| ((10 + ox..30 + ox).contains(&(k % n)) && (10..30).contains(&(k / n))) as u8).collect()
        };
        let full = Some([0, 0, n - 1, n - 1]);
        assert_eq!(ev.edge_support(&square(0), full, 0.5), 1.0);
        // Shifted by 6 (x 16..=35): 76 boundary pixels. At radius 0.5 only the top and bottom
        // rows' x 16..=29 lie on strokes (2 × 14); x 30..=35 there are 1..=6 from a stroke's end,
        // the left column (x 16) 1..=6 from the strokes, the right column (x 35) 6 from x = 29.
        let shifted = square(6);
        let support = |r: f64| ev.edge_support(&shifted, full, r);
        assert!((support(0.5) - 28.0 / 76.0).abs() < 1e-12, "{}", support(0.5));
        // Radius 5.5: add the rows' x 30..=34 (2 × 5) and the left column's 5 pixels nearest
        // each corner (2 × 5): 48 of 76. Radius 6 (inclusive) reaches every boundary pixel.
        assert!((support(5.5) - 48.0 / 76.0).abs() < 1e-12, "{}", support(5.5));
        assert_eq!(support(6.0), 1.0);
        assert_eq!(ev.edge_support(&vec![0u8; n * n], full, 3.0), 0.0);
        // Per label, the shifted square's left half (x < 26) and right half: the counts add up
        // to the whole's, the left half holds the left column and is better supported than the
        // right one (whose column is 6 from a stroke), and a label at or above `labels` is skipped.
        let halves = ev.edge_support_counts(&shifted, full, 5.5, 2, |x, _| Some((x >= 26) as usize));
        assert_eq!(halves[0].1 + halves[1].1, 76);
        assert_eq!(halves[0].0 + halves[1].0, 48);
        assert!(halves[0].0 as f64 / halves[0].1 as f64 > halves[1].0 as f64 / halves[1].1 as f64, "{halves:?}");
        let one = ev.edge_support_counts(&shifted, full, 5.5, 1, |x, _| Some((x >= 26) as usize));
        assert_eq!(one, vec![halves[0]]);
    }

    /// Two outlined squares: the figure is the one a skeleton point falls in (with its strokes),
    /// not the other, though both are inside the outline; skeleton points off the raster are
    /// ignored, and with none inside a region every enclosed region is kept.
    #[test]
    fn the_figure_is_the_enclosed_region_holding_the_skeleton() {
        let n = 30;
        let square = |a: usize, b: usize| [[a, a, b, a], [a, b, b, b], [a, a, a, b], [b, a, b, b]];
        let rects: Vec<[usize; 4]> = square(3, 12).into_iter().chain(square(17, 26)).collect();
        let edges = strokes(n, &rects);
        let at = |v: &[u8], x: usize, y: usize| v[y * n + x];
        let ev = SketchEvidence::new(&edges, n, n, &[[7.5, 7.5], [-4.0, 20.0], [35.0, 20.0]]).unwrap();
        assert_eq!((at(ev.figure(), 7, 7), at(ev.figure(), 3, 7), at(ev.figure(), 21, 21)), (1, 1, 0));
        assert_eq!((at(&ev.inside, 7, 7), at(&ev.inside, 21, 21), at(&ev.inside, 15, 15)), (1, 1, 0));
        let ev = SketchEvidence::new(&edges, n, n, &[[-4.0, 20.0], [35.0, 20.0]]).unwrap();
        assert_eq!((at(ev.figure(), 7, 7), at(ev.figure(), 21, 21), at(ev.figure(), 15, 15)), (1, 1, 0));
    }

    /// A pocket closed at the top, bottom and right but open to the raster's left edge is
    /// background reached from that edge: not inside the outline, not figure.
    #[test]
    fn a_pocket_open_to_the_left_edge_is_background() {
        let n = 20;
        let edges = strokes(n, &[[0, 5, 14, 5], [0, 14, 14, 14], [14, 5, 14, 14]]);
        let ev = SketchEvidence::new(&edges, n, n, &[[7.0, 9.0]]).unwrap();
        assert_eq!(ev.inside[9 * n + 7], 0);
        assert!(ev.figure().iter().all(|&f| f == 0));
    }

    #[test]
    fn blank_sketch_is_rejected() {
        let blank = GrayImage::filled(10, 10, 0).unwrap();
        assert!(matches!(SketchEvidence::new(&blank, 10, 10, &[]), Err(Error::OutOfRange { .. })));
    }

    /// A square outline with a stroke across its middle: a mask shrunk onto the interior stroke
    /// fools the one-sided chamfer but not the two-sided one.
    #[test]
    fn two_sided_chamfer_rejects_a_mask_shrunk_onto_interior_strokes() {
        let n = 40;
        let mut img = vec![0u8; n * n];
        for i in 8..32 {
            for (x, y) in [(i, 8), (i, 31), (8, i), (31, i), (i, 20)] {
                img[y * n + x] = 255;
            }
        }
        let ev = SketchEvidence::new(&GrayImage::from_vec(n, n, img).unwrap(), n, n, &[[20.0, 20.0]]).unwrap();
        let mask_of = |x0: usize, x1: usize, y0: usize, y1: usize| -> Vec<u8> {
            (0..n * n).map(|k| ((x0..=x1).contains(&(k % n)) && (y0..=y1).contains(&(k / n))) as u8).collect()
        };
        let full = mask_of(8, 31, 8, 31);
        let shrunk = mask_of(8, 31, 8, 20); // top half: its boundary lies on strokes too
        let one = |m: &[u8]| ev.score(m, MatchScore::Chamfer);
        let two = |m: &[u8]| ev.score(m, MatchScore::TwoSidedChamfer);
        assert!(
            one(&shrunk) >= one(&full) - 1e-9,
            "one-sided cannot tell them apart: {} vs {}",
            one(&shrunk),
            one(&full)
        );
        assert!(two(&full) > two(&shrunk) + 1.0, "two-sided: {} vs {}", two(&full), two(&shrunk));
        assert_eq!(two(&full), one(&full), "a mask covering every stroke has no uncovered-edge cost");
        assert_eq!(ev.score(&vec![0u8; n * n], MatchScore::TwoSidedChamfer), -2.0 * CHAMFER_CAP as f64);
    }
}
