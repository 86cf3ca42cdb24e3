//! `run SHEET --sheet [--views front,side,back]`: the figures of a model sheet as the run's front
//! view and extra views. The figures are found left to right ([`sketchbody::sheet::split_sheet`]);
//! their views are the user's `--views` labels in that order, else the detector's facing of each
//! ([`sketchbody::sheet::label_from_facing`]). Joint files given with `--joints` (the front
//! figure) and `--view-joints LABEL=JSON` are in the sheet's pixels.

use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::image::{canny, to_gray, CannyParams, RgbImage};
use sketchbody::pipeline::{FigureJoints, JointsSource};
use sketchbody::pose::Dictionary;
use sketchbody::sheet::{label_from_facing, split_sheet, SheetFigure};
use sketchbody::skeleton::Joints2;
use sketchbody::view::ViewLabel;

use crate::CliError;

/// One figure of a sheet: its view, its box on the sheet and its colour crop.
pub struct SheetCrop {
    /// The figure's view.
    pub label: ViewLabel,
    /// The figure's box in the sheet's pixels.
    pub figure: SheetFigure,
    /// The figure's crop of the sheet.
    pub rgb: RgbImage,
}

impl SheetCrop {
    /// `joints` in the sheet's pixels moved into this crop's.
    pub fn from_sheet(&self, joints: &Joints2) -> Joints2 {
        let (dx, dy) = (self.figure.x as f64, self.figure.y as f64);
        Joints2 { xy: joints.xy.map(|[x, y]| [x - dx, y - dy]), visible: joints.visible }
    }

    /// `x0–x1` of the crop on the sheet, for the report.
    pub fn span(&self) -> String {
        format!("x {}–{}", self.figure.x, self.figure.x + self.figure.width)
    }
}

/// Parses `--views front,side,back`. Errors: an unknown label or one given twice.
pub fn parse_views(text: &str) -> Result<Vec<ViewLabel>, CliError> {
    let mut labels = Vec::new();
    for part in text.split(',') {
        let label = ViewLabel::parse(part).map_err(|e| CliError(format!("--views {text}: {e}")))?;
        if labels.contains(&label) {
            return Err(CliError(format!("--views {text}: {} twice", label.name())));
        }
        labels.push(label);
    }
    if !labels.contains(&ViewLabel::Front) {
        return Err(CliError(format!("--views {text}: one of the figures must be the front view")));
    }
    Ok(labels)
}

/// The colour crop of `figure`.
fn crop(sheet: &RgbImage, f: &SheetFigure) -> Result<RgbImage, CliError> {
    let w = sheet.width();
    let src = sheet.as_bytes();
    let mut data = Vec::with_capacity(3 * f.width * f.height);
    for y in f.y..f.y + f.height {
        data.extend_from_slice(&src[3 * (y * w + f.x)..3 * (y * w + f.x + f.width)]);
    }
    Ok(RgbImage::from_vec(f.width, f.height, data)?)
}

/// The figures of `sheet` (loaded from `path`), cropped and labelled: by `labels` (the user's
/// `--views`, in reading order) or, when `None`, by the detector's facing of each crop
/// (`detectors` must then be loaded). Errors: fewer than two figures, a label count that is not
/// the figure count, a facing that does not name the views (each naming the figures and the fix).
pub fn sheet_views(
    path: &std::path::Path,
    sheet: &RgbImage,
    labels: Option<&[ViewLabel]>,
    detectors: Option<(&Model, &LandmarkNet)>,
    options: &sketchbody::detect::figure::FigureOptions,
    dict: &Dictionary,
) -> Result<Vec<SheetCrop>, CliError> {
    let at = |e: &dyn std::fmt::Display| CliError(format!("{}: {e}", path.display()));
    let figures = split_sheet(&to_gray(&sheet.view())?).map_err(|e| at(&e))?;
    if figures.len() < 2 {
        return Err(at(&format!(
            "--sheet found {} figure on the sheet; a model sheet has its views side by side with blank space between \
             them (for one view, run without --sheet)",
            figures.len()
        )));
    }
    let crops: Vec<RgbImage> = figures.iter().map(|f| crop(sheet, f)).collect::<Result<_, _>>()?;
    let labels = match labels {
        Some(l) if l.len() != figures.len() => {
            return Err(at(&format!(
                "--views names {} views but the sheet has {} figures ({})",
                l.len(),
                figures.len(),
                figures.iter().map(|f| format!("x {}–{}", f.x, f.x + f.width)).collect::<Vec<_>>().join(", ")
            )))
        }
        Some(l) => l.to_vec(),
        None => {
            let Some((model, net)) = detectors else {
                return Err(CliError("internal: --sheet without --views needs the detector".into()));
            };
            let mut facings = Vec::with_capacity(crops.len());
            for c in &crops {
                let gray = to_gray(&c.view())?;
                let edges = canny(&gray.view(), &CannyParams::default())?;
                let source = FigureJoints { model, net, options, colour: Some(c.view()) };
                let (_, detection) = source.figure(&gray, &edges, dict).map_err(|e| at(&e))?;
                facings.push(detection.map_or(sketchbody::detect::facing::Facing::Unknown, |d| d.facing.facing));
            }
            label_from_facing(&facings).map_err(|e| match e {
                sketchbody::Error::OutOfRange { detail, .. } => {
                    at(&format!("{detail} (--views front,side,… in reading order)"))
                }
                e => at(&e),
            })?
        }
    };
    Ok(labels
        .into_iter()
        .zip(figures)
        .zip(crops)
        .map(|((label, figure), rgb)| SheetCrop { label, figure, rgb })
        .collect())
}
