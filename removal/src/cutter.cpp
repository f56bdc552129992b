#include "vcut/removal/cutter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "distance.h"

namespace vcut::removal {

CutterCore core_of(const Cutter& cutter) {
  if (cutter.type == CutterType::VBit) return {cutter.radius_mm(), 0.0, cutter.flute_length_mm, 0.0};
  const double r = cutter.corner_radius_mm;
  return {cutter.radius_mm() - r, r, std::max(r, cutter.flute_length_mm - r), r};
}

namespace {

// Radius per height of a V-bit's cone (the last angle's, kept: meshing asks millions of times).
double vbit_slope(double tip_angle_deg) {
  thread_local double angle_deg = -1.0, slope = 0.0;
  if (tip_angle_deg != angle_deg) {
    angle_deg = tip_angle_deg;
    slope = std::tan(0.5 * tip_angle_deg * M_PI / 180.0);
  }
  return slope;
}

}  // namespace

// Signed distance in the (rho, z) half-plane to the V-bit's profile: the convex polygon
// (0, 0), (R, R / tan(a/2)), (R, H), (0, H), cut at H when the cone is taller than that. Its
// edge on the axis (0, H) - (0, 0) bounds the half-plane, not the solid of revolution: it
// counts for inside or out, never as the nearest surface. The gradient: away from the
// nearest boundary point (toward it inside), the outward normal of the nearest edge on it.
double vbit_profile_distance(const Cutter& c, double rho, double z, double& g_rho, double& g_z) {
  const double slope = vbit_slope(c.tip_angle_deg);
  const double height = c.flute_length_mm;
  const double cone_top = std::min(height, c.radius_mm() / slope);
  const double radius = cone_top * slope;
  // Polygon vertices counter-clockwise in (rho, z).
  const Eigen::Vector2d v[4] = {{0.0, 0.0}, {radius, cone_top}, {radius, height}, {0.0, height}};
  const Eigen::Vector2d q(rho, z);
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector2d away(0.0, 0.0), edge(1.0, 0.0);
  bool inside = true;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d a = v[i], b = v[(i + 1) % 4], e = b - a;
    if (e.squaredNorm() == 0.0) continue;
    if (e.x() * (q.y() - a.y()) - e.y() * (q.x() - a.x()) < 0.0) inside = false;
    if (i == 3) continue;  // the axis
    const double t = std::clamp((q - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    const Eigen::Vector2d off = q - a - t * e;
    const double d2 = off.squaredNorm();
    if (d2 < best) {
      best = d2;
      away = off;
      edge = e;
    }
  }
  const double distance = std::sqrt(best);
  const Eigen::Vector2d g =
      distance > 0.0 ? Eigen::Vector2d(away / distance) : Eigen::Vector2d(edge.y(), -edge.x()).normalized();
  g_rho = inside ? -g.x() : g.x();
  g_z = inside ? -g.y() : g.y();
  return inside ? -distance : distance;
}

double section_radius(const Cutter& c, double h) {
  if (h < 0.0 || h > c.flute_length_mm) return 0.0;
  if (c.type == CutterType::VBit) return std::min(c.radius_mm(), h * vbit_slope(c.tip_angle_deg));
  return core_section_radius(core_of(c), c.flute_length_mm, h);
}

double underside_height(const Cutter& c, double rho) {
  if (c.type == CutterType::VBit) return rho / vbit_slope(c.tip_angle_deg);
  const CutterCore k = core_of(c);
  const double off = rho - k.core_radius_mm;
  return off <= 0.0 ? 0.0 : k.rounding_mm - std::sqrt(std::max(0.0, k.rounding_mm * k.rounding_mm - off * off));
}

double cutter_distance(const Cutter& cutter, const Eigen::Vector3d& p) {
  const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());  // mm: no overflow to guard against
  double g_rho, g_z;
  if (cutter.type == CutterType::VBit) return vbit_profile_distance(cutter, rho, p.z(), g_rho, g_z);
  const CutterCore k = core_of(cutter);
  // The core cylinder is a disk extruded over an interval (exact).
  return detail::extrude(rho - k.core_radius_mm, detail::interval_distance(p.z(), k.z_low_mm, k.z_high_mm)) -
         k.rounding_mm;
}

std::string to_string(CutterType type) {
  switch (type) {
    case CutterType::Flat:
      return "flat";
    case CutterType::Ball:
      return "ball";
    case CutterType::BullNose:
      return "bull";
    case CutterType::VBit:
      return "vbit";
  }
  return "?";
}

}  // namespace vcut::removal
