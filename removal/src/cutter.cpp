#include "vcut/removal/cutter.h"

#include <algorithm>
#include <cmath>

namespace vcut::removal {

CutterCore core_of(const Cutter& cutter) {
  const double r = cutter.corner_radius_mm;
  return {cutter.radius_mm() - r, r, std::max(r, cutter.flute_length_mm - r), r};
}

double cutter_distance(const Cutter& cutter, const Eigen::Vector3d& p) {
  const CutterCore k = core_of(cutter);
  // Signed distance to the core cylinder: a disk extruded over an interval (exact).
  const double d_radial = std::hypot(p.x(), p.y()) - k.core_radius_mm;
  const double z_mid = 0.5 * (k.z_low_mm + k.z_high_mm);
  const double d_axial = std::abs(p.z() - z_mid) - 0.5 * (k.z_high_mm - k.z_low_mm);
  const double outside = std::hypot(std::max(d_radial, 0.0), std::max(d_axial, 0.0));
  const double inside = std::min(std::max(d_radial, d_axial), 0.0);
  return outside + inside - k.rounding_mm;
}

std::string to_string(CutterType type) {
  switch (type) {
    case CutterType::Flat: return "flat";
    case CutterType::Ball: return "ball";
    case CutterType::BullNose: return "bull";
  }
  return "?";
}

}  // namespace vcut::removal
