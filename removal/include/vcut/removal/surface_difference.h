// The distance between two machined surfaces: engine: both's self-check, the nominal
// against the actual part, a densification study's settings against their reference.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "vcut/removal/compare.h"
#include "vcut/removal/stock.h"

namespace vcut::removal {

// The distance between two machined surfaces, every vertex of each against the other's
// triangles.
struct SurfaceDifference {
  bool done = false;
  double max_mm = 0.0, rms_mm = 0.0, p99_mm = 0.0;  // over every vertex of both surfaces
  Eigen::Vector3d max_where_mm = Eigen::Vector3d::Zero();
  std::size_t vertices = 0, beyond_quarter = 0;  // vertices farther apart than v/4
  // With sharp edges left out: how many vertices were, and the largest distance among them.
  std::size_t edge_vertices = 0;
  double edge_max_mm = 0.0;
};

// The angle (deg) past which the engine check and `vcut study` call an edge sharp.
inline constexpr double kSharpEdgeDeg = 20.0;

// Every vertex of each surface against the other's triangles (exact point-to-triangle);
// beyond_quarter counts those farther than v/4 (v: the voxel size, mm). With
// sharp_edge_deg > 0 the vertices within 2 v of a sharp edge of either surface (a vertex
// where an incident face's normal strays more than that from their mean) are left out of
// max, RMS and p99 and reported as edge_*: meshing cuts a sharp edge's corner anywhere
// within a cell or two, so two meshings of nearly one solid differ there by up to ~v/2.
SurfaceDifference surface_difference(const SurfaceMesh& a, const SurfaceMesh& b, double v, double sharp_edge_deg = 0.0);

// A surface made ready once to be measured against several (a densification study's
// reference): its triangles' distance structure and its sharp vertices. It refers to
// `surface`, which must outlive it.
class PreparedSurface {
 public:
  PreparedSurface(const SurfaceMesh& surface, double sharp_edge_deg);
  const SurfaceMesh& surface() const { return surface_; }
  const DesignDistance& distance() const { return distance_; }
  double sharp_edge_deg() const { return sharp_edge_deg_; }
  const std::vector<Eigen::Vector3d>& sharp_points() const { return sharp_points_; }

 private:
  const SurfaceMesh& surface_;
  DesignDistance distance_;
  double sharp_edge_deg_;
  std::vector<Eigen::Vector3d> sharp_points_;  // vertices at a sharp edge (none when sharp_edge_deg is 0)
};

// The same as surface_difference(a, b.surface(), v, b.sharp_edge_deg()), to the bit.
SurfaceDifference surface_difference(const SurfaceMesh& a, const PreparedSurface& b, double v);

}  // namespace vcut::removal
