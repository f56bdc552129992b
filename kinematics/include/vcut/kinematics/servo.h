// Servo dynamic path error (ARCHITECTURE §7, seed 004): each machine axis is a sampled
// position loop with gain Kv (1/s) around a second-order velocity loop (natural frequency
// omega_n 1/s, damping zeta), optional velocity feed-forward, run at the interpolation
// period dT on the time-stamped commanded axis trajectory. Out: the actual trajectory.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "vcut/kinematics/machine.h"

namespace vcut::kinematics {

struct ServoAxis {
  double kv_per_s = 20.0;  // position loop gain Kv, >= 0 (0: open loop, feed-forward only)
  // Velocity loop natural frequency; <= 0: ideal velocity loop (first-order position loop).
  double omega_n_per_s = 120.0;
  double zeta = 0.8;          // velocity loop damping, >= 0
  double feed_forward = 0.0;  // velocity feed-forward fraction in [0, 1]
};

struct ServoSettings {
  double period_s = 0.005;      // interpolation period dT
  std::vector<ServoAxis> axes;  // one per machine axis, or one for all
};

// Whether one axis's sampled loop is stable at the period: every eigenvalue of the
// closed-loop period map (phi - gamma Kv e1^T; feed-forward only adds input) inside the unit
// circle. An ideal velocity loop needs Kv dT < 2. Settings out of range are unstable.
bool servo_stable(const ServoAxis& axis, double period_s);

// The loops of all axes, one interpolation period at a time (the controller's view: the
// interpolator hands the position controller a command every dT). Starts at rest on
// `start`. step(c) runs one period with c, the command at the period's first instant:
// u = Kv (c - x) + ff (c - c_prev) / dT held over the period, the velocity loop integrated
// exactly (zero-order hold, Van Loan). Throws std::invalid_argument on settings out of
// range (programmer errors: the io layer validates user input).
class ServoLoop {
 public:
  ServoLoop(const ServoSettings& settings, const AxisValues& start);

  void step(const AxisValues& command);
  // Actual axis values at the current instant (after the last step).
  const AxisValues& position() const { return x_; }
  // Actual axis values at fraction r in [0, 1] of the last period (0: the instant before the
  // last step, 1: position()): linear for an ideal velocity loop (exact), else the quintic
  // Hermite in (x, x', x'') of both ends (error <= max|x^(6)| dT^6 / 46080).
  AxisValues within_last_period(double r) const { return within(s_prev_, s_, r); }
  // The same over the period before the last one (its start two steps back).
  AxisValues within_period_before_last(double r) const { return within(s_prev2_, s_prev_, r); }
  // Largest |velocity| over the axes (mm/s or rad/s): zero at rest.
  double max_speed() const;
  double period_s() const { return dt_; }
  // The largest eigenvalue magnitude of axis j's closed-loop period map (< 1: stable).
  double spectral_radius(int j) const;
  int axis_count() const { return axes_; }

 private:
  struct Axis {
    bool second_order = false;
    double kv = 0.0, ff = 0.0;
    Eigen::Matrix3d phi = Eigen::Matrix3d::Identity();
    Eigen::Vector3d gamma = Eigen::Vector3d::Zero();
  };
  static Axis discretize(const ServoAxis& axis, double dt);
  double dt_ = 0.0;
  int axes_ = 0;
  std::array<Axis, 5> model_{};
  AxisValues within(const std::array<Eigen::Vector3d, 5>& a, const std::array<Eigen::Vector3d, 5>& b, double r) const;
  // (x, x', x'') per axis: now, one and two steps back.
  std::array<Eigen::Vector3d, 5> s_{}, s_prev_{}, s_prev2_{};
  std::array<double, 5> c_prev_{};
  AxisValues x_;
};

// `t_s` strictly ascending time stamps, `commanded` the axis values at those times (linear
// between them, held after the last). The interpolator samples the command every dT from
// t_s[0]; the position controller sets u = Kv (c[k] - x[k]) + ff (c[k] - c[k-1]) / dT,
// held over the period; the velocity loop is integrated exactly over each period. Each
// axis starts at rest on commanded[0]. Returns the actual axis values at the same time
// stamps: exact at the sampling instants; between them linear for an ideal velocity loop
// (also exact) and quintic Hermite in (x, x', x'') for a second-order one (about 1e-5 mm
// after a 1 m/s velocity step at omega_n = 120/s, dT = 5 ms; scales as dT^6).
// `settings.axes` holds one entry for all axes or one per axis. Throws
// std::invalid_argument on empty or mismatched input, non-ascending or non-finite stamps,
// non-finite values or settings out of range (programmer errors: the io layer validates
// user input). Stability (e.g. Kv dT < 2 for an ideal velocity loop) is the caller's.
std::vector<AxisValues> simulate_servo(const std::vector<double>& t_s, const std::vector<AxisValues>& commanded,
                                       const ServoSettings& settings);

}  // namespace vcut::kinematics
