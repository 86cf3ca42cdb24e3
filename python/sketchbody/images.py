"""Images: the library's PNG/JPEG loaders and PNG writer, Canny edges and Gaussian blur, on
numpy arrays.

Images are numpy uint8 arrays: (H, W) gray, (H, W, 3) RGB or (H, W, 4) RGBA (alpha ignored).
Every function accepting an image also accepts a path (str or os.PathLike) to a PNG or JPEG,
decoded by the library as gray (OpenCV's weights)."""

import ctypes

import numpy as np

from . import _arrays as A
from . import _bindings as B
from ._lib import Handle, call, lib, new_handle


class _GrayImage(Handle):
    _free_fn = "skb_gray_image_free"


class _RgbImage(Handle):
    _free_fn = "skb_rgb_image_free"


def load_image(path):
    """Decodes a PNG or JPEG file as an 8-bit gray (H, W) array (a copy; colour converted
    with OpenCV's weights). Errors: SketchbodyError SKB_ERR_IO (missing, unreadable),
    SKB_ERR_DECODE (not an image), SKB_ERR_IMAGE_TOO_LARGE."""
    p = A.path_arg(path)
    with _GrayImage(new_handle("skb_gray_image_new_from_file", B.skb_gray_image, p)) as img:
        view = B.skb_image()
        call("skb_gray_image_view", img._p, ctypes.byref(view))
        h, w, stride = view.height, view.width, view.stride
        buf = ctypes.string_at(view.data, stride * (h - 1) + w) if h else b""
    rows = np.frombuffer(buf + b"\0" * (stride * h - len(buf)), dtype=np.uint8).reshape(h, stride)
    return np.ascontiguousarray(rows[:, :w])


def load_rgb_image(path):
    """Decodes a PNG or JPEG file as an 8-bit RGB (H, W, 3) array (a copy; gray expanded,
    transparency composited over white, EXIF orientation applied): the sketch as `sketchbody run`
    reads it for the texture. Errors as load_image."""
    p = A.path_arg(path)
    with _RgbImage(new_handle("skb_rgb_image_new_from_file", B.skb_rgb_image, p)) as img:
        view = B.skb_image()
        call("skb_rgb_image_view", img._p, ctypes.byref(view))
        h, w = view.height, view.width
        buf = ctypes.string_at(view.data, 3 * w * h)
    return np.frombuffer(buf, dtype=np.uint8).reshape(h, w, 3).copy()


def write_png(image, path):
    """Writes a numpy uint8 image ((H, W) gray, (H, W, 3) RGB, (H, W, 4) RGBA) as an 8-bit PNG
    with the library's encoder (the bytes `sketchbody run` writes for the same pixels),
    atomically: on error nothing is left at `path`."""
    view, keep = A.image(image, "image")
    call("skb_image_write_png", ctypes.byref(view), A.path_arg(path))
    del keep


def as_image(image, name="image"):
    """(skb_image view, keep-alive array) of a numpy image or a file path."""
    if A.is_path(image):
        image = load_image(image)
    return A.image(image, name)


def canny(image, low=50.0, high=150.0, aperture=3, l2_gradient=False):
    """Canny edges (255 edge, 0 not) as a (H, W) uint8 array, bit-exact with OpenCV 4.6
    cv::Canny on the gray image (colour converted with COLOR_RGB2GRAY). The thresholds may be
    given in either order; `aperture` is 3, 5 or 7."""
    view, keep = as_image(image)
    out = np.empty((view.height, view.width), dtype=np.uint8)
    call("skb_image_canny", ctypes.byref(view), A.real(low, "low"), A.real(high, "high"),
         A.index(aperture, "aperture", 0, 2**31 - 1), bool(l2_gradient), A.ptr(out), view.width, out.size)
    del keep
    return out


def gaussian_blur(image, sigma):
    """Gaussian blur of a gray image (sigma in pixels, 0 < sigma <= 1024), equal to OpenCV's
    cv::GaussianBlur(src, dst, Size(0, 0), sigma). Returns a new (H, W) uint8 array."""
    view, keep = as_image(image)
    if view.channels != 1:
        raise ValueError("gaussian_blur takes a gray (H, W) image")
    out = np.empty((view.height, view.width), dtype=np.uint8)
    call("skb_image_gaussian_blur", ctypes.byref(view), A.real(sigma, "sigma"), A.ptr(out), view.width, out.size)
    del keep
    return out


def render_sketch(gender, width=512, height=512, weights=None, joints3d=None, seed=0, style="random",
                  camera=None, context=None):
    """The synthetic-sketch renderer (the detector's training data): a (height, width) uint8
    gray sketch of a body of `gender` ("female"/"male"), PCA `weights` (None: a random shape),
    posed onto `joints3d` ((15, 3) metres; None: a random pose), drawn in `style` ("random" or
    "clean"), camera angles `camera` = (yaw, pitch, roll) degrees (None: random near-frontal).
    Returns (image, joints2d (15, 2) pixels, visible (15,) bool)."""
    from .context import default_context, gender_code
    ctx = context or default_context()
    g = gender_code(gender, allow_auto=False)
    w = A.vector(weights, "weights", np.float32)
    j = None if joints3d is None else A.numeric(joints3d, "joints3d", np.float64, (15, 3))
    styles = {"random": B.SKB_SKETCH_STYLE_RANDOM, "clean": B.SKB_SKETCH_STYLE_CLEAN}
    if style not in styles:
        raise ValueError(f"style must be one of {sorted(styles)}, not {style!r}")
    opts = new_handle("skb_sketch_options_new", B.skb_sketch_options)
    try:
        call("skb_sketch_options_set_style", opts, styles[style])
        if camera is not None:
            yaw, pitch, roll = (A.real(v, "camera") for v in camera)
            call("skb_sketch_options_set_camera", opts, yaw, pitch, roll)
        width, height = A.index(width, "width", 1, 4096), A.index(height, "height", 1, 4096)
        img = np.empty((height, width), dtype=np.uint8)
        xy = np.empty((15, 2), dtype=np.float64)
        vis = np.empty(15, dtype=np.uint8)
        call("skb_context_render_sketch", ctx._p, g, A.ptr(w) if w.size else None, w.size,
             None if j is None else A.ptr(j), A.index(seed, "seed", 0, 2**64 - 1), width, height, opts,
             A.ptr(img), width, img.size, A.ptr(xy), A.ptr(vis))
    finally:
        lib.skb_sketch_options_free(opts)
    return img, xy, vis.astype(bool)
