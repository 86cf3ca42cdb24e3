//! Non-photorealistic stylisations of photos for the real-drawing proxy benchmark (issue 15,
//! item 7): PARSE test photos turned into an ink drawing ([`Stylisation::XdogInk`]), a pencil
//! sketch with hatching ([`Stylisation::PencilHatching`]) and a flat-colour design
//! ([`Stylisation::PosterisedFlat`]), plus figure-free pages ([`negative_page`]) for the
//! "no figure" rate. None of these is used to train a detector, so scores on them measure
//! transfer to drawing styles the detector has never seen.
//!
//! Every output is an RGB image of the input's size. Every random step draws from a
//! `ChaCha8Rng` seeded by the caller's `seed` (mixed with a per-style stream tag), so a call
//! always returns the same bytes. Lengths scale with the image: [`unit`] is 1 at a 256 px short
//! side (0.6 at least), so PARSE photos (≈ 150–200 px) and 512² sketches look alike.
//!
//! Files: `filters` (float blur, bilateral, k-means), `pencil`, `flat`, `negative`.

pub(crate) mod filters;
mod flat;
mod negative;
mod pencil;

use std::str::FromStr;

pub use negative::{negative_page, NegativePage};

use filters::{blur, components, luma, rgb_planes, smooth_photo, Rgb};
use sketchbody::error::{Error, Result, MAX_DECODED_PIXELS, MAX_IMAGE_SIDE};
use sketchbody::image::{ImageView, RgbImage};

/// A drawing style a photo can be turned into.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stylisation {
    /// Black ink lines on white paper: Winnemöller's XDoG on the luminance of the photo after
    /// two bilateral passes (σ 0.8–1.2 px at PARSE sizes, k = 1.6, τ = 0.98, tanh soft
    /// threshold, φ = 12 per luminance unit), solid fill only where the photo is very dark
    /// (luminance below 0.16), specks under 10 u² px removed. Deterministic: the seed is not
    /// used.
    XdogInk,
    /// Light gray pencil outlines (Canny edges traced into jittered, tapered strokes of gray
    /// 65–120, never black) and diagonal hatching in three tone levels (sparse, dense,
    /// cross-hatched for the darkest), on faint paper grain.
    PencilHatching,
    /// Flat colour fills (bilateral smoothing, colour k-means to 8 colours, mode filter) with
    /// dark outlines from Canny on the smoothed image, like a flat-colour character design.
    PosterisedFlat,
}

impl Stylisation {
    /// Every stylisation, in benchmark order.
    pub const ALL: [Stylisation; 3] = [Stylisation::XdogInk, Stylisation::PencilHatching, Stylisation::PosterisedFlat];

    /// Short name used on the command line and in benchmark tables: "xdog", "pencil", "flat".
    pub fn name(self) -> &'static str {
        match self {
            Stylisation::XdogInk => "xdog",
            Stylisation::PencilHatching => "pencil",
            Stylisation::PosterisedFlat => "flat",
        }
    }
}

impl std::fmt::Display for Stylisation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Stylisation {
    type Err = Error;
    /// Parses a [`Stylisation::name`] (ASCII case ignored).
    fn from_str(s: &str) -> Result<Self> {
        Stylisation::ALL.into_iter().find(|st| st.name().eq_ignore_ascii_case(s)).ok_or_else(|| Error::OutOfRange {
            name: "style",
            detail: format!("{s:?} is not one of xdog, pencil, flat"),
        })
    }
}

/// Length scale of a `w`×`h` image: short side / 256 px, at least 0.6.
pub(crate) fn unit(w: usize, h: usize) -> f64 {
    (w.min(h) as f64 / 256.0).max(0.6)
}

/// Refuses empty images, sides over [`MAX_IMAGE_SIDE`] and images whose pixel count exceeds [`MAX_DECODED_PIXELS`] (the float planes of a
/// stylisation take about 40 bytes a pixel).
pub(crate) fn check_pixels(w: usize, h: usize) -> Result<()> {
    if w == 0 || h == 0 {
        return Err(Error::EmptyImage { width: w, height: h });
    }
    if w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(Error::ImageTooLarge { width: w, height: h });
    }
    if w * h > MAX_DECODED_PIXELS {
        return Err(Error::TooManyPixels { width: w, height: h });
    }
    Ok(())
}

/// Packs 0..=1 RGB pixels into an 8-bit image (rounded, clamped).
pub(crate) fn to_image(w: usize, h: usize, px: &[Rgb]) -> Result<RgbImage> {
    let data = px.iter().flat_map(|p| p.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8)).collect();
    RgbImage::from_vec(w, h, data)
}

