#!/usr/bin/env python3
"""A long three-axis raster for measuring memory per move (issue 22): a 6 mm ball 1 mm deep
in a 50 x 50 x 20 mm box, 50 rows 1 mm apart, each row cut into N / 50 equal G1 moves.
Every size cuts the same part (the same stock, the same machined surface), so the
difference in peak memory between two sizes is what the moves themselves cost.
Writes, into the folder given: r.ngc, tools.yaml, job.yaml (engine dexel, v = 0.1 mm).
Usage: make_raster.py FOLDER MOVES
"""
import os
import sys


def main():
    out, moves = sys.argv[1], int(sys.argv[2])
    os.makedirs(out, exist_ok=True)
    size, rows = 50.0, 50
    per_row = max(1, moves // rows)
    step = size / per_row
    with open(os.path.join(out, "r.ngc"), "w") as f:
        f.write("(vcut memory raster, written by make_raster.py)\nG21 G90 G94 G17\nT1 M6\nS12000 M3\n")
        f.write("G0 X0 Y0 Z25\nG1 Z19 F2000\n")
        for j in range(rows):
            f.write("G1 Y%.4f\n" % float(j))
            for i in range(1, per_row + 1):
                x = i * step if j % 2 == 0 else size - i * step
                f.write("G1 X%.5f\n" % x)
        f.write("G0 Z25\nM5\nM30\n")
    with open(os.path.join(out, "tools.yaml"), "w") as f:
        f.write("tools:\n  1: {type: ball, diameter: 6, corner_radius: 3, flute_length: 25, shank_diameter: 6, length: 40}\n")
    with open(os.path.join(out, "job.yaml"), "w") as f:
        f.write("job: raster\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: r.ngc}\n"
                "stock: {box: {min: [0, 0, 0], max: [50, 50, 20]}}\n"
                "engine: {kind: dexel, resolution: 0.1, threads: auto}\n")


if __name__ == "__main__":
    main()
