//! Stylisation and negative-page tests: determinism, sizes, channels, and that each style does
//! what it is meant to (ink on edges, few flat colours, gray pencil without black, pages
//! without blobs). "Ink" is a gray level below 215, the landmark ROI's `INK_LEVEL`.

use super::*;
use sketchbody::detect::landmark::roi::INK_LEVEL;

/// A 128×112 test photo: light gray wall with a soft vertical gradient, a dark-gray disc
/// (centre (40, 56), radius 24), a red box (x 76..116, y 20..92) and mild deterministic noise.
fn test_photo() -> RgbImage {
    let (w, h) = (128usize, 112usize);
    let mut data = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            let n = ((x * 7919 + y * 104_729) % 13) as f32 / 13.0 * 0.03;
            let wall = 0.8 + 0.1 * y as f32 / h as f32 + n;
            let (fx, fy) = (x as f32 + 0.5 - 40.0, y as f32 + 0.5 - 56.0);
            let p = if fx * fx + fy * fy < 24.0 * 24.0 {
                [0.3 + n, 0.3 + n, 0.32 + n]
            } else if (76..116).contains(&x) && (20..92).contains(&y) {
                [0.75 + n, 0.15 + n, 0.12]
            } else {
                [wall, wall, wall * 0.97]
            };
            data.extend(p.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8));
        }
    }
    RgbImage::from_vec(w, h, data).unwrap()
}

/// Distance (pixels) from pixel centre (x, y) to the nearest shape boundary of [`test_photo`].
fn boundary_distance(x: usize, y: usize) -> f32 {
    let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
    let disc = (((px - 40.0).powi(2) + (py - 56.0).powi(2)).sqrt() - 24.0).abs();
    let (dx, dy) = ((px - 76.0).max(0.0).min(116.0 - px), (py - 20.0).max(0.0).min(92.0 - py));
    let inside = (76.0..116.0).contains(&px) && (20.0..92.0).contains(&py);
    let boxd = if inside {
        dx.min(dy)
    } else {
        let ox = (76.0 - px).max(px - 116.0).max(0.0);
        let oy = (20.0 - py).max(py - 92.0).max(0.0);
        (ox * ox + oy * oy).sqrt()
    };
    disc.min(boxd)
}

fn grays(img: &RgbImage) -> Vec<u8> {
    img.as_bytes()
        .chunks_exact(3)
        .map(|p| sketchbody::image::to_gray(&ImageView::new(p, 1, 1, 3, 3).unwrap()).unwrap().as_bytes()[0])
        .collect()
}

#[test]
fn names_parse_back_and_unknown_names_are_errors() {
    for s in Stylisation::ALL {
        assert_eq!(s.name().parse::<Stylisation>().unwrap(), s);
        assert_eq!(s.to_string(), s.name());
    }
    assert_eq!("XDOG".parse::<Stylisation>().unwrap(), Stylisation::XdogInk);
    assert!("oil".parse::<Stylisation>().is_err());
    for k in NegativePage::ALL {
        assert_eq!(k.name().parse::<NegativePage>().unwrap(), k);
    }
    assert!("poster".parse::<NegativePage>().is_err());
}

#[test]
fn styles_are_deterministic_rgb_of_the_input_size() {
    let photo = test_photo();
    for style in Stylisation::ALL {
        let a = stylise(&photo.view(), style, 7).unwrap();
        assert_eq!((a.width(), a.height(), a.as_bytes().len()), (128, 112, 128 * 112 * 3), "{style}");
        assert_eq!(a, stylise(&photo.view(), style, 7).unwrap(), "{style}: same seed, same bytes");
        assert_ne!(a.as_bytes(), photo.as_bytes(), "{style} changes the image");
    }
    // The pencil's strokes and the flat style's k-means draw from the seed; XDoG has no random step.
    assert_ne!(
        stylise(&photo.view(), Stylisation::PencilHatching, 7).unwrap(),
        stylise(&photo.view(), Stylisation::PencilHatching, 8).unwrap()
    );
    assert_eq!(
        stylise(&photo.view(), Stylisation::XdogInk, 7).unwrap(),
        stylise(&photo.view(), Stylisation::XdogInk, 8).unwrap()
    );
}

