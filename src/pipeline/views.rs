//! A turnaround's extra views in the pipeline ([`super::run_pipeline_views`]): each view's edges
//! and joints, the views' agreement with the front view, and what the run reports of them.
//!
//! Agreement: after the pose is triangulated from every view ([`crate::pose::views`]), a view
//! whose joints miss their triangulated positions by more than [`VIEWS_REFUSE`] of its figure
//! height is refused ([`Error::ViewsDisagree`]: another pose, another character or a
//! wrong label; the run does not fall back to the front view alone); above [`VIEWS_WARN`] the
//! run goes on with a warning. Views drawn at different sizes are scaled to each other by their
//! joints; a size ratio beyond [`SCALE_WARN`] is reported. A side view whose depth comes out
//! mirrored ([`crate::pose::views::SideFacing::mirrored`]: drawn facing the other way than its
//! label says) is refused, naming the label to use.

use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::image::{canny, CannyParams, GrayImage};
use crate::pose::views::{SideFacing, ViewJoints, ViewsPose};
use crate::pose::Dictionary;
use crate::skeleton::Joints2;
use crate::view::ViewLabel;

use super::joints::{check_in_image, JointsSource};
use super::MIN_SKETCH_SIDE;

/// A view's RMS joint residual after triangulation, as a fraction of its figure height, above
/// which the views are refused as disagreeing.
pub const VIEWS_REFUSE: f64 = 0.12;

/// A view's RMS joint residual (fraction of its figure height) above which the run warns that
/// the views disagree.
pub const VIEWS_WARN: f64 = 0.05;

/// Size ratio between a view and the front view beyond which (or below its inverse) the run
/// reports that the views are drawn at different scales.
pub const SCALE_WARN: f64 = 1.15;

/// One extra view of a turnaround given to [`super::run_pipeline_views`].
#[derive(Clone, Copy)]
pub struct ViewInput<'a> {
    /// The view's label (side, side_left or back; the front view is the main sketch).
    pub label: ViewLabel,
    /// The view's gray sketch (0 ink … 255 paper).
    pub sketch: &'a GrayImage,
    /// Where the view's 2-D joints come from.
    pub source: &'a dyn JointsSource,
}

/// What a turnaround run made of one extra view. Owns its data.
#[derive(Clone, Debug)]
pub struct ViewResult {
    /// The view's label.
    pub label: ViewLabel,
    /// The view's Canny edge map (255 edge, 0 not).
    pub edges: GrayImage,
    /// The view's 2-D joints used, pixels of its image.
    pub joints2d: Joints2,
    /// Name of the view's joints source ([`JointsSource::name`]).
    pub joints_source: String,
    /// The view's camera refitted to the chosen body, pixels of its image: project
    /// [`super::PipelineResult::posed_vertices`] with it.
    pub camera: WeakPerspective,
    /// RMS joint residual after triangulation, fraction of the view's figure height.
    pub residual: f64,
    /// The view's drawn size over the front view's (1: the same scale).
    pub scale_ratio: f64,
    /// For a side view, how its labelled and its other facing agree with the front view's pose
    /// ([`crate::pose::views::side_facing`]); `None` for a back view or a given pose.
    pub facing: Option<SideFacing>,
    /// Share of the fitted outline in this view within reach of a stroke
    /// ([`crate::fit::FitResult::view_support`]; NaN for the mean shape).
    pub edge_support: f64,
    /// The view's detected joints are the detector's other labelling (left and right swapped),
    /// which fits the shared pose better; `false` for given joints.
    pub swapped: bool,
}

/// A view's edges and joints before the pose.
pub(super) struct PreparedView {
    pub label: ViewLabel,
    pub edges: GrayImage,
    pub joints2d: Joints2,
    pub joints_source: String,
    /// The detector's other labelling (left and right swapped); `None` for given joints.
    pub alternative: Option<Joints2>,
    /// `joints2d` is the detector's other labelling ([`choose_labelling`]).
    pub swapped: bool,
}

/// Checks the labels (no front, none twice) and every view's size, edges and joints. Errors:
/// a front or repeated label ([`Error::OutOfRange`]); as the front sketch's.
pub(super) fn prepare(views: &[ViewInput], canny_params: &CannyParams, dict: &Dictionary) -> Result<Vec<PreparedView>> {
    let mut out: Vec<PreparedView> = Vec::with_capacity(views.len());
    for v in views {
        if v.label == ViewLabel::Front {
            return Err(Error::OutOfRange {
                name: "view label",
                detail: "the front view is the main sketch; extra views are side, side_left or back".into(),
            });
        }
        if out.iter().any(|p| p.label == v.label) {
            return Err(Error::OutOfRange { name: "view label", detail: format!("two {} views", v.label.name()) });
        }
        let (w, h) = (v.sketch.width(), v.sketch.height());
        if w < MIN_SKETCH_SIDE || h < MIN_SKETCH_SIDE {
            return Err(Error::ImageTooSmall { width: w, height: h, min: MIN_SKETCH_SIDE });
        }
        let edges = canny(&v.sketch.view(), canny_params)?;
        if edges.as_bytes().iter().all(|&e| e == 0) {
            let (a, b) = (canny_params.threshold1, canny_params.threshold2);
            return Err(Error::BlankImage { width: w, height: h, low: a.min(b), high: a.max(b) });
        }
        let (joints2d, detection) = v.source.figure(v.sketch, &edges, dict)?;
        check_in_image(&joints2d, w, h)?;
        let alternative = detection.map(|d| d.facing.alternative);
        let joints_source = v.source.name().to_string();
        out.push(PreparedView { label: v.label, edges, joints2d, joints_source, alternative, swapped: false });
    }
    Ok(out)
}

