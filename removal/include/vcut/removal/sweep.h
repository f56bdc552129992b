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
// closed form. Otherwise d is the minimum of a convex function of t, found to
// kGeneralSweepTolerance_mm by secant steps on its analytic slope (the cylinder core's, or
// the V-bit profile's gradient turned about the axis). Outside the sweep the distance is
// exact to that tolerance; inside, |d| may be underestimated (never the sign), which the
// level-set narrow band tolerates.
inline constexpr double kGeneralSweepTolerance_mm = 1e-7;

class TranslationSweep {
 public:
  TranslationSweep(const Cutter& cutter, const Move& move);

  // With far_mm: where the distance is at least far_mm, any value >= far_mm may come back
  // (a cheaper lower bound); elsewhere the exact distance.
  double distance(const Eigen::Vector3d& x_mm, double far_mm = std::numeric_limits<double>::infinity()) const;
  const Eigen::AlignedBox3d& bounds() const { return bounds_; }
  // distance(x[j]) for j < n, the same values to the bit. A tilted flat or bull-nose cutter in
  // general motion (its march's case) takes the points' first steps side by side: each is a
  // chain of square roots, and four at once keep the processor busy where one waits. With
  // `lanes`, where the processor has AVX2, those steps (the ends of the move, which settle 95 %
  // of W5's bull-nose points) are four points' lanes of one AVX2 evaluation.
  void distances(const Eigen::Vector3d* x_mm, int n, double* out, bool lanes = true) const;
  // The same, with each distance's slope along the workpiece's axis `axis` (0, 1, 2: d distance
  // / d x[axis]) into slope[j] where it is exact: a tilted flat or bull-nose cutter in general
  // motion whose nearest instance to the point is the move's start or end (where the ends
  // settle the least, as for 95 % of W5's bull-nose points), the point outside the core's
  // sweep (the distance to a convex set is smooth there: its gradient is the unit vector from
  // the nearest point). Elsewhere NaN: a least inside the move is found only to a tolerance,
  // and the other cutters and motions take no slope. The same bits with and without lanes.
  void distances(const Eigen::Vector3d* x_mm, int n, double* out, bool lanes, int axis, double* slope) const;

  // A ball end's sweep is the sweep of its core (a segment on the axis) grown by the ball's
  // radius: the point q_mm of the core's sweep nearest x_mm (workpiece frame), so that
  // distance(x) = |x - q| - radius_mm and, outside the core's sweep, the sweep's surface
  // point nearest x is q + radius (x - q) / |x - q|. False for other cutters.
  bool ball_core_nearest(const Eigen::Vector3d& x_mm, Eigen::Vector3d& q_mm, double& radius_mm) const;

  // The sweep's surface point nearest x_mm (workpiece frame) where x lies outside the core's
  // sweep: for a ball end, ball_core_nearest's q grown by the radius toward x; for a flat or
  // bull-nose end mill moving other than square to or along its axis, the core cylinder's
  // point nearest x's nearest instance grown by r toward x. False otherwise (a V-bit, the
  // motions whose distance is in closed form, x in or on the core's sweep).
  bool surface_point(const Eigen::Vector3d& x_mm, Eigen::Vector3d& out_mm) const;

  // Whether, at every point of `box` (workpiece frame), the nearest cutter instance of the
  // sweep is the one at the move's start, so that the distance to the sweep is the distance
  // to that cutter: true only when that is certain. The test: d(t) = d_K(y - t delta) is
  // convex in t, so t = 0 is its minimum when d'(0) >= 0, i.e. when delta points away from
  // the outward normal at y's nearest point of K. Ball-end cutters only (K's core is a
  // segment on the axis, so the normal is y - c(y) with c(y) y's nearest core point); for
  // other cutters it returns false. A move that continues the cutter's previous move (same
  // cutter and axis, starting where it ended) changes nothing where this holds.
  bool start_dominates(const Eigen::AlignedBox3d& box) const;
  bool start_dominates(const Eigen::Vector3d& x) const;

 private:
  enum class Kind { Along, Across, General };
  double core_distance(const Eigen::Vector3d& y) const;  // y in the tool frame at t = 0
  bool ball() const { return core_.core_radius_mm == 0.0 && cutter_.type != CutterType::VBit; }
  // Kind::Across: the point of the motion's segment (tool frame, xy) nearest y's xy.
  Eigen::Vector2d across_spine(const Eigen::Vector3d& y) const;
  // Kind::Along: the heights the core's segment covers over the move (tool frame).
  void along_span(double& lo_mm, double& hi_mm) const;
  // A ball end's core sweep (tool frame, y relative to the tip at t = 0): its point nearest y.
  Eigen::Vector3d ball_core_point(const Eigen::Vector3d& y) const;
  // The General kind for a cylinder core: the distance to the core's sweep (before the
  // rounding), exact to kGeneralSweepTolerance_mm, or any value >= far where it is that far.
  double cylinder_sweep_distance(const Eigen::Vector3d& y, double far) const;
  // cylinder_sweep_distance's f(t) at t: its value and slope num / den (den > 0).
  void cylinder_eval(const Eigen::Vector3d& y, double t, double& f, double& num, double& den) const;
  // The same, and the value's slope along e (tool frame) as along_num / den.
  void cylinder_eval(const Eigen::Vector3d& y, double t, const Eigen::Vector3d& e, double& f, double& num, double& den,
                     double& along_num) const;
  Eigen::Vector3d tool_frame(const Eigen::Vector3d& x) const { return to_tool_ * (x - origin_); }
  // The same for a V-bit (its whole profile).
  double vbit_sweep_distance(const Eigen::Vector3d& y, double far) const;

  CutterCore core_;
  Cutter cutter_;            // a V-bit's distance comes from its profile, not from a core
  Eigen::Matrix3d to_tool_;  // workpiece -> tool frame rotation (tool axis to +Z)
  Eigen::Vector3d origin_;   // tip at t = 0
  Eigen::Vector3d delta_tool_;
  double delta_length_;
  Kind kind_;
  Eigen::AlignedBox3d bounds_;
};

}  // namespace vcut::removal
