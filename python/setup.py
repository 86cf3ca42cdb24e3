"""Bundles libsketchbody into the package when it is built.

`pip install ./python` (after `cargo build --release -p sketchbody-capi`) copies
SKETCHBODY_LIBRARY, or else ../target/release/libsketchbody.so, to sketchbody/lib/ inside the
installed package, stripped of debug info when `strip` is available, and tags the wheel as
platform-specific (py3-none-<platform>). Without a built library the package installs without
one and finds the library at run time (SKETCHBODY_LIBRARY, the checkout, the system loader).
Metadata is in pyproject.toml.
"""

import os
import shutil
import subprocess
import sys

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))


def built_library():
    env = os.environ.get("SKETCHBODY_LIBRARY")
    if env:
        if not os.path.isfile(env):
            sys.exit(f"SKETCHBODY_LIBRARY={env}: no such file")
        return env
    p = os.path.join(os.path.dirname(HERE), "target", "release", "libsketchbody.so")
    return p if os.path.isfile(p) else None


LIBRARY = built_library()


class BuildPyWithLibrary(build_py):
    def run(self):
        super().run()
        if not LIBRARY:
            print("sketchbody: no built libsketchbody.so found (run `cargo build --release -p sketchbody-capi` "
                  "first to bundle it); the package will look for it at run time", file=sys.stderr)
            return
        dst_dir = os.path.join(self.build_lib, "sketchbody", "lib")
        os.makedirs(dst_dir, exist_ok=True)
        dst = os.path.join(dst_dir, "libsketchbody.so")
        shutil.copyfile(os.path.realpath(LIBRARY), dst)
        if shutil.which("strip"):
            subprocess.run(["strip", "--strip-debug", dst], check=False)
        print(f"sketchbody: bundled {LIBRARY} ({os.path.getsize(dst) / 1e6:.1f} MB)", file=sys.stderr)


cmdclass = {"build_py": BuildPyWithLibrary}
try:
    try:
        from setuptools.command.bdist_wheel import bdist_wheel
    except ImportError:
        from wheel.bdist_wheel import bdist_wheel

    class BdistWheel(bdist_wheel):
        """A wheel with the library inside is platform-specific but not Python-specific."""

        def finalize_options(self):
            super().finalize_options()
            if LIBRARY:
                self.root_is_pure = False

        def get_tag(self):
            python, abi, plat = super().get_tag()
            return ("py3", "none", plat) if LIBRARY else (python, abi, plat)

    cmdclass["bdist_wheel"] = BdistWheel
except ImportError:
    pass

setup(cmdclass=cmdclass)
