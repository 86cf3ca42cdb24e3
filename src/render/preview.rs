//! Preview images: a mesh shaded (z-buffer + two-sided Lambert, flat per triangle) from the
//! front and from its right side, side by side in one RGB PNG, so people can look at results;
//! and [`compare_preview`], which puts the posed body seen through the estimated camera beside
//! and over the sketch, then the front and side views.

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::body::rig::FaceUvs;
use crate::camera::WeakPerspective;
use crate::error::{Error, Result, MAX_IMAGE_SIDE};
use crate::image::RgbImage;
use crate::raster::{check_size, scan, setup, GUARD_BAND, MAX_RASTER_SIDE, SUB};

const BACKGROUND: [u8; 3] = [236, 238, 242];
const BASE: [f32; 3] = [205.0, 180.0, 165.0];

/// A base-colour texture laid over a triangle list, so the preview shows what an export's
/// material shows. Borrows the image; owns the per-corner UVs.
#[derive(Clone, Debug)]
pub struct SurfaceTexture<'a> {
    image: &'a RgbImage,
    /// (u, v) of each triangle's three corners, v up (row 0 of `image` is v = 1).
    corners: Vec<[[f32; 2]; 3]>,
}

impl<'a> SurfaceTexture<'a> {
    /// The texture of a quad mesh with per-corner `uvs`, for the triangles
    /// [`quads_to_triangles`](crate::body::rig::quads_to_triangles) makes of `quads`, in that order.
    /// Errors: UV faces that do not match the quads or index past the UV list.
    pub fn for_quads(image: &'a RgbImage, quads: &[[u32; 4]], uvs: &FaceUvs) -> Result<Self> {
        let m = uvs.coords.len();
        if uvs.quads.len() != quads.len() || uvs.quads.iter().flatten().any(|&i| i as usize >= m) {
            return Err(Error::OutOfRange {
                name: "texture UVs",
                detail: format!("{} UV faces over {m} coordinates for {} quads", uvs.quads.len(), quads.len()),
            });
        }
        let uv = |k: u32| uvs.coords[k as usize];
        let mut corners = Vec::with_capacity(2 * quads.len());
        // The same split as `quads_to_triangles`, decided on the position indices.
        for (q, t) in quads.iter().zip(&uvs.quads) {
            corners.push([uv(t[0]), uv(t[1]), uv(t[2])]);
            if q[3] != q[2] && q[3] != q[0] {
                corners.push([uv(t[0]), uv(t[2]), uv(t[3])]);
            }
        }
        Ok(Self { image, corners })
    }

    /// Triangles this texture covers.
    pub fn triangles(&self) -> usize {
        self.corners.len()
    }

    /// The texel (nearest) at barycentric weights `w` of triangle `t`.
    fn texel(&self, t: usize, w: [f64; 3]) -> [f32; 3] {
        let c = &self.corners[t];
        let u = w[0] * c[0][0] as f64 + w[1] * c[1][0] as f64 + w[2] * c[2][0] as f64;
        let v = w[0] * c[0][1] as f64 + w[1] * c[1][1] as f64 + w[2] * c[2][1] as f64;
        let (iw, ih) = (self.image.width(), self.image.height());
        let x = ((u * iw as f64).floor().max(0.0) as usize).min(iw - 1);
        let y = (((1.0 - v) * ih as f64).floor().max(0.0) as usize).min(ih - 1);
        let o = (y * iw + x) * 3;
        [0, 1, 2].map(|k| self.image.as_bytes()[o + k] as f32)
    }
}

