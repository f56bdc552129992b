#!/usr/bin/env python3
"""Height error of machined meshes against the exact envelope of a swept ball (issue 9's
accuracy check of the bench, independent of vcut's code).

The ball (radius R) centre follows the polyline of tip points + (0, 0, R). On a vertical
line through (x, y), the lowest point of the ball swept along one segment c0 -> c1 is the
lowest of: the two end spheres and the cylinder around the segment (closed form each);
the machined top is the lowest over all segments, capped by the stock top. The mesh's top
at (x, y) is its highest triangle hit by the vertical line.
Usage: height_error.py PATH_FILE RADIUS STOCK_TOP POINTS SEED MESH.stl [MESH.stl ...]
Prints one JSON line per mesh: max and RMS |mesh - exact| over the sample (mm), points used."""
import json
import struct
import sys

import numpy as np


def read_stl(path):
    data = open(path, "rb").read()
    if data[:5] == b"solid" and b"facet" in data[:400]:
        v = [list(map(float, l.split()[1:4])) for l in data.decode().splitlines() if l.strip().startswith("vertex")]
        return np.array(v).reshape(-1, 3, 3)
    n = struct.unpack("<I", data[80:84])[0]
    rec = np.frombuffer(data[84:84 + 50 * n], dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", 9), ("a", "<u2")]))
    return rec["v"].astype(np.float64).reshape(-1, 3, 3)


def envelope(x, y, c0, c1, r, top):
    """Lowest z of the swept ball on the vertical line (x, y), vectorised over segments."""
    best = np.full(1, top)
    for c in (c0, c1):
        d2 = (c[:, 0] - x) ** 2 + (c[:, 1] - y) ** 2
        ok = d2 <= r * r
        if ok.any():
            best = np.minimum(best, (c[ok, 2] - np.sqrt(r * r - d2[ok])).min())
    d = c1 - c0
    m = np.stack([x - c0[:, 0], y - c0[:, 1], -c0[:, 2]], axis=1)
    dd = (d * d).sum(1)
    md = (m * d).sum(1)
    nd = d[:, 2]
    a = dd - nd * nd
    b = dd * m[:, 2] - nd * md
    c = dd * ((m * m).sum(1) - r * r) - md * md
    disc = b * b - a * c
    ok = (a > 1e-12 * dd) & (disc >= 0) & (dd > 0)
    if ok.any():
        s = (-b[ok] - np.sqrt(disc[ok])) / a[ok]
        u = (md[ok] + s * nd[ok]) / dd[ok]  # the projection onto the segment must be inside it
        inside = (u >= 0) & (u <= 1)
        if inside.any():
            best = np.minimum(best, s[inside].min())
    return float(best[0])


def mesh_top(tris, x, y):
    """Highest z where the vertical line (x, y) meets the triangles (barycentric test)."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    ok = np.abs(det) > 1e-18
    l1 = ((x - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (y - a[:, 1])) / np.where(ok, det, 1)
    l2 = ((b[:, 0] - a[:, 0]) * (y - a[:, 1]) - (x - a[:, 0]) * (b[:, 1] - a[:, 1])) / np.where(ok, det, 1)
    hit = ok & (l1 >= -1e-12) & (l2 >= -1e-12) & (l1 + l2 <= 1 + 1e-12)
    if not hit.any():
        return None
    z = a[hit, 2] + l1[hit] * (b[hit, 2] - a[hit, 2]) + l2[hit] * (c[hit, 2] - a[hit, 2])
    return float(z.max())


def main():
    path_file, r, top, count, seed = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
    pts = np.loadtxt(path_file)[1:]  # the first line is the approach point above the stock
    c = pts + np.array([0, 0, r])
    c0, c1 = c[:-1], c[1:]
    lo, hi = pts[:, :2].min(0) + 2 * r, pts[:, :2].max(0) - 2 * r  # away from the raster's ends
    rng = np.random.default_rng(seed)
    samples = rng.uniform(lo, hi, size=(count, 2))
    exact = []
    for x, y in samples:
        near = (np.abs(c0[:, 0] - x) < r + 1) & (np.abs(c0[:, 1] - y) < r + 1)
        exact.append(envelope(x, y, c0[near], c1[near], r, top))
    for path in sys.argv[6:]:
        tris = read_stl(path)
        # Only triangles facing up near the top matter; bucket them on a 1 mm grid.
        cell = np.floor(tris[:, :, :2].mean(1)).astype(np.int64)
        key = cell[:, 0] * 100000 + cell[:, 1]
        order = np.argsort(key)
        key, tris_sorted = key[order], tris[order]
        errors = []
        for (x, y), z_exact in zip(samples, exact):
            cand = []
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    k = (int(np.floor(x)) + dx) * 100000 + int(np.floor(y)) + dy
                    i0, i1 = np.searchsorted(key, k), np.searchsorted(key, k, side="right")
                    if i1 > i0:
                        cand.append(tris_sorted[i0:i1])
            z = mesh_top(np.concatenate(cand), x, y) if cand else None
            if z is not None:
                errors.append(z - z_exact)
        e = np.abs(np.array(errors))
        print(json.dumps({"mesh": path, "points": int(e.size), "max_mm": float(e.max()) if e.size else None,
                          "rms_mm": float(np.sqrt((e * e).mean())) if e.size else None}))


if __name__ == "__main__":
    main()
