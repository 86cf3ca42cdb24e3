//! Costume lines and hair, placed with the posed joints and mesh.
//!
//! Costume pieces are 3-D bands around a bone (belt, boot tops, glove cuffs, collar, armour
//! plates): at a fraction `t` along the bone, the cross-section of the vertices bound mostly to
//! that bone gives a radius per angle (24 bins, the largest radial distance), the band is that
//! outline inflated a little, and only the parts the depth buffer does not hide are drawn — so a
//! belt shows its front half and disappears behind a forearm. The cape hangs from behind the
//! shoulders to below the knees and is drawn only where the body does not cover it.
//! Hair shapes are drawn in the image around the projected head (outline cap, strands, and a
//! style: short, long, spiky, bun or ponytail) and are never hidden.

use nalgebra::Vector3;
use rand::Rng;
use std::f64::consts::{PI, TAU};

use super::contours::DepthView;
use crate::camera::WeakPerspective;
use crate::skeleton::{joint, Joints3, BONES};

/// Which costume pieces to draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Costume {
    /// Two bands around the waist and a buckle.
    pub belt: bool,
    /// Boot tops: double bands around both shins.
    pub boots: bool,
    /// Glove cuffs around both forearms near the wrists.
    pub gloves: bool,
    /// A collar band around the neck.
    pub collar: bool,
    /// Shoulder pauldrons, chest plates and knee guards.
    pub armour: bool,
    /// A cape hanging behind the body.
    pub cape: bool,
}

/// Hair shape around the head.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Hair {
    /// No hair lines (bald or helmet-less sketch).
    #[default]
    None,
    /// A cap outline with a few strands.
    Short,
    /// A cap and curtains down to the shoulders.
    Long,
    /// A zig-zag crown.
    Spiky,
    /// A cap and a bun on top.
    Bun,
    /// A cap and a tail hanging at the back.
    Ponytail,
}

impl Hair {
    /// Every style, for random choice.
    pub const ALL: [Hair; 6] = [Hair::None, Hair::Short, Hair::Long, Hair::Spiky, Hair::Bun, Hair::Ponytail];
}

/// What the costume code needs of the posed figure.
pub struct Figure<'a> {
    /// Posed vertices, metres, model frame.
    pub vertices: &'a [[f32; 3]],
    /// Dominant bone of each vertex.
    pub dominant: &'a [u8],
    /// Posed joints, metres.
    pub joints: &'a Joints3,
    /// The camera.
    pub cam: &'a WeakPerspective,
    /// The depth buffer.
    pub depth: DepthView<'a>,
}

fn v3(p: [f64; 3]) -> Vector3<f64> {
    Vector3::from(p)
}

