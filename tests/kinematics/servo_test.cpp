// Servo dynamic path error (ARCHITECTURE §7, seed 004). Expected values come from closed
// forms derived in the comments below, never from the code under test:
//  - the discrete first-order loop's error recursion (ramp lag, feed-forward);
//  - the continuous first-order loop's corner response (e^-1 v/Kv) and frequency response
//    (circle shrink R[1 - 1/sqrt(1 + (w/Kv)^2)]), at a period small enough to vanish;
//  - the second-order velocity loop's step response, integrated by hand (under-, critically
//    and over-damped);
//  - seed 004's figures (Huan Ji & Ma Weimin 2003, §2.4), loosely, and the continuous
//    third-order loop with the zero-order hold taken as a half-period delay.
//
// Model under test: u[k] = Kv (c[k] - x[k]) + ff (c[k] - c[k-1]) / dT held over
// [k dT, (k+1) dT); x' = u (ideal velocity loop) or x' = v, v'' + 2 zeta wn v' + wn^2 v = wn^2 u.
#include "vcut/kinematics/servo.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace vcut::kinematics {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Positions below 1e3 mm through a few hundred to 1e5 periods of a 3x3 update: rounding
// stays near 1e-12 mm; 1e-9 mm is "exact" for a servo error measured in um.
constexpr double kExactMm = 1e-9;
// Steady state relative: the brief's 1e-6 after settling (transients decay below 1e-15).
constexpr double kSteadyRel = 1e-6;
// Closed forms of the continuous loop reproduced by the sampled one at dT = 1e-4 s
// (Kv dT = 2e-3): the sampled decay (1 - Kv dT)^k differs from e^{-Kv t} by O(Kv dT) = 0.2 %;
// the bound is 1 %.
constexpr double kContinuousLimitRel = 0.01;

ServoSettings settings_for(double dt, ServoAxis axis) {
  ServoSettings s;
  s.period_s = dt;
  s.axes = {axis};
  return s;
}

AxisValues axis_values(std::initializer_list<double> v) {
  AxisValues a(static_cast<int>(v.size()));
  int i = 0;
  for (double x : v) a[i++] = x;
  return a;
}

struct Trajectory {
  std::vector<double> t_s;
  std::vector<AxisValues> x;
};

// Samples `f` at stamps i * step, i = 0..ceil(duration / step).
Trajectory sample(double duration_s, double step_s, const std::function<AxisValues(double)>& f) {
  Trajectory tr;
  const long n = static_cast<long>(std::ceil(duration_s / step_s - 1e-9));
  for (long i = 0; i <= n; ++i) {
    const double t = static_cast<double>(i) * step_s;
    tr.t_s.push_back(t);
    tr.x.push_back(f(t));
  }
  return tr;
}

double segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double s = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - a - s * d).norm();
}

// ---------------------------------------------------------------------------------------
// Ideal velocity loop (omega_n <= 0): x[k+1] = x[k] + dT u[k].

// Ramp c = v t from rest. With e[k] = c[k] - x[k] and c[k+1] - c[k] = v dT:
//   e[k+1] = e[k] (1 - Kv dT) + v dT,  e[0] = 0  =>  e[k] = (v/Kv) (1 - (1 - Kv dT)^k),
// whose fixed point is v/Kv exactly, for every dT with 0 < Kv dT < 2 (no dT -> 0 limit is
// needed). Inside a period x' = Kv e[k] and c' = v: e(t_k + tau) = e[k] + tau (v - Kv e[k]).
TEST(ServoFirstOrder, RampLagFollowsTheDiscreteRecursionAndSettlesOnVOverKv) {
  const double kv = 20.0, dt = 0.005, v = 100.0;  // mm/s
  const Trajectory cmd = sample(2.0, dt / 4, [&](double t) { return axis_values({v * t}); });
  const auto act = simulate_servo(cmd.t_s, cmd.x, settings_for(dt, ServoAxis{kv, 0.0, 0.8, 0.0}));
  ASSERT_EQ(act.size(), cmd.t_s.size());
  for (std::size_t i = 0; i < act.size(); ++i) {
    const int k = static_cast<int>(i / 4);
    const double tau = static_cast<double>(i % 4) * dt / 4;
    const double ek = v / kv * (1.0 - std::pow(1.0 - kv * dt, k));
    const double expected = ek + tau * (v - kv * ek);
    ASSERT_NEAR(cmd.x[i][0] - act[i][0], expected, kExactMm) << "stamp " << i;
  }
  // After 2 s the transient (0.9^400 ~ 5e-19) is gone: the lag is v/Kv.
  EXPECT_NEAR((cmd.x.back()[0] - act.back()[0]) / (v / kv), 1.0, kSteadyRel);
}

