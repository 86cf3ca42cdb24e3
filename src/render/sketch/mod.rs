//! Synthetic concept sketches with full ground truth (issue 4; the paper's §III evaluation at
//! scale). A [`SketchRenderer`] takes a body shape (given weights or a GMM sample), a pose (given
//! 3-D joints, a random upright mocap frame, or a procedural pose), non-standard proportions, a
//! near-frontal weak-perspective camera, and draws the posed mesh as line art: occluding contours
//! and creases with pencil-like strokes, optional hatching, costume lines, hair, paper and
//! clutter. Every random choice comes from one `ChaCha8Rng` seeded by [`SketchRequest::seed`], in
//! a fixed order, so a request always gives the same image and ground truth.
//!
//! Files: `scene` (shape, proportions, pose, camera), `contours` (line extraction and
//! visibility), `canvas` (strokes), `art` (flat, cel, screen-tone and watercolour fills, thick
//! ink, masses, stylised proportions, textured paper: [`SketchRenderer::render_art`]), `costume` (costume and hair), `paper` (hatching, paper,
//! clutter), `style` ([`SketchStyle`]), `mocap` (pose clips), `truth` (ground truth and files).

pub mod art;
pub mod background;
pub mod canvas;
pub mod contours;
pub mod costume;
pub mod mocap;
pub mod paper;
pub mod scene;
pub mod style;
pub mod truth;

use std::sync::Arc;

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub use crate::body::proportions::Proportions;
pub use art::ArtStyle;
pub use costume::{Costume, Hair};
pub use mocap::MocapLibrary;
pub use scene::CameraAngles;
pub use style::SketchStyle;
pub use truth::GroundTruth;

use self::canvas::{Canvas, Pen};
use self::contours::{DepthView, EdgeTopology, LineKind};
use crate::body::{BodyModel, Gender, VertexWeights};
use crate::camera::WeakPerspective;
use crate::error::Result;
use crate::raster::{check_size, Rasterizer};
use crate::skeleton::{Joints2, Joints3, BONES, NUM_JOINTS};

/// Default image side, pixels.
pub const DEFAULT_SIZE: usize = 512;

/// What to draw. `None` fields are chosen at random from the seed.
#[derive(Clone, Debug, PartialEq)]
pub struct SketchRequest {
    /// Seed of every random choice.
    pub seed: u64,
    /// Image width, pixels (1..=4096, the rasteriser's limit).
    pub width: usize,
    /// Image height, pixels (1..=4096).
    pub height: usize,
    /// Gender; random (even odds) when `None`.
    pub gender: Option<Gender>,
    /// PCA shape weights (metres, as `ShapeSpace::synthesize`); a GMM sample when `None`.
    pub shape_weights: Option<Vec<f64>>,
    /// Pose as 15 joints (metres, any frame with +Y up; only bone directions are used); a random
    /// upright mocap frame (or a procedural pose without a mocap library) when `None`.
    pub joints: Option<Joints3>,
    /// Camera angles; random near-frontal (yaw ±30°, pitch ±10°, roll ±5°) when `None`.
    pub camera: Option<CameraAngles>,
    /// Drawing style; [`SketchStyle::random`] when `None`.
    pub style: Option<SketchStyle>,
}

impl SketchRequest {
    /// A fully random request of a square image.
    pub fn random(seed: u64, size: usize) -> SketchRequest {
        SketchRequest {
            seed,
            width: size,
            height: size,
            gender: None,
            shape_weights: None,
            joints: None,
            camera: None,
            style: None,
        }
    }
}

/// A rendered sketch: the image, its ground truth and the two meshes.
#[derive(Clone, Debug)]
pub struct Sketch {
    /// Gray pixels, row-major, `width` bytes a row (0 black ink, 255 white paper).
    pub pixels: Vec<u8>,
    /// Everything known about the image.
    pub truth: GroundTruth,
    /// Rest mesh with the proportions applied, metres, model frame.
    pub rest_vertices: Vec<[f32; 3]>,
    /// Posed mesh, metres, model frame (pelvis at the origin); project with `truth.camera`.
    pub posed_vertices: Vec<[f32; 3]>,
}

