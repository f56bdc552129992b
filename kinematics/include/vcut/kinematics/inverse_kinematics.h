// Inverse kinematics, one solver for every topology (ARCHITECTURE §4): the rotary angles
// from the tool orientation alone (the two-rotation subproblem, Paden-Kahan 2), then the
// linear axes from a 3x3 linear solve (the tip is affine in them once the angles are fixed).
// Ideal geometry; `compensate` (compensation.h) handles a machine with errors.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/tool_pose.h"

namespace vcut::kinematics {

struct IkSettings {
  // A tool axis within this angle of rotary(0)'s axis is singular: that axis keeps the
  // previous angle. Negative: take the machine's singularity_angle_rad.
  double singularity_angle_rad = -1.0;
  // Tool axes this far from what the rotary axes can reach are unreachable.
  double orientation_tolerance_rad = 1e-7;
  // Optional preference: the named rotary axis should have this sign (+1 or -1).
  char preferred_axis = 0;
  int preferred_sign = 0;
};

enum class IkStatus { Ok, Singular, Unreachable };

struct IkSolution {
  AxisValues q;
  bool within_limits = true;
  std::string violation;  // the first limit it breaks, in words
  int branch = 0;         // 0 or 1: the two orientation branches
};

struct IkResult {
  IkStatus status = IkStatus::Ok;
  // Both branches, every 2 pi winding within limits (at most 4 per axis, those nearest the
  // previous value, when the limits span more turns).
  std::vector<IkSolution> solutions;
  int chosen = -1;     // index into solutions; -1 when unreachable
  std::string reason;  // unreachable: why; singular: what was kept
  // Singular poses: the angle between the requested tool axis and the one reached with the
  // kept free angle (0 elsewhere).
  double orientation_error_rad = 0.0;

  const AxisValues& q() const { return solutions[static_cast<size_t>(chosen)].q; }
  bool ok() const { return chosen >= 0; }
};

// `previous` (may be null): the axis values of the previous pose, for the choice of branch
// and winding (least rotary motion) and the free angle at a singularity. Without it, the
// preferred sign decides, then the angles nearest zero.
IkResult inverse(const Machine& machine, const ToolPose& pose, double tool_length_mm,
                 const AxisValues* previous = nullptr, const IkSettings& settings = {});

// The linear axis values (written into q) that put the tip at `tip_mm` with q's rotary values
// held, ideal geometry; false when the linear axes cannot (a singular 3x3 system).
bool solve_linear_axes(const Machine& machine, AxisValues& q, const Eigen::Vector3d& tip_mm, double tool_length_mm);
// The first axis of q outside its limits, as "axis A limits [-120, 30]: needs 60 deg"; empty
// when every axis is within them.
std::string limit_violation(const Machine& machine, const AxisValues& q);

}  // namespace vcut::kinematics
