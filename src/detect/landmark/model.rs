//! The BlazePose landmark network run by tract-onnx: loading (the embedded asset or bytes of a
//! converted ONNX file), checking its interface, rewriting the depthwise convolutions that tract
//! runs on slow paths ([`rewrite_depthwise`]), and one inference on a 256×256 crop.

use std::sync::{Arc, OnceLock};

use tract_onnx::prelude::*;
use tract_onnx::tract_core::internal::*;
use tract_onnx::tract_core::ops::nn::resize::AxisPlan;
use tract_onnx::tract_core::ops::nn::{CoordTransformer, Interpolator, Resize};

use super::crop::INPUT_SIDE;
use crate::error::{Error, Result};

/// Landmarks the network outputs: the 33 pose landmarks and 6 auxiliary ones (33 = hips' midpoint
/// and 34 = scale point are the ROI alignment points).
pub const NUM_OUTPUT_LANDMARKS: usize = 39;
/// Values per output landmark: x, y (px of the 256² crop), z, visibility logit, presence logit.
pub const LANDMARK_VALUES: usize = 5;
/// Side of the network's heatmap output (64 × 64 cells over the 256² crop, one channel per
/// output landmark: [`NUM_OUTPUT_LANDMARKS`]).
pub const HEATMAP_SIDE: usize = 64;

/// MediaPipe's `pose_landmark_full` converted to ONNX (`scripts/convert-blazepose.sh`;
/// provenance and licence in `assets/pose_landmark_full.LICENSE`).
pub static EMBEDDED_ONNX: &[u8] = include_bytes!("../../../assets/pose_landmark_full.onnx");

/// The raw output of one inference.
#[derive(Clone, Debug, PartialEq)]
pub struct RawOutput {
    /// 39 × 5 values (see [`LANDMARK_VALUES`]), crop px for x and y.
    pub landmarks: Vec<[f32; LANDMARK_VALUES]>,
    /// The pose-presence flag in [0, 1] (the network's own sigmoid output).
    pub pose_flag: f32,
    /// The heatmap output, [`HEATMAP_SIDE`]² × [`NUM_OUTPUT_LANDMARKS`] logits in HWC order
    /// (MediaPipe refines the landmarks from it: [`super::heatmap`]); `None` for a model
    /// without it.
    pub heatmap: Option<Vec<f32>>,
}

/// A loaded, optimised landmark network (cheap to share: clones share the plan), or the
/// embedded one to be built at its first inference ([`LandmarkNet::embedded_deferred`]).
#[derive(Clone)]
pub struct LandmarkNet {
    plan: Plan,
}

/// Where a [`LandmarkNet`]'s runnable plan is.
#[derive(Clone)]
enum Plan {
    /// Built.
    Built(Arc<TypedRunnableModel>),
    /// The embedded model's shared plan, built by the first caller that needs it.
    Embedded,
}

/// The embedded model's plan, parsed and optimised once per process (concurrent first callers
/// wait for the one building it).
fn embedded_plan() -> Result<Arc<TypedRunnableModel>> {
    static PLAN: OnceLock<std::result::Result<Arc<TypedRunnableModel>, String>> = OnceLock::new();
    PLAN.get_or_init(|| LandmarkNet::from_onnx(EMBEDDED_ONNX).and_then(|n| n.plan()).map_err(|e| e.to_string()))
        .clone()
        .map_err(Error::CorruptData)
}

impl std::fmt::Debug for LandmarkNet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LandmarkNet")
    }
}

fn corrupt(e: impl std::fmt::Display) -> Error {
    Error::CorruptData(format!("BlazePose landmark model: {e}"))
}

impl LandmarkNet {
    /// Parses and optimises an ONNX landmark model from its bytes. Errors: `CorruptData` when
    /// the bytes are not ONNX, or the model lacks a 1×256×256×3 input, a 195-value landmark output
    /// or a 1-value pose flag. A 64×64×39 heatmap output is kept when the model has one.
    pub fn from_onnx(bytes: &[u8]) -> Result<Self> {
        Self::build(bytes, true)
    }

