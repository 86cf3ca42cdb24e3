"""Options: plain Python dataclasses turned into the C option handles for one call.

Every field defaults to None, meaning the library's default. Values are checked by type here
and by range in the C setters (SketchbodyError SKB_ERR_OUT_OF_RANGE / SKB_ERR_NON_FINITE
naming the option)."""

import dataclasses

from . import _arrays as A
from . import _bindings as B
from ._lib import call, lib, new_handle


def _convert(value, ctype, what):
    if ctype == "double":
        return A.real(value, what)
    if ctype in ("uint32_t", "uint64_t"):
        return A.index(value, what, 0, 2**32 - 1 if ctype == "uint32_t" else 2**64 - 1)
    if ctype in ("bool", "int"):
        if not isinstance(value, (bool, int)):
            raise TypeError(f"{what} must be a bool, not {type(value).__name__}")
        return int(bool(value)) if ctype == "int" else bool(value)
    raise AssertionError(ctype)


class OptionsBase:
    """Base of the option dataclasses: `_c_prefix` names the C handle (`skb_<x>_options`),
    `_enums` maps a field to {name: code}."""

    _c_prefix = ""
    _enums = {}

    def handle(self):
        """A new C options handle with these values (caller frees it with free_handle)."""
        opaque = getattr(B, f"{self._c_prefix}")
        h = new_handle(f"{self._c_prefix}_new", opaque)
        try:
            for f in dataclasses.fields(self):
                v = getattr(self, f.name)
                if v is None:
                    continue
                fn = f"{self._c_prefix}_set_{f.name}"
                params = B.FUNCTIONS[fn][3][1:]
                what = f"{type(self).__name__}.{f.name}"
                if f.name in self._enums:
                    table = self._enums[f.name]
                    if isinstance(v, str):
                        if v.lower() not in table:
                            raise ValueError(f"{what} must be one of {sorted(table)}, not {v!r}")
                        v = table[v.lower()]
                if len(params) > 1:
                    if isinstance(v, (str, bytes)) or not hasattr(v, "__len__") or len(v) != len(params):
                        raise TypeError(f"{what} must be a tuple of {len(params)} values")
                    args = [_convert(x, ct, what) for x, (_, ct) in zip(v, params)]
                else:
                    args = [_convert(v, params[0][1], what)]
                call(fn, h, *args)
        except BaseException:
            self.free_handle(h)
            raise
        return h

    def free_handle(self, h):
        getattr(lib, f"{self._c_prefix}_free")(h)


class options_handle:
    """`with options_handle(opts) as h:` a C handle for `opts` (None -> NULL)."""

    def __init__(self, opts, cls):
        if opts is not None and not isinstance(opts, cls):
            raise TypeError(f"options must be a {cls.__name__} or None, not {type(opts).__name__}")
        self.opts, self.h = opts, None

    def __enter__(self):
        if self.opts is not None:
            self.h = self.opts.handle()
        return self.h

    def __exit__(self, *exc):
        if self.h is not None:
            self.opts.free_handle(self.h)
