#!/usr/bin/env bash
# Rebuilds the fitted body's calibration (`FitCalibration::SHIPPED`, src/fit/calibration.rs) from
# the reference motion: the training sketches are fitted by a pose step that has not seen their
# motion, as a user's drawing is.
#
#   scripts/train-fit-calibration.sh WORK_DIR      (about 40 minutes on 2 cores)
#
# 1. 3 × 1200 training sketches (`make-dataset --seed 79`, `80`, `81`) posed by the DeepMimic
#    clips other than the shape-fit benchmark's six held-out ones.
# 2. Those clips in two folds (a clip and its mirror together); per fold, a pose dictionary
#    learned from the library's motion without that fold (`learn-poses --exclude`).
# 3. Each sketch fitted with its true gender by the dictionary that has not seen its clip
#    (`run-dataset --dictionary`).
# 4. `calibrate-fit` on all six result folders: prints the cross-validation, the shape map and
#    the height calibration to paste into `ShapeCalibration::SHIPPED` and
#    `HeightCalibration::SHIPPED`.
#
# Needs ../shared/data/mocap beside the repository (or SKB_SHARED_DATA) and a release build.
# FIT_ARGS (optional, word-split): fit options passed to every `run-dataset`, to train the
# calibration for fits other than the default (e.g. FIT_ARGS="--initial-factor 4").
set -euo pipefail
work=${1:?usage: scripts/train-fit-calibration.sh WORK_DIR}
root=$(cd "$(dirname "$0")/.." && pwd)
data=${SKB_SHARED_DATA:-$root/../shared/data}
skb=$root/target/release/sketchbody-lab
[ -x "$skb" ] || (cd "$root" && cargo build --release -p sketchbody-lab)
mkdir -p "$work/mocap"
held_out="dance_b jog kick long_long_walk3 long_long_walk3_mirror long_stealthy_walk1"
for f in "$data"/mocap/deepmimic/*.csv; do
    name=$(basename "$f" .csv)
    case " $held_out " in *" $name "*) continue ;; esac
    ln -sf "$f" "$work/mocap/$name.csv"
done
fold_a="long_long_walk1 getup_facedown spinkick long_stealthy_walk0 walk dance_spin run stealthy_walk getup_faceup sideflip amass_walk_to_ready"
fold_b="long_long_walk2 spin jump roll punch cartwheel long_long_zombie backflip zombie_walk amass_ready_to_walk dance_a"
with_mirrors() { for c in $1; do printf '%s,%s_mirror,' "$c" "$c"; done | sed 's/,$//'; }
fold_of() {
    local clip=${1%_mirror}
    case " $fold_a " in *" $clip "*) echo A ;; esac
    case " $fold_b " in *" $clip "*) echo B ;; esac
}
"$skb" learn-poses --mocap "$data/mocap/deepmimic" --mocap "$data/mocap/cmu" --exclude "$(with_mirrors "$fold_a")" --out "$work/dictA.skbpd"
"$skb" learn-poses --mocap "$data/mocap/deepmimic" --mocap "$data/mocap/cmu" --exclude "$(with_mirrors "$fold_b")" --out "$work/dictB.skbpd"
train=()
for seed in 79 80 81; do
    ds=$work/ds$seed
    "$skb" make-dataset 1200 --seed $seed --mocap "$work/mocap" --out "$ds"
    for fold in A B; do mkdir -p "$ds$fold"; done
    for j in "$ds"/[0-9]*.json; do
        stem=$(basename "$j" .json)
        clip=$(grep -o '"pose_source": *"mocap:[^:"]*' "$j" | sed 's/.*mocap://')
        fold=$(fold_of "$clip")
        [ -n "$fold" ] || continue
        for ext in json mesh png; do ln -sf "$ds/$stem.$ext" "$ds$fold/$stem.$ext"; done
    done
    for fold in A B; do
        "$skb" run-dataset "$ds$fold" --out "$work/r$seed$fold" --gender truth --dictionary "$work/dict$fold.skbpd" ${FIT_ARGS:-}
        # calibrate-fit reads the results' JSON only; the meshes would take 3 MB a sketch.
        find "$work/r$seed$fold" -name '*.obj' -delete
        train+=(--train "$ds$fold=$work/r$seed$fold")
    done
done
"$skb" calibrate-fit "${train[@]}" --cv 5