    /// [`Self::from_onnx`], with or without [`rewrite_depthwise`] (the tests compare the two).
    fn build(bytes: &[u8], rewrite: bool) -> Result<Self> {
        let shape = [1, INPUT_SIDE, INPUT_SIDE, 3];
        let model = tract_onnx::onnx()
            .model_for_read(&mut &*bytes)
            .map_err(corrupt)?
            .with_input_fact(0, f32::fact(shape).into())
            .map_err(corrupt)?;
        let mut typed = model.into_typed().map_err(corrupt)?;
        let outlets = typed.output_outlets().map_err(corrupt)?.to_vec();
        let size = |o: &OutletId| -> Option<usize> {
            typed.outlet_fact(*o).ok()?.shape.as_concrete().map(|s| s.iter().product())
        };
        let find = |n: usize| outlets.iter().find(|o| size(o) == Some(n)).copied();
        let (Some(lm), Some(flag)) = (find(NUM_OUTPUT_LANDMARKS * LANDMARK_VALUES), find(1)) else {
            return Err(corrupt("no 195-value landmark output or 1-value pose flag output"));
        };
        let mut selected = vec![lm, flag];
        selected.extend(find(HEATMAP_SIDE * HEATMAP_SIDE * NUM_OUTPUT_LANDMARKS));
        typed.select_output_outlets(&selected).map_err(corrupt)?;
        let typed = if rewrite {
            let typed = rewrite_depthwise(typed).and_then(|t| t.into_decluttered()).map_err(corrupt)?;
            rewrite_upsampling(typed).map_err(corrupt)?
        } else {
            typed
        };
        let plan = typed.into_optimized().map_err(corrupt)?.into_runnable().map_err(corrupt)?;
        Ok(Self { plan: Plan::Built(plan) })
    }

    /// The embedded model, parsed and optimised once per process (0.2 s; later calls share the
    /// plan). Errors: `CorruptData` if the embedded bytes are damaged (a build fault).
    pub fn embedded() -> Result<Self> {
        Ok(Self { plan: Plan::Built(embedded_plan()?) })
    }

    /// The embedded model without building it now: the first inference builds it (once per
    /// process, shared with [`LandmarkNet::embedded`]) on the thread that runs it. A caller that
    /// detects at once gains the build's time where detection runs the network beside the
    /// sketch model ([`crate::detect::figure::gather`]); the embedded bytes' errors then come
    /// from [`LandmarkNet::run`].
    pub fn embedded_deferred() -> Self {
        Self { plan: Plan::Embedded }
    }

    /// The runnable plan (built now for a deferred embedded net).
    fn plan(&self) -> Result<Arc<TypedRunnableModel>> {
        match &self.plan {
            Plan::Built(plan) => Ok(plan.clone()),
            Plan::Embedded => embedded_plan(),
        }
    }

    /// Runs the network on a 256×256×3 HWC tensor in [0, 1] ([`super::crop::crop_tensor`]).
    /// Errors: `OutOfRange` for a wrong tensor length, `CorruptData` if inference fails.
    pub fn run(&self, tensor: Vec<f32>) -> Result<RawOutput> {
        let want = INPUT_SIDE * INPUT_SIDE * 3;
        if tensor.len() != want {
            return Err(Error::OutOfRange { name: "tensor", detail: format!("{} values, need {want}", tensor.len()) });
        }
        let input: Tensor =
            tract_ndarray::Array4::from_shape_vec((1, INPUT_SIDE, INPUT_SIDE, 3), tensor).map_err(corrupt)?.into();
        let out = self.plan()?.run(tvec!(input.into())).map_err(corrupt)?;
        let lm = out[0].to_plain_array_view::<f32>().map_err(corrupt)?;
        let flag = out[1].to_plain_array_view::<f32>().map_err(corrupt)?;
        let lm: Vec<f32> = lm.iter().copied().collect();
        if lm.len() != NUM_OUTPUT_LANDMARKS * LANDMARK_VALUES || flag.is_empty() {
            return Err(corrupt(format!("outputs of {} and {} values", lm.len(), flag.len())));
        }
        let landmarks = lm.chunks_exact(LANDMARK_VALUES).map(|c| [c[0], c[1], c[2], c[3], c[4]]).collect();
        let heatmap = match out.get(2) {
            Some(h) => Some(h.to_plain_array_view::<f32>().map_err(corrupt)?.iter().copied().collect()),
            None => None,
        };
        Ok(RawOutput { landmarks, pose_flag: flag.iter().next().copied().unwrap_or(0.0), heatmap })
    }
}

