// The volume swept by a cutter translated along a segment, as a signed distance (mm,
// negative inside) in the workpiece frame: d(x) = min over t in [0,1] of
// d_cutter(R^T (x - p0 - t*delta)) (ARCHITECTURE §8).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <limits>

#include "vcut/removal/cutter.h"
#include "vcut/removal/move.h"

namespace vcut::removal {

// Exactness: the cutter is a core cylinder K grown by a ball of radius r, so the sweep is
// (K + segment) grown by r. For motion perpendicular or parallel to the tool axis,
// K + segment is a stadium or a cylinder extruded over an interval and the distance is in
// closed form. Otherwise d is the minimum of a convex function of t, found by
// golden-section search to kGeneralSweepTolerance_mm. Outside the sweep the distance is
// exact to that tolerance; inside, |d| may be underestimated (never the sign), which the
// level-set narrow band tolerates.
inline constexpr double kGeneralSweepTolerance_mm = 1e-7;

class TranslationSweep {
 public:
  TranslationSweep(const Cutter& cutter, const Move& move);

  // With far_mm: where the distance is at least far_mm, any value >= far_mm may come back
  // (a cheaper lower bound); elsewhere the exact distance.
  double distance(const Eigen::Vector3d& x_mm,
                  double far_mm = std::numeric_limits<double>::infinity()) const;
  const Eigen::AlignedBox3d& bounds() const { return bounds_; }

 private:
  enum class Kind { Along, Across, General };
  double core_distance(const Eigen::Vector3d& y) const;  // y in the tool frame at t = 0

  CutterCore core_;
  Cutter cutter_;  // a V-bit's distance comes from its profile, not from a core
  Eigen::Matrix3d to_tool_;  // workpiece -> tool frame rotation (tool axis to +Z)
  Eigen::Vector3d origin_;   // tip at t = 0
  Eigen::Vector3d delta_tool_;
  double delta_length_;
  Kind kind_;
  Eigen::AlignedBox3d bounds_;
};

}  // namespace vcut::removal
