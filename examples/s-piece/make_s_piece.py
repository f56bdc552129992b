#!/usr/bin/env python3
"""Generates vcut's five-axis example: the aerospace "S" test piece of seed 001 (the RTCP
paper's "S件": two splines in parallel planes joined by a ruled surface, a 3 mm flange on a
rectangular base, checked to +-0.05 mm), its APT CL program (this script is the CAM system),
the tool library and the job file.

Regenerate with:  python3 examples/s-piece/make_s_piece.py     (Python 3 standard library only)
The outputs are deterministic (same bytes on every run). Writes into examples/s-piece/:
part.stl, program.apt, program.ngc (the same motions as TCP G-code), tools.yaml, job.yaml,
job-gcode.yaml, job-servo.yaml (with servo lag).

Workpiece frame (mm): programming zero at the centre of the base plate's top face; x along
the plate's 100 mm side, y along its 60 mm side, z up. The job takes table-table-ac's
workpiece origin (the centre of its table top) as this zero as it stands: vcut models no
table or fixture, so only the machine axis values (Z by 5 mm) would differ from a setup
with the plate standing on the table.

The part (one watertight solid, part.stl):
  * Base plate x -50..50, y -30..30, z -5..0.
  * The S flange, 35 mm tall, 3 mm thick, standing on the plate. Its mid-surface is the
    ruled surface M(u, t) = B(u) + t D(u), u, t in [0, 1], between
        B(u) = (80 u - 40, 12 sin(2 pi u), 0)                 (bottom S curve, plate top)
        T(u) = B(u) + lambda(u) N(u) + (0, 0, 35)             (top S curve, 35 mm higher)
        lambda(u) = 1.5 - cos(2 pi u)                          (0.5 mm at the ends, 2.5 mm mid)
    where N(u) is the unit left normal of B'(u) in the xy plane, and D = T - B. The two
    curves are different S curves in parallel planes (the top one is B pushed sideways by a
    varying lambda), so the flange leans toward +N by atan(lambda/35) = 0.8 .. 4.1 deg: the
    angle between flange and base varies along the S, as in the paper. The surface is not
    developable: the triple product [B', D, D'] = -35 lambda'(u) |B'| vanishes only at
    u = 0, 1/2, 1, so the tangent plane turns along all the other rulings (up to about 5 deg
    from bottom to top; printed). Smallest radius of curvature of B: 13.5 mm (> the 5 mm
    tool radius on the concave side).
  * The two sides. Each side is itself a ruled surface (so that a cylinder can flank it
    along straight rulings) F(u, t) = Bf(u) + t (Tf(u) - Bf(u)): Bf and Tf are B and T
    moved by +-1.5 mm along the mid-surface normal n(u, t) (at t = 0 and t = 1) and then
    slid along the ruling back onto z = 0 and z = 35. They are within a few um of the exact
    +-1.5 mm offsets of M (printed). The "+" side (toward +N, larger y) is the overhanging
    side; the "-" side faces up. The ends u = 0 and u = 1 are planar (lambda' = 0 there:
    the normal does not turn along the end rulings), perpendicular to B'. The top is flat at
    z = 35. Mesh: 200 steps in u, 14 along each ruling; its chord error is printed.

Stock: the box x -50..50, y -30..30, z -5..35 (the wall's top is the stock's top face, left
as supplied; the plate's sides and bottom too).

Tool T1: flat end mill D10, 40 mm of flute (covers the 35 mm flank), 60 mm out of the
holder, gauge length 120 mm. Program (program.apt, APT CL data, ISO 4343 text form: tool
tip x,y,z and unit tool axis i,j,k from the tip toward the spindle, workpiece frame):
  1. Three-axis clearing, axis (0, 0, 1): z levels 28, 21, 14, 7, 0; on each side of the
     flange a column zig-zag along y (stepover 6 mm) and one contour, the tool centre kept
     5.5 mm from the flange's projection onto the plate (0.5 mm left on the flange for the
     flank pass; under the overhang, more). The z = 0 level faces the plate top to its
     design height.
  2. Five-axis flank milling, climb (CLW spindle, the flange on the tool's left): one loop
     counterclockwise seen from above: the "-" side from u = 0 to 1, round the corner, the
     u = 1 end face, round the corner, the "+" side from u = 1 to 0, the u = 0 end face,
     back onto the "-" side, 5 mm of overlap, lead-out.
     Each pose touches one ruling of the side along a straight line: the tool axis is the
     ruling's direction (Tf - Bf)/|Tf - Bf|, the axis line lies R = 5 mm from the ruling
     along the side's unit normal at the ruling's bottom point Bf (single-point offset at
     the bottom, pointing away from the flange). Placement along the axis: the tool is slid
     along its axis until the lowest point of its tilted flat bottom is at the plate top
     (z = 0), so the bottom never cuts into the plate: on the "-" side that lowest point is
     (within 0.03 mm) the contact point Bf itself, the tip centre R sin(lean) above the
     plate; on the overhanging "+" side the flat bottom cannot reach into the corner under
     the overhang, and the side contact starts a little above the plate (the "root wedge",
     printed: a limit of any flat end mill there, which vcut reports as excess). Poses every ~0.5 mm
     along the side's bottom curve; convex corners: the axis stays along the end ruling
     while the tool rolls round the corner edge in 5 deg steps.
     The rulings tilt at most a few degrees from +z, well inside table-table-ac's reach (tool
     axis (sin A sin C, sin A cos C, cos A), A -120..30 deg, C continuous).
One deliberate gouge: three consecutive "-" side poses in the middle of the S are pushed
0.3 mm into the flange (the axis line moved 0.3 mm toward the ruling, then placed along the
axis as above); their program.apt lines are printed and carry a $$ comment. The moves
ending on those three lines and the next one (leaving the gouge) cut into the flange.

Independent estimate of the flank-milling error (to compare with vcut's report):
the design sides are sampled on a grid (every half pose step in u, every 1 mm of height);
for each sample point S with outward unit normal n, the swept tool (every pose plus 3
interpolated poses between neighbours: tip linear, axis on the great circle, as vcut's APT
reader moves it) is intersected exactly with the line S + d n (finite cylinder: radius 5,
flat bottom, 40 mm of flute); the first d inside any tool is the signed error: < 0 a gouge
(the tool went |d| into the design), > 0 material left. Printed per side, above the root
zone, with and without the deliberate gouge.
"""
import bisect
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