// Circle c = R (cos wt, sin wt) on two independent first-order loops. Each axis's steady
// response to a sinusoid is scaled by |H(jw)| = |Kv / (jw + Kv)| = 1/sqrt(1 + (w/Kv)^2), the
// same for both axes with the same phase lag, so the actual path is a circle of radius
// R |H|: shrink R [1 - 1/sqrt(1 + (w/Kv)^2)] (seed 004 eq. 1 in the frequency domain).
TEST(ServoFirstOrder, CircleShrinksByTheFrequencyResponse) {
  const double kv = 20.0, dt = 1e-4, r = 100.0, w = 10.0;  // w / Kv = 0.5: shrink 10.557 mm
  const double shrink = r * (1.0 - 1.0 / std::sqrt(1.0 + (w / kv) * (w / kv)));
  const double settle_s = 10.0 / kv;  // e^-10 * (v/Kv = 50 mm) = 2e-3 mm of transient left
  const double turn_s = 2 * kPi / w;
  const Trajectory cmd = sample(settle_s + turn_s, dt, [&](double t) {
    return axis_values({r * std::cos(w * t), r * std::sin(w * t)});
  });
  const auto act = simulate_servo(cmd.t_s, cmd.x, settings_for(dt, ServoAxis{kv, 0.0, 0.8, 0.0}));
  double lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < act.size(); ++i) {
    if (cmd.t_s[i] < settle_s) continue;
    const double d = r - std::hypot(act[i][0], act[i][1]);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  EXPECT_NEAR(lo / shrink, 1.0, kContinuousLimitRel);
  EXPECT_NEAR(hi / shrink, 1.0, kContinuousLimitRel);
}

// 90 deg corner: X ramps at v to the corner (0, 0), then Y ramps at v; each leg lasts 10/Kv.
// Continuous first-order loop, t from the corner, T = Kv t: X arrives with the steady lag,
// x = -(v/Kv) e^{-T}; Y starts from rest, y = v t - (v/Kv)(1 - e^{-T}) = (v/Kv)(T - 1 + e^{-T}).
// The actual point lies in x < 0 < y, so its distance to the commanded polyline (the
// negative x axis and the positive y axis) is min(|x|, y): |x| falls, y rises, and the
// maximum is where they meet, e^{-T} = T - 1 + e^{-T}, i.e. T = 1: e_max = e^{-1} v/Kv
// = 0.368 v/Kv. Before the corner the point runs on the x axis (error 0); after, on the y axis.
TEST(ServoFirstOrder, CornerContourErrorIsVOverKvOverE) {
  const double kv = 20.0, dt = 1e-4, v = 100.0, leg = 10.0 / kv * v;  // 50 mm legs
  const double t1 = leg / v, t2 = 2 * leg / v;
  const Trajectory cmd = sample(t2 + 10.0 / kv, dt, [&](double t) {
    if (t < t1) return axis_values({v * t - leg, 0.0});
    return axis_values({0.0, v * std::min(t - t1, t2 - t1)});
  });
  const auto act = simulate_servo(cmd.t_s, cmd.x, settings_for(dt, ServoAxis{kv, 0.0, 0.8, 0.0}));
  double e_max = 0.0;
  for (const AxisValues& p : act) {
    const Eigen::Vector2d q(p[0], p[1]);
    e_max = std::max(e_max, std::min(segment_distance(q, {-leg, 0}, {0, 0}), segment_distance(q, {0, 0}, {0, leg})));
  }
  EXPECT_NEAR(e_max / (std::exp(-1.0) * v / kv), 1.0, kContinuousLimitRel);
}

// ---------------------------------------------------------------------------------------
// Second-order velocity loop.

