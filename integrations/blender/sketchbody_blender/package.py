"""Finding and importing the `sketchbody` Python package (python/ in the sketchbody checkout).

Search order: the add-on preference "Python package folder", the environment variable
SKETCHBODY_PYTHON_PATH (folders separated by os.pathsep), the checkout's python/ folder when the
add-on runs from (or is symlinked to) integrations/blender/ of a checkout, then a pip-installed
`sketchbody`. Import errors are turned into one message with an install hint, never raised into
Blender's UI as a traceback.
"""

import importlib
import os
import sys

ADDON_DIR = os.path.dirname(os.path.realpath(__file__))
# integrations/blender/sketchbody_blender -> the checkout's python/ folder.
CHECKOUT_PYTHON = os.path.normpath(os.path.join(ADDON_DIR, "..", "..", "..", "python"))

INSTALL_HINT = (
    "Install the sketchbody Python package: in the sketchbody checkout run "
    "`cargo build --release -p sketchbody-capi`, then either `pip install ./python` into "
    "Blender's Python or set the add-on preference 'Python package folder' (or the environment "
    "variable SKETCHBODY_PYTHON_PATH) to the checkout's python/ folder. If the library is "
    "elsewhere, set SKETCHBODY_LIBRARY to libsketchbody.so."
)


class PackageError(Exception):
    """The sketchbody package or its library could not be loaded; str() says why and how to fix."""


def candidate_folders(preference=""):
    """Folders to put on sys.path, in search order (existing ones only)."""
    out = []
    if preference:
        out.append(bpy_abspath(preference))
    for p in os.environ.get("SKETCHBODY_PYTHON_PATH", "").split(os.pathsep):
        if p:
            out.append(p)
    out.append(CHECKOUT_PYTHON)
    seen, result = set(), []
    for p in out:
        p = os.path.normpath(os.path.abspath(os.path.expanduser(p)))
        if p not in seen and os.path.isdir(os.path.join(p, "sketchbody")):
            seen.add(p)
            result.append(p)
    return result


def bpy_abspath(path):
    try:
        import bpy

        return bpy.path.abspath(path)
    except Exception:  # outside Blender
        return path


_loaded = None


def load(preference=""):
    """The imported `sketchbody` module, or PackageError with the reason and the install hint."""
    global _loaded
    if _loaded is not None:
        return _loaded
    folders = candidate_folders(preference)
    for p in reversed(folders):
        if p not in sys.path:
            sys.path.insert(0, p)
    try:
        mod = importlib.import_module("sketchbody")
    except ImportError as e:
        # A half-imported package must not stay in sys.modules: a later attempt (after the user
        # fixed the path or built the library) imports it afresh.
        for name in [n for n in sys.modules if n == "sketchbody" or n.startswith("sketchbody.")]:
            del sys.modules[name]
        searched = ", ".join(folders) if folders else "no folder with a sketchbody/ package found"
        reason = " ".join(line.strip() for line in str(e).split("To fix:")[0].splitlines() if line.strip())
        reason = reason or type(e).__name__
        raise PackageError(f"Cannot load the sketchbody package ({reason}; package folders searched: {searched}). "
                           f"{INSTALL_HINT}")
    except Exception as e:  # e.g. a syntax error from an incompatible Python
        for name in [n for n in sys.modules if n == "sketchbody" or n.startswith("sketchbody.")]:
            del sys.modules[name]
        raise PackageError(f"The sketchbody package failed to import: {type(e).__name__}: {e}. {INSTALL_HINT}")
    _loaded = mod
    return mod


def forget():
    """Drops the cached module (after the preference changed)."""
    global _loaded
    _loaded = None
