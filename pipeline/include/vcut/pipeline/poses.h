// The pose engine run on a job (ARCHITECTURE §1, issue #5): program -> densified tool poses
// with axis values -> time stamps (jerk-limited feed with look-ahead) -> optional servo lag
// and geometric errors -> actual poses and contour error. `vcut poses` writes it as CSV.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vcut/io/job.h"
#include "vcut/io/program_reader.h"
#include "vcut/kinematics/densify.h"
#include "vcut/kinematics/feed_planner.h"
#include "vcut/kinematics/interpolator.h"
#include "vcut/kinematics/pose_chain.h"
#include "vcut/kinematics/program.h"

namespace vcut::pipeline {

// A block-level finding with its NC line: an axis limit, a singular pose, a limited speed.
enum class PoseEventKind { Unreachable, Singular, AxisLimitedSpeed, DensifyError };
// "unreachable", "singular", "axis_limited_speed", "densify_error": as the reports write it.
const char* to_string(PoseEventKind kind);

struct PoseEvent {
  PoseEventKind kind = PoseEventKind::Unreachable;
  kinematics::SourceRange lines;  // written by Program::where: "file:line", "file:first-last", "a:12 to b:3"
  std::string detail;
  int first_block = -1, last_block = -1;  // the blocks it names
};

// The job's program files read into one Program (file names relative to the job), and the
// tools: the library, plus APT CUTTER/ shapes for T numbers the library lacks.
struct JobProgram {
  kinematics::Program program;
  io::ToolLibrary tools;
  io::ProgramReader reader = io::ProgramReader::Gcode;  // the reader used
};
JobProgram read_job_program(const io::Job& job);

// The pose chain (kinematics::run_pose_chain) on a job's program, with what the job adds:
// its tools, findings with their NC lines, and the summary.
struct PoseRun : kinematics::PoseChain {
  kinematics::Program program;
  io::ToolLibrary tools;
  io::ProgramReader reader = io::ProgramReader::Gcode;  // of the program
  std::vector<PoseEvent> events;
  // Findings a user must see (terminal, report.json warnings, the page's events): a block
  // whose densification leaves it farther from the machine's path than the gouge tolerance.
  std::vector<std::string> warnings;
  // Streamed (simulate and study without servo or machine errors): densified.samples and the
  // feed plan's per-sample arrays stay empty; the poses are densified again, from the program,
  // wherever they are needed (CutMoves), so that memory does not grow with them. `poses`,
  // feed.cycle_time_s and the timeline are there either way.
  bool streamed = false;
  // A streamed run whose passes are still to come (run_pose_engine's stream_passes_later):
  // until finish_pose_run, `poses`, `events`, `warnings`, feed.cycle_time_s, the timeline and
  // the summary are not filled.
  bool passes_pending = false;
  std::size_t poses = 0;        // densified poses (samples)
  bool poses_need_axes = true;  // a block starts from the previous axes (kinematics::uses_start_axes)
  std::shared_ptr<const kinematics::Machine> machine;
  kinematics::DensifySettings densify_settings;
  kinematics::DensifyMachine densify_machine;  // its machine is *machine
  // Time, feed and contour error (with servo or errors) at most 4,000 samples: sample
  // p * n / 4000 for point p of n samples (or, with a contour error, the one with the largest
  // error up to the next point's), for the page.
  struct Timeline {
    std::vector<double> t_s, speed_mm_per_s, contour_error_um;
    std::vector<std::size_t> sample;  // the sample of each point
  } timeline;
  // Summary.
  double max_nonlinear_error_mm = 0.0;
  std::optional<kinematics::SourceRef> max_nonlinear_line;
  std::optional<kinematics::SourceRef> max_contour_line;  // of PoseChain::max_contour_block
  int q_min = 0, q_max = 0;
  double q_mean = 0.0;
};

// Every interpolation period of a servo run (vcut poses --every-period streams them to a file).
using PeriodVisitor = kinematics::PeriodVisitor;

PoseRun run_pose_engine(const io::Job& job, const PeriodVisitor* every_period = nullptr);
// With the program already read; `resolution_mm` sets the default densification (the arc
// chord tolerance resolution / 20, the tolerance mode's min(resolution / 10, gouge / 2)).
// stream: without servo and errors, a streamed run (PoseRun::streamed). stream_passes_later:
// such a run comes back before its two passes over the program (PoseRun::passes_pending), which
// finish_pose_run then makes (simulate: after the cut, beside the mesh; the moves, CutMoves,
// need nothing the passes find).
PoseRun run_pose_engine(const io::Job& job, JobProgram program, double resolution_mm,
                        const PeriodVisitor* every_period = nullptr, bool stream = false,
                        bool stream_passes_later = false);
// The passes a streamed run made with stream_passes_later still owes (none: nothing to do).
void finish_pose_run(const io::Job& job, PoseRun& run);

// How F reads in axis blocks: the machine file's feed_interpretation, else by the job's
// dialect (fanuc: combined; apt: tip; G-code and SINUMERIK: linuxcnc). `reader` is the
// reader used (JobProgram::reader).
kinematics::FeedInterpretation axis_feed_of(const io::Job& job, io::ProgramReader reader);
const char* feed_interpretation_name(kinematics::FeedInterpretation f);

// The arc chord tolerance: the job's, else resolution / 20 (mm).
double chord_tolerance_mm(const io::Job& job, double resolution_mm);
// How far the pieces of a turning move may leave the rigid motion (mm): engine.turn_tolerance,
// else default_densify_tolerance_mm (min(v / 10, gouge tolerance / 2)).
double turn_tolerance_mm(const io::Job& job, double resolution_mm);
// The densification tolerance when the job gives no `densify:` (issue #20): min(v / 10,
// gouge tolerance / 2), v the resolution (mm).
double default_densify_tolerance_mm(const io::Job& job, double resolution_mm);

}  // namespace vcut::pipeline