// Unit step response of v'' + 2 z wn v' + wn^2 v = wn^2 u from rest, integrated once:
// I(T) = int_0^T s(t) dt, the position after a unit velocity step.
//  z < 1: s = 1 - e^{-sigma t}(cos wd t + (sigma/wd) sin wd t), sigma = z wn,
//         wd = wn sqrt(1 - z^2);
//         with E = e^{-sigma T}, c = cos wd T, sn = sin wd T,
//           int_0^T e^{-sigma t} cos wd t dt = [sigma - E (sigma c - wd sn)] / wn^2,
//           int_0^T e^{-sigma t} sin wd t dt = [wd - E (sigma sn + wd c)] / wn^2,
//         I = T - [2 sigma - E (2 sigma c + sn (sigma^2 - wd^2) / wd)] / wn^2.
//  z = 1: s = 1 - e^{-wt}(1 + wt): I = T - 2/wn + e^{-wn T}(2/wn + T).
//  z > 1: p1,2 = wn(-z +- sqrt(z^2 - 1)): s = 1 + (p2 e^{p1 t} - p1 e^{p2 t})/(p1 - p2),
//         I = T + [p2 (e^{p1 T} - 1)/p1 - p1 (e^{p2 T} - 1)/p2] / (p1 - p2).
// All tend to T - 2 z / wn: the velocity loop's DC gain is 1, its lag 2 z / wn.
double step_integral(double wn, double z, double t) {
  if (t <= 0.0) return 0.0;
  if (z < 1.0) {
    const double sg = z * wn, wd = wn * std::sqrt(1.0 - z * z), e = std::exp(-sg * t);
    const double c = std::cos(wd * t), sn = std::sin(wd * t);
    return t - (2 * sg - e * (2 * sg * c + sn * (sg * sg - wd * wd) / wd)) / (wn * wn);
  }
  if (z == 1.0) return t - 2 / wn + std::exp(-wn * t) * (2 / wn + t);
  const double q = std::sqrt(z * z - 1.0), p1 = wn * (-z + q), p2 = wn * (-z - q);
  return t + (p2 * std::expm1(p1 * t) / p1 - p1 * std::expm1(p2 * t) / p2) / (p1 - p2);
}

// The velocity loop alone: Kv = 0, full feed-forward, a ramp at V from rest. The backward
// difference gives u = 0 over the first period and u = V after, a velocity step at t = dT,
// so x(t) = V I(t - dT). At sampling instants the integrator is exact (kExactMm). Between
// them the quintic Hermite interpolant errs by at most max|x^(6)| dT^6 / 46080 (the error
// term f^(6)/6! (t-a)^3 (t-b)^3, at most (dT/2)^6 / 720), with |x^(6)| = V |s^(5)| bounded below.
// max |s^(5)| from the forms above: z < 1: s' = (wn / sqrt(1 - z^2)) e^{-sigma t} sin wd t and
// each derivative multiplies the amplitude by |-sigma + j wd| = wn: wn^5 / sqrt(1 - z^2);
// z = 1: s' = wn^2 t e^{-wn t}, |s^(5)| <= 4 wn^5 (at t = 0); z > 1:
// s^(5) = p1 p2 (p1^4 e^{p1 t} - p2^4 e^{p2 t}) / (p1 - p2) <= p1 p2 (p1^4 + p2^4) / |p1 - p2|.
double step_fifth_derivative_bound(double wn, double z) {
  if (z < 1.0) return std::pow(wn, 5) / std::sqrt(1.0 - z * z);
  if (z == 1.0) return 4.0 * std::pow(wn, 5);
  const double q = std::sqrt(z * z - 1.0), p1 = wn * (-z + q), p2 = wn * (-z - q);
  return p1 * p2 * (std::pow(p1, 4) + std::pow(p2, 4)) / std::abs(p1 - p2);
}

TEST(ServoSecondOrder, VelocityStepResponseMatchesTheClosedForm) {
  const double dt = 0.005, wn = 120.0, v = 100.0;
  for (double z : {0.5, 0.8, 1.0, 2.0}) {
    SCOPED_TRACE("zeta " + std::to_string(z));
    const double hermite_bound = v * step_fifth_derivative_bound(wn, z) * std::pow(dt, 6) / 46080;
    const Trajectory cmd = sample(0.5, dt / 7, [&](double t) { return axis_values({v * t}); });
    const auto act = simulate_servo(cmd.t_s, cmd.x, settings_for(dt, ServoAxis{0.0, wn, z, 1.0}));
    for (std::size_t i = 0; i < act.size(); ++i) {
      const double expected = v * step_integral(wn, z, cmd.t_s[i] - dt);
      const double tol = (i % 7 == 0 ? 0.0 : hermite_bound) + kExactMm;
      ASSERT_NEAR(act[i][0], expected, tol) << "t " << cmd.t_s[i];
    }
    // DC gain 1: the settled velocity is V (e^{-sigma 0.4 s} <= e^{-16}; slope over 0.1 s).
    const std::size_t last = act.size() - 1, back = last - 70;
    EXPECT_NEAR((act[last][0] - act[back][0]) / (cmd.t_s[last] - cmd.t_s[back]) / v, 1.0, kSteadyRel);
  }
}

