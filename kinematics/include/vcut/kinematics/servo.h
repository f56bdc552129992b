// Servo dynamic path error (ARCHITECTURE §7, seed 004): each machine axis is a sampled
// position loop with gain Kv (1/s) around a second-order velocity loop (natural frequency
// omega_n 1/s, damping zeta), optional velocity feed-forward, run at the interpolation
// period dT on the time-stamped commanded axis trajectory. Out: the actual trajectory.
#pragma once

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
std::vector<AxisValues> simulate_servo(const std::vector<double>& t_s,
                                       const std::vector<AxisValues>& commanded,
                                       const ServoSettings& settings);

}  // namespace vcut::kinematics
