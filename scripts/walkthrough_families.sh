#!/usr/bin/env bash
# The README's own-data walk-through (the small scene in the TUM layout at 640×480, per-frame ids,
# mapped with no flag) under catmap's own Kinect-like noise and under each camera family of
# `catmap synth --noise`, plus "kmask": the Kinect-like masks on exact depth. Each run prints the
# all-objects metrics and the scores of its worst objects (scripts/object_table.py).
#
#   scripts/walkthrough_families.sh CATMAP WORK TAG [-- extra `catmap run` arguments]
#
# CATMAP: the catmap binary (a release build); WORK: a folder for scenes and runs (scenes are
# written once and reused); TAG: names this set of runs (WORK/runs/TAG_FAMILY), so two binaries
# or two settings can be compared: `python3 scripts/object_table.py WORK/runs/A_kinect WORK/runs/B_kinect`.
# About 20 s per run at 640×480 on a 2-core machine.
set -euo pipefail
catmap=$(realpath "$1"); work=$2; tag=$3; shift 3
[ "${1:-}" = "--" ] && shift
here=$(dirname "$(realpath "$0")")
mkdir -p "$work/scenes" "$work/runs"
for family in kinect structured-light time-of-flight active-stereo kmask; do
  dir="$work/scenes/walk_$family"
  if [ ! -f "$dir/scene.json" ]; then
    case $family in
      kmask) noise=(--noise kinect --depth-noise exact) ;;
      *) noise=(--noise "$family") ;;
    esac
    "$catmap" synth --preset small --layout tum "${noise[@]}" --ids per-frame --width 640 --out "$dir" 2>/dev/null
  fi
  run="$work/runs/${tag}_$family"
  if [ ! -f "$run/metrics.json" ]; then
    "$catmap" run --dataset "$dir" --no-recording --out "$run" "$@" > "$run.log" 2>&1 \
      || { echo "$family: failed (log: $run.log)"; continue; }
  fi
  python3 - "$run" "$family" <<'PY'
import json, sys
run, family = sys.argv[1:]
m = json.load(open(f"{run}/metrics.json"))["mean"]
s = json.load(open(f"{run}/summary.json"))
print(f"{family:18} objects {len(s['objects'])} missing {m['missing']}  "
      f"{m['accuracy_cm']:.2f} / {m['completion_cm']:.2f} / {m['completion_ratio_5cm_pct']:.1f}  "
      f"{s['total_seconds']:.0f} s")
PY
  python3 "$here/object_table.py" "$run" | sed -n '2,4p' | sed 's/^/    /'
done
