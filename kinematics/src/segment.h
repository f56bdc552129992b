// Internal: the nearest point of a segment, shared by densification (chord errors) and the
// interpolator (contour error).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <utility>

namespace vcut::kinematics::detail {

// The nearest point of the segment [a, b] to p: its parameter in [0, 1] and the distance (mm).
inline std::pair<double, double> segment_nearest(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                 const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return {t, (p - (a + t * d)).norm()};
}

}  // namespace vcut::kinematics::detail
