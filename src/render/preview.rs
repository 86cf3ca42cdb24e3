//! Preview images: a mesh shaded (z-buffer + two-sided Lambert, flat per triangle) from the
//! front and from its right side, side by side in one RGB PNG, so people can look at results;
//! and [`compare_preview`], which puts the posed body seen through the estimated camera beside
//! and over the sketch, then the front and side views.

use std::path::Path;

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::raster::{check_size, scan, setup, GUARD_BAND, SUB};

/// An RGB image, rows of `width * 3` bytes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbImage {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Interleaved R, G, B bytes, row-major, no padding.
    pub data: Vec<u8>,
}

const BACKGROUND: [u8; 3] = [236, 238, 242];
const BASE: [f32; 3] = [205.0, 180.0, 165.0];

/// One view of `vertices`/`tris` (metres, model frame) seen through rotation `r` (model →
/// camera, orthographic along −Z of the camera), fitted into a `size`×`size` tile with a 5%
/// margin, written into `img` at column offset `x0`.
fn draw_view(img: &mut RgbImage, x0: usize, size: usize, vertices: &[[f32; 3]], tris: &[[u32; 3]], r: &Matrix3<f64>) {
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
    let light = Vector3::new(-0.4, 0.5, 1.0).normalize();
    let mut depth = vec![f32::NEG_INFINITY; size * size];
    for t in tris {
        let [a, b, c] = t.map(|i| i as usize);
        let n = (cam[b] - cam[a]).cross(&(cam[c] - cam[a]));
        if n.norm() < 1e-20 {
            continue;
        }
        let shade = 0.3 + 0.7 * (n.normalize().dot(&light)).abs() as f32;
        let rgb = BASE.map(|c| (c * shade).min(255.0) as u8);
        let z = [cam[a].z as f32, cam[b].z as f32, cam[c].z as f32];
        let Some(s) = setup([px[a], px[b], px[c]], z, size, size, true) else { continue };
        scan(&s, size, |idx, i, j, d| {
            if d > depth[idx] {
                depth[idx] = d;
                let o = (j * img.width + x0 + i) * 3;
                img.data[o..o + 3].copy_from_slice(&rgb);
            }
        });
    }
}

/// Front and right-side views of a mesh, each `size`×`size` pixels (1..=4096), side by side.
/// Errors: bad size, no triangles, out-of-range indices, non-finite vertices.
pub fn preview(vertices: &[[f32; 3]], tris: &[[u32; 3]], size: usize) -> Result<RgbImage> {
    check_size(size, size)?;
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
    let mut img = RgbImage { width: 2 * size, height: size, data: BACKGROUND.repeat(2 * size * size) };
    draw_view(&mut img, 0, size, vertices, tris, &Matrix3::identity());
    // The character's right side (−X) faces the viewer: turn the model 90° about +Y.
    let side = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2).into_inner();
    draw_view(&mut img, size, size, vertices, tris, &side);
    Ok(img)
}

/// The body shaded through `camera` on a `w`×`h` canvas (the sketch's pixels): colour per pixel,
/// `None` where the body does not cover.
fn camera_view(
    vertices: &[[f32; 3]],
    tris: &[[u32; 3]],
    camera: &WeakPerspective,
    w: usize,
    h: usize,
) -> Vec<Option<[u8; 3]>> {
    let cam: Vec<Vector3<f64>> =
        vertices.iter().map(|v| camera.r * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64)).collect();
    let px: Vec<[i64; 2]> = cam
        .iter()
        .map(|p| {
            let u = (camera.sx * p.x + camera.t[0]).clamp(-GUARD_BAND, GUARD_BAND);
            let v = (-camera.sy * p.y + camera.t[1]).clamp(-GUARD_BAND, GUARD_BAND);
            [(u * SUB as f64).round() as i64, (v * SUB as f64).round() as i64]
        })
        .collect();
    let light = Vector3::new(-0.4, 0.5, 1.0).normalize();
    let mut depth = vec![f32::NEG_INFINITY; w * h];
    let mut out = vec![None; w * h];
    for t in tris {
        let [a, b, c] = t.map(|i| i as usize);
        let n = (cam[b] - cam[a]).cross(&(cam[c] - cam[a]));
        if n.norm() < 1e-20 {
            continue;
        }
        let shade = 0.3 + 0.7 * (n.normalize().dot(&light)).abs() as f32;
        let rgb = BASE.map(|c| (c * shade).min(255.0) as u8);
        let z = [cam[a].z as f32, cam[b].z as f32, cam[c].z as f32];
        let Some(s) = setup([px[a], px[b], px[c]], z, w, h, true) else { continue };
        scan(&s, w, |idx, _, _, d| {
            if d > depth[idx] {
                depth[idx] = d;
                out[idx] = Some(rgb);
            }
        });
    }
    out
}

