// A move: the rigid motion of the cutter between two consecutive tool poses in the
// workpiece frame (mm). This version moves the cutter by pure translation (tool axis
// constant); the block index leads back to the NC line.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "vcut/removal/cutter.h"

namespace vcut::removal {

struct Move {
  Eigen::Vector3d start_mm = Eigen::Vector3d::Zero();  // tool tip
  Eigen::Vector3d end_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, tip -> spindle
  int cutter = 0;      // index into MoveList::cutters
  int block = -1;      // index of the NC block it came from
  bool rapid = false;  // rapids never cut: touching material is a collision
};

struct MoveList {
  std::vector<Cutter> cutters;
  std::vector<Move> moves;
};

}  // namespace vcut::removal
