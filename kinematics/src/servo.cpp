#include "vcut/kinematics/servo.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

namespace vcut::kinematics {
namespace {

constexpr double kMaxPeriods = 1e9;  // a longer run is a units mistake, not a job

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("servo: " + what); }

}  // namespace

// One axis's loop over one interpolation period, exact for a velocity command held
// constant over the period (zero-order hold). Second order: state (x, v, a = v'),
//   x' = v,  v'' + 2 zeta omega_n v' + omega_n^2 v = omega_n^2 u,
// i.e. s' = A s + B u; over dT, s(k+1) = phi s(k) + gamma u(k) with phi = e^{A dT} and
// gamma = int_0^dT e^{A t} dt B, both read from the exponential of the augmented
// 4x4 matrix [[A, B], [0, 0]] dT (Van Loan). That covers under-, critically and
// over-damped loops alike. First order (ideal velocity loop, x' = u): x += u dT, exact.
ServoLoop::Axis ServoLoop::discretize(const ServoAxis& axis, double dt) {
  if (!std::isfinite(axis.kv_per_s) || axis.kv_per_s < 0.0) fail("kv_per_s must be finite and >= 0");
  if (!std::isfinite(axis.omega_n_per_s)) fail("omega_n_per_s must be finite");
  if (!std::isfinite(axis.feed_forward) || axis.feed_forward < 0.0 || axis.feed_forward > 1.0)
    fail("feed_forward must be in [0, 1]");
  Axis d;
  d.kv = axis.kv_per_s;
  d.ff = axis.feed_forward;
  if (axis.omega_n_per_s <= 0.0) {
    d.gamma = Eigen::Vector3d(dt, 0.0, 0.0);
    return d;
  }
  if (!std::isfinite(axis.zeta) || axis.zeta < 0.0) fail("zeta must be finite and >= 0");
  const double wn = axis.omega_n_per_s;
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 1) = 1.0;
  m(1, 2) = 1.0;
  m(2, 1) = -wn * wn;
  m(2, 2) = -2.0 * axis.zeta * wn;
  m(2, 3) = wn * wn;
  const Eigen::Matrix4d e = (m * dt).exp();
  d.second_order = true;
  d.phi = e.topLeftCorner<3, 3>();
  d.gamma = e.topRightCorner<3, 1>();
  return d;
}

bool servo_stable(const ServoAxis& axis, double period_s) {
  if (!std::isfinite(period_s) || period_s <= 0.0) return false;
  try {
    ServoSettings one;
    one.period_s = period_s;
    one.axes = {axis};
    ServoLoop loop(one, AxisValues::Zero(1));
    return loop.spectral_radius(0) < 1.0;
  } catch (const std::invalid_argument&) {
    return false;
  }
}

double ServoLoop::spectral_radius(int j) const {
  const Axis& m = model_[j];
  if (!m.second_order) return std::abs(1.0 - m.kv * dt_);
  Eigen::Matrix3d closed = m.phi;
  closed.col(0) -= m.gamma * m.kv;
  return Eigen::EigenSolver<Eigen::Matrix3d>(closed, false).eigenvalues().cwiseAbs().maxCoeff();
}

ServoLoop::ServoLoop(const ServoSettings& settings, const AxisValues& start) {
  dt_ = settings.period_s;
  axes_ = static_cast<int>(start.size());
  if (!std::isfinite(dt_) || dt_ <= 0.0) fail("period_s must be finite and > 0");
  if (axes_ < 1 || axes_ > 5) fail("one to five axes");
  if (!start.allFinite()) fail("non-finite start");
  if (settings.axes.size() != 1 && settings.axes.size() != static_cast<std::size_t>(axes_))
    fail("settings.axes must hold one entry or one per axis");
  for (int j = 0; j < axes_; ++j) {
    model_[j] = discretize(settings.axes[settings.axes.size() == 1 ? 0 : j], dt_);
    s_[j] = s_prev_[j] = s_prev2_[j] = Eigen::Vector3d(start[j], 0.0, 0.0);
    c_prev_[j] = start[j];
  }
  x_ = start;
}

void ServoLoop::step(const AxisValues& c) {
  for (int j = 0; j < axes_; ++j) {
    const Axis& m = model_[j];
    const double u = m.kv * (c[j] - s_[j][0]) + m.ff * (c[j] - c_prev_[j]) / dt_;
    s_prev2_[j] = s_prev_[j];
    s_prev_[j] = s_[j];
    s_[j] = m.phi * s_prev_[j] + m.gamma * u;
    c_prev_[j] = c[j];
    x_[j] = s_[j][0];
  }
}