# Part.
PLATE_X, PLATE_Y, PLATE_Z = 50.0, 30.0, -5.0  # x -50..50, y -30..30, z -5..0
X_HALF = 40.0        # B spans x -40..40
AMP = 12.0           # S amplitude (y)
H = 35.0             # flange height
LAM0, LAM1 = 1.5, 1.0  # lambda(u) = LAM0 - LAM1 cos(2 pi u)
W = 1.5              # half the flange thickness
NU, NT = 200, 14     # mesh steps in u and along each ruling
# Stock.
STOCK_MIN = (-50.0, -30.0, -5.0)
STOCK_MAX = (50.0, 30.0, 35.0)
# Tool and program.
R = 5.0
FLUTE = 40.0
ALLOWANCE = 0.5      # left by the clearing for the flank pass
LEVELS = (28.0, 21.0, 14.0, 7.0, 0.0)
STEPOVER = 6.0
SAFE_Z = 50.0
FOLLOW_STEP = 1.0    # mm along the keep-out's edge (in x, and in y where it is steep)
POSE_STEP = 0.5      # mm along the side's bottom curve
CORNER_STEP_DEG = 5.0
LEAD = 8.0           # lead-in length beyond the u = 0 end
OVERLAP = 5.0        # flank loop overlap at the end (mm)
GOUGE_DEPTH = 0.3
FEED, PLUNGE = 1500, 600
SUBDIV = 4           # interpolated poses per move in the error estimate


# ---------------------------------------------------------------- vectors
def add(a, b): return (a[0] + b[0], a[1] + b[1], a[2] + b[2])
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def mul(a, s): return (a[0] * s, a[1] * s, a[2] * s)
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
def norm(a): return math.sqrt(dot(a, a))
def unit(a): return mul(a, 1.0 / norm(a))


def slerp(a, b, f):
    """Great-circle interpolation between unit vectors a and b (as vcut's APT reader turns the
    tool axis)."""
    c = max(-1.0, min(1.0, dot(a, b)))
    ang = math.acos(c)
    if ang < 1e-12:
        return a
    s = math.sin(ang)
    return unit(add(mul(a, math.sin((1 - f) * ang) / s), mul(b, math.sin(f * ang) / s)))


# ---------------------------------------------------------------- surfaces
TWO_PI = 2 * math.pi


def lam(u): return LAM0 - LAM1 * math.cos(TWO_PI * u)
def dlam(u): return TWO_PI * LAM1 * math.sin(TWO_PI * u)
def B(u): return (2 * X_HALF * u - X_HALF, AMP * math.sin(TWO_PI * u), 0.0)
def dB(u): return (2 * X_HALF, TWO_PI * AMP * math.cos(TWO_PI * u), 0.0)
def ddB(u): return (0.0, -TWO_PI * TWO_PI * AMP * math.sin(TWO_PI * u), 0.0)


def frame(u):
    """Speed |B'|, unit tangent, unit left normal (xy plane), signed curvature of B."""
    d1, d2 = dB(u), ddB(u)
    sp = norm(d1)
    tg = mul(d1, 1 / sp)
    nn = (-tg[1], tg[0], 0.0)
    kappa = (d1[0] * d2[1] - d1[1] * d2[0]) / sp ** 3
    return sp, tg, nn, kappa


def D(u):
    _, _, nn, _ = frame(u)
    return add(mul(nn, lam(u)), (0.0, 0.0, H))


def dD(u):
    sp, tg, nn, kappa = frame(u)
    # N' = -kappa |B'| T
    return add(mul(nn, dlam(u)), mul(tg, -lam(u) * kappa * sp))


def T(u): return add(B(u), D(u))


def mid_normal(u, t):
    """Unit normal of the mid-surface, toward +N (the "+" side)."""
    return unit(cross(D(u), add(dB(u), mul(dD(u), t))))


def Bf(s, u):
    """Bottom point of side s (+1 or -1) on the ruling u: B + s W n(u, 0) slid along the
    ruling onto z = 0."""
    d = unit(D(u))
    n0 = mid_normal(u, 0.0)
    p = add(B(u), mul(n0, s * W))
    p = add(p, mul(d, -p[2] / d[2]))
    return (p[0], p[1], 0.0)


def Tf(s, u):
    d = unit(D(u))
    n1 = mid_normal(u, 1.0)
    p = add(T(u), mul(n1, s * W))
    p = add(p, mul(d, (H - p[2]) / d[2]))
    return (p[0], p[1], H)


def F(s, u, t):
    b, top = Bf(s, u), Tf(s, u)
    return add(b, mul(sub(top, b), t))


def side_normal(s, u, t):
    """Outward unit normal of side s at (u, t) (away from the flange)."""
    e = 1e-5
    fu = mul(sub(F(s, u + e, t), F(s, u - e, t)), 0.5 / e)
    ft = sub(Tf(s, u), Bf(s, u))
    return mul(unit(cross(fu, ft)), -s)


# ---------------------------------------------------------------- design mesh
class Mesh:
    """Vertices welded in float32 (what the STL stores), so the checks see the written mesh."""

    def __init__(self):
        self.verts, self.tris, self.index = [], [], {}

    def vid(self, p):
        key = struct.unpack("<3f", struct.pack("<3f", *p))
        if key not in self.index:
            self.index[key] = len(self.verts)
            self.verts.append(key)
        return self.index[key]

    def quad(self, a, b, c, d):
        """Counterclockwise seen from outside."""
        a, b, c, d = (self.vid(p) for p in (a, b, c, d))
        self.tris += [(a, b, c), (a, c, d)]

    def polygon(self, pts):
        """Ear clipping of a small simple polygon, counterclockwise seen from +z, in z = 0."""
        idx = list(range(len(pts)))
        out = []

        def turn(a, b, c):
            return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

        while len(idx) > 3:
            for k in range(len(idx)):
                i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % len(idx)]
                a, b, c = pts[i0], pts[i1], pts[i2]
                if turn(a, b, c) <= 1e-12:
                    continue
                if any(turn(a, b, pts[j]) >= 0 and turn(b, c, pts[j]) >= 0 and turn(c, a, pts[j]) >= 0
                       for j in idx if j not in (i0, i1, i2)):
                    continue
                out.append((i0, i1, i2))
                idx.pop(k)
                break
            else:
                raise SystemExit("ear clipping failed")
        out.append(tuple(idx))
        for a, b, c in out:
            self.tris.append((self.vid(pts[a]), self.vid(pts[b]), self.vid(pts[c])))


