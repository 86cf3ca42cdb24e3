#!/usr/bin/env bash
# Runs every test of sketchbody on a fresh Debian 12 machine: installs the Debian packages it
# needs when missing (blender and python3-numpy for the Blender import and add-on tests,
# python3-opencv for the BlazePose reference), a small Python venv for that reference
# (scripts/reference-venv.sh), then cargo tests,
# a short run of every fuzz target (scripts/fuzz.sh; installs cargo-fuzz when missing), the
# CMake/ctest harness (OpenCV, Ceres, Embree cross-checks, C and C++ API tests under
# sanitizers) and the Python package's tests (scripts/test-python.sh).
# Set SKB_REQUIRE_SHARED_DATA=1 to turn "skipped: ../shared/data missing" into failures (CI does).
set -euo pipefail
cd "$(dirname "$0")/.."

# step MESSAGE: announces a step with the time elapsed since the start (m:ss), so a slow CI run
# shows where its time went.
step() { printf '== [%d:%02d] %s\n' $((SECONDS / 60)) $((SECONDS % 60)) "$*"; }

packages=(cmake g++ pkg-config python3 libopencv-dev libceres-dev libembree-dev blender python3-numpy python3-opencv)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  step "installing Debian packages: ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${missing[@]}"
fi

jobs=$(nproc)
step "lint gates: cargo fmt --check, cargo clippy -D warnings"
cargo fmt --all --check
feature_list=sketchbody/model-builder,sketchbody/test-fixtures
features=(--features "$feature_list")
cargo clippy --release --workspace --all-targets "${features[@]}" -- -D warnings

step "MediaPipe reference venv (the BlazePose cross-check, tests/blazepose_reference.rs)"
SKB_MEDIAPIPE_PYTHON="$(scripts/reference-venv.sh)"
export SKB_MEDIAPIPE_PYTHON

step "cargo test (release build, shared with the CMake build)"
cargo test --release --workspace --all-targets "${features[@]}"
cargo test --release --workspace --doc "${features[@]}"

step "fuzz targets: 2000 executions each from the committed seeds (the long run: scripts/fuzz.sh 1000000)"
scripts/fuzz.sh 2000

step "CMake build + ctest (cargo's folder shared with the cargo tests above)"
# The library is built with the cargo test run's selection, so cargo reuses that build (CMakeLists.txt,
# SKB_CARGO_SELECTION) instead of compiling every crate again with other features.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSKB_CARGO_TARGET_DIR="$PWD/target" \
  -DSKB_CARGO_SELECTION="--workspace;--lib;--tests;--features;$feature_list"
cmake --build build -j "$jobs"
(cd build && ctest --output-on-failure -j 1)

step "Python package (python/tests: bindings drift, the pipeline, the Dask batch)"
scripts/test-python.sh

step "Blender add-on (integrations/blender, headless Blender 3.4; renders docs/img/blender-addon.png)"
scripts/test-blender-addon.sh

step "all tests passed"