// Between the instants. First order: x is linear over the period, so linear interpolation is
// exact. Second order: x is analytic inside the period and x, x', x'' are known at both
// ends, so the quintic Hermite interpolant is used; its error is at most max|x^(6)| dT^6 /
// 46080 (after a velocity step dv, |x^(6)| <= dv omega_n^5 / sqrt(1 - zeta^2): 1.4e-5 mm for
// dv = 1 m/s, omega_n = 120/s, zeta = 0.8, dT = 5 ms), and zero at the instants.
AxisValues ServoLoop::within(const std::array<Eigen::Vector3d, 5>& s0, const std::array<Eigen::Vector3d, 5>& s1,
                             double r) const {
  AxisValues o(axes_);
  const double dt = dt_;
  const double r2 = r * r, r3 = r2 * r, r4 = r3 * r, r5 = r4 * r;
  const double h0 = 1.0 - 10.0 * r3 + 15.0 * r4 - 6.0 * r5;
  const double h1 = (r - 6.0 * r3 + 8.0 * r4 - 3.0 * r5) * dt;
  const double h2 = 0.5 * (r2 - 3.0 * r3 + 3.0 * r4 - r5) * dt * dt;
  const double h3 = 0.5 * (r3 - 2.0 * r4 + r5) * dt * dt;
  const double h4 = (-4.0 * r3 + 7.0 * r4 - 3.0 * r5) * dt;
  const double h5 = 10.0 * r3 - 15.0 * r4 + 6.0 * r5;
  for (int j = 0; j < axes_; ++j) {
    const Eigen::Vector3d& a = s0[j];
    const Eigen::Vector3d& b = s1[j];
    o[j] = model_[j].second_order ? h0 * a[0] + h1 * a[1] + h2 * a[2] + h5 * b[0] + h4 * b[1] + h3 * b[2]
                                  : a[0] + r * (b[0] - a[0]);
  }
  return o;
}

double ServoLoop::max_speed() const {
  double v = 0.0;
  for (int j = 0; j < axes_; ++j)
    v = std::max(v, std::abs(model_[j].second_order ? s_[j][1] : (s_[j][0] - s_prev_[j][0]) / dt_));
  return v;
}

std::vector<AxisValues> simulate_servo(const std::vector<double>& t_s, const std::vector<AxisValues>& commanded,
                                       const ServoSettings& settings) {
  // ---- checks: these are programmer errors, the io layer has validated user input
  const std::size_t n = t_s.size();
  if (n == 0) fail("no time stamps");
  if (commanded.size() != n) fail("t_s and commanded differ in length");
  const int axes = static_cast<int>(commanded[0].size());
  if (axes < 1) fail("commanded values have no axes");
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t_s[i])) fail("non-finite time stamp at " + std::to_string(i));
    if (i > 0 && !(t_s[i] > t_s[i - 1])) fail("time stamps not ascending at " + std::to_string(i));
    if (commanded[i].size() != axes) fail("axis count changes at " + std::to_string(i));
    if (!commanded[i].allFinite()) fail("non-finite commanded value at " + std::to_string(i));
  }
  const double dt = settings.period_s;
  if (!std::isfinite(dt) || dt <= 0.0) fail("period_s must be finite and > 0");
  if ((t_s.back() - t_s.front()) / dt > kMaxPeriods) fail("more than 1e9 interpolation periods");

  ServoLoop loop(settings, commanded[0]);
  std::vector<AxisValues> out(n, AxisValues::Zero(axes));
  AxisValues c(axes);
  const double t0 = t_s.front();
  std::size_t seg = 0;   // command segment [t_s[seg], t_s[seg + 1]) holding the sample time
  std::size_t next = 0;  // next stamp to write
  for (long long k = 0; next < n; ++k) {
    // Interpolator: the commanded value at the sampling instant (held after the last stamp).
    const double t_k = t0 + static_cast<double>(k) * dt;
    while (seg + 1 < n && t_s[seg + 1] <= t_k) ++seg;
    if (seg + 1 < n) {
      const double f = (t_k - t_s[seg]) / (t_s[seg + 1] - t_s[seg]);
      c = commanded[seg] + f * (commanded[seg + 1] - commanded[seg]);
    } else {
      c = commanded[n - 1];
    }
    loop.step(c);
    // Stamps inside [t_k, t_k+1).
    const double t_k1 = t0 + static_cast<double>(k + 1) * dt;
    while (next < n && t_s[next] < t_k1) {
      out[next] = loop.within_last_period((t_s[next] - t_k) / dt);
      ++next;
    }
  }
  return out;
}

}  // namespace vcut::kinematics