/// Barycentric weights of point `p` in triangle `t` (either orientation), clamped into the
/// triangle so pixel centres just outside a snapped edge still read a texel of this face.
fn barycentric(t: [[f64; 2]; 3], p: [f64; 2]) -> [f64; 3] {
    let (ab, ac, ap) = (
        [t[1][0] - t[0][0], t[1][1] - t[0][1]],
        [t[2][0] - t[0][0], t[2][1] - t[0][1]],
        [p[0] - t[0][0], p[1] - t[0][1]],
    );
    let d = ab[0] * ac[1] - ab[1] * ac[0];
    if d == 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let wb = ((ap[0] * ac[1] - ap[1] * ac[0]) / d).clamp(0.0, 1.0);
    let wc = ((ab[0] * ap[1] - ab[1] * ap[0]) / d).clamp(0.0, 1.0);
    let s = wb + wc;
    let (wb, wc) = if s > 1.0 { (wb / s, wc / s) } else { (wb, wc) };
    [1.0 - wb - wc, wb, wc]
}

/// Draws `tris` of the camera-frame points `cam`, projected to fixed-point pixels `px` (1/SUB
/// px) of a `w`×`h` canvas, calling `put(pixel_index, x, y, rgb)` for each pixel where a
/// triangle is nearest: two-sided Lambert shading of the plain skin colour, or of `texture`'s
/// texel when given.
fn shade_triangles(
    cam: &[Vector3<f64>],
    px: &[[i64; 2]],
    tris: &[[u32; 3]],
    texture: Option<&SurfaceTexture>,
    (w, h): (usize, usize),
    mut put: impl FnMut(usize, usize, usize, [u8; 3]),
) {
    let light = Vector3::new(-0.4, 0.5, 1.0).normalize();
    let mut depth = vec![f32::NEG_INFINITY; w * h];
    for (t, tri) in tris.iter().enumerate() {
        let [a, b, c] = tri.map(|i| i as usize);
        let n = (cam[b] - cam[a]).cross(&(cam[c] - cam[a]));
        if n.norm() < 1e-20 {
            continue;
        }
        let lambert = (n.normalize().dot(&light)).abs() as f32;
        let z = [cam[a].z as f32, cam[b].z as f32, cam[c].z as f32];
        let Some(s) = setup([px[a], px[b], px[c]], z, w, h, true) else { continue };
        let corners = [a, b, c].map(|k| [px[k][0] as f64, px[k][1] as f64]);
        scan(&s, w, |idx, i, j, d| {
            if d > depth[idx] {
                depth[idx] = d;
                let rgb = match texture {
                    None => BASE.map(|c| (c * (0.3 + 0.7 * lambert)).min(255.0) as u8),
                    Some(tex) => {
                        let p = [(i as f64 + 0.5) * SUB as f64, (j as f64 + 0.5) * SUB as f64];
                        let texel = tex.texel(t, barycentric(corners, p));
                        texel.map(|c| (c * (0.55 + 0.45 * lambert)).min(255.0) as u8)
                    }
                };
                put(idx, i, j, rgb);
            }
        });
    }
}

