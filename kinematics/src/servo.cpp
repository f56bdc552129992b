#include "vcut/kinematics/servo.h"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

namespace vcut::kinematics {
namespace {

constexpr double kMaxPeriods = 1e9;  // a longer run is a units mistake, not a job

// One axis's loop over one interpolation period, exact for a velocity command held
// constant over the period (zero-order hold). Second order: state (x, v, a = v'),
//   x' = v,  v'' + 2 zeta omega_n v' + omega_n^2 v = omega_n^2 u,
// i.e. s' = A s + B u; over dT, s(k+1) = phi s(k) + gamma u(k) with phi = e^{A dT} and
// gamma = int_0^dT e^{A t} dt B, both read from the exponential of the augmented
// 4x4 matrix [[A, B], [0, 0]] dT (Van Loan). That covers under-, critically and
// over-damped loops alike. First order (ideal velocity loop, x' = u): x += u dT, exact.
struct DiscreteAxis {
  bool second_order = false;
  double kv = 0.0, ff = 0.0;
  Eigen::Matrix3d phi = Eigen::Matrix3d::Identity();
  Eigen::Vector3d gamma = Eigen::Vector3d::Zero();
};

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("simulate_servo: " + what);
}

DiscreteAxis discretize(const ServoAxis& axis, double dt) {
  if (!std::isfinite(axis.kv_per_s) || axis.kv_per_s < 0.0)
    fail("kv_per_s must be finite and >= 0");
  if (!std::isfinite(axis.omega_n_per_s)) fail("omega_n_per_s must be finite");
  if (!std::isfinite(axis.feed_forward) || axis.feed_forward < 0.0 || axis.feed_forward > 1.0)
    fail("feed_forward must be in [0, 1]");
  DiscreteAxis d;
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

}  // namespace

std::vector<AxisValues> simulate_servo(const std::vector<double>& t_s,
                                       const std::vector<AxisValues>& commanded,
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
  if (settings.axes.size() != 1 && settings.axes.size() != static_cast<std::size_t>(axes))
    fail("settings.axes must hold one entry or one per axis");
  if ((t_s.back() - t_s.front()) / dt > kMaxPeriods) fail("more than 1e9 interpolation periods");

  std::array<DiscreteAxis, 5> model;
  for (int j = 0; j < axes; ++j)
    model[j] = discretize(settings.axes[settings.axes.size() == 1 ? 0 : j], dt);

  // ---- state: at rest on the first commanded value
  std::array<Eigen::Vector3d, 5> s, s_next;
  std::array<double, 5> c_prev{}, c{};
  for (int j = 0; j < axes; ++j) {
    s[j] = Eigen::Vector3d(commanded[0][j], 0.0, 0.0);
    c_prev[j] = commanded[0][j];
  }

  std::vector<AxisValues> out(n, AxisValues::Zero(axes));
  const double t0 = t_s.front();
  std::size_t seg = 0;   // command segment [t_s[seg], t_s[seg + 1]) holding the sample time
  std::size_t next = 0;  // next stamp to write
  for (long long k = 0; next < n; ++k) {
    // Interpolator: the commanded value at the sampling instant (held after the last stamp).
    const double t_k = t0 + static_cast<double>(k) * dt;
    while (seg + 1 < n && t_s[seg + 1] <= t_k) ++seg;
    if (seg + 1 < n) {
      const double f = (t_k - t_s[seg]) / (t_s[seg + 1] - t_s[seg]);
      for (int j = 0; j < axes; ++j)
        c[j] = commanded[seg][j] + f * (commanded[seg + 1][j] - commanded[seg][j]);
    } else {
      for (int j = 0; j < axes; ++j) c[j] = commanded[n - 1][j];
    }
    // Position controller: velocity command, held over the period; one period of the loop.
    for (int j = 0; j < axes; ++j) {
      const DiscreteAxis& m = model[j];
      const double u = m.kv * (c[j] - s[j][0]) + m.ff * (c[j] - c_prev[j]) / dt;
      s_next[j].noalias() = m.phi * s[j];
      s_next[j] += m.gamma * u;
      c_prev[j] = c[j];
    }
    // Stamps inside [t_k, t_k+1). First order: x is linear over the period, so linear
    // interpolation is exact. Second order: x is analytic inside the period and x, x', x''
    // are known at both ends, so the quintic Hermite interpolant is used; its error is at
    // most max|x^(6)| dT^6 / 46080 (after a velocity step dv, |x^(6)| <= dv omega_n^5 /
    // sqrt(1 - zeta^2): 1.4e-5 mm for dv = 1 m/s, omega_n = 120/s, zeta = 0.8, dT = 5 ms),
    // and zero at the instants.
    const double t_k1 = t0 + static_cast<double>(k + 1) * dt;
    while (next < n && t_s[next] < t_k1) {
      const double r = (t_s[next] - t_k) / dt;
      const double r2 = r * r, r3 = r2 * r, r4 = r3 * r, r5 = r4 * r;
      const double h0 = 1.0 - 10.0 * r3 + 15.0 * r4 - 6.0 * r5;
      const double h1 = (r - 6.0 * r3 + 8.0 * r4 - 3.0 * r5) * dt;
      const double h2 = 0.5 * (r2 - 3.0 * r3 + 3.0 * r4 - r5) * dt * dt;
      const double h3 = 0.5 * (r3 - 2.0 * r4 + r5) * dt * dt;
      const double h4 = (-4.0 * r3 + 7.0 * r4 - 3.0 * r5) * dt;
      const double h5 = 10.0 * r3 - 15.0 * r4 + 6.0 * r5;
      AxisValues& o = out[next];
      for (int j = 0; j < axes; ++j) {
        const Eigen::Vector3d& a = s[j];
        const Eigen::Vector3d& b = s_next[j];
        o[j] = model[j].second_order
                   ? h0 * a[0] + h1 * a[1] + h2 * a[2] + h5 * b[0] + h4 * b[1] + h3 * b[2]
                   : a[0] + r * (b[0] - a[0]);
      }
      ++next;
    }
    for (int j = 0; j < axes; ++j) s[j] = s_next[j];
  }
  return out;
}

}  // namespace vcut::kinematics