// Overshoot of the velocity step: peak at t_p = pi / wd after the step, v(t_p) / V =
// 1 + exp(-pi z / sqrt(1 - z^2)). Read as a central difference of the output positions,
// h = 1e-6 s: truncation h^2/6 |x'''| ~ 1e-12 / 6 * wn^2 V, i.e. 2e-9 relative; the Hermite
// interpolant's derivative error is below (hermite_bound / dT) / V ~ 1e-7; rounding
// eps * 50 mm / h ~ 1e-8 mm/s. 1e-5 relative covers all three with margin.
TEST(ServoSecondOrder, VelocityStepOvershootAndDcGain) {
  constexpr double kOvershootTol = 1e-5;
  const double dt = 0.005, wn = 120.0, v = 100.0, h = 1e-6;
  for (double z : {0.3, 0.5, 0.8}) {
    SCOPED_TRACE("zeta " + std::to_string(z));
    const double wd = wn * std::sqrt(1 - z * z), tp = dt + kPi / wd;
    Trajectory cmd = sample(0.5, dt, [&](double t) { return axis_values({v * t}); });
    // Insert the probe stamps tp - h, tp + h (and a settled pair) into the same ramp.
    std::vector<double> probes = {tp - h, tp + h, 0.45 - h, 0.45 + h};
    for (double p : probes) {
      const auto it = std::upper_bound(cmd.t_s.begin(), cmd.t_s.end(), p);
      cmd.x.insert(cmd.x.begin() + (it - cmd.t_s.begin()), axis_values({v * p}));
      cmd.t_s.insert(it, p);
    }
    const auto act = simulate_servo(cmd.t_s, cmd.x, settings_for(dt, ServoAxis{0.0, wn, z, 1.0}));
    auto at = [&](double t) { return act[std::lower_bound(cmd.t_s.begin(), cmd.t_s.end(), t) - cmd.t_s.begin()][0]; };
    const double peak = (at(tp + h) - at(tp - h)) / (2 * h) / v;
    EXPECT_NEAR(peak - 1.0, std::exp(-kPi * z / std::sqrt(1 - z * z)), kOvershootTol);
    const double settled = (at(0.45 + h) - at(0.45 - h)) / (2 * h) / v;  // e^{-0.3*120*0.44} = 1e-7
    EXPECT_NEAR(settled, 1.0, kOvershootTol);
  }
}

// The whole loop (Kv = 20, wn = 120, z = 0.8, dT = 5 ms) is type 1: in a steady ramp the
// velocity loop sits at v = V, v' = 0, which needs u = V = Kv e + ff V, so e = (1 - ff) V/Kv
// for either velocity loop. A held command is reached exactly (DC gain 1). The closed-loop
// poles decay at least as e^{-20 t} (checked: the lag after 1.5 s matches to 1e-9 mm).
TEST(ServoLoop, RampLagIsOneMinusFeedForwardTimesVOverKvAndHoldIsReached) {
  const double kv = 20.0, dt = 0.005, v = 250.0, t_stop = 1.5;
  for (double wn : {0.0, 120.0}) {
    for (double ff : {0.0, 0.5, 1.0}) {
      SCOPED_TRACE("wn " + std::to_string(wn) + " ff " + std::to_string(ff));
      const Trajectory cmd =
          sample(t_stop + 1.5, dt / 2, [&](double t) { return axis_values({v * std::min(t, t_stop)}); });
      const auto act = simulate_servo(cmd.t_s, cmd.x, settings_for(dt, ServoAxis{kv, wn, 0.8, ff}));
      const std::size_t at_stop = static_cast<std::size_t>(std::lround(t_stop / (dt / 2)));
      EXPECT_NEAR(cmd.x[at_stop][0] - act[at_stop][0], (1.0 - ff) * v / kv, kExactMm);
      EXPECT_NEAR(act.back()[0], v * t_stop, kExactMm);
    }
  }
}

