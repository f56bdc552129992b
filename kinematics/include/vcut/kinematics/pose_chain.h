// The pose engine on a program, in one call: densified tool poses with axis values -> time
// stamps (jerk-limited feed with look-ahead) -> with a servo, every interpolation period of the
// loops; with geometric errors, the actual poses -> the actual path the machine cuts with, and
// the contour error. pipeline::run_pose_engine (a job) and the benchmarks both run this.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <vector>

#include "vcut/kinematics/densify.h"
#include "vcut/kinematics/feed_planner.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/interpolator.h"
#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/program.h"
#include "vcut/kinematics/servo.h"

namespace vcut::kinematics {

struct PoseChainSettings {
  DensifySettings densify;
  FeedSettings feed;
  std::optional<ServoSettings> servo;   // present: servo lag, every interpolation period
  Geometry geometry = Geometry::Ideal;  // Actual: the machine's geometric errors on every pose
  // With servo: the thinned actual path keeps every period's tool (tip, and the axis over
  // densify.cutter_length_mm) within this of its chords (mm).
  double actual_path_tolerance_mm = 0.0;
  // With servo: called with the feed plan before the first period (it may throw to refuse a
  // run that would take too many periods).
  std::function<void(const FeedPlan&)> before_servo;
};

struct PoseChain {
  Densified densified;
  FeedPlan feed;
  std::vector<double> tool_length_mm;  // per sample (0 before the first tool)
  // Servo and/or geometric errors: the actual pose per sample and the distance of its tip
  // from the commanded path (um). Empty when neither is on.
  std::vector<ToolPose> actual;
  std::vector<double> contour_error_um;
  // What the machine cuts with servo or errors on: with servo the actual path at every
  // interpolation period, thinned so that no dropped period's tool (tip, and the tool axis
  // over the flute length) lies farther than actual_path_tolerance_mm from the chord kept;
  // with errors only the actual pose of every sample. Each pose's block is the block of the
  // commanded path nearest the actual tip: where the tool is, not what is being commanded
  // (the lag still finishes a cut while the interpolator starts the retract). Empty when
  // neither is on.
  struct ActualPose {
    ToolPose pose;
    int block = -1;
  };
  std::vector<ActualPose> actual_path;
  double actual_path_tolerance_mm = 0.0;
  std::size_t periods = 0;  // interpolation periods simulated (servo)
  // Per program block (servo or errors): the contour error over its periods (servo; a period
  // counts for the block nearest the actual tip) or its samples (errors only), feed moves and
  // rapids alike; at_mm where the largest was.
  struct BlockContour {
    double max_um = 0.0, rms_um = 0.0;
    Eigen::Vector3d at_mm = Eigen::Vector3d::Zero();
    std::size_t count = 0;
  };
  std::vector<BlockContour> block_contour;
  // Over feed moves (rapids cut corners by design): the largest contour error and its block,
  // and the RMS.
  double max_contour_error_um = 0.0;
  int max_contour_block = -1;
  double rms_contour_error_um = 0.0;
};

// Every interpolation period of a servo run, as the interpolator gives it.
using PeriodVisitor = std::function<void(const PeriodSample&)>;

// tool_length_mm: the gauge length of every tool the program uses, by T number.
PoseChain run_pose_chain(const Program& program, const Machine& machine, const std::map<int, double>& tool_length_mm,
                         const PoseChainSettings& settings, const PeriodVisitor* every_period = nullptr);

}  // namespace vcut::kinematics
