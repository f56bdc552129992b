#include "simulate_command.h"

#include <cmath>
#include <cstdio>

#include "job_command.h"
#include "progress.h"
#include "vcut/io/atomic_file.h"
#include "vcut/io/job.h"
#include "vcut/pipeline/simulate.h"
#include "vcut/report/drawing.h"
#include "vcut/report/outputs.h"

namespace vcut::cli {
namespace {

int run_simulate(const SimulateCommand& c, const pipeline::SimulateOptions& base) {
  const io::Job job = job_or_program(c.job, c.program);
  const std::string& out = c.out;
  const bool quiet = c.quiet;
  // What vcut assumed for a program given alone, before anything else.
  for (const auto& a : job.assumptions) std::fprintf(stderr, "vcut: assumed %s\n", a.c_str());
  pipeline::SimulateOptions options = base;
  const std::string out_dir = out.empty() ? job.out_dir : out;
  // Fail on an unwritable output folder before hours of cutting, not after.
  io::ensure_writable_folder(out_dir);
  report::require_font();  // likewise the pictures' font
  ProgressBar bar(!quiet);
  options.progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    bar.update(stage, done, total);
  };
  pipeline::SimulationResult r = pipeline::simulate(job, options);
  report::write_simulation(out_dir, job, r, options.progress);
  bar.finish();
  for (const auto& w : r.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (!quiet) {
    std::printf("job %s: %zu blocks, %zu moves (%zu cutting) at %.3g mm, %d threads, %.2f s, peak %.0f MB\n",
                r.job_name.c_str(), r.blocks, r.moves, r.cutting_moves, r.resolution_mm, r.threads, r.wall_time_s,
                r.peak_memory_mb);
    std::printf("removed %.1f mm3 of %.1f mm3\n", r.removed_volume_mm3, r.initial_volume_mm3);
    for (const auto& c : r.collisions)
      std::printf("collision: %s (%s of T%d) at %s, %.3f mm deep at %s\n", pipeline::collision_kind(c.probe),
                  pipeline::collision_part(c.probe), c.tool, r.pose_run.program.where(c.lines).c_str(), c.depth_mm,
                  r.pose_run.program.where(c.deepest_line).c_str());
    for (const auto& c : r.machine.contacts) {
      const std::string at = pipeline::axis_text(*r.pose_run.machine, c.axes);
      if (c.hit)
        std::printf("machine collision: %s hits %s, %.3f mm deep, at %s%s (%s)\n", c.a.c_str(), c.b.c_str(), c.depth_mm,
                    r.pose_run.program.where(c.lines).c_str(), c.between_poses ? " between two poses" : "", at.c_str());
      else
        std::printf("machine near miss: %s passes %.3f mm from %s at %s (%s)\n", c.a.c_str(), c.clearance_mm,
                    c.b.c_str(), r.pose_run.program.where(c.lines).c_str(), at.c_str());
    }
    if (r.compared) {
      std::printf("max gouge %.4f mm in %zu region(s), max excess %.4f mm in %zu region(s)\n", r.max_gouge_mm,
                  r.gouges.size(), r.max_excess_mm, r.excess.size());
      for (std::size_t i = 0; i < r.gouges.size() && i < 5; ++i) {
        std::string lines;
        for (const std::string& l : r.pose_run.program.where(r.gouges[i].spans)) lines += " " + l;
        std::printf("  gouge %.4f mm deep, %.3f mm2 at (%.2f, %.2f, %.2f):%s\n", r.gouges[i].depth_mm,
                    r.gouges[i].area_mm2, r.gouges[i].deepest_mm.x(), r.gouges[i].deepest_mm.y(),
                    r.gouges[i].deepest_mm.z(), lines.c_str());
      }
    }
    std::printf("report: %s/report.json\n", out_dir.c_str());
  }
  return 0;
}

}  // namespace

void add_simulate_command(CLI::App& app, SimulateCommand& c) {
  c.command = app.add_subcommand("simulate", "Cut the job's program into its stock and compare with the design");
  c.command->add_option("job", c.job, "Job file (YAML), or an NC program alone (its job assumed)")->required();
  c.command->add_option("--resolution", c.resolution_mm, "Voxel size in mm (overrides engine.resolution)")
      ->check(CLI::PositiveNumber);
  c.command->add_option("--threads", c.threads, "Worker threads, 0 = all cores (overrides engine.threads)")
      ->check(CLI::NonNegativeNumber);
  c.command->add_option("--out", c.out, "Output folder (overrides report.out)");
  c.command
      ->add_option("--max-memory", c.max_memory_mb,
                   "Refuse a stock needing more than this many MB (default 75% of RAM)")
      ->check(CLI::PositiveNumber);
  c.command->add_flag("--quiet,-q", c.quiet, "Print nothing but errors and warnings");
  add_program_job_options(*c.command, c.program);
}

std::optional<int> run_simulate_command(const SimulateCommand& c) {
  if (!c.command || !*c.command) return std::nullopt;
  pipeline::SimulateOptions options;
  if (c.resolution_mm > 0.0) options.resolution_mm = c.resolution_mm;
  if (c.threads >= 0) options.threads = c.threads;
  options.max_memory_mb = c.max_memory_mb;
  SimulateCommand command = c;
  command.program.resolution_mm = c.resolution_mm;
  return run_simulate(command, options);
}

}  // namespace vcut::cli