// ---------------------------------------------------------------------------------------
// Axes, determinism, inputs.

// 1 to 5 axes with per-axis parameters: bit-identical on a second call; each axis equals
// a one-axis run with its own parameters (the axes are independent); one ServoAxis entry
// serves all axes.
TEST(ServoAxes, OneToFiveAxesAreIndependentAndDeterministic) {
  std::mt19937 rng(4004);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const ServoAxis kinds[5] = {
      {20, 120, 0.8, 0}, {25, 0, 0, 0.3}, {15, 80, 1.0, 1}, {30, 150, 0.9, 0.5}, {10, 60, 2.0, 0}};
  for (int axes = 1; axes <= 5; ++axes) {
    SCOPED_TRACE("axes " + std::to_string(axes));
    Trajectory cmd;
    double t = 0.0;
    AxisValues x = AxisValues::Zero(axes);
    for (int i = 0; i < 400; ++i) {
      cmd.t_s.push_back(t);
      cmd.x.push_back(x);
      t += 0.001 + 0.01 * (u(rng) + 1.0);  // irregular stamps, 1 to 21 ms
      for (int j = 0; j < axes; ++j) x[j] += 5.0 * u(rng);
    }
    ServoSettings s;
    s.period_s = 0.004;
    s.axes.assign(kinds, kinds + axes);
    const auto a = simulate_servo(cmd.t_s, cmd.x, s);
    const auto b = simulate_servo(cmd.t_s, cmd.x, s);
    ASSERT_EQ(a.size(), cmd.t_s.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].size(), axes);
      for (int j = 0; j < axes; ++j) ASSERT_EQ(a[i][j], b[i][j]);
    }
    for (int j = 0; j < axes; ++j) {
      std::vector<AxisValues> one(cmd.x.size());
      for (std::size_t i = 0; i < one.size(); ++i) one[i] = axis_values({cmd.x[i][j]});
      const auto alone = simulate_servo(cmd.t_s, one, settings_for(0.004, kinds[j]));
      for (std::size_t i = 0; i < a.size(); ++i) ASSERT_NEAR(a[i][j], alone[i][0], kExactMm);
    }
    ServoSettings all = s;
    all.axes = {kinds[0]};
    ServoSettings each = s;
    each.axes.assign(axes, kinds[0]);
    const auto c = simulate_servo(cmd.t_s, cmd.x, all), d = simulate_servo(cmd.t_s, cmd.x, each);
    for (std::size_t i = 0; i < c.size(); ++i) ASSERT_EQ(c[i], d[i]);
  }
}

TEST(ServoInput, SingleStampIsTheCommandAtRest) {
  const auto a = simulate_servo({1.5}, {axis_values({1.0, 2.0, 3.0})}, settings_for(0.005, ServoAxis{}));
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0], axis_values({1.0, 2.0, 3.0}));
}

