// Axis specs for the kinematics tests' hand-built machines.
#pragma once

#include <Eigen/Core>

#include "vcut/kinematics/machine.h"

namespace vcut::kinematics::test {

inline AxisSpec linear(char letter, const Eigen::Vector3d& direction) {
  AxisSpec a;
  a.letter = letter;
  a.kind = AxisKind::Linear;
  a.direction = direction;
  return a;
}

// Turning about the line (center, axis) by the right-hand rule.
inline AxisSpec rotary(char letter, const Eigen::Vector3d& axis, const Eigen::Vector3d& center) {
  AxisSpec a;
  a.letter = letter;
  a.kind = AxisKind::Rotary;
  a.direction = axis;
  a.center_mm = center;
  return a;
}

}  // namespace vcut::kinematics::test