/// Smallest input side of a stride-2 depthwise convolution that [`rewrite_depthwise`] splits: on
/// smaller planes (BlazePose's 16² and under) the stride-1 convolution costs as much as the
/// strided one (measured).
const SPLIT_MIN_SIDE: usize = 32;

/// Smallest output side of a padded depthwise convolution that [`rewrite_depthwise`] pads
/// explicitly: tract's vectorised kernel takes rows of 8 outputs and more.
const PAD_MIN_SIDE: usize = 8;

/// The float depthwise convolution of `node` (no dilation, explicit padding, concrete input) and
/// its input's spatial sides, or `None`.
fn depthwise_conv<'a>(
    model: &TypedModel,
    node: &'a TypedNode,
) -> TractResult<Option<(&'a tract_onnx::tract_core::ops::cnn::Conv, TVec<usize>)>> {
    use tract_onnx::tract_core::ops::cnn::{Conv, PaddingSpec};
    let Some(conv) = node.op_as::<Conv>() else { return Ok(None) };
    let spec = &conv.pool_spec;
    let depthwise = conv.group > 1 && conv.group == spec.input_channels && conv.group == spec.output_channels;
    let plain = spec.rank() == 2 && (0..2).all(|ax| spec.dilation(ax) == 1 && spec.stride(ax) <= 2);
    let fact = model.outlet_fact(node.inputs[0])?;
    if !depthwise
        || !plain
        || conv.q_params.is_some()
        || fact.datum_type != f32::datum_type()
        || !matches!(spec.padding, PaddingSpec::Explicit(..))
    {
        return Ok(None);
    }
    let Some(shape) = fact.shape.as_concrete() else { return Ok(None) };
    let sides = spec.data_format.shape(shape.to_vec())?.hw_dims().into();
    Ok(Some((conv, sides)))
}

