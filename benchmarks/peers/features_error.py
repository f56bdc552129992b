#!/usr/bin/env python3
"""Height error of machined meshes on the fine-features workload (make_features.py),
independent of vcut's code.

Every cutting move there is horizontal (constant Z) or a vertical plunge, so on the vertical
line through (x, y) a move's lowest point is its lower end's height plus the tool's underside
at the horizontal distance d from the move's xy projection (a point, for a plunge):
  flat (radius R):         0                      for d <= R
  ball (radius r):         r - sqrt(r^2 - d^2)    for d <= r
  V-bit (angle a, rad. R): d / tan(a / 2)         for d <= R
The exact machined top is the lowest of these over all moves, capped by the stock top.
The mesh's top at (x, y) is its highest triangle hit by the vertical line.

Points: 80 % of POINTS within 0.6 tool radii of a random horizontal cutting move, 20 %
anywhere in the features' regions (each tool's moves' bounding box grown by its radius, kept
0.5 mm inside the stock's outline). Points within WALL mm of a flat cutter's vertical wall
(where the exact height jumps, and a sub-voxel shift of the wall gives an error as tall as
the wall) are counted as wall_points and left out of max/RMS. Besides, 2,000 points exactly on
the V-bit engravings' centre lines (d = 0): the engraving is visible there when the mesh
lies at least 0.05 mm below the stock top.
Usage: features_error.py PATH_JSON [POINTS [SEED]] MESH.stl [MESH.stl ...]   (Debian python3
with numpy; POINTS defaults to 2000, SEED to 1). Prints one JSON line per mesh."""
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from height_error import mesh_top, read_stl  # noqa: E402  (numpy STL reader, vertical-ray hit)

WALL = 0.1        # mm, 2 voxels at v = 0.05
VISIBLE = 0.05    # mm below the stock top
CENTRE_POINTS = 2000  # the floor is checked where creases meet and end too, not only mid-groove


class Exact:
    """The closed-form machined top, vectorised over points and moves."""

    def __init__(self, data):
        tools = data["tools"]
        seg = data["segments"]
        self.top = float(data.get("stock", {}).get("max", [0, 0, 0.0])[2])
        self.a = np.array([s["start"] for s in seg], dtype=float)
        self.b = np.array([s["end"] for s in seg], dtype=float)
        for s in seg:
            if s["start"][2] != s["end"][2] and s["start"][:2] != s["end"][:2]:
                raise SystemExit("move neither horizontal nor vertical: %r" % s)
        tl = [tools[str(s["tool"])] for s in seg]
        self.tool = np.array([s["tool"] for s in seg])
        self.kind = np.array([{"flat": 0, "ball": 1, "vbit": 2}[t["type"]] for t in tl])
        self.r = np.array([t["diameter"] / 2.0 for t in tl])
        self.cot = np.array([1.0 / math.tan(math.radians(t.get("angle", 90.0)) / 2) for t in tl])
        self.zlow = np.minimum(self.a[:, 2], self.b[:, 2])
        self.d = self.b[:, :2] - self.a[:, :2]
        self.l2 = (self.d ** 2).sum(1)

    def distance(self, p):
        """(points, moves) horizontal distances from the points to the moves' xy projections."""
        rel = p[:, None, :] - self.a[None, :, :2]
        t = np.where(self.l2 > 0, (rel * self.d).sum(2) / np.where(self.l2 > 0, self.l2, 1), 0.0)
        t = np.clip(t, 0.0, 1.0)
        return np.hypot(rel[..., 0] - t * self.d[:, 0], rel[..., 1] - t * self.d[:, 1])

    def height(self, p, chunk=500):
        out = np.empty(len(p))
        for i in range(0, len(p), chunk):
            d = self.distance(p[i:i + chunk])
            r = self.r
            under = np.where(self.kind == 0, 0.0,
                             np.where(self.kind == 1, r - np.sqrt(np.maximum(r * r - d * d, 0.0)), d * self.cot))
            z = np.where(d <= r, self.zlow + under, np.inf)
            out[i:i + chunk] = np.minimum(self.top, z.min(1))
        return out

    def near_wall(self, p):
        """Points within WALL of a vertical step of the exact top (a flat cutter's rim where it
        is not covered by something deeper): the height jumps by more than a 45 degree slope
        allows (plus 0.02 mm) between the point and one of 16 points around it at WALL."""
        ang = np.linspace(0, 2 * math.pi, 16, endpoint=False)
        ring = WALL * np.stack([np.cos(ang), np.sin(ang)], 1)
        zc = self.height(p)
        zn = self.height((p[:, None, :] + ring[None]).reshape(-1, 2)).reshape(len(p), -1)
        return (np.abs(zn - zc[:, None]) > WALL + 0.02).any(1)


