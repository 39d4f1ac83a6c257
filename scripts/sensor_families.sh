#!/usr/bin/env bash
# The "Real sensors" table: each scene mapped clean (exact depth and masks, consistent ids) and
# through each camera family with its segmenter and per-frame ids, with no --depth / --masks /
# --instances flag (the probe decides), and each family's metrics against the clean run's.
#
#   scripts/sensor_families.sh CATMAP WORK [SCENES] [FAMILIES] [-- extra `catmap run` arguments]
#
# CATMAP: the catmap binary (a release build: target/release/catmap); WORK: a folder for scenes,
# runs and logs (scenes are written once and reused). SCENES: "preset:seed ..." (default
# "default:0 default:1 default:2 default:3 living:0 living:1"); FAMILIES: camera families of
# `catmap synth --noise` (default "structured-light time-of-flight active-stereo"). Runs go one
# after another; each prints its line as it ends, the table comes last (also WORK/table.md).
set -euo pipefail
catmap=$(realpath "$1"); work=$2; shift 2
scenes=${1:-"default:0 default:1 default:2 default:3 living:0 living:1"}; [ $# -gt 0 ] && shift
families=${1:-"structured-light time-of-flight active-stereo"}; [ $# -gt 0 ] && shift
[ "${1:-}" = "--" ] && shift
mkdir -p "$work/scenes" "$work/runs" "$work/logs"
rows=()
for scene in $scenes; do
  preset=${scene%%:*}; seed=${scene##*:}
  for family in clean $families; do
    name="${preset}_${seed}_${family}"
    dir="$work/scenes/$name"
    if [ ! -f "$dir/scene.json" ]; then
      if [ "$family" = clean ]; then
        "$catmap" synth --preset "$preset" --seed "$seed" --out "$dir" 2>/dev/null
      else
        "$catmap" synth --preset "$preset" --seed "$seed" --noise "$family" --ids per-frame --out "$dir" 2>/dev/null
      fi
    fi
    if [ ! -f "$work/runs/$name/metrics.json" ]; then
      "$catmap" run --dataset "$dir" --seed 0 --no-recording --out "$work/runs/$name" "$@" \
        > "$work/logs/$name.txt" 2>&1 || { echo "$name: failed (log: $work/logs/$name.txt)"; continue; }
    fi
    rows+=("$name")
    echo "$name done"
  done
done
python3 - "$work" "${rows[@]}" <<'PY' | tee "$work/table.md"
import json, sys
work, names = sys.argv[1], sys.argv[2:]
def load(name):
    m = json.load(open(f"{work}/runs/{name}/metrics.json"))
    s = json.load(open(f"{work}/runs/{name}/summary.json"))
    truth = len(m["objects"])
    return dict(truth=truth, predicted=len(s["objects"]), missing=m["mean"]["missing"], acc=m["mean"]["accuracy_cm"],
                comp=m["mean"]["completion_cm"], cr5=m["mean"]["completion_ratio_5cm_pct"], seconds=s["total_seconds"],
                choice=s.get("sensor", {}))
runs = {n: load(n) for n in names}
print("| scene | family | objects (truth) | missing | Acc. cm | Comp. cm | C.R. <5 cm % | Acc. / Comp. vs clean | C.R. vs clean (points) | probe: depth, masks, ids | s |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|")
for name, r in runs.items():
    preset, seed, family = name.split("_", 2)
    clean = runs.get(f"{preset}_{seed}_clean")
    ratio = f"{r['acc']/clean['acc']-1:+.0%} / {r['comp']/clean['comp']-1:+.0%}" if clean else "–"
    points = f"{r['cr5']-clean['cr5']:+.1f}" if clean else "–"
    ch = r["choice"]
    probe = f"{ch.get('depth','?')}, {ch.get('masks','?')}, {ch.get('instances','?')}"
    print(f"| {preset} {seed} | {family} | {r['predicted']} ({r['truth']}) | {r['missing']} | {r['acc']:.2f} | {r['comp']:.2f} | {r['cr5']:.1f} | {ratio} | {points} | {probe} | {r['seconds']:.0f} |")
PY
