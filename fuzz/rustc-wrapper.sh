#!/usr/bin/env bash
# RUSTC_WRAPPER for the fuzz build (scripts/fuzz.sh sets it): compiles the tract crates (the
# landmark model's inference engine) and their matrix kernels without libFuzzer's coverage
# instrumentation, every other crate as cargo-fuzz asks.
#
# Why: with the instrumentation, comparison tracing inside tract's convolution loops took 60 % of
# the C-API target's time (perf, 2026-12-03: __sanitizer_cov_trace_cmp8 and _const_cmp8, mostly
# under tract_linalg's depthwise kernel), and its coverage, the loop counters of a neural
# network's kernels, tells the fuzzer nothing about sketchbody's code. Every other crate (ours,
# the image decoders, serde_json, nalgebra, ...) stays instrumented.
#
# Called by cargo as: rustc-wrapper.sh RUSTC ARGS...
set -euo pipefail
rustc=$1
shift
name=""
prev=""
for a in "$@"; do
  [ "$prev" = "--crate-name" ] && name=$a
  prev=$a
done
case "$name" in
  tract_* | matrixmultiply | ndarray)
    args=()
    for a in "$@"; do
      case "$a" in
        -Cpasses=sancov-module | -Cllvm-args=-sanitizer-coverage-*) ;;
        *) args+=("$a") ;;
      esac
    done
    exec "$rustc" "${args[@]}"
    ;;
esac
exec "$rustc" "$@"
