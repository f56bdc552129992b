#!/usr/bin/env python3
"""Workload W1 (issue 9): a 6 mm ball finishing raster over a 100 x 100 mm freeform surface,
0.3 mm stepover, 0.5 mm segments, stock 100 x 100 x 40 mm.

The tool tip follows z = surface(x, y) along rasters in x (zig-zag in y). The stock is cut
from the full block, so each raster line ploughs up to 10 mm deep beside the previous one.
Writes, into the folder given (default: benchmarks/workloads/w1):
  w1.ngc      the program (G21 G90 G94, one G1 per 0.5 mm segment)
  w1.path     the same tip points, one "x y z" per line (for the peers and the error check)
  tools.yaml  T1: ball D6, flute length 25 mm
  job.yaml    the vcut job (engine dexel, v = 0.05 mm); `--resolution`/`--threads` override
With --tilt DEG, W1T (issue 24): the same tip path as 3+2 work, the tool's axis tilted DEG
from +z toward +y throughout, written as APT CL data (w1.apt: MULTAX GOTO/x, y, z, i, j, k)
for the table-table-ac machine, whose job then reads it.
With --tool flat or --tool bull, W1F and W1B (issue 24): the same raster with a D6 flat end
mill or a D6 r1 bull-nose (three-axis finishing with those tools: moves along their axis).
Usage: make_w1.py [folder] [--size MM] [--tilt DEG] [--tool ball|flat|bull] (a smaller size
gives a quick variant of the same kind)
"""
import math
import os
import sys


# The D6 tools, as tools.yaml entries and APT CUTTER statements (d, r, e, f, a, b, h).
TOOLS = {
    "ball": ("{type: ball, diameter: 6, corner_radius: 3", "CUTTER/6,3,0,3,0,0,25"),
    "flat": ("{type: flat, diameter: 6, corner_radius: 0", "CUTTER/6,0,3,0,0,0,25"),
    "bull": ("{type: bull, diameter: 6, corner_radius: 1", "CUTTER/6,1,2,1,0,0,25"),
}


def surface(x, y):
    return 32.0 + 3.0 * math.sin(2 * math.pi * x / 50.0) * math.cos(2 * math.pi * y / 40.0) + 0.02 * x


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    size = 100.0
    if "--size" in sys.argv:
        size = float(sys.argv[sys.argv.index("--size") + 1])
        args = [a for a in args if a != sys.argv[sys.argv.index("--size") + 1]]
    tool = "ball"
    if "--tool" in sys.argv:
        tool = sys.argv[sys.argv.index("--tool") + 1]
        args = [a for a in args if a != tool]
        if tool not in TOOLS:
            sys.exit("make_w1.py: --tool takes ball, flat or bull, not %s" % tool)
    tilt = None
    if "--tilt" in sys.argv:
        tilt = float(sys.argv[sys.argv.index("--tilt") + 1])
        args = [a for a in args if a != sys.argv[sys.argv.index("--tilt") + 1]]
    out = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "w1")
    os.makedirs(out, exist_ok=True)
    step, stepover = 0.5, 0.3
    nx = int(round(size / step))
    ny = int(math.floor(size / stepover)) + 1
    points = []
    for j in range(ny):
        y = j * stepover
        xs = [i * step for i in range(nx + 1)]
        if j % 2:
            xs.reverse()
        points.extend((x, y, surface(x, y)) for x in xs)
    safe = 45.0
    with open(os.path.join(out, "w1.ngc"), "w") as f:
        f.write("%\n(vcut workload W1: 6 mm ball finishing raster, written by make_w1.py)\n")
        f.write("G21 G90 G94 G17\nT1 M6\nS12000 M3\n")
        x0, y0, z0 = points[0]
        f.write("G0 X%.4f Y%.4f Z%.1f\n" % (x0, y0, safe))
        f.write("G1 Z%.4f F2000\n" % z0)
        for x, y, z in points[1:]:
            f.write("G1 X%.4f Y%.4f Z%.4f\n" % (x, y, z))
        f.write("G0 Z%.1f\nM5\nM30\n%%\n" % safe)
    with open(os.path.join(out, "w1.path"), "w") as f:
        f.write("%.4f %.4f %.1f\n" % (x0, y0, safe))
        for x, y, z in points:
            f.write("%.4f %.4f %.4f\n" % (x, y, z))
    with open(os.path.join(out, "tools.yaml"), "w") as f:
        f.write("tools:\n  1: %s, flute_length: 25, shank_diameter: 6, length: 40}\n" % TOOLS[tool][0])
    if tilt is not None:
        i, j, k = 0.0, math.sin(math.radians(tilt)), math.cos(math.radians(tilt))
        with open(os.path.join(out, "w1.apt"), "w") as f:
            f.write("$$ vcut workload W1T: W1's tip path at a fixed axis tilted %g deg, written by make_w1.py\n" % tilt)
            f.write("UNITS/MM\nMULTAX/ON\n%s\nLOADTL/1\nSPINDL/12000,CLW\n" % TOOLS[tool][1])
            f.write("RAPID\nGOTO/%.4f,%.4f,%.1f,%.6f,%.6f,%.6f\nFEDRAT/2000\n" % (x0, y0, safe, i, j, k))
            for x, y, z in points:
                f.write("GOTO/%.4f,%.4f,%.4f,%.6f,%.6f,%.6f\n" % (x, y, z, i, j, k))
            f.write("RAPID\nGOTO/%.4f,%.4f,%.1f,%.6f,%.6f,%.6f\nFINI\n" % (points[-1][0], points[-1][1], safe, i, j, k))
    head = ("job: w1\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: w1.ngc}\n" if tilt is None else
            "job: w1t\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: w1.apt, dialect: apt}\n")
    with open(os.path.join(out, "job.yaml"), "w") as f:
        f.write(head + "stock: {box: {min: [0, 0, 0], max: [%g, %g, 40]}}\n"
                "engine: {kind: dexel, resolution: 0.05, threads: auto}\n"
                "report: {out: out}\n" % (size, size))
    if tilt is not None:
        print("W1T: %d moves over %g x %g mm, the axis tilted %g deg -> %s" % (len(points), size, size, tilt, out))
        return
    print("W1%s: %d moves over %g x %g mm -> %s" % ({"ball": "", "flat": "F", "bull": "B"}[tool], len(points), size, size, out))


if __name__ == "__main__":
    main()