class MeshTop:
    """Vertical-ray top of a triangle mesh, the triangles bucketed on a 1 mm grid by their
    bounding boxes (the approach of height_error.py)."""

    def __init__(self, path, zmin):
        tris = read_stl(path)
        tris = tris[tris[:, :, 2].max(1) >= zmin]  # the stock's floor and low walls never are the top
        lo = np.floor(tris[:, :, :2].min(1)).astype(np.int64)
        hi = np.floor(tris[:, :, :2].max(1)).astype(np.int64)
        idx, keys = [], []
        for dx in range(int((hi - lo)[:, 0].max()) + 1):
            for dy in range(int((hi - lo)[:, 1].max()) + 1):
                ok = (lo[:, 0] + dx <= hi[:, 0]) & (lo[:, 1] + dy <= hi[:, 1])
                idx.append(np.nonzero(ok)[0])
                keys.append((lo[ok, 0] + dx) * 1000003 + lo[ok, 1] + dy)
        idx, keys = np.concatenate(idx), np.concatenate(keys)
        order = np.argsort(keys, kind="stable")
        self.keys, self.tris = keys[order], tris[idx[order]]

    def __call__(self, x, y):
        k = int(math.floor(x)) * 1000003 + int(math.floor(y))
        i0, i1 = np.searchsorted(self.keys, k), np.searchsorted(self.keys, k, side="right")
        return mesh_top(self.tris[i0:i1], x, y) if i1 > i0 else None


def samples(ex, data, count, rng):
    horiz = np.nonzero(ex.l2 > 0)[0]
    n_near = int(round(0.8 * count))
    pick = rng.choice(horiz, size=n_near)
    t = rng.uniform(size=n_near)
    ang = rng.uniform(0, 2 * math.pi, size=n_near)
    rad = 0.6 * ex.r[pick] * np.sqrt(rng.uniform(size=n_near))
    near = ex.a[pick, :2] + t[:, None] * ex.d[pick] + rad[:, None] * np.stack([np.cos(ang), np.sin(ang)], 1)
    smin = np.array(data.get("stock", {}).get("min", [-1e9, -1e9])[:2], float) + 0.5
    smax = np.array(data.get("stock", {}).get("max", [1e9, 1e9])[:2], float) - 0.5
    boxes = []
    for tool in np.unique(ex.tool):
        m = (ex.tool == tool) & (ex.zlow < ex.top)
        r = ex.r[m].max()
        pts = np.concatenate([ex.a[m, :2], ex.b[m, :2]])
        boxes.append((np.maximum(pts.min(0) - r, smin), np.minimum(pts.max(0) + r, smax)))
    which = rng.integers(len(boxes), size=count - n_near)
    region = np.array([rng.uniform(boxes[w][0], boxes[w][1]) for w in which]).reshape(-1, 2)
    near = near[np.all((near >= smin) & (near <= smax), 1)]
    return np.concatenate([near, region])


def main():
    args = sys.argv[1:]
    if not args or not args[-1].lower().endswith(".stl"):
        raise SystemExit(__doc__)
    data = json.load(open(args[0]))
    nums = [a for a in args[1:] if not a.lower().endswith(".stl")]
    meshes = [a for a in args[1:] if a.lower().endswith(".stl")]
    count = int(nums[0]) if nums else 2000
    seed = int(nums[1]) if len(nums) > 1 else 1
    ex = Exact(data)
    rng = np.random.default_rng(seed)
    pts = samples(ex, data, count, rng)
    exact = ex.height(pts)
    wall = ex.near_wall(pts)
    vb = np.nonzero((ex.kind == 2) & (ex.l2 > 0) & (ex.zlow < ex.top))[0]
    pick = rng.choice(vb, size=CENTRE_POINTS)
    centre = ex.a[pick, :2] + rng.uniform(size=CENTRE_POINTS)[:, None] * ex.d[pick]
    centre_exact = ex.height(centre)
    zmin = ex.zlow.min() - 1.0
    for path in meshes:
        top = MeshTop(path, zmin)
        err, missed = [], 0
        for (x, y), z, w in zip(pts, exact, wall):
            if w:
                continue
            m = top(x, y)
            if m is None:
                missed += 1
            else:
                err.append(m - z)
        e = np.abs(np.array(err))
        deep, cerr = 0, []
        for (x, y), z in zip(centre, centre_exact):
            m = top(x, y)
            if m is not None:
                deep += m <= ex.top - VISIBLE
                cerr.append(abs(m - z))
        print(json.dumps({
            "mesh": path, "points": int(e.size), "wall_points": int(wall.sum()), "missed": missed,
            "max_mm": float(e.max()) if e.size else None,
            "rms_mm": float(np.sqrt((e * e).mean())) if e.size else None,
            "engravings_visible": {"deep": int(deep), "total": CENTRE_POINTS, "all": bool(deep == CENTRE_POINTS),
                                   "centre_max_mm": float(max(cerr)) if cerr else None,
                                   "centre_mean_mm": float(np.mean(cerr)) if cerr else None,
                                   "centre_within_0.005": int(sum(1 for c in cerr if c <= 0.005))},
            # the keys scripts/bench-features reads
            "engraving_points_deeper_than_0.05": int(deep), "engraving_points": CENTRE_POINTS}))


if __name__ == "__main__":
    main()
