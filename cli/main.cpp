// vcut: the command line. It only wires the libraries; every error from bad input is a
// vcut::InputError, printed here on one line with exit code 2.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>

#include "machine_commands.h"
#include "progress.h"
#include "vcut/io/input_error.h"
#include "vcut/io/job.h"
#include "vcut/io/simulate.h"

namespace {

int run_simulate(const std::string& job_file, const vcut::io::SimulateOptions& base, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  vcut::io::SimulateOptions options = base;
  vcut::cli::ProgressBar bar(!quiet);
  options.progress = [&](const std::string& stage, std::size_t done, std::size_t total) { bar.update(stage, done, total); };
  const vcut::io::SimulationResult r = vcut::io::simulate(job, options);
  bar.finish();
  for (const auto& w : r.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (!quiet) {
    std::printf("job %s: %zu blocks, %zu moves (%zu cutting) at %.3g mm, %d threads, %.2f s, peak %.0f MB\n",
                r.job_name.c_str(), r.blocks, r.moves, r.cutting_moves, r.resolution_mm, r.threads, r.wall_time_s,
                r.peak_memory_mb);
    std::printf("removed %.1f mm3 of %.1f mm3\n", r.removed_volume_mm3, r.initial_volume_mm3);
    for (const auto& c : r.collisions)
      std::printf("collision: %s at %s, %.3f mm deep (T%d)\n", c.kind.c_str(), c.line.c_str(), c.depth_mm, c.tool);
    if (r.compared) {
      std::printf("max gouge %.4f mm in %zu region(s), max excess %.4f mm in %zu region(s)\n", r.max_gouge_mm,
                  r.gouges.size(), r.max_excess_mm, r.excess.size());
      for (std::size_t i = 0; i < r.gouges.size() && i < 5; ++i) {
        std::string lines;
        for (const auto& l : r.gouges[i].lines) lines += " " + l;
        std::printf("  gouge %.4f mm deep, %.3f mm2 at (%.2f, %.2f, %.2f):%s\n", r.gouges[i].depth_mm,
                    r.gouges[i].area_mm2, r.gouges[i].deepest_mm.x(), r.gouges[i].deepest_mm.y(),
                    r.gouges[i].deepest_mm.z(), lines.c_str());
      }
    }
    std::printf("report: %s/report.json\n", r.out_dir.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vcut: virtual machining - NC program in, machined part and its gouges out"};
  app.require_subcommand(1);
  bool quiet = false;
  std::string job_file;
  vcut::io::SimulateOptions options;
  double resolution = 0.0, max_memory = 0.0;
  int threads = -1;
  std::string out;
  auto* simulate = app.add_subcommand("simulate", "Cut the job's program into its stock and compare with the design");
  simulate->add_option("job", job_file, "Job file (YAML)")->required();
  simulate->add_option("--resolution", resolution, "Voxel size in mm (overrides engine.resolution)")->check(CLI::PositiveNumber);
  simulate->add_option("--threads", threads, "Worker threads, 0 = all cores (overrides engine.threads)")->check(CLI::NonNegativeNumber);
  simulate->add_option("--out", out, "Output folder (overrides report.out)");
  simulate->add_option("--max-memory", max_memory, "Refuse a stock needing more than this many MB (default 75% of RAM)")
      ->check(CLI::PositiveNumber);
  simulate->add_flag("--quiet,-q", quiet, "Print nothing but errors and warnings");
  vcut::cli::MachineCommands machine_commands;
  vcut::cli::add_machine_commands(app, machine_commands);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (*simulate) {
      if (resolution > 0.0) options.resolution_mm = resolution;
      if (threads >= 0) options.threads = threads;
      if (!out.empty()) options.out_dir = out;
      options.max_memory_mb = max_memory;
      return run_simulate(job_file, options, quiet);
    }
    if (vcut::cli::run_machine_commands(machine_commands)) return 0;
  } catch (const vcut::InputError& e) {
    std::fprintf(stderr, "vcut: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vcut: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
