//! The image's tone (issue 51): cheap signs of a photo, or a photo turned into a drawing, as
//! against a line drawing on plain paper. A drawing leaves most of its paper bare and the page
//! around the figure empty; a photo (and a stylised photo) has tones and edges everywhere,
//! its scene included.

use crate::error::Result;
use crate::image::{to_gray, ImageView};
use crate::skeleton::Joints2;

/// A gray level within this of the paper's counts as paper.
pub const PAPER_BAND: u8 = 24;

/// A pixel whose central differences (|dx| + |dy|) reach this is an edge.
pub const EDGE: i32 = 48;

/// The figure's box is the joints' box grown by this fraction of its longer side on each side.
pub const BOX_MARGIN: f64 = 0.2;

/// Under this share of paper ([`ImageTone::paper`]) an image is photo-like.
pub const MIN_DRAWING_PAPER: f64 = 0.75;

/// From this share of edge pixels ([`ImageTone::edges`]) an image is photo-like.
pub const MAX_DRAWING_EDGES: f64 = 0.14;

/// The tone of an image ([`image_tone`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageTone {
    /// The share of pixels within [`PAPER_BAND`] of the paper's gray (the commonest gray
    /// level), in [0, 1].
    pub paper: f64,
    /// The share of pixels neither paper nor dark (gray ≥ 64): tones, in [0, 1].
    pub mid: f64,
    /// The mean colour saturation, (max − min channel) / 255, in [0, 1].
    pub saturation: f64,
    /// The share of edge pixels ([`EDGE`]) in the whole image, in [0, 1].
    pub edges: f64,
    /// The share of edge pixels outside the figure's box ([`BOX_MARGIN`]), in [0, 1]; 0 when
    /// the box covers the image.
    pub edges_outside: f64,
}

impl ImageTone {
    /// Whether the image looks like a photo (or a stylised photo) rather than a drawing: under
    /// [`MIN_DRAWING_PAPER`] of it is bare paper, or [`MAX_DRAWING_EDGES`] or more of it is
    /// edges.
    pub fn photo_like(&self) -> bool {
        self.paper < MIN_DRAWING_PAPER || self.edges >= MAX_DRAWING_EDGES
    }
}

/// The tone of `image` around the figure `j` (its joints' box, grown by [`BOX_MARGIN`]).
/// Errors: as [`to_gray`].
pub fn image_tone(image: &ImageView<'_>, j: &Joints2) -> Result<ImageTone> {
    let (w, h) = (image.width(), image.height());
    let gray = to_gray(image)?.into_vec();
    let paper = paper_level(&gray);
    let bx = figure_box(j, w, h);
    let (mut on_paper, mut mid, mut sat, mut edges, mut out_edges, mut outside) = (0usize, 0usize, 0.0, 0usize, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let g = gray[y * w + x];
            on_paper += usize::from(g.abs_diff(paper) <= PAPER_BAND);
            mid += usize::from(g.abs_diff(paper) > PAPER_BAND && g >= 64);
            sat += saturation_at(image, x, y);
            let edge = is_edge(&gray, w, h, x, y);
            edges += usize::from(edge);
            let out = x < bx[0] || x >= bx[2] || y < bx[1] || y >= bx[3];
            outside += usize::from(out);
            out_edges += usize::from(out && edge);
        }
    }
    let n = (w * h).max(1) as f64;
    Ok(ImageTone {
        paper: on_paper as f64 / n,
        mid: mid as f64 / n,
        saturation: sat / n,
        edges: edges as f64 / n,
        edges_outside: if outside > 0 { out_edges as f64 / outside as f64 } else { 0.0 },
    })
}

/// The paper's gray: the level whose ±4 window holds the most pixels.
fn paper_level(gray: &[u8]) -> u8 {
    let mut hist = [0usize; 256];
    for &g in gray {
        hist[usize::from(g)] += 1;
    }
    let window = |k: usize| hist[k.saturating_sub(4)..(k + 5).min(256)].iter().sum::<usize>();
    (0..=255u8).max_by_key(|&k| (window(usize::from(k)), k)).unwrap_or(255)
}

/// The joints' box grown by [`BOX_MARGIN`], clipped to the image: [x0, y0, x1, y1) in pixels;
/// the whole image when no joint is finite.
fn figure_box(j: &Joints2, w: usize, h: usize) -> [usize; 4] {
    let pts = j.xy.iter().filter(|p| p[0].is_finite() && p[1].is_finite());
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in pts {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if !(lo[0] <= hi[0]) {
        return [0, 0, w, h];
    }
    let m = BOX_MARGIN * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let clip = |v: f64, max: usize| (v.max(0.0) as usize).min(max);
    [clip(lo[0] - m, w), clip(lo[1] - m, h), clip((hi[0] + m).ceil(), w), clip((hi[1] + m).ceil(), h)]
}

/// Whether pixel (`x`, `y`) of the gray plane is an edge ([`EDGE`]); border pixels are not.
fn is_edge(gray: &[u8], w: usize, h: usize, x: usize, y: usize) -> bool {
    if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
        return false;
    }
    let at = |x: usize, y: usize| i32::from(gray[y * w + x]);
    (at(x + 1, y) - at(x - 1, y)).abs() + (at(x, y + 1) - at(x, y - 1)).abs() >= EDGE
}

