#!/usr/bin/env bash
# Tests the Blender add-on (integrations/blender) headless in Debian's Blender 3.4: enables it,
# checks the error paths, runs "Sketch to body" on assets/examples/sketch.png with
# sketch_joints.json, checks the mesh, armature, weights, markers and material against the
# sketchbody Python package, runs it in the background and cancels a run, moves a joint marker and
# re-runs (the edited body kept), compares the detector path with the CLI's `run` (SKB_CLI, else
# target/release/sketchbody, built when missing), and renders the result beside the sketch to
# target/blender-addon/blender-addon.png (integrations/blender/tests/test_addon.py).
# The test writes only under target/: `scripts/test-blender-addon.sh --update-docs` also copies
# the pictures to docs/img/blender-addon.png and blender-addon-detect.png when they differ
# visibly (refreshing the documentation's pictures is a deliberate step, never a test run's).
# The add-on finds the package in python/ of this checkout and the package finds
# target/release/libsketchbody.so (built here when missing), or the library SKETCHBODY_LIBRARY
# names (scripts/test-all.sh's build). Without Blender it prints SKIPPED,
# or fails when SKB_REQUIRE_SHARED_DATA is set (as tests/blender_import.rs). Called by
# scripts/test-all.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
docs_png=()
case "${1:-}" in
  --update-docs) docs_png=(docs/img/blender-addon.png) ;;
  "") ;;
  *) echo "usage: scripts/test-blender-addon.sh [--update-docs]" >&2; exit 2 ;;
esac

if ! blender --version >/dev/null 2>&1; then
  if [ -n "${SKB_REQUIRE_SHARED_DATA:-}" ]; then
    echo "test-blender-addon: Blender is not installed, but SKB_REQUIRE_SHARED_DATA is set" >&2
    exit 1
  fi
  echo "SKIPPED Blender add-on: blender is not installed (apt-get install blender)"
  exit 0
fi
if [ -n "${SKETCHBODY_LIBRARY:-}" ]; then
  [ -f "$SKETCHBODY_LIBRARY" ] || { echo "test-blender-addon: $SKETCHBODY_LIBRARY missing" >&2; exit 1; }
else
  [ -f target/release/libsketchbody.so ] || cargo build --release -p sketchbody-capi
fi
# The CLI whose `run` the add-on's result is compared with (scripts/test-all.sh passes its build).
if [ -n "${SKB_CLI:-}" ]; then
  [ -x "$SKB_CLI" ] || { echo "test-blender-addon: $SKB_CLI missing" >&2; exit 1; }
else
  [ -x target/release/sketchbody ] || cargo build --release -p sketchbody-cli
  export SKB_CLI=$PWD/target/release/sketchbody
fi

out=target/blender-addon
rm -rf "$out" && mkdir -p "$out"
# No user add-ons or preferences (--factory-startup); the package comes from python/ of this
# checkout (SKETCHBODY_PYTHON_PATH unset on purpose: the add-on's checkout default is tested).
status=0
env -u SKETCHBODY_PYTHON_PATH blender -b --factory-startup --python-exit-code 1 \
  --python integrations/blender/tests/test_addon.py -- \
  assets/examples/sketch.png assets/examples/sketch_joints.json "$out/blender-addon.png" "$out/report.json" \
  "${docs_png[@]}" \
  >"$out/blender.log" 2>&1 || status=$?
grep -E '^(ok  |FAIL|blender add-on test|sketchbody package|docs picture)' "$out/blender.log" || true
if [ "$status" -ne 0 ]; then
  echo "test-blender-addon: blender exited with status $status; its log ($out/blender.log):" >&2
  tail -40 "$out/blender.log" >&2
  exit 1
fi

# The same add-on in a windowed Blender under Xvfb, where Blender's event loop runs the add-on's
# timer as for an artist (integrations/blender/tests/test_addon_ui.py: the run in the
# background, Cancel, a re-run keeping the former body, all from timers). Needs xvfb-run
# (apt-get install xvfb; scripts/test-all.sh installs it): without it SKIPPED, or a failure
# when SKB_REQUIRE_SHARED_DATA is set.
if ! command -v xvfb-run >/dev/null 2>&1; then
  if [ -n "${SKB_REQUIRE_SHARED_DATA:-}" ]; then
    echo "test-blender-addon: xvfb-run is not installed, but SKB_REQUIRE_SHARED_DATA is set" >&2
    exit 1
  fi
  echo "SKIPPED Blender add-on in a window: xvfb-run is not installed (apt-get install xvfb)"
  exit 0
fi
rm -f "$out/ui-result.txt"
ui_status=0
env -u SKETCHBODY_PYTHON_PATH timeout 900 xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup \
  --python integrations/blender/tests/test_addon_ui.py -- \
  assets/examples/sketch.png assets/examples/sketch_joints.json "$out/ui-result.txt" \
  >"$out/blender-ui.log" 2>&1 || ui_status=$?
cat "$out/ui-result.txt" 2>/dev/null || true
if [ "$ui_status" -ne 0 ] || [ "$(tail -1 "$out/ui-result.txt" 2>/dev/null)" != "PASS" ]; then
  echo "test-blender-addon: the windowed check failed (status $ui_status); its log ($out/blender-ui.log):" >&2
  tail -40 "$out/blender-ui.log" >&2
  exit 1
fi
