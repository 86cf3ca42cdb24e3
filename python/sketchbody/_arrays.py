"""Input checks: everything handed to C is checked here first, so wrong types, None, short or
non-contiguous arrays raise TypeError / ValueError instead of reaching the library."""

import ctypes
import os

import numpy as np

from . import _bindings as B

_CT = {np.dtype(np.float32): ctypes.c_float, np.dtype(np.float64): ctypes.c_double,
       np.dtype(np.uint32): ctypes.c_uint32, np.dtype(np.int32): ctypes.c_int32,
       np.dtype(np.uint8): ctypes.c_uint8}


def ptr(a):
    """A ctypes pointer to the first element of the C-contiguous array `a`."""
    assert a.flags["C_CONTIGUOUS"]
    return a.ctypes.data_as(ctypes.POINTER(_CT[a.dtype]))


def numeric(x, name, dtype, shape):
    """`x` as a C-contiguous array of `dtype` and `shape` (a tuple; a flat array of the same
    size is accepted too). Integers and floats convert; None, strings, objects, complex or
    booleans raise TypeError; a wrong size raises ValueError."""
    if x is None:
        raise TypeError(f"{name} must be an array of numbers, not None")
    if isinstance(x, (str, bytes)):
        raise TypeError(f"{name} must be an array of numbers, not {type(x).__name__}")
    try:
        a = np.asarray(x)
    except ValueError as e:  # ragged nested lists
        raise ValueError(f"{name}: {e}") from None
    if a.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers, not {a.dtype}")
    a = np.ascontiguousarray(a, dtype=dtype)
    want = int(np.prod(shape))
    if a.shape != tuple(shape):
        if a.size != want:
            raise ValueError(f"{name} must have shape {tuple(shape)} ({want} numbers), got {a.shape}")
        a = a.reshape(shape)
    return a


def vector(x, name, dtype, min_len=0, max_len=None):
    """A 1-D C-contiguous array of `dtype` (None and an empty sequence give length 0)."""
    if x is None:
        return np.zeros(0, dtype=dtype)
    if isinstance(x, (str, bytes)):
        raise TypeError(f"{name} must be a sequence of numbers, not {type(x).__name__}")
    a = np.asarray(x)
    if a.size == 0:
        a = a.astype(dtype)
    if a.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers, not {a.dtype}")
    a = np.ascontiguousarray(a, dtype=dtype).reshape(-1)
    if a.size < min_len or (max_len is not None and a.size > max_len):
        raise ValueError(f"{name} has {a.size} values; expected {min_len}..{max_len}")
    return a


def image(x, name="image"):
    """A numpy image (uint8, (H, W), (H, W, 1), (H, W, 3) RGB or (H, W, 4) RGBA) as
    (skb_image, the array kept alive for the call). Rows must be C-contiguous pixels; other
    layouts are copied. Non-uint8 images are refused (TypeError: scale them to 0..255 first)."""
    if x is None:
        raise TypeError(f"{name} must be a numpy uint8 array or a file path, not None")
    if not isinstance(x, np.ndarray):
        raise TypeError(f"{name} must be a numpy uint8 array or a file path, not {type(x).__name__}")
    if x.dtype != np.uint8:
        raise TypeError(f"{name} must have dtype uint8, not {x.dtype} (convert to 0..255 first)")
    if x.ndim == 3 and x.shape[2] == 1:
        x = x[:, :, 0]
    if x.ndim == 2:
        channels = 1
    elif x.ndim == 3 and x.shape[2] in (3, 4):
        channels = x.shape[2]
    else:
        raise ValueError(f"{name} must be (H, W), (H, W, 3) or (H, W, 4), got shape {x.shape}")
    h, w = x.shape[:2]
    if h == 0 or w == 0:
        raise ValueError(f"{name} is empty ({w}x{h})")
    if max(h, w) > B.SKB_MAX_IMAGE_SIDE:
        raise ValueError(f"{name} is {w}x{h}; the largest side is {B.SKB_MAX_IMAGE_SIDE} px")
    x = np.ascontiguousarray(x)
    view = B.skb_image(ptr(x), w, h, w * channels, channels)
    return view, x


def path_arg(p, name="path"):
    """A str or os.PathLike as NUL-terminated UTF-8 bytes."""
    if p is None:
        raise TypeError(f"{name} must be a path, not None")
    if not isinstance(p, (str, bytes, os.PathLike)):
        raise TypeError(f"{name} must be a str or os.PathLike, not {type(p).__name__}")
    b = os.fsencode(p)
    if b"\0" in b:
        raise ValueError(f"{name} contains a NUL byte")
    return b


def is_path(x):
    return isinstance(x, (str, os.PathLike))


def index(x, name, lo=0, hi=None):
    """A Python int in lo..hi (bool refused)."""
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)):
        raise TypeError(f"{name} must be an int, not {type(x).__name__}")
    x = int(x)
    if x < lo or (hi is not None and x > hi):
        raise ValueError(f"{name} = {x} is outside {lo}..{hi}")
    return x


def real(x, name):
    """A Python float (NaN/inf pass through to the library, which names them)."""
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number, not {type(x).__name__}")
    return float(x)
