#!/usr/bin/env python3
"""Fine-features workload (issue 9): features a coarse simulator loses, on a 60 x 40 x 10 mm
block (top face at z = 0):
  T1 flat D1      grooves 0.2 mm deep (straight and an L)             x 2..28,  y 2..18
  T2 V-bit 90 deg engraving 0.1 mm deep: a zig-zag and block letters    x 32..58, y 2..18
  T3 ball D0.5    grooves 0.1 mm deep (straight and a zig-zag)          x 2..28,  y 22..38
  T4 flat D6      a 20 x 12 mm pocket 2 mm deep in two 1 mm passes      x 35..55, y 25..37
Every cutting move is horizontal or a vertical plunge, so the exact machined height has a
closed form (benchmarks/peers/features_error.py). Cuts are split into 0.35 mm moves.
Writes into the folder given (default benchmarks/workloads/features): features.ngc,
features.path.json (tools and every cutting segment), tools.yaml, job.yaml (v = 0.05 mm).
"""
import json
import math
import os
import sys

TOOLS = {
    1: {"type": "flat", "diameter": 1.0, "flute_length": 3},
    2: {"type": "vbit", "diameter": 3.0, "angle": 90.0, "flute_length": 5},
    3: {"type": "ball", "diameter": 0.5, "flute_length": 2},
    4: {"type": "flat", "diameter": 6.0, "flute_length": 10},
}
STEP = 0.35


def polylines():
    """(tool, depth, [polyline of (x, y)]) in cutting order."""
    out = []
    for y in (4.0, 7.0, 10.0):
        out.append((1, 0.2, [(2.0, y), (28.0, y)]))
    out.append((1, 0.2, [(4.0, 13.0), (22.0, 13.0), (22.0, 17.5)]))
    zig = [(32.0 + 2.0 * i, 3.0 if i % 2 == 0 else 8.0) for i in range(14)]
    out.append((2, 0.1, zig))
    # Block letters V C U T, 4 mm wide, 6 mm tall, from x = 33.
    x0, y0, h = 33.0, 11.0, 6.0
    out.append((2, 0.1, [(x0, y0 + h), (x0 + 2, y0), (x0 + 4, y0 + h)]))                        # V
    out.append((2, 0.1, [(x0 + 10, y0 + h), (x0 + 6, y0 + h), (x0 + 6, y0), (x0 + 10, y0)]))      # C
    out.append((2, 0.1, [(x0 + 12, y0 + h), (x0 + 12, y0), (x0 + 16, y0), (x0 + 16, y0 + h)]))    # U
    out.append((2, 0.1, [(x0 + 18, y0 + h), (x0 + 23, y0 + h)]))                                 # T
    out.append((2, 0.1, [(x0 + 20.5, y0 + h), (x0 + 20.5, y0)]))
    for y in (24.0, 27.0):
        out.append((3, 0.1, [(2.0, y), (28.0, y)]))
    out.append((3, 0.1, [(3.0 + 2.0 * i, 30.0 if i % 2 == 0 else 36.0) for i in range(13)]))
    for depth in (1.0, 2.0):
        path = []
        for j, y in enumerate((28.0, 30.0, 32.0, 34.0)):
            xs = (38.0, 52.0) if j % 2 == 0 else (52.0, 38.0)
            path += [(xs[0], y), (xs[1], y)]
        path += [(38.0, 34.0), (38.0, 28.0), (52.0, 28.0), (52.0, 34.0), (38.0, 34.0)]
        out.append((4, depth, path))
    return out


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "features")
    os.makedirs(out, exist_ok=True)
    segments = []
    lines = ["%", "(vcut fine-features workload, written by make_features.py)", "G21 G90 G94 G17"]
    tool = None
    moves = 0
    for t, depth, poly in polylines():
        if t != tool:
            lines += ["G0 Z2", "T%d M6" % t, "S18000 M3"]
            tool = t
        x, y = poly[0]
        lines += ["G0 X%.4f Y%.4f Z2" % (x, y), "G1 Z1 F600", "G1 Z%.4f F300" % -depth]
        segments.append({"tool": t, "start": [x, y, 1.0], "end": [x, y, -depth]})
        moves += 2
        for (ax, ay), (bx, by) in zip(poly, poly[1:]):
            n = max(1, int(math.ceil(math.hypot(bx - ax, by - ay) / STEP)))
            for i in range(1, n + 1):
                px, py = ax + (bx - ax) * i / n, ay + (by - ay) * i / n
                lines.append("G1 X%.4f Y%.4f F600" % (px, py))
                segments.append({"tool": t, "start": [x, y, -depth], "end": [px, py, -depth]})
                x, y = px, py
                moves += 1
        lines.append("G0 Z2")
    lines += ["M5", "M30", "%"]
    with open(os.path.join(out, "features.ngc"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out, "features.path.json"), "w") as f:
        json.dump({"tools": TOOLS, "segments": segments}, f)
    with open(os.path.join(out, "tools.yaml"), "w") as f:
        f.write("tools:\n")
        f.write("  1: {type: flat, diameter: 1, corner_radius: 0, flute_length: 3, shank_diameter: 3, length: 20}\n")
        f.write("  2: {type: vbit, diameter: 3, angle: 90, flute_length: 5, shank_diameter: 3, length: 20}\n")
        f.write("  3: {type: ball, diameter: 0.5, corner_radius: 0.25, flute_length: 2, shank_diameter: 3, length: 20}\n")
        f.write("  4: {type: flat, diameter: 6, corner_radius: 0, flute_length: 10, shank_diameter: 6, length: 30}\n")
    with open(os.path.join(out, "job.yaml"), "w") as f:
        f.write("job: features\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: features.ngc}\n"
                "stock: {box: {min: [0, 0, -10], max: [60, 40, 0]}}\n"
                "engine: {kind: dexel, resolution: 0.05, threads: auto}\nreport: {out: out}\n")
    print("features: %d G1 moves -> %s" % (moves, out))


if __name__ == "__main__":
    main()