/// Renders sketches from one body model. Immutable after construction: share it across threads
/// (`Send + Sync`).
pub struct SketchRenderer {
    model: Arc<BodyModel>,
    topo: EdgeTopology,
    triangles: Vec<[u32; 3]>,
    dominant: Vec<u8>,
    face_detail: Vec<bool>,
    mocap: Option<MocapLibrary>,
}

fn dominant_bone(w: &VertexWeights) -> u8 {
    w.influences().max_by(|a, b| a.1.total_cmp(&b.1)).map_or(0, |x| x.0 as u8)
}

/// Splits a polyline into pencil strokes of random length around `mean` pixels, each extended
/// by up to `overshoot` pixels past its ends.
fn pencil_pieces<R: Rng + ?Sized>(pts: &[[f64; 2]], mean: f64, overshoot: f64, rng: &mut R) -> Vec<Vec<[f64; 2]>> {
    let s = canvas::resample(pts, 1.0);
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < s.len() {
        let n = (mean * rng.random_range(0.5..1.5)).max(4.0) as usize;
        let j = (i + n).min(s.len() - 1);
        // Leave the last scrap to the previous piece.
        let j = if s.len() - 1 - j < 6 { s.len() - 1 } else { j };
        let mut piece = s[i..=j].to_vec();
        if overshoot > 0.0 && piece.len() >= 3 {
            let ext = |a: [f64; 2], b: [f64; 2], d: f64| {
                let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
                let l = (dx * dx + dy * dy).sqrt().max(1e-9);
                [a[0] + dx / l * d, a[1] + dy / l * d]
            };
            let (d0, d1) = (rng.random_range(0.0..overshoot), rng.random_range(0.0..overshoot));
            let first = ext(piece[0], piece[2], d0);
            let k = piece.len();
            let last = ext(piece[k - 1], piece[k - 3], d1);
            piece.insert(0, first);
            piece.push(last);
        }
        out.push(piece);
        // A small gap or overlap before the next stroke.
        i = (j as i64 + rng.random_range(-3..3)).clamp(i as i64 + 1, s.len() as i64 - 1) as usize;
        if j == s.len() - 1 {
            break;
        }
    }
    out
}

impl SketchRenderer {
    /// A renderer for `model`, drawing poses from `mocap` when given.
    pub fn new(model: Arc<BodyModel>, mocap: Option<MocapLibrary>) -> Result<SketchRenderer> {
        let topo = EdgeTopology::new(model.faces(), model.num_vertices())?;
        let triangles = model.triangles();
        let dominant = model.skin_weights().iter().map(dominant_bone).collect();
        let face_detail = topo.near_boundary(model.num_vertices(), 4);
        Ok(SketchRenderer { model, topo, triangles, dominant, face_detail, mocap })
    }

    /// The body model.
    pub fn model(&self) -> &BodyModel {
        &self.model
    }

    /// Renders one sketch. Errors: sizes outside 1..=4096, shape weights the space rejects
    /// (too many, non-finite), non-finite joints or zero-length bones, invalid style or camera
    /// angles.
    pub fn render(&self, req: &SketchRequest) -> Result<Sketch> {
        self.render_with(req, None)
    }

    /// Renders one sketch in an art style ([`art`]): the figure, pose, camera and lines of
    /// [`SketchRenderer::render`] for the same request (proportions replaced for a chibi or
    /// heroic build), painted. The art's own random choices come from a second generator seeded
    /// from `req.seed`, so the request's stream is unchanged. Errors: as `render`.
    pub fn render_art(&self, req: &SketchRequest, art: &ArtStyle) -> Result<Sketch> {
        self.render_with(req, Some(art))
    }

