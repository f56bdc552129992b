// The controller's interpolator and position loops (ARCHITECTURE §5 and §7, seed 004): every
// interpolation period dT along the timed path (the feed profile inside each block, not only
// at the densified poses) the commanded axis values, with a servo model the actual ones after
// each axis's loop, the actual tool pose through forward kinematics (ideal or with the
// machine's geometric errors), and the contour error: the distance of the actual tip from the
// commanded tip path. Units: mm, rad, s.
#pragma once

#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

#include "vcut/kinematics/densify.h"
#include "vcut/kinematics/feed_planner.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/program.h"
#include "vcut/kinematics/servo.h"
#include "vcut/kinematics/tool_pose.h"

namespace vcut::kinematics {

struct InterpolatorInput {
  const Program* program = nullptr;
  const std::vector<PoseSample>* samples = nullptr;  // densified, with axis values
  const std::vector<BlockReport>* blocks = nullptr;  // densify's reports (q of each block)
  const FeedPlan* feed = nullptr;                    // their time stamps and timing
  const Machine* machine = nullptr;
  const std::vector<double>* tool_length_mm = nullptr;  // per sample
  ServoSettings servo;                                  // its period is the interpolation period
  Geometry geometry = Geometry::Ideal;
  IkSettings ik;                // the inverse kinematics of TCP moves between samples (densify's settings)
  bool commanded_pose = false;  // also the commanded tool pose (forward kinematics) per period
  // After the program's end the loops run on until every axis is within this of its last
  // command and at rest (mm or rad; mm/s or rad/s), at most settle_max_s.
  double settle_tolerance = 1e-6;
  double settle_max_s = 5.0;
};

struct PeriodSample {
  double t_s = 0.0;
  std::size_t segment = 1;  // the densified move being interpolated: samples[segment - 1] -> [segment]
  int block = 0;            // its program block (the block being commanded)
  bool feed = true;         // not a rapid
  // A densified sample's own instant (poses.csv's actual columns): its index; -1 for an
  // interpolation period. The loops' state between two periods comes from the quintic
  // Hermite of ServoLoop::within_last_period.
  long long stamp = -1;
  // A local maximum of the contour error between the instants (the actual path is
  // continuous; at 40 m/min it moves 3 mm in a 5 ms period): found by golden section over
  // the two periods around an instant whose error exceeds both neighbours', and visited
  // right after the period that revealed it. Only for the largest error, not for RMS.
  bool peak = false;
  AxisValues commanded, actual;  // mm, rad
  ToolPose commanded_pose;       // when InterpolatorInput::commanded_pose
  ToolPose actual_pose;
  double contour_error_mm = 0.0;    // actual tip from the commanded tip path
  std::size_t nearest_segment = 1;  // the densified move whose path is nearest the actual tip
};

// Visits every period from t = 0 to the end of the program plus the settling, in time
// order, interleaved with the densified samples' own instants (stamp >= 0) and the contour
// error's peaks between instants (peak). Returns the number of periods. The commanded path for the
// contour error is each block's true path where it is known in closed form (lines; arcs and helices
// of tool-pose blocks; the machine's curve of an axis block, from its axes), otherwise the
// densified polyline.
std::size_t for_each_period(const InterpolatorInput& input, const std::function<void(const PeriodSample&)>& visit);

// The commanded path near a point (used by for_each_period, exposed for tests): the
// distance from p to the densified path's moves lo..hi (indices of their end samples),
// refined on the true path of the nearest one.
class CommandedPath {
 public:
  CommandedPath(const Program& program, const std::vector<PoseSample>& samples, const std::vector<BlockReport>& blocks,
                const Machine* machine, const std::vector<double>* tool_length_mm);
  double distance(const Eigen::Vector3d& p, std::size_t lo, std::size_t hi, std::size_t* nearest) const;
  // The moves [lo, hi] to search for an actual tip: the lag runs along the path, so from a
  // few moves before the one found nearest last to a couple beyond the one commanded.
  std::pair<std::size_t, std::size_t> window(std::size_t nearest_last, std::size_t commanded) const;

 private:
  double refine(const Eigen::Vector3d& p, std::size_t k, double polyline) const;
  const Program& program_;
  const std::vector<PoseSample>& samples_;
  const Machine* machine_;
  const std::vector<double>* tool_length_mm_;
  std::vector<double> param_;  // per sample: its fraction of its block (densify's k / q)
};

}  // namespace vcut::kinematics
