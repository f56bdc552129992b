// The canonical motion list of an NC program: one Block per programmed motion, in the
// workpiece frame (mm, after work offsets and unit conversion), each with its source line.
// Readers (vcut::io) produce it; densification and cutting consume it.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace vcut::kinematics {

enum class MotionKind { Rapid, Linear, Arc };
enum class SpindleState { Off, Clockwise, CounterClockwise };
enum class FeedMode { UnitsPerMinute, InverseTime };

// Where a block came from: an index into Program::files and a 1-based line number.
struct SourceRef {
  int file = 0;
  int line = 0;
};

struct Block {
  MotionKind kind = MotionKind::Linear;
  Eigen::Vector3d start_mm = Eigen::Vector3d::Zero();  // tool tip before the motion
  Eigen::Vector3d end_mm = Eigen::Vector3d::Zero();    // tool tip after the motion
  // Arcs only. The tip turns about the line (center_mm, normal) by the right-hand rule
  // (G2 in G17 has normal -Z, G3 has +Z). The swept angle is the angle from start to end
  // in (0, 2*pi] about normal, plus 2*pi for each turn beyond the first; the component
  // along normal (helix) changes linearly with the angle. center_mm lies in the plane of
  // start_mm perpendicular to normal.
  Eigen::Vector3d center_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int turns = 1;
  double feed_mm_per_min = 0.0;  // 0 for rapids
  FeedMode feed_mode = FeedMode::UnitsPerMinute;
  int tool = 0;                  // T number in the spindle (0 = none)
  SpindleState spindle = SpindleState::Off;
  double spindle_rpm = 0.0;
  SourceRef source;
};

struct Program {
  std::vector<std::string> files;  // files[SourceRef::file]
  std::vector<Block> blocks;
  std::vector<std::string> warnings;  // "file:line:col: message"

  std::string where(const SourceRef& ref) const {
    return files.at(static_cast<size_t>(ref.file)) + ":" + std::to_string(ref.line);
  }
};

}  // namespace vcut::kinematics
