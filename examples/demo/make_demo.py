#!/usr/bin/env python3
"""Generates vcut's bundled demo: a design part, a tool library, roughing and finishing
programs for it (this script is the CAM system), and the job file.

Regenerate with:  python3 examples/demo/make_demo.py     (Python 3 standard library only)
The outputs are deterministic (same bytes on every run).

The part (workpiece frame = G54, mm): the stock is the box x 0..100, y 0..70, z -25..0; the
design keeps the stock's sides and bottom and has this top:
  * x <= 60: a freeform surface z = f(x, y) = -4 - 4 s(x) (1 + 0.3 sin(2 pi y / 70)),
    s(x) = (1 + cos(pi x / 60)) / 2, between -9.2 and -4; it meets the flat region at x = 60
    with matching slope (C1). Its smallest radius of curvature is about 140 mm.
  * x >= 60: flat at z = -4, with a pocket: a rounded rectangle x 68..92, y 20..50, corner
    radius 5, vertical walls, flat floor at z = -12 (sharp convex rim, sharp concave floor edge).

Tools: T1 flat D10, T2 ball D6, T3 flat D6.
  rough.ngc   T1 z-level zig-zag (levels -3, -6, -9, -11.5), stepover 6, riding 0.5 mm above
              the design (flat-cutter drop onto the design grown by 0.5 mm).
  finish.ngc  T2 ball raster over x -3..63 along X, stepover 0.5, 0.5 mm segments, tip from an
              exact drop-cutter (Newton on the contact point); T1 facing of the flat region at
              z = -4; T3 pocket floor zig-zag at z = -12 and one wall contour with G3 corner
              arcs of radius 2 (tool centre 3 mm inside the outline).
One deliberate gouge: one ball-raster point 0.3 mm too deep, commented in finish.ngc.
Scallop height of the ball raster: 3 - sqrt(9 - 0.25^2) = 0.0104 mm.
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
R_BALL = 3.0
GOUGE_DEPTH = 0.3
POCKET = (68.0, 92.0, 20.0, 50.0, 5.0, -12.0)  # x0 x1 y0 y1 corner_radius floor_z


def s_of(x):
    return (1 + math.cos(math.pi * x / 60)) / 2 if x < 60 else 0.0


def ds_of(x):
    return -math.pi / 120 * math.sin(math.pi * x / 60) if x < 60 else 0.0


def f(x, y):
    return -4 - 4 * s_of(x) * (1 + 0.3 * math.sin(2 * math.pi * y / 70))


def grad_f(x, y):
    g = 1 + 0.3 * math.sin(2 * math.pi * y / 70)
    dg = 0.3 * 2 * math.pi / 70 * math.cos(2 * math.pi * y / 70)
    return -4 * ds_of(x) * g, -4 * s_of(x) * dg


def in_pocket(x, y, grow=0.0):
    x0, x1, y0, y1, r, _ = POCKET
    r += grow
    x0 -= grow; x1 += grow; y0 -= grow; y1 += grow
    if not (x0 <= x <= x1 and y0 <= y <= y1):
        return False
    cx = min(max(x, x0 + r), x1 - r)
    cy = min(max(y, y0 + r), y1 - r)
    return math.hypot(x - cx, y - cy) <= r + 1e-12


def design_height(x, y):
    """Top of the design at (x, y); None outside the stock."""
    if x < 0 or x > 100 or y < 0 or y > 70:
        return None
    if x <= 60:
        return f(x, y)
    return POCKET[5] if in_pocket(x, y) else -4.0


# ---------------------------------------------------------------- design mesh
def pocket_outline(step_deg=0.5):
    """Counter-clockwise outline of the pocket, corner arcs every step_deg (chord error
    5 (1 - cos(0.25 deg)) = 4.8e-5 mm)."""
    x0, x1, y0, y1, r, _ = POCKET
    corners = [(x1 - r, y0 + r, -90), (x1 - r, y1 - r, 0), (x0 + r, y1 - r, 90), (x0 + r, y0 + r, 180)]
    pts = []
    n = int(round(90 / step_deg))
    for cx, cy, a0 in corners:
        for k in range(n + 1):
            a = math.radians(a0 + 90 * k / n)
            pts.append((cx + r * math.cos(a), cy + r * math.sin(a)))
    return pts


def build_mesh():
    verts, tris, index = [], [], {}

    def vid(p):
        key = (round(p[0], 9), round(p[1], 9), round(p[2], 9))
        if key not in index:
            index[key] = len(verts)
            verts.append(key)
        return index[key]

    h = 0.5
    nx, ny = 120, 140  # freeform grid x 0..60, y 0..70 at 0.5 mm
    xs = [i * h for i in range(nx + 1)]
    ys = [j * h for j in range(ny + 1)]
    for i in range(nx):
        for j in range(ny):
            a = vid((xs[i], ys[j], f(xs[i], ys[j])))
            b = vid((xs[i + 1], ys[j], f(xs[i + 1], ys[j])))
            c = vid((xs[i + 1], ys[j + 1], f(xs[i + 1], ys[j + 1])))
            d = vid((xs[i], ys[j + 1], f(xs[i], ys[j + 1])))
            tris += [(a, b, c), (a, c, d)]
    # Flat region x 60..100 with the pocket hole: merge the outer boundary and the pocket
    # outline by angle around the pocket centre (both are star-shaped about it).
    cx, cy = 80.0, 35.0
    outer = [(60.0, y) for y in reversed(ys)]               # x = 60, from y 70 down to 0
    outer += [(60.0 + k * h, 0.0) for k in range(1, 81)]    # y = 0
    outer += [(100.0, k * h) for k in range(1, 141)]        # x = 100
    outer += [(100.0 - k * h, 70.0) for k in range(1, 80)]  # y = 70 (60 excluded: already there)
    inner = pocket_outline()

    def ang(p):
        return math.atan2(p[1] - cy, p[0] - cx) % (2 * math.pi)

    def rotate_to_min(loop):
        k = min(range(len(loop)), key=lambda i: ang(loop[i]))
        return loop[k:] + loop[:k]

    outer = rotate_to_min(outer)
    inner = rotate_to_min(inner)
    # Both counter-clockwise seen from above.
    oi = [vid((p[0], p[1], -4.0)) for p in outer]
    ii = [vid((p[0], p[1], -4.0)) for p in inner]
    i = j = 0
    no, ni = len(outer), len(inner)
    while i < no or j < ni:
        a_o = ang(outer[(i + 1) % no]) + (2 * math.pi if i + 1 >= no else 0)
        a_i = ang(inner[(j + 1) % ni]) + (2 * math.pi if j + 1 >= ni else 0)
        if j >= ni or (i < no and a_o <= a_i):
            tris.append((oi[i % no], oi[(i + 1) % no], ii[j % ni]))
            i += 1
        else:
            tris.append((oi[i % no], ii[(j + 1) % ni], ii[j % ni]))
            j += 1
    # Pocket walls and floor.
    zf = POCKET[5]
    for k in range(ni):
        p, q = inner[k], inner[(k + 1) % ni]
        a, b = vid((p[0], p[1], -4.0)), vid((q[0], q[1], -4.0))
        c, d = vid((q[0], q[1], zf)), vid((p[0], p[1], zf))
        tris += [(a, b, c), (a, c, d)]  # normals into the pocket opening
    centre = vid((cx, cy, zf))
    for k in range(ni):
        p, q = inner[k], inner[(k + 1) % ni]
        tris.append((centre, vid((p[0], p[1], zf)), vid((q[0], q[1], zf))))
    # Side walls down to z = -25 along the top's boundary, and the bottom.
    boundary = [(x, 0.0) for x in xs] + [(60.0 + k * h, 0.0) for k in range(1, 81)]
    boundary += [(100.0, k * h) for k in range(1, 141)]
    boundary += [(100.0 - k * h, 70.0) for k in range(1, 201)]
    boundary += [(0.0, 70.0 - k * h) for k in range(1, 140)]
    top = [vid((x, y, design_height(x, y))) for x, y in boundary]
    bottom = [vid((x, y, -25.0)) for x, y in boundary]
    nb = len(boundary)
    for k in range(nb):
        a, b = top[k], top[(k + 1) % nb]
        c, d = bottom[(k + 1) % nb], bottom[k]
        tris += [(a, d, c), (a, c, b)]
    bc = vid((50.0, 35.0, -25.0))
    for k in range(nb):
        tris.append((bc, bottom[(k + 1) % nb], bottom[k]))
    return verts, tris


def check_mesh(verts, tris):
    edges = {}
    for t in tris:
        for k in range(3):
            e = (t[k], t[(k + 1) % 3])
            if e in edges:
                raise SystemExit("design mesh: edge used twice in one direction: %r" % (e,))
            edges[e] = 1
    for (a, b) in edges:
        if (b, a) not in edges:
            raise SystemExit("design mesh: open edge %r" % ((a, b),))
    vol = 0.0
    for a, b, c in tris:
        pa, pb, pc = verts[a], verts[b], verts[c]
        vol += (pa[0] * (pb[1] * pc[2] - pb[2] * pc[1]) - pa[1] * (pb[0] * pc[2] - pb[2] * pc[0])
                + pa[2] * (pb[0] * pc[1] - pb[1] * pc[0])) / 6
    if vol <= 0:
        raise SystemExit("design mesh: inward orientation (volume %.3f)" % vol)
    return vol


def write_stl(path, verts, tris):
    with open(path, "wb") as out:
        out.write(b"vcut demo design part".ljust(80, b" "))
        out.write(struct.pack("<I", len(tris)))
        for a, b, c in tris:
            pa, pb, pc = verts[a], verts[b], verts[c]
            u = [pb[i] - pa[i] for i in range(3)]
            v = [pc[i] - pa[i] for i in range(3)]
            n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
            ln = math.sqrt(sum(x * x for x in n)) or 1.0
            out.write(struct.pack("<12fH", *[x / ln for x in n], *pa, *pb, *pc, 0))


# ---------------------------------------------------------------- toolpaths
def flat_drop(x, y, radius, allowance):
    """Lowest tip z of a flat cutter of `radius` at (x, y) staying `allowance` above the
    design, sampled on rings (the slope of f is below 0.4, so 0.6 mm sampling loses < 0.25)."""
    best = -1e9
    for r in [0.0] + [radius * k / 8 for k in range(1, 9)]:
        n = max(1, int(2 * math.pi * r / 0.6))
        for k in range(n):
            a = 2 * math.pi * k / n
            hgt = design_height(x + r * math.cos(a), y + r * math.sin(a))
            if hgt is not None:
                best = max(best, hgt)
    return best + allowance


def ball_tip(x, y):
    """Exact drop of the ball (radius 3) onto z = f: find the contact point p with
    p + R n(p) above (x, y) by Newton, tip = centre - R. f's curvature radius (>= 140 mm)
    exceeds R, so the contact is unique."""
    px, py = x, y
    for _ in range(50):
        gx, gy = grad_f(px, py)
        norm = math.sqrt(1 + gx * gx + gy * gy)
        ex = px - R_BALL * gx / norm - x
        ey = py - R_BALL * gy / norm - y
        if abs(ex) < 1e-12 and abs(ey) < 1e-12:
            break
        px -= ex
        py -= ey
    gx, gy = grad_f(px, py)
    norm = math.sqrt(1 + gx * gx + gy * gy)
    return f(px, py) + R_BALL / norm - R_BALL


def brute_ball_tip(x, y):
    best = -1e9
    for i in range(-60, 61):
        for j in range(-60, 61):
            dx, dy = i * 0.05, j * 0.05
            d2 = dx * dx + dy * dy
            if d2 <= 9:
                best = max(best, f(x + dx, y + dy) + math.sqrt(9 - d2) - 3)
    return best


class Program:
    def __init__(self, title):
        self.lines = ["%", "(" + title + ")", "G17 G21 G90 G94 G54"]

    def add(self, text):
        self.lines.append(text)
        return len(self.lines)  # 1-based line number

    def text(self):
        return "\n".join(self.lines + ["M5", "M30", "%"]) + "\n"


def fmt(v):
    return ("%.4f" % v).rstrip("0").rstrip(".") if abs(v) >= 1e-9 else "0"


def rough():
    p = Program("vcut demo: roughing, T1 flat D10, 0.5 mm allowance")
    p.add("T1 M6")
    p.add("S12000 M3")
    ys = [-4 + 6 * k for k in range(14)]  # -4 .. 74
    xs = [-7 + 2 * k for k in range(58)]  # -7 .. 107
    for level in (-3.0, -6.0, -9.0, -11.5):
        p.add("G0 Z5")
        p.add("G0 X%s Y%s" % (fmt(xs[0]), fmt(ys[0])))
        p.add("G1 Z%s F600" % fmt(level))
        for row, y in enumerate(ys):
            line = xs if row % 2 == 0 else list(reversed(xs))
            if row > 0:
                p.add("G1 Y%s Z%s F1500" % (fmt(y), fmt(max(level, flat_drop(line[0], y, 5.5, 0.5)))))
            for x in line[1:]:
                p.add("G1 X%s Z%s F1500" % (fmt(x), fmt(max(level, flat_drop(x, y, 5.5, 0.5)))))
    p.add("G0 Z5")
    return p


def finish():
    p = Program("vcut demo: finishing")
    p.add("(T2 ball D6 raster over the freeform surface)")
    p.add("T2 M6")
    p.add("S15000 M3")
    gouge_line = None
    ys = [-3 + 0.5 * k for k in range(153)]  # -3 .. 73
    xs = [-3 + 0.5 * k for k in range(133)]  # -3 .. 63
    p.add("G0 Z5")
    p.add("G0 X%s Y%s" % (fmt(xs[0]), fmt(ys[0])))
    p.add("G1 Z%s F800" % fmt(ball_tip(xs[0], ys[0])))
    moves = 0
    for row, y in enumerate(ys):
        line = xs if row % 2 == 0 else list(reversed(xs))
        if row > 0:
            p.add("G1 Y%s Z%s F2000" % (fmt(y), fmt(ball_tip(line[0], y))))
            moves += 1
        for x in line[1:]:
            z = ball_tip(x, y)
            if gouge_line is None and abs(y - 35) < 1e-9 and abs(x - 30) < 1e-9:
                gouge_line = p.add("G1 X%s Z%s F2000 (deliberate gouge: 0.3 mm too deep)" % (fmt(x), fmt(z - GOUGE_DEPTH)))
            else:
                p.add("G1 X%s Z%s F2000" % (fmt(x), fmt(z)))
            moves += 1
    p.add("G0 Z5")
    p.add("(T1 flat D10 facing of the flat region at z = -4)")
    p.add("T1 M6")
    p.add("S12000 M3")
    fy = [-4 + 6 * k for k in range(14)]
    p.add("G0 X57 Y%s" % fmt(fy[0]))
    p.add("G1 Z-4 F600")
    for row, y in enumerate(fy):
        if row > 0:
            p.add("G1 Y%s F1500" % fmt(y))
        p.add("G1 X%s F1500" % ("107" if row % 2 == 0 else "57"))
    p.add("G0 Z5")
    p.add("(T3 flat D6 pocket floor and wall)")
    p.add("T3 M6")
    p.add("S15000 M3")
    p.add("G0 X80 Y35")
    p.add("G1 Z-12 F200")
    for k, x in enumerate([73, 77, 81, 85, 87]):
        y_lo, y_hi = (23, 47) if k % 2 == 0 else (47, 23)
        p.add("G1 X%s Y%s F800" % (fmt(x), fmt(y_lo)))
        p.add("G1 Y%s" % fmt(y_hi))
    # Wall contour: centre path is the outline offset 3 mm inward (corner radius 2).
    p.add("G1 X73 Y23")
    p.add("G1 X87 Y23")
    p.add("G3 X89 Y25 I0 J2")
    p.add("G1 X89 Y45")
    p.add("G3 X87 Y47 I-2 J0")
    p.add("G1 X73 Y47")
    p.add("G3 X71 Y45 I0 J-2")
    p.add("G1 X71 Y25")
    p.add("G3 X73 Y23 I2 J0")
    p.add("G0 Z5")
    return p, gouge_line, moves


def main():
    verts, tris = build_mesh()
    vol = check_mesh(verts, tris)
    write_stl(os.path.join(HERE, "part.stl"), verts, tris)
    print("part.stl: %d triangles, watertight, volume %.1f mm3" % (len(tris), vol))
    # The exact drop-cutter against a brute-force one at a few places.
    for x, y in [(10, 10), (30, 35), (45, 60), (59, 20)]:
        e, b = ball_tip(x, y), brute_ball_tip(x, y)
        if not (0 <= e - b < 0.002):
            raise SystemExit("ball drop-cutter disagrees with brute force at (%g, %g): %g vs %g" % (x, y, e, b))
    r = rough()
    fin, gouge_line, moves = finish()
    with open(os.path.join(HERE, "rough.ngc"), "w") as out:
        out.write(r.text())
    with open(os.path.join(HERE, "finish.ngc"), "w") as out:
        out.write(fin.text())
    with open(os.path.join(HERE, "tools.yaml"), "w") as out:
        out.write("tools:\n"
                  "  1: {type: flat, diameter: 10, corner_radius: 0, flute_length: 25, shank_diameter: 10, length: 40}\n"
                  "  2: {type: ball, diameter: 6, corner_radius: 3, flute_length: 20, shank_diameter: 6, length: 35}\n"
                  "  3: {type: flat, diameter: 6, corner_radius: 0, flute_length: 20, shank_diameter: 6, length: 35}\n")
    with open(os.path.join(HERE, "job.yaml"), "w") as out:
        out.write("job: demo\nmachine: 3axis\ntools: tools.yaml\n"
                  "program: {files: [rough.ngc, finish.ngc], dialect: auto}\n"
                  "offsets: {G54: [0, 0, 0]}\n"
                  "stock: {box: {min: [0, 0, -25], max: [100, 70, 0]}}\n"
                  "design: {file: part.stl}\n"
                  "engine: {kind: vdb, resolution: 0.1, threads: auto}\n"
                  "report: {out: out/demo, gouge_tolerance: 0.02, excess_tolerance: 0.1}\n")
    print("rough.ngc: %d lines; finish.ngc: %d lines, %d ball raster moves" % (len(r.lines) + 3, len(fin.lines) + 3, moves))
    print("deliberate gouge: finish.ngc:%d, %.1f mm deep" % (gouge_line, GOUGE_DEPTH))
    print("ball raster scallop height: %.4f mm" % (R_BALL - math.sqrt(R_BALL ** 2 - 0.25 ** 2)))


if __name__ == "__main__":
    main()
