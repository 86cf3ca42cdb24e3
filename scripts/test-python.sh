#!/usr/bin/env bash
# Tests the Python package (python/): installs it with the freshly built library into a venv
# under target/ and runs python/tests (the ctypes drift test against include/sketchbody.h, the
# Pythonic layer on the bundled example, the Dask batch on a local two-worker cluster).
# Needs target/release/libsketchbody.so (`cargo build --release -p sketchbody-capi`), or the
# library SKETCHBODY_LIBRARY names (scripts/test-all.sh passes its target/sanitize build). The
# tests load the copy the package bundled, as a user's install does. Called by scripts/test-all.sh.
#
# The venv (target/py-venv) is made from Debian's /usr/bin/python3 with --system-site-packages,
# so python3-numpy is used as installed (Debian 12's system Python is externally managed: no
# pip install into it). dask[distributed] is pip-installed into the venv on the first run only.
# Without network the batch test prints SKIPPED unless SKB_REQUIRE_DASK=1.
set -euo pipefail
cd "$(dirname "$0")/.."

# SKETCHBODY_LIBRARY overrides the library bundled and tested (setup.py and the package read it).
lib=${SKETCHBODY_LIBRARY:-target/release/libsketchbody.so}
[ -f "$lib" ] || { echo "test-python: $lib missing: run cargo build --release -p sketchbody-capi" >&2; exit 1; }

base=python3
[ -x /usr/bin/python3 ] && base=/usr/bin/python3
venv=target/py-venv
if ! "$venv/bin/python" -c "import numpy" >/dev/null 2>&1; then
  echo "== creating $venv (from $base, with system site packages)"
  rm -rf "$venv"
  "$base" -m venv --system-site-packages "$venv"
fi
py="$venv/bin/python"
if ! "$py" -c "import dask, distributed" >/dev/null 2>&1; then
  echo "== installing dask[distributed] into $venv"
  "$py" -m pip install -q "dask[distributed]" || echo "test-python: could not install dask[distributed]" >&2
fi

echo "== pip install ./python (bundles $lib)"
"$py" -m pip install -q --no-build-isolation --no-deps ./python
rm -rf python/build python/sketchbody.egg-info

echo "== python/tests (installed package: $(env -u SKETCHBODY_LIBRARY "$py" -c 'import sketchbody; print(sketchbody.__file__, sketchbody.library_path())' 2>&1))"
cd python/tests
env -u SKETCHBODY_LIBRARY "../../$py" -m unittest discover -s . -p 'test_*.py' -v