TEST(ServoInput, ProgrammerErrorsThrowInvalidArgument) {
  const ServoSettings ok = settings_for(0.005, ServoAxis{});
  const std::vector<double> t = {0.0, 0.1, 0.2};
  const std::vector<AxisValues> x = {axis_values({0, 0}), axis_values({1, 0}), axis_values({2, 0})};
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_NO_THROW(simulate_servo(t, x, ok));
  EXPECT_THROW(simulate_servo({}, {}, ok), std::invalid_argument);                  // empty
  EXPECT_THROW(simulate_servo({0.0, 0.1}, x, ok), std::invalid_argument);           // lengths
  EXPECT_THROW(simulate_servo({0.0, 0.2, 0.1}, x, ok), std::invalid_argument);      // descending
  EXPECT_THROW(simulate_servo({0.0, 0.1, 0.1}, x, ok), std::invalid_argument);      // repeated
  EXPECT_THROW(simulate_servo({0.0, nan, 0.2}, x, ok), std::invalid_argument);      // NaN stamp
  EXPECT_THROW(simulate_servo({0.0, 0.1, inf}, x, ok), std::invalid_argument);      // inf stamp
  EXPECT_THROW(simulate_servo({0.0}, {AxisValues(0)}, ok), std::invalid_argument);  // no axes
  auto bad = x;
  bad[1][1] = nan;
  EXPECT_THROW(simulate_servo(t, bad, ok), std::invalid_argument);  // NaN value
  bad = x;
  bad[2] = axis_values({2, 0, 0});
  EXPECT_THROW(simulate_servo(t, bad, ok), std::invalid_argument);  // axis count changes
  auto with = [&](auto edit) {
    ServoSettings s = ok;
    edit(s);
    return s;
  };
  EXPECT_THROW(simulate_servo(t, x, with([](ServoSettings& s) { s.period_s = 0; })), std::invalid_argument);
  EXPECT_THROW(simulate_servo(t, x, with([&](ServoSettings& s) { s.period_s = nan; })), std::invalid_argument);
  EXPECT_THROW(simulate_servo(t, x, with([](ServoSettings& s) { s.axes.clear(); })), std::invalid_argument);
  EXPECT_THROW(simulate_servo(t, x, with([](ServoSettings& s) { s.axes.resize(3); })), std::invalid_argument);
  EXPECT_THROW(simulate_servo(t, x, with([](ServoSettings& s) { s.axes[0].kv_per_s = -1; })), std::invalid_argument);
  EXPECT_THROW(simulate_servo(t, x, with([](ServoSettings& s) { s.axes[0].feed_forward = 1.5; })),
               std::invalid_argument);
  EXPECT_THROW(simulate_servo(t, x, with([&](ServoSettings& s) { s.axes[0].zeta = nan; })), std::invalid_argument);
  EXPECT_THROW(simulate_servo(t, x, with([&](ServoSettings& s) { s.axes[0].omega_n_per_s = inf; })),
               std::invalid_argument);
}

// ---------------------------------------------------------------------------------------
// Seed 004's worked cases with its parameters: wn = 120/s, xi = 0.8, Kv = 20/s, dT = 5 ms,
// v = 10, 20, 40 m/min. The commands are the paper's input functions (eqs. 3-16), stamped
// every 1 ms (the interpolator samples them every 5 ms).
//
// Its figures (§2.4): "图 8a ... 最大轨迹误差 e 分别为 2.8mm, 5.2mm, 10mm" (corner);
// "图 8b ... e 分别为 1.3mm, 0.5mm, 2mm" (circle); "图 8c ... e 分别为 0.04 mm, 0.35 mm,
// 1.4 mm" (swivel-head line). They are read off plots to one or two digits, and the loop is
// linear, so an error must scale as v (corner) or about v^2 (circle while w << Kv, and the
// line: there the first-order lag is a pure time shift along the path) -- which 2.8/5.2/10,
// 1.3/0.5/2 and 0.04/0.35/1.4 do not quite. The circle's 1.3 mm at 10 m/min is read as 0.13 (the
// paper's own 0.5 mm at 20 m/min, / 4); the line's 0.04 mm at 10 m/min is set beside ours, not
// asserted. The corner figure matches the distance from the commanded corner to the actual path;
// the contour error (distance from the commanded path, max) is tabulated beside it.
constexpr double kPaperRel = 0.10;  // figures to ~2 digits off a plot
// The circle against the continuous loop with the ZOH taken as a half-period delay: that
// delay model errs by O((w dT)^2) = 1e-3 at 40 m/min on |L|, and the 1 ms polyline's chord
// sag (5.6e-4 mm at 40 m/min) is 0.03 % of the shrink.
constexpr double kZohModelRel = 0.01;

struct Seed004Row {
  double corner_contour, corner_distance, circle_max, circle_first_order, circle_third_order, circle_zoh, line;
};

