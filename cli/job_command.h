// `vcut job PROGRAM [--machine M] [--tool-table FILE] [--tool-diameter MM] [--resolution MM]`:
// the job vcut assumes for a program given alone, written to stdout as a job file to edit
// (its assumptions as comments at the top). `vcut simulate PROGRAM` runs the same job.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/program_job.h"

namespace vcut::cli {

// The options of a program given without a job file, on `command`.
void add_program_job_options(CLI::App& command, pipeline::ProgramJobOptions& options);
// A job file (.yaml, .yml) or a CAMotics project (.camotics) read, or a program's assumed job.
io::Job job_or_program(const std::string& file, const pipeline::ProgramJobOptions& options);

struct JobCommand {
  CLI::App* command = nullptr;
  std::string program;
  pipeline::ProgramJobOptions options;
};

void add_job_command(CLI::App& app, JobCommand& command);
// Runs it if it was given (true); bad input: vcut::InputError.
bool run_job_command(const JobCommand& command);

}  // namespace vcut::cli