/// What an artist compares: four panels `size` pixels high, left to right — the sketch, the
/// posed body through the estimated `camera` (same framing as the sketch), the body blended
/// half over the sketch, then the body's front and right side ([`preview`]). The first three
/// are the sketch's aspect ratio, scaled to `size` pixels high. Errors: [`preview`]'s, a camera
/// that is not a rotation, a canvas over 4096 pixels wide.
pub fn compare_preview(
    sketch: &crate::image::RgbImage,
    vertices: &[[f32; 3]],
    tris: &[[u32; 3]],
    camera: &WeakPerspective,
    size: usize,
) -> Result<RgbImage> {
    let views = preview(vertices, tris, size)?;
    camera.validate()?;
    let (sw, sh) = (sketch.width(), sketch.height());
    let body = camera_view(vertices, tris, camera, sw, sh);
    let tile = ((size as f64 * sw as f64 / sh as f64).round() as usize).max(1);
    let width = 3 * tile + views.width;
    check_size(width, size)?;
    let mut img = RgbImage { width, height: size, data: BACKGROUND.repeat(width * size) };
    let pix = sketch.as_bytes();
    for j in 0..size {
        let y = ((j as f64 + 0.5) * sh as f64 / size as f64) as usize;
        for i in 0..tile {
            let x = ((i as f64 + 0.5) * sw as f64 / tile as f64) as usize;
            let (x, y) = (x.min(sw - 1), y.min(sh - 1));
            let s: [u8; 3] = [pix[(y * sw + x) * 3], pix[(y * sw + x) * 3 + 1], pix[(y * sw + x) * 3 + 2]];
            let b = body[y * sw + x];
            let blend = b.map_or(s, |b| [0, 1, 2].map(|c| ((s[c] as u16 + b[c] as u16) / 2) as u8));
            for (k, rgb) in [s, b.unwrap_or(BACKGROUND), blend].iter().enumerate() {
                let o = (j * width + k * tile + i) * 3;
                img.data[o..o + 3].copy_from_slice(rgb);
            }
        }
        let o = (j * width + 3 * tile) * 3;
        img.data[o..o + views.width * 3].copy_from_slice(&views.data[j * views.width * 3..(j + 1) * views.width * 3]);
    }
    Ok(img)
}

/// Encodes an RGB image as PNG and writes it to `path` atomically.
pub fn save_rgb_png(img: &RgbImage, path: &Path) -> Result<()> {
    let mut bytes = Vec::new();
    let enc = image::codecs::png::PngEncoder::new(&mut bytes);
    image::ImageEncoder::write_image(
        enc,
        &img.data,
        img.width as u32,
        img.height as u32,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| Error::Io { path: path.to_path_buf(), source: std::io::Error::other(e.to_string()) })?;
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::procedural::{capsule_humanoid, rest_joints};

    #[test]
    fn front_and_side_views_show_the_body_shaded() {
        let m = capsule_humanoid(&rest_joints(), 10, 8);
        let img = preview(&m.vertices, &m.triangles(), 128).unwrap();
        assert_eq!(img.data.len(), 256 * 128 * 3);
        let covered = |x0: usize| {
            (0..128 * 128).filter(|&k| img.data[((k / 128) * 256 + x0 + k % 128) * 3..][..3] != BACKGROUND).count()
        };
        let (front, side) = (covered(0), covered(128));
        // The A-pose is wider from the front than from the side.
        assert!(front > side && side > 500, "front {front}, side {side}");
        let shades: std::collections::HashSet<u8> = img.data.chunks(3).map(|p| p[0]).collect();
        assert!(shades.len() > 20, "shading should vary");
        assert!(preview(&m.vertices, &[[0, 1, 999_999]], 64).is_err());
        assert!(preview(&m.vertices, &m.triangles(), 0).is_err());
    }

    /// The camera panel shows the body where the camera puts it; the blend mixes both.
    #[test]
    fn compare_preview_shows_the_body_through_the_camera() {
        let m = capsule_humanoid(&rest_joints(), 10, 8);
        let sketch = crate::image::RgbImage::from_vec(100, 200, vec![255; 100 * 200 * 3]).unwrap();
        let cam = WeakPerspective { sx: 80.0, sy: 80.0, r: Matrix3::identity(), t: [50.0, 100.0] };
        let img = compare_preview(&sketch, &m.vertices, &m.triangles(), &cam, 64).unwrap();
        assert_eq!((img.width, img.height), (3 * 32 + 128, 64));
        let at = |i: usize, j: usize| img.data[(j * img.width + i) * 3..][..3].to_vec();
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
}
