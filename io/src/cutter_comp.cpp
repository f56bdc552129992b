// Cutter radius compensation as LinuxCNC's interpreter computes it, for the G-code reader
// (G41/G42) and the APT reader (CUTCOM/): see cutter_comp.h.
#include "cutter_comp.h"

#include <cmath>
#include <string>

#include "reader_util.h"

namespace vcut::io::detail {

using kinematics::Block;
using kinematics::MotionKind;
using Comp = GcodeState::CutterComp;

namespace {

constexpr double kCornerRad = 0.05;  // rs274ngc's TOLERANCE_CONCAVE_CORNER
constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kMaxMagnitude = 1e6;  // mm, the readers' bound on any position

double angle(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  return std::atan2(to.y() - from.y(), to.x() - from.x());
}
Eigen::Vector2d direction(double a) { return {std::cos(a), std::sin(a)}; }

// The signed sweep (rad) of an arc from s to e about k with `turn` turns (> 0 counterclockwise):
// one turn sweeps (0, 2 pi], so equal angles make a full circle.
double sweep(const Eigen::Vector2d& s, const Eigen::Vector2d& k, int turn, const Eigen::Vector2d& e) {
  double a = angle(k, s), b = angle(k, e);
  if (turn > 0) {
    if (b <= a) b += kTwoPi;
    return b - a + (turn - 1) * kTwoPi;
  }
  if (turn < 0) {
    if (a <= b) a += kTwoPi;
    return b - a + (turn + 1) * kTwoPi;
  }
  return 0.0;
}

}  // namespace

// The offset path can leave the bound a programmed point respects (an offset near 1e6 mm and
// the radius beyond it): an error on the line being read, as for a programmed point.
void Compensator::check_range(const Block& block) const {
  for (const Eigen::Vector3d& p : {block.start_mm, block.end_mm})
    if (!(p.cwiseAbs().maxCoeff() <= kMaxMagnitude))
      host_.comp_fail(1, "cutter compensation puts the tool at " + num(p.x()) + ", " + num(p.y()) + ", " + num(p.z()) +
                             " mm, out of range (expected within +-1e6 mm)");
}

// Emits the held moves, each from where the one before ended.
void Compensator::flush() {
  Comp& comp = comp_;
  for (Comp::Held& h : comp.held) {
    Block& block = h.block;
    if (!host_.comp_blocks().empty()) block.start_mm = host_.comp_blocks().back().end_mm;
    check_range(block);
    if (block.kind != MotionKind::Arc && block.start_mm == block.end_mm &&
        block.start_rotary.angle_rad == block.end_rotary.angle_rad)
      continue;
    host_.comp_blocks().push_back(block);
  }
  comp.held.clear();
  comp.endpoint_valid = false;
}

// Moves the end of every held move to x (along its circle for an arc), checking that none has
// to run backwards or further round than programmed (a gouge), then emits them.
void Compensator::move_end_and_flush(const Eigen::Vector2d& x, int column) {
  Comp& comp = comp_;
  if (comp.held.empty()) return;
  int a, b, c;
  host_.comp_plane(a, b, c);
  const double sweep_tolerance = (host_.comp_unit() != 1.0) ? 0.001 : 0.0254;  // rs274ngc's, in its program units
  for (Comp::Held& h : comp.held) {
    Block& block = h.block;
    const Eigen::Vector2d end(block.end_mm[a], block.end_mm[b]);
    if (block.kind == MotionKind::Arc) {
      const Eigen::Vector2d k(block.center_mm[a], block.center_mm[b]);
      const int turn = block.normal[c] > 0.0 ? block.turns : -block.turns;
      if (std::abs((end - k).norm() - (x - k).norm()) > 0.01 * host_.comp_unit()) {
        host_.comp_fail(column, "cutter compensation moved an arc's end off its circle (radius " +
                                    num((end - k).norm()) + " mm, the corner at " + num((x - k).norm()) +
                                    " mm from its centre)");
      }
      const double l2 = sweep(comp.endpoint, k, turn, x);
      if (h.sweep_rad != 0.0 && comp.endpoint_valid && std::abs(l2) > std::abs(h.sweep_rad) + sweep_tolerance) {
        host_.comp_fail(column,
                        "cutter compensation: the arc before this move cannot reach the concave corner without "
                        "gouging (tool radius " +
                            num(comp.radius_mm) + " mm)");
      }
    } else if (comp.endpoint_valid && h.direction.dot(x - comp.endpoint) < 0.0) {
      host_.comp_fail(
          column, std::string("cutter compensation: the ") + (block.kind == MotionKind::Rapid ? "rapid" : "straight") +
                      " move before this one would run backwards to reach the concave corner: a gouge (tool radius " +
                      num(comp.radius_mm) + " mm too large for the corner)");
    }
    block.end_mm[a] = x.x();
    block.end_mm[b] = x.y();
  }
  flush();
  comp.endpoint = x;
  comp.endpoint_valid = true;
}

// Emits the arc (G1, G2, G3) or the traverse (G0) about the programmed corner that joins the
// offset paths at a convex corner, with no motion along the plane's normal.
void Compensator::corner(const Block& main, const Eigen::Vector2d& corner, const Eigen::Vector2d& end, int turn) {
  int a, b, c;
  host_.comp_plane(a, b, c);
  Block block;
  block.kind = main.kind == MotionKind::Rapid ? MotionKind::Rapid : MotionKind::Arc;
  block.start_mm = host_.tool_position();
  block.end_mm = host_.tool_position();
  block.end_mm[a] = end.x();
  block.end_mm[b] = end.y();
  block.feed_mm_per_min = main.feed_mm_per_min;
  if (block.kind == MotionKind::Arc) {
    block.center_mm = host_.tool_position();
    block.center_mm[a] = corner.x();
    block.center_mm[b] = corner.y();
    block.normal = Eigen::Vector3d::Zero();
    block.normal[c] = turn > 0 ? 1.0 : -1.0;
    block.turns = 1;
  }
  check_range(block);
  host_.comp_append(block, {true, true, true}, false, Eigen::Vector2d::Zero(), 0.0);
}

// A convex corner: the arc (or traverse) about the programmed corner to `start`, where the next
// move's offset path begins.
void Compensator::convex_corner(const Block& main, const Eigen::Vector2d& corner_point, const Eigen::Vector2d& start,
                                int turn) {
  corner(main, corner_point, start, turn);
  comp_.endpoint = start;
  comp_.endpoint_valid = true;
}

// No corner to make (the paths meet tangentially): the held moves go as they are.
void Compensator::straight_on(const Eigen::Vector2d& at) {
  flush();
  comp_.endpoint = at;
  comp_.endpoint_valid = true;
}

Compensator::Move Compensator::move(const Block& block) const {
  Move m;
  host_.comp_plane(m.a, m.b, m.c);
  m.r = comp_.radius_mm;
  m.left = comp_.side == Comp::Side::Left;
  m.programmed_end = block.end_mm;
  m.p = Eigen::Vector2d(block.end_mm[m.a], block.end_mm[m.b]);
  m.cur = Eigen::Vector2d(host_.tool_position()[m.a], host_.tool_position()[m.b]);
  return m;
}

void Compensator::hold_move(Block& block, const std::array<bool, 3>& programmed, const Move& m,
                            const Eigen::Vector2d& end, const Eigen::Vector2d* center, const Eigen::Vector2d& direction,
                            double sweep_rad) {
  block.end_mm[m.a] = end.x();
  block.end_mm[m.b] = end.y();
  if (center != nullptr) {
    block.center_mm[m.a] = center->x();
    block.center_mm[m.b] = center->y();
  }
  host_.comp_append(block, programmed, true, direction, sweep_rad);
  comp_.program_mm = m.programmed_end;
}

void Compensator::straight(Block& block, const std::array<bool, 3>& programmed, int column) {
  Comp& comp = comp_;
  const Move m = move(block);
  const double r = m.r;
  const bool left = m.left;
  const int a = m.a, b = m.b, c = m.c;
  const Eigen::Vector2d p = m.p, cur = m.cur;
  auto hold = [&](const Eigen::Vector2d& end, const Eigen::Vector2d& dir) {
    hold_move(block, programmed, m, end, nullptr, dir, 0.0);
  };
  if (comp.first_move) {
    const double length = (p - cur).norm();
    if (length <= r) {
      host_.comp_fail(column, "cutter compensation entry move of " + num(length) +
                                  " mm in the plane is not longer than the tool radius " + num(r) +
                                  " mm (expected a longer move after G41/G42)");
    }
    const double normal = angle(cur, p) + (left ? M_PI_2 : -M_PI_2);
    comp.endpoint = cur;
    comp.endpoint_valid = true;
    comp.first_move = false;
    hold(p + r * direction(normal), direction(normal));
    return;
  }
  const Eigen::Vector2d o(comp.program_mm[a], comp.program_mm[b]);
  if (p == o) {  // no motion in the plane: the tool stays at C
    hold(cur, Eigen::Vector2d::Zero());
    return;
  }
  double theta = angle(o, cur), alpha = angle(o, p), beta, gamma;
  if (left) {
    if (theta < alpha) theta += kTwoPi;
    beta = theta - alpha - M_PI_2;
    gamma = M_PI_2;
  } else {
    if (alpha < theta) alpha += kTwoPi;
    beta = alpha - theta - M_PI_2;
    gamma = -M_PI_2;
  }
  const Eigen::Vector2d end = p + r * direction(alpha + gamma);
  const Eigen::Vector2d start = o + r * direction(alpha + gamma);
  const Comp::Held* front = comp.held.empty() ? nullptr : &comp.held.front();
  const bool front_arc = front != nullptr && front->block.kind == MotionKind::Arc;
  const int front_turn = front_arc ? (front->block.normal[c] > 0.0 ? 1 : -1) : 0;
  const bool front_outside = front_arc && ((!left && front_turn > 0) || (left && front_turn < 0));
  const bool concave = beta < -kCornerRad || beta > M_PI + kCornerRad || (beta > M_PI - kCornerRad && front_outside);
  if (concave && !front_arc) {
    const double half = (beta + M_PI) / 2.0;
    if (half == 0.0)
      host_.comp_fail(
          column, "cutter compensation: a zero-degree inside corner (expected the path not to fold back on itself)");
    move_end_and_flush(cur + r / std::tan(half) * direction(theta + gamma), column);
  } else if (concave) {
    // Arc then straight: where the straight's offset line meets the arc's offset circle.
    const Eigen::Vector2d arc_end(front->block.end_mm[a], front->block.end_mm[b]);
    const Eigen::Vector2d arc_center(front->block.center_mm[a], front->block.center_mm[b]);
    const double rho = (arc_center - arc_end).norm();
    const double tau = angle(o, p) + (front_turn > 0 ? M_PI_2 : -M_PI_2);
    const double phi = angle(o, arc_center);
    const bool inside = (left && front_turn > 0) || (!left && front_turn < 0);
    const double d = (inside ? rho + r : rho - r) * std::cos(tau - phi);
    const double l = (inside ? d - r : d + r) / rho;
    if (!(std::abs(l) <= 1.0)) {
      host_.comp_fail(column,
                      "cutter compensation: the corner from the arc to this straight move is too tight for the tool "
                      "(radius " +
                          num(r) + " mm) without gouging");
    }
    const double psi = tau + M_PI + (inside == (front_turn > 0) ? -1.0 : 1.0) * std::acos(l);
    move_end_and_flush(arc_center + rho * direction(psi), column);
  } else if (beta > kCornerRad) {
    move_end_and_flush(cur, column);
    convex_corner(block, o, start, left ? -1 : 1);
  } else {
    straight_on(cur);
  }
  hold(end, p - o);
}

void Compensator::arc(Block& block, const std::array<bool, 3>& programmed, int turn, int column) {
  Comp& comp = comp_;
  const Move m = move(block);
  const double r = m.r;
  const bool left = m.left;
  const int a = m.a, b = m.b, c = m.c;
  const Eigen::Vector2d p = m.p, cur = m.cur;
  const Eigen::Vector2d k(block.center_mm[a], block.center_mm[b]);
  const bool inside = (left && turn > 0) || (!left && turn < 0);  // the tool on the arc's concave side
  const std::string code = turn < 0 ? "G2" : "G3";
  auto hold = [&](const Eigen::Vector2d& end, const Eigen::Vector2d& center, double sweep_rad) {
    hold_move(block, programmed, m, end, &center, Eigen::Vector2d::Zero(), sweep_rad);
  };
  auto too_small = [&](double arc_radius) {
    host_.comp_fail(column, code + " arc of radius " + num(arc_radius) + " mm with the tool (radius " + num(r) +
                                " mm) on its inside (expected an arc radius larger than the tool's)");
  };
  if (comp.first_move) {
    if ((p - cur).norm() <= r) {
      host_.comp_fail(column, "cutter compensation entry arc ends " + num((p - cur).norm()) +
                                  " mm from its start, not more than the tool radius " + num(r) + " mm");
    }
    if ((k - cur).norm() <= r && inside) too_small((k - cur).norm());
    const Eigen::Vector2d end = p + r * direction(inside ? angle(p, k) : angle(k, p));
    // The entry arc's centre: on the line from its end toward the programmed centre, as far
    // from the start as from the end.
    const double h = (cur - end).norm() / 2.0, lambda = angle(end, k), cos_a = std::cos(angle(end, cur) - lambda);
    if (std::abs(cos_a) < 1e-6) too_small((k - cur).norm());
    const Eigen::Vector2d center = end + (h / cos_a) * direction(lambda);
    comp.first_move = false;
    comp.endpoint_valid = false;
    hold(end, center, sweep(cur, center, turn, end));
    return;
  }
  const Eigen::Vector2d o(comp.program_mm[a], comp.program_mm[b]);
  const double arc_radius = (k - p).norm();
  const double theta = angle(o, cur) + (left ? -M_PI_2 : M_PI_2);  // the tool's heading at C
  double delta = angle(o, k);
  const double alpha = delta + (turn > 0 ? -M_PI_2 : M_PI_2);  // the arc's heading at O
  double beta = left ? theta - alpha : alpha - theta;
  if (beta > 1.5 * M_PI) {
    beta -= kTwoPi;
  } else if (beta < -M_PI_2) {
    beta += kTwoPi;
  }
  double gamma;
  if (inside) {
    gamma = angle(p, k);
    if (arc_radius <= r) too_small(arc_radius);
  } else {
    gamma = angle(k, p);
    delta += M_PI;
  }
  const Eigen::Vector2d end = p + r * direction(gamma);
  const double programmed_sweep = sweep(o, k, turn, p);
  const bool concave =
      beta < -kCornerRad || beta > M_PI + kCornerRad || (std::abs(beta - M_PI) < kCornerRad && !inside);
  const Comp::Held* front = comp.held.empty() ? nullptr : &comp.held.front();
  if (concave && (front == nullptr || front->block.kind != MotionKind::Arc)) {
    // Straight then arc: where the straight's offset line meets this arc's offset circle.
    const double y = arc_radius * std::sin(beta - M_PI_2);
    const double dist = inside ? arc_radius - r : arc_radius + r;
    const double l = (inside ? y + r : y - r) / dist;
    if (!(std::abs(l) <= 1.0)) {
      host_.comp_fail(column, "cutter compensation: this " + code +
                                  " arc cannot be reached in the concave corner by the tool (radius " + num(r) +
                                  " mm) without gouging");
    }
    const double psi = inside ? (turn > 0 ? theta + std::asin(l) : theta - std::asin(l))
                              : (turn > 0 ? theta + M_PI - std::asin(l) : theta + M_PI + std::asin(l));
    const Eigen::Vector2d corner = k + dist * direction(psi);
    // The move before was already sent (M0, M1 or M60 send the held move, ending where the
    // tool is): this arc would start off its offset circle (the fuzzer found such an arc, its
    // start 0.47 mm further from the centre than its end).
    if (comp.held.empty() && (corner - cur).norm() > 0.01 * host_.comp_unit()) {
      host_.comp_fail(column, "cutter compensation: this " + code +
                                  " arc turns into a concave corner after a stop (M0, M1 or M60) sent the move "
                                  "before it, which can no longer end in the corner (expected the stop elsewhere)");
    }
    move_end_and_flush(corner, column);
  } else if (concave) {
    // Arc then arc: where the two offset circles meet.
    const Eigen::Vector2d front_end(front->block.end_mm[a], front->block.end_mm[b]);
    const Eigen::Vector2d front_center(front->block.center_mm[a], front->block.center_mm[b]);
    const int front_turn = front->block.normal[c] > 0.0 ? 1 : -1;
    const double rho = (front_center - front_end).norm();
    const double rho_new = inside ? arc_radius - r : arc_radius + r;
    const double centers = (front_center - k).norm();
    if (rho == 0.0 || centers == 0.0) {
      host_.comp_fail(
          column,
          "cutter compensation: two arcs with the same centre meet in a concave corner (expected them to differ)");
    }
    const double cos_p = (rho * rho + centers * centers - rho_new * rho_new) / (2.0 * rho * centers);
    if (!(std::abs(cos_p) <= 1.0)) {
      host_.comp_fail(column, "cutter compensation: the corner between two arcs is too tight for the tool (radius " +
                                  num(r) + " mm) without gouging");
    }
    const double pa = std::acos(cos_p), kappa = angle(front_center, k);
    const bool front_inside = (left && front_turn > 0) || (!left && front_turn < 0);
    const double psi = front_inside ? (turn > 0 ? kappa + pa : kappa - pa) : (turn > 0 ? kappa - pa : kappa + pa);
    move_end_and_flush(front_center + rho * direction(psi), column);
  } else if (beta > kCornerRad) {
    flush();
    convex_corner(block, o, o + r * direction(delta), left ? -1 : 1);
  } else {
    straight_on(cur);
  }
  hold(end, k, programmed_sweep);
}

}  // namespace vcut::io::detail
