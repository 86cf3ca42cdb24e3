//! Line extraction from a posed mesh: occluding contours (mesh edges between a face turned to
//! the viewer and one turned away, which covers the silhouette boundary and the interior
//! contours such as an arm in front of the torso), creases (edges whose two front faces meet at
//! more than the crease angle); open boundaries (the body mesh's eye and mouth holes) are
//! not drawn. Edges are chained into
//! polylines, projected, and cut where the depth buffer shows something nearer in front of them.
//!
//! Visibility of a point at camera depth `z` (metres, larger = nearer): visible when, in the 3×3
//! pixels around it, some pixel is empty or its depth is at most `z + eps`, with
//! `eps = 0.02 m + 3 px` (a contour lies where the surface is seen edge-on, so its own pixel may
//! hold surface up to a few pixels' worth of depth nearer).

use std::collections::HashMap;

use nalgebra::{Matrix3, Vector3};

use crate::camera::WeakPerspective;
use crate::error::{Error, Result};

/// Mesh edges with their (one or two) faces, built once per topology. `Send + Sync`.
#[derive(Clone, Debug)]
pub struct EdgeTopology {
    /// (v0, v1, f0, f1) with f1 = `u32::MAX` on an open boundary.
    edges: Vec<[u32; 4]>,
}

impl EdgeTopology {
    /// Builds the edge table of a quad mesh with `num_vertices` vertices. Errors on indices out
    /// of range or an edge shared by more than two faces.
    pub fn new(quads: &[[u32; 4]], num_vertices: usize) -> Result<EdgeTopology> {
        let mut map: HashMap<(u32, u32), usize> = HashMap::with_capacity(quads.len() * 2);
        let mut edges: Vec<[u32; 4]> = Vec::with_capacity(quads.len() * 2);
        for (f, q) in quads.iter().enumerate() {
            if q.iter().any(|&i| i as usize >= num_vertices) {
                return Err(Error::OutOfRange {
                    name: "face index",
                    detail: format!("face {f} indexes a vertex >= {num_vertices}"),
                });
            }
            for k in 0..4 {
                let (a, b) = (q[k], q[(k + 1) % 4]);
                if a == b {
                    continue;
                }
                let key = (a.min(b), a.max(b));
                match map.get(&key) {
                    Some(&e) => {
                        if edges[e][3] != u32::MAX {
                            return Err(Error::CorruptData(format!("edge {a}-{b} is shared by more than two faces")));
                        }
                        edges[e][3] = f as u32;
                    }
                    None => {
                        map.insert(key, edges.len());
                        edges.push([key.0, key.1, f as u32, u32::MAX]);
                    }
                }
            }
        }
        Ok(EdgeTopology { edges })
    }

    /// Marks the vertices within `rings` edge steps of an open boundary (the eye and mouth holes
    /// of the body mesh): their small folds would otherwise draw goggle-like rings on the face.
    pub fn near_boundary(&self, num_vertices: usize, rings: usize) -> Vec<bool> {
        let mut mark = vec![false; num_vertices];
        for e in &self.edges {
            if e[3] == u32::MAX {
                mark[e[0] as usize] = true;
                mark[e[1] as usize] = true;
            }
        }
        for _ in 0..rings {
            let prev = mark.clone();
            for e in &self.edges {
                let (a, b) = (e[0] as usize, e[1] as usize);
                if prev[a] || prev[b] {
                    mark[a] = true;
                    mark[b] = true;
                }
            }
        }
        mark
    }

    /// Number of edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    /// `true` for a mesh without faces.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }
}

/// What a line is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineKind {
    /// Occluding contour or open boundary.
    Contour,
    /// Crease between two visible faces.
    Crease,
}

/// A visible polyline, pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// Contour or crease.
    pub kind: LineKind,
    /// Points, pixels, image frame.
    pub pts: Vec<[f64; 2]>,
}

/// A depth buffer as the rasteriser leaves it: camera-frame z (metres, larger = nearer),
/// `-inf` where empty, `width` values a row.
#[derive(Clone, Copy, Debug)]
pub struct DepthView<'a> {
    /// Depth values.
    pub depth: &'a [f32],
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
}

impl DepthView<'_> {
    /// `true` when the point at pixel position (u, v) and depth `z` is not hidden (module doc).
    pub fn visible(&self, u: f64, v: f64, z: f64, eps: f64) -> bool {
        let (i, j) = (u.floor() as i64, v.floor() as i64);
        for y in j - 1..=j + 1 {
            for x in i - 1..=i + 1 {
                if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
                    return true;
                }
                let d = self.depth[y as usize * self.width + x as usize];
                if d == f32::NEG_INFINITY || (d as f64) <= z + eps {
                    return true;
                }
            }
        }
        false
    }

    /// Depth at pixel (u, v), `None` when empty or outside.
    pub fn at(&self, u: f64, v: f64) -> Option<f64> {
        let (i, j) = (u.floor(), v.floor());
        if i < 0.0 || j < 0.0 || i as usize >= self.width || j as usize >= self.height {
            return None;
        }
        let d = self.depth[j as usize * self.width + i as usize];
        (d != f32::NEG_INFINITY).then_some(d as f64)
    }
}

fn face_normal(r: &Matrix3<f64>, v: &[[f32; 3]], q: &[u32; 4]) -> Vector3<f64> {
    let p = |k: usize| Vector3::new(v[q[k] as usize][0] as f64, v[q[k] as usize][1] as f64, v[q[k] as usize][2] as f64);
    let n = (p(2) - p(0)).cross(&(p(3) - p(1)));
    r * n
}

