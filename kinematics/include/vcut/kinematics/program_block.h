// One programmed motion of an NC program (program.h): its kind, end points, orientation, feed
// and source line, in the workpiece frame (mm, after work offsets and unit conversion).
#pragma once

#include <Eigen/Core>

#include <array>

namespace vcut::kinematics {

enum class MotionKind { Rapid, Linear, Arc };
enum class SpindleState { Off, Clockwise, CounterClockwise };
enum class FeedMode { UnitsPerMinute, InverseTime };
// How the tool orientation moves within a block (SINUMERIK 840D names, seed 000 §3):
// Axes: the rotary axes interpolate linearly (ORIAXES; also every axis program);
// Vector: the tool axis turns on the great circle from start to end (ORIVECT);
// ConeClockwise / ConeCounterClockwise: it turns about Block::cone_axis (ORICONCW/CCW).
enum class OrientationMode { Axes, Vector, ConeClockwise, ConeCounterClockwise };

// Rotary words A B C as programmed (rad, index 0 1 2); `given` says which were.
struct RotaryWords {
  std::array<double, 3> angle_rad = {0.0, 0.0, 0.0};
  std::array<bool, 3> given = {false, false, false};
  bool any() const { return given[0] || given[1] || given[2]; }
};

// Extra linear axes U V W as programmed (mm, work offsets applied, index 0 1 2); `given` says
// which were. LinuxCNC's interpreter moves them with X Y Z (9-axis machines: a quill, a
// second carriage); `vcut program` lists them, a job refuses them (its machines have none).
struct ExtraAxes {
  std::array<double, 3> value_mm = {0.0, 0.0, 0.0};
  std::array<bool, 3> given = {false, false, false};
  bool any() const { return given[0] || given[1] || given[2]; }
};

// Where a block came from: an index into Program::files and a 1-based line number.
struct SourceRef {
  int file = 0;
  int line = 0;
};

// Lines first..last of one program file (a run of blocks, a merged region's lines).
struct SourceSpan {
  int file = 0;
  int first_line = 0, last_line = 0;
};

// From one line to another, possibly in another file (a run of blocks that a subprogram call
// or a second program file splits): what a finding names.
struct SourceRange {
  SourceRef first, last;
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
  // Tool orientation. Tool-pose blocks (every three-axis program, TCP, TRAORI, APT):
  // start_mm/end_mm are tips and start_axis/end_axis tool axes, both in the workpiece frame.
  // Axis blocks (tool_pose false: rotary words without TCP): start_mm/end_mm are the
  // programmed X Y Z, the rotary words are axis values, and the tip follows from the machine.
  bool tool_pose = true;
  Eigen::Vector3d start_axis = Eigen::Vector3d::UnitZ();  // unit, tip -> spindle
  Eigen::Vector3d end_axis = Eigen::Vector3d::UnitZ();
  RotaryWords start_rotary, end_rotary;
  ExtraAxes start_extra, end_extra;  // U V W (G-code only; none given in most programs)
  OrientationMode orientation = OrientationMode::Vector;
  Eigen::Vector3d cone_axis = Eigen::Vector3d::Zero();  // Cone modes: unit axis of the cone
  double feed_mm_per_min = 0.0;  // 0 for rapids; InverseTime: 1 / F is the block's time in minutes
  FeedMode feed_mode = FeedMode::UnitsPerMinute;
  bool exact_stop = false;           // G61 / G9 / G60: the path stops at the end of this block
  double blend_tolerance_mm = -1.0;  // G64 P: allowed path deviation at the junction; < 0: none given
  int tool = 0;                      // T number in the spindle (0 = none)
  SpindleState spindle = SpindleState::Off;
  double spindle_rpm = 0.0;
  SourceRef source;
};

}  // namespace vcut::kinematics
