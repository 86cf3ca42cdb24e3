//! Where the pipeline's 2-D joints come from. [`JointsSource`] is the plug-in point for a joint
//! detector: the caller's joints ([`GivenJoints`], the paper's user-correction path) or a
//! detector's ([`DetectedJoints`], by default the embedded model trained on concept sketches).

use super::figure::detect_figure;
use crate::detect::figure::{Figure, FigureOptions};
use crate::detect::landmark::LandmarkNet;
use crate::detect::{detect, DetectOptions, Model};
use crate::error::{Error, Result};
use crate::image::{GrayImage, ImageView};
use crate::pose::{dict_io, Dictionary};
use crate::skeleton::{Joints2, BONES, JOINT_NAMES, NUM_JOINTS};

/// A provider of the 15 canonical 2-D joints of a sketch. Implementations must be deterministic
/// and shareable across threads.
pub trait JointsSource: Sync {
    /// Short name for reports ("given", a detector's name).
    fn name(&self) -> &str;
    /// The joints of `sketch` (gray, 0 ink … 255 paper), pixels; `edges` is its Canny edge map.
    fn joints(&self, sketch: &GrayImage, edges: &GrayImage) -> Result<Joints2>;
    /// The joints with the detection behind them (backend, calibrated confidences), when the
    /// source is a single-figure detector; by default [`JointsSource::joints`] and `None`.
    /// `dict` is the pose step's dictionary, for a detector the pose step referees.
    fn figure(&self, sketch: &GrayImage, edges: &GrayImage, _dict: &Dictionary) -> Result<(Joints2, Option<Figure>)> {
        Ok((self.joints(sketch, edges)?, None))
    }
}

/// Joints given by the caller (a joints file, a user's clicks).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GivenJoints(pub Joints2);

impl JointsSource for GivenJoints {
    fn name(&self) -> &str {
        "given"
    }
    fn joints(&self, _sketch: &GrayImage, _edges: &GrayImage) -> Result<Joints2> {
        Ok(self.0)
    }
}

/// Joints from a 2-D pose detector ([`crate::detect`]; by default the embedded model trained on
/// concept sketches, [`crate::detect::Model::embedded`]): the best figure's 15 joints. A joint
/// the detector put within [`COINCIDENT_PX`] of its parent joint (both parts in one cell, e.g. a
/// wrist on a foreshortened elbow) is marked missing, so the pose solver drops it instead of
/// rejecting coincident joints. Errors as [`crate::detect::detect`], notably
/// [`Error::NoFigure`] when nothing reaches the threshold.
#[derive(Clone, Copy, Debug)]
pub struct DetectedJoints<'a> {
    /// The detector model (borrowed).
    pub model: &'a Model,
    /// Detection options (default: the model's threshold and the sketch search range).
    pub options: &'a DetectOptions,
}

impl JointsSource for DetectedJoints<'_> {
    fn name(&self) -> &str {
        "detector"
    }
    fn joints(&self, sketch: &GrayImage, _edges: &GrayImage) -> Result<Joints2> {
        let mut j = detect(&sketch.view(), self.model, self.options)?.best().joints;
        hide_coincident_children(&mut j);
        Ok(j)
    }
}

/// Joints from the single-figure detector ([`detect_figure`]; by default `auto`: the sketch model
/// and BlazePose, one candidate per image, [`crate::detect::figure::Fusion::PerImage`], refereed
/// by the pose step with the pipeline's dictionary): the product's default source. Runs on `colour` when given (a painted drawing's colours help the landmark model),
/// else on the gray sketch. Coincident children are marked missing as in [`DetectedJoints`].
/// Errors as [`detect_figure`], notably [`Error::NoFigure`] on a page without a figure.
#[derive(Clone, Copy, Debug)]
pub struct FigureJoints<'a> {
    /// The sketch model (borrowed).
    pub model: &'a Model,
    /// The landmark network (borrowed).
    pub net: &'a LandmarkNet,
    /// Backend and thresholds.
    pub options: &'a FigureOptions,
    /// The sketch in colour (same size as the gray sketch), if the caller has it.
    pub colour: Option<ImageView<'a>>,
}

