//! The overlay picture of a run: the sketch (gray, lightened) with the fitted body's projected
//! silhouette outline (green), the bones (the character's right side orange, left side blue,
//! centre purple) and the 2-D joints (filled dots; hollow for joints marked missing); on its
//! right, a side-view panel of the 3-D skeleton alone, seen from the viewer's right at the
//! sketch's scale and height, the viewer to the left (a gray arrow at head height points at the
//! figure from the viewer's side), so a limb bent toward or away from the viewer shows at a
//! glance.

use crate::camera::WeakPerspective;
use crate::error::Result;
use crate::error::MAX_IMAGE_SIDE;
use crate::image::GrayImage;
use crate::image::RgbImage;
use crate::raster::{Rasterizer, MAX_RASTER_SIDE};
use crate::skeleton::{joint, Joints2, Joints3, BONES, NUM_JOINTS};

const OUTLINE: [u8; 3] = [20, 170, 60];
const RIGHT: [u8; 3] = [235, 120, 20];
const LEFT: [u8; 3] = [30, 110, 230];
const CENTRE: [u8; 3] = [150, 60, 170];
const JOINT_RIM: [u8; 3] = [20, 20, 20];
const PANEL: [u8; 3] = [248, 248, 244];
const SEPARATOR: [u8; 3] = [90, 90, 90];
const VIEWER: [u8; 3] = [120, 120, 120];

/// Longest side, px, of the sketch part of [`overlay`]'s picture: a larger sketch is drawn
/// shrunk by the smallest whole factor that brings it within (the picture is for looking at; at
/// the sketch's own size a 4096² sketch's overlay would be 6144 × 4096 px and take most of a
/// run's writing time).
pub const MAX_OVERLAY_SIDE: usize = 2048;

/// Width of the side-view panel for a `w` × `h` sketch: half the height, less where the picture
/// would pass [`MAX_IMAGE_SIDE`] (0 for a sketch already that wide: no panel).
pub fn side_panel_width(w: usize, h: usize) -> usize {
    h.div_ceil(2).min(MAX_IMAGE_SIDE.saturating_sub(w))
}

fn side_colour(j: usize) -> [u8; 3] {
    match j {
        joint::R_SHOULDER | joint::R_ELBOW | joint::R_WRIST | joint::R_HIP | joint::R_KNEE | joint::R_ANKLE => RIGHT,
        joint::L_SHOULDER | joint::L_ELBOW | joint::L_WRIST | joint::L_HIP | joint::L_KNEE | joint::L_ANKLE => LEFT,
        _ => CENTRE,
    }
}

fn put(img: &mut RgbImage, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as usize) < img.width() && (y as usize) < img.height() {
        let o = (y as usize * img.width() + x as usize) * 3;
        img.as_bytes_mut()[o..o + 3].copy_from_slice(&c);
    }
}

fn disc(img: &mut RgbImage, cx: f64, cy: f64, r: f64, c: [u8; 3]) {
    let ri = r.ceil() as i64;
    for dy in -ri..=ri {
        for dx in -ri..=ri {
            if (dx * dx + dy * dy) as f64 <= r * r {
                put(img, cx.floor() as i64 + dx, cy.floor() as i64 + dy, c);
            }
        }
    }
}

fn line(img: &mut RgbImage, a: [f64; 2], b: [f64; 2], half_width: f64, c: [u8; 3]) {
    let steps = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).clamp(1, 100_000);
    for i in 0..=steps {
        let t = i as f64 / steps as f64;
        disc(img, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), half_width, c);
    }
}

