// Triangle meshes in the workpiece frame (mm), and the mesh work done on them: outward
// vertex normals, per-vertex areas, enclosed volume, closedness, decimation.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <vector>

namespace vcut::removal {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_mm;
  std::vector<Eigen::Vector3i> triangles;  // counter-clockwise seen from outside
};

// Signed enclosed volume (mm^3, divergence theorem): positive for outward triangles.
double signed_volume_mm3(const TriangleMesh& mesh);

// Area-weighted unit vertex normals: every triangle counts, at complex edges too; a vertex
// no triangle uses (or whose triangles' normals cancel) gets zero.
std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh);

// A third of the area of every incident triangle (mm^2): vertex areas sum to the mesh area.
std::vector<double> vertex_areas_mm2(const TriangleMesh& mesh);

// Fewer triangles, for display, in time linear in the mesh (Lindstrom's vertex clustering):
// the vertices are grouped by the cells of a grid, the smallest cell (in steps of a few per
// cent) that leaves at most max_triangles, and each group becomes one of its own vertices, the
// one nearest the planes of the group's triangles (a corner stays a corner, an edge an edge).
// So every vertex left is an original one: `kept` gets, per vertex of the result, its index in
// `mesh` (its attributes carry over). A triangle stays where its corners fall in three groups;
// a triangle and its reverse cancel (a wall thinner than a cell), so a closed mesh's triangles
// still bound a volume, though not always as a manifold. The same result for any number of
// threads. A mesh already small enough comes back as it is.
TriangleMesh decimate(const TriangleMesh& mesh, std::size_t max_triangles, std::vector<int>& kept);

// Whether every edge is shared by exactly two triangles with opposite orientation.
bool is_closed(const TriangleMesh& mesh);

}  // namespace vcut::removal