/// The colour saturation of pixel (`x`, `y`), (max − min channel) / 255; 0 for a gray image.
fn saturation_at(image: &ImageView<'_>, x: usize, y: usize) -> f64 {
    let c = image.channels();
    if c < 3 {
        return 0.0;
    }
    let p = &image.row(y)[x * c..x * c + 3];
    let (mx, mn) = (p.iter().max().copied().unwrap_or(0), p.iter().min().copied().unwrap_or(0));
    f64::from(mx - mn) / 255.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::facing::tests::front;
    use crate::skeleton::{BONES, NUM_JOINTS};

    const W: usize = 400;
    const H: usize = 460;

    /// A line drawing of [`front`]: 2 px black strokes along its bones on white paper.
    fn line_drawing() -> Vec<u8> {
        let j = front();
        let mut px = vec![255u8; W * H];
        for &(a, b) in &BONES {
            let (p, q) = (j.xy[a], j.xy[b]);
            let steps = (q[0] - p[0]).hypot(q[1] - p[1]).ceil() as usize * 2;
            for s in 0..=steps {
                let t = s as f64 / steps.max(1) as f64;
                let (x, y) = ((p[0] + t * (q[0] - p[0])) as usize, (p[1] + t * (q[1] - p[1])) as usize);
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    if x + dx < W && y + dy < H {
                        px[(y + dy) * W + x + dx] = 0;
                    }
                }
            }
        }
        px
    }

    #[test]
    fn a_line_drawing_is_not_photo_like_a_shaded_or_textured_page_is() {
        let j = front();
        let drawing = line_drawing();
        let t = image_tone(&ImageView::gray(&drawing, W, H).unwrap(), &j).unwrap();
        assert!(!t.photo_like(), "{t:?}");
        assert!(t.paper > 0.95 && t.mid < 0.05 && t.edges < 0.05 && t.edges_outside < 0.01, "{t:?}");
        // The same figure in a shaded scene: a lit wall graded from dark to light, the figure's
        // body a darker tone: little of the page is one paper gray.
        let shaded: Vec<u8> = (0..W * H)
            .map(|i| {
                let (x, y) = (i % W, i / W);
                let wall = 90 + (120 * (x + y) / (W + H)) as u8;
                let body = (150..250).contains(&x) && (40..430).contains(&y);
                if drawing[i] == 0 {
                    20
                } else if body {
                    wall - 50
                } else {
                    wall
                }
            })
            .collect();
        let t = image_tone(&ImageView::gray(&shaded, W, H).unwrap(), &j).unwrap();
        assert!(t.photo_like() && t.paper < MIN_DRAWING_PAPER && t.mid > 0.5, "{t:?}");
        // A stylised photo: white paper, but the scene's texture drawn everywhere (hatching every
        // 6 px): most of it is paper, a third of it edges.
        let hatched: Vec<u8> = (0..W * H).map(|i| if (i % W).is_multiple_of(6) { 0 } else { drawing[i] }).collect();
        let t = image_tone(&ImageView::gray(&hatched, W, H).unwrap(), &j).unwrap();
        assert!(t.paper >= MIN_DRAWING_PAPER && t.edges >= MAX_DRAWING_EDGES && t.photo_like(), "{t:?}");
        assert!(t.edges_outside > 0.25, "{t:?}");
        // Colour: saturation read from the channels; the drawing as RGB is as gray.
        let rgb: Vec<u8> = drawing.iter().flat_map(|&g| [g, g, g]).collect();
        let t_rgb = image_tone(&ImageView::new(&rgb, W, H, 3, 3 * W).unwrap(), &j).unwrap();
        assert_eq!(t_rgb.saturation, 0.0);
        assert!(!t_rgb.photo_like());
        let red: Vec<u8> = drawing.iter().flat_map(|&g| [g, g / 2, g / 2]).collect();
        let t_red = image_tone(&ImageView::new(&red, W, H, 3, 3 * W).unwrap(), &j).unwrap();
        assert!(t_red.saturation > 0.45, "{t_red:?}");
    }

    #[test]
    fn bad_figures_and_tiny_images_give_finite_tones() {
        let px = [255u8, 0, 255, 0];
        let mut j = front();
        j.xy = [[f64::NAN, f64::INFINITY]; NUM_JOINTS];
        for (w, h) in [(1, 1), (4, 1), (2, 2)] {
            let t = image_tone(&ImageView::gray(&px[..w * h], w, h).unwrap(), &j).unwrap();
            for v in [t.paper, t.mid, t.saturation, t.edges, t.edges_outside] {
                assert!((0.0..=1.0).contains(&v), "{t:?}");
            }
            assert_eq!(t.edges_outside, 0.0, "no joint: the box is the whole image");
        }
        // Joints far outside the image: the box is clipped, the whole image outside it.
        let mut far = front();
        for p in &mut far.xy {
            p[0] += 1e9;
        }
        let t = image_tone(&ImageView::gray(&line_drawing(), W, H).unwrap(), &far).unwrap();
        assert!(t.edges_outside > 0.0 && t.edges_outside == t.edges, "{t:?}");
        // Deterministic.
        assert_eq!(t, image_tone(&ImageView::gray(&line_drawing(), W, H).unwrap(), &far).unwrap());
    }
}