    fn render_with(&self, req: &SketchRequest, art: Option<&ArtStyle>) -> Result<Sketch> {
        check_size(req.width, req.height)?;
        let mut rng = ChaCha8Rng::seed_from_u64(req.seed);
        let mut art_rng = ChaCha8Rng::seed_from_u64(req.seed ^ 0x4152_5453_5459_4C45);
        let gender = match req.gender {
            Some(g) => g,
            None => Gender::ALL[rng.random_range(0..2)],
        };
        let mut style = match &req.style {
            Some(s) => s.clone(),
            None => SketchStyle::random(&mut rng),
        };
        if let Some(p) = art.and_then(|a| a.proportions(&mut art_rng)) {
            style.proportions = p;
        }
        style.validate()?;
        let space = self.model.space(gender);
        let weights = match &req.shape_weights {
            Some(w) => {
                space.check_weights(w)?;
                w.clone()
            }
            None => space.gmm().sample(&mut rng),
        };
        let shape = space.synthesize(&weights)?;
        let (rest_v, rest_j) = crate::body::proportions::apply_proportions(
            &shape.vertices,
            &shape.joints,
            self.model.skin_weights(),
            &style.proportions,
        )?;
        let (source, pose_source) = match (&req.joints, &self.mocap) {
            (Some(j), _) => (*j, "given".to_string()),
            (None, Some(lib)) => match lib.random(&mut rng) {
                Some(f) => (mocap::normalize_frame(&f.joints), format!("mocap:{}:{}", f.clip, f.frame)),
                None => (
                    mocap::normalize_frame(&crate::body::procedural::random_pose(&rest_j, &mut rng, 0.0)),
                    "procedural".into(),
                ),
            },
            (None, None) => (
                mocap::normalize_frame(&crate::body::procedural::random_pose(&rest_j, &mut rng, 0.0)),
                "procedural".into(),
            ),
        };
        let target = crate::body::retarget::retarget_directions(&rest_j, &source)?;
        let (posed, pose) = crate::body::retarget::pose_mesh(&rest_v, &rest_j, self.model.skin_weights(), &target)?;
        let angles = match req.camera {
            Some(a) => a,
            None => CameraAngles::random(&mut rng),
        };
        let cam = scene::fit_camera(angles.rotation()?, &posed, req.width, req.height, style.margin)?;
        let mut raster = Rasterizer::new();
        raster.rasterize(&posed, &self.triangles, &cam, req.width, req.height, true)?;
        let depth = DepthView { depth: raster.depth(), width: req.width, height: req.height };

        let unit = req.width.min(req.height) as f64 / DEFAULT_SIZE as f64;
        let mut canvas = Canvas::new(req.width, req.height);
        let pen = Pen {
            width: style.stroke_width * unit,
            ink: style.ink,
            wobble: style.wobble * unit,
            jitter: style.pressure_jitter,
            taper: 0.15,
        };
        let crease_pen = Pen { width: pen.width * 0.7, ink: style.ink * style.crease_ink, ..pen };
        let lines = contours::extract_lines(
            &self.topo,
            &self.face_detail,
            self.model.faces(),
            &posed,
            &cam,
            &depth,
            style.crease_deg,
            2.5 * unit,
        );
        for mut line in lines {
            canvas::smooth(&mut line.pts, 2);
            let p = if line.kind == LineKind::Contour { pen } else { crease_pen };
            for piece in pencil_pieces(&line.pts, style.stroke_length * unit, style.overshoot * unit, &mut rng) {
                canvas.stroke(&piece, &p, &mut rng);
            }
            if line.kind == LineKind::Contour && rng.random_bool(style.retrace) {
                let (ox, oy) = (rng.random_range(-1.5..1.5) * unit, rng.random_range(-1.5..1.5) * unit);
                let shifted: Vec<[f64; 2]> = line.pts.iter().map(|q| [q[0] + ox, q[1] + oy]).collect();
                let light = Pen { ink: pen.ink * 0.5, width: pen.width * 0.7, ..pen };
                canvas.stroke(&shifted, &light, &mut rng);
            }
        }
        let figure =
            costume::Figure { vertices: &posed, dominant: &self.dominant, joints: &pose.joints, cam: &cam, depth };
        let extra_pen = Pen { width: pen.width * 0.8, ..pen };
        for l in
            figure.costume_lines(&style.costume, &mut rng).into_iter().chain(figure.hair_lines(style.hair, &mut rng))
        {
            let mut l = l;
            canvas::smooth(&mut l, 1);
            canvas.stroke(&l, &extra_pen, &mut rng);
        }
        paper::hatch(&mut canvas, &depth, cam.sx, style.hatching, style.hatch_spacing * unit, style.ink, &mut rng);
        let ground = if style.ground_line {
            let (mut lo, mut x0, mut x1) = (f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
            for p in &posed {
                let uv = cam.project(&Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                lo = lo.max(uv[1]);
                x0 = x0.min(uv[0]);
                x1 = x1.max(uv[0]);
            }
            let half = (x1 - x0).max(40.0 * unit) * rng.random_range(0.6..1.0);
            let mid = (x0 + x1) / 2.0;
            Some((lo + 2.0 * unit, mid - half, mid + half))
        } else {
            None
        };
        paper::clutter(
            &mut canvas,
            &pen,
            unit,
            style.stray_strokes,
            style.scribbles,
            style.text_rows,
            ground,
            &mut rng,
        );
        let joints2d = self.joints2d(&pose.joints, &posed, &cam, &depth);
        let pixels = match art {
            None => paper::compose(&canvas, style.paper_tone, style.paper_noise, 1.0, &mut rng),
            Some(a) => {
                let fig = art::FigureView { depth, scale: cam.sx, joints: &joints2d.xy, unit };
                let layer = art::paint(&mut canvas, &fig, a, &extra_pen, &mut art_rng);
                art::compose(&canvas, &layer, style.paper_tone, style.paper_noise, a.textured_paper, &mut art_rng)
            }
        };
        let height_m = {
            let (lo, hi) =
                rest_v.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| (lo.min(v[1]), hi.max(v[1])));
            (hi - lo) as f64
        };
        let truth = GroundTruth::new(
            req,
            gender,
            weights,
            joints2d,
            &pose.joints,
            &rest_j,
            &cam,
            angles,
            height_m,
            pose_source,
            style,
        );
        Ok(Sketch { pixels, truth, rest_vertices: rest_v, posed_vertices: posed })
    }

    /// Projected joints and their visibility: a joint is visible when the depth buffer at its
    /// pixel is empty or no nearer than the front of its own body part (the nearest vertex
    /// within 0.15 m bound mostly to a bone at that joint) plus 2 cm.
    fn joints2d(&self, joints: &Joints3, posed: &[[f32; 3]], cam: &WeakPerspective, depth: &DepthView<'_>) -> Joints2 {
        let mut out = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [false; NUM_JOINTS] };
        for k in 0..NUM_JOINTS {
            let j = Vector3::from(joints[k]);
            let uv = cam.project(&j);
            out.xy[k] = uv;
            let mut front = cam.depth(&j);
            for (v, &d) in posed.iter().zip(&self.dominant) {
                let (s, c) = BONES[d as usize];
                if s != k && c != k {
                    continue;
                }
                let p = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                if (p - j).norm() < 0.15 {
                    front = front.max(cam.depth(&p));
                }
            }
            let inside = uv[0] >= 0.0 && uv[1] >= 0.0 && uv[0] < depth.width as f64 && uv[1] < depth.height as f64;
            out.visible[k] = inside && depth.at(uv[0], uv[1]).is_none_or(|d| d <= front + 0.02);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pencil_pieces_cover_the_line() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let line: Vec<[f64; 2]> = (0..=100).map(|i| [i as f64, 0.0]).collect();
        let pieces = pencil_pieces(&line, 30.0, 0.0, &mut rng);
        assert!(pieces.len() >= 2, "{}", pieces.len());
        let covered: f64 = pieces.iter().map(|p| canvas::length(p)).sum();
        assert!(covered > 90.0, "{covered}");
        assert!(pieces.last().unwrap().last().unwrap()[0] > 99.0);
    }
}