/// Rewrites the depthwise convolutions that tract would run on its slow paths (measured in
/// docs/benchmarks-history.md, "Detector backends: BlazePose, calibrated confidences, `auto`"):
/// - a stride-2 one over an input of at least [`SPLIT_MIN_SIDE`] px a side becomes the same
///   convolution at stride 1 followed by [`Subsample`]: tract runs strided depthwise kernels on a
///   scalar path, several times slower per output than its vectorised stride-1 path, so computing
///   four times the outputs and keeping one in four is faster;
/// - a padded stride-1 one (the split ones included) whose output is at least [`PAD_MIN_SIDE`] px
///   a side gets its padding from a [`ZeroPad`] and none of its own: tract computes the outputs
///   whose window crosses the border on a scalar path (most outputs of the small planes, where
///   BlazePose has many channels), and with the zeros in place every output runs vectorised.
///
/// The outputs are bit-identical: each sums the same taps of the same window in the same order
/// (the padded form adds products with zero, which leave a sum as it is).
fn rewrite_depthwise(mut model: TypedModel) -> TractResult<TypedModel> {
    use tract_onnx::tract_core::ops::cnn::PaddingSpec;
    let ids: Vec<usize> = model.nodes().iter().map(|n| n.id).collect();
    for id in ids {
        let node = model.node(id).clone();
        let Some((conv, sides)) = depthwise_conv(&model, &node)? else { continue };
        let spec = &conv.pool_spec;
        let strided = (0..2).all(|ax| spec.stride(ax) == 2);
        let split = strided && sides.iter().all(|&s| s >= SPLIT_MIN_SIDE);
        if !split && (0..2).any(|ax| spec.stride(ax) != 1) {
            continue;
        }
        let PaddingSpec::Explicit(before, after) = &spec.padding else { continue };
        let padded = before.iter().chain(after).any(|&p| p > 0);
        // The stride-1 output side (the input's, padding and kernel accounted for).
        let out_side = |ax: usize| sides[ax] + before[ax] + after[ax] + 1 - spec.kernel_shape[ax];
        let pad = padded && (0..2).all(|ax| out_side(ax) >= PAD_MIN_SIDE);
        if !split && !pad {
            continue;
        }
        let input_shape = model.outlet_fact(node.inputs[0])?.shape.to_tvec();
        let h = spec.data_format.shape(input_shape)?.h_axis();
        let mut op = conv.clone();
        let mut patch = TypedModelPatch::default();
        let mut taps = patch.taps(&model, &node.inputs)?;
        if split {
            op.pool_spec.strides = Some(tvec![1, 1]);
        }
        if pad {
            let zero_pad = ZeroPad { axes: tvec![h, h + 1], before: before.clone(), after: after.clone() };
            taps[0] = patch.wire_node(format!("{}.zero_pad", node.name), zero_pad, &taps[..1])?[0];
            op.pool_spec.padding = PaddingSpec::Explicit(tvec![0, 0], tvec![0, 0]);
        }
        let mut out = patch.wire_node(format!("{}.rewritten", node.name), op, &taps)?[0];
        if split {
            out = patch.wire_node(format!("{}.subsample", node.name), Subsample { axes: tvec![h, h + 1] }, &[out])?[0];
        }
        patch.shunt_outside(&model, OutletId::new(id, 0), out)?;
        patch.apply(&mut model)?;
    }
    Ok(model)
}

/// The 2× bilinear upsampling of two adjacent axes that `node` performs, when it is one: tract's
/// `Resize` with linear interpolation, half-pixel coordinates and constant scales of 2 on two
/// adjacent axes and 1 on the others. Returns the op and the two axes.
fn bilinear_upsampling(model: &TypedModel, node: &TypedNode) -> TractResult<Option<(Resize, TVec<usize>)>> {
    let Some(resize) = node.op_as::<Resize>() else { return Ok(None) };
    if resize.interpolator != Interpolator::Linear || resize.coord_transformer != CoordTransformer::HalfPixel {
        return Ok(None);
    }
    let Some(scales) = resize.optional_scales_input.and_then(|ix| node.inputs.get(ix)) else { return Ok(None) };
    let Some(scales) = model.outlet_fact(*scales)?.konst.clone() else { return Ok(None) };
    let scales: Vec<f32> = scales.cast_to::<f32>()?.try_as_plain_ram()?.as_slice::<f32>()?.to_vec();
    let axes: TVec<usize> = (0..scales.len()).filter(|&a| scales[a] != 1.0).collect();
    let fact = model.outlet_fact(node.inputs[0])?;
    let doubled = axes.len() == 2 && axes[1] == axes[0] + 1 && axes.iter().all(|&a| scales[a] == 2.0);
    Ok((doubled && fact.datum_type == f32::datum_type() && fact.rank() == scales.len()).then(|| (resize.clone(), axes)))
}

