//! A base-colour texture from the sketch: every texel of MakeHuman's UV layout whose surface
//! point the estimated camera sees (facing it and not hidden behind another part of the posed
//! body) takes the sketch's colour where that point projects; every other texel gets
//! [`NEUTRAL`], a light grey (no mirrored fill: a sketch's left and right sides are rarely drawn
//! alike, and a wrong copy is worse than a neutral patch). Visible texels are grown by
//! [`GUTTER`] texels into the unused space around UV islands, so filtering at island borders
//! does not bleed grey into the drawing.

use nalgebra::Vector3;

use crate::body::rig::FaceUvs;
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::image::RgbImage;
use crate::raster::{Rasterizer, MAX_RASTER_SIDE};

/// Colour of the texels the sketch does not see.
pub const NEUTRAL: [u8; 3] = [190, 190, 190];
/// Texels visible texels grow into the unused space around UV islands.
pub const GUTTER: usize = 2;
/// Default texture side, texels.
pub const DEFAULT_TEXTURE_SIZE: usize = 1024;
/// A texel is visible when its point is at most this far (metres, along the view) behind the
/// nearest surface at its pixel.
pub const DEPTH_TOLERANCE: f64 = 0.01;

/// What a projection did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TextureStats {
    /// Texels inside some UV triangle.
    pub texels: usize,
    /// Of those, texels the sketch coloured.
    pub visible: usize,
}

/// Checks a texture side for [`project_sketch`]: 1..=[`MAX_RASTER_SIDE`] texels
/// ([`Error::OutOfRange`] otherwise), so a caller can check it before the work.
pub fn check_texture_size(size: usize) -> Result<()> {
    if size == 0 || size > MAX_RASTER_SIDE {
        return Err(Error::OutOfRange {
            name: "texture size",
            detail: format!("{size}: expected 1..={MAX_RASTER_SIDE}"),
        });
    }
    Ok(())
}

/// Longest side, pixels, of the depth raster that decides which texels of a `size`-texel
/// texture the sketch sees: twice the texture's side (a texel's footprint on the body is no
/// finer), at least [`MIN_DEPTH_SIDE`], at most [`MAX_RASTER_SIDE`].
fn depth_side(size: usize) -> usize {
    (2 * size).clamp(MIN_DEPTH_SIDE, MAX_RASTER_SIDE)
}

/// Sketches up to this many pixels a side decide visibility at their own pixels whatever the
/// texture's size.
pub const MIN_DEPTH_SIDE: usize = 1024;

