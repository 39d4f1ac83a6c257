#!/usr/bin/env python3
"""How much larger than its true object each mapped object's box is.

    scripts/box_excess.py SCENE RUN

SCENE: a scene `catmap synth` wrote (scene.json, gt_meshes/); RUN: the output folder of
`catmap run` on it followed by `catmap eval` pairing (its metrics.json names each true object's
prediction, as runs with per-frame ids do). For each true object the paired prediction's box
extents (summary.json's `box_extents_m`) minus the true mesh's extents in its own frame, both
sorted longest first, in centimetres; then the median and mean of each object's largest excess.
A box grown past its object by a camera's flying pixels or fattened edges holds a layer of cells
beside the object that the views see free. Standard library only.
"""
import json
import statistics
import struct
import sys


def ply_vertices(path):
    """The vertices of a binary little-endian PLY as catmap writes it (x, y, z floats first)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    count, props, in_vertex = 0, [], False
    for line in header:
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            count, in_vertex = int(words[2]), True
        elif words[:1] == ["element"]:
            in_vertex = False
        elif words[:1] == ["property"] and in_vertex:
            props.append(words[1])
    sizes = {"float": ("f", 4), "uchar": ("B", 1), "double": ("d", 8), "int": ("i", 4)}
    fmt = "<" + "".join(sizes[p][0] for p in props)
    stride = struct.calcsize(fmt)
    return [v[:3] for v in struct.iter_unpack(fmt, data[end:end + count * stride])]


def extents_in_frame(points, world_from_object):
    """Extents of the points in the object's frame (the inverse of a rigid 4×4)."""
    r = [row[:3] for row in world_from_object[:3]]
    t = [row[3] for row in world_from_object[:3]]
    lo, hi = [float("inf")] * 3, [float("-inf")] * 3
    for p in points:
        d = [p[i] - t[i] for i in range(3)]
        local = [sum(r[i][a] * d[i] for i in range(3)) for a in range(3)]
        lo = [min(a, b) for a, b in zip(lo, local)]
        hi = [max(a, b) for a, b in zip(hi, local)]
    return [h - l for l, h in zip(lo, hi)]


def main(scene, run):
    truth = {o["id"]: o for o in json.load(open(f"{scene}/scene.json"))["objects"]}
    pairs = {o["id"]: o.get("prediction") for o in json.load(open(f"{run}/metrics.json"))["objects"]}
    boxes = {o["id"]: o["box_extents_m"] for o in json.load(open(f"{run}/summary.json"))["objects"]}
    largest = []
    print("| object | class | box − truth, cm (longest first) |")
    print("|---:|---|---|")
    for gid, obj in sorted(truth.items()):
        pid = pairs.get(gid)
        if pid is None or pid not in boxes:
            print(f"| {gid} | {obj['class_name']} | not paired |")
            continue
        true = sorted(extents_in_frame(ply_vertices(f"{scene}/gt_meshes/obj_{gid}.ply"), obj["world_from_object"]), reverse=True)
        mapped = sorted(boxes[pid], reverse=True)
        excess = [100 * (m - t) for m, t in zip(mapped, true)]
        largest.append(max(excess))
        print(f"| {gid} | {obj['class_name']} | {' / '.join(f'{e:+.1f}' for e in excess)} |")
    if largest:
        print(f"\nlargest excess per object: median {statistics.median(largest):.1f} cm, mean {statistics.mean(largest):.1f} cm")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
