#include "study_command.h"

#include <cmath>
#include <cstdio>

#include "progress.h"
#include "vcut/io/atomic_file.h"
#include "vcut/io/job.h"
#include "vcut/pipeline/study.h"
#include "vcut/report/drawing.h"
#include "vcut/report/study_report.h"

namespace vcut::cli {
namespace {

int run_study(const std::string& job_file, pipeline::StudyOptions options, const std::string& out, bool quiet) {
  const io::Job job = io::read_job(job_file);
  const std::string out_dir = out.empty() ? job.out_dir : out;
  // Fail on an unwritable output folder before the runs, not after.
  io::ensure_writable_folder(out_dir);
  report::require_font();  // likewise the plot's font
  ProgressBar bar(!quiet);
  std::string current;
  options.on_run = [&](std::size_t index, std::size_t count, const std::string& label) {
    current = (index + 1 == count ? "reference "
                                  : "setting " + std::to_string(index + 1) + "/" + std::to_string(count - 1) + " ") +
              label;
  };
  options.progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    bar.update(current + ": " + stage, done, total);
  };
  pipeline::StudyResult s = pipeline::run_densification_study(job, options);
  report::write_study(out_dir, s, job);
  bar.finish();
  for (const auto& w : s.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  const pipeline::StudyRow* best = s.recommended >= 0 ? &s.rows[static_cast<std::size_t>(s.recommended)] : nullptr;
  if (!quiet) {
    std::printf(
        "densification study of %s (%s), %s engine at %.3g mm, %d threads; accuracy %.4g mm, turning moves within "
        "%.3g mm\n",
        s.job_name.c_str(), s.varied.c_str(), io::engine_name(s.engine), s.resolution_mm, s.threads, s.accuracy_mm,
        s.turn_tolerance_mm);
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

void add_study_command(CLI::App& app, StudyCommand& c) {
  auto* study = app.add_subcommand("study", "Studies of the job: how a setting trades accuracy for time");
  study->require_subcommand(1);
  c.densification = study->add_subcommand(
      "densification",
      "Cut the job at a series of densification settings and a much finer reference; per setting the "
      "distance from the reference cut, poses and time; recommends the coarsest within --accuracy");
  CLI::App* d = c.densification;
  d->add_option("job", c.job, "Job file (YAML)")->required();
  d->add_option("--steps", c.options.steps_mm, "Tip steps lambda to try, mm (comma-separated)")->delimiter(',');
  d->add_option("--angles", c.options.angles_deg,
                "Orientation steps phi to try, deg (comma-separated; "
                "paired with --steps by position when both are given)")
      ->delimiter(',');
  d->add_option("--tolerances", c.options.tolerances_mm, "Tolerance-mode epsilons to try, mm (comma-separated)")
      ->delimiter(',');
  d->add_option("--reference-step", c.reference_step_mm, "Reference lambda, mm (default: the finest step / 4)");
  d->add_option("--reference-angle", c.reference_angle_deg, "Reference phi, deg (default: the finest angle / 4)");
  d->add_option("--reference-tolerance", c.reference_tolerance_mm,
                "Reference epsilon, mm (default: the finest tolerance / 4)");
  d->add_option("--accuracy", c.accuracy_mm, "Required accuracy, mm (default: the job's gouge tolerance)");
  d->add_option("--resolution", c.resolution_mm, "Voxel size in mm (overrides engine.resolution)")
      ->check(CLI::PositiveNumber);
  d->add_option("--threads", c.threads, "Worker threads, 0 = all cores")->check(CLI::NonNegativeNumber);
  d->add_option("--out", c.out, "Folder for study.csv, .json, .svg and .png (default: the job's output folder)");
  d->add_flag("--quiet,-q", c.quiet, "Print nothing but errors and warnings");
}

std::optional<int> run_study_command(const StudyCommand& c) {
  if (!c.densification || !*c.densification) return std::nullopt;
  pipeline::StudyOptions options = c.options;
  if (c.densification->count("--reference-step")) options.reference_step_mm = c.reference_step_mm;
  if (c.densification->count("--reference-angle")) options.reference_angle_deg = c.reference_angle_deg;
  if (c.densification->count("--reference-tolerance")) options.reference_tolerance_mm = c.reference_tolerance_mm;
  if (c.densification->count("--accuracy")) options.accuracy_mm = c.accuracy_mm;
  if (c.resolution_mm > 0.0) options.resolution_mm = c.resolution_mm;
  if (c.threads >= 0) options.threads = c.threads;
  return run_study(c.job, options, c.out, c.quiet);
}

}  // namespace vcut::cli
