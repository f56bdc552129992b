// Error compensation (ARCHITECTURE §6): the axis commands whose error-aware forward
// kinematics give the nominal tool pose, by Gauss-Newton on the numerical Jacobian,
// started from the ideal inverse kinematics.
#pragma once

#include <string>

#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/tool_pose.h"

namespace vcut::kinematics {

// Target residuals: 0.01 um at the tip and 0.01 urad on the axis.
constexpr double kCompensationTipToleranceMm = 1e-5;
constexpr double kCompensationAxisToleranceRad = 1e-8;

struct CompensationResult {
  bool converged = false;
  AxisValues q;                  // compensated axis commands (mm, rad)
  double residual_tip_um = 0.0;  // |actual tip - nominal tip| at q
  double residual_axis_urad = 0.0;
  int iterations = 0;
  std::string note;  // why it did not converge, or what could not be compensated
};

// `start`: the ideal inverse kinematics' solution for `nominal` (the branch to stay on).
// With fewer than two rotary axes the orientation cannot be corrected: only the tip is,
// and the note says so.
CompensationResult compensate(const Machine& machine, const ToolPose& nominal, double tool_length_mm,
                              const AxisValues& start);

}  // namespace vcut::kinematics
