// Densification (ARCHITECTURE §5, seed 000 §3): the programmed blocks become a sequence of
// tool poses in the workpiece frame (tip in mm, unit axis) whose moves follow the
// controller's interpolation. Per block q = max(1, ceil(L / lambda), ceil(theta / phi)) (and
// arcs by a chord tolerance), or in tolerance mode the q that keeps every point of the
// cutter within epsilon of the controller's path. Orientation as the 840D does it: ORIVECT
// (great circle, Rodrigues rotation), ORIAXES (rotary axes linear), ORICONE (about a cone
// axis); axis programs interpolate the axes linearly and the tip follows from the machine.
#pragma once

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

#include "vcut/kinematics/inverse_kinematics.h"
#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/program.h"
#include "vcut/kinematics/tool_pose.h"

namespace vcut::kinematics {

// The motion from the previous sample to this one belongs to `block` (the first sample,
// the start of the first block, has block -1).
struct PoseSample {
  ToolPose pose;
  int block = -1;
  AxisValues axes;        // machine axis values (mm, rad) when densified with a machine
  bool singular = false;  // the inverse kinematics kept a free angle here
};

struct DensifySettings {
  double chord_tolerance_mm = 0.005;  // max distance of an arc chord from its arc
  double step_mm = 0.0;               // lambda: max tip step per sample; 0 = no limit
  double angle_step_rad = 0.0;        // phi: max orientation step per sample; 0 = no limit
  // Tolerance mode (> 0 replaces lambda, phi and the chord tolerance): every point of the
  // cutting part (up to cutter_length_mm above the tip, cutter_radius_mm off the axis) stays
  // within this distance of where the controller's interpolation puts it.
  double tolerance_mm = 0.0;
  double cutter_length_mm = 0.0;
  double cutter_radius_mm = 0.0;
  // Tolerance mode: arcs also get at least the chord tolerance's count (vcut's default
  // densification, where the chord tolerance is the finer of the two).
  bool arcs_by_chord = false;
};

// The machine side of densification: needed for axis programs, ORIAXES and axis values.
struct DensifyMachine {
  const Machine* machine = nullptr;
  std::map<int, double> tool_length_mm;  // by T number (spindle nose to tip); missing = 0
  IkSettings ik;
};

struct BlockReport {
  int q = 1;  // moves this block was split into
  // Axis programs: the largest distance of the tip's path (forward kinematics of linearly
  // interpolated axes) from the straight line between the block's end points, and where.
  double nonlinear_error_mm = 0.0;
  Eigen::Vector3d nonlinear_at_mm = Eigen::Vector3d::Zero();
  // Outside tolerance mode: the largest distance of the controller's tip path from the
  // densified moves' chords (what a too coarse step or angle leaves), and where. 0 for a
  // straight tip path.
  double chord_error_mm = 0.0;
  Eigen::Vector3d chord_error_at_mm = Eigen::Vector3d::Zero();
  bool singular = false;           // a pose of this block is singular (free angle kept)
  double singular_miss_rad = 0.0;  // the largest tool-axis miss that keeping it caused
  std::string unreachable;         // why a pose of this block cannot be reached ("" = all reached)
  std::string note;                // e.g. ORIAXES without a machine, done as ORIVECT
};

struct Densified {
  std::vector<PoseSample> samples;
  std::vector<BlockReport> blocks;  // one per program block
};

// Number of chords for an arc of radius r (mm) turning angle_rad with chord error <= tol:
// the sagitta of a chord spanning angle a is r (1 - cos(a/2)).
int arc_chord_count(double radius_mm, double angle_rad, double tolerance_mm);

// The swept angle (rad) of an arc block, by the convention of Block.
double arc_angle_rad(const Block& block);

// An arc block's radius in its plane (the start's distance from the axis) and the length of
// its tip path (helix included), mm.
double arc_radius_mm(const Block& block);
double arc_length_mm(const Block& block);

// The point of an arc block at fraction s in [0, 1] of its angle (helix included).
Eigen::Vector3d arc_point(const Block& block, double s);

// ORIVECT: the unit vector at fraction s of the great circle from u0 to u1 (Rodrigues
// rotation about u0 x u1, seed 000 eqs. 2-4). Opposite vectors turn about a fixed
// perpendicular.
Eigen::Vector3d great_circle(const Eigen::Vector3d& u0, const Eigen::Vector3d& u1, double s);

// The controller's pose of a block at fraction s in [0, 1] (tool-pose blocks; for axis
// blocks and ORIAXES see densify). Exposed for tests and the tolerance search.
ToolPose block_pose(const Block& block, double s);

// Densification one block at a time, in program order, holding only the last sample (the
// axis values the next block's inverse kinematics starts from): what densify() does, for a
// caller that streams the samples instead of keeping them. rewind() starts again from the
// program's start; the samples are the same bytes every time.
class Densifier {
 public:
  // The program (and the machine DensifyMachine points to) must outlive the densifier.
  // poses_only: the machine's axis values only where a pose needs them (axis programs); the
  // inverse kinematics of tool poses is skipped, their axes and singular flags left as they
  // were. Only for programs where no block starts from the previous axes (uses_start_axes).
  Densifier(const Program& program, const DensifySettings& settings, const DensifyMachine& machine,
            bool poses_only = false);
  // Sample 0: the first block's start (block -1).
  const PoseSample& start() const { return start_; }
  // Block next_index()'s samples appended to out, and its report (block 0's carries the
  // start's unreachable reason).
  void next_block(std::vector<PoseSample>& out, BlockReport& report);
  std::size_t next_index() const { return next_; }
  bool done() const { return next_ >= program_.blocks.size(); }
  // The last sample made (the start before the first block).
  const PoseSample& last() const { return last_; }
  void rewind();

 private:
  const Program& program_;
  DensifySettings settings_;
  DensifyMachine dm_;
  PoseSample start_, last_;
  std::string start_unreachable_;
  std::size_t next_ = 0;
  bool poses_only_ = false;
};

// Whether a block's poses start from the machine's axis values at its start (TCP rotary words,
// ORIAXES turning the tool): the previous block's inverse kinematics then shapes its path.
bool uses_start_axes(const Block& block);

Densified densify(const Program& program, const DensifySettings& settings, const DensifyMachine& machine);

// Three-axis convenience: no machine, poses only.
std::vector<PoseSample> densify(const Program& program, const DensifySettings& settings);

}  // namespace vcut::kinematics