/// Replaces tract's 2× bilinear `Resize` nodes of a decluttered model (the ONNX `Resize` becomes
/// tract's there, and runs slowly; BlazePose's heatmap head has three) by [`Upsample2x`], which
/// sums the same taps with the same weights in the same order into the same intermediate tensor:
/// bit-identical outputs.
fn rewrite_upsampling(mut model: TypedModel) -> TractResult<TypedModel> {
    let ids: Vec<usize> = model.nodes().iter().map(|n| n.id).collect();
    for id in ids {
        let node = model.node(id).clone();
        let Some((resize, axes)) = bilinear_upsampling(&model, &node)? else { continue };
        let mut patch = TypedModelPatch::default();
        let input = patch.tap_model(&model, node.inputs[0])?;
        let out = patch.wire_node(format!("{}.upsample2x", node.name), Upsample2x { resize, axes }, &[input])?[0];
        patch.shunt_outside(&model, OutletId::new(id, 0), out)?;
        patch.apply(&mut model)?;
    }
    Ok(model)
}

/// A tensor's shape seen as `[outer, h, w, inner]` around two adjacent axes.
fn around_axes(shape: &[usize], axes: &[usize]) -> TractResult<[usize; 4]> {
    let &[h, w] = axes else { bail!("two axes wanted, got {axes:?}") };
    ensure!(w == h + 1 && w < shape.len(), "adjacent axes wanted, got {axes:?} of rank {}", shape.len());
    Ok([shape[..h].iter().product(), shape[h], shape[w], shape[w + 1..].iter().product()])
}

/// The fact of the f32 `input` with each of `axes` resized by `resize(index in axes, size)`.
fn resized_fact(
    op: &str,
    input: &TypedFact,
    axes: &[usize],
    resize: impl Fn(usize, TDim) -> TDim,
) -> TractResult<TVec<TypedFact>> {
    ensure!(input.datum_type == f32::datum_type(), "{op} takes f32");
    let mut fact = input.without_value();
    for (i, &ax) in axes.iter().enumerate() {
        ensure!(ax < fact.rank(), "{op} axis {ax} out of rank {}", fact.rank());
        let d = resize(i, fact.shape[ax].clone());
        fact.shape.set(ax, d);
    }
    Ok(tvec!(fact))
}

/// An op's single f32 output of `shape`.
fn f32_value(shape: &[usize], data: Vec<f32>) -> TractResult<TVec<TValue>> {
    let t = tract_ndarray::ArrayD::from_shape_vec(shape, data)?;
    Ok(tvec!(t.into_tensor().into_tvalue()))
}

/// `axes` after an axis change, or `None` when the change does not keep them two
/// adjacent axes.
fn changed_axes(axes: &[usize], change: &AxisOp) -> Option<TVec<usize>> {
    if !matches!(change, AxisOp::Add(_) | AxisOp::Rm(_) | AxisOp::Move(..)) {
        return None;
    }
    let new: TVec<usize> = axes.iter().map(|&a| change.transform_axis(a)).collect::<Option<_>>()?;
    (new.len() == 2 && new[1] == new[0] + 1).then_some(new)
}

/// `TypedOp::change_axes` of an op with two adjacent `axes` and nothing else tied to the layout:
/// the same op on the changed axes, when they stay adjacent.
macro_rules! change_axes_keeping_op {
    () => {
        fn change_axes(
            &self,
            model: &TypedModel,
            node: &TypedNode,
            _io: InOut,
            change: &AxisOp,
        ) -> TractResult<Option<AxisChangeConsequence>> {
            Ok(changed_axes(&self.axes, change).map(|axes| {
                let mut op = self.clone();
                op.axes = axes;
                AxisChangeConsequence::new(model, node, Some(Box::new(op)), change)
            }))
        }
    };
}

/// Pads two adjacent axes with zeros: a depthwise convolution's padding made explicit (see
/// [`rewrite_depthwise`]). An op of this module rather than tract's `Pad`, which tract's optimiser
/// folds back into the convolution.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct ZeroPad {
    axes: TVec<usize>,
    before: TVec<usize>,
    after: TVec<usize>,
}

impl Op for ZeroPad {
    fn name(&self) -> StaticName {
        "ZeroPad".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!("axes {:?}, before {:?}, after {:?}", self.axes, self.before, self.after)])
    }

    tract_onnx::tract_core::op_as_typed_op!();
}

