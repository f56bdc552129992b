#include "vcut/kinematics/densify.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace vcut::kinematics {
namespace {
constexpr double kTwoPi = 2.0 * M_PI;
}

int arc_chord_count(double radius_mm, double angle_rad, double tolerance_mm) {
  if (radius_mm <= tolerance_mm) return std::max(1, static_cast<int>(std::ceil(angle_rad / (M_PI / 2))));
  const double max_angle = 2.0 * std::acos(1.0 - tolerance_mm / radius_mm);
  return std::max(1, static_cast<int>(std::ceil(angle_rad / max_angle - 1e-12)));
}

double arc_angle_rad(const Block& b) {
  const Eigen::Vector3d n = b.normal.normalized();
  Eigen::Vector3d u = b.start_mm - b.center_mm;
  Eigen::Vector3d w = b.end_mm - b.center_mm;
  u -= u.dot(n) * n;
  w -= w.dot(n) * n;
  double angle = std::atan2(u.cross(w).dot(n), u.dot(w));  // (-pi, pi]
  if (angle <= 1e-12) angle += kTwoPi;                       // (0, 2 pi]: start == end is a full turn
  return angle + kTwoPi * std::max(0, b.turns - 1);
}

Eigen::Vector3d arc_point(const Block& b, double s) {
  const Eigen::Vector3d n = b.normal.normalized();
  const Eigen::Vector3d u = b.start_mm - b.center_mm;  // in the start plane
  const double rise = (b.end_mm - b.start_mm).dot(n);
  const double r_start = u.norm();
  const Eigen::Vector3d w_end = (b.end_mm - b.center_mm) - ((b.end_mm - b.center_mm).dot(n)) * n;
  const double r_end = w_end.norm();
  const double angle = arc_angle_rad(b) * s;
  // Radius blends linearly when the end radius differs within the reader's tolerance,
  // so the arc ends exactly on the programmed point.
  const double radius = r_start + (r_end - r_start) * s;
  const Eigen::Vector3d dir = Eigen::AngleAxisd(angle, n) * (r_start > 0 ? Eigen::Vector3d(u / r_start) : u);
  return b.center_mm + radius * dir + s * rise * n;
}

std::vector<PoseSample> densify(const Program& program, const DensifySettings& settings) {
  std::vector<PoseSample> samples;
  if (program.blocks.empty()) return samples;
  samples.reserve(program.blocks.size() + 1);
  samples.push_back({{program.blocks.front().start_mm, Eigen::Vector3d::UnitZ()}, -1});
  for (std::size_t i = 0; i < program.blocks.size(); ++i) {
    const Block& b = program.blocks[i];
    const int id = static_cast<int>(i);
    if (b.kind == MotionKind::Arc) {
      const double radius = (b.start_mm - b.center_mm - (b.start_mm - b.center_mm).dot(b.normal) * b.normal).norm();
      const double angle = arc_angle_rad(b);
      int q = arc_chord_count(radius, angle, settings.chord_tolerance_mm);
      if (settings.step_mm > 0.0) {
        const double rise = std::abs((b.end_mm - b.start_mm).dot(b.normal));
        q = std::max(q, static_cast<int>(std::ceil(std::hypot(radius * angle, rise) / settings.step_mm)));
      }
      for (int k = 1; k < q; ++k) samples.push_back({{arc_point(b, static_cast<double>(k) / q), Eigen::Vector3d::UnitZ()}, id});
      samples.push_back({{b.end_mm, Eigen::Vector3d::UnitZ()}, id});
    } else {
      int q = 1;
      if (settings.step_mm > 0.0 && b.kind == MotionKind::Linear)
        q = std::max(1, static_cast<int>(std::ceil((b.end_mm - b.start_mm).norm() / settings.step_mm)));
      for (int k = 1; k < q; ++k)
        samples.push_back({{b.start_mm + (b.end_mm - b.start_mm) * (static_cast<double>(k) / q), Eigen::Vector3d::UnitZ()}, id});
      samples.push_back({{b.end_mm, Eigen::Vector3d::UnitZ()}, id});
    }
  }
  return samples;
}

}  // namespace vcut::kinematics
