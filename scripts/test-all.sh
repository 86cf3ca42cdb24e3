#!/usr/bin/env bash
# Runs every test of sketchbody on a fresh Debian 12 machine: installs the Debian packages it
# needs when missing (blender and python3-numpy for the Blender import and add-on tests, xvfb for
# the add-on's windowed check, python3-opencv for the BlazePose reference, assimp-utils for the
# FBX export's second reader, abigail-tools for the C ABI check against the 1.0 baseline), a small Python venv for that reference (scripts/reference-venv.sh) and one with Pixar's usd-core
# for the USD export (scripts/usd-venv.sh), then cargo tests, the CMake/ctest harness (OpenCV, Ceres, Embree
# cross-checks, C and C++ API tests under sanitizers), the Python package's tests
# (scripts/test-python.sh), the Blender add-on's, the Windows DLL's C API tests under Wine
# (scripts/windows-dll.sh; MinGW-w64 cross build in the background meanwhile), and last a short
# run of every fuzz target (scripts/fuzz.sh; cargo-fuzz's flags with plain cargo; built in the
# background meanwhile).
# Set SKB_REQUIRE_SHARED_DATA=1 to turn "skipped: ../shared/data missing" into failures (CI does).
set -euo pipefail
cd "$(dirname "$0")/.."

# step MESSAGE: announces a step with the time elapsed since the start (m:ss), so a slow CI run
# shows where its time went.
step() { printf '== [%d:%02d] %s\n' $((SECONDS / 60)) $((SECONDS % 60)) "$*"; }

packages=(cmake g++ pkg-config python3 libopencv-dev libceres-dev libembree-dev blender xvfb python3-numpy python3-opencv assimp-utils abigail-tools
          gcc-mingw-w64-x86-64 g++-mingw-w64-x86-64 wine wine64)
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

windows_triple=x86_64-pc-windows-gnu
if ! rustup target list --installed | grep -qx "$windows_triple"; then
  step "installing the Rust target $windows_triple (the Windows DLL's cross build)"
  rustup target add "$windows_triple"
fi

# The test run must leave the checkout as it found it: tests write only under target/, build/
# or a temporary folder (checked at the end against this snapshot of the work tree's state).
tree_state() {
  git status --porcelain=v1 --untracked-files=all 2>/dev/null && git diff 2>/dev/null | sha256sum
}
tree_before=$(tree_state || true)

jobs=$(nproc)
# The fuzz targets' instrumented build (every dependency again, with libFuzzer's flags: the
# longest build here) runs in the background at the lowest CPU priority, on the core time the
# steps below leave idle (downloads, serial test programs); it is joined before the targets run.
mkdir -p target
fuzz_build_log=target/fuzz-build.log
step "fuzz targets: building in the background (scripts/fuzz.sh build, log $fuzz_build_log)"
# Job control on for this one job: it gets a process group of its own, so that a failing step
# stops the build with all its children. (Not setsid: a new session is a new scheduler autogroup,
# in which nice 19 counts for nothing against this script's processes.)
set -m
nice -n 19 scripts/fuzz.sh build >"$fuzz_build_log" 2>&1 &
fuzz_build_pid=$!
set +m
# The Windows DLL's cross build (every dependency again, for x86_64-pc-windows-gnu, in its own
# cargo folder target/windows-gnu), the same way and with the test build's profile.
windows_build_log=target/windows-build.log
step "Windows DLL: building in the background (scripts/windows-dll.sh build, log $windows_build_log)"
set -m
nice -n 19 scripts/windows-dll.sh build sanitize >"$windows_build_log" 2>&1 &
windows_build_pid=$!
set +m
trap 'kill -- -"$fuzz_build_pid" -"$windows_build_pid" 2>/dev/null || true' EXIT

step "lint gates: cargo fmt --check, cargo clippy -D warnings"
cargo fmt --all --check
feature_list=sketchbody/model-builder,sketchbody/test-fixtures
features=(--features "$feature_list")
# Every test below runs on one build, cargo's `sanitize` profile (Cargo.toml: release code with
# overflow checks and debug assertions in sketchbody's own crates): the cargo tests, the CMake
# harness (whose ASan/UBSan C tests need that profile), the Python package and the Blender add-on.
# Two profiles would compile every dependency, tract above all, twice. Clippy takes the same
# profile, so the build scripts and proc-macros it compiles are the test build's.
profile=sanitize
lib_dir="$PWD/target/$profile"
cargo clippy --profile "$profile" --workspace --all-targets "${features[@]}" -- -D warnings

step "MediaPipe reference venv (the BlazePose cross-check, tests/blazepose_reference.rs)"
SKB_MEDIAPIPE_PYTHON="$(scripts/reference-venv.sh)"
export SKB_MEDIAPIPE_PYTHON

step "usd-core venv (usdchecker's validators and UsdSkel for the USD export, tests/export_usd.rs)"
SKB_USD_PYTHON="$(scripts/usd-venv.sh)/python"
export SKB_USD_PYTHON

step "cargo test (profile $profile, shared with the CMake build)"
cargo test --profile "$profile" --workspace --all-targets "${features[@]}"
cargo test --profile "$profile" --workspace --doc "${features[@]}"


step "CMake build + ctest (cargo's folder shared with the cargo tests above)"
# The library is built with the cargo test run's profile and selection, so cargo reuses that build
# (CMakeLists.txt, SKB_CARGO_PROFILE, SKB_CARGO_SELECTION) instead of compiling every crate again.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSKB_CARGO_TARGET_DIR="$PWD/target" \
  -DSKB_CARGO_PROFILE="$profile" -DSKB_CARGO_SELECTION="--workspace;--lib;--tests;--features;$feature_list"
cmake --build build -j "$jobs"
(cd build && ctest --output-on-failure -j 1)

export SKETCHBODY_LIBRARY="$lib_dir/libsketchbody.so" SKB_CLI="$lib_dir/sketchbody"
step "Python package (python/tests: bindings drift, the pipeline, the Dask batch)"
scripts/test-python.sh

step "Blender add-on (integrations/blender, headless Blender 3.4; renders target/blender-addon/blender-addon.png)"
scripts/test-blender-addon.sh

step "Windows DLL: joining the background build, then the C API tests under Wine"
if ! wait "$windows_build_pid"; then
  tail -n 60 "$windows_build_log"
  echo "== the Windows DLL's build FAILED (log: $windows_build_log)"
  exit 1
fi
tail -n 1 "$windows_build_log"
scripts/windows-dll.sh test

step "fuzz targets: joining the background build"
if ! wait "$fuzz_build_pid"; then
  tail -n 60 "$fuzz_build_log"
  echo "== the fuzz targets' build FAILED (log: $fuzz_build_log)"
  exit 1
fi
trap - EXIT
step "fuzz targets: 2000 executions each from the committed seeds (the long run: scripts/fuzz.sh 1000000)"
scripts/fuzz.sh 2000

step "the work tree is as the tests found it (tests write only under target/, build/ or a temporary folder)"
tree_after=$(tree_state || true)
if [ "$tree_before" != "$tree_after" ]; then
  diff <(echo "$tree_before") <(echo "$tree_after") || true
  echo "== the tests changed files of the checkout (above)"
  exit 1
fi

step "all tests passed"
