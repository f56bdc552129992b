// Closed-form signed distances shared by the cutter, the sweeps and the analytic stocks
// (mm, negative inside). Internal to vcut::removal.
#pragma once

#include <algorithm>
#include <cmath>

namespace vcut::removal {
struct Cutter;
// A V-bit's signed distance in its (radius, height) half-plane, and the gradient there
// (cutter.cpp; cutter_distance's for a V-bit).
double vbit_profile_distance(const Cutter& c, double rho, double z, double& g_rho, double& g_z);
}  // namespace vcut::removal

namespace vcut::removal::detail {

// A convex 2-D shape with signed distance `d_plane`, extruded over an interval with signed
// distance `d_axial`: exact for the product set.
inline double extrude(double d_plane, double d_axial) {
  const double a = std::max(d_plane, 0.0), b = std::max(d_axial, 0.0);
  return std::sqrt(a * a + b * b) + std::min(std::max(d_plane, d_axial), 0.0);
}

// Signed distance of z to the interval [lo, hi].
inline double interval_distance(double z, double lo, double hi) {
  return std::abs(z - 0.5 * (lo + hi)) - 0.5 * (hi - lo);
}

}  // namespace vcut::removal::detail
