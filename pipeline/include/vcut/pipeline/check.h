// `vcut check`: everything but the cut, as a fast go/no-go before a long simulation or a
// real machine. Reads the program, densifies and times it on the machine, and checks reach,
// axis limits, singular poses, tools, the spindle, and the tool's clearance against the
// stock's bounding box (the stock is not cut, so a pass through a pocket the program has
// already made shows as a possible collision: the simulation settles it). With the machine's
// bodies (machine_check.h) also the machine, fixtures and holder against each other, the
// spindle head against the stock's initial shape, and where the stock is not a box, the
// shank and holder against its shape instead of its box.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "vcut/io/job.h"
#include "vcut/pipeline/poses.h"

namespace vcut::pipeline {

enum class Severity { Error, Warning, Note };
const char* to_string(Severity severity);

// What an event found: the pose engine's findings (PoseEventKind), then the check's own.
enum class CheckKind {
  Unreachable,
  Singular,
  AxisLimitedSpeed,
  DensifyError,
  NoTool,
  RapidInStockBox,
  SpindleStoppedFeed,
  ShankInStockBox,
  HolderInStockBox,
  MachineCollision,  // two bodies of the machine, fixture or tool touch (an error)
  MachineNearMiss,   // closer than report.machine_clearance
  BodyInStock,       // the tool's holder or shank, or a machine body, inside the stock's initial shape
};
// As check.json writes it: "unreachable" ... "densify_error" (PoseEventKind's names), "no_tool",
// "rapid_in_stock_box", "spindle_stopped_feed", "shank_in_stock_box", "holder_in_stock_box",
// "machine_collision", "machine_near_miss", "body_in_stock".
const char* to_string(CheckKind kind);
CheckKind check_kind(PoseEventKind kind);

struct CheckEvent {
  Severity severity = Severity::Warning;
  CheckKind kind = CheckKind::Unreachable;
  kinematics::SourceRange lines;  // the first block's line to the last's in that file
  std::string detail;
  double depth_mm = 0.0;  // how far into the stock's box (0 where it does not apply)
  Eigen::Vector3d where_mm = Eigen::Vector3d::Zero();
  bool has_where = false;
  // Machine checks: the two bodies, the smallest distance (near misses), the axes at the
  // deepest or closest instant (mm, rad; machine axis order) and whether it lies between poses.
  std::vector<std::string> bodies;
  double clearance_mm = 0.0;
  kinematics::AxisValues axes;
  bool between_poses = false;
};

// Per tool: the lowest its holder comes to the stock's top face over the stock's footprint.
struct ToolClearance {
  int tool = 0;
  bool has_holder = false;
  double holder_clearance_mm = 0.0;  // min (holder face z - stock top z) over moves above the stock; < 0 enters
  std::optional<kinematics::SourceRef> holder_line;  // where that minimum is
  bool over_stock = false;                           // the tool ever came over the stock's footprint
};

struct CheckResult {
  PoseRun run;
  Eigen::AlignedBox3d stock_box;
  std::vector<CheckEvent> events;  // in program order of their first line
  std::vector<ToolClearance> tools;
  std::size_t errors = 0, warnings = 0;
  // The machine check (where the machine file has models or the job fixtures).
  bool machine_checked = false;
  std::vector<std::string> bodies;
  std::size_t body_pairs = 0, body_queries = 0;
  double machine_seconds = 0.0;
  std::vector<std::string> notes;  // a fixture in the stock at the start
  double wall_time_s = 0.0;
};

// Bad input (job, program, machine, tools) is a vcut::InputError as for simulate.
CheckResult run_check(const io::Job& job);

}  // namespace vcut::pipeline
