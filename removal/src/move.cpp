#include "vcut/removal/move.h"

#include <Eigen/Geometry>

#include "vcut/kinematics/densify.h"

#include <algorithm>
#include <cmath>

namespace vcut::removal {
namespace {

constexpr int kMaxPieces = 1 << 16;

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

double rotation_error_mm(const Cutter& cutter, double angle_rad, int pieces) {
  const double reach = std::hypot(cutter.radius_mm(), cutter.flute_length_mm);
  return reach * angle_rad / (2.0 * std::max(1, pieces));
}

int five_axis_pieces(const Cutter& cutter, const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1,
                     double bound_mm) {
  const double angle = angle_between(axis0.normalized(), axis1.normalized());
  if (angle == 0.0) return 1;
  const double reach = std::hypot(cutter.radius_mm(), cutter.flute_length_mm);
  const double n = std::ceil(reach * angle / (2.0 * bound_mm) - 1e-12);
  return static_cast<int>(std::clamp(n, 1.0, static_cast<double>(kMaxPieces)));
}

void append_five_axis_move(std::vector<Move>& out, const Move& move, const Eigen::Vector3d& axis0,
                           const Eigen::Vector3d& axis1, int pieces) {
  const Eigen::Vector3d a = axis0.normalized(), b = axis1.normalized();
  const int n = std::max(1, pieces);
  for (int k = 0; k < n; ++k) {
    Move piece = move;
    piece.start_mm = move.start_mm + (static_cast<double>(k) / n) * (move.end_mm - move.start_mm);
    piece.end_mm = k + 1 == n ? move.end_mm : Eigen::Vector3d(move.start_mm + (static_cast<double>(k + 1) / n) * (move.end_mm - move.start_mm));
    piece.axis = kinematics::great_circle(a, b, (k + 0.5) / n);
    out.push_back(piece);
  }
}

}  // namespace vcut::removal
