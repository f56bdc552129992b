#include "vcut/removal/cutter.h"

#include <algorithm>
#include <cmath>

#include "distance.h"

namespace vcut::removal {

CutterCore core_of(const Cutter& cutter) {
  const double r = cutter.corner_radius_mm;
  return {cutter.radius_mm() - r, r, std::max(r, cutter.flute_length_mm - r), r};
}

double cutter_distance(const Cutter& cutter, const Eigen::Vector3d& p) {
  const CutterCore k = core_of(cutter);
  // The core cylinder is a disk extruded over an interval (exact).
  return detail::extrude(std::hypot(p.x(), p.y()) - k.core_radius_mm,
                         detail::interval_distance(p.z(), k.z_low_mm, k.z_high_mm)) -
         k.rounding_mm;
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
