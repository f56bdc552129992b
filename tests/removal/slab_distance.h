// How far a point lies outside the sweep of a move's slab (Move::slab_low_mm, slab_high_mm:
// heights above its tip along its axis, swept along the move), for the removal tests.
#pragma once

#include <Eigen/Core>

#include <algorithm>

#include "vcut/removal/move.h"

namespace vcut::removal::test {

// Measured along the axis, <= 0 inside.
inline double slab_distance(const Move& m, const Eigen::Vector3d& p) {
  const double h = (p - m.start_mm).dot(m.axis), along = (m.end_mm - m.start_mm).dot(m.axis);
  return std::max(m.slab_low_mm + std::min(0.0, along) - h, h - (m.slab_high_mm + std::max(0.0, along)));
}

}  // namespace vcut::removal::test