impl EvalOp for ZeroPad {
    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        let input = args_1!(inputs);
        let [outer, ih, iw, inner] = around_axes(input.shape(), &self.axes)?;
        let (oh, ow) = (ih + self.before[0] + self.after[0], iw + self.before[1] + self.after[1]);
        let mut shape: TVec<usize> = input.shape().into();
        (shape[self.axes[0]], shape[self.axes[1]]) = (oh, ow);
        let view = input.to_plain_array_view::<f32>()?;
        let x = view.as_slice().ok_or_else(|| format_err!("ZeroPad input is not contiguous"))?;
        let mut out = vec![0f32; outer * oh * ow * inner];
        let row = iw * inner;
        for o in 0..outer {
            for y in 0..ih {
                let src = (o * ih + y) * row;
                let dst = ((o * oh + y + self.before[0]) * ow + self.before[1]) * inner;
                out[dst..dst + row].copy_from_slice(&x[src..src + row]);
            }
        }
        f32_value(&shape, out)
    }

    tract_onnx::tract_core::op_out_of_plan!();
}

impl TypedOp for ZeroPad {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        resized_fact("ZeroPad", inputs[0], &self.axes, |i, d| d + self.before[i] + self.after[i])
    }

    change_axes_keeping_op!();

    tract_onnx::tract_core::as_op!();
}

/// Keeps every second element (from the first) along each of `axes`: a stride-2 convolution's
/// outputs out of the stride-1 convolution's. An op of this module rather than tract's
/// `Downsample`, which tract's optimiser folds back into the convolution's stride.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct Subsample {
    axes: TVec<usize>,
}

impl Op for Subsample {
    fn name(&self) -> StaticName {
        "Subsample".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!("axes {:?}, stride 2", self.axes)])
    }

    tract_onnx::tract_core::op_as_typed_op!();
}

impl EvalOp for Subsample {
    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        let input = args_1!(inputs);
        let [outer, ih, iw, inner] = around_axes(input.shape(), &self.axes)?;
        let (oh, ow) = (ih.div_ceil(2), iw.div_ceil(2));
        let mut out_shape: TVec<usize> = input.shape().into();
        (out_shape[self.axes[0]], out_shape[self.axes[1]]) = (oh, ow);
        let view = input.to_plain_array_view::<f32>()?;
        let x = view.as_slice().ok_or_else(|| format_err!("Subsample input is not contiguous"))?;
        let mut out = Vec::with_capacity(outer * oh * ow * inner);
        for plane in x.chunks_exact((ih * iw * inner).max(1)).take(outer) {
            for row in plane.chunks_exact((iw * inner).max(1)).step_by(2) {
                if inner == 1 {
                    out.extend(row.iter().step_by(2));
                } else {
                    row.chunks_exact(inner).step_by(2).for_each(|px| out.extend_from_slice(px));
                }
            }
        }
        f32_value(&out_shape, out)
    }

    tract_onnx::tract_core::op_out_of_plan!();
}

/// Doubles two adjacent axes by `resize`'s interpolation (tract's bilinear, half-pixel `Resize`,
/// see [`rewrite_upsampling`]): the first axis, then the second, each output the sum from 0 of
/// its taps' weight × value in tap order, skipping zero weights, as tract's `Resize` computes
/// it, without its per-call copies and its generic inner loop.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct Upsample2x {
    resize: Resize,
    axes: TVec<usize>,
}

