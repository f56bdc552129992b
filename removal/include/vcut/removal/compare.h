// Signed deviation of the machined surface from the design part, exact against the
// design's triangles (a grid of the cells each triangle meets; CGAL's AABB tree for points
// far from the design): negative = gouge (inside the design), positive = excess (material
// left). Workpiece frame, mm.
#pragma once

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <vector>

#include "vcut/removal/mesh.h"
#include "vcut/removal/stock.h"

namespace vcut::removal {

// Signed distance to a triangle mesh. The sign comes from the angle-weighted pseudo-normal
// of the closest feature (face, edge or vertex; Baerentzen & Aanaes 2005), exact for
// closed meshes and the natural choice for open ones.
// The nearest triangle of a previous query: a bound that speeds up the next query near it.
// The distance returned never depends on the hint.
struct DistanceHint {
  std::size_t triangle = static_cast<std::size_t>(-1);  // none
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
};

// Whether a triangle is too thin to have a side (its normal's length within rounding of
// zero): DesignDistance leaves such triangles out.
bool degenerate_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

class DesignDistance {
 public:
  explicit DesignDistance(const TriangleMesh& design);
  ~DesignDistance();
  DesignDistance(DesignDistance&&) noexcept;
  // +infinity for a mesh with no triangle of nonzero area (empty()).
  double signed_distance(const Eigen::Vector3d& x_mm) const;
  double signed_distance(const Eigen::Vector3d& x_mm, DistanceHint& hint) const;
  // The distance from x_mm to the hint's triangle (+infinity without one), or where that is
  // more than enough_mm, to the nearest of it and the triangles across its edges (the hint
  // then names that one): at least |signed_distance(x_mm)|, which is the least such distance
  // over all the triangles computed the same way (a point far from the design, whose nearest
  // triangle CGAL's tree finds, may differ by rounding). One to four point-triangle distances.
  double distance_bound(const Eigen::Vector3d& x_mm, DistanceHint& hint, double enough_mm) const;
  bool closed() const;
  bool empty() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Runs query(i, hint) for every i in [0, count), in parallel, in fixed chunks of 1,024
// consecutive indices, each chunk starting with no hint and passing one hint along: give
// neighbouring points neighbouring indices. The same hints, so the same answers, for any
// thread count.
void hinted_queries(std::size_t count, const std::function<void(std::size_t, DistanceHint&)>& query);

struct CompareSettings {
  double gouge_tolerance_mm = 0.01;
  double excess_tolerance_mm = 0.1;
};

// A connected part of the machined surface beyond a tolerance.
struct Region {
  double depth_mm = 0.0;  // largest |deviation|, positive
  double area_mm2 = 0.0;
  Eigen::Vector3d centroid_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d deepest_mm = Eigen::Vector3d::Zero();
  std::vector<int> moves;  // sorted, unique; -1 = initial stock surface
  int vertices = 0;
};

struct Comparison {
  std::vector<double> deviation_mm;     // per machined vertex
  std::vector<double> vertex_area_mm2;  // per machined vertex: a third of its triangles' area
  std::vector<Region> gouges;           // deepest first
  std::vector<Region> excess;           // thickest first
  double max_gouge_mm = 0.0;            // positive depth, 0 when none
  double max_excess_mm = 0.0;
};

Comparison compare(const SurfaceMesh& machined, const DesignDistance& design, const CompareSettings& settings);

}  // namespace vcut::removal
