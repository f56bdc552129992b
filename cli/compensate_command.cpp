#include "compensate_command.h"

#include <cmath>
#include <cstdio>

#include "vcut/io/atomic_file.h"
#include "vcut/io/job.h"
#include "vcut/io/program_reader.h"
#include "vcut/pipeline/compensate.h"
#include "vcut/pipeline/poses.h"

namespace vcut::cli {
namespace {

int run_compensate(const std::string& job_file, std::string out, bool quiet) {
  const io::Job job = io::read_job(job_file);
  if (out.empty()) {
    io::ensure_writable_folder(job.out_dir);
  }
  const pipeline::PoseRun run = pipeline::run_pose_engine(job);
  if (out.empty()) out = job.out_dir + (run.reader == io::ProgramReader::Apt ? "/compensated.apt" : "/compensated.ngc");
  const pipeline::CompensatedProgram compensated = pipeline::compensate_program(job, run);
  io::write_text_atomically(out, compensated.text);
  const pipeline::CompensationReport& r = compensated.report;
  if (quiet) return r.not_converged == 0 ? 0 : 1;
  std::printf("compensated %zu poses on %s: uncompensated tip error up to %.3f um (%s)\n", r.poses, job.machine.c_str(),
              r.max_error_before_um, r.max_error_line ? run.program.where(r.max_error_line).c_str() : "start");
  std::printf("residual after compensation: tip %.2e um, axis %.2e urad (bounds 0.01 um, 0.01 urad)\n",
              r.max_residual_tip_um, r.max_residual_axis_urad);
  if (r.not_converged > 0)
    std::printf("%zu poses did not converge; first: %s\n", r.not_converged, r.first_failure.c_str());
  std::printf("program: %s\n", out.c_str());
  return r.not_converged == 0 ? 0 : 1;
}

}  // namespace

void add_compensate_command(CLI::App& app, CompensateCommand& c) {
  c.command = app.add_subcommand("compensate", "Error-compensated axis program of the job (machine errors)");
  c.command->add_option("job", c.job, "Job file (YAML)")->required();
  c.command->add_option("--out", c.out, "Output program (default: the job's output folder/compensated.ngc or .apt)");
  c.command->add_flag("--quiet,-q", c.quiet, "Print nothing but errors and warnings");
}

std::optional<int> run_compensate_command(const CompensateCommand& c) {
  if (!c.command || !*c.command) return std::nullopt;
  return run_compensate(c.job, c.out, c.quiet);
}

}  // namespace vcut::cli
