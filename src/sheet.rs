//! A model sheet: the views of one character drawn side by side on one page (front, side, back),
//! as concept artists hand them to modellers. [`split_sheet`] finds the figures as groups of
//! inked columns separated by blank gaps, in reading order (left to right); guide lines drawn
//! across the whole sheet (a ground line, head and chin lines) do not join them.
//! [`label_from_facing`] names each figure's view from the detector's facing.

use crate::detect::facing::Facing;
use crate::error::{Error, Result};
use crate::image::GrayImage;
use crate::view::ViewLabel;

/// Pixels darker than this are ink (0 ink … 255 paper).
pub const INK_BELOW: u8 = 160;
/// A horizontal ink run longer than this share of the sheet's width is a guide line across the
/// views, not part of a figure.
pub const GUIDE_LINE_SHARE: f64 = 0.6;
/// Smallest blank gap between two figures: this share of the sheet's width (at least 4 px).
pub const MIN_GAP_SHARE: f64 = 0.01;
/// A group of columns with less ink than this share of the inkiest group's is a stray mark or a
/// caption, not a figure.
pub const MIN_INK_SHARE: f64 = 0.15;

/// One figure of a sheet: its box in the sheet's pixels (margins included, inside the sheet)
/// and its ink.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SheetFigure {
    /// Left column of the box, pixels.
    pub x: usize,
    /// Top row of the box, pixels.
    pub y: usize,
    /// Width of the box, pixels.
    pub width: usize,
    /// Height of the box, pixels.
    pub height: usize,
    /// Ink pixels of the figure (guide lines excluded).
    pub ink: usize,
}

/// The figures of `sheet` in reading order (left to right). Each box covers the figure's ink with
/// a margin of 4 % of the sheet's height (at most half the gap to a neighbour). Errors: a blank
/// sheet ([`Error::BlankImage`]).
pub fn split_sheet(sheet: &GrayImage) -> Result<Vec<SheetFigure>> {
    let (w, h) = (sheet.width(), sheet.height());
    let px = sheet.as_bytes();
    let mut ink = vec![false; w * h];
    for y in 0..h {
        let row = &px[y * w..(y + 1) * w];
        let mut x = 0;
        while x < w {
            if row[x] >= INK_BELOW {
                x += 1;
                continue;
            }
            let start = x;
            while x < w && row[x] < INK_BELOW {
                x += 1;
            }
            if ((x - start) as f64) <= GUIDE_LINE_SHARE * w as f64 {
                ink[y * w + start..y * w + x].fill(true);
            }
        }
    }
    let columns: Vec<usize> = (0..w).map(|x| (0..h).filter(|&y| ink[y * w + x]).count()).collect();
    if columns.iter().all(|&c| c == 0) {
        return Err(Error::BlankImage { width: w, height: h, low: f64::from(INK_BELOW), high: f64::from(INK_BELOW) });
    }
    let min_gap = ((MIN_GAP_SHARE * w as f64).round() as usize).max(4);
    let mut groups: Vec<(usize, usize)> = Vec::new();
    let mut x = 0;
    while x < w {
        if columns[x] == 0 {
            x += 1;
            continue;
        }
        let start = x;
        while x < w && columns[x] > 0 {
            x += 1;
        }
        match groups.last_mut() {
            Some(last) if start - last.1 < min_gap => last.1 = x,
            _ => groups.push((start, x)),
        }
    }
    let mass = |&(a, b): &(usize, usize)| columns[a..b].iter().sum::<usize>();
    let heaviest = groups.iter().map(mass).max().unwrap_or(0);
    let kept: Vec<(usize, usize)> =
        groups.into_iter().filter(|g| mass(g) as f64 >= MIN_INK_SHARE * heaviest as f64).collect();
    let margin = ((0.04 * h as f64).round() as usize).max(2);
    Ok(kept
        .iter()
        .enumerate()
        .map(|(k, &(a, b))| {
            let rows: Vec<usize> = (0..h).filter(|&y| (a..b).any(|x| ink[y * w + x])).collect();
            let (top, bottom) = (rows[0], rows[rows.len() - 1] + 1);
            let left_room = if k == 0 { a } else { (a - kept[k - 1].1) / 2 };
            let right_room = if k + 1 == kept.len() { w - b } else { (kept[k + 1].0 - b) / 2 };
            let (x0, x1) = (a - margin.min(left_room), b + margin.min(right_room));
            let (y0, y1) = (top.saturating_sub(margin), (bottom + margin).min(h));
            SheetFigure { x: x0, y: y0, width: x1 - x0, height: y1 - y0, ink: mass(&(a, b)) }
        })
        .collect())
}