impl JointsSource for FigureJoints<'_> {
    fn name(&self) -> &str {
        "detector"
    }
    fn joints(&self, sketch: &GrayImage, edges: &GrayImage) -> Result<Joints2> {
        Ok(self.figure(sketch, edges, dict_io::embedded_shared()?)?.0)
    }
    fn figure(&self, sketch: &GrayImage, _edges: &GrayImage, dict: &Dictionary) -> Result<(Joints2, Option<Figure>)> {
        let view = match self.colour {
            Some(c) if c.width() == sketch.width() && c.height() == sketch.height() => c,
            _ => sketch.view(),
        };
        let f = detect_figure(&view, self.model, self.net, self.options, Some(dict))?;
        let mut j = f.joints;
        hide_coincident_children(&mut j);
        Ok((j, Some(f)))
    }
}

/// Detected joints closer than this to their parent joint, pixels, are marked missing.
pub const COINCIDENT_PX: f64 = 0.5;

/// Marks missing every visible child joint within [`COINCIDENT_PX`] of its visible parent
/// (bones in [`BONES`] order, parent first).
fn hide_coincident_children(j: &mut Joints2) {
    for &(parent, child) in BONES.iter() {
        let d = (j.xy[parent][0] - j.xy[child][0]).hypot(j.xy[parent][1] - j.xy[child][1]);
        if j.visible[parent] && j.visible[child] && d < COINCIDENT_PX {
            j.visible[child] = false;
        }
    }
}

/// Checks that every visible joint is finite and inside the `width`×`height` image
/// (0 ≤ x ≤ width, 0 ≤ y ≤ height). Errors: [`Error::NonFinite`], [`Error::JointOutsideImage`].
pub fn check_in_image(j: &Joints2, width: usize, height: usize) -> Result<()> {
    for k in 0..NUM_JOINTS {
        if !j.visible[k] {
            continue;
        }
        let [x, y] = j.xy[k];
        if !x.is_finite() || !y.is_finite() {
            return Err(Error::NonFinite { name: "2-D joint", value: if x.is_finite() { y } else { x } });
        }
        if !(0.0..=width as f64).contains(&x) || !(0.0..=height as f64).contains(&y) {
            return Err(Error::JointOutsideImage { joint: JOINT_NAMES[k], x, y, width, height });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_and_the_image_check() {
        let img = GrayImage::filled(100, 80, 255).unwrap();
        let j = Joints2 { xy: [[50.0, 40.0]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
        assert_eq!(GivenJoints(j).joints(&img, &img).unwrap(), j);
        let model = Model::embedded().unwrap();
        let options = DetectOptions { threshold: Some(1e3), ..DetectOptions::default() };
        let blank = DetectedJoints { model: &model, options: &options };
        assert_eq!(blank.name(), "detector");
        assert!(matches!(blank.joints(&img, &img), Err(Error::NoFigure { .. })));
        let mut wrist_on_elbow = j;
        for k in 0..NUM_JOINTS {
            wrist_on_elbow.xy[k] = [10.0 * k as f64, 5.0 * k as f64];
        }
        wrist_on_elbow.xy[7] = [wrist_on_elbow.xy[6][0] + 0.2, wrist_on_elbow.xy[6][1]];
        hide_coincident_children(&mut wrist_on_elbow);
        assert_eq!(wrist_on_elbow.visible.iter().filter(|&&v| !v).count(), 1);
        assert!(!wrist_on_elbow.visible[7], "the wrist (child of the elbow) is the one dropped");
        check_in_image(&j, 100, 80).unwrap();
        let mut out = j;
        out.xy[3] = [50.0, 80.5];
        let e = check_in_image(&out, 100, 80).unwrap_err();
        assert!(matches!(e, Error::JointOutsideImage { joint: "r_elbow", .. }), "{e}");
        out.visible[3] = false;
        check_in_image(&out, 100, 80).unwrap();
        let mut nan = j;
        nan.xy[0] = [f64::NAN, 1.0];
        assert!(matches!(check_in_image(&nan, 100, 80), Err(Error::NonFinite { .. })));
    }
}
