"""The library context (the body model and the embedded detector)."""

import ctypes
import threading

from . import _bindings as B
from ._lib import Handle, call, new_handle

FEMALE = B.SKB_GENDER_FEMALE
MALE = B.SKB_GENDER_MALE
AUTO = B.SKB_GENDER_AUTO
_GENDERS = {"female": FEMALE, "f": FEMALE, "male": MALE, "m": MALE, "auto": AUTO}


def gender_code(g, allow_auto=True):
    """"female"/"f"/0, "male"/"m"/1 (and "auto"/2 when allowed) as the C code."""
    if isinstance(g, str) and g.lower() in _GENDERS:
        code = _GENDERS[g.lower()]
    elif isinstance(g, int) and not isinstance(g, bool) and g in (FEMALE, MALE, AUTO):
        code = g
    else:
        raise ValueError(f"gender must be 'female', 'male'{' or auto' if allow_auto else ''}, not {g!r}")
    if code == AUTO and not allow_auto:
        raise ValueError("gender must be 'female' or 'male' here")
    return code


def gender_name(code):
    return {FEMALE: "female", MALE: "male"}.get(code, str(code))


class Context(Handle):
    """The library context: the embedded body model and detector (decoded on first use).
    Immutable and thread-safe: one context may serve many threads at once, and the
    functions taking `context=None` share one (default_context()). Meshes and results made
    from it stay valid after it is closed. Close it (or use `with`) to free it early."""

    _free_fn = "skb_context_free"

    def __init__(self):
        super().__init__(new_handle("skb_context_new", B.skb_context))

    def num_components(self, gender):
        """Principal components of `gender`'s shape space (the most weights a shape takes)."""
        n = ctypes.c_size_t()
        call("skb_context_component_count", self._p, gender_code(gender, False), ctypes.byref(n))
        return n.value

    def default_dim(self, gender):
        """The default fitting dimension of `gender`'s shape space (96% of the variance)."""
        n = ctypes.c_size_t()
        call("skb_context_default_dim", self._p, gender_code(gender, False), ctypes.byref(n))
        return n.value


_default = None
_default_lock = threading.Lock()


def default_context():
    """The process-wide shared Context, created on first use (thread-safe)."""
    global _default
    with _default_lock:
        if _default is None or _default.closed:
            _default = Context()
        return _default
