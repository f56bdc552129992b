#include "poses_command.h"

#include <cmath>
#include <cstdio>

#include "vcut/io/atomic_file.h"
#include "vcut/io/job.h"
#include "vcut/pipeline/poses.h"
#include "vcut/report/pose_tables.h"

namespace vcut::cli {
namespace {

int run_poses(const std::string& job_file, std::string out, bool every_period, bool quiet) {
  const io::Job job = io::read_job(job_file);
  if (out.empty()) {
    io::ensure_writable_folder(job.out_dir);
    out = job.out_dir + "/poses.csv";
  }
  // Beside it: poses.csv -> poses_blocks.csv (per block), poses_periods.csv (every period).
  const std::string stem =
      out.size() > 4 && out.compare(out.size() - 4, 4, ".csv") == 0 ? out.substr(0, out.size() - 4) : out;
  const std::string blocks_out = stem + "_blocks.csv", periods_out = stem + "_periods.csv";
  const pipeline::PoseRun run =
      every_period ? report::run_pose_engine_with_periods(job, periods_out) : pipeline::run_pose_engine(job);
  report::write_poses_csv(out, job, run);
  report::write_blocks_csv(blocks_out, job, run);
  for (const auto& w : job.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : run.program.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : run.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (quiet) return 0;
  std::printf("job %s on %s: %zu blocks, %zu poses (q %d..%d, mean %.2f), cycle time %.3f s\n", job.name.c_str(),
              job.machine.c_str(), run.program.blocks.size(), run.poses, run.q_min, run.q_max, run.q_mean,
              run.feed.cycle_time_s);
  if (run.max_nonlinear_error_mm > 0.0)
    std::printf("max non-linear tip error %.4f mm at %s\n", run.max_nonlinear_error_mm,
                run.program.where(run.max_nonlinear_line).c_str());
  if (!run.actual.empty()) {
    std::printf("contour error: max %.2f um at %s, RMS %.2f um", run.max_contour_error_um,
                run.program.where(run.max_contour_line).c_str(), run.rms_contour_error_um);
    if (job.servo) std::printf(" (%zu interpolation periods of %g s)", run.periods, job.servo->period_s);
    std::printf("\n");
  }
  size_t shown = 0;
  for (const auto& e : run.events)
    if (shown++ < 10)
      std::printf("%s at %s: %s\n", pipeline::to_string(e.kind), run.program.where(e.lines).c_str(), e.detail.c_str());
  if (run.events.size() > 10) std::printf("... %zu events in all\n", run.events.size());
  std::printf("poses: %s\nper block: %s\n", out.c_str(), blocks_out.c_str());
  return 0;
}

}  // namespace

void add_poses_command(CLI::App& app, PosesCommand& c) {
  c.command = app.add_subcommand("poses", "Densified, time-stamped tool poses of the job's program (CSV)");
  c.command->add_option("job", c.job, "Job file (YAML)")->required();
  c.command->add_option("--out", c.out, "Output CSV (default: the job's output folder/poses.csv)");
  c.command->add_flag("--quiet,-q", c.quiet, "Print nothing but errors and warnings");
  c.command->add_flag(
      "--every-period", c.every_period,
      "Also write every interpolation period of the servo (commanded and actual axes, tip, contour error) "
      "to <out>_periods.csv");
}

std::optional<int> run_poses_command(const PosesCommand& c) {
  if (!c.command || !*c.command) return std::nullopt;
  return run_poses(c.job, c.out, c.every_period, c.quiet);
}

}  // namespace vcut::cli