/// Gray, RGB and RGBA inputs with padded strides give the same drawing as the RGB original;
/// tiny images do not fail.
#[test]
fn channels_strides_and_tiny_images() {
    let photo = test_photo();
    let (w, h) = (photo.width(), photo.height());
    let gray = grays(&photo);
    let as_rgb: Vec<u8> = gray.iter().flat_map(|&g| [g, g, g]).collect();
    let rgb = RgbImage::from_vec(w, h, as_rgb).unwrap();
    let padded: Vec<u8> = gray.chunks_exact(w).flat_map(|r| r.iter().copied().chain([9, 9])).collect();
    let gview = ImageView::new(&padded, w, h, 1, w + 2).unwrap();
    let rgba: Vec<u8> = photo.as_bytes().chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
    let rgba_view = ImageView::new(&rgba, w, h, 4, 4 * w).unwrap();
    for style in Stylisation::ALL {
        assert_eq!(stylise(&gview, style, 3).unwrap(), stylise(&rgb.view(), style, 3).unwrap(), "{style} gray");
        assert_eq!(stylise(&rgba_view, style, 3).unwrap(), stylise(&photo.view(), style, 3).unwrap(), "{style} rgba");
        for (tw, th) in [(1, 1), (2, 3), (7, 1)] {
            let px = vec![120u8; tw * th * 3];
            let out = stylise(&ImageView::new(&px, tw, th, 3, 3 * tw).unwrap(), style, 1).unwrap();
            assert_eq!((out.width(), out.height()), (tw, th), "{style} {tw}x{th}");
        }
    }
}

/// XDoG: white paper with black lines where the shapes' edges are, the mid-gray disc left
/// unfilled (it is darker than the wall but not "very dark").
#[test]
fn xdog_draws_ink_on_edges_only() {
    let out = stylise(&test_photo().view(), Stylisation::XdogInk, 0).unwrap();
    let g = grays(&out);
    let ink: Vec<usize> = (0..g.len()).filter(|&i| g[i] < INK_LEVEL).collect();
    let white = g.iter().filter(|&&v| v >= 250).count() as f64 / g.len() as f64;
    assert!(white > 0.8, "paper fraction {white:.3}");
    let near = ink.iter().filter(|&&i| boundary_distance(i % 128, i / 128) <= 3.0).count();
    println!("xdog: {} ink pixels, {near} within 3 px of an edge, white {white:.3}", ink.len());
    assert!(ink.len() > 200, "the outlines are drawn: {} ink pixels", ink.len());
    assert!(near as f64 >= 0.95 * ink.len() as f64, "{near} of {} ink pixels on edges", ink.len());
    assert!(ink.iter().any(|&i| g[i] < 40), "the ink is black");
}

/// Flat colour: at most k colours plus the outline colour, dark outlines along the shapes.
#[test]
fn flat_has_few_colours_and_dark_outlines() {
    let out = stylise(&test_photo().view(), Stylisation::PosterisedFlat, 5).unwrap();
    let colours: std::collections::HashSet<&[u8]> = out.as_bytes().chunks_exact(3).collect();
    println!("flat: {} distinct colours", colours.len());
    assert!(colours.len() <= flat::COLOURS + 1, "{} colours", colours.len());
    let outline = flat::OUTLINE.map(|v| (v * 255.0).round() as u8);
    let lines: Vec<usize> = (0..128 * 112).filter(|&i| out.as_bytes()[3 * i..3 * i + 3] == outline).collect();
    assert!(lines.len() > 100, "{} outline pixels", lines.len());
    let near = lines.iter().filter(|&&i| boundary_distance(i % 128, i / 128) <= 2.5).count();
    assert!(near as f64 >= 0.9 * lines.len() as f64, "{near} of {} outline pixels on edges", lines.len());
    // The red box stays red inside.
    let p = &out.as_bytes()[3 * (56 * 128 + 96)..][..3];
    assert!(p[0] > 150 && p[1] < 90, "box interior {p:?}");
}