/// Chains edges (vertex pairs) into vertex paths: open chains from their ends first, then loops.
fn chain(edges: &[[u32; 2]]) -> Vec<Vec<u32>> {
    let mut adj: HashMap<u32, Vec<usize>> = HashMap::new();
    for (e, &[a, b]) in edges.iter().enumerate() {
        adj.entry(a).or_default().push(e);
        adj.entry(b).or_default().push(e);
    }
    let mut used = vec![false; edges.len()];
    let mut starts: Vec<u32> = adj.iter().filter(|(_, l)| l.len() != 2).map(|(&v, _)| v).collect();
    starts.sort_unstable();
    let mut rest: Vec<u32> = edges.iter().map(|e| e[0]).collect();
    rest.sort_unstable();
    starts.extend(rest);
    let mut out = Vec::new();
    for s in starts {
        while let Some(&first) = adj[&s].iter().find(|&&e| !used[e]) {
            let mut path = vec![s];
            let (mut cur, mut e) = (s, first);
            loop {
                used[e] = true;
                let [a, b] = edges[e];
                cur = if a == cur { b } else { a };
                path.push(cur);
                match adj[&cur].iter().find(|&&x| !used[x]) {
                    Some(&n) if adj[&cur].len() == 2 => e = n,
                    _ => break,
                }
            }
            out.push(path);
        }
    }
    out
}

/// Extracts the visible lines of a posed quad mesh seen by `cam` (see the module doc).
/// `crease_deg` is the dihedral angle above which an edge between two front faces is drawn
/// (≥ 180 turns creases off). Runs shorter than `min_len` pixels are dropped. Edges with both
/// vertices marked in `skip` are not drawn.
#[allow(clippy::too_many_arguments)]
pub fn extract_lines(
    topo: &EdgeTopology,
    skip: &[bool],
    quads: &[[u32; 4]],
    vertices: &[[f32; 3]],
    cam: &WeakPerspective,
    depth: &DepthView<'_>,
    crease_deg: f64,
    min_len: f64,
) -> Vec<Line> {
    let normals: Vec<Vector3<f64>> = quads.iter().map(|q| face_normal(&cam.r, vertices, q)).collect();
    let cos_crease = crease_deg.to_radians().cos();
    let mut contour = Vec::new();
    let mut crease = Vec::new();
    for &[a, b, f0, f1] in &topo.edges {
        if skip.get(a as usize).copied().unwrap_or(false) && skip.get(b as usize).copied().unwrap_or(false) {
            continue;
        }
        let n0 = normals[f0 as usize];
        if f1 == u32::MAX {
            continue; // open boundaries are the eye and mouth holes: not drawn
        }
        let n1 = normals[f1 as usize];
        if (n0.z > 0.0) != (n1.z > 0.0) {
            contour.push([a, b]);
        } else if crease_deg < 180.0 && n0.z > 0.0 {
            let (l0, l1) = (n0.norm(), n1.norm());
            if l0 > 0.0 && l1 > 0.0 && n0.dot(&n1) / (l0 * l1) < cos_crease {
                crease.push([a, b]);
            }
        }
    }
    let eps = 0.02 + 3.0 / cam.sx;
    let mut lines = Vec::new();
    for (kind, edges) in [(LineKind::Contour, contour), (LineKind::Crease, crease)] {
        for path in chain(&edges) {
            let mut run: Vec<[f64; 2]> = Vec::new();
            let mut flush = |run: &mut Vec<[f64; 2]>| {
                if run.len() >= 2 && super::canvas::length(run) >= min_len {
                    lines.push(Line { kind, pts: std::mem::take(run) });
                }
                run.clear();
            };
            let proj = |i: u32| {
                let p = vertices[i as usize];
                let x = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                let uv = cam.project(&x);
                (uv, cam.depth(&x))
            };
            for w in path.windows(2) {
                let ((a, za), (b, zb)) = (proj(w[0]), proj(w[1]));
                let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
                let n = (len.ceil() as usize).clamp(1, 64);
                let start = if run.is_empty() { 0 } else { 1 };
                for k in start..=n {
                    let t = k as f64 / n as f64;
                    let (u, v, z) = (a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, za + (zb - za) * t);
                    if depth.visible(u, v, z, eps) {
                        run.push([u, v]);
                    } else {
                        flush(&mut run);
                    }
                }
            }
            flush(&mut run);
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chains_follow_edges_and_topology_checks_indices() {
        let paths = chain(&[[0, 1], [1, 2], [2, 3], [5, 6], [6, 7], [7, 5]]);
        assert_eq!(paths.len(), 2);
        assert!(paths.iter().any(|p| p == &vec![0, 1, 2, 3] || p == &vec![3, 2, 1, 0]));
        assert!(paths.iter().any(|p| p.len() == 4 && p[0] == p[3]), "{paths:?}");
        let quads = [[0, 1, 2, 3], [1, 4, 5, 2]];
        let t = EdgeTopology::new(&quads, 6).unwrap();
        assert_eq!(t.len(), 7);
        // Every edge of the two-quad strip is on the boundary except the shared one (1-2).
        let near = t.near_boundary(6, 0);
        assert!(near.iter().all(|&m| m));
        assert!(EdgeTopology::new(&quads, 5).is_err());
        let d = [f32::NEG_INFINITY, 1.0, 1.0, 1.0];
        let view = DepthView { depth: &d, width: 2, height: 2 };
        assert!(view.visible(1.5, 1.5, 0.0, 0.01), "an empty neighbour makes it visible");
        let d = [1.0f32; 25];
        let view = DepthView { depth: &d, width: 5, height: 5 };
        assert!(!view.visible(2.5, 2.5, 0.5, 0.01));
        assert!(view.visible(2.5, 2.5, 0.995, 0.01));
    }
}