/// One view of `vertices`/`tris` (metres, model frame) seen through rotation `r` (model →
/// camera, orthographic along −Z of the camera), fitted into a `size`×`size` tile with a 5%
/// margin, written into `img` at column offset `x0`.
fn draw_view(
    img: &mut RgbImage,
    x0: usize,
    size: usize,
    vertices: &[[f32; 3]],
    tris: &[[u32; 3]],
    texture: Option<&SurfaceTexture>,
    r: &Matrix3<f64>,
) {
    let cam: Vec<Vector3<f64>> =
        vertices.iter().map(|v| r * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64)).collect();
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for p in &cam {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let extent = (hi.x - lo.x).max(hi.y - lo.y).max(1e-9);
    let scale = 0.9 * size as f64 / extent;
    let (cx, cy) = ((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0);
    let px: Vec<[i64; 2]> = cam
        .iter()
        .map(|p| {
            let u = (p.x - cx) * scale + size as f64 / 2.0;
            let v = -(p.y - cy) * scale + size as f64 / 2.0;
            [(u * SUB as f64).round() as i64, (v * SUB as f64).round() as i64]
        })
        .collect();
    let width = img.width();
    shade_triangles(&cam, &px, tris, texture, (size, size), |_, i, j, rgb| {
        let o = (j * width + x0 + i) * 3;
        img.as_bytes_mut()[o..o + 3].copy_from_slice(&rgb);
    });
}

/// Front and right-side views of a mesh, each `size`×`size` pixels (1..=4096), side by side.
/// Errors: bad size, no triangles, out-of-range indices, non-finite vertices.
pub fn preview(vertices: &[[f32; 3]], tris: &[[u32; 3]], size: usize) -> Result<RgbImage> {
    preview_textured(vertices, tris, None, size)
}

/// [`preview`] with the surface shaded by `texture` (one UV triangle per entry of `tris`) when
/// given. Errors: [`preview`]'s, a texture for another number of triangles.
pub fn preview_textured(
    vertices: &[[f32; 3]],
    tris: &[[u32; 3]],
    texture: Option<&SurfaceTexture>,
    size: usize,
) -> Result<RgbImage> {
    check_size(size, size)?;
    if let Some(tex) = texture {
        if tex.triangles() != tris.len() {
            return Err(Error::OutOfRange {
                name: "texture",
                detail: format!("UVs for {} triangles, the mesh has {}", tex.triangles(), tris.len()),
            });
        }
    }
    if tris.is_empty() {
        return Err(Error::OutOfRange { name: "triangles", detail: "no triangles to draw".into() });
    }
    let n = vertices.len();
    if let Some(t) = tris.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err(Error::OutOfRange {
            name: "triangle index",
            detail: format!("triangle {t} indexes a vertex >= {n}"),
        });
    }
    if let Some(v) = vertices.iter().flatten().find(|c| !c.is_finite()) {
        return Err(Error::NonFinite { name: "mesh vertex", value: *v as f64 });
    }
    let mut img = RgbImage::filled(2 * size, size, BACKGROUND)?;
    draw_view(&mut img, 0, size, vertices, tris, texture, &Matrix3::identity());
    // The character's right side (−X) faces the viewer: turn the model 90° about +Y.
    let side = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2).into_inner();
    draw_view(&mut img, size, size, vertices, tris, texture, &side);
    Ok(img)
}

/// The body shaded through `camera` (the sketch's pixels, a `sw`×`sh` sketch) on a `w`×`h`
/// canvas covering the whole sketch: colour per pixel, `None` where the body does not cover.
fn camera_view(
    vertices: &[[f32; 3]],
    tris: &[[u32; 3]],
    texture: Option<&SurfaceTexture>,
    camera: &WeakPerspective,
    (sw, sh): (usize, usize),
    w: usize,
    h: usize,
) -> Vec<Option<[u8; 3]>> {
    let (fx, fy) = (w as f64 / sw as f64, h as f64 / sh as f64);
    let cam: Vec<Vector3<f64>> =
        vertices.iter().map(|v| camera.r * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64)).collect();
    let px: Vec<[i64; 2]> = cam
        .iter()
        .map(|p| {
            let u = ((camera.sx * p.x + camera.t[0]) * fx).clamp(-GUARD_BAND, GUARD_BAND);
            let v = ((-camera.sy * p.y + camera.t[1]) * fy).clamp(-GUARD_BAND, GUARD_BAND);
            [(u * SUB as f64).round() as i64, (v * SUB as f64).round() as i64]
        })
        .collect();
    let mut out = vec![None; w * h];
    shade_triangles(&cam, &px, tris, texture, (w, h), |idx, _, _, rgb| out[idx] = Some(rgb));
    out
}

/// Largest width of a [`compare_preview`], pixels: the library's image side limit, so the
/// preview can be read back by its own loaders.
pub const MAX_COMPARE_WIDTH: usize = MAX_IMAGE_SIDE;