/// Pencil: mid-gray strokes, nothing near black, hatching inside the dark disc, light paper
/// away from the shapes.
#[test]
fn pencil_is_gray_with_hatching_in_the_dark() {
    let out = stylise(&test_photo().view(), Stylisation::PencilHatching, 11).unwrap();
    let g = grays(&out);
    let darkest = *g.iter().min().unwrap();
    let strokes = g.iter().filter(|&&v| (60..=130).contains(&v)).count();
    println!("pencil: darkest {darkest}, {strokes} pixels at gray 60-130");
    assert!(darkest >= 55, "no black: darkest {darkest}");
    assert!(strokes > 100, "{strokes} outline pixels");
    // No solid dark patch: every 4x4 block keeps a pixel lighter than 140 (hatching has gaps).
    for by in 0..112 - 4 {
        for bx in 0..128 - 4 {
            let lightest = (0..16).map(|k| g[(by + k / 4) * 128 + bx + k % 4]).max().unwrap();
            assert!(lightest >= 140, "solid dark 4x4 block at ({bx}, {by})");
        }
    }
    let disc_ink = (0..g.len())
        .filter(|&i| {
            let (x, y) = ((i % 128) as f32 + 0.5, (i / 128) as f32 + 0.5);
            (x - 40.0).powi(2) + (y - 56.0).powi(2) < 18.0 * 18.0 && g[i] < INK_LEVEL
        })
        .count();
    assert!(disc_ink > 150, "hatching in the dark disc: {disc_ink} ink pixels");
    let far = (0..g.len()).filter(|&i| boundary_distance(i % 128, i / 128) > 6.0 && i % 128 > 4 && i / 128 > 4);
    let (paper, n) = far
        .fold((0, 0), |(p, n), i| (p + usize::from(g[i] >= 200 || boundary_distance(i % 128, i / 128) < 24.0), n + 1));
    assert!(paper as f64 > 0.95 * n as f64, "paper stays light: {paper} of {n}");
}

/// Pages: right size, same bytes for a seed and other bytes for another; blank pages hold
/// (almost) no ink; text and clutter hold ink but no solid blob (ink whose whole 5×5
/// neighbourhood is ink, as a filled figure would be) larger than 0.3 % of the page.
#[test]
fn negative_pages_have_ink_but_no_blob() {
    let (w, h) = (320, 256);
    for kind in NegativePage::ALL {
        for seed in 0..6 {
            let page = negative_page(kind, w, h, seed).unwrap();
            assert_eq!((page.width(), page.height()), (w, h));
            assert_eq!(page, negative_page(kind, w, h, seed).unwrap(), "{kind} {seed}");
            assert_ne!(page, negative_page(kind, w, h, seed + 100).unwrap(), "{kind} {seed}");
            let ink: Vec<bool> = grays(&page).iter().map(|&v| v < INK_LEVEL).collect();
            let frac = ink.iter().filter(|&&b| b).count() as f64 / ink.len() as f64;
            let solid: Vec<bool> = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    x >= 2
                        && y >= 2
                        && x + 2 < w
                        && y + 2 < h
                        && (0..25).all(|k| ink[(y + k / 5 - 2) * w + x + k % 5 - 2])
                })
                .collect();
            let blob = filters::components(&solid, w).1.into_iter().max().unwrap_or(0);
            println!("{kind} seed {seed}: ink {:.4}, largest solid blob {blob} px", frac);
            match kind {
                NegativePage::Blank => assert!(frac < 1e-4, "blank {seed}: ink {frac}"),
                _ => {
                    assert!(frac > 0.005, "{kind} {seed}: ink {frac}");
                    assert!((blob as f64) < 0.003 * (w * h) as f64, "{kind} {seed}: blob of {blob} px");
                }
            }
        }
    }
    assert!(negative_page(NegativePage::Text, 0, 10, 1).is_err());
    assert!(negative_page(NegativePage::Blank, 20_000, 10, 1).is_err());
    assert!(matches!(negative_page(NegativePage::Blank, 16_000, 16_000, 1), Err(Error::TooManyPixels { .. })));
    for kind in NegativePage::ALL {
        for (tw, th) in [(1, 1), (3, 200), (200, 2)] {
            assert_eq!(negative_page(kind, tw, th, 9).unwrap().width(), tw);
        }
    }
}