def build_mesh():
    m = Mesh()
    us = [i / NU for i in range(NU + 1)]
    grid = {}
    for s in (-1, 1):
        for i, u in enumerate(us):
            b, top = Bf(s, u), Tf(s, u)
            for j in range(NT + 1):
                grid[s, i, j] = b if j == 0 else top if j == NT else add(b, mul(sub(top, b), j / NT))
    # Sides: "-" has outward normal dF/du x dF/dt, "+" the opposite.
    for i in range(NU):
        for j in range(NT):
            m.quad(grid[-1, i, j], grid[-1, i + 1, j], grid[-1, i + 1, j + 1], grid[-1, i, j + 1])
            m.quad(grid[1, i, j], grid[1, i, j + 1], grid[1, i + 1, j + 1], grid[1, i + 1, j])
        m.quad(grid[-1, i, NT], grid[-1, i + 1, NT], grid[1, i + 1, NT], grid[1, i, NT])  # top
    for j in range(NT):  # ends
        m.quad(grid[-1, 0, j], grid[-1, 0, j + 1], grid[1, 0, j + 1], grid[1, 0, j])
        m.quad(grid[-1, NU, j], grid[1, NU, j], grid[1, NU, j + 1], grid[-1, NU, j + 1])
    # Plate top: strips between the flange's foot and the plate's long edges, and two end
    # regions; the foot's vertices are the sides' bottom vertices.
    lo = [grid[-1, i, 0] for i in range(NU + 1)]
    hi = [grid[1, i, 0] for i in range(NU + 1)]
    for i in range(NU):
        if not (lo[i + 1][0] > lo[i][0] and hi[i + 1][0] > hi[i][0]):
            raise SystemExit("the flange's foot is not monotone in x")
        m.quad((lo[i][0], -PLATE_Y, 0.0), (lo[i + 1][0], -PLATE_Y, 0.0), lo[i + 1], lo[i])
        m.quad(hi[i], hi[i + 1], (hi[i + 1][0], PLATE_Y, 0.0), (hi[i][0], PLATE_Y, 0.0))
    m.polygon([(-PLATE_X, -PLATE_Y, 0.0), (lo[0][0], -PLATE_Y, 0.0), lo[0], hi[0], (hi[0][0], PLATE_Y, 0.0),
               (-PLATE_X, PLATE_Y, 0.0)])
    m.polygon([(lo[NU][0], -PLATE_Y, 0.0), (PLATE_X, -PLATE_Y, 0.0), (PLATE_X, PLATE_Y, 0.0),
               (hi[NU][0], PLATE_Y, 0.0), hi[NU], lo[NU]])
    # Plate sides along the top face's boundary, counterclockwise seen from above, and bottom.
    ring = [(-PLATE_X, -PLATE_Y)] + [(p[0], -PLATE_Y) for p in lo] + [(PLATE_X, -PLATE_Y), (PLATE_X, PLATE_Y)]
    ring += [(p[0], PLATE_Y) for p in reversed(hi)] + [(-PLATE_X, PLATE_Y)]
    n = len(ring)
    for k in range(n):
        p, q = ring[k], ring[(k + 1) % n]
        m.quad((p[0], p[1], 0.0), (p[0], p[1], PLATE_Z), (q[0], q[1], PLATE_Z), (q[0], q[1], 0.0))
    centre = m.vid((0.0, 0.0, PLATE_Z))
    for k in range(n):
        p, q = ring[k], ring[(k + 1) % n]
        m.tris.append((centre, m.vid((q[0], q[1], PLATE_Z)), m.vid((p[0], p[1], PLATE_Z))))
    return m.verts, m.tris


def check_mesh(verts, tris):
    """Closed (every edge in exactly two triangles), consistently oriented (each directed edge
    once and its reverse once), no degenerate triangle, positive volume."""
    edges = set()
    for t in tris:
        if len(set(t)) < 3:
            raise SystemExit("design mesh: degenerate triangle %r" % (t,))
        for k in range(3):
            e = (t[k], t[(k + 1) % 3])
            if e in edges:
                raise SystemExit("design mesh: edge used twice in one direction: %r" % (e,))
            edges.add(e)
    for (a, b) in edges:
        if (b, a) not in edges:
            raise SystemExit("design mesh: open edge %r" % ((a, b),))
    vol = 0.0
    min_area = 1e9
    for a, b, c in tris:
        pa, pb, pc = verts[a], verts[b], verts[c]
        vol += dot(pa, cross(pb, pc)) / 6
        min_area = min(min_area, 0.5 * norm(cross(sub(pb, pa), sub(pc, pa))))
    if vol <= 0:
        raise SystemExit("design mesh: inward orientation (volume %.3f)" % vol)
    if min_area < 1e-6:
        raise SystemExit("design mesh: sliver triangle (area %g mm2)" % min_area)
    return vol


def integrated_volume():
    """The solid's volume by another route: the plate plus the flange's horizontal sections
    (at height z both sides are at t = z / H) integrated with Simpson's rule."""
    def section(t):
        n = 1000
        loop = [F(-1, i / n, t) for i in range(n + 1)] + [F(1, 1 - i / n, t) for i in range(n + 1)]
        return 0.5 * abs(sum(loop[k][0] * loop[(k + 1) % len(loop)][1] - loop[(k + 1) % len(loop)][0] * loop[k][1]
                             for k in range(len(loop))))
    m = 10
    s = section(0) + section(1) + sum((4 if k % 2 else 2) * section(k / m) for k in range(1, m))
    return 2 * PLATE_X * 2 * PLATE_Y * -PLATE_Z + H * s / (3 * m)