Seed004Row seed004_row(double v_m_per_min) {
  const ServoAxis axis{20.0, 120.0, 0.8, 0.0};
  const double dt = 0.005, step = 0.001, v = v_m_per_min * 1000.0 / 60.0, kv = axis.kv_per_s;
  const ServoSettings s = settings_for(dt, axis);
  Seed004Row row{};

  // Corner (eqs. 3-6): Y from (0, 0) to (0, 100) at v, then X to (100, 100); 1 s to settle.
  const double ye = 100.0, xe = 100.0, t1 = ye / v, t2 = (ye + xe) / v;
  const Trajectory corner = sample(t2 + 1.0, step, [&](double t) {
    if (t < t1) return axis_values({0.0, v * t});
    return axis_values({v * (std::min(t, t2) - t1), ye});
  });
  row.corner_distance = 1e300;
  for (const AxisValues& p : simulate_servo(corner.t_s, corner.x, s)) {
    const Eigen::Vector2d q(p[0], p[1]);
    row.corner_contour = std::max(
        row.corner_contour, std::min(segment_distance(q, {0, 0}, {0, ye}), segment_distance(q, {0, ye}, {xe, ye})));
    row.corner_distance = std::min(row.corner_distance, (q - Eigen::Vector2d(0, ye)).norm());
  }

  // Circle (eqs. 7-8): R = 100 from (R, 0) at rest, one turn, then held for 1 s.
  const double r = 100.0, w = v / r, turn = 2 * kPi / w;
  const Trajectory circle = sample(turn + 1.0, step, [&](double t) {
    const double a = w * std::min(t, turn);
    return axis_values({r * std::cos(a), r * std::sin(a)});
  });
  for (const AxisValues& p : simulate_servo(circle.t_s, circle.x, s))
    row.circle_max = std::max(row.circle_max, std::abs(r - std::hypot(p[0], p[1])));
  // Expected shrinks R (1 - |H(jw)|), H = L / (1 + L): first order L = Kv / s (the issue's
  // formula); third order L = Kv wn^2 / (s (s^2 + 2 xi wn s + wn^2)); and that times e^{-s dT/2}.
  const std::complex<double> jw(0.0, w);
  const std::complex<double> l3 =
      kv * axis.omega_n_per_s * axis.omega_n_per_s /
      (jw * (jw * jw + 2 * axis.zeta * axis.omega_n_per_s * jw + axis.omega_n_per_s * axis.omega_n_per_s));
  const std::complex<double> lz = l3 * std::exp(-jw * (dt / 2));
  row.circle_first_order = r * (1.0 - 1.0 / std::sqrt(1.0 + (w / kv) * (w / kv)));
  row.circle_third_order = r * (1.0 - std::abs(l3 / (1.0 + l3)));
  row.circle_zoh = r * (1.0 - std::abs(lz / (1.0 + lz)));

  // Swivel-head line (eqs. 9-16): axes X, Y, Z, B; tip = (X, Y, Z) - L (sin B cos th,
  // sin B sin th, cos B) runs on the line from (0,0,0) to (200,200,0) while B goes -30 -> 30 deg.
  const double len = 500.0, alpha = 30.0 * kPi / 180.0, xc = 200.0, yc = 200.0;
  const double span = std::hypot(xc, yc), th = std::atan2(yc, xc), t_end = span / v;
  const Trajectory line = sample(t_end + 1.0, step, [&](double t) {
    const double b = 2 * alpha * v * std::min(t, t_end) / span - alpha;
    const double rr = len * std::sin(b) + span * std::tan(b) / (2 * std::tan(alpha));
    return axis_values({rr * std::cos(th) + xc / 2, rr * std::sin(th) + yc / 2, len * std::cos(b), b});
  });
  const Eigen::Vector3d dir(std::cos(th), std::sin(th), 0.0);
  for (const AxisValues& p : simulate_servo(line.t_s, line.x, settings_for(dt, axis))) {
    const Eigen::Vector3d tip(p[0] - len * std::sin(p[3]) * std::cos(th), p[1] - len * std::sin(p[3]) * std::sin(th),
                              p[2] - len * std::cos(p[3]));
    const double along = std::clamp(tip.dot(dir), 0.0, span);
    row.line = std::max(row.line, (tip - along * dir).norm());
  }
  return row;
}

