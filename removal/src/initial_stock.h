// Signed distances (mm, negative inside) of the analytic initial stocks, shared by the stock
// engines. Internal to vcut::removal.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <functional>
#include <memory>

#include "vcut/removal/stock.h"
#include "distance.h"

namespace vcut::removal {
class DesignDistance;
}

namespace vcut::removal::detail {

inline double box_distance(const BoxShape& box, const Eigen::Vector3d& x) {
  const Eigen::Vector3d q = (x - 0.5 * (box.min_mm + box.max_mm)).cwiseAbs() - 0.5 * (box.max_mm - box.min_mm);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

inline double cylinder_distance(const CylinderShape& c, const Eigen::Vector3d& x) {
  const Eigen::Vector3d d = x - c.base_center_mm;
  const double h = d.dot(c.axis);
  const double radial = (d - h * c.axis).norm();
  return extrude(radial - c.radius_mm, interval_distance(h, 0.0, c.height_mm));
}

// The initial stock's signed distance; a mesh stock keeps its distance structure alive in
// `mesh_distance`.
std::function<double(const Eigen::Vector3d&)> initial_distance(const StockShape& shape,
                                                               std::shared_ptr<const DesignDistance>& mesh_distance);

}  // namespace vcut::removal::detail
