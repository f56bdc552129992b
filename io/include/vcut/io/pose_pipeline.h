// The pose engine run on a job (ARCHITECTURE §1, issue #5): program -> densified tool poses
// with axis values -> time stamps (jerk-limited feed with look-ahead) -> optional servo lag
// and geometric errors -> actual poses and contour error. `vcut poses` writes it as CSV.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "vcut/io/job.h"
#include "vcut/kinematics/densify.h"
#include "vcut/kinematics/feed_planner.h"
#include "vcut/kinematics/interpolator.h"
#include "vcut/kinematics/program.h"

namespace vcut::io {

// A block-level finding with its NC line: an axis limit, a singular pose, a limited speed.
struct PoseEvent {
  std::string kind;  // "unreachable", "singular", "axis_limited_speed"
  std::string line;  // "file:line"
  std::string detail;
};

// The job's program files read into one Program (file names relative to the job), and the
// tools: the library, plus APT CUTTER/ shapes for T numbers the library lacks.
struct JobProgram {
  kinematics::Program program;
  ToolLibrary tools;
  std::string dialect;  // the reader used: "gcode" or "apt"
};
JobProgram read_job_program(const Job& job);

struct PoseRun {
  kinematics::Program program;
  ToolLibrary tools;
  std::string dialect;  // of the program: "gcode" or "apt"
  kinematics::Densified densified;
  kinematics::FeedPlan feed;
  std::vector<double> tool_length_mm;  // per sample (0 before the first tool)
  // Servo and/or geometric errors: the actual pose per sample and the distance of its tip
  // from the commanded path (um). Empty when neither is on.
  std::vector<kinematics::ToolPose> actual;
  std::vector<double> contour_error_um;
  // What the machine cuts with servo or errors on: with servo the actual path at every
  // interpolation period, thinned so that no dropped period's tool (tip, and the tool axis
  // over the flute length) lies farther than actual_path_tolerance_mm from the chord kept;
  // with errors only the actual pose of every sample. Each pose's block is the block of the
  // commanded path nearest the actual tip: where the tool is, not what is being commanded
  // (the lag still finishes a cut while the interpolator starts the retract). Empty when
  // neither is on.
  struct ActualPose {
    kinematics::ToolPose pose;
    int block = -1;
  };
  std::vector<ActualPose> actual_path;
  double actual_path_tolerance_mm = 0.0;
  std::size_t periods = 0;  // interpolation periods simulated (servo)
  // Per program block (servo or errors): the contour error over its periods (servo; a period
  // counts for the block nearest the actual tip) or its samples (errors only), feed moves and
  // rapids alike; at_mm where the largest was.
  struct BlockContour {
    double max_um = 0.0, rms_um = 0.0;
    Eigen::Vector3d at_mm = Eigen::Vector3d::Zero();
    std::size_t count = 0;
  };
  std::vector<BlockContour> block_contour;
  std::vector<PoseEvent> events;
  // Findings a user must see (terminal, report.json warnings, the page's events): a block
  // whose densification leaves it farther from the machine's path than the gouge tolerance.
  std::vector<std::string> warnings;
  // Summary.
  double max_nonlinear_error_mm = 0.0;
  std::string max_nonlinear_line;
  double max_contour_error_um = 0.0;
  std::string max_contour_line;
  double rms_contour_error_um = 0.0;
  int q_min = 0, q_max = 0;
  double q_mean = 0.0;
};

// Every interpolation period of a servo run, as the interpolator gives it (vcut poses
// --every-period streams them to a file).
using PeriodVisitor = std::function<void(const kinematics::PeriodSample&)>;

PoseRun run_pose_engine(const Job& job, const PeriodVisitor* every_period = nullptr);
// With the program already read; `resolution_mm` sets the default densification (the arc
// chord tolerance resolution / 20, the tolerance mode's min(resolution / 10, gouge / 2)).
PoseRun run_pose_engine(const Job& job, JobProgram program, double resolution_mm,
                        const PeriodVisitor* every_period = nullptr);

// How F reads in axis blocks: the machine file's feed_interpretation, else by the job's
// dialect (fanuc: combined; apt: tip; G-code and SINUMERIK: linuxcnc). `reader` is the
// reader used (JobProgram::dialect).
kinematics::FeedInterpretation axis_feed_of(const Job& job, const std::string& reader);
const char* feed_interpretation_name(kinematics::FeedInterpretation f);

// The densification tolerance when the job gives no `densify:` (issue #20): min(v / 10,
// gouge tolerance / 2), v the resolution (mm).
double default_densify_tolerance_mm(const Job& job, double resolution_mm);

// The pose engine with every interpolation period of the servo streamed into a CSV at
// `periods_path` (vcut poses --every-period): t, block, source, the commanded and the actual
// axis values by letter (mm, deg), commanded tip, actual tip and tool axis, contour_error_um.
// Written atomically (the file appears when the run is done); an InputError when the job has
// no servo.
PoseRun run_pose_engine_with_periods(const Job& job, const std::string& periods_path);

// One row per program block: block, source, kind, q, time_s, nonlinear_error_mm (and where),
// singular, unreachable, and with servo or errors the contour error of its interpolation
// periods (servo) or its poses (errors only): max, RMS, where. Written atomically.
void write_blocks_csv(const std::string& path, const Job& job, const PoseRun& run);

// One row per densified pose: block, source, t, x y z (tip), i j k (axis), the axis values by
// letter (mm, deg), feed (mm/min); with servo or errors also actual_x .. actual_k and
// contour_error_um. Written atomically.
void write_poses_csv(const std::string& path, const Job& job, const PoseRun& run);

// `vcut compensate`: for every densified pose, the axis commands whose error-aware forward
// kinematics put the tool on the nominal pose (kinematics::compensate), written in the
// program's dialect, one motion per pose with its source line as a comment. G-code: an axis
// program (X Y Z the linear axes zeroed so that at all-zero rotary axes the tip is at the
// programmed point, the convention of axis programs; A B C in deg). APT: the tool poses a
// tool-centre-point controller turns into those commands (the ideal forward kinematics of
// the compensated axes), as GOTO/x,y,z,i,j,k - provided the controller picks the same
// branch (near the pole, where both tie on rotary motion, it may not). Throws InputError
// when the machine has no geometric errors.
struct CompensationReport {
  std::size_t poses = 0;
  std::size_t not_converged = 0;
  double max_residual_tip_um = 0.0;
  double max_residual_axis_urad = 0.0;
  double max_error_before_um = 0.0;  // uncompensated volumetric tip error
  std::string max_error_line;
  std::string first_failure;  // "file:line: note" of the first pose that did not converge
};
CompensationReport write_compensated_program(const std::string& path, const Job& job, const PoseRun& run);

}  // namespace vcut::io
