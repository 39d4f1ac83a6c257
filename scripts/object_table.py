#!/usr/bin/env python3
"""Each true object's scores in a run, worst completion first.

    scripts/object_table.py RUN [RUN2]

RUN: the output folder of `catmap run` on a scene with `gt_meshes/` (its metrics.json). For each
true object: its id, class, the paired prediction (runs with per-frame ids), its visible frames and
`depth_share` from summary.json, accuracy / completion cm / C.R. < 5 cm %, then the mean over objects.
With RUN2, the second run's scores of the same true objects beside the first's. Standard library only.
"""
import json
import sys


def load(run):
    metrics = json.load(open(f"{run}/metrics.json"))
    summary = json.load(open(f"{run}/summary.json"))
    by_id = {o["id"]: o for o in summary["objects"]}
    rows = {}
    for o in metrics["objects"]:
        s = o["scores"]
        pred = by_id.get(o.get("prediction", o["id"]), {})
        rows[o["id"]] = {
            "class": o.get("class_name", "?"),
            "pred": o.get("prediction", o["id"]),
            "frames": pred.get("visible_frames", "-"),
            "depth": pred.get("depth_share"),
            "score": (s.get("accuracy_cm"), s.get("completion_cm"), s.get("completion_ratio_5cm_pct"))
            if s.get("status") == "reconstructed"
            else None,
        }
    return rows, metrics.get("mean", {})


def cell(score):
    return "missing" if score is None else "%.2f / %.2f / %.1f" % score


def main(runs):
    tables = [load(r) for r in runs]
    rows, _ = tables[0]
    order = sorted(rows, key=lambda i: -(rows[i]["score"][1] if rows[i]["score"] else 1e9))
    head = "| id | class | pred | frames | depth | " + " | ".join(runs) + " |"
    print(head)
    print("|" + "---|" * (5 + len(runs)))
    for i in order:
        r = rows[i]
        depth = "-" if r["depth"] is None else "%.2f" % r["depth"]
        cells = [cell(t[0].get(i, {}).get("score")) for t in tables]
        print(f"| {i} | {r['class']} | {r['pred']} | {r['frames']} | {depth} | " + " | ".join(cells) + " |")
    means = []
    for _, m in tables:
        means.append("%.2f / %.2f / %.1f" % (m.get("accuracy_cm", 0), m.get("completion_cm", 0), m.get("completion_ratio_5cm_pct", 0)))
    print("| mean | | | | | " + " | ".join(means) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