/// The size of a [`compare_preview`] of a `sw`×`sh` sketch asked for `size` pixels high:
/// `(height, tile)`, the panels' height and the width of each of the three sketch-framed
/// panels. The height is `size`, lowered when needed so that every panel fits the rasteriser
/// ([`MAX_RASTER_SIDE`] a side) and the whole preview ([`MAX_COMPARE_WIDTH`]); so any `size` in
/// 1..=16384 and any sketch the library loads gives a preview, smaller when it must be. Cheap:
/// callers check their options with it before the work. Errors ([`Error::OutOfRange`]): `size`
/// 0 or above [`MAX_IMAGE_SIDE`], an empty sketch, a sketch so elongated that even 1 px high
/// panels are too wide.
pub fn compare_layout(sw: usize, sh: usize, size: usize) -> Result<(usize, usize)> {
    let bad = |detail: String| Error::OutOfRange { name: "preview size", detail };
    if size == 0 || size > MAX_IMAGE_SIDE {
        return Err(bad(format!("{size}: expected 1..={MAX_IMAGE_SIDE}")));
    }
    if sw == 0 || sh == 0 {
        return Err(Error::EmptyImage { width: sw, height: sh });
    }
    let tile = |h: usize| ((h as f64 * sw as f64 / sh as f64).round() as usize).max(1);
    let fits = |h: usize| tile(h) <= MAX_RASTER_SIDE && 3 * tile(h) + 2 * h <= MAX_COMPARE_WIDTH;
    let aspect = sw as f64 / sh as f64;
    let mut h = size
        .min(MAX_RASTER_SIDE)
        .min((MAX_COMPARE_WIDTH as f64 / (3.0 * aspect + 2.0)).floor() as usize + 1)
        .min((MAX_RASTER_SIDE as f64 / aspect).floor() as usize + 1)
        .max(1);
    while h > 1 && !fits(h) {
        h -= 1;
    }
    if !fits(h) {
        return Err(bad(format!("a {sw}x{sh} sketch gives panels too wide for a {MAX_COMPARE_WIDTH} px preview")));
    }
    Ok((h, tile(h)))
}