TEST(ServoSeed004, CornerCircleAndSwivelLineBesideThePaper) {
  const double speeds[3] = {10, 20, 40};
  const double paper_corner[3] = {2.8, 5.2, 10.0};
  const double paper_circle[3] = {0.13 /* printed 1.3, see above */, 0.5, 2.0};
  const double paper_line[3] = {0.04, 0.35, 1.4};
  Seed004Row rows[3];
  std::printf("seed 004 (Kv 20/s, wn 120/s, xi 0.8, dT 5 ms), mm:\n");
  std::printf(
      "  v m/min | corner: contour  to-corner paper | circle: max  1st-order 3rd-order 3rd+ZOH "
      "paper"
      " | line: max  paper\n");
  for (int i = 0; i < 3; ++i) {
    const Seed004Row& r = rows[i] = seed004_row(speeds[i]);
    std::printf(
        "  %7.0f |       %7.3f %9.3f %5.2f |      %6.3f %9.3f %9.3f %7.3f %5.2f |     %6.3f "
        "%5.2f\n",
        speeds[i], r.corner_contour, r.corner_distance, paper_corner[i], r.circle_max, r.circle_first_order,
        r.circle_third_order, r.circle_zoh, paper_circle[i], r.line, paper_line[i]);
    RecordProperty("corner_contour_mm_" + std::to_string(static_cast<int>(speeds[i])),
                   std::to_string(r.corner_contour));
    RecordProperty("circle_shrink_mm_" + std::to_string(static_cast<int>(speeds[i])), std::to_string(r.circle_max));
    RecordProperty("line_error_mm_" + std::to_string(static_cast<int>(speeds[i])), std::to_string(r.line));

    EXPECT_NEAR(r.corner_distance / paper_corner[i], 1.0, kPaperRel) << speeds[i] << " m/min";
    EXPECT_NEAR(r.circle_max / paper_circle[i], 1.0, kPaperRel) << speeds[i] << " m/min";
    if (i > 0) {
      EXPECT_NEAR(r.line / paper_line[i], 1.0, kPaperRel) << speeds[i] << " m/min";
    }
    // The circle is the first-order formula corrected by what the velocity loop (and the
    // hold) explain: it matches the third-order + ZOH loop, and lies below the first-order
    // shrink by that model's difference.
    EXPECT_NEAR(r.circle_max / r.circle_zoh, 1.0, kZohModelRel) << speeds[i] << " m/min";
    EXPECT_NEAR((r.circle_first_order - r.circle_max) / (r.circle_first_order - r.circle_zoh), 1.0, kZohModelRel);
  }
  // A linear loop: corner errors scale as v, line errors as v^2, each to 1 % (the corner's
  // 100 mm legs settle, 150 ms at 40 m/min against a ~30 ms loop time constant; the line's
  // next term in v is smaller by ~(v/Kv)/L). The circle's shrink is not a power of v:
  // 1 - |H(jw)| is checked against its closed form above.
  constexpr double kScalingRel = 0.01;
  for (int i = 1; i < 3; ++i) {
    EXPECT_NEAR(rows[i].corner_contour / rows[i - 1].corner_contour / 2.0, 1.0, kScalingRel);
    EXPECT_NEAR(rows[i].line / rows[i - 1].line / 4.0, 1.0, kScalingRel);
  }
}

}  // namespace
}  // namespace vcut::kinematics

namespace vcut::kinematics {
namespace {

// Stability of the sampled loop. First order: x[k+1] - c = (1 - Kv dT)(x[k] - c), stable
// iff Kv dT < 2 (closed form). Second order: judged by running the loop on a step and
// watching the error grow or decay over 2,000 periods (a second method beside the
// eigenvalues servo_stable reads).
TEST(ServoStability, MatchesTheClosedFormAndASimulation) {
  ServoAxis first;
  first.omega_n_per_s = 0.0;
  for (double kv_dt : {0.5, 1.5, 1.99}) {
    first.kv_per_s = kv_dt / 0.005;
    EXPECT_TRUE(servo_stable(first, 0.005)) << kv_dt;
  }
  for (double kv_dt : {2.01, 3.0}) {
    first.kv_per_s = kv_dt / 0.005;
    EXPECT_FALSE(servo_stable(first, 0.005)) << kv_dt;
  }
  for (double kv : {5.0, 20.0, 60.0, 150.0, 400.0, 1000.0}) {
    ServoAxis second;  // seed 004's velocity loop
    second.kv_per_s = kv;
    ServoSettings s;
    s.period_s = 0.005;
    s.axes = {second};
    ServoLoop loop(s, AxisValues::Zero(1));
    AxisValues c(1);
    c << 1.0;
    double early = 0.0, late = 0.0;
    for (int k = 0; k < 2000; ++k) {
      loop.step(c);
      const double e = std::abs(loop.position()[0] - 1.0);
      if (k >= 100 && k < 200) early = std::max(early, e);
      if (k >= 1900) late = std::max(late, e);
    }
    EXPECT_EQ(servo_stable(second, 0.005), late < early) << "Kv " << kv << ": early " << early << ", late " << late;
  }
}

}  // namespace
}  // namespace vcut::kinematics
