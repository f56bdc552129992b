#include "vcut/removal/move.h"

#include <Eigen/Geometry>

#include "vcut/kinematics/densify.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vcut::removal {

bool ListSource::next(std::vector<Move>& out, std::size_t wanted) {
  const std::size_t n = std::min(wanted, list_.moves.size() - at_);
  out.insert(out.end(), list_.moves.begin() + static_cast<std::ptrdiff_t>(at_),
             list_.moves.begin() + static_cast<std::ptrdiff_t>(at_ + n));
  at_ += n;
  return n > 0;
}
namespace {

constexpr int kMaxPieces = 1 << 16;

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

double rotation_reach_mm(const Cutter& cutter) {
  const CutterCore core = core_of(cutter);  // a V-bit's: its bounding cylinder, so sqrt(R^2 + H^2)
  return std::hypot(core.core_radius_mm, core.z_high_mm);
}

double rotation_error_mm(const Cutter& cutter, double angle_rad, int pieces) {
  return rotation_reach_mm(cutter) * angle_rad / (2.0 * std::max(1, pieces));
}

int five_axis_pieces(const Cutter& cutter, const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1,
                     double bound_mm) {
  // No height limit: the core's reach.
  return five_axis_pieces_within(cutter, 0.0, std::numeric_limits<double>::infinity(), axis0, axis1, bound_mm);
}

double highest_point_in_box_mm(double radius_mm, const Eigen::Vector3d& tip0, const Eigen::Vector3d& tip1,
                               const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1,
                               const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3d a0 = axis0.normalized(), a1 = axis1.normalized();
  const double angle = angle_between(a0, a1);
  double highest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k)
    for (const double sign : {-1.0, 1.0}) {
      // Face n = sign e_k, offset o: inside means n.x <= o.
      const double offset = sign > 0.0 ? box.max()[k] : -box.min()[k];
      const double along_min = std::min(sign * a0[k], sign * a1[k]) - angle * angle / 8.0;
      if (!(along_min > 0.0)) continue;
      const double tip_min = std::min(sign * tip0[k], sign * tip1[k]);
      const double spread = radius_mm * std::sqrt(std::max(0.0, 1.0 - along_min * along_min));
      highest = std::min(highest, (offset - tip_min + spread) / along_min);
    }
  return std::max(0.0, highest);
}

int five_axis_pieces_within(const Cutter& cutter, double radius_mm, double height_mm, const Eigen::Vector3d& axis0,
                            const Eigen::Vector3d& axis1, double bound_mm) {
  const double angle = angle_between(axis0.normalized(), axis1.normalized());
  if (angle == 0.0) return 1;
  const double reach = std::min(rotation_reach_mm(cutter), std::hypot(radius_mm, height_mm));
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
    piece.end_mm =
        k + 1 == n ? move.end_mm
                   : Eigen::Vector3d(move.start_mm + (static_cast<double>(k + 1) / n) * (move.end_mm - move.start_mm));
    piece.axis = kinematics::great_circle(a, b, (k + 0.5) / n);
    out.push_back(piece);
  }
}

std::vector<ToolBody> add_tool_bodies(MoveList& list) {
  const std::size_t n = list.cutters.size();
  std::vector<ToolBody> bodies(n);
  auto cylinder = [&](double diameter_mm, double length_mm) {
    Cutter c;
    c.type = CutterType::Flat;
    c.diameter_mm = diameter_mm;
    c.shank_diameter_mm = diameter_mm;
    c.flute_length_mm = length_mm;
    c.length_mm = length_mm;
    list.cutters.push_back(c);
    return static_cast<int>(list.cutters.size() - 1);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Cutter c = list.cutters[i];  // a copy: push_back may move the vector
    const double shank_mm = c.length_mm - c.flute_length_mm;
    const double shank_diameter_mm = c.shank_diameter_mm > 0.0 ? c.shank_diameter_mm : c.diameter_mm;
    if (shank_mm > 1e-9 && shank_diameter_mm > 0.0) {
      bodies[i].shank = cylinder(shank_diameter_mm, shank_mm);
      bodies[i].shank_height_mm = c.flute_length_mm;
    }
    if (c.holder_diameter_mm > 0.0 && c.holder_length_mm > 0.0) {
      bodies[i].holder = cylinder(c.holder_diameter_mm, c.holder_length_mm);
      bodies[i].holder_height_mm = std::max(c.length_mm, c.flute_length_mm);
    }
  }
  return bodies;
}

void append_body_probes(std::vector<Move>& out, const Move& move, const ToolBody& body) {
  auto probe = [&](int cutter, double height_mm, ProbeKind kind) {
    if (cutter < 0) return;
    Move p = move;
    p.start_mm = move.start_mm + height_mm * move.axis;
    p.end_mm = move.end_mm + height_mm * move.axis;
    p.cutter = cutter;
    p.rapid = true;
    p.probe = kind;
    out.push_back(p);
  };
  probe(body.shank, body.shank_height_mm, ProbeKind::Shank);
  probe(body.holder, body.holder_height_mm, ProbeKind::Holder);
}

}  // namespace vcut::removal
