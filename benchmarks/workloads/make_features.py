#!/usr/bin/env python3
"""Fine-features workload (issue 9): features a coarse simulator loses, on a 60 x 40 x 10 mm
block (top face at z = 0), v = 0.05 mm:
  T1 flat D1        1 mm grooves 0.2 mm deep (three straight, one L)      x 2..28,  y 2..18
  T2 V-bit 90 deg   engraving 0.1 mm deep: a zig-zag and block "VCUT"     x 32..58, y 2..18
  T3 ball D0.5      grooves 0.1 mm deep (two straight, one zig-zag)       x 2..28,  y 22..38
  T4 flat D6        a 20 x 12 mm pocket (x 35..55, y 25..37) 2 mm deep, zig-zag at 2 mm
                    stepover plus a finishing ring, in two passes of 1 mm  x 34..56, y 24..38
Every cutting move is horizontal (constant Z) or a vertical plunge, so the exact machined
height has a closed form (benchmarks/peers/features_error.py). Rapids run at Z2, each
feature starts with a rapid down to Z1 and a G1 plunge to depth at F300; cuts run at F600,
split into moves of at most STEP mm.
Writes, into the folder given (default: benchmarks/workloads/features):
  features.ngc        the program (G21 G90 G94 G17)
  features.path.json  {"tools": {n: {...}}, "stock": {...}, "segments": [{"tool", "start",
                      "end"} for every G1 move, in order]}
  tools.yaml          T1..T4 as above
  job.yaml            the vcut job (engine dexel, v = 0.05 mm)
Usage: make_features.py [folder]
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
STOCK = {"min": [0, 0, -10], "max": [60, 40, 0]}
STEP = 0.35  # longest cutting move (mm); gives about 1,600 G1 moves
SAFE, START = 2.0, 1.0


def polylines():
    """(tool, depth, [(x, y), ...]) in cutting order."""
    out = []
    # T1: straight grooves and an L.
    for y in (4.0, 7.0, 10.0):
        out.append((1, 0.2, [(2.5, y), (27.5, y)]))
    out.append((1, 0.2, [(4.0, 13.0), (22.0, 13.0), (22.0, 17.0)]))
    # T2: a zig-zag with sharp corners, then block letters V C U T (4 mm wide, 6 mm tall).
    out.append((2, 0.1, [(32.5 + 2.0 * i, 3.0 if i % 2 == 0 else 8.0) for i in range(13)]))
    x0, y0, h = 33.0, 11.0, 6.0
    out.append((2, 0.1, [(x0, y0 + h), (x0 + 2, y0), (x0 + 4, y0 + h)]))                       # V
    out.append((2, 0.1, [(x0 + 10, y0 + h), (x0 + 6, y0 + h), (x0 + 6, y0), (x0 + 10, y0)]))     # C
    out.append((2, 0.1, [(x0 + 12, y0 + h), (x0 + 12, y0), (x0 + 16, y0), (x0 + 16, y0 + h)]))   # U
    out.append((2, 0.1, [(x0 + 18, y0 + h), (x0 + 23, y0 + h)]))                                # T bar
    out.append((2, 0.1, [(x0 + 20.5, y0 + h), (x0 + 20.5, y0)]))                                # T stem
    # T3: straight grooves and a zig-zag.
    for y in (24.0, 27.0):
        out.append((3, 0.1, [(2.5, y), (27.5, y)]))
    out.append((3, 0.1, [(3.0 + 2.0 * i, 30.0 if i % 2 == 0 else 36.0) for i in range(13)]))
    # T4: pocket x 35..55, y 25..37 with a D6 flat: centres x 38..52, y 28..34; zig-zag rows
    # at 2 mm stepover, then the finishing ring around the centres' rectangle; two passes.
    for depth in (1.0, 2.0):
        path = []
        for j, y in enumerate((28.0, 30.0, 32.0, 34.0)):
            path += [(38.0, y), (52.0, y)] if j % 2 == 0 else [(52.0, y), (38.0, y)]
        path += [(38.0, 28.0), (52.0, 28.0), (52.0, 34.0), (38.0, 34.0)]  # from (38, 34)
        out.append((4, depth, path))
    return out


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "features")
    os.makedirs(out, exist_ok=True)
    segments = []
    lines = ["%", "(vcut fine-features workload, written by make_features.py)", "G21 G90 G94 G17"]
    tool = None
    for t, depth, poly in polylines():
        if t != tool:
            if tool is not None:
                lines.append("M5")
            lines += ["G0 Z%.1f" % SAFE, "T%d M6" % t, "S18000 M3"]
            tool = t
        x, y = poly[0]
        z = -depth
        lines += ["G0 X%.4f Y%.4f Z%.1f" % (x, y, SAFE), "G0 Z%.1f" % START, "G1 Z%.4f F300" % z]
        segments.append({"tool": t, "start": [x, y, START], "end": [x, y, z]})
        feed = " F600"
        for (ax, ay), (bx, by) in zip(poly, poly[1:]):
            n = int(math.ceil(math.hypot(bx - ax, by - ay) / STEP - 1e-9))
            for i in range(1, n + 1):
                px, py = round(ax + (bx - ax) * i / n, 4), round(ay + (by - ay) * i / n, 4)
                lines.append("G1 X%.4f Y%.4f%s" % (px, py, feed))
                segments.append({"tool": t, "start": [x, y, z], "end": [px, py, z]})
                x, y, feed = px, py, ""
        lines.append("G0 Z%.1f" % SAFE)
    lines += ["M5", "M30", "%"]
    with open(os.path.join(out, "features.ngc"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out, "features.path.json"), "w") as f:
        json.dump({"tools": TOOLS, "stock": STOCK, "segments": segments}, f)
    with open(os.path.join(out, "tools.yaml"), "w") as f:
        f.write("tools:\n"
                "  1: {type: flat, diameter: 1, corner_radius: 0, flute_length: 3, shank_diameter: 3, length: 20}\n"
                "  2: {type: vbit, diameter: 3, angle: 90, flute_length: 5, shank_diameter: 3, length: 20}\n"
                "  3: {type: ball, diameter: 0.5, corner_radius: 0.25, flute_length: 2, shank_diameter: 3, length: 20}\n"
                "  4: {type: flat, diameter: 6, corner_radius: 0, flute_length: 10, shank_diameter: 6, length: 30}\n")
    with open(os.path.join(out, "job.yaml"), "w") as f:
        f.write("job: features\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: features.ngc}\n"
                "stock: {box: {min: [0, 0, -10], max: [60, 40, 0]}}\n"
                "engine: {kind: dexel, resolution: 0.05, threads: auto}\n"
                "report: {out: out}\n")
    print("features: %d G1 moves -> %s" % (len(segments), out))


if __name__ == "__main__":
    main()