/// Draws the overlay of `sketch` (see the module doc), [`side_panel_width`] wider than the
/// sketch: `vertices`/`tris` is the posed mesh (metres, model frame) projected with `camera`
/// (image pixels); `joints` are the 2-D joints; `pose` the 3-D joints (metres, model frame) the
/// side panel draws. Images with a side above the rasteriser's 4096 px get the outline from a
/// scaled raster. A sketch with a side above [`MAX_OVERLAY_SIDE`] is drawn shrunk by a whole
/// factor n (joints and camera divided by n). Errors: an invalid camera or mesh (as
/// [`Rasterizer::rasterize`]); a mesh wholly outside the image draws no outline and is not an
/// error.
pub fn overlay(
    sketch: &GrayImage,
    joints: &Joints2,
    pose: &Joints3,
    vertices: &[[f32; 3]],
    tris: &[[u32; 3]],
    camera: &WeakPerspective,
) -> Result<RgbImage> {
    let n = sketch.width().max(sketch.height()).div_ceil(MAX_OVERLAY_SIDE);
    let shrunk;
    let (sketch, joints, camera) = if n > 1 {
        let k = 1.0 / n as f64;
        let mut small_joints = *joints;
        for p in &mut small_joints.xy {
            *p = [p[0] * k, p[1] * k];
        }
        shrunk = (sketch.box_shrunk(n), small_joints, camera.scaled_image(k));
        (&shrunk.0, &shrunk.1, &shrunk.2)
    } else {
        (sketch, joints, camera)
    };
    let (w, h) = (sketch.width(), sketch.height());
    let pw = side_panel_width(w, h);
    let mut data = vec![0u8; 3 * (w + pw) * h];
    for (row, out) in sketch.as_bytes().chunks_exact(w).zip(data.chunks_exact_mut(3 * (w + pw))) {
        let (ink, panel) = out.split_at_mut(3 * w);
        for (&g, px) in row.iter().zip(ink.chunks_exact_mut(3)) {
            px.fill((128 + g as u16 / 2) as u8);
        }
        for px in panel.chunks_exact_mut(3) {
            px.copy_from_slice(&PANEL);
        }
    }
    let mut img = RgbImage::from_vec(w + pw, h, data)?;
    let f = (MAX_RASTER_SIDE as f64 / w.max(h) as f64).min(1.0);
    let (rw, rh) = (((w as f64 * f).round() as usize).max(1), ((h as f64 * f).round() as usize).max(1));
    let cam = camera.scaled_image(f);
    let mut raster = Rasterizer::new();
    match raster.rasterize(vertices, tris, &cam, rw, rh, false) {
        Ok(_) => {
            let m = raster.mask();
            let inside = |x: usize, y: usize| m[y * rw + x] != 0;
            for y in 0..rh {
                for x in 0..rw {
                    let edge = inside(x, y)
                        && (x == 0
                            || y == 0
                            || x + 1 == rw
                            || y + 1 == rh
                            || !inside(x - 1, y)
                            || !inside(x + 1, y)
                            || !inside(x, y - 1)
                            || !inside(x, y + 1));
                    if edge {
                        let (px, py) = (((x as f64 + 0.5) / f).floor() as i64, ((y as f64 + 0.5) / f).floor() as i64);
                        disc(&mut img, px as f64, py as f64, 0.8 / f.max(0.25), OUTLINE);
                    }
                }
            }
        }
        Err(crate::Error::MeshOutsideImage { .. }) => {}
        Err(e) => return Err(e),
    }
    let scale = (w.min(h) as f64 / 512.0).max(0.5);
    for &(a, b) in &BONES {
        line(&mut img, joints.xy[a], joints.xy[b], 1.2 * scale, side_colour(b));
    }
    for k in 0..NUM_JOINTS {
        let [x, y] = joints.xy[k];
        disc(&mut img, x, y, 4.5 * scale, JOINT_RIM);
        if joints.visible[k] {
            disc(&mut img, x, y, 3.2 * scale, side_colour(k));
        } else {
            disc(&mut img, x, y, 3.2 * scale, [255, 255, 255]);
        }
    }
    if pw > 0 {
        side_panel(&mut img, w, pw, pose, camera, scale);
    }
    Ok(img)
}

