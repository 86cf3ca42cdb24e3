"""2-D figure detection: the context's embedded detector or a model file."""

import ctypes
import dataclasses
from typing import Optional, Tuple

import numpy as np

from . import _arrays as A
from . import _bindings as B
from ._lib import Handle, NoFigure, error, lib, new_handle
from ._options import OptionsBase, options_handle
from .context import default_context
from .images import as_image
from .pose import Joints2D


@dataclasses.dataclass
class DetectOptions(OptionsBase):
    """Options of detect() (None: the library default). `backend`: "auto" (default: the sketch
    model and BlazePose, one candidate per image: on a drawing the sketch model recognises the one
    whose proportions the 3-D pose step finds nearer a body's, else the higher calibrated
    confidence), "fmp" (the sketch
    model) or "blazepose"; `strict`: hard thresholds instead of the calibrated presence;
    `threshold`: the sketch model's score threshold when strict (NaN: the model's own); the
    sketch model's search: `figure_range` = (min_fraction, max_fraction) (default figures from
    1/2 of the shorter side to the longer side); `scales` = (min_cell_px, max_cell_px),
    replacing the figure range; `levels_per_octave` (0: the model's own; default 7)."""

    backend: Optional[str] = None
    strict: Optional[bool] = None
    threshold: Optional[float] = None
    scales: Optional[Tuple[float, float]] = None
    figure_range: Optional[Tuple[float, float]] = None
    levels_per_octave: Optional[int] = None

    _c_prefix = "skb_detect_options"
    _enums = {"backend": {"auto": B.SKB_DETECTOR_AUTO, "fmp": B.SKB_DETECTOR_FMP,
                          "blazepose": B.SKB_DETECTOR_BLAZEPOSE}}


@dataclasses.dataclass
class Detection:
    """The best figure: `joints` (Joints2D, all visible), `confidence` (15,) in [0, 1], `score`.
    From detect(): calibrated confidences (each the probability that the joint is within 0.2 x
    the figure's size of the truth), `score` their mean (the expected fraction of correct
    joints), `backend` kept ("fmp", "blazepose"), `presence` (probability that the image holds a
    figure), `low_confidence` (score < 0.75: show the joints to the user for correction). From
    Detector.detect(): the model's raw confidences and score; the other fields None."""

    joints: Joints2D
    confidence: np.ndarray
    score: float
    backend: Optional[str] = None
    presence: Optional[float] = None
    low_confidence: Optional[bool] = None
    facing: Optional["Facing"] = None


FACINGS = ("front", "back", "left", "right")
_FACING_NAMES = {B.SKB_FACING_FRONT: "front", B.SKB_FACING_BACK: "back", B.SKB_FACING_LEFT: "left",
                 B.SKB_FACING_RIGHT: "right", B.SKB_FACING_UNKNOWN: "unknown"}


@dataclasses.dataclass
class Facing:
    """Which way the detected figure faces: `facing` "front", "back", "left" (a left profile:
    the character's left side toward the viewer), "right" or "unknown" (no facing reaches
    probability 0.6, a back view 0.5 with the front ruled out; or a back view in a photo-like
    image); `probabilities` {facing: p} over the four (summing to 1); `swapped` (the
    joints are the detector's with left and right swapped: a labelling that implied a back view
    without evidence of one, or the reverse); `alternative` (Joints2D: the joints with left and
    right swapped) and `alternative_score` (the probability that it is the right labelling)."""

    facing: str
    probabilities: dict
    swapped: bool
    alternative: Joints2D
    alternative_score: float

    @classmethod
    def from_struct(cls, f):
        """From a filled skb_facing_info."""
        return cls(_FACING_NAMES.get(f.facing, "?"), dict(zip(FACINGS, list(f.probabilities))), bool(f.swapped),
                   Joints2D.from_struct(f.alternative), f.alternative_score)


@dataclasses.dataclass
class FigureInfo:
    """What the embedded detector found behind a pipeline result's joints (Result.detection()):
    `backend` kept ("fmp", "blazepose"), `confidence` (calibrated: the expected fraction of
    joints within 0.2 x the figure's size of the truth), `presence` (probability that the image
    holds a figure), `low_confidence` (confidence < 0.75: show the joints for correction),
    `other_figures` (further figures the sketch model found above its threshold)."""

    backend: str
    confidence: float
    presence: float
    low_confidence: bool
    other_figures: int

    @classmethod
    def from_struct(cls, info):
        """From a filled skb_figure_info."""
        return cls(_BACKEND_NAMES.get(info.backend, "?"), info.confidence, info.presence,
                   bool(info.low_confidence), int(info.other_figures))


_BACKEND_NAMES = {B.SKB_DETECTOR_AUTO: "auto", B.SKB_DETECTOR_FMP: "fmp", B.SKB_DETECTOR_BLAZEPOSE: "blazepose"}


def _detect(fn, first_args, view, keep, rest=()):
    xy = np.empty((15, 2), dtype=np.float64)
    conf = np.empty(15, dtype=np.float64)
    score = ctypes.c_double(float("nan"))
    st = getattr(lib, fn)(*first_args[:1], ctypes.byref(view), *first_args[1:], *rest, A.ptr(xy), xy.size,
                          A.ptr(conf), conf.size, ctypes.byref(score))
    del keep
    if st != B.SKB_OK:
        e = error(st, fn)
        if isinstance(e, NoFigure):
            e.score = score.value
        raise e
    return Detection(Joints2D(xy), conf, score.value)


def detect(image, options=None, context=None):
    """Detects the best figure in `image` (numpy uint8 image or a path) with the embedded
    backends (see DetectOptions). Raises NoFigure when the image holds no figure (blank pages,
    text, clutter; or, when strict, nothing passes a backend's threshold). Thread-safe."""
    ctx = context or default_context()
    view, keep = as_image(image)
    with options_handle(options, DetectOptions) as h:
        xy = np.empty((15, 2), dtype=np.float64)
        conf = np.empty(15, dtype=np.float64)
        info, facing = B.skb_figure_info(), B.skb_facing_info()
        st = lib.skb_context_detect_facing(ctx._p, ctypes.byref(view), h, A.ptr(xy), xy.size, A.ptr(conf), conf.size,
                                   ctypes.byref(info), ctypes.byref(facing))
        del keep
        if st != B.SKB_OK:
            raise error(st, "skb_context_detect_facing")
        return Detection(Joints2D(xy), conf, info.confidence, _BACKEND_NAMES.get(info.backend, "?"),
                         info.presence, bool(info.low_confidence), Facing.from_struct(facing))


class Detector(Handle):
    """A detector model loaded from a `.skbd` file or the PARSE model JSON. Immutable and
    thread-safe."""

    _free_fn = "skb_detector_free"

    def __init__(self, path):
        super().__init__(new_handle("skb_detector_new_from_file", B.skb_detector, A.path_arg(path)))

    def detect(self, image, options=None):
        """As detect(), with this model and the sketch-model settings of `options`
        (DetectOptions: threshold, scales, figure_range, levels_per_octave; None: the
        defaults)."""
        view, keep = as_image(image)
        with options_handle(options, DetectOptions) as h:
            return _detect("skb_detector_detect", (self._p,), view, keep, (h, None, None))
