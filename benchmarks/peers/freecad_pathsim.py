#!/usr/bin/python3
"""FreeCAD's CAM simulator (PathSimulator, a height map) on a tip path: the peer vcut is
measured against in `make bench`. Run with Debian's /usr/bin/python3 (package
freecad-python3). Usage: freecad_pathsim.py PATH_FILE STOCK_X STOCK_Y STOCK_Z RES OUT.stl
Prints one JSON line: moves, cut_s (ApplyCommand loop), total_s (set-up, cut, mesh, write),
triangles, peak_memory_mb."""
import json
import resource
import sys
import time

sys.path.append("/usr/lib/freecad-python3/lib")
t_start = time.perf_counter()
import FreeCAD  # noqa: E402
import Mesh  # noqa: E402
import Part  # noqa: E402
import Path  # noqa: E402
import PathSimulator  # noqa: E402

path_file, sx, sy, sz, res, out = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5]), sys.argv[6]
points = [tuple(map(float, line.split())) for line in open(path_file) if line.strip()]
t0 = time.perf_counter()
stock = Part.makeBox(sx, sy, sz)
sim = PathSimulator.PathSim()
sim.BeginSimulation(stock, res)
# Ball D6 with 25 mm of flutes: tip at the origin, axis +Z.
tool = Part.makeCylinder(3.0, 25.0, FreeCAD.Vector(0, 0, 3.0)).fuse(Part.makeSphere(3.0, FreeCAD.Vector(0, 0, 3.0)))
sim.SetToolShape(tool, res)
x0, y0, z0 = points[0]
placement = FreeCAD.Placement(FreeCAD.Vector(x0, y0, z0), FreeCAD.Rotation())
t_cut = time.perf_counter()
for x, y, z in points[1:]:
    placement = sim.ApplyCommand(placement, Path.Command("G1", {"X": x, "Y": y, "Z": z}))
cut_s = time.perf_counter() - t_cut
meshes = sim.GetResultMesh()  # the stock's sides and bottom, and the machined top
result = meshes[0].copy()
for m in meshes[1:]:
    result.addMesh(m)
result.write(out)
total_s = time.perf_counter() - t0
print(json.dumps({"moves": len(points) - 1, "cut_s": cut_s, "total_s": total_s,
                  "triangles": result.CountFacets,
                  "peak_memory_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}))
