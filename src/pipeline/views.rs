//! A turnaround's extra views in the pipeline ([`super::run_pipeline_views`]): each view's edges
//! and joints, the views' agreement with the front view, and what the run reports of them.
//!
//! Agreement: after the pose is triangulated from every view ([`crate::pose::views`]), a view
//! whose joints miss their triangulated positions by more than [`VIEWS_REFUSE`] of its figure
//! height is refused ([`Error::OutOfRange`] named `views`: another pose, another character or a
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
}

/// A view's edges and joints before the pose.
pub(super) struct PreparedView {
    pub label: ViewLabel,
    pub edges: GrayImage,
    pub joints2d: Joints2,
    pub joints_source: String,
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
        let (joints2d, _) = v.source.figure(v.sketch, &edges, dict)?;
        check_in_image(&joints2d, w, h)?;
        out.push(PreparedView { label: v.label, edges, joints2d, joints_source: v.source.name().to_string() });
    }
    Ok(out)
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
                return Err(Error::OutOfRange {
                    name: "views",
                    detail: format!(
                        "the {name} view's depth comes out mirrored: its limbs miss the front view's pose by {:.0}° as \
                         labelled and by {:.0}° as the other side; is it drawn facing image {}? Then label it {}",
                        f.as_labelled_deg,
                        f.other_side_deg,
                        if other == ViewLabel::SideLeft { "left" } else { "right" },
                        other.name()
                    ),
                });
            }
        }
        if residual > VIEWS_REFUSE {
            return Err(Error::OutOfRange {
                name: "views",
                detail: format!(
                    "the {name} view disagrees with the front view: one pose seen from both misses their joints by {:.0}% \
                     of the figure's height (limit {:.0}%): a different pose or character, or a wrong label",
                    100.0 * residual,
                    100.0 * VIEWS_REFUSE
                ),
            });
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
