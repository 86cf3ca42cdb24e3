#!/usr/bin/env bash
# Canny benchmark against OpenCV (cpp_tests/canny_bench.cpp): single-threaded, then all cores.
# Prints the markdown tables quoted in docs/benchmarks-history.md ("Canny vs OpenCV 4.6").
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" --target canny_bench >/dev/null
./build/cpp_tests/canny_bench --threads 1 --reps "${REPS:-15}"
echo
./build/cpp_tests/canny_bench --threads 0 --reps "${REPS:-15}"
