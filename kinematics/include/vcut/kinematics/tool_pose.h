// A tool pose (ARCHITECTURE §2): the tip (control point) in mm and the unit tool axis
// pointing from the tip toward the spindle, both in the workpiece frame.
#pragma once

#include <Eigen/Core>

namespace vcut::kinematics {

struct ToolPose {
  Eigen::Vector3d tip_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, tip -> spindle
};

}  // namespace vcut::kinematics
