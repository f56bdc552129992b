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
#include "vcut/io/input_error.h"
#include "vcut/io/job.h"
#include "vcut/pipeline/check.h"
#include "vcut/pipeline/compensate.h"
#include "vcut/pipeline/poses.h"
#include "vcut/pipeline/simulate.h"
#include "vcut/pipeline/study.h"
#include "vcut/report/check_report.h"
#include "vcut/report/outputs.h"
#include "vcut/report/pose_tables.h"
#include "vcut/report/study_report.h"

namespace {

int run_simulate(const std::string& job_file, const vcut::pipeline::SimulateOptions& base, const std::string& out,
                 bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  vcut::pipeline::SimulateOptions options = base;
  const std::string out_dir = out.empty() ? job.out_dir : out;
  // Fail on an unwritable output folder before hours of cutting, not after.
  vcut::io::ensure_writable_folder(out_dir);
  vcut::cli::ProgressBar bar(!quiet);
  options.progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    bar.update(stage, done, total);
  };
  vcut::pipeline::SimulationResult r = vcut::pipeline::simulate(job, options);
  vcut::report::write_simulation(out_dir, job, r, options.progress);
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
    std::printf("report: %s/report.json\n", out_dir.c_str());
  }
  return 0;
}

int run_poses(const std::string& job_file, std::string out, bool every_period, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  if (out.empty()) {
    vcut::io::ensure_writable_folder(job.out_dir);
    out = job.out_dir + "/poses.csv";
  }
  // Beside it: poses.csv -> poses_blocks.csv (per block), poses_periods.csv (every period).
  const std::string stem =
      out.size() > 4 && out.compare(out.size() - 4, 4, ".csv") == 0 ? out.substr(0, out.size() - 4) : out;
  const std::string blocks_out = stem + "_blocks.csv", periods_out = stem + "_periods.csv";
  const vcut::pipeline::PoseRun run = every_period ? vcut::report::run_pose_engine_with_periods(job, periods_out)
                                                   : vcut::pipeline::run_pose_engine(job);
  vcut::report::write_poses_csv(out, job, run);
  vcut::report::write_blocks_csv(blocks_out, job, run);
  for (const auto& w : job.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : run.program.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : run.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (quiet) return 0;
  std::printf("job %s on %s: %zu blocks, %zu poses (q %d..%d, mean %.2f), cycle time %.3f s\n", job.name.c_str(),
              job.machine.c_str(), run.program.blocks.size(), run.densified.samples.size(), run.q_min, run.q_max,
              run.q_mean, run.feed.cycle_time_s);
  if (run.max_nonlinear_error_mm > 0.0)
    std::printf("max non-linear tip error %.4f mm at %s\n", run.max_nonlinear_error_mm, run.max_nonlinear_line.c_str());
  if (!run.actual.empty()) {
    std::printf("contour error: max %.2f um at %s, RMS %.2f um", run.max_contour_error_um, run.max_contour_line.c_str(),
                run.rms_contour_error_um);
    if (job.servo) std::printf(" (%zu interpolation periods of %g s)", run.periods, job.servo->period_s);
    std::printf("\n");
  }
  size_t shown = 0;
  for (const auto& e : run.events)
    if (shown++ < 10)
      std::printf("%s at %s: %s\n", vcut::pipeline::to_string(e.kind), e.line.c_str(), e.detail.c_str());
  if (run.events.size() > 10) std::printf("... %zu events in all\n", run.events.size());
  std::printf("poses: %s\nper block: %s\n", out.c_str(), blocks_out.c_str());
  return 0;
}

int run_compensate(const std::string& job_file, std::string out, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  if (out.empty()) {
    vcut::io::ensure_writable_folder(job.out_dir);
  }
  const vcut::pipeline::PoseRun run = vcut::pipeline::run_pose_engine(job);
  if (out.empty())
    out = job.out_dir + (run.reader == vcut::io::ProgramReader::Apt ? "/compensated.apt" : "/compensated.ngc");
  const vcut::pipeline::CompensatedProgram compensated = vcut::pipeline::compensate_program(job, run);
  vcut::io::write_text_atomically(out, compensated.text);
  const vcut::pipeline::CompensationReport& r = compensated.report;
  if (quiet) return r.not_converged == 0 ? 0 : 1;
  std::printf("compensated %zu poses on %s: uncompensated tip error up to %.3f um (%s)\n", r.poses, job.machine.c_str(),
              r.max_error_before_um, r.max_error_line.c_str());
  std::printf("residual after compensation: tip %.2e um, axis %.2e urad (bounds 0.01 um, 0.01 urad)\n",
              r.max_residual_tip_um, r.max_residual_axis_urad);
  if (r.not_converged > 0)
    std::printf("%zu poses did not converge; first: %s\n", r.not_converged, r.first_failure.c_str());
  std::printf("program: %s\n", out.c_str());
  return r.not_converged == 0 ? 0 : 1;
}

int run_check(const std::string& job_file, const std::string& json_out, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  const vcut::pipeline::CheckResult r = vcut::pipeline::run_check(job);
  for (const auto& w : job.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : r.run.program.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (!json_out.empty()) vcut::report::write_check_json(json_out, job, r);
  if (!quiet) {
    const double t = r.run.feed.cycle_time_s;
    std::printf("check %s on %s: %zu blocks, %zu poses, cycle time %.1f s (%d:%02d:%02d)\n", job.name.c_str(),
                job.machine.c_str(), r.run.program.blocks.size(), r.run.densified.samples.size(), t,
                static_cast<int>(t / 3600), static_cast<int>(std::fmod(t, 3600.0) / 60),
                static_cast<int>(std::fmod(t, 60.0)));
    for (const auto& e : r.events)
      std::printf("%-7s %s at %s: %s\n", to_string(e.severity), e.kind.c_str(), e.line.c_str(), e.detail.c_str());
    for (const auto& c : r.tools) {
      if (!c.has_holder)
        std::printf("T%d: no holder in the tool library (not checked)\n", c.tool);
      else if (!c.over_stock)
        std::printf("T%d: its holder never comes over the stock\n", c.tool);
      else
        std::printf("T%d: holder %.3f mm %s the stock's top at its lowest over the stock (%s)\n", c.tool,
                    std::abs(c.holder_clearance_mm), c.holder_clearance_mm >= 0.0 ? "above" : "below",
                    c.holder_line.c_str());
    }
    std::printf("%s: %zu error(s), %zu warning(s) in %.2f s\n", r.errors == 0 ? "go" : "no-go", r.errors, r.warnings,
                r.wall_time_s);
  }
  return r.errors == 0 ? 0 : 1;
}

int run_study(const std::string& job_file, vcut::pipeline::StudyOptions options, const std::string& out, bool quiet) {
  const vcut::io::Job job = vcut::io::read_job(job_file);
  const std::string out_dir = out.empty() ? job.out_dir : out;
  // Fail on an unwritable output folder before the runs, not after.
  vcut::io::ensure_writable_folder(out_dir);
  vcut::cli::ProgressBar bar(!quiet);
  std::string current;
  options.on_run = [&](std::size_t index, std::size_t count, const std::string& label) {
    current = (index + 1 == count ? "reference "
                                  : "setting " + std::to_string(index + 1) + "/" + std::to_string(count - 1) + " ") +
              label;
  };
  options.progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    bar.update(current + ": " + stage, done, total);
  };
  vcut::pipeline::StudyResult s = vcut::pipeline::run_densification_study(job, options);
  vcut::report::write_study(out_dir, s, job);
  bar.finish();
  for (const auto& w : s.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  const vcut::pipeline::StudyRow* best =
      s.recommended >= 0 ? &s.rows[static_cast<std::size_t>(s.recommended)] : nullptr;
  if (!quiet) {
    std::printf("densification study of %s (%s), %s engine at %.3g mm, %d threads; accuracy %.4g mm\n",
                s.job_name.c_str(), s.varied.c_str(), vcut::io::engine_name(s.engine), s.resolution_mm, s.threads,
                s.accuracy_mm);
    std::printf("  %-28s %10s %12s %12s %10s\n", "setting", "poses", "max mm", "RMS mm", "time s");
    for (const auto& r : s.rows) {
      if (!r.error.empty()) {
        std::printf("  %-28s not run: %s\n", r.label.c_str(), r.error.c_str());
        continue;
      }
      std::printf("  %-28s %10zu %12.6f %12.6f %10.2f%s\n", r.label.c_str(), r.poses, r.max_mm, r.rms_mm, r.wall_time_s,
                  &r == best ? "  <- recommended"
                  : r.meets  ? "  meets"
                             : "");
    }
    std::printf("  %-28s %10zu %12s %12s %10.2f  (reference)\n", s.reference.label.c_str(), s.reference.poses, "-", "-",
                s.reference.wall_time_s);
    if (best)
      std::printf("recommended: %s, the coarsest setting within %.4g mm of the reference (%.4g mm)\n",
                  best->label.c_str(), s.accuracy_mm, best->max_mm);
    for (const auto& f : s.outputs) std::printf("%s\n", f.c_str());
  }
  if (!best) {
    double finest = -1.0;
    for (const auto& r : s.rows)
      if (r.error.empty() && (finest < 0.0 || r.max_mm < finest)) finest = r.max_mm;
    std::fprintf(stderr,
                 "vcut: no setting is within %.4g mm of the reference (the closest: %.4g mm); try finer settings\n",
                 s.accuracy_mm, finest);
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vcut: virtual machining - NC program in, machined part and its gouges out"};
  app.require_subcommand(1);
  bool quiet = false;
  std::string job_file;
  vcut::pipeline::SimulateOptions options;
  double resolution = 0.0, max_memory = 0.0;
  int threads = -1;
  std::string out;
  auto* simulate = app.add_subcommand("simulate", "Cut the job's program into its stock and compare with the design");
  simulate->add_option("job", job_file, "Job file (YAML)")->required();
  simulate->add_option("--resolution", resolution, "Voxel size in mm (overrides engine.resolution)")
      ->check(CLI::PositiveNumber);
  simulate->add_option("--threads", threads, "Worker threads, 0 = all cores (overrides engine.threads)")
      ->check(CLI::NonNegativeNumber);
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
  bool poses_every_period = false;
  poses->add_flag("--every-period", poses_every_period,
                  "Also write every interpolation period of the servo (commanded and actual axes, tip, contour error) "
                  "to <out>_periods.csv");
  auto* compensate = app.add_subcommand("compensate", "Error-compensated axis program of the job (machine errors)");
  std::string compensate_job, compensate_out;
  bool compensate_quiet = false;
  compensate->add_option("job", compensate_job, "Job file (YAML)")->required();
  compensate->add_option("--out", compensate_out,
                         "Output program (default: the job's output folder/compensated.ngc or .apt)");
  compensate->add_flag("--quiet,-q", compensate_quiet, "Print nothing but errors and warnings");
  auto* check = app.add_subcommand("check",
                                   "Everything but the cut: parse, densify, time, reach, limits, singularities, "
                                   "tool clearance against the stock's box; exit 1 on errors");
  std::string check_job, check_json;
  bool check_quiet = false;
  check->add_option("job", check_job, "Job file (YAML)")->required();
  check->add_option("--json", check_json, "Also write the findings as JSON to this file");
  check->add_flag("--quiet,-q", check_quiet, "Print nothing but errors and warnings");
  auto* study = app.add_subcommand("study", "Studies of the job: how a setting trades accuracy for time");
  study->require_subcommand(1);
  auto* densification = study->add_subcommand(
      "densification",
      "Cut the job at a series of densification settings and a much finer reference; per setting the "
      "distance from the reference cut, poses and time; recommends the coarsest within --accuracy");
  std::string study_job;
  bool study_quiet = false;
  vcut::pipeline::StudyOptions study_options;
  double study_resolution = 0.0, study_accuracy = 0.0, ref_step = 0.0, ref_angle = 0.0, ref_tolerance = 0.0;
  int study_threads = -1;
  std::string study_out;
  densification->add_option("job", study_job, "Job file (YAML)")->required();
  densification->add_option("--steps", study_options.steps_mm, "Tip steps lambda to try, mm (comma-separated)")
      ->delimiter(',');
  densification
      ->add_option("--angles", study_options.angles_deg,
                   "Orientation steps phi to try, deg (comma-separated; "
                   "paired with --steps by position when both are given)")
      ->delimiter(',');
  densification
      ->add_option("--tolerances", study_options.tolerances_mm, "Tolerance-mode epsilons to try, mm (comma-separated)")
      ->delimiter(',');
  densification->add_option("--reference-step", ref_step, "Reference lambda, mm (default: the finest step / 4)");
  densification->add_option("--reference-angle", ref_angle, "Reference phi, deg (default: the finest angle / 4)");
  densification->add_option("--reference-tolerance", ref_tolerance,
                            "Reference epsilon, mm (default: the finest tolerance / 4)");
  densification->add_option("--accuracy", study_accuracy, "Required accuracy, mm (default: the job's gouge tolerance)");
  densification->add_option("--resolution", study_resolution, "Voxel size in mm (overrides engine.resolution)")
      ->check(CLI::PositiveNumber);
  densification->add_option("--threads", study_threads, "Worker threads, 0 = all cores")->check(CLI::NonNegativeNumber);
  densification->add_option("--out", study_out,
                            "Folder for study.csv, .json, .svg and .png (default: the job's output folder)");
  densification->add_flag("--quiet,-q", study_quiet, "Print nothing but errors and warnings");
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
      options.max_memory_mb = max_memory;
      return run_simulate(job_file, options, out, quiet);
    }
    if (*poses) return run_poses(poses_job, poses_out, poses_every_period, poses_quiet);
    if (*densification) {
      if (densification->count("--reference-step")) study_options.reference_step_mm = ref_step;
      if (densification->count("--reference-angle")) study_options.reference_angle_deg = ref_angle;
      if (densification->count("--reference-tolerance")) study_options.reference_tolerance_mm = ref_tolerance;
      if (densification->count("--accuracy")) study_options.accuracy_mm = study_accuracy;
      if (study_resolution > 0.0) study_options.resolution_mm = study_resolution;
      if (study_threads >= 0) study_options.threads = study_threads;
      return run_study(study_job, study_options, study_out, study_quiet);
    }
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