def mesh_chord_error():
    """Largest distance between the exact sides and the mesh, sampled at each quad's centre
    (the two triangles' common diagonal midpoint and the quad's centre point)."""
    worst = 0.0
    for s in (-1, 1):
        for i in range(0, NU, 5):
            u0, u1 = i / NU, (i + 1) / NU
            for j in range(NT):
                t0, t1 = j / NT, (j + 1) / NT
                exact = F(s, (u0 + u1) / 2, (t0 + t1) / 2)
                diag = mul(add(F(s, u0, t0), F(s, u1, t1)), 0.5)
                worst = max(worst, norm(sub(exact, diag)))
    return worst


def closest_on_mid(q, u_guess):
    """Distance from q to the mid-surface (golden-section search in u near u_guess; the best t
    on each ruling in closed form)."""
    def f(u):
        b, d = B(u), D(u)
        t = max(0.0, min(1.0, dot(sub(q, b), d) / dot(d, d)))
        return norm(sub(q, add(b, mul(d, t))))
    a, c = u_guess - 0.02, u_guess + 0.02
    g = (math.sqrt(5) - 1) / 2
    x1, x2 = c - g * (c - a), a + g * (c - a)
    f1, f2 = f(x1), f(x2)
    for _ in range(80):
        if f1 < f2:
            c, x2, f2 = x2, x1, f1
            x1 = c - g * (c - a)
            f1 = f(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + g * (c - a)
            f2 = f(x2)
    return min(f1, f2)


def offset_error():
    """How far the ruled sides are from the exact +-W offsets of the mid-surface."""
    worst = 0.0
    for s in (-1, 1):
        for i in range(1, 40):
            u = i / 40
            for j in range(0, 8):
                t = j / 7
                worst = max(worst, abs(closest_on_mid(F(s, u, t), u) - W))
    return worst


def twist_deg():
    """Largest turn of the mid-surface's normal along one ruling (bottom to top), deg."""
    return max(math.degrees(math.acos(min(1.0, dot(mid_normal(i / 400, 0.0), mid_normal(i / 400, 1.0)))))
               for i in range(401))


def min_radius_b():
    return min(1 / abs(frame(i / 2000)[3]) for i in range(2001) if abs(frame(i / 2000)[3]) > 1e-12)


def write_stl(path, verts, tris):
    with open(path, "wb") as out:
        out.write(b"vcut s-piece design part (seed 001), make_s_piece.py".ljust(80, b" "))
        out.write(struct.pack("<I", len(tris)))
        for a, b, c in tris:
            pa, pb, pc = verts[a], verts[b], verts[c]
            nv = cross(sub(pb, pa), sub(pc, pa))
            ln = norm(nv) or 1.0
            out.write(struct.pack("<12fH", *mul(nv, 1 / ln), *pa, *pb, *pc, 0))


# ---------------------------------------------------------------- tool poses
def place(contact, axis, offset_dir, offset):
    """Tool tip for an axis line at `offset` from `contact` along `offset_dir` (unit, normal
    to the axis): slid along the axis until the lowest point of the flat bottom is at z = 0.
    Also returns the height at which the side contact line starts (the root wedge)."""
    line = add(contact, mul(offset_dir, offset))
    t0 = (R * math.sqrt(max(0.0, 1 - axis[2] ** 2)) - line[2]) / axis[2]
    return add(line, mul(axis, t0)), t0 * axis[2]


def side_u_values(s):
    """u values ~POSE_STEP apart along side s's bottom curve."""
    n = 4000
    pts = [Bf(s, i / n) for i in range(n + 1)]
    cum = [0.0]
    for k in range(n):
        cum.append(cum[-1] + norm(sub(pts[k + 1], pts[k])))
    steps = max(1, round(cum[-1] / POSE_STEP))
    us = []
    for k in range(steps + 1):
        target = cum[-1] * k / steps
        j = min(n - 1, bisect.bisect_right(cum, target) - 1)
        f = (target - cum[j]) / (cum[j + 1] - cum[j])
        us.append((j + f) / n)
    us[0], us[-1] = 0.0, 1.0
    return us, cum[-1]


class Pose:
    def __init__(self, tip, axis, u=None, side=0, wedge=0.0, note=None):
        self.tip, self.axis, self.u, self.side, self.wedge, self.note = tip, axis, u, side, wedge, note


def side_pose(s, u, push=0.0):
    c = Bf(s, u)
    a = unit(sub(Tf(s, u), c))
    o = side_normal(s, u, 0.0)
    tip, wedge = place(c, a, o, R - push)
    return Pose(tip, a, u, s, wedge)


def corner(c, a, o1, o2):
    """Tool rolling round a convex edge through c along a, offset turning from o1 to o2."""
    ang = math.degrees(math.acos(max(-1.0, min(1.0, dot(o1, o2)))))
    n = max(1, math.ceil(ang / CORNER_STEP_DEG))
    return [Pose(place(c, a, slerp(o1, o2, k / n), R)[0], a) for k in range(1, n)]


def flank_loop(gouge_at):
    """The flank-milling loop (see the docstring): the poses in order, the "-" and "+" side
    poses (for the estimate), the lead-in and the lead-out pose."""
    u_lo, _ = side_u_values(-1)
    u_hi, _ = side_u_values(1)
    lo = [side_pose(-1, u, GOUGE_DEPTH if k in gouge_at else 0.0) for k, u in enumerate(u_lo)]
    for k in gouge_at:
        lo[k].note = "deliberate gouge %.1f mm into the flange" % GOUGE_DEPTH
    hi = [side_pose(1, u) for u in reversed(u_hi)]

    def round_end(u, s_from):
        """Round the end u from side s_from to the other side: corner, end face, corner. The
        end face is the plane through the end rulings normal to B'(u), outward +-B'."""
        _, tg, _, _ = frame(u)
        e = tg if u == 1.0 else mul(tg, -1)
        c_from, c_to = Bf(s_from, u), Bf(-s_from, u)
        a = unit(sub(Tf(s_from, u), c_from))
        out = corner(c_from, a, side_normal(s_from, u, 0.0), e)
        out.append(Pose(place(c_from, a, e, R)[0], a))
        out.append(Pose(place(c_to, a, e, R)[0], a))
        out += corner(c_to, a, e, side_normal(-s_from, u, 0.0))
        return out

    loop = lo + round_end(1.0, -1) + hi + round_end(0.0, 1) + [side_pose(-1, 0.0)]
    loop += [side_pose(-1, u) for u in u_lo if 0 < u and norm(sub(Bf(-1, u), Bf(-1, 0.0))) <= OVERLAP]
    last = loop[-1]
    away = Pose(add(last.tip, mul(side_normal(-1, last.u, 0.0), 2.0)), last.axis)
    _, tg0, _, _ = frame(0.0)
    lead = Pose(add(lo[0].tip, mul(tg0, -LEAD)), lo[0].axis)
    return loop, lo, hi, lead, away


# ---------------------------------------------------------------- clearing
def footprint_points():
    """Points whose union of R+ALLOWANCE discs is the clearing's keep-out: the flange's
    projection onto the plate. The flange leans toward +N everywhere (lambda > 0), so that
    projection is bounded by the "-" side's foot, the "+" side's top edge and the end faces'
    projections (segments along N); all four edges are sampled, 0.1 mm apart. Sorted by x."""
    if min(lam(i / 100) for i in range(101)) <= 0:
        raise SystemExit("the keep-out assumes the flange leans toward +N everywhere")
    n = 1000
    pts = [(p[0], p[1]) for s in (-1, 1) for i in range(n + 1) for p in (Bf(s, i / n), Tf(s, i / n))]
    for u in (0.0, 1.0):
        ends = [Bf(-1, u), Bf(1, u), Tf(-1, u), Tf(1, u)]
        for p in ends:
            for q in ends:
                k = max(1, math.ceil(math.hypot(q[0] - p[0], q[1] - p[1]) / 0.1))
                pts += [(p[0] + (q[0] - p[0]) * j / k, p[1] + (q[1] - p[1]) * j / k) for j in range(k + 1)]
    pts.sort()
    return pts


class KeepOut:
    def __init__(self):
        self.pts = footprint_points()
        self.xs = [p[0] for p in self.pts]
        self.rho = R + ALLOWANCE
        self.x_min, self.x_max = self.xs[0] - self.rho, self.xs[-1] + self.rho
        self.y_left = self.pts[0][1]
        self.y_right = self.pts[-1][1]

    def bounds(self, x):
        """(lowest, highest) y of the keep-out on the line x; outside its x range, the y of its
        extreme point (both bounds equal), so that the bounds are continuous in x."""
        if x <= self.x_min:
            return self.y_left, self.y_left
        if x >= self.x_max:
            return self.y_right, self.y_right
        i = bisect.bisect_left(self.xs, x - self.rho)
        j = bisect.bisect_right(self.xs, x + self.rho)
        r2 = self.rho * self.rho
        near = [(py, math.sqrt(r2 - (x - px) ** 2)) for px, py in self.pts[i:j] if (x - px) ** 2 < r2]
        if not near:  # within rho of the x range but no point within reach
            return (self.y_left, self.y_left) if x < 0 else (self.y_right, self.y_right)
        return min(py - h for py, h in near), max(py + h for py, h in near)


def drop_collinear(path):
    out = [path[0]]
    for k in range(1, len(path) - 1):
        a, b, c = out[-1], path[k], path[k + 1]
        cr = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        if abs(cr) > 1e-6 * max(1.0, math.hypot(c[0] - a[0], c[1] - a[1])):
            out.append(b)
    out.append(path[-1])
    return out


def follow(edge, x0, x1):
    """Points of the keep-out's edge y = edge(x) from x0 (excluded) to x1, FOLLOW_STEP apart
    in x and, where the edge is steep (round the flange's ends), in y too."""
    n = max(1, int(round(abs(x1 - x0) / FOLLOW_STEP)))
    out = []
    prev = (x0, edge(x0))
    for j in range(1, n + 1):
        x = x0 + (x1 - x0) * j / n
        p = (x, edge(x))
        parts = max(1, min(64, math.ceil(abs(p[1] - prev[1]) / FOLLOW_STEP)))
        for k in range(1, parts):
            xx = prev[0] + (x - prev[0]) * k / parts
            out.append((xx, edge(xx)))
        out.append(p)
        prev = p
    return out


def clearing_paths(keep):
    """For one z level: the passes below the flange (y < keep-out) and above it, as lists of
    (x, y) tool centre points: a column zig-zag from outside the stock to the keep-out's
    edge, then one contour along that edge."""
    xs = [-PLATE_X + 1]  # columns -49, -43, .. 47: the tool covers x -54 .. 52
    while xs[-1] + R < PLATE_X:
        xs.append(xs[-1] + STEPOVER)
    y_out = PLATE_Y + R + 1
    paths = []
    for which in (0, 1):  # 0: below the flange, from y = -36; 1: above it, from y = +36
        sign = -1 if which == 0 else 1
        edge = lambda x: keep.bounds(x)[which]
        order = xs if which == 0 else list(reversed(xs))
        path = []
        for k, x in enumerate(order):
            if k % 2 == 0:
                path.append((x, sign * y_out))
                path.append((x, edge(x)))
                if k + 1 < len(order):
                    path += follow(edge, x, order[k + 1])
            else:
                path.append((x, sign * y_out))
                if k + 1 < len(order):
                    path.append((order[k + 1], sign * y_out))
        # The zig-zag follows the keep-out's edge only between every other pair of columns:
        # one contour along the whole edge, back to the first column, covers the rest.
        if path[-1][1] == sign * y_out:
            path.append((order[-1], edge(order[-1])))
        path += follow(edge, order[-1], order[0])
        dedup = [path[0]]
        for p in path[1:]:
            if abs(p[0] - dedup[-1][0]) > 1e-9 or abs(p[1] - dedup[-1][1]) > 1e-9:
                dedup.append(p)
        paths.append(drop_collinear(dedup))
    return paths


# ---------------------------------------------------------------- APT output
def fmt(v, d):
    s = "%.*f" % (d, v)
    return "0." + "0" * d if s == "-0." + "0" * d else s


class Apt:
    """APT CL data (ISO 4343 text): GOTO/x,y,z,i,j,k under MULTAX/ON."""
    def __init__(self):
        self.lines = []
        self.gotos = 0

    def add(self, text):
        self.lines.append(text)
        return len(self.lines)

    def comment(self, text):
        return self.add("$$ " + text)

    def feed(self, mm_per_min):
        self.add("FEDRAT/%d,MMPM" % mm_per_min)

    def start(self):
        self.add("PARTNO S-PIECE FIVE-AXIS FLANK TEST (VCUT EXAMPLE, SEED 001)")
        self.comment("generated by examples/s-piece/make_s_piece.py; edit that script, not this file")
        self.comment("workpiece frame: zero at the centre of the base plate's top face, mm")
        self.add("UNITS/MM")
        self.add("MULTAX/ON")
        self.add("CUTTER/10,0,5,0,0,0,40")
        self.add("LOADTL/1")
        self.add("SPINDL/12000,CLW")
        self.add("FROM/0.0000,0.0000,100.0000,0.000000,0.000000,1.000000")

    def end(self):
        self.add("SPINDL/OFF")
        self.add("FINI")

    def goto(self, p, a=(0.0, 0.0, 1.0), rapid=False, note=None):
        if rapid:
            self.add("RAPID")
        self.gotos += 1
        text = "GOTO/%s,%s,%s,%s,%s,%s" % (fmt(p[0], 4), fmt(p[1], 4), fmt(p[2], 4), fmt(a[0], 6), fmt(a[1], 6), fmt(a[2], 6))
        if note:
            text += " $$ " + note
        return self.add(text)


class Ngc(Apt):
    """The same motions as a tool-centre-point G-code program (Fanuc G43.5: X Y Z the tool tip,
    I J K the unit tool axis, both in the workpiece frame), as vcut's G-code reader and
    LinuxCNC-style controls with TCP read it."""
    def __init__(self):
        super().__init__()
        self.pending_feed = None

    def comment(self, text):
        return self.add("(" + text.replace("(", "[").replace(")", "]") + ")")

    def feed(self, mm_per_min):
        self.pending_feed = mm_per_min

    def start(self):
        self.add("%")
        self.comment("S-PIECE FIVE-AXIS FLANK TEST, VCUT EXAMPLE, SEED 001")
        self.comment("generated by examples/s-piece/make_s_piece.py; edit that script, not this file")
        self.comment("workpiece frame: zero at the centre of the base plate's top face, mm")
        self.add("G17 G21 G90 G94 G54")
        self.add("T1 M6")
        self.add("S12000 M3")
        self.add("G43.5 H1")
        self.add("G0 X0.0000 Y0.0000 Z100.0000 I0.000000 J0.000000 K1.000000")

    def end(self):
        self.add("G49")
        self.add("M5")
        self.add("M30")
        self.add("%")

    def goto(self, p, a=(0.0, 0.0, 1.0), rapid=False, note=None):
        self.gotos += 1
        text = "%s X%s Y%s Z%s I%s J%s K%s" % ("G0" if rapid else "G1", fmt(p[0], 4), fmt(p[1], 4), fmt(p[2], 4),
                                              fmt(a[0], 6), fmt(a[1], 6), fmt(a[2], 6))
        if not rapid and self.pending_feed is not None:
            text += " F%d" % self.pending_feed
            self.pending_feed = None
        if note:
            text += " (" + note.replace("(", "[").replace(")", "]") + ")"
        return self.add(text)


def program(keep, loop, lead, away, apt):
    apt.start()
    apt.comment("1. three-axis clearing round the flange, z levels %s, 0.5 mm left on it" %
                ", ".join(fmt(z, 0) for z in LEVELS))
    paths = clearing_paths(keep)
    for z in LEVELS:
        for path in paths:
            x0, y0 = path[0]
            apt.goto((x0, y0, SAFE_Z), rapid=True)
            apt.goto((x0, y0, z + 1.0), rapid=True)
            apt.feed(PLUNGE)
            apt.goto((x0, y0, z))
            apt.feed(FEED)
            for x, y in path[1:]:
                apt.goto((x, y, z))
            x1, y1 = path[-1]
            apt.goto((x1, y1, SAFE_Z), rapid=True)
    apt.comment("2. five-axis flank milling of the flange, one loop counterclockwise seen from above")
    top = add(lead.tip, mul(lead.axis, SAFE_Z - lead.tip[2]))
    apt.goto(top, lead.axis, rapid=True)
    apt.goto(add(lead.tip, mul(lead.axis, 3.0)), lead.axis, rapid=True)
    apt.feed(PLUNGE)
    apt.goto(lead.tip, lead.axis)
    apt.feed(FEED)
    gouge_lines = []
    for p in loop:
        line = apt.goto(p.tip, p.axis, note=p.note)
        if p.note:
            gouge_lines.append(line)
    apt.goto(away.tip, away.axis)
    apt.goto(add(away.tip, mul(away.axis, (SAFE_Z - away.tip[2]) / away.axis[2])), away.axis, rapid=True)
    apt.goto((0.0, 0.0, 100.0), rapid=True)
    apt.end()
    return "\n".join(apt.lines) + "\n", apt.gotos, gouge_lines


# ---------------------------------------------------------------- error estimate
def entry(sp, nv, tip, axis):
    """Smallest d with sp + d nv inside the tool (finite flat cylinder), or None."""
    r0 = (sp[0] - tip[0], sp[1] - tip[1], sp[2] - tip[2])
    ra = r0[0] * axis[0] + r0[1] * axis[1] + r0[2] * axis[2]
    na = nv[0] * axis[0] + nv[1] * axis[1] + nv[2] * axis[2]
    p = (r0[0] - ra * axis[0], r0[1] - ra * axis[1], r0[2] - ra * axis[2])
    q = (nv[0] - na * axis[0], nv[1] - na * axis[1], nv[2] - na * axis[2])
    qq = q[0] * q[0] + q[1] * q[1] + q[2] * q[2]
    pq = p[0] * q[0] + p[1] * q[1] + p[2] * q[2]
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
    lo, hi = -1e9, 1e9
    if qq < 1e-15:
        if pp > R * R:
            return None
    else:
        disc = pq * pq - qq * (pp - R * R)
        if disc < 0:
            return None
        sq = math.sqrt(disc)
        lo, hi = (-pq - sq) / qq, (-pq + sq) / qq
    if abs(na) < 1e-15:
        if not (0.0 <= ra <= FLUTE):
            return None
    else:
        a0, a1 = (0.0 - ra) / na, (FLUTE - ra) / na
        if a0 > a1:
            a0, a1 = a1, a0
        lo, hi = max(lo, a0), min(hi, a1)
    return lo if lo <= hi else None


def sweep(poses):
    """The poses with SUBDIV-1 interpolated ones between neighbours, each with its u."""
    out = []
    for k in range(len(poses) - 1):
        a, b = poses[k], poses[k + 1]
        for j in range(SUBDIV):
            f = j / SUBDIV
            out.append((a.u + (b.u - a.u) * f, add(a.tip, mul(sub(b.tip, a.tip), f)), slerp(a.axis, b.axis, f)))
    out.append((poses[-1].u, poses[-1].tip, poses[-1].axis))
    out.sort(key=lambda e: e[0])
    return out


class SideFrame:
    """Side s along the ruling u: its bottom and top points and their u-derivatives, so that
    F(s, u, t) and the outward normal at any t come cheaply."""

    def __init__(self, s, u):
        e = 1e-5
        self.s = s
        self.b, self.t = Bf(s, u), Tf(s, u)
        self.db = mul(sub(Bf(s, u + e), Bf(s, u - e)), 0.5 / e)
        self.dt = mul(sub(Tf(s, u + e), Tf(s, u - e)), 0.5 / e)
        self.ft = sub(self.t, self.b)

    def point(self, t):
        return add(self.b, mul(self.ft, t))

    def normal(self, t):
        fu = add(self.db, mul(sub(self.dt, self.db), t))
        return mul(unit(cross(fu, self.ft)), -self.s)


def flank_error(s, poses):
    """(most negative error, (u, z)), (most positive error, (u, z)) over the side's grid (every
    half pose step in u, every mm of height), 1 mm above the root wedge and up."""
    sw = sweep(poses)
    su = [e[0] for e in sw]
    us = sorted(p.u for p in poses)
    samples = sorted(us + [(us[k] + us[k + 1]) / 2 for k in range(len(us) - 1)])
    wedge = {p.u: p.wedge for p in poses}
    worst_g, worst_e = (0.0, None), (0.0, None)
    window = 0.03  # in u, about 3 mm along the S: farther poses cannot come nearer
    for u in samples:
        k = bisect.bisect_left(us, u)
        wz = max(wedge[us[max(0, k - 1)]], wedge[us[min(len(us) - 1, k)]])
        cand = sw[bisect.bisect_left(su, u - window):bisect.bisect_right(su, u + window)]
        fr = SideFrame(s, u)
        for j in range(int(H) + 1):
            z = float(j)
            if z < wz + 1.0:
                continue
            sp, nv = fr.point(z / H), fr.normal(z / H)
            best = None
            for _, tip, axis in cand:
                d = entry(sp, nv, tip, axis)
                if d is not None and d > -3.0 and (best is None or d < best):
                    best = d
            if best is None:
                continue
            if best < worst_g[0]:
                worst_g = (best, (u, z))
            if best > worst_e[0]:
                worst_e = (best, (u, z))
    return worst_g, worst_e


def root_excess(poses, keep):
    """Largest distance from the design of the material that the tilted flat bottom leaves in
    the corner under the overhang, where the vertical clearing tool could not reach either:
    in the cross-section through each pose, the bottom's trace q against the floor (q_z) and
    the side ((1 + sigma) R)."""
    worst = 0.0
    for p in poses:
        if p.wedge <= 1e-9:
            continue
        o = side_normal(p.side, p.u, 0.0)
        for k in range(101):
            sgm = -1 + 2 * k / 100
            q = add(p.tip, mul(o, sgm * R))
            lo, hi = keep.bounds(q[0])
            if (q[1] >= hi - R) if p.side > 0 else (q[1] <= lo + R):
                continue  # the clearing tool's side was there, at z = 0
            worst = max(worst, min(q[2], (1 + sgm) * R))
    return worst


def job_text(name, program_file, dialect):
    """The job file's keys (after its comment): the S-piece on the AC trunnion at 0.1 mm."""
    return ("job: %s\n"
            "machine: table-table-ac\n"
            "tools: tools.yaml\n"
            "program: {file: %s, dialect: %s}\n"
            "stock: {box: {min: [%g, %g, %g], max: [%g, %g, %g]}}\n"
            "design: {file: part.stl}\n"
            "engine: {kind: dexel, resolution: 0.1}\n"
            "report: {out: out/%s, gouge_tolerance: 0.05, excess_tolerance: 0.1}\n"
            "densify: {angle: 0.5}\n" % ((name, program_file, dialect) + STOCK_MIN + STOCK_MAX + (name,)))


def main():
    verts, tris = build_mesh()
    vol = check_mesh(verts, tris)
    write_stl(os.path.join(HERE, "part.stl"), verts, tris)
    vol2 = integrated_volume()
    print("part.stl: %d triangles, %d vertices, closed and consistently oriented, volume %.1f mm3 "
          "(sections integrated: %.1f mm3)" % (len(tris), len(verts), vol, vol2))
    print("  flange: lean %.2f .. %.2f deg, normal turns up to %.2f deg along a ruling, smallest radius of B %.1f mm"
          % (math.degrees(math.atan(min(lam(i / 100) for i in range(101)) / H)),
             math.degrees(math.atan(max(lam(i / 100) for i in range(101)) / H)), twist_deg(), min_radius_b()))
    print("  sides within %.4f mm of the exact +-%.1f mm offsets; mesh chord error %.4f mm" % (offset_error(), W, mesh_chord_error()))

    u_lo, len_lo = side_u_values(-1)
    mid_k = len(u_lo) // 2
    gouge_at = (mid_k - 1, mid_k, mid_k + 1)
    loop, lo, hi, lead, away = flank_loop(gouge_at)
    keep = KeepOut()
    text, gotos, gouge_lines = program(keep, loop, lead, away, Apt())
    with open(os.path.join(HERE, "program.apt"), "w") as out:
        out.write(text)
    ngc_text, _, ngc_gouge_lines = program(keep, loop, lead, away, Ngc())
    with open(os.path.join(HERE, "program.ngc"), "w") as out:
        out.write(ngc_text)
    print("program.ngc: the same motions as TCP G-code (G43.5 X Y Z I J K); deliberate gouge at program.ngc:%s"
          % ",".join(str(n) for n in ngc_gouge_lines))
    flank = [lead] + loop + [away]
    tilts = [math.degrees(math.acos(p.axis[2])) for p in flank]
    print("program.apt: %d lines, %d GOTOs (%d flank poses: %d on the - side, %d on the + side, ~%.2f mm apart)"
          % (text.count("\n"), gotos, len(loop), len(lo), len(hi), len_lo / (len(u_lo) - 1)))
    print("  max tool tilt %.2f deg (table-table-ac: A = -tilt in -120..30, C = atan2(-i, -j))" % max(tilts))
    print("  deliberate gouge: program.apt:%s, poses %.1f mm into the - side at u = %.3f..%.3f (x = %.1f .. %.1f);"
          " the moves ending on lines %d..%d cut into the flange"
          % (",".join(str(n) for n in gouge_lines), GOUGE_DEPTH, u_lo[gouge_at[0]], u_lo[gouge_at[-1]],
             Bf(-1, u_lo[gouge_at[0]])[0], Bf(-1, u_lo[gouge_at[-1]])[0], gouge_lines[0], gouge_lines[-1] + 1))
    print("  root wedge (side contact starts this high above the plate): - side %.3f mm, + side %.3f mm"
          % (max(p.wedge for p in lo), max(p.wedge for p in hi)))
    corner_left = root_excess(hi, keep)
    print("  material left in the corner under the overhang (+ side root), up to %.3f mm from the design"
          % corner_left)

    ideal_lo = [side_pose(-1, u) for u in u_lo]
    print("flank-milling error estimate (signed distance from the design side to the swept tool along the "
          "side's normal; < 0 gouge, > 0 material left; side points 1 mm above the root wedge and up):")
    estimates = {}
    for name, s, poses in (("-", -1, ideal_lo), ("+", 1, hi), ("- with the deliberate gouge", -1, lo)):
        (g, gw), (e, ew) = flank_error(s, poses)
        estimates[name] = (g, e)
        print("  %s side: min %+.4f mm%s, max %+.4f mm%s" % (
            name, g, " at u = %.3f, z = %.0f" % gw if gw else "", e, " at u = %.3f, z = %.0f" % ew if ew else ""))

    with open(os.path.join(HERE, "tools.yaml"), "w") as out:
        out.write("tools:\n  1: {type: flat, diameter: 10, flute_length: 40, length: 60, gauge_length: 120}\n")
    g_lo, e_lo = estimates["-"]
    g_hi, e_hi = estimates["+"]
    with open(os.path.join(HERE, "job.yaml"), "w") as out:
        out.write(
            "# Seed 001's S test piece, five-axis flank milling on the table-table-ac trunnion.\n"
            "# Generated by make_s_piece.py (its docstring documents the part, frame and program);\n"
            "# regenerate with: python3 examples/s-piece/make_s_piece.py\n"
            "# Expected report:\n"
            "#   - one gouge, the deliberate one: poses at program.apt:%s pushed %.1f mm into\n"
            "#     the - side (the moves ending on lines %d..%d cut in);\n"
            "#   - flank-milling error of a cylinder along the rulings of this non-developable\n"
            "#     surface (make_s_piece.py's independent estimate, side points 1 mm above the\n"
            "#     root and up): - side %+.3f .. %+.3f mm, + side %+.3f .. %+.3f mm;\n"
            "#   - excess at the + side's root: a flat end mill cannot reach under the overhang\n"
            "#     (side contact from %.2f mm above the plate, material up to %.2f mm from the design);\n"
            "#   - a warning that PARTNO is ignored.\n"
            % (",".join(str(n) for n in gouge_lines), GOUGE_DEPTH, gouge_lines[0], gouge_lines[-1] + 1,
               g_lo, e_lo, g_hi, e_hi,
               max(p.wedge for p in hi), corner_left))
        out.write(job_text("s-piece", "program.apt", "apt"))
    with open(os.path.join(HERE, "job-servo.yaml"), "w") as out:
        out.write("# The S-piece job with servo lag on every axis (seed 004's loop: Kv 20/s, omega_n 120/s,\n"
                  "# zeta 0.8, 5 ms): simulate cuts the actual poses, the prediction of the real part, and\n"
                  "# the nominal ones; report.json's pose_engine gives the contour error per block and\n"
                  "# nominal_vs_actual the distance between the two parts. Geometric errors too: point\n"
                  "# machine: at a machine file with an errors: block (table-table-ac.yaml shows one) and\n"
                  "# add errors: machine. Generated by make_s_piece.py.\n")
        out.write(job_text("s-piece-servo", "program.apt", "apt") +
                  "servo: {kv: 20, omega_n: 120, zeta: 0.8, period: 0.005}\n")
    with open(os.path.join(HERE, "job-gcode.yaml"), "w") as out:
        out.write("# The S-piece job with its program as tool-centre-point G-code (program.ngc, G43.5 X Y Z\n"
                  "# I J K): the same motions as program.apt, so the same report; the deliberate gouge\n"
                  "# is at program.ngc:%s. Generated by make_s_piece.py.\n" % ",".join(str(n) for n in ngc_gouge_lines))
        out.write(job_text("s-piece-gcode", "program.ngc", "gcode"))


if __name__ == "__main__":
    main()
