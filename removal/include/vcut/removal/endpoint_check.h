// The tri-dexel stock's every interval endpoint against the design, exactly (point to
// triangle): figures that do not depend on meshing.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "vcut/removal/compare.h"
#include "vcut/removal/dexel_stock.h"

namespace vcut::removal {

struct EndpointDeviation {
  std::size_t points = 0;
  double max_gouge_mm = 0.0, max_excess_mm = 0.0;  // positive figures, 0 when none
  Eigen::Vector3d deepest_mm = Eigen::Vector3d::Zero();
  int deepest_move = -1;  // the move that made the deepest gouge point (-1: none, or the initial stock)
  std::size_t gouge_points = 0, excess_points = 0;  // beyond the tolerances
};

// The points are measured in Morton order of their lattice cells (cell size v from
// origin_mm), so that consecutive queries are neighbours; of equally deep gouge points the
// first in that order is the deepest: one answer for any thread count.
EndpointDeviation endpoint_deviation(const std::vector<DexelEndpoint>& points, const Eigen::Vector3d& origin_mm,
                                     double v, const DesignDistance& design, const CompareSettings& settings);

}  // namespace vcut::removal
