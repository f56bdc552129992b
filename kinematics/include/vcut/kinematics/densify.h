// Densification: the programmed blocks become a sequence of tool poses in the workpiece
// frame (tip in mm, unit axis) whose straight segments follow the controller's path:
// lines as they are (split by a step length if asked), arcs and helices by chords within
// a tolerance. This version handles three-axis programs (tool axis +Z).
#pragma once

#include <Eigen/Core>

#include <vector>

#include "vcut/kinematics/program.h"
#include "vcut/kinematics/tool_pose.h"

namespace vcut::kinematics {

// The motion from the previous sample to this one belongs to `block` (the first sample,
// the start of the first block, has block -1).
struct PoseSample {
  ToolPose pose;
  int block = -1;
};

struct DensifySettings {
  double chord_tolerance_mm = 0.005;  // max distance of an arc chord from its arc
  double step_mm = 0.0;               // lambda: max tip step per sample; 0 = no limit
};

// Number of chords for an arc of radius r (mm) turning angle_rad with chord error <= tol:
// the sagitta of a chord spanning angle a is r (1 - cos(a/2)).
int arc_chord_count(double radius_mm, double angle_rad, double tolerance_mm);

// The swept angle (rad) of an arc block, by the convention of Block.
double arc_angle_rad(const Block& block);

// The point of an arc block at fraction s in [0, 1] of its angle (helix included).
Eigen::Vector3d arc_point(const Block& block, double s);

std::vector<PoseSample> densify(const Program& program, const DensifySettings& settings);

}  // namespace vcut::kinematics
