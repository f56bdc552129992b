// `vcut simulate JOB [--resolution MM] [--threads N] [--out DIR] [--max-memory MB]`: the job's
// program cut into its stock and compared with the design; the output folder written. JOB may
// be a program given alone (pipeline/program_job.h): its assumptions are printed first.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "vcut/pipeline/program_job.h"

namespace vcut::cli {

struct SimulateCommand {
  CLI::App* command = nullptr;
  std::string job;
  double resolution_mm = 0.0, max_memory_mb = 0.0;
  int threads = -1;
  std::string out;
  bool quiet = false;
  pipeline::ProgramJobOptions program;  // a program without a job file
};

void add_simulate_command(CLI::App& app, SimulateCommand& command);
// Runs it if it was given and returns its exit code; nothing when it was not. Bad input:
// vcut::InputError.
std::optional<int> run_simulate_command(const SimulateCommand& command);

}  // namespace vcut::cli