/// Resamples `src` seen as `[outer, len_in, inner]` along its middle axis by `plan` into `dst`
/// (`[outer, len_out, inner]`), exactly as tract's `resample_axis` sums (extrapolated outputs
/// 0).
fn resample(src: &[f32], outer: usize, len_in: usize, inner: usize, plan: &AxisPlan, dst: &mut [f32]) {
    let (len_out, window) = (plan.extrapolated.len(), plan.window);
    for o in 0..outer {
        let src = &src[o * len_in * inner..][..len_in * inner];
        let dst = &mut dst[o * len_out * inner..][..len_out * inner];
        for (x, out) in dst.chunks_exact_mut(inner).enumerate() {
            let (indices, weights) = (&plan.indices[x * window..][..window], &plan.weights[x * window..][..window]);
            if plan.extrapolated[x] {
                out.fill(0.0);
                continue;
            }
            if inner == 1 {
                // One value per output (the second axis of an NCHW plan): the plain sum.
                out[0] =
                    indices.iter().zip(weights).filter(|(_, &w)| w != 0.0).fold(0f32, |sum, (&i, &w)| sum + w * src[i]);
                continue;
            }
            // Tap by tap over the whole inner row (vectorised); every output still sums its
            // taps in window order from 0.
            out.fill(0.0);
            for (&i, &w) in indices.iter().zip(weights).filter(|(_, &w)| w != 0.0) {
                for (d, &s) in out.iter_mut().zip(&src[i * inner..][..inner]) {
                    *d += w * s;
                }
            }
        }
    }
}

impl Op for Upsample2x {
    fn name(&self) -> StaticName {
        "Upsample2x".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!("axes {:?}, {:?}", self.axes, self.resize.interpolator)])
    }

    tract_onnx::tract_core::op_as_typed_op!();
}

impl EvalOp for Upsample2x {
    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        let input = args_1!(inputs);
        let [outer, ih, iw, inner] = around_axes(input.shape(), &self.axes)?;
        let (oh, ow) = (2 * ih, 2 * iw);
        let mut shape: TVec<usize> = input.shape().into();
        (shape[self.axes[0]], shape[self.axes[1]]) = (oh, ow);
        let view = input.to_plain_array_view::<f32>()?;
        let x = view.as_slice().ok_or_else(|| format_err!("Upsample2x input is not contiguous"))?;
        let mut rows = vec![0f32; outer * oh * iw * inner];
        resample(x, outer, ih, iw * inner, &self.resize.plan_axis(2.0, ih, oh), &mut rows);
        let mut out = vec![0f32; outer * oh * ow * inner];
        resample(&rows, outer * oh, iw, inner, &self.resize.plan_axis(2.0, iw, ow), &mut out);
        f32_value(&shape, out)
    }

    tract_onnx::tract_core::op_out_of_plan!();
}

impl TypedOp for Upsample2x {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        resized_fact("Upsample2x", inputs[0], &self.axes, |_, d| d * 2)
    }

    change_axes_keeping_op!();

    tract_onnx::tract_core::as_op!();
}

