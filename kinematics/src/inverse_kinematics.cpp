#include "vcut/kinematics/inverse_kinematics.h"

#include <fmt/format.h>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "chain.h"

namespace vcut::kinematics {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kLimitSlack = 1e-9;      // mm or rad: a value this far past a limit is still on it
constexpr double kFreeAngleSine = 1e-12;  // a vector this close to a rotation axis has no angle about it
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kMaxWindings = 4.0;  // windings listed per axis when its limits span more turns

std::string num(double v) { return fmt::format("{:.6g}", v); }

// The angle (rad) that turns v into w about the unit axis k, both projected onto the plane
// normal to k; NaN when either lies along k.
double angle_about(const Eigen::Vector3d& k, const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
  const Eigen::Vector3d a = v - v.dot(k) * k, b = w - w.dot(k) * k;
  if (a.norm() < kFreeAngleSine || b.norm() < kFreeAngleSine) return std::numeric_limits<double>::quiet_NaN();
  return std::atan2(k.dot(a.cross(b)), a.dot(b));
}

double wrap(double a) {  // (-pi, pi]
  a = std::remainder(a, kTwoPi);
  return a <= -M_PI ? a + kTwoPi : a;
}

std::string value_in_file_units(const AxisSpec& a, double v) {
  return a.kind == AxisKind::Rotary ? num(v * kRadToDeg) + " deg" : num(v) + " mm";
}

std::string limit_text(const AxisSpec& a) {
  const double f = a.kind == AxisKind::Rotary ? kRadToDeg : 1.0;
  return std::string("axis ") + a.letter + " limits [" + num(a.limits->first * f) + ", " + num(a.limits->second * f) +
         "]";
}

// The linear axis values that put the tip at `tip_mm` once the rotary values in q are fixed.
// The tip is affine in them: tip = b + J s, with column i = +-R_W^T R_prefix d_i (+ on the
// tool side, - on the workpiece side, R_prefix the rotations between the frame and the axis).
}  // namespace

std::string limit_violation(const Machine& m, const AxisValues& q) {
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisSpec& a = m.axis(i);
    if (a.limits && (q[i] < a.limits->first - kLimitSlack || q[i] > a.limits->second + kLimitSlack))
      return limit_text(a) + ": needs " + value_in_file_units(a, q[i]);
  }
  return "";
}

// Linear axes closer to dependent than this (|det| over the product of the directions'
// lengths: the volume they span, 1 for orthogonal axes) cannot place the tip.
constexpr double kDependentAxes = 1e-9;

bool solve_linear_axes(const Machine& m, AxisValues& q, const Eigen::Vector3d& tip_mm, double tool_length_mm) {
  using detail::Rigid;
  std::array<int, 3> index{};
  Eigen::Matrix3d J;
  int n = 0;
  Rigid w, t;
  std::array<Eigen::Vector3d, 3> raw;
  std::array<int, 3> chain_side{};
  for (int i : m.workpiece_chain()) {
    const AxisSpec& a = m.axis(i);
    if (a.kind == AxisKind::Linear) {
      q[i] = 0.0;
      raw[static_cast<size_t>(n)] = w.R * a.direction;
      chain_side[static_cast<size_t>(n)] = -1;
      index[static_cast<size_t>(n++)] = i;
    }
    detail::append_node(w, a, q[i], Geometry::Ideal);
  }
  for (int i : m.tool_chain()) {
    const AxisSpec& a = m.axis(i);
    if (a.kind == AxisKind::Linear) {
      q[i] = 0.0;
      raw[static_cast<size_t>(n)] = t.R * a.direction;
      chain_side[static_cast<size_t>(n)] = 1;
      index[static_cast<size_t>(n++)] = i;
    }
    detail::append_node(t, a, q[i], Geometry::Ideal);
  }
  w.t = w.apply(m.spec().workpiece_origin_mm);
  const Eigen::Matrix3d Rwt = w.R.transpose();
  for (int c = 0; c < 3; ++c) J.col(c) = chain_side[static_cast<size_t>(c)] * (Rwt * raw[static_cast<size_t>(c)]);
  const Eigen::Vector3d tip_frame = t.apply(m.spec().gauge_point_mm - tool_length_mm * m.spec().spindle_axis);
  const Eigen::Vector3d b = Rwt * (tip_frame - w.t);
  // J's columns are the linear axes' directions in the workpiece frame: a closed-form 3x3
  // inverse (cofactors) is exact enough and a fifth of a pivoting LU's work, which the
  // interpolator pays every period of a TCP move. Singular: the axes do not span space.
  const double det = J.determinant();
  if (!(std::abs(det) > kDependentAxes * J.col(0).norm() * J.col(1).norm() * J.col(2).norm())) return false;
  const Eigen::Vector3d s = J.inverse() * (tip_mm - b);
  for (int c = 0; c < 3; ++c) q[index[static_cast<size_t>(c)]] = s[c];
  return true;
}

