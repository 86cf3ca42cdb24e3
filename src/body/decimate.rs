//! Subset-preserving mesh decimation: half-edge collapses (a vertex is merged into one of its
//! neighbours, which keeps its position) ordered by the quadric error metric (Garland &
//! Heckbert's plane quadrics, area-weighted). Every kept vertex is an original vertex, so
//! per-vertex data (PCA rows, skin weights) of the decimated mesh are plain subsets.
//!
//! A collapse u → v is refused when u is on a boundary (open edges stay exactly), when it would
//! make the mesh non-manifold (the link condition: u and v share exactly the two neighbours
//! opposite their edge), or when it would turn or flatten a surviving face of u (its normal
//! would turn by more than about 70°, or it would lose most of its area). Single-threaded and
//! deterministic: ties in cost are broken by vertex indices.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::error::{Error, Result};

/// A decimated mesh: which original vertices survive and the triangles over them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decimated {
    /// Indices of the kept vertices in the original mesh, ascending.
    pub kept: Vec<u32>,
    /// Triangles as indices into `kept` (same winding as the faces they come from).
    pub triangles: Vec<[u32; 3]>,
}

/// Symmetric 4×4 quadric, upper triangle: a²  ab  ac  ad  b²  bc  bd  c²  cd  d².
type Quadric = [f64; 10];

fn plane_quadric(n: [f64; 3], d: f64, weight: f64) -> Quadric {
    let [a, b, c] = n;
    [a * a, a * b, a * c, a * d, b * b, b * c, b * d, c * c, c * d, d * d].map(|x| x * weight)
}