/// Projects `sketch` (colour, same pixels as the image the pose was estimated on) onto the
/// posed mesh (`posed` vertices, metres, model frame; `quads` with per-corner `uvs`) through
/// `camera`, into a `size`×`size` texture (row 0 is the top, v = 1). A sketch that sees no face
/// gives an all-neutral texture. Sketches of any size the library loads work: which texel is
/// seen is decided on a depth raster of the sketch scaled down to [`depth_side`] (twice the
/// texture's side, at least [`MIN_DEPTH_SIDE`] px; the colour is still the sketch's own).
/// Errors: `size` 0 or above 4096 ([`check_texture_size`]), UV faces that do not match the quads
/// or index out of range, a non-finite vertex ([`Error::OutOfRange`] / [`Error::NonFinite`]).
pub fn project_sketch(
    sketch: &RgbImage,
    posed: &[[f32; 3]],
    quads: &[[u32; 4]],
    uvs: &FaceUvs,
    camera: &WeakPerspective,
    size: usize,
) -> Result<(RgbImage, TextureStats)> {
    check_texture_size(size)?;
    let (n, m) = (posed.len(), uvs.coords.len());
    if uvs.quads.len() != quads.len()
        || quads.iter().any(|q| q.iter().any(|&i| i as usize >= n))
        || uvs.quads.iter().any(|q| q.iter().any(|&i| i as usize >= m))
    {
        return Err(Error::OutOfRange {
            name: "UV faces",
            detail: format!("{} UV faces for {} faces", uvs.quads.len(), quads.len()),
        });
    }
    if let Some(c) = posed.iter().flatten().find(|c| !c.is_finite()) {
        return Err(Error::NonFinite { name: "mesh vertex", value: *c as f64 });
    }
    camera.validate()?;
    let (w, h) = (sketch.width(), sketch.height());
    let tris = crate::body::rig::quads_to_triangles(quads);
    // The visibility depth at the sketch's pixels, or scaled down to `depth_side` for larger
    // sketches (the colour is still sampled at full resolution).
    let depth_side = depth_side(size);
    let f = (depth_side as f64 / w.max(h) as f64).min(1.0);
    let (rw, rh) = (
        ((w as f64 * f).round() as usize).clamp(1, depth_side),
        ((h as f64 * f).round() as usize).clamp(1, depth_side),
    );
    let (fx, fy) = (rw as f64 / w as f64, rh as f64 / h as f64);
    let depth_camera = WeakPerspective {
        sx: camera.sx * fx,
        sy: camera.sy * fy,
        r: camera.r,
        t: [camera.t[0] * fx, camera.t[1] * fy],
    };
    let mut raster = Rasterizer::new();
    let depth: Option<Vec<f32>> = match raster.rasterize(posed, &tris, &depth_camera, rw, rh, true) {
        Ok(_) => Some(raster.depth().to_vec()),
        Err(Error::MeshOutsideImage { .. }) => None,
        Err(e) => return Err(e),
    };
    let pixels = sketch.as_bytes();
    let sample = |x: f64, y: f64| -> [u8; 3] {
        // Bilinear, pixel centres at +0.5.
        let (fx, fy) = ((x - 0.5).clamp(0.0, (w - 1) as f64), (y - 0.5).clamp(0.0, (h - 1) as f64));
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (ax, ay) = (fx - x0 as f64, fy - y0 as f64);
        let px = |i: usize, j: usize, c: usize| pixels[(j * w + i) * 3 + c] as f64;
        [0, 1, 2].map(|c| {
            let top = px(x0, y0, c) * (1.0 - ax) + px(x1, y0, c) * ax;
            let bottom = px(x0, y1, c) * (1.0 - ax) + px(x1, y1, c) * ax;
            (top * (1.0 - ay) + bottom * ay).round() as u8
        })
    };
    // 0 unused, 1 inside a triangle but unseen, 2 coloured.
    let mut state = vec![0u8; size * size];
    let mut img = RgbImage::filled(size, size, NEUTRAL)?;
    let view = camera.r.transpose() * Vector3::z();
    let p3 =
        |i: u32| Vector3::new(posed[i as usize][0] as f64, posed[i as usize][1] as f64, posed[i as usize][2] as f64);
    for (f, q) in quads.iter().enumerate() {
        let uq = uvs.quads[f];
        let corners: &[[usize; 3]] = if q[3] == q[2] || q[3] == q[0] { &[[0, 1, 2]] } else { &[[0, 1, 2], [0, 2, 3]] };
        for c in corners {
            let p = c.map(|k| p3(q[k]));
            let normal = (p[1] - p[0]).cross(&(p[2] - p[0]));
            let facing = normal.dot(&view) > 0.0;
            let t = c.map(|k| {
                let uv = uvs.coords[uq[k] as usize];
                [uv[0] as f64 * size as f64, (1.0 - uv[1] as f64) * size as f64]
            });
            let area = (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[1][1] - t[0][1]) * (t[2][0] - t[0][0]);
            if area.abs() < 1e-12 {
                continue;
            }
            let lo = |k: usize| t.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min).floor().max(0.0) as usize;
            let hi = |k: usize| (t.iter().map(|v| v[k]).fold(f64::NEG_INFINITY, f64::max).ceil() as usize).min(size);
            for j in lo(1)..hi(1) {
                for i in lo(0)..hi(0) {
                    let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
                    let b1 = ((x - t[0][0]) * (t[2][1] - t[0][1]) - (y - t[0][1]) * (t[2][0] - t[0][0])) / area;
                    let b2 = ((t[1][0] - t[0][0]) * (y - t[0][1]) - (t[1][1] - t[0][1]) * (x - t[0][0])) / area;
                    let b0 = 1.0 - b1 - b2;
                    if b0 < -1e-9 || b1 < -1e-9 || b2 < -1e-9 {
                        continue;
                    }
                    let k = j * size + i;
                    if state[k] == 2 {
                        continue;
                    }
                    state[k] = 1;
                    let Some(depth) = depth.as_ref().filter(|_| facing) else { continue };
                    let point = p[0] * b0 + p[1] * b1 + p[2] * b2;
                    let [u, v] = camera.project(&point);
                    if !(u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64) {
                        continue;
                    }
                    let (du, dv) = (((u * fx) as usize).min(rw - 1), ((v * fy) as usize).min(rh - 1));
                    let nearest = depth[dv * rw + du] as f64;
                    if camera.depth(&point) >= nearest - DEPTH_TOLERANCE {
                        state[k] = 2;
                        img.as_bytes_mut()[k * 3..k * 3 + 3].copy_from_slice(&sample(u, v));
                    }
                }
            }
        }
    }
    let stats = TextureStats {
        texels: state.iter().filter(|&&s| s > 0).count(),
        visible: state.iter().filter(|&&s| s == 2).count(),
    };
    for _ in 0..GUTTER {
        let before = state.clone();
        for j in 0..size {
            for i in 0..size {
                if before[j * size + i] != 0 {
                    continue;
                }
                let near = [(0i64, -1i64), (0, 1), (-1, 0), (1, 0)].iter().find_map(|&(di, dj)| {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    (a >= 0
                        && b >= 0
                        && a < size as i64
                        && b < size as i64
                        && before[b as usize * size + a as usize] == 2)
                        .then(|| b as usize * size + a as usize)
                });
                if let Some(src) = near {
                    state[j * size + i] = 2;
                    let c: [u8; 3] = img.as_bytes()[src * 3..src * 3 + 3].try_into().unwrap_or(NEUTRAL);
                    img.as_bytes_mut()[(j * size + i) * 3..(j * size + i) * 3 + 3].copy_from_slice(&c);
                }
            }
        }
    }
    Ok((img, stats))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    /// A unit square facing the camera: the front texels take the sketch's colour; turned away,
    /// none do and the texture is neutral; off-image likewise, and the call still succeeds.
    #[test]
    fn visible_faces_take_the_sketch_colour_and_hidden_ones_stay_neutral() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let quads = [[0, 1, 2, 3]];
        let uvs = FaceUvs { coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], quads: vec![[0, 1, 2, 3]] };
        let sketch = RgbImage::from_vec(64, 64, [200u8, 30, 30].repeat(64 * 64)).unwrap();
        let cam = WeakPerspective { sx: 40.0, sy: 40.0, r: Matrix3::identity(), t: [10.0, 50.0] };
        let (img, stats) = project_sketch(&sketch, &v, &quads, &uvs, &cam, 16).unwrap();
        assert_eq!(stats.texels, 256);
        assert_eq!(stats.visible, 256);
        assert_eq!(&img.as_bytes()[..3], &[200, 30, 30]);
        let back = WeakPerspective {
            r: *nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), std::f64::consts::PI).matrix(),
            t: [50.0, 50.0],
            ..cam
        };
        let (img, stats) = project_sketch(&sketch, &v, &quads, &uvs, &back, 16).unwrap();
        assert_eq!(stats.visible, 0);
        assert!(img.as_bytes().chunks(3).all(|p| p == NEUTRAL));
        let away = WeakPerspective { t: [-500.0, 50.0], ..cam };
        assert_eq!(project_sketch(&sketch, &v, &quads, &uvs, &away, 16).unwrap().1.visible, 0);
        assert!(project_sketch(&sketch, &v, &quads, &uvs, &cam, 0).is_err());
        assert!(crate::image::encode_png(&img.view()).unwrap().starts_with(b"\x89PNG"));
    }

    /// Each texel takes the sketch's colour, bilinearly sampled, at the pixel its surface point
    /// projects to: on a sketch whose red and green channels grow with the column and the row,
    /// the texel's colour gives back the point's pixel.
    #[test]
    fn texels_take_the_sketch_colour_where_their_point_projects() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let uvs = FaceUvs { coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], quads: vec![[0, 1, 2, 3]] };
        let pixels: Vec<u8> = (0..64 * 64).flat_map(|k| [(k % 64 * 3) as u8, (k / 64 * 3) as u8, 7]).collect();
        let sketch = RgbImage::from_vec(64, 64, pixels).unwrap();
        let cam = WeakPerspective { sx: 40.0, sy: 40.0, r: Matrix3::identity(), t: [10.0, 50.0] };
        let size = 16;
        let (img, stats) = project_sketch(&sketch, &v, &[[0, 1, 2, 3]], &uvs, &cam, size).unwrap();
        assert_eq!(stats.visible, size * size);
        for j in 0..size {
            for i in 0..size {
                // The texel's point: model x = u, y = v (row 0 is v = 1); its pixel (u, v).
                let (x, y) = ((i as f64 + 0.5) / size as f64, 1.0 - (j as f64 + 0.5) / size as f64);
                let [pu, pv] = cam.project(&Vector3::new(x, y, 0.0));
                // Pixel centres at +0.5: the bilinear value at pu is 3 (pu − 0.5).
                let want = [3.0 * (pu - 0.5), 3.0 * (pv - 0.5), 7.0];
                let got = &img.as_bytes()[(j * size + i) * 3..(j * size + i) * 3 + 3];
                for c in 0..3 {
                    assert!((got[c] as f64 - want[c]).abs() <= 0.5 + 1e-9, "texel ({i}, {j}): {got:?} vs {want:?}");
                }
            }
        }
    }

    /// Only texels whose centre lies inside a UV triangle are textured: on a triangle with no
    /// edge along the texture's axes, the texels of its bounding box beyond each edge are not
    /// counted (a three-corner quad is one triangle).
    #[test]
    fn only_texels_inside_a_uv_triangle_count() {
        let corners = [[0.5f32, 0.0], [1.0, 0.7], [0.0, 1.0]];
        let v: Vec<[f32; 3]> = corners.iter().map(|c| [c[0], c[1], 0.0]).collect();
        let uvs = FaceUvs { coords: corners.to_vec(), quads: vec![[0, 1, 2, 2]] };
        let sketch = RgbImage::from_vec(64, 64, [200u8, 30, 30].repeat(64 * 64)).unwrap();
        let cam = WeakPerspective { sx: 40.0, sy: 40.0, r: Matrix3::identity(), t: [10.0, 50.0] };
        let size = 16;
        let (_, stats) = project_sketch(&sketch, &v, &[[0, 1, 2, 2]], &uvs, &cam, size).unwrap();
        // The texel centres on the inner side of all three edges (counter-clockwise corners; two
        // centres lie on the first edge and count).
        let c = corners.map(|c| [c[0] as f64, c[1] as f64]);
        let side =
            |a: [f64; 2], b: [f64; 2], p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let inside = (0..size * size)
            .filter(|k| {
                let p = [(k % size) as f64 + 0.5, size as f64 - (k / size) as f64 - 0.5].map(|x| x / size as f64);
                [(0, 1), (1, 2), (2, 0)].iter().all(|&(a, b)| side(c[a], c[b], p) >= -1e-9)
            })
            .count();
        assert!(inside > 60 && inside < 160, "{inside}");
        assert_eq!(stats, TextureStats { texels: inside, visible: inside });
    }

    /// A face seen exactly edge-on (its normal across the view) does not face the camera: its
    /// texels count but stay neutral, even where nothing else covers its pixels.
    #[test]
    fn faces_seen_edge_on_stay_neutral() {
        // A facing square (texture's left half) and a square in the plane y = 1.1 (right half),
        // which projects onto the sketch's row 6, above the first.
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 1.1, 0.0],
            [1.0, 1.1, 0.0],
            [1.0, 1.1, 1.0],
            [0.0, 1.1, 1.0f32],
        ];
        let coords =
            vec![[0.0, 0.0], [0.5, 0.0], [0.5, 1.0], [0.0, 1.0], [0.5, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 1.0]];
        let uvs = FaceUvs { coords, quads: vec![[0, 1, 2, 3], [4, 5, 6, 7]] };
        let sketch = RgbImage::from_vec(64, 64, [200u8, 30, 30].repeat(64 * 64)).unwrap();
        let cam = WeakPerspective { sx: 40.0, sy: 40.0, r: Matrix3::identity(), t: [10.0, 50.0] };
        let (_, stats) = project_sketch(&sketch, &v, &[[0, 1, 2, 3], [4, 5, 6, 7]], &uvs, &cam, 16).unwrap();
        assert_eq!(stats, TextureStats { texels: 256, visible: 128 });
    }

    /// Visible texels grow by exactly [`GUTTER`] texels (4-neighbour steps) into the unused space
    /// around their UV island, on every side, with the island's colour; texels further away and
    /// the statistics (which count the island only) are untouched.
    #[test]
    fn the_gutter_grows_islands_by_two_texels_on_every_side() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        // The island: texels 4..12 of a 16-texel texture in both directions.
        let coords = vec![[0.25, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75]];
        let uvs = FaceUvs { coords, quads: vec![[0, 1, 2, 3]] };
        let sketch = RgbImage::from_vec(64, 64, [200u8, 30, 30].repeat(64 * 64)).unwrap();
        let cam = WeakPerspective { sx: 40.0, sy: 40.0, r: Matrix3::identity(), t: [10.0, 50.0] };
        let (img, stats) = project_sketch(&sketch, &v, &[[0, 1, 2, 3]], &uvs, &cam, 16).unwrap();
        assert_eq!(stats, TextureStats { texels: 64, visible: 64 });
        for j in 0..16i64 {
            for i in 0..16i64 {
                // 4-neighbour steps from the island [4, 12)²: the Manhattan distance.
                let out = |k: i64| (4 - k).max(k - 11).max(0);
                let steps = out(i) + out(j);
                let want = if steps <= GUTTER as i64 { [200, 30, 30] } else { NEUTRAL };
                let k = (j * 16 + i) as usize;
                assert_eq!(&img.as_bytes()[k * 3..k * 3 + 3], &want, "texel ({i}, {j}), {steps} steps out");
            }
        }
    }

    /// Issue 52 finding 1: a sketch wider than the rasteriser's 4096 px is textured (it failed
    /// with "raster size is out of range"), and occlusion is still decided on the depth raster
    /// scaled down to [`depth_side`] (here 1024 px, an eighth of the sketch): a square half
    /// hidden behind a nearer one gives the same visible texels as on a small sketch, to one
    /// texel row along the hidden edge.
    #[test]
    fn sketches_above_the_raster_side_are_textured_with_occlusion() {
        // Square A at z = 0 (texture's left half), square B at z = 0.5 over A's left half
        // (texture's right half).
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 0.5],
            [0.5, 0.0, 0.5],
            [0.5, 1.0, 0.5],
            [0.0, 1.0, 0.5f32],
        ];
        let quads = [[0, 1, 2, 3], [4, 5, 6, 7]];
        let coords =
            vec![[0.0, 0.0], [0.5, 0.0], [0.5, 1.0], [0.0, 1.0], [0.5, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 1.0]];
        let uvs = FaceUvs { coords, quads: vec![[0, 1, 2, 3], [4, 5, 6, 7]] };
        let cam = WeakPerspective { sx: 40.0, sy: 40.0, r: Matrix3::identity(), t: [10.0, 50.0] };
        let small = RgbImage::from_vec(64, 64, [200u8, 30, 30].repeat(64 * 64)).unwrap();
        let wide = RgbImage::from_vec(8200, 64, [200u8, 30, 30].repeat(8200 * 64)).unwrap();
        let (_, s) = project_sketch(&small, &v, &quads, &uvs, &cam, 32).unwrap();
        let (img, w) = project_sketch(&wide, &v, &quads, &uvs, &cam, 32).unwrap();
        assert_eq!(s.texels, 32 * 32);
        assert!(s.visible > 700 && s.visible < 800, "B whole, half of A: {}", s.visible);
        assert!(w.visible.abs_diff(s.visible) <= 32, "wide {} vs small {}", w.visible, s.visible);
        assert_eq!((depth_side(32), depth_side(1024), depth_side(4096)), (MIN_DEPTH_SIDE, 2048, MAX_RASTER_SIDE));
        let red = img.as_bytes().chunks(3).filter(|p| *p == [200, 30, 30]).count();
        assert_eq!(red, w.visible);
    }
}
