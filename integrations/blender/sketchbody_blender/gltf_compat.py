"""Stock Debian Blender 3.4 and glTF import: its bundled importer (io_import_scene_gltf2) still
uses `numpy.bool`, an alias numpy 1.24 removed, so importing any .glb fails with
"module 'numpy' has no attribute 'bool'" against Debian 12's numpy 1.24. Restoring the alias
(`numpy.bool = bool`, what numpy < 1.24 had) fixes it; the add-on does so when it is enabled,
so File > Import > glTF 2.0 (e.g. a `sketchbody run` body.glb) works while it is on.
"""


def patch_numpy_bool():
    """Sets `numpy.bool = bool` when numpy lacks it (numpy 1.24 to 1.26; numpy 2 has its own
    `numpy.bool` again, which is left alone). Returns True when it patched."""
    import numpy

    if hasattr(numpy, "bool"):
        return False
    numpy.bool = bool
    return True