impl TypedOp for Subsample {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        resized_fact("Subsample", inputs[0], &self.axes, |_, d| d.div_ceil(2))
    }

    change_axes_keeping_op!();

    tract_onnx::tract_core::as_op!();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corrupt_and_truncated_models_are_errors() {
        assert!(matches!(LandmarkNet::from_onnx(b"not an onnx file"), Err(Error::CorruptData(_))));
        let half = &EMBEDDED_ONNX[..EMBEDDED_ONNX.len() / 2];
        assert!(matches!(LandmarkNet::from_onnx(half), Err(Error::CorruptData(_))));
        let net = LandmarkNet::embedded().unwrap();
        assert!(matches!(net.run(vec![0.5; 10]), Err(Error::OutOfRange { .. })));
        let out = net.run(vec![1.0; INPUT_SIDE * INPUT_SIDE * 3]).unwrap();
        // The deferred net runs the same shared plan.
        let deferred = LandmarkNet::embedded_deferred();
        assert!(matches!(deferred.plan, Plan::Embedded));
        assert_eq!(deferred.run(vec![1.0; INPUT_SIDE * INPUT_SIDE * 3]).unwrap(), out);
        assert!(Arc::ptr_eq(&deferred.plan().unwrap(), &net.plan().unwrap()));
        assert_eq!(out.landmarks.len(), NUM_OUTPUT_LANDMARKS);
        assert!((0.0..=1.0).contains(&out.pose_flag));
        let heatmap = out.heatmap.expect("the asset has MediaPipe's heatmap output");
        assert_eq!(heatmap.len(), HEATMAP_SIDE * HEATMAP_SIDE * NUM_OUTPUT_LANDMARKS);
        assert!(heatmap.iter().any(|&v| v != 0.0));
    }

    /// The rewritten plan (stride-2 depthwise convolutions split, padding made explicit) gives the
    /// same bits as tract's own plan of the model, on a blank page and on a noisy one.
    #[test]
    fn rewritten_depthwise_is_bit_identical() {
        let rewritten = LandmarkNet::build(EMBEDDED_ONNX, true).unwrap();
        let plain = LandmarkNet::build(EMBEDDED_ONNX, false).unwrap();
        let count = |net: &LandmarkNet, name: &str| {
            net.plan().unwrap().model().nodes().iter().filter(|n| n.op().name() == name).count()
        };
        assert_eq!(count(&plain, "Subsample") + count(&plain, "ZeroPad"), 0);
        assert!(count(&rewritten, "Subsample") >= 2, "the 128² and 64² stride-2 convolutions are split");
        assert!(count(&rewritten, "ZeroPad") >= 10);
        assert_eq!(count(&plain, "Upsample2x"), 0);
        assert_eq!(count(&rewritten, "Upsample2x"), 3, "the heatmap head's three bilinear upsamplings");
        let n = INPUT_SIDE * INPUT_SIDE * 3;
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let noise: Vec<f32> = (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 40) as f32 / (1u64 << 24) as f32
            })
            .collect();
        for tensor in [vec![1.0; n], noise] {
            let (a, b) = (rewritten.run(tensor.clone()).unwrap(), plain.run(tensor).unwrap());
            let bits = |o: &RawOutput| -> Vec<u32> {
                let heatmap = o.heatmap.iter().flatten();
                o.landmarks.iter().flatten().chain([&o.pose_flag]).chain(heatmap).map(|v| v.to_bits()).collect()
            };
            assert_eq!(bits(&a), bits(&b));
        }
    }

    #[test]
    fn zero_pad_and_subsample_on_small_tensors() {
        let ctx = EvalContext::out_of_plan();
        let x = tract_ndarray::Array::from_shape_vec((1, 2, 3, 2), (0..12).map(|v| v as f32).collect()).unwrap();
        let pad = ZeroPad { axes: tvec![1, 2], before: tvec![1, 0], after: tvec![0, 1] };
        let padded = pad.eval(&ctx, tvec!(x.into_tensor().into_tvalue())).unwrap().remove(0);
        assert_eq!(padded.shape(), &[1, 3, 4, 2]);
        let want: Vec<f32> =
            [[0.0; 8].as_slice(), &[0., 1., 2., 3., 4., 5., 0., 0.], &[6., 7., 8., 9., 10., 11., 0., 0.]].concat();
        assert_eq!(padded.to_plain_array_view::<f32>().unwrap().iter().copied().collect::<Vec<_>>(), want);
        let kept = Subsample { axes: tvec![1, 2] }.eval(&ctx, tvec!(padded)).unwrap().remove(0);
        assert_eq!(kept.shape(), &[1, 2, 2, 2]);
        let want = [0., 0., 0., 0., 6., 7., 10., 11.];
        assert_eq!(kept.to_plain_array_view::<f32>().unwrap().iter().copied().collect::<Vec<_>>(), want);
        assert!(changed_axes(&[1, 2], &AxisOp::Rm(0)) == Some(tvec![0, 1]));
        assert!(changed_axes(&[1, 2], &AxisOp::Rm(1)).is_none());
        assert!(changed_axes(&[1, 2], &AxisOp::Move(1, 3)).is_none());
    }
}
