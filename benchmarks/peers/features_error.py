#!/usr/bin/env python3
"""Height error of machined meshes on the fine-features workload (make_features.py),
independent of vcut: every cutting move there is horizontal or a vertical plunge, so on
the vertical line through (x, y) a move's lowest point is its height plus the tool's
underside at the horizontal distance d from the move (flat: 0 for d <= R; ball:
r - sqrt(r^2 - d^2); V-bit: d / tan(angle / 2)); the machined top is the lowest over all
moves, capped by the stock top z = 0. Points: POINTS random points within 0.6 tool radii
of random cutting moves, and 200 points on the V-bit engravings' centre lines, where the
engraving counts as visible when the mesh there lies at least 0.05 mm deep.
Usage: features_error.py PATH_JSON POINTS SEED MESH.stl [MESH.stl ...]   (Debian python3)"""
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from height_error import mesh_top, read_stl  # noqa: E402


def underside(tool, d):
    r = tool["diameter"] / 2
    if d > r:
        return None
    if tool["type"] == "flat":
        return 0.0
    if tool["type"] == "ball":
        return r - math.sqrt(r * r - d * d)
    return d / math.tan(math.radians(tool["angle"]) / 2)


def exact_top(x, y, segments, tools):
    best = 0.0
    for s in segments:
        (ax, ay, az), (bx, by, bz) = s["start"], s["end"]
        dx, dy = bx - ax, by - ay
        L2 = dx * dx + dy * dy
        t = 0.0 if L2 == 0 else min(1.0, max(0.0, ((x - ax) * dx + (y - ay) * dy) / L2))
        d = math.hypot(x - ax - t * dx, y - ay - t * dy)
        u = underside(tools[str(s["tool"])], d)
        if u is not None:
            best = min(best, min(az, bz) + u)
    return best


def main():
    data = json.load(open(sys.argv[1]))
    count, seed = int(sys.argv[2]), int(sys.argv[3])
    tools, segments = data["tools"], [s for s in data["segments"] if s["end"][2] < 0]
    rng = np.random.default_rng(seed)
    lengths = np.array([math.hypot(s["end"][0] - s["start"][0], s["end"][1] - s["start"][1]) for s in segments])
    weights = lengths / lengths.sum()
    samples = []
    for i in rng.choice(len(segments), size=count, p=weights):
        s = segments[i]
        r = tools[str(s["tool"])]["diameter"] / 2
        t = rng.uniform()
        ang = rng.uniform(0, 2 * math.pi)
        rad = 0.6 * r * math.sqrt(rng.uniform())
        samples.append((s["start"][0] + t * (s["end"][0] - s["start"][0]) + rad * math.cos(ang),
                        s["start"][1] + t * (s["end"][1] - s["start"][1]) + rad * math.sin(ang)))
    vbit = [s for s in segments if tools[str(s["tool"])]["type"] == "vbit" and lengths[segments.index(s)] > 0]
    centre = []
    for i in rng.choice(len(vbit), size=200):
        s, t = vbit[i], rng.uniform(0.1, 0.9)
        centre.append((s["start"][0] + t * (s["end"][0] - s["start"][0]), s["start"][1] + t * (s["end"][1] - s["start"][1])))
    near = lambda x, y: [s for s in segments if min(s["start"][0], s["end"][0]) - 3.5 < x < max(s["start"][0], s["end"][0]) + 3.5
                         and min(s["start"][1], s["end"][1]) - 3.5 < y < max(s["start"][1], s["end"][1]) + 3.5]
    exact = [exact_top(x, y, near(x, y), tools) for x, y in samples]
    for path in sys.argv[4:]:
        tris = read_stl(path)
        keep = tris[:, :, 2].max(1) > -3.0  # the top region only (the pocket floor is at -2)
        tris = tris[keep]
        cell = np.floor(tris[:, :, :2].mean(1)).astype(np.int64)
        key = cell[:, 0] * 100000 + cell[:, 1]
        order = np.argsort(key)
        key, tris = key[order], tris[order]

        def top(x, y):
            cand = []
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    k = (int(math.floor(x)) + dx) * 100000 + int(math.floor(y)) + dy
                    i0, i1 = np.searchsorted(key, k), np.searchsorted(key, k, side="right")
                    if i1 > i0:
                        cand.append(tris[i0:i1])
            return mesh_top(np.concatenate(cand), x, y) if cand else None

        errors = [top(x, y) - z for (x, y), z in zip(samples, exact) if top(x, y) is not None]
        e = np.abs(np.array(errors))
        visible = sum(1 for x, y in centre if (top(x, y) is not None and top(x, y) <= -0.05))
        print(json.dumps({"mesh": path, "points": int(e.size), "max_mm": float(e.max()), "rms_mm": float(np.sqrt((e * e).mean())),
                          "engraving_points_deeper_than_0.05": visible, "engraving_points": len(centre)}))


if __name__ == "__main__":
    main()
