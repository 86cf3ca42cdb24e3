#!/usr/bin/env bash
# Fine-tunes the shipped BlazePose landmark network on drawings (issue 15 experiment; results in
# docs/benchmarks-history.md, "Fine-tuning the landmark model on drawings"). Everything generated stays
# under $WORK (default /tmp/ft): never commit the crops or the models.
#
# Python: a venv with torch (CPU), onnx and onnx2torch (PYTHON, default /tmp/tv/bin/python; the
# experiment used torch 2.15, onnx 1.23.2, onnx2torch 1.5.15, numpy 2.4.6), 2 threads.
# Data (training only): rendered sketches of seed $SEED (half in art styles), PARSE photos 1-80
# plain and through the training filters (render::photo_npr), mirrored, 40 text + 40 clutter pages;
# never PARSE 81-100 (validation) or 101-305 (test), never the benchmark's stylisations.
#
# Usage: scripts/finetune-blazepose.sh [TRAIN ARGS...]   (run 1 of the write-up: --steps 470; the
# defaults are its settings: --lr 3e-5 --freeze 60 --distill-drawing 0.2 --flag-drawing 0; run 6:
# --minutes 6 --freeze 30 --warmup 60)
set -euo pipefail
cd "$(dirname "$0")/.."
WORK=${WORK:-/tmp/ft}
PYTHON=${PYTHON:-/tmp/tv/bin/python}
SEED=${SEED:-81}
SKETCHES=${SKETCHES:-1000}
RUN=${RUN:-run}
parse=../shared/data/parse
mkdir -p "$WORK"
cargo build --release -p sketchbody --example landmark_model_diff
cargo build --release -p sketchbody-lab --example landmark_finetune_data
cargo build --release -p sketchbody-lab

# 1. The export path, checked with the unmodified network: our loader must read the same landmarks.
"$PYTHON" scripts/finetune-blazepose.py export-identity "$WORK/identity.onnx"
images=(assets/examples/sketch.png "$parse"/images/im008{1,5,9}.jpg)
target/release/examples/landmark_model_diff "$WORK/identity.onnx" "${images[@]}" | tail -1

# 2. Training crops (as inference takes them) with the shipped network's outputs: ~5 min.
[ -f "$WORK/data/meta.f32" ] || RAYON_NUM_THREADS=2 \
  target/release/examples/landmark_finetune_data "$parse" "$WORK/data" "$SKETCHES" "$SEED"

# 3. Fine-tuning, then the candidate against the asset on a few images.
"$PYTHON" scripts/finetune-blazepose.py train "$WORK/data" "$WORK/$RUN" "$@"
target/release/examples/landmark_model_diff "$WORK/$RUN/model.onnx" "${images[@]}" | tail -1

# 4. Validation (choose here only): PARSE photos 81-100 plain and stylised; sketches and pages of
#    seed 83 (neither the training seed nor the benchmark's 2).
for model in "" "--landmark-model $WORK/$RUN/model.onnx"; do
  # shellcheck disable=SC2086
  target/release/sketchbody-lab eval-detector --sets parse,xdog,pencil,flat --parse-range 81-100 $model
  # shellcheck disable=SC2086
  target/release/sketchbody-lab eval-detector --sets synthetic,negatives --seed 83 --n 100 --hair keep $model
done
