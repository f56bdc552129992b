#include "vcut/kinematics/compensation.h"

#include <Eigen/QR>

#include <cmath>

#include "vcut/kinematics/forward_kinematics.h"

namespace vcut::kinematics {
namespace {

constexpr int kMaxIterations = 30;
constexpr double kStep = 1e-6;  // mm or rad: central-difference step of the Jacobian

// Tip difference (mm) and axis difference (unit vectors, ~rad) of the actual pose at q.
Eigen::Matrix<double, 6, 1> residual(const Machine& m, const AxisValues& q, const ToolPose& nominal, double length) {
  const ToolPose p = forward(m, q, length, Geometry::Actual);
  Eigen::Matrix<double, 6, 1> r;
  r << p.tip_mm - nominal.tip_mm, p.axis - nominal.axis;
  return r;
}

}  // namespace

CompensationResult compensate(const Machine& m, const ToolPose& target, double tool_length_mm,
                              const AxisValues& start) {
  ToolPose nominal = target;
  nominal.axis.normalize();
  CompensationResult out;
  out.q = start;
  // With two rotary axes the whole pose (5 degrees of freedom) is corrected; otherwise only
  // the tip, with the linear axes.
  const bool full = m.rotary_count() == 2;
  std::vector<int> unknowns;
  for (int i = 0; i < m.axis_count(); ++i)
    if (full || m.axis(i).kind == AxisKind::Linear) unknowns.push_back(i);
  const int rows = full ? 6 : 3;
  const int n = static_cast<int>(unknowns.size());

  auto measure = [&](const AxisValues& q) {
    const ToolPose p = forward(m, q, tool_length_mm, Geometry::Actual);
    const PoseError e = pose_error(nominal, p);
    out.residual_tip_um = e.tip_um.norm();
    out.residual_axis_urad = e.axis_tilt_urad;
  };
  // Iterate to a hundredth of the bounds (Newton gets there in one more step, far above the
  // ~1e-10 um rounding floor) so that the result is not just barely inside them.
  auto within = [&](double fraction) {
    return out.residual_tip_um <= fraction * kCompensationTipToleranceMm * 1000.0 &&
           (!full || out.residual_axis_urad <= fraction * kCompensationAxisToleranceRad * 1e6);
  };
  auto done = [&]() { return within(1.0); };
  measure(out.q);
  for (; out.iterations < kMaxIterations && !within(0.01); ++out.iterations) {
    const Eigen::Matrix<double, 6, 1> r = residual(m, out.q, nominal, tool_length_mm);
    Eigen::MatrixXd J(rows, n);
    for (int c = 0; c < n; ++c) {
      AxisValues plus = out.q, minus = out.q;
      plus[unknowns[static_cast<size_t>(c)]] += kStep;
      minus[unknowns[static_cast<size_t>(c)]] -= kStep;
      const Eigen::Matrix<double, 6, 1> r_plus = residual(m, plus, nominal, tool_length_mm);
      const Eigen::Matrix<double, 6, 1> r_minus = residual(m, minus, nominal, tool_length_mm);
      const Eigen::Matrix<double, 6, 1> slope = (r_plus - r_minus) / (2.0 * kStep);
      J.col(c) = slope.head(rows);
    }
    const Eigen::VectorXd step = J.colPivHouseholderQr().solve(-r.head(rows));
    for (int c = 0; c < n; ++c) out.q[unknowns[static_cast<size_t>(c)]] += step[c];
    measure(out.q);
  }
  out.converged = done();
  if (!out.converged)
    out.note = "did not converge in " + std::to_string(kMaxIterations) + " iterations";
  else if (!full && out.residual_axis_urad > kCompensationAxisToleranceRad * 1e6)
    out.note = "tip compensated; the tool axis cannot be corrected with " + std::to_string(m.rotary_count()) +
               " rotary axis(es)";
  return out;
}

}  // namespace vcut::kinematics