/// Turns `image` (1, 3 or 4 channels; RGBA composited over white) into `style`; the output is
/// RGB of the same size. `seed` drives every random choice (same seed, same bytes). Errors:
/// images over [`MAX_DECODED_PIXELS`] pixels (`TooManyPixels`). Cost is linear in the pixels;
/// the flat style's bilateral filter dominates (about 0.5 s a megapixel).
pub fn stylise(image: &ImageView<'_>, style: Stylisation, seed: u64) -> Result<RgbImage> {
    let (w, h) = (image.width(), image.height());
    check_pixels(w, h)?;
    let rgb = rgb_planes(image);
    let px = match style {
        Stylisation::XdogInk => xdog(&rgb, w, h),
        Stylisation::PencilHatching => pencil::pencil(&rgb, w, h, seed)?,
        Stylisation::PosterisedFlat => flat::flat(&rgb, w, h, seed)?,
    };
    to_image(w, h, &px)
}

/// XDoG scale σ (pixels) of a `w`×`h` image: short side / 250 clamped to 0.8–1.2, then grown in
/// proportion above a 600 px short side so lines keep their share of the picture.
pub(crate) fn xdog_sigma(w: usize, h: usize) -> f64 {
    let s = w.min(h) as f64;
    (s / 250.0).clamp(0.8, 1.2) * (s / 600.0).max(1.0)
}

/// XDoG parameters (Winnemöller et al. 2012, "XDoG: an eXtended difference-of-Gaussians",
/// the τ form: D = G_σ − τ·G_kσ, here scaled by 1/(1 − τ) so that flat areas give their
/// luminance).
const XDOG_K: f64 = 1.6;
const XDOG_TAU: f32 = 0.98;
/// Threshold ε on the scaled response (a luminance): flat areas darker than this fill with ink.
const XDOG_EPS: f32 = 0.16;
/// Sharpness φ of the tanh soft threshold, per luminance unit.
const XDOG_PHI: f32 = 12.0;

/// XDoG ink drawing of RGB pixels: white paper (1.0) and black ink.
fn xdog(rgb: &[Rgb], w: usize, h: usize) -> Vec<Rgb> {
    let u = unit(w, h);
    let l: Vec<f32> = smooth_photo(rgb, w, h, u, 2, 0.1).iter().map(|&p| luma(p)).collect();
    let sigma = xdog_sigma(w, h);
    let g1 = blur(&l, w, h, sigma);
    let g2 = blur(&l, w, h, sigma * XDOG_K);
    let mut e: Vec<f32> = g1
        .iter()
        .zip(&g2)
        .map(|(&a, &b)| {
            let d = (a - XDOG_TAU * b) / (1.0 - XDOG_TAU);
            if d >= XDOG_EPS {
                1.0
            } else {
                1.0 + (XDOG_PHI * (d - XDOG_EPS)).tanh()
            }
        })
        .collect();
    // Specks (texture, JPEG noise) are not drawn: ink marks under 10 u² pixels become paper.
    let (labels, sizes) = components(&e.iter().map(|&v| v < 0.9).collect::<Vec<_>>(), w);
    let min = (10.0 * u * u).max(4.0) as usize;
    for (v, &l) in e.iter_mut().zip(&labels) {
        if sizes.get(l as usize).is_some_and(|&n| n < min) {
            *v = 1.0;
        }
    }
    e.into_iter().map(|v| [v; 3]).collect()
}

/// A contact sheet for people to look at: `rows` of images, each centred (and cropped) in a
/// `tile`² cell, `gap` px apart on a gray background, stored with 5 bits a channel so that the
/// PNG stays small (paper grain compresses badly).
pub fn contact_sheet(rows: &[Vec<RgbImage>], tile: usize, gap: usize) -> Result<RgbImage> {
    let cols = rows.iter().map(Vec::len).max().unwrap_or(1);
    let (w, h) = (cols * (tile + gap) + gap, rows.len() * (tile + gap) + gap);
    let mut data = vec![200u8; w * h * 3];
    for (r, row) in rows.iter().enumerate() {
        for (c, img) in row.iter().enumerate() {
            let (iw, ih) = (img.width().min(tile), img.height().min(tile));
            let x0 = gap + c * (tile + gap) + (tile - iw) / 2;
            let y0 = gap + r * (tile + gap) + (tile - ih) / 2;
            for y in 0..ih {
                let src = &img.as_bytes()[y * img.width() * 3..][..iw * 3];
                data[((y0 + y) * w + x0) * 3..][..iw * 3].copy_from_slice(src);
            }
        }
    }
    data.iter_mut().for_each(|v| *v = (*v & !7) | (*v >> 5));
    RgbImage::from_vec(w, h, data)
}

#[cfg(test)]
mod tests;
