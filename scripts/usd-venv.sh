#!/usr/bin/env bash
# Creates (once) the small Python venv target/usd-venv holding Pixar's `usd-core` wheel (the
# `pxr` modules and the `usdchecker` tool) for the USD export checks (tests/export_usd.rs) and
# prints its bin folder. Quick when already installed.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/usd-venv
base=python3
[ -x /usr/bin/python3 ] && base=/usr/bin/python3
[ -x "$venv/bin/python" ] || "$base" -m venv "$venv" >&2
if ! "$venv/bin/python" -c 'import importlib.metadata as m, sys
sys.exit(m.version("usd-core") != "26.11")' 2>/dev/null; then
  "$venv/bin/pip" install -q 'usd-core==26.11' >&2
fi
echo "$PWD/$venv/bin"