/// What an artist compares: four panels side by side, left to right — the sketch, the posed
/// body through the estimated `camera` (same framing as the sketch), the body blended half
/// over the sketch, then the body's front and right side ([`preview`]). The first three are
/// the sketch's aspect ratio. The panels are `size` pixels high, or less when the preview would
/// not fit otherwise ([`compare_layout`]). With `texture` (the export's base colour, one UV
/// triangle per entry of `tris`) every body panel shows it. Errors: [`compare_layout`]'s,
/// [`preview_textured`]'s, a camera that is not a rotation.
pub fn compare_preview(
    sketch: &RgbImage,
    vertices: &[[f32; 3]],
    tris: &[[u32; 3]],
    texture: Option<&SurfaceTexture>,
    camera: &WeakPerspective,
    size: usize,
) -> Result<RgbImage> {
    let (sw, sh) = (sketch.width(), sketch.height());
    let (size, tile) = compare_layout(sw, sh, size)?;
    let views = preview_textured(vertices, tris, texture, size)?;
    camera.validate()?;
    let body = camera_view(vertices, tris, texture, camera, (sw, sh), tile, size);
    let width = 3 * tile + views.width();
    let mut img = RgbImage::filled(width, size, BACKGROUND)?;
    let pix = sketch.as_bytes();
    for j in 0..size {
        let y = (((j as f64 + 0.5) * sh as f64 / size as f64) as usize).min(sh - 1);
        for i in 0..tile {
            let x = (((i as f64 + 0.5) * sw as f64 / tile as f64) as usize).min(sw - 1);
            let s: [u8; 3] = [pix[(y * sw + x) * 3], pix[(y * sw + x) * 3 + 1], pix[(y * sw + x) * 3 + 2]];
            let b = body[j * tile + i];
            let blend = b.map_or(s, |b| [0, 1, 2].map(|c| ((s[c] as u16 + b[c] as u16) / 2) as u8));
            for (k, rgb) in [s, b.unwrap_or(BACKGROUND), blend].iter().enumerate() {
                let o = (j * width + k * tile + i) * 3;
                img.as_bytes_mut()[o..o + 3].copy_from_slice(rgb);
            }
        }
        let o = (j * width + 3 * tile) * 3;
        let vw = views.width() * 3;
        img.as_bytes_mut()[o..o + vw].copy_from_slice(&views.as_bytes()[j * vw..(j + 1) * vw]);
    }
    Ok(img)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::procedural::{capsule_humanoid, rest_joints};

    #[test]
    fn front_and_side_views_show_the_body_shaded() {
        let m = capsule_humanoid(&rest_joints(), 10, 8);
        let img = preview(&m.vertices, &m.triangles(), 128).unwrap();
        assert_eq!(img.as_bytes().len(), 256 * 128 * 3);
        let covered = |x0: usize| {
            (0..128 * 128)
                .filter(|&k| img.as_bytes()[((k / 128) * 256 + x0 + k % 128) * 3..][..3] != BACKGROUND)
                .count()
        };
        let (front, side) = (covered(0), covered(128));
        // The A-pose is wider from the front than from the side.
        assert!(front > side && side > 500, "front {front}, side {side}");
        let shades: std::collections::HashSet<u8> = img.as_bytes().chunks(3).map(|p| p[0]).collect();
        assert!(shades.len() > 20, "shading should vary");
        assert!(preview(&m.vertices, &[[0, 1, 999_999]], 64).is_err());
        assert!(preview(&m.vertices, &m.triangles(), 0).is_err());
    }

    /// The camera panel shows the body where the camera puts it; the blend mixes both.
    #[test]
    fn compare_preview_shows_the_body_through_the_camera() {
        let m = capsule_humanoid(&rest_joints(), 10, 8);
        let sketch = RgbImage::from_vec(100, 200, vec![255; 100 * 200 * 3]).unwrap();
        let cam = WeakPerspective { sx: 80.0, sy: 80.0, r: Matrix3::identity(), t: [50.0, 100.0] };
        let img = compare_preview(&sketch, &m.vertices, &m.triangles(), None, &cam, 64).unwrap();
        assert_eq!((img.width(), img.height()), (3 * 32 + 128, 64));
        let at = |i: usize, j: usize| img.as_bytes()[(j * img.width() + i) * 3..][..3].to_vec();
        // The chest (between the pelvis and the neck) where the camera projects it.
        let j = rest_joints();
        let chest = (Vector3::from(j[1]) + Vector3::from(j[8])) / 2.0;
        let [u, v] = cam.project(&chest);
        let (i, k) = ((u * 32.0 / 100.0) as usize, (v * 64.0 / 200.0) as usize);
        assert_eq!(at(i, k), vec![255, 255, 255], "sketch panel");
        assert_ne!(at(32 + i, k), BACKGROUND.to_vec(), "body at the chest");
        assert_eq!(at(32, 0), BACKGROUND.to_vec(), "no body in the top-left corner");
        let blend = at(64 + i, k);
        assert!(blend[0] > at(32 + i, k)[0] && blend[0] < 255);
    }

    /// A textured square shows the texture's two halves where its UVs put them, shaded but
    /// recognisable; a texture for another triangle count is an error.
    #[test]
    fn textured_preview_shows_the_texture_where_the_uvs_put_it() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0f32]];
        let quads = [[0u32, 1, 2, 3]];
        let uvs = FaceUvs { coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], quads: vec![[0, 1, 2, 3]] };
        // Left half red, right half blue.
        let mut data = Vec::new();
        for _ in 0..8 {
            for x in 0..8 {
                data.extend_from_slice(if x < 4 { &[250, 0, 0] } else { &[0, 0, 250] });
            }
        }
        let tex_img = RgbImage::from_vec(8, 8, data).unwrap();
        let tex = SurfaceTexture::for_quads(&tex_img, &quads, &uvs).unwrap();
        let tris = crate::body::rig::quads_to_triangles(&quads);
        assert_eq!(tex.triangles(), tris.len());
        let img = preview_textured(&v, &tris, Some(&tex), 64).unwrap();
        let at = |i: usize, j: usize| img.as_bytes()[(j * img.width() + i) * 3..][..3].to_vec();
        let (left, right) = (at(16, 32), at(48, 32));
        assert!(left[0] > 100 && left[2] == 0, "left {left:?}");
        assert!(right[2] > 100 && right[0] == 0, "right {right:?}");
        let plain = preview(&v, &tris, 64).unwrap();
        assert_ne!(plain.as_bytes(), img.as_bytes());
        assert!(preview_textured(&v, &tris[..1], Some(&tex), 64).is_err());
        let bad = FaceUvs { coords: uvs.coords.clone(), quads: vec![[0, 1, 2, 9]] };
        assert!(SurfaceTexture::for_quads(&tex_img, &quads, &bad).is_err());
    }

    /// Issue 52 finding 1: every preview size the CLI accepts (1..=16384) and any sketch shape
    /// gives a layout that fits the rasteriser and the preview width, lowered only as far as it
    /// must be; a 2:1 sketch at 512 is unchanged.
    #[test]
    fn compare_layout_fits_every_size_and_shrinks_only_when_it_must() {
        let fits = |sw: usize, sh: usize, h: usize| {
            let t = ((h as f64 * sw as f64 / sh as f64).round() as usize).max(1);
            h <= MAX_RASTER_SIDE && t <= MAX_RASTER_SIDE && 3 * t + 2 * h <= MAX_COMPARE_WIDTH
        };
        assert_eq!(compare_layout(1024, 512, 512).unwrap(), (512, 1024));
        for (sw, sh) in [(512, 512), (4144, 512), (4097, 4097), (16384, 16384), (16384, 64), (64, 16384), (700, 300)] {
            for size in [1, 2, 511, 512, 819, 820, 2048, 4096, 4097, 8192, 16384] {
                let (h, tile) = compare_layout(sw, sh, size).unwrap();
                assert!(h >= 1 && h <= size && fits(sw, sh, h), "{sw}x{sh} at {size}: {h}, {tile}");
                assert!(h == size || !fits(sw, sh, h + 1), "{sw}x{sh} at {size}: {h} could be taller");
            }
        }
        assert!(compare_layout(512, 512, 0).is_err());
        assert!(compare_layout(512, 512, 16385).is_err());
        assert!(compare_layout(16384, 1, 512).is_err(), "even 1 px panels too wide");
    }

    /// Issue 52 finding 1: the previews that failed ("4100x820 exceeds 4096", "4144x512") are
    /// drawn, smaller, with the body where the camera puts it.
    #[test]
    fn wide_sketches_and_large_sizes_give_a_preview() {
        let m = capsule_humanoid(&rest_joints(), 10, 8);
        let sketch = crate::image::RgbImage::from_vec(4144, 512, vec![255; 4144 * 512 * 3]).unwrap();
        let cam = WeakPerspective { sx: 200.0, sy: 200.0, r: Matrix3::identity(), t: [2072.0, 256.0] };
        for size in [512, 820] {
            let img = compare_preview(&sketch, &m.vertices, &m.triangles(), None, &cam, size).unwrap();
            let (h, tile) = compare_layout(4144, 512, size).unwrap();
            assert_eq!((img.width(), img.height()), (3 * tile + 2 * h, h));
            let j = rest_joints();
            let chest = (Vector3::from(j[1]) + Vector3::from(j[8])) / 2.0;
            let [u, v] = cam.project(&chest);
            let (i, k) = ((u * tile as f64 / 4144.0) as usize, (v * h as f64 / 512.0) as usize);
            let at = |i: usize, j: usize| img.as_bytes()[(j * img.width() + i) * 3..][..3].to_vec();
            assert_ne!(at(tile + i, k), BACKGROUND.to_vec(), "body at the chest");
            assert_eq!(at(tile, 0), BACKGROUND.to_vec());
        }
    }
}
