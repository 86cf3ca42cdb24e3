"""Finding and loading libsketchbody, the errors, and the small helpers every wrapper uses.

Library lookup order (the first that exists wins; see python/README.md):
1. the environment variable SKETCHBODY_LIBRARY (a path to the shared library; when it is set
   and the file does not exist that is an error, no fallback);
2. the library bundled in the package (sketchbody/lib/libsketchbody.so, copied by
   `pip install ./python` when it finds the built library);
3. the repository's target/release/libsketchbody.so (when running from a checkout);
4. the system loader (`libsketchbody.so.1`, `libsketchbody.so`: LD_LIBRARY_PATH, ldconfig).
"""

import ctypes
import enum
import os

from . import _bindings as B

_HERE = os.path.dirname(os.path.abspath(__file__))
_NAMES = ("libsketchbody.so",)
_SYSTEM_NAMES = ("libsketchbody.so.1", "libsketchbody.so")

INSTALL_HINT = (
    "build the library and install the package: `cargo build --release -p sketchbody-capi` "
    "then `pip install ./python` in the sketchbody checkout; or point SKETCHBODY_LIBRARY at "
    "libsketchbody.so (e.g. /opt/sketchbody/lib/libsketchbody.so.1 after `cmake --install`)"
)


class LibraryNotFoundError(ImportError):
    """libsketchbody could not be found or loaded (an ImportError, so `import sketchbody`
    fails with it). The message lists the places searched and how to install."""


def _candidates():
    env = os.environ.get("SKETCHBODY_LIBRARY")
    if env:
        return [("SKETCHBODY_LIBRARY", env)], True
    out = [("bundled", os.path.join(_HERE, "lib", n)) for n in _NAMES]
    repo = os.path.dirname(os.path.dirname(_HERE))
    out += [("repository", os.path.join(repo, "target", "release", n)) for n in _NAMES]
    return out, False


def _load():
    cands, explicit = _candidates()
    tried = []
    for where, path in cands:
        if not os.path.exists(path):
            tried.append(f"{where}: {path} (missing)")
            continue
        try:
            return ctypes.CDLL(os.path.abspath(path)), os.path.abspath(path)
        except OSError as e:
            tried.append(f"{where}: {path} ({e})")
    if not explicit:
        for name in _SYSTEM_NAMES:
            try:
                return ctypes.CDLL(name), name
            except OSError:
                tried.append(f"system loader: {name} (not found)")
    raise LibraryNotFoundError(
        "sketchbody: cannot load libsketchbody; tried\n  " + "\n  ".join(tried) + "\nTo fix: " + INSTALL_HINT,
        name="sketchbody")


lib, LIBRARY_PATH = _load()
_missing = B.declare(lib)
if _missing:
    raise LibraryNotFoundError(
        f"sketchbody: {LIBRARY_PATH} lacks {len(_missing)} functions of the header the package was "
        f"generated from (first: {_missing[0]}): the library is older than the package. " + INSTALL_HINT,
        name="sketchbody", path=LIBRARY_PATH)
_lib_version = lib.skb_version().decode()
if _lib_version.split(".")[0] != B.SKB_VERSION_STRING.split(".")[0]:
    raise LibraryNotFoundError(
        f"sketchbody: {LIBRARY_PATH} is version {_lib_version}, the package needs "
        f"{B.SKB_VERSION_STRING} (same major version). " + INSTALL_HINT,
        name="sketchbody", path=LIBRARY_PATH)


Status = enum.IntEnum("Status", {name: value for value, name in B.STATUS_NAMES.items()})
Status.__doc__ = "The C API's status codes (enum skb_status): Status.SKB_ERR_IO == 11."


class SketchbodyError(Exception):
    """A sketchbody C call failed.

    Attributes: `status` (int, the skb_status code), `status_name` (e.g. "SKB_ERR_IO"),
    `message` (skb_last_error_message(): the specific reason), `function` (the C function).
    str(error) is "<function>: <message> (<status_name>)".
    """

    def __init__(self, status, message, function=""):
        self.status = int(status)
        self.status_name = B.STATUS_NAMES.get(self.status, f"status {self.status}")
        self.message = message or status_text(self.status)
        self.function = function
        prefix = f"{function}: " if function else ""
        super().__init__(f"{prefix}{self.message} ({self.status_name})")


class Cancelled(SketchbodyError):
    """SKB_ERR_CANCELLED: the progress callback or the cancel event stopped the call."""


class NoFigure(SketchbodyError):
    """SKB_ERR_NO_FIGURE: the detector found no figure; `score` is what fell below the
    threshold: the calibrated probability that the image holds a figure (the default), or the
    backend's raw score when strict (-inf when no scale was searched)."""

    score = float("nan")


_CLASSES = {B.SKB_ERR_CANCELLED: Cancelled, B.SKB_ERR_NO_FIGURE: NoFigure}


def status_text(status):
    """skb_status_str: the generic English text of a status code."""
    return lib.skb_status_str(int(status)).decode("utf-8", "replace")


def error(status, function=""):
    """The exception for `status`, with this thread's last error message (call right after
    the failing C call, on the same thread)."""
    msg = lib.skb_last_error_message().decode("utf-8", "replace")
    return _CLASSES.get(int(status), SketchbodyError)(status, msg, function)


def call(name, *args):
    """Calls C function `name`; raises SketchbodyError on a non-zero status."""
    st = getattr(lib, name)(*args)
    if st != B.SKB_OK:
        raise error(st, name)


class Handle:
    """Owner of one C object, freed by close(), by leaving a `with` block or by the garbage
    collector (__del__). close() is idempotent; using a closed handle raises ValueError. Do not
    close a handle while another thread is using it."""

    _free_fn = ""

    def __init__(self, ptr):
        self._ptr = ptr

    @property
    def _p(self):
        p = self._ptr
        if not p:
            raise ValueError(f"operation on a closed {type(self).__name__}")
        return p

    @property
    def closed(self):
        return not self._ptr

    def close(self):
        p, self._ptr = self._ptr, None
        if p and lib is not None:
            getattr(lib, self._free_fn)(p)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown
            pass


def new_handle(new_fn, opaque, *args):
    """Calls `new_fn(*args, &out)` and returns the out pointer."""
    out = ctypes.POINTER(opaque)()
    call(new_fn, *args, ctypes.byref(out))
    return out


class Progress:
    """The skb_progress_fn trampoline for one call: forwards the fraction to `progress`
    (a callable; returning False cancels, None or True continues) and cancels when `cancel`
    (anything with is_set(), e.g. threading.Event) is set. An exception raised by `progress`
    cancels the C call and is re-raised by `reraise()` after it returns."""

    def __init__(self, progress=None, cancel=None, always=False):
        if progress is not None and not callable(progress):
            raise TypeError(f"progress must be callable, not {type(progress).__name__}")
        if cancel is not None and not callable(getattr(cancel, "is_set", None)):
            raise TypeError("cancel must have an is_set() method (e.g. threading.Event)")
        self.progress, self.cancel, self.exc = progress, cancel, None
        self.fn = B.skb_progress_fn(self._cb) if (progress or cancel or always) else B.skb_progress_fn()

    def _cb(self, _user, fraction):
        try:
            if self.exc is not None:
                return 1
            if self.cancel is not None and self.cancel.is_set():
                return 1
            if self.progress is not None and self.progress(float(fraction)) is False:
                return 1
            return 0
        except BaseException as e:  # noqa: BLE001 - re-raised after the C call
            self.exc = e
            return 1

    def reraise(self):
        if self.exc is not None:
            e, self.exc = self.exc, None
            raise e