/// Draws the side view of `pose` into the panel of `img` that starts at column `x0` and is `pw`
/// wide (module doc): camera-frame height at the sketch's scale and offset, camera-frame depth
/// horizontally (toward the viewer = left), the pelvis in the panel's middle.
fn side_panel(img: &mut RgbImage, x0: usize, pw: usize, pose: &Joints3, camera: &WeakPerspective, scale: f64) {
    let h = img.height();
    for y in 0..h {
        for dx in 0..(2.0 * scale).ceil() as usize {
            put(img, (x0 + dx) as i64, y as i64, SEPARATOR);
        }
    }
    let y: [nalgebra::Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| camera.r * nalgebra::Vector3::from(pose[j]));
    let s = 0.5 * (camera.sx + camera.sy);
    let cx = x0 as f64 + 0.5 * pw as f64;
    let at = |j: usize| [cx - s * (y[j].z - y[joint::PELVIS].z), -camera.sy * y[j].y + camera.t[1]];
    let head_v = at(joint::HEAD)[1];
    let tip = x0 as f64 + (0.2 * pw as f64).max(12.0 * scale);
    line(img, [x0 as f64 + 6.0 * scale, head_v], [tip, head_v], 1.5 * scale, VIEWER);
    for d in [-1.0, 1.0] {
        line(img, [tip - 6.0 * scale, head_v + d * 5.0 * scale], [tip, head_v], 1.5 * scale, VIEWER);
    }
    for &(a, b) in &BONES {
        line(img, at(a), at(b), 1.2 * scale, side_colour(b));
    }
    for k in 0..NUM_JOINTS {
        let [px, py] = at(k);
        disc(img, px, py, 4.5 * scale, JOINT_RIM);
        disc(img, px, py, 3.2 * scale, side_colour(k));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::procedural::{capsule_humanoid, rest_joints};
    use nalgebra::Matrix3;

    /// A capsule humanoid and its joints projected by `cam`, all visible.
    fn projected_humanoid(cam: &WeakPerspective) -> (crate::body::rig::mesh::RiggedMesh, Joints2) {
        let m = capsule_humanoid(&rest_joints(), 10, 8);
        let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
        for k in 0..NUM_JOINTS {
            j.xy[k] = cam.project(&nalgebra::Vector3::from(m.joints[k]));
        }
        (m, j)
    }

    #[test]
    fn a_large_sketch_is_drawn_shrunk_with_its_joints_in_place() {
        let cam = WeakPerspective { sx: 1200.0, sy: 1200.0, r: Matrix3::identity(), t: [2200.0, 1300.0] };
        let (m, j) = projected_humanoid(&cam);
        let sketch = GrayImage::filled(4400, 2600, 255).unwrap();
        let img = overlay(&sketch, &j, &m.joints, &m.vertices, &m.triangles(), &cam).unwrap();
        // n = 3: 1467 × 867 and a 434 px panel.
        assert_eq!((img.width(), img.height()), (1467 + 434, 867));
        let [hx, hy] = j.xy[joint::HEAD];
        let o = (((hy / 3.0) as usize) * img.width() + (hx / 3.0) as usize) * 3;
        assert_eq!(&img.as_bytes()[o..o + 3], CENTRE);
        let outline = img.as_bytes().chunks(3).filter(|p| *p == OUTLINE).count();
        assert!(outline > 200, "outline {outline}");
    }

    #[test]
    fn outline_bones_and_joints_are_drawn() {
        let cam = WeakPerspective { sx: 120.0, sy: 120.0, r: Matrix3::identity(), t: [128.0, 128.0] };
        let (m, mut j) = projected_humanoid(&cam);
        j.visible[joint::L_WRIST] = false;
        let sketch = GrayImage::filled(256, 256, 255).unwrap();
        let img = overlay(&sketch, &j, &m.joints, &m.vertices, &m.triangles(), &cam).unwrap();
        assert_eq!((img.width(), img.height()), (256 + 128, 256));
        let count = |c: [u8; 3]| img.as_bytes().chunks(3).filter(|p| *p == c).count();
        assert!(count(OUTLINE) > 200, "outline {}", count(OUTLINE));
        assert!(
            count(RIGHT) > 50 && count(LEFT) > 50 && count(CENTRE) > 10,
            "{} {} {}",
            count(RIGHT),
            count(LEFT),
            count(CENTRE)
        );
        let px = |x: f64, y: f64| &img.as_bytes()[((y as usize) * 384 + x as usize) * 3..][..3];
        let [hx, hy] = j.xy[joint::HEAD];
        assert_eq!(px(hx, hy), CENTRE);
        let [wx, wy] = j.xy[joint::L_WRIST];
        assert_eq!(px(wx, wy), [255, 255, 255]);
        // Paper is lightened: white stays white, black ink becomes mid-gray.
        assert_eq!(px(2.0, 2.0), [255, 255, 255]);
        let far = WeakPerspective { t: [1e4, 1e4], ..cam };
        assert!(overlay(&sketch, &j, &m.joints, &m.vertices, &m.triangles(), &far).is_ok());
    }

    /// The panel pixel nearest to the side-view position of joint `k` (module doc).
    fn panel_spot(pose: &Joints3, cam: &WeakPerspective, k: usize, x0: f64, pw: f64) -> (usize, usize) {
        let y = |j: usize| cam.r * nalgebra::Vector3::from(pose[j]);
        let x = x0 + 0.5 * pw - cam.sx * (y(k).z - y(joint::PELVIS).z);
        (x.floor() as usize, (-cam.sy * y(k).y + cam.t[1]).floor() as usize)
    }

    #[test]
    fn the_side_panel_shows_a_knee_bent_toward_the_viewer() {
        let m = capsule_humanoid(&rest_joints(), 10, 8);
        let cam = WeakPerspective { sx: 100.0, sy: 100.0, r: Matrix3::identity(), t: [128.0, 220.0] };
        let mut pose = m.joints;
        pose[joint::R_KNEE][2] += 0.2;
        let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
        for k in 0..NUM_JOINTS {
            j.xy[k] = cam.project(&nalgebra::Vector3::from(pose[k]));
        }
        let sketch = GrayImage::filled(256, 256, 255).unwrap();
        let img = overlay(&sketch, &j, &pose, &m.vertices, &m.triangles(), &cam).unwrap();
        let px = |(x, y): (usize, usize)| &img.as_bytes()[(y * 384 + x) * 3..][..3];
        // The bent knee sits 20 px left of the hip and ankle (toward the viewer), in its colour.
        let (knee, hip, ankle) =
            [joint::R_KNEE, joint::R_HIP, joint::R_ANKLE].map(|k| panel_spot(&pose, &cam, k, 256.0, 128.0)).into();
        assert_eq!(px(knee), RIGHT);
        assert!(knee.0 + 15 < hip.0 && knee.0 + 15 < ankle.0, "knee {knee:?} hip {hip:?} ankle {ankle:?}");
        // The unbent figure has its knee 20 px further right, drawn there (under the left knee,
        // at the same depth), and the panel's paper is its own colour beside the figure.
        let straight = overlay(&sketch, &j, &m.joints, &m.vertices, &m.triangles(), &cam).unwrap();
        let k2 = panel_spot(&m.joints, &cam, joint::R_KNEE, 256.0, 128.0);
        assert!(knee.0 + 15 < k2.0, "{knee:?} {k2:?}");
        assert_eq!(&straight.as_bytes()[(k2.1 * 384 + k2.0) * 3..][..3], LEFT);
        assert_eq!(&straight.as_bytes()[(250 * 384 + 380) * 3..][..3], PANEL);
        // The viewer's arrow points at the figure from the left at head height.
        let (_, head_y) = panel_spot(&pose, &cam, joint::HEAD, 256.0, 128.0);
        assert_eq!(&img.as_bytes()[(head_y * 384 + 256 + 12) * 3..][..3], VIEWER);
    }

    #[test]
    fn the_panel_narrows_to_keep_the_picture_within_the_largest_side() {
        assert_eq!(side_panel_width(512, 512), 256);
        assert_eq!(side_panel_width(512, 511), 256);
        assert_eq!(side_panel_width(16000, 4096), 384);
        assert_eq!(side_panel_width(MAX_IMAGE_SIDE, 4096), 0);
    }
}