impl Figure<'_> {
    /// A closed band around bone `b` at fraction `t` from its start joint, from the vertices
    /// whose dominant bone is in `bones`, inflated by `inflate`. `None` when no vertex is there.
    fn band(&self, b: usize, bones: &[usize], t: f64, inflate: f64) -> Option<Vec<Vector3<f64>>> {
        let (s, c) = (v3(self.joints[BONES[b].0]), v3(self.joints[BONES[b].1]));
        let len = (c - s).norm();
        if len < 1e-6 {
            return None;
        }
        let d = (c - s) / len;
        let mut e1 = d.cross(&Vector3::z());
        if e1.norm() < 1e-3 {
            e1 = d.cross(&Vector3::x());
        }
        let e1 = e1.normalize();
        let e2 = d.cross(&e1);
        const BINS: usize = 24;
        let mut r = [0.0f64; BINS];
        for (v, &dom) in self.vertices.iter().zip(self.dominant) {
            if !bones.contains(&(dom as usize)) {
                continue;
            }
            let p = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64) - s;
            let along = p.dot(&d);
            if (along / len - t).abs() > 0.04 {
                continue;
            }
            let radial = p - d * along;
            let k = (((radial.dot(&e2).atan2(radial.dot(&e1)) + PI) / TAU * BINS as f64) as usize).min(BINS - 1);
            r[k] = r[k].max(radial.norm());
        }
        let filled: Vec<f64> = r.iter().copied().filter(|&x| x > 0.0).collect();
        if filled.len() < 3 {
            return None;
        }
        let mean = filled.iter().sum::<f64>() / filled.len() as f64;
        let centre = s + d * (t * len);
        Some(
            (0..=48)
                .map(|i| {
                    let a = -PI + TAU * (i as f64 + 0.5) / 48.0;
                    let k = ((i % 48) * BINS / 48).min(BINS - 1);
                    let rad = if r[k] > 0.0 { r[k] } else { mean };
                    centre + (e1 * a.cos() + e2 * a.sin()) * rad * inflate
                })
                .collect(),
        )
    }

    /// Projects a 3-D polyline and keeps its runs not hidden by the depth buffer.
    fn visible_runs(&self, pts: &[Vector3<f64>], out: &mut Vec<Vec<[f64; 2]>>) {
        let eps = 0.01 + 1.5 / self.cam.sx;
        let mut run: Vec<[f64; 2]> = Vec::new();
        for p in pts {
            let uv = self.cam.project(p);
            if self.depth.visible(uv[0], uv[1], self.cam.depth(p), eps) {
                run.push(uv);
            } else if run.len() >= 2 {
                out.push(std::mem::take(&mut run));
            } else {
                run.clear();
            }
        }
        if run.len() >= 2 {
            out.push(run);
        }
    }

    fn band_lines(&self, b: usize, bones: &[usize], ts: &[f64], inflate: f64, out: &mut Vec<Vec<[f64; 2]>>) {
        for &t in ts {
            if let Some(ring) = self.band(b, bones, t, inflate) {
                self.visible_runs(&ring, out);
            }
        }
    }

    /// The body's forward direction (hip line × up), unit.
    fn forward(&self) -> Vector3<f64> {
        let hips = v3(self.joints[joint::L_HIP]) - v3(self.joints[joint::R_HIP]);
        let f = hips.cross(&Vector3::y());
        if f.norm() < 1e-9 {
            Vector3::z()
        } else {
            f.normalize()
        }
    }

    /// Polylines (pixels) of the costume pieces in `c`.
    pub fn costume_lines<R: Rng + ?Sized>(&self, c: &Costume, rng: &mut R) -> Vec<Vec<[f64; 2]>> {
        let mut out = Vec::new();
        let torso = [7usize, 8, 11];
        if c.belt {
            let t0 = rng.random_range(0.08..0.16);
            self.band_lines(7, &torso, &[t0, t0 + 0.06], 1.05, &mut out);
            // Buckle: a small square on the front of the waist.
            let (p, n) = (v3(self.joints[joint::PELVIS]), v3(self.joints[joint::NECK]));
            let up = (n - p).normalize();
            let f = self.forward();
            let side = up.cross(&f).normalize();
            if let Some(ring) = self.band(7, &torso, t0 + 0.03, 1.07) {
                let front =
                    ring.iter().copied().max_by(|a, b| (a - p).dot(&f).total_cmp(&(b - p).dot(&f))).unwrap_or(p);
                let h = 0.035;
                let sq: Vec<Vector3<f64>> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)]
                    .iter()
                    .map(|&(a, b)| front + side * (a * h) + up * (b * h) + f * 0.01)
                    .collect();
                self.visible_runs(&sq, &mut out);
            }
        }
        if c.boots {
            for b in [10, 13] {
                let t = rng.random_range(0.2..0.45);
                self.band_lines(b, &[b], &[t, t + 0.05], 1.08, &mut out);
            }
        }
        if c.gloves {
            for b in [3, 6] {
                self.band_lines(b, &[b], &[0.72, 0.8], 1.1, &mut out);
            }
        }
        if c.collar {
            self.band_lines(0, &[0, 7], &[0.08, 0.22], 1.12, &mut out);
        }
        if c.armour {
            for b in [2, 5] {
                self.band_lines(b, &[b, 1, 4], &[0.05, 0.2, 0.35], 1.3, &mut out);
            }
            self.band_lines(7, &torso, &[0.5, 0.62, 0.74], 1.06, &mut out);
            for b in [10, 13] {
                self.band_lines(b, &[b, b - 1], &[0.02, 0.14], 1.15, &mut out);
            }
        }
        if c.cape {
            self.cape(rng, &mut out);
        }
        out
    }

    fn cape<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut Vec<Vec<[f64; 2]>>) {
        let f = self.forward();
        let (rs, ls) = (v3(self.joints[joint::R_SHOULDER]), v3(self.joints[joint::L_SHOULDER]));
        let side = (ls - rs).normalize();
        let low = self.joints[joint::R_ANKLE][1].min(self.joints[joint::L_ANKLE][1]);
        let drop = rng.random_range(0.15..0.45);
        let flare = rng.random_range(0.1..0.3);
        let top_r = rs - f * 0.06;
        let top_l = ls - f * 0.06;
        let bottom =
            |top: Vector3<f64>, sgn: f64| Vector3::new(top.x, low + drop, top.z) + side * (sgn * flare) - f * 0.18;
        let (br, bl) = (bottom(top_r, -1.0), bottom(top_l, 1.0));
        let curve = |a: Vector3<f64>, b: Vector3<f64>| -> Vec<Vector3<f64>> {
            let ctrl = (a + b) / 2.0 - f * 0.12;
            (0..=40)
                .map(|i| {
                    let t = i as f64 / 40.0;
                    a * (1.0 - t) * (1.0 - t) + ctrl * 2.0 * t * (1.0 - t) + b * t * t
                })
                .collect()
        };
        self.visible_runs(&curve(top_r, br), out);
        self.visible_runs(&curve(top_l, bl), out);
        let waves = rng.random_range(2.0..5.0);
        let hem: Vec<Vector3<f64>> = (0..=60)
            .map(|i| {
                let t = i as f64 / 60.0;
                br * (1.0 - t) + bl * t + Vector3::y() * (0.03 * (TAU * waves * t).sin())
            })
            .collect();
        self.visible_runs(&hem, out);
    }

    /// Polylines (pixels) of a hair shape around the projected head.
    pub fn hair_lines<R: Rng + ?Sized>(&self, hair: Hair, rng: &mut R) -> Vec<Vec<[f64; 2]>> {
        if hair == Hair::None {
            return Vec::new();
        }
        let h3 = v3(self.joints[joint::HEAD]);
        let n3 = v3(self.joints[joint::NECK]);
        let up3 = (h3 - n3).normalize();
        // Head size: farthest head-bone vertex above the head centre, and sideways.
        let (mut top, mut wide) = (0.0f64, 0.0f64);
        let side3 = {
            let s = v3(self.joints[joint::L_SHOULDER]) - v3(self.joints[joint::R_SHOULDER]);
            (s - up3 * s.dot(&up3)).normalize()
        };
        for (v, &d) in self.vertices.iter().zip(self.dominant) {
            if d != 0 {
                continue;
            }
            let p = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64) - h3;
            let a = p.dot(&up3);
            top = top.max(a);
            if a > -0.03 {
                wide = wide.max(p.dot(&side3).abs());
            }
        }
        if top <= 0.0 || wide <= 0.0 {
            return Vec::new();
        }
        let c = self.cam.project(&h3);
        let s = self.cam.sx;
        let tip = self.cam.project(&(h3 + up3));
        let (ux, uy) = ((tip[0] - c[0]) / s, (tip[1] - c[1]) / s);
        let ul = (ux * ux + uy * uy).sqrt().max(1e-9);
        let (ux, uy) = (ux / ul, uy / ul); // image "up" of the head
        let (rx, ry) = (-uy, ux); // image "right" (perpendicular)
        let (a, b) = (wide * s * 1.12, top * s * 1.12);
        // Point on the hair ellipse at angle th (0 = up, +: toward image right).
        let at = |th: f64, k: f64| -> [f64; 2] {
            let (x, y) = (th.sin() * a * k, th.cos() * b * k);
            [c[0] + rx * x + ux * y, c[1] + ry * x + uy * y]
        };
        let mut out = Vec::new();
        let span = rng.random_range(1.6..2.0);
        let cap: Vec<[f64; 2]> = (0..=40).map(|i| at(-span + 2.0 * span * i as f64 / 40.0, 1.0)).collect();
        match hair {
            Hair::Spiky => {
                let spikes = rng.random_range(5..9);
                let pts: Vec<[f64; 2]> = (0..=2 * spikes)
                    .map(|i| {
                        at(
                            -span + 2.0 * span * i as f64 / (2 * spikes) as f64,
                            if i % 2 == 1 { rng.random_range(1.25..1.5) } else { 1.0 },
                        )
                    })
                    .collect();
                out.push(pts);
            }
            _ => out.push(cap),
        }
        // Seen from behind, the hair covers the head: strands from the crown to the nape across
        // the whole head (no face to draw).
        let fwd3 = side3.cross(&up3);
        if (self.cam.r * fwd3)[2] < 0.0 {
            for _ in 0..rng.random_range(7..12) {
                let th = rng.random_range(-1.2..1.2);
                let (p0, p1) = (at(th * 0.5, 0.95), at(PI - th * rng.random_range(0.5..0.9), 0.9));
                let bow = rng.random_range(0.05..0.15) * a * th.signum();
                out.push(
                    (0..=8)
                        .map(|i| {
                            let t = i as f64 / 8.0;
                            let b = bow * 4.0 * t * (1.0 - t);
                            [p0[0] + (p1[0] - p0[0]) * t + rx * b, p0[1] + (p1[1] - p0[1]) * t + ry * b]
                        })
                        .collect(),
                );
            }
        }
        // Strands from the crown toward the forehead.
        for _ in 0..rng.random_range(2..5) {
            let th = rng.random_range(-1.0..1.0);
            let p0 = at(th * 0.3, 0.95);
            let p1 = at(th, rng.random_range(0.55..0.8));
            let mid = at(th * 0.7, 0.9);
            out.push(vec![p0, mid, p1]);
        }
        let down = |p: [f64; 2], d: f64, sideways: f64| [p[0] - ux * d + rx * sideways, p[1] - uy * d + ry * sideways];
        match hair {
            Hair::Long => {
                let len = rng.random_range(1.8..3.2) * b;
                for sgn in [-1.0, 1.0] {
                    let p0 = at(sgn * span, 1.0);
                    let pts: Vec<[f64; 2]> = (0..=12)
                        .map(|i| {
                            let t = i as f64 / 12.0;
                            down(p0, len * t, sgn * a * 0.35 * t * t)
                        })
                        .collect();
                    out.push(pts);
                }
            }
            Hair::Bun => {
                let cb = at(0.0, 1.25);
                let rb = 0.35 * a;
                out.push(
                    (0..=30)
                        .map(|i| {
                            let t = TAU * i as f64 / 30.0;
                            [cb[0] + rb * t.cos(), cb[1] + rb * t.sin()]
                        })
                        .collect(),
                );
            }
            Hair::Ponytail => {
                let sgn = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                let p0 = at(sgn * 1.2, 1.0);
                let len = rng.random_range(1.5..2.5) * b;
                for off in [0.0, 0.25] {
                    out.push(
                        (0..=12)
                            .map(|i| {
                                let t = i as f64 / 12.0;
                                down(p0, len * t, sgn * a * (0.5 * t + off * (1.0 - t)))
                            })
                            .collect(),
                    );
                }
            }
            _ => {}
        }
        out
    }
}