fn quadric_error(q: &Quadric, p: [f64; 3]) -> f64 {
    let [x, y, z] = p;
    q[0] * x * x
        + 2.0 * q[1] * x * y
        + 2.0 * q[2] * x * z
        + 2.0 * q[3] * x
        + q[4] * y * y
        + 2.0 * q[5] * y * z
        + 2.0 * q[6] * y
        + q[7] * z * z
        + 2.0 * q[8] * z
        + q[9]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A candidate collapse in the heap (smallest cost first; ties by vertex indices).
#[derive(PartialEq)]
struct Candidate {
    cost: f64,
    from: u32,
    to: u32,
    /// Versions of `from` and `to` when the cost was computed (stale entries are skipped).
    stamps: (u32, u32),
}

impl Eq for Candidate {}

impl Ord for Candidate {
    fn cmp(&self, o: &Self) -> Ordering {
        o.cost.total_cmp(&self.cost).then_with(|| (o.from, o.to).cmp(&(self.from, self.to)))
    }
}

impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

struct State {
    pos: Vec<[f64; 3]>,
    tris: Vec<[u32; 3]>,
    alive_tri: Vec<bool>,
    /// Faces incident to each vertex (may hold dead faces, skipped on use).
    faces_of: Vec<Vec<u32>>,
    quadric: Vec<Quadric>,
    boundary: Vec<bool>,
    alive: Vec<bool>,
    stamp: Vec<u32>,
    heap: BinaryHeap<Candidate>,
    /// Reused neighbour lists.
    scratch: [Vec<u32>; 2],
}

impl State {
    fn face_normal(&self, t: [u32; 3]) -> [f64; 3] {
        let p = t.map(|i| self.pos[i as usize]);
        cross(sub(p[1], p[0]), sub(p[2], p[0]))
    }

    /// Distinct live neighbours of `u` into `out` (sorted).
    fn neighbours_into(&self, u: u32, out: &mut Vec<u32>) {
        out.clear();
        for &f in &self.faces_of[u as usize] {
            if self.alive_tri[f as usize] {
                out.extend(self.tris[f as usize].iter().copied().filter(|&x| x != u));
            }
        }
        out.sort_unstable();
        out.dedup();
    }

    fn push(&mut self, from: u32, to: u32) {
        if self.boundary[from as usize] {
            return;
        }
        let mut q = self.quadric[from as usize];
        for (a, b) in q.iter_mut().zip(&self.quadric[to as usize]) {
            *a += b;
        }
        let cost = quadric_error(&q, self.pos[to as usize]).max(0.0);
        self.heap.push(Candidate { cost, from, to, stamps: (self.stamp[from as usize], self.stamp[to as usize]) });
    }

    /// Whether collapsing `u` into `v` keeps the mesh manifold and its faces unflipped.
    fn can_collapse(&mut self, u: u32, v: u32) -> bool {
        let (mut nu, mut nv) = (std::mem::take(&mut self.scratch[0]), std::mem::take(&mut self.scratch[1]));
        self.neighbours_into(u, &mut nu);
        self.neighbours_into(v, &mut nv);
        let linked = nu.binary_search(&v).is_ok();
        let common = nu.iter().filter(|x| nv.binary_search(x).is_ok()).count();
        self.scratch = [nu, nv];
        if !linked {
            return false;
        }
        let opposite = self.faces_of[u as usize]
            .iter()
            .filter(|&&f| self.alive_tri[f as usize] && self.tris[f as usize].contains(&v))
            .count();
        if common != 2 || opposite != 2 {
            return false;
        }
        self.faces_of[u as usize].iter().all(|&f| {
            let t = self.tris[f as usize];
            if !self.alive_tri[f as usize] || t.contains(&v) {
                return true;
            }
            let before = self.face_normal(t);
            let after = self.face_normal(t.map(|x| if x == u { v } else { x }));
            let (lb, la) = (dot(before, before).sqrt(), dot(after, after).sqrt());
            la > 0.05 * lb && dot(before, after) > 0.35 * lb * la
        })
    }

    fn collapse(&mut self, u: u32, v: u32) {
        let faces = std::mem::take(&mut self.faces_of[u as usize]);
        for &f in &faces {
            let fi = f as usize;
            if !self.alive_tri[fi] {
                continue;
            }
            if self.tris[fi].contains(&v) {
                self.alive_tri[fi] = false;
            } else {
                for x in self.tris[fi].iter_mut() {
                    if *x == u {
                        *x = v;
                    }
                }
                self.faces_of[v as usize].push(f);
            }
        }
        let (alive_tri, faces_of) = (&self.alive_tri, &mut self.faces_of);
        faces_of[v as usize].retain(|&f| alive_tri[f as usize]);
        self.alive[u as usize] = false;
        let qu = self.quadric[u as usize];
        for (a, b) in self.quadric[v as usize].iter_mut().zip(&qu) {
            *a += b;
        }
        // Only costs involving v's quadric changed; entries holding v's old stamp are stale.
        self.stamp[v as usize] += 1;
        let mut nv = std::mem::take(&mut self.scratch[0]);
        self.neighbours_into(v, &mut nv);
        for &w in &nv {
            self.push(v, w);
            self.push(w, v);
        }
        self.scratch[0] = nv;
    }
}

/// Decimates triangle mesh (`positions`, metres; `triangles`, indices) by half-edge collapses
/// until at most `target_vertices` vertices remain or no allowed collapse is left. Unreferenced
/// vertices are dropped. Errors: an index out of range, a non-finite position, or a target of 0.
pub fn decimate(positions: &[[f32; 3]], triangles: &[[u32; 3]], target_vertices: usize) -> Result<Decimated> {
    let n = positions.len();
    if target_vertices == 0 {
        return Err(Error::OutOfRange { name: "decimation target", detail: "0 vertices".into() });
    }
    if let Some(t) = triangles.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err(Error::OutOfRange {
            name: "triangle index",
            detail: format!("triangle {t} indexes a vertex >= {n}"),
        });
    }
    if let Some(&c) = positions.iter().flatten().find(|c| !c.is_finite()) {
        return Err(Error::NonFinite { name: "mesh vertex", value: c as f64 });
    }
    let mut s = State {
        pos: positions.iter().map(|p| p.map(|c| c as f64)).collect(),
        tris: triangles.to_vec(),
        alive_tri: vec![true; triangles.len()],
        faces_of: vec![Vec::new(); n],
        quadric: vec![[0.0; 10]; n],
        boundary: vec![false; n],
        alive: vec![false; n],
        stamp: vec![0; n],
        heap: BinaryHeap::new(),
        scratch: [Vec::new(), Vec::new()],
    };
    for (f, t) in triangles.iter().enumerate() {
        let nrm = s.face_normal(*t);
        let len = dot(nrm, nrm).sqrt();
        if len > 0.0 {
            let unit = nrm.map(|c| c / len);
            let q = plane_quadric(unit, -dot(unit, s.pos[t[0] as usize]), 0.5 * len);
            for &i in t {
                for (a, b) in s.quadric[i as usize].iter_mut().zip(&q) {
                    *a += b;
                }
            }
        }
        for &i in t {
            s.faces_of[i as usize].push(f as u32);
            s.alive[i as usize] = true;
        }
    }
    for (a, b) in boundary_edges(triangles) {
        s.boundary[a as usize] = true;
        s.boundary[b as usize] = true;
    }
    let mut edges: Vec<(u32, u32)> = triangles.iter().flat_map(|t| (0..3).map(move |k| sorted_edge(t, k))).collect();
    edges.sort_unstable();
    edges.dedup();
    for (a, b) in edges.iter().copied() {
        s.push(a, b);
        s.push(b, a);
    }
    let mut count = s.alive.iter().filter(|&&a| a).count();
    while count > target_vertices {
        let Some(c) = s.heap.pop() else { break };
        let (u, v) = (c.from as usize, c.to as usize);
        if !s.alive[u] || !s.alive[v] || c.stamps != (s.stamp[u], s.stamp[v]) {
            continue;
        }
        if !s.can_collapse(c.from, c.to) {
            continue;
        }
        s.collapse(c.from, c.to);
        count -= 1;
    }
    let kept: Vec<u32> = (0..n as u32).filter(|&i| s.alive[i as usize]).collect();
    let mut local = vec![u32::MAX; n];
    for (k, &i) in kept.iter().enumerate() {
        local[i as usize] = k as u32;
    }
    let triangles =
        s.tris.iter().zip(&s.alive_tri).filter(|(_, &a)| a).map(|(t, _)| t.map(|i| local[i as usize])).collect();
    Ok(Decimated { kept, triangles })
}

fn sorted_edge(t: &[u32; 3], k: usize) -> (u32, u32) {
    let (a, b) = (t[k], t[(k + 1) % 3]);
    (a.min(b), a.max(b))
}

/// Edges used by exactly one triangle (boundary edges), as sorted pairs, ascending.
pub fn boundary_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut edges: Vec<(u32, u32)> = triangles.iter().flat_map(|t| (0..3).map(move |k| sorted_edge(t, k))).collect();
    edges.sort_unstable();
    let mut out = Vec::new();
    let mut i = 0;
    while i < edges.len() {
        let j = (i..edges.len()).find(|&j| edges[j] != edges[i]).unwrap_or(edges.len());
        if j - i == 1 {
            out.push(edges[i]);
        }
        i = j;
    }
    out
}