/// The view label of each figure from the detector's facing of it: front, back, a right profile
/// (the character's right side toward the viewer) as [`ViewLabel::Side`], a left profile as
/// [`ViewLabel::SideLeft`]. Errors ([`Error::OutOfRange`] `sheet views`, naming the figures): a
/// facing the detector could not decide, two figures with one label, or no front view.
pub fn label_from_facing(facings: &[Facing]) -> Result<Vec<ViewLabel>> {
    let mut labels = Vec::with_capacity(facings.len());
    for (k, f) in facings.iter().enumerate() {
        let label = match f {
            Facing::Front => ViewLabel::Front,
            Facing::Back => ViewLabel::Back,
            Facing::Right => ViewLabel::Side,
            Facing::Left => ViewLabel::SideLeft,
            Facing::Unknown => {
                return Err(Error::OutOfRange {
                    name: "sheet views",
                    detail: format!(
                        "figure {} of {}: its facing is undecided; give the views' labels",
                        k + 1,
                        facings.len()
                    ),
                })
            }
        };
        if let Some(first) = labels.iter().position(|&l| l == label) {
            return Err(Error::OutOfRange {
                name: "sheet views",
                detail: format!(
                    "figures {} and {} both read as the {} view; give the views' labels",
                    first + 1,
                    k + 1,
                    label.name()
                ),
            });
        }
        labels.push(label);
    }
    if !labels.contains(&ViewLabel::Front) {
        let read: Vec<&str> = labels.iter().map(|l| l.name()).collect();
        return Err(Error::OutOfRange {
            name: "sheet views",
            detail: format!("no figure reads as the front view ({}); give the views' labels", read.join(", ")),
        });
    }
    Ok(labels)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A white `w`×`h` sheet with a dark filled box per `(x0, x1, y0, y1)`.
    fn sheet(w: usize, h: usize, boxes: &[(usize, usize, usize, usize)]) -> GrayImage {
        let mut px = vec![255u8; w * h];
        for &(x0, x1, y0, y1) in boxes {
            for y in y0..y1 {
                px[y * w + x0..y * w + x1].fill(0);
            }
        }
        GrayImage::from_vec(w, h, px).unwrap()
    }

    #[test]
    fn three_figures_on_a_ground_line_are_found_left_to_right_and_a_stray_mark_is_not() {
        // Three figures, a ground line across the sheet, a small stray mark between two figures.
        let img = sheet(
            600,
            200,
            &[(40, 120, 20, 180), (250, 300, 25, 180), (420, 520, 20, 180), (0, 600, 180, 182), (180, 184, 100, 104)],
        );
        let figs = split_sheet(&img).unwrap();
        assert_eq!(figs.len(), 3, "{figs:?}");
        let centres: Vec<usize> = figs.iter().map(|f| f.x + f.width / 2).collect();
        assert!(centres.windows(2).all(|c| c[0] < c[1]), "reading order: {centres:?}");
        for (f, (x0, x1)) in figs.iter().zip([(40, 120), (250, 300), (420, 520)]) {
            assert!(f.x <= x0 && f.x + f.width >= x1 && f.x + 20 >= x0 && f.x + f.width <= x1 + 20, "{f:?}");
            assert!(f.y <= 20 + 8 && f.y + f.height >= 180 && f.y + f.height <= 200, "{f:?}");
            assert_eq!(f.ink, (x1 - x0) * 160 - if x0 == 250 { (x1 - x0) * 5 } else { 0 });
        }
        // Boxes never overlap.
        assert!(figs.windows(2).all(|p| p[0].x + p[0].width <= p[1].x));
    }

    #[test]
    fn one_figure_is_one_box_and_a_blank_sheet_is_an_error() {
        let figs = split_sheet(&sheet(300, 300, &[(100, 200, 30, 270)])).unwrap();
        assert_eq!(figs.len(), 1);
        assert!(matches!(split_sheet(&sheet(100, 100, &[])), Err(Error::BlankImage { .. })));
        // A guide line alone is not a figure.
        assert!(matches!(split_sheet(&sheet(100, 100, &[(0, 100, 50, 52)])), Err(Error::BlankImage { .. })));
    }

    #[test]
    fn facings_name_the_views_or_say_why_not() {
        let labels = label_from_facing(&[Facing::Front, Facing::Right, Facing::Back]).unwrap();
        assert_eq!(labels, [ViewLabel::Front, ViewLabel::Side, ViewLabel::Back]);
        assert_eq!(label_from_facing(&[Facing::Left, Facing::Front]).unwrap(), [ViewLabel::SideLeft, ViewLabel::Front]);
        let err = |f: &[Facing]| label_from_facing(f).unwrap_err().to_string();
        assert!(err(&[Facing::Front, Facing::Unknown]).contains("figure 2 of 2: its facing is undecided"));
        assert!(err(&[Facing::Front, Facing::Front]).contains("figures 1 and 2 both read as the front view"));
        assert!(err(&[Facing::Right, Facing::Back]).contains("no figure reads as the front view (side, back)"));
    }
}
