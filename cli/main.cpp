// vcut: the command line. It only wires the libraries; every error from bad input is a
// vcut::InputError, printed here on one line with exit code 2.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>

#include "machine_commands.h"
#include "program_command.h"
#include "progress.h"
#include "vcut/io/atomic_file.h"
#include "vcut/io/check.h"
#include "vcut/io/input_error.h"
#include "vcut/io/job.h"
#include "vcut/io/pose_pipeline.h"
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
      std::printf("collision: %s (%s of T%d) at %s, %.3f mm deep at %s\n", c.kind.c_str(), c.part.c_str(), c.tool,
                  c.line.c_str(), c.depth_mm, c.deepest_line.c_str());
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

int run_poses(const std::string& job_file, std::string out, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  if (out.empty()) {
    vcut::io::ensure_writable_folder(job.out_dir);
    out = job.out_dir + "/poses.csv";
  }
  const vcut::io::PoseRun run = vcut::io::run_pose_engine(job);
  vcut::io::write_poses_csv(out, job, run);
  // Per-block figures beside it: poses.csv -> poses_blocks.csv.
  const std::string blocks_out = (out.size() > 4 && out.compare(out.size() - 4, 4, ".csv") == 0 ? out.substr(0, out.size() - 4) : out) +
                                 "_blocks.csv";
  vcut::io::write_blocks_csv(blocks_out, job, run);
  for (const auto& w : job.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : run.program.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (quiet) return 0;
  std::printf("job %s on %s: %zu blocks, %zu poses (q %d..%d, mean %.2f), cycle time %.3f s\n", job.name.c_str(),
              job.machine.c_str(), run.program.blocks.size(), run.densified.samples.size(), run.q_min, run.q_max,
              run.q_mean, run.feed.cycle_time_s);
  if (run.max_nonlinear_error_mm > 0.0)
    std::printf("max non-linear tip error %.4f mm at %s\n", run.max_nonlinear_error_mm, run.max_nonlinear_line.c_str());
  if (!run.actual.empty())
    std::printf("contour error: max %.2f um at %s, RMS %.2f um\n", run.max_contour_error_um, run.max_contour_line.c_str(),
                run.rms_contour_error_um);
  size_t shown = 0;
  for (const auto& e : run.events)
    if (shown++ < 10) std::printf("%s at %s: %s\n", e.kind.c_str(), e.line.c_str(), e.detail.c_str());
  if (run.events.size() > 10) std::printf("... %zu events in all\n", run.events.size());
  std::printf("poses: %s\nper block: %s\n", out.c_str(), blocks_out.c_str());
  return 0;
}

int run_compensate(const std::string& job_file, std::string out, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  if (out.empty()) {
    vcut::io::ensure_writable_folder(job.out_dir);
  }
  const vcut::io::PoseRun run = vcut::io::run_pose_engine(job);
  if (out.empty()) out = job.out_dir + (run.dialect == "apt" ? "/compensated.apt" : "/compensated.ngc");
  const vcut::io::CompensationReport r = vcut::io::write_compensated_program(out, job, run);
  if (quiet) return r.not_converged == 0 ? 0 : 1;
  std::printf("compensated %zu poses on %s: uncompensated tip error up to %.3f um (%s)\n", r.poses, job.machine.c_str(),
              r.max_error_before_um, r.max_error_line.c_str());
  std::printf("residual after compensation: tip %.2e um, axis %.2e urad (bounds 0.01 um, 0.01 urad)\n", r.max_residual_tip_um,
              r.max_residual_axis_urad);
  if (r.not_converged > 0)
    std::printf("%zu poses did not converge; first: %s\n", r.not_converged, r.first_failure.c_str());
  std::printf("program: %s\n", out.c_str());
  return r.not_converged == 0 ? 0 : 1;
}

int run_check(const std::string& job_file, const std::string& json_out, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  const vcut::io::CheckResult r = vcut::io::run_check(job);
  for (const auto& w : job.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : r.run.program.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (!json_out.empty()) vcut::io::write_check_json(json_out, job, r);
  if (!quiet) {
    const double t = r.run.feed.cycle_time_s;
    std::printf("check %s on %s: %zu blocks, %zu poses, cycle time %.1f s (%d:%02d:%02d)\n", job.name.c_str(), job.machine.c_str(),
                r.run.program.blocks.size(), r.run.densified.samples.size(), t, static_cast<int>(t / 3600),
                static_cast<int>(std::fmod(t, 3600.0) / 60), static_cast<int>(std::fmod(t, 60.0)));
    for (const auto& e : r.events) std::printf("%-7s %s at %s: %s\n", to_string(e.severity), e.kind.c_str(), e.line.c_str(), e.detail.c_str());
    for (const auto& c : r.tools) {
      if (!c.has_holder) std::printf("T%d: no holder in the tool library (not checked)\n", c.tool);
      else if (!c.over_stock) std::printf("T%d: its holder never comes over the stock\n", c.tool);
      else std::printf("T%d: holder %.3f mm %s the stock's top at its lowest over the stock (%s)\n", c.tool, std::abs(c.holder_clearance_mm),
                       c.holder_clearance_mm >= 0.0 ? "above" : "below", c.holder_line.c_str());
    }
    std::printf("%s: %zu error(s), %zu warning(s) in %.2f s\n", r.errors == 0 ? "go" : "no-go", r.errors, r.warnings, r.wall_time_s);
  }
  return r.errors == 0 ? 0 : 1;
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
  auto* poses = app.add_subcommand("poses", "Densified, time-stamped tool poses of the job's program (CSV)");
  std::string poses_job, poses_out;
  bool poses_quiet = false;
  poses->add_option("job", poses_job, "Job file (YAML)")->required();
  poses->add_option("--out", poses_out, "Output CSV (default: the job's output folder/poses.csv)");
  poses->add_flag("--quiet,-q", poses_quiet, "Print nothing but errors and warnings");
  auto* compensate = app.add_subcommand("compensate", "Error-compensated axis program of the job (machine errors)");
  std::string compensate_job, compensate_out;
  bool compensate_quiet = false;
  compensate->add_option("job", compensate_job, "Job file (YAML)")->required();
  compensate->add_option("--out", compensate_out, "Output program (default: the job's output folder/compensated.ngc or .apt)");
  compensate->add_flag("--quiet,-q", compensate_quiet, "Print nothing but errors and warnings");
  auto* check = app.add_subcommand("check", "Everything but the cut: parse, densify, time, reach, limits, singularities, "
                                            "tool clearance against the stock's box; exit 1 on errors");
  std::string check_job, check_json;
  bool check_quiet = false;
  check->add_option("job", check_job, "Job file (YAML)")->required();
  check->add_option("--json", check_json, "Also write the findings as JSON to this file");
  check->add_flag("--quiet,-q", check_quiet, "Print nothing but errors and warnings");
  vcut::cli::MachineCommands machine_commands;
  vcut::cli::add_machine_commands(app, machine_commands);
  vcut::cli::ProgramCommand program_command;
  vcut::cli::add_program_command(app, program_command);
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
    if (*poses) return run_poses(poses_job, poses_out, poses_quiet);
    if (*check) return run_check(check_job, check_json, check_quiet);
    if (*compensate) return run_compensate(compensate_job, compensate_out, compensate_quiet);
    if (vcut::cli::run_machine_commands(machine_commands)) return 0;
    if (vcut::cli::run_program_command(program_command)) return 0;
  } catch (const vcut::InputError& e) {
    std::fprintf(stderr, "vcut: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vcut: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