namespace {

// The values of a rotary axis equal to `angle` modulo 2 pi that the axis can take: every
// winding within its limits, or for a continuous axis the one nearest the previous value.
void windings(const AxisSpec& a, double angle, const double* previous, std::vector<double>& out) {
  out.clear();
  if (!a.limits) {
    out.push_back(previous ? angle + kTwoPi * std::round((*previous - angle) / kTwoPi) : wrap(angle));
    return;
  }
  const double lo = a.limits->first - kLimitSlack, hi = a.limits->second + kLimitSlack;
  const double first = std::ceil((lo - angle) / kTwoPi), last = std::floor((hi - angle) / kTwoPi);
  if (last - first + 1.0 <= kMaxWindings) {
    for (double n = first; n <= last; n += 1.0) out.push_back(angle + n * kTwoPi);
    return;
  }
  // Limits many turns wide: the windings nearest the previous value (or zero), not all.
  const double centre = std::clamp(std::round(((previous ? *previous : 0.0) - angle) / kTwoPi), first, last);
  const double from = std::clamp(centre - kMaxWindings / 2, first, last - kMaxWindings + 1.0);
  for (double n = from; n < from + kMaxWindings; n += 1.0) out.push_back(angle + n * kTwoPi);
}

}  // namespace

IkResult inverse(const Machine& m, const ToolPose& pose, double tool_length_mm, const AxisValues* previous,
                 const IkSettings& settings) {
  IkResult result;
  const Eigen::Vector3d u_w = pose.axis.normalized();
  const Eigen::Vector3d u0 = m.spec().spindle_axis;
  const int nr = m.rotary_count();
  const double singular_angle =
      settings.singularity_angle_rad >= 0.0 ? settings.singularity_angle_rad : m.spec().singularity_angle_rad;
  auto unreachable = [&](const std::string& why) {
    result.status = IkStatus::Unreachable;
    result.reason = why;
    return result;
  };
  auto prev_angle = [&](int k) -> const double* { return previous ? &(*previous)[m.rotary_axis(k)] : nullptr; };

  // Orientation: u_w = R(k1, b1) R(k2, b2) u0 with b_k = s_k q_k (Machine::rotary_*).
  std::vector<std::array<double, 2>> branches;  // b1, b2 per branch
  bool singular = false;
  if (nr == 0) {
    if (std::atan2(u0.cross(u_w).norm(), u0.dot(u_w)) > settings.orientation_tolerance_rad)
      return unreachable("orientation out of reach: without rotary axes the tool axis stays (" + num(u0.x()) + ", " +
                         num(u0.y()) + ", " + num(u0.z()) + ")");
    branches.push_back({0.0, 0.0});
  } else if (nr == 1) {
    const Eigen::Vector3d k1 = m.axis(m.rotary_axis(0)).direction;
    const double miss =
        std::abs(std::asin(std::clamp(u_w.dot(k1), -1.0, 1.0)) - std::asin(std::clamp(u0.dot(k1), -1.0, 1.0)));
    if (miss > settings.orientation_tolerance_rad)
      return unreachable(std::string("orientation out of reach: axis ") + m.axis(m.rotary_axis(0)).letter +
                         " keeps the tool at " + num(std::acos(std::clamp(u0.dot(k1), -1.0, 1.0)) * kRadToDeg) +
                         " deg from its axis, the pose asks " +
                         num(std::acos(std::clamp(u_w.dot(k1), -1.0, 1.0)) * kRadToDeg));
    double b1 = angle_about(k1, u0, u_w);
    if (std::isnan(b1)) b1 = previous ? m.rotary_sign(0) * *prev_angle(0) : 0.0;
    branches.push_back({b1, 0.0});
  } else {
    const Eigen::Vector3d k1 = m.axis(m.rotary_axis(0)).direction, k2 = m.axis(m.rotary_axis(1)).direction;
    const double s1 = m.rotary_sign(0), s2 = m.rotary_sign(1);
    const double alpha = k1.dot(k2), p1 = u_w.dot(k1), p2 = u0.dot(k2);
    const Eigen::Vector3d n = k1.cross(k2);
    const double n2 = n.squaredNorm();
    if (n2 < 1e-12) {
      // Parallel rotary axes add up: only their sum is determined; the second keeps its value.
      if (std::abs(std::asin(std::clamp(p1, -1.0, 1.0)) - std::asin(std::clamp(u0.dot(k1), -1.0, 1.0))) >
          settings.orientation_tolerance_rad)
        return unreachable("orientation out of reach of the parallel rotary axes");
      const double b2 = previous ? s2 * *prev_angle(1) : 0.0;
      double total = angle_about(k1, u0, u_w);
      if (std::isnan(total)) total = (previous ? s1 * *prev_angle(0) : 0.0) + b2;
      branches.push_back({total - alpha * b2, b2});
    } else {
      // Paden-Kahan subproblem 2: c = R(k2, b2) u0 = R(k1, -b1) u_w lies on both cones,
      // c = x k1 + y k2 + z (k1 x k2).
      const double x = (p1 - alpha * p2) / (1.0 - alpha * alpha);
      const double y = (p2 - alpha * p1) / (1.0 - alpha * alpha);
      double z2 = (1.0 - x * x - y * y - 2.0 * x * y * alpha) / n2;
      if (z2 < 0.0) {
        if (std::sqrt(-z2 * n2) > settings.orientation_tolerance_rad)
          return unreachable(std::string("orientation out of reach: no angles of axes ") +
                             m.axis(m.rotary_axis(0)).letter + " and " + m.axis(m.rotary_axis(1)).letter +
                             " turn the tool to (" + num(u_w.x()) + ", " + num(u_w.y()) + ", " + num(u_w.z()) + ")");
        z2 = 0.0;
      }
      if (std::abs(p1) >= std::cos(singular_angle)) {
        // Singular: the tool axis lies (nearly) along k1, whose angle is free. Keep its
        // previous value and turn k2 as close as it gets to the requested axis.
        singular = true;
        const double b1 = previous ? s1 * *prev_angle(0) : 0.0;
        const Eigen::Vector3d c = detail::rotation(k1, -b1) * u_w;
        double b2 = angle_about(k2, u0, c);
        if (std::isnan(b2)) b2 = previous ? s2 * *prev_angle(1) : 0.0;
        branches.push_back({b1, b2});
      } else {
        const double z = std::sqrt(z2);
        for (double sign : {1.0, -1.0}) {
          const Eigen::Vector3d c = x * k1 + y * k2 + sign * z * n;
          double b2 = angle_about(k2, u0, c);
          if (std::isnan(b2)) b2 = previous ? s2 * *prev_angle(1) : 0.0;  // u0 along k2: k2 changes nothing
          const double b1 = angle_about(k1, c, u_w);
          branches.push_back({b1, b2});
          if (z == 0.0) break;
        }
      }
    }
  }

  // Every branch x winding, then the linear axes.
  std::vector<double> w0, w1;
  w0.reserve(4);
  w1.reserve(4);
  result.solutions.reserve(8);
  for (size_t br = 0; br < branches.size(); ++br) {
    AxisValues base = m.zero();
    std::string violation;
    for (int k = 0; k < nr; ++k) {
      const AxisSpec& a = m.axis(m.rotary_axis(k));
      const double angle = m.rotary_sign(k) * branches[br][static_cast<size_t>(k)];
      std::vector<double>& w = k == 0 ? w0 : w1;
      if (singular && k == 0 && previous) {
        w.assign(1, *prev_angle(0));
        if (a.limits && (w[0] < a.limits->first - kLimitSlack || w[0] > a.limits->second + kLimitSlack))
          violation = limit_text(a) + ": needs " + value_in_file_units(a, w[0]);
      } else {
        windings(a, angle, prev_angle(k), w);
        if (w.empty()) {
          violation = limit_text(a) + ": needs " + value_in_file_units(a, wrap(angle)) + " (modulo 360 deg)";
          w.push_back(wrap(angle));
        }
      }
    }
    if (nr < 1) w0.assign(1, 0.0);
    if (nr < 2) w1.assign(1, 0.0);
    // The linear axes depend on the rotations only, the same for every winding: solve once.
    if (nr > 0) base[m.rotary_axis(0)] = w0.front();
    if (nr > 1) base[m.rotary_axis(1)] = w1.front();
    if (!solve_linear_axes(m, base, pose.tip_mm, tool_length_mm) && violation.empty())
      violation = "linear axes cannot reach the tip at these angles (singular linear solve)";
    for (int i = 0; i < m.axis_count() && violation.empty(); ++i) {
      const AxisSpec& a = m.axis(i);
      if (a.kind == AxisKind::Linear && a.limits &&
          (base[i] < a.limits->first - kLimitSlack || base[i] > a.limits->second + kLimitSlack))
        violation = limit_text(a) + ": needs " + value_in_file_units(a, base[i]);
    }
    for (double q0 : w0) {
      for (double q1 : w1) {
        IkSolution& s = result.solutions.emplace_back();
        s.branch = static_cast<int>(br);
        s.q = base;
        if (nr > 0) s.q[m.rotary_axis(0)] = q0;
        if (nr > 1) s.q[m.rotary_axis(1)] = q1;
        s.violation = violation;
        s.within_limits = violation.empty();
      }
    }
  }

  // Choice: within limits; least rotary motion from the previous pose (then the preferred
  // sign); without a previous pose the preferred sign first, then angles nearest zero.
  const int pref = settings.preferred_axis ? m.axis_index(settings.preferred_axis) : -1;
  double best_cost = std::numeric_limits<double>::infinity();
  int best_pref = 2;
  for (size_t i = 0; i < result.solutions.size(); ++i) {
    const IkSolution& s = result.solutions[i];
    if (!s.within_limits) continue;
    double cost = 0.0;
    for (int k = 0; k < nr; ++k) {
      const int a = m.rotary_axis(k);
      cost += std::abs(s.q[a] - (previous ? (*previous)[a] : 0.0));
    }
    const int pref_miss =
        (pref >= 0 && settings.preferred_sign != 0 && s.q[pref] * settings.preferred_sign < -kLimitSlack) ? 1 : 0;
    bool better;
    if (previous)
      better = cost < best_cost - 1e-9 || (cost < best_cost + 1e-9 && pref_miss < best_pref);
    else
      better = pref_miss < best_pref || (pref_miss == best_pref && cost < best_cost - 1e-9);
    if (better) {
      best_cost = cost;
      best_pref = pref_miss;
      result.chosen = static_cast<int>(i);
    }
  }
  if (result.chosen < 0) {
    result.status = IkStatus::Unreachable;
    result.reason = result.solutions.empty() ? "no solution" : result.solutions.front().violation;
    return result;
  }
  if (singular) {
    result.status = IkStatus::Singular;
    const AxisSpec& free_axis = m.axis(m.rotary_axis(0));
    const ToolPose reached = forward(m, result.q(), tool_length_mm);
    result.orientation_error_rad = std::atan2(reached.axis.cross(u_w).norm(), reached.axis.dot(u_w));
    result.reason = std::string("tool axis within ") + num(singular_angle * kRadToDeg) + " deg of axis " +
                    free_axis.letter + ": " + free_axis.letter + " kept at " +
                    value_in_file_units(free_axis, result.q()[m.rotary_axis(0)]);
  }
  return result;
}

}  // namespace vcut::kinematics
