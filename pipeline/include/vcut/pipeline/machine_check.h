// The machine in the simulation (issue #25): the machine file's models on their nodes, the
// job's fixtures and the tool's parts posed at every densified pose and checked against each
// other with FCL (BVH of triangles, distance and collision queries): whatever rides on the
// tool side (spindle head, holder, shank, cutter) against the frame (bed, column) and the
// workpiece side (table, trunnion, fixtures; in `vcut check` the head against the stock's
// initial shape, the holder and shank being checked against its box there), and
// the workpiece side against the frame. Between two poses the axes move linearly; a pair is
// proven apart over the whole interval by conservative advancement (the distance changes no
// faster than the bodies' points move, a bound from the axis steps and each body's reach from
// the rotary axes), and the interval is halved where it is not, so that a fast rotary move
// cannot step over a collision.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "vcut/io/job.h"
#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/program_block.h"
#include "vcut/pipeline/poses.h"
#include "vcut/removal/mesh.h"

namespace vcut::pipeline {

// Which part of the machine a body moves with.
enum class BodySide { Tool, Frame, Work };

enum class BodyKind { Model, Fixture, Stock, Cutter, Shank, Holder };

struct MachineContact {
  std::string a, b;  // the two bodies, the tool side's first: "spindle head (Z)", "T1 holder"
  BodyKind a_kind = BodyKind::Model, b_kind = BodyKind::Model;
  bool hit = false;               // the bodies touch or overlap (else a near miss)
  double depth_mm = 0.0;          // hit: the deepest penetration FCL found over the run
  double clearance_mm = 0.0;      // near miss: the smallest distance over the run
  kinematics::SourceRange lines;  // the first block's line to the last's
  int first_block = -1, last_block = -1;
  kinematics::AxisValues axes;                         // at the deepest (closest) instant (mm, rad)
  Eigen::Vector3d where_mm = Eigen::Vector3d::Zero();  // a point of the contact, workpiece frame
  bool between_poses = false;                          // that instant lies between two densified poses
  std::size_t sample = 0;                              // the densified pose at (or just after) that instant
};

struct MachineCheckOptions {
  double clearance_mm = 1.0;  // closer than this: a near miss
  bool stock = false;         // the tool side's machine bodies against the stock's initial shape (`vcut check`)
  bool stock_parts = false;   // with `stock`: the tool's shank and holder too (a stock that is not a box)
  // > 0: MachineCheck::playback is filled, with at most this many frames (and at most
  // 10 times as many tool path points).
  std::size_t playback_frames = 0;
};

// The machine posed along the program, for the report page's playback. Every pose is written
// as 12 floats: the 3 x 4 matrix [R | t] row by row, taking a node's coordinates to the
// workpiece frame (mm).
struct Playback {
  struct Body {
    std::string name;
    BodyKind kind = BodyKind::Model;
    int node = 0;                // index into `nodes`
    int tool = 0;                // a tool's part: its T number (shown while that tool is in the spindle)
    removal::TriangleMesh mesh;  // node coordinates
  };
  std::vector<char> nodes;  // the nodes that carry a body: axis letters, F, W, T
  std::vector<Body> bodies;
  // Frames: the densified poses p * n / max for p < max (all of them when fewer), and the
  // last. Each frame: `nodes.size()` poses, then the workpiece frame in the machine frame F.
  std::vector<std::size_t> frame_sample;
  std::vector<int> frame_block;
  std::vector<int> frame_tool;    // the T number in the spindle (0: none)
  std::vector<float> frame_pose;  // 12 * (nodes.size() + 1) per frame
  // The programmed tool path: the tip of the densified poses (workpiece frame), spread the same
  // way over at most 10 times as many points, each with its block and whether it is a rapid.
  std::vector<float> path_mm;  // x y z per point
  std::vector<int> path_block;
  std::vector<std::uint8_t> path_rapid;
  std::vector<float> contact_pose;  // per contact (MachineCheck::contacts): as a frame, at its instant
  std::size_t floats_per_pose() const { return 12 * (nodes.size() + 1); }
};

struct MachineCheck {
  std::vector<std::string> bodies;       // every body checked, by name
  std::vector<MachineContact> contacts;  // in program order of their first block
  std::size_t pairs = 0;                 // pairs of bodies checked
  std::size_t queries = 0;               // FCL distance queries made (poses and between)
  std::vector<std::string> warnings;     // a fixture in the stock at the start
  Playback playback;                     // with MachineCheckOptions::playback_frames
};

// A mesh file placed in the workpiece frame by its transform (rotations about X, then Y, then
// Z, fixed axes; then the translation).
removal::TriangleMesh placed_mesh(removal::TriangleMesh mesh, const io::DesignSpec& placement);

// Axis values as a person reads them: by letter in the machine's order, linear axes in mm,
// rotary axes in deg.
std::vector<std::pair<char, double>> axis_readout(const kinematics::Machine& machine, const kinematics::AxisValues& q);
// The same as one line: "X0.000 Y-215.000 Z-550.000 A0.000 C0.000".
std::string axis_text(const kinematics::Machine& machine, const kinematics::AxisValues& q);

// The bound the continuous check rests on: while the axes go linearly from q0 to q1 (t from 0
// to 1), no point within radius_mm of center_mm (frame F at q0) on node `node` (an axis letter,
// F, W or T) moves faster than this many mm per unit of t.
double motion_bound_mm(const kinematics::Machine& machine, char node, const Eigen::Vector3d& center_mm,
                       double radius_mm, const kinematics::AxisValues& q0, const kinematics::AxisValues& q1);

// Nothing to check (no models, no fixtures): false. check_machine still poses the tool for
// the playback then.
bool has_machine_bodies(const io::Job& job, const PoseRun& run);

// A streamed run (simulate) is densified again, block by block. A model or fixture that is not
// a closed mesh is a vcut::InputError naming the file.
MachineCheck check_machine(const io::Job& job, const PoseRun& run, const MachineCheckOptions& options);

// check_machine in two steps, so that the check can run beside other work (simulate: after the
// cut, beside the mesh): made, it has read and placed every body (a model or fixture that is not
// a closed mesh stops the run here, before the cut); run(), once, poses them along the program.
// job and run must outlive it.
class MachineChecker {
 public:
  MachineChecker(const io::Job& job, const PoseRun& run, const MachineCheckOptions& options);
  ~MachineChecker();
  MachineChecker(const MachineChecker&) = delete;
  MachineChecker& operator=(const MachineChecker&) = delete;
  MachineCheck run();

 private:
  struct Parts;
  std::unique_ptr<Parts> parts_;
};

}  // namespace vcut::pipeline
