// Triangle meshes in the workpiece frame (mm), and the mesh work done on them with
// OpenMesh: outward vertex normals, per-vertex areas, enclosed volume.
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

// Area-weighted unit vertex normals (OpenMesh); triangles OpenMesh cannot take (complex
// edges) still count through a direct accumulation.
std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh);

// A third of the area of every incident triangle (mm^2): vertex areas sum to the mesh area.
std::vector<double> vertex_areas_mm2(const TriangleMesh& mesh);

// Fewer triangles, for display: OpenMesh's quadric decimater collapses edges until at most
// max_triangles remain. Each collapse keeps one of its two vertices, so every vertex left is
// an original one: `kept` gets, per vertex of the result, its index in `mesh` (its
// attributes carry over). Triangles OpenMesh cannot take (complex edges at thin features)
// are left out. A mesh already small enough comes back as it is.
// Large meshes are cut into slabs of equal triangle counts along their longest axis, each
// decimated to its share of the budget in parallel, the vertices two slabs share kept (so the
// slabs still meet): the same result for any number of threads.
TriangleMesh decimate(const TriangleMesh& mesh, std::size_t max_triangles, std::vector<int>& kept);
// With a given number of slabs (1: the whole mesh at once).
TriangleMesh decimate(const TriangleMesh& mesh, std::size_t max_triangles, std::vector<int>& kept, std::size_t slabs);
// The slabs `decimate` uses: one per 200,000 triangles of the mesh and of the budget, at most 16.
std::size_t decimation_slabs(std::size_t triangles, std::size_t max_triangles);

// Whether every edge is shared by exactly two triangles with opposite orientation.
bool is_closed(const TriangleMesh& mesh);

}  // namespace vcut::removal
