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
#
# MAPPER_SEEDS (environment, default "0"): the `catmap run --seed` values each scene is mapped
# with. With more than one, each row is the mean over them and the last column the spread
# (lowest–highest all-objects accuracy): the same data mapped with another seed moves a clean
# run's accuracy by a few percent, more than a small change to the mapper does.
#
# The column "objects with a depth" compares with the clean run over the objects the camera
# measured: those whose paired prediction has a depth at half its pixels or more (summary.json's
# depth_share; below it the run reports the object as mapped from little), each noisy run against
# the clean run of the same mapper seed. "(N out)": the most objects a seed left out (missing, or
# mostly beyond the camera's range, dark or shiny).
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
    mapped=()
    for mapper_seed in ${MAPPER_SEEDS:-0}; do
      # Seed 0's run keeps the scene's name (runs made before the option are reused).
      run=$name; [ "$mapper_seed" = 0 ] || run="${name}_m${mapper_seed}"
      if [ ! -f "$work/runs/$run/metrics.json" ]; then
        "$catmap" run --dataset "$dir" --seed "$mapper_seed" --no-recording --out "$work/runs/$run" "$@" \
          > "$work/logs/$run.txt" 2>&1 || { echo "$run: failed (log: $work/logs/$run.txt)"; continue; }
      fi
      mapped+=("$run")
      echo "$run done"
    done
    [ ${#mapped[@]} -gt 0 ] && rows+=("$name=$(IFS=,; echo "${mapped[*]}")")
  done
done
python3 - "$work" "${rows[@]}" <<'PY' | tee "$work/table.md"
import json, sys
work, rows = sys.argv[1], sys.argv[2:]
def load(run):
    m = json.load(open(f"{work}/runs/{run}/metrics.json"))
    s = json.load(open(f"{work}/runs/{run}/summary.json"))
    share = {o["id"]: o.get("depth_share") for o in s["objects"]}
    # Ground-truth objects whose paired prediction has a depth at half its pixels or more (the
    # run's LOW_DEPTH_SHARE, 0.5): what the camera measured, not what lay beyond its range. Their
    # ratio to the clean run is taken per mapper seed (each seed's set may differ), then averaged.
    measured = {o["id"] for o in m["objects"]
                if o.get("prediction") is not None and (share.get(o["prediction"]) or 0.0) >= 0.5}
    scores = {o["id"]: o["scores"] for o in m["objects"] if o.get("scores")}
    return dict(truth=len(m["objects"]), predicted=len(s["objects"]), missing=m["mean"]["missing"],
                acc=m["mean"]["accuracy_cm"], comp=m["mean"]["completion_cm"],
                cr5=m["mean"]["completion_ratio_5cm_pct"], seconds=s["total_seconds"], choice=s.get("sensor", {}),
                measured=measured, scores=scores)
def over(run, ids, key):
    return sum(run["scores"][i][key] for i in ids) / len(ids)
def measured_ratio(runs, cleans):
    """Acc. / Comp. vs clean over the objects each run measured (the clean run of the same mapper seed)."""
    scored = lambda run: {i for i, sc in run["scores"].items() if sc.get("accuracy_cm") is not None}
    pairs = [(r, c, sorted(r["measured"] & scored(r) & scored(c))) for r, c in zip(runs, cleans)]
    pairs = [p for p in pairs if p[2]]
    if not pairs:
        return "–"
    acc = sum(over(r, ids, "accuracy_cm") / over(c, ids, "accuracy_cm") for r, c, ids in pairs) / len(pairs)
    comp = sum(over(r, ids, "completion_cm") / over(c, ids, "completion_cm") for r, c, ids in pairs) / len(pairs)
    left = max(len(r["scores"]) - len(ids) for r, _, ids in pairs)
    return f"{acc-1:+.0%} / {comp-1:+.0%} ({left} out)"
def mean(runs):
    avg = {k: sum(r[k] for r in runs) / len(runs) for k in ("predicted", "missing", "acc", "comp", "cr5", "seconds")}
    accs = [r["acc"] for r in runs]
    return dict(avg, truth=runs[0]["truth"], choice=runs[0]["choice"], seeds=len(runs), spread=(min(accs), max(accs)),
                runs=runs)
scenes = {}
for row in rows:
    name, runs = row.split("=", 1)
    scenes[name] = mean([load(run) for run in runs.split(",")])
print("| scene | family | objects (truth) | missing | Acc. cm | Comp. cm | C.R. <5 cm % | Acc. / Comp. vs clean | C.R. vs clean (points) | Acc. / Comp. vs clean, objects with a depth (left out) | probe: depth, masks, ids | s | mapper seeds: Acc. lowest–highest |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---|")
for name, r in scenes.items():
    preset, seed, family = name.split("_", 2)
    clean = scenes.get(f"{preset}_{seed}_clean")
    ratio = f"{r['acc']/clean['acc']-1:+.0%} / {r['comp']/clean['comp']-1:+.0%}" if clean else "–"
    points = f"{r['cr5']-clean['cr5']:+.1f}" if clean else "–"
    measured = measured_ratio(r["runs"], clean["runs"]) if clean else "–"
    ch = r["choice"]
    probe = f"{ch.get('depth','?')}, {ch.get('masks','?')}, {ch.get('instances','?')}"
    spread = f"{r['seeds']}: {r['spread'][0]:.2f}–{r['spread'][1]:.2f}" if r["seeds"] > 1 else "1"
    objects = f"{r['predicted']:g} ({r['truth']})"
    print(f"| {preset} {seed} | {family} | {objects} | {r['missing']:g} | {r['acc']:.2f} | {r['comp']:.2f} | {r['cr5']:.1f} | {ratio} | {points} | {measured} | {probe} | {r['seconds']:.0f} | {spread} |")
PY