/// Detected views take the detector's other labelling (left and right swapped) where it fits the
/// shared pose better: the detector reads a faceless figure as facing the viewer, which labels a
/// back view's sides, and often a side view's near and far limbs, the other way round. Each
/// detected view in turn is posed by `pose` (the other views as chosen so far) with both
/// labellings and keeps the one with the smaller residual; a labelling the views cannot be posed
/// with counts as the worse. Given joints are never changed.
pub(super) fn choose_labelling(views: &mut [PreparedView], pose: impl Fn(&[ViewJoints]) -> Result<ViewsPose>) {
    for k in 0..views.len() {
        let Some(other) = views[k].alternative else { continue };
        let residual = |views: &[PreparedView]| pose(&view_joints(views)).map_or(f64::INFINITY, |p| p.residual[k + 1]);
        let as_detected = residual(views);
        let detected = std::mem::replace(&mut views[k].joints2d, other);
        if residual(views) < as_detected {
            views[k].swapped = true;
            views[k].alternative = Some(detected);
        } else {
            views[k].joints2d = detected;
        }
    }
}

/// The views' joints for [`crate::pose::views`].
pub(super) fn view_joints(views: &[PreparedView]) -> Vec<ViewJoints<'_>> {
    views.iter().map(|v| ViewJoints { label: v.label, joints: &v.joints2d }).collect()
}

/// Refuses views that disagree beyond [`VIEWS_REFUSE`] and side views drawn facing the other
/// way (`facing`, per view); returns the warnings of the others.
pub(super) fn agreement(
    views: &[PreparedView],
    pose: &ViewsPose,
    facing: &[Option<SideFacing>],
) -> Result<Vec<String>> {
    let mut warnings = Vec::new();
    let front = pose.residual.first().copied().unwrap_or(0.0);
    for (k, v) in views.iter().enumerate() {
        let (residual, ratio) = (pose.residual[k + 1].max(front), pose.scale_ratio[k]);
        let name = v.label.name();
        if let (Some(f), Some(other)) = (facing.get(k).copied().flatten(), v.label.other_side()) {
            if f.mirrored() {
                return Err(Error::ViewsDisagree(format!(
                    "the {name} view's depth comes out mirrored: its limbs miss the front view's pose by {:.0}° as \
                         labelled and by {:.0}° as the other side; is it drawn facing image {}? Then label it {}",
                    f.as_labelled_deg,
                    f.other_side_deg,
                    if other == ViewLabel::SideLeft { "left" } else { "right" },
                    other.name()
                )));
            }
        }
        if residual > VIEWS_REFUSE {
            return Err(Error::ViewsDisagree(format!(
                "the {name} view disagrees with the front view: one pose seen from both misses their joints by {:.0}% \
                     of the figure's height (limit {:.0}%): a different pose or character, or a wrong label",
                100.0 * residual,
                100.0 * VIEWS_REFUSE
            )));
        }
        if residual > VIEWS_WARN {
            warnings.push(format!(
                "the {name} view agrees only roughly with the front view: one pose seen from both misses their joints by \
                 {:.0}% of the figure's height (same pose and character?)",
                100.0 * residual
            ));
        }
        if !(1.0 / SCALE_WARN..=SCALE_WARN).contains(&ratio) {
            warnings.push(format!(
                "the {name} view is drawn at {ratio:.2}x the front view's size; the views were scaled to each other by \
                 their joints"
            ));
        }
    }
    Ok(warnings)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::facing::swap_sides;
    use crate::pose::views::tests::{estimate, front_camera, project, walking};
    use crate::pose::views::triangulate;

    /// A prepared view of `joints` with the detector's `alternative` (none for given joints).
    fn view(label: ViewLabel, joints: Joints2, alternative: Option<Joints2>) -> PreparedView {
        let edges = GrayImage::filled(8, 8, 0).unwrap();
        PreparedView { label, edges, joints2d: joints, joints_source: "test".into(), alternative, swapped: false }
    }

    #[test]
    fn a_detected_back_view_labelled_as_facing_the_viewer_takes_the_swapped_labelling() {
        let (truth, cam) = (walking(), front_camera());
        let front = project(&truth, &cam);
        let back = project(&truth, &ViewLabel::Back.camera_from_front(&cam));
        let est = estimate(truth, cam);
        let pose = |vj: &[ViewJoints]| triangulate(&est, &front, vj);
        // The detector read the back view as facing the viewer: its sides are swapped.
        let mut views = vec![view(ViewLabel::Back, swap_sides(&back), Some(back))];
        choose_labelling(&mut views, pose);
        assert!(views[0].swapped);
        assert_eq!(views[0].joints2d, back);
        // Read right, it stays.
        let mut views = vec![view(ViewLabel::Back, back, Some(swap_sides(&back)))];
        choose_labelling(&mut views, pose);
        assert!(!views[0].swapped);
        assert_eq!(views[0].joints2d, back);
        // Given joints are never changed, even swapped ones.
        let mut views = vec![view(ViewLabel::Back, swap_sides(&back), None)];
        choose_labelling(&mut views, pose);
        assert!(!views[0].swapped);
        assert_eq!(views[0].joints2d, swap_sides(&back));
    }
}
