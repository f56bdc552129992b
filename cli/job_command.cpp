#include "job_command.h"

#include <cstdio>
#include <filesystem>

#include "vcut/io/camotics_project.h"
#include "vcut/io/program_reader.h"

namespace vcut::cli {

void add_program_job_options(CLI::App& command, pipeline::ProgramJobOptions& options) {
  command
      .add_option("--machine", options.machine,
                  "A program without a job file: the machine (a bundled name or a machine file; default by its axes)")
      ->group("Program without a job file");
  command
      .add_option("--tool-table", options.tool_table,
                  "The program's tools: a LinuxCNC tool table (.tbl) or a CAMotics tool table (.json)")
      ->group("Program without a job file");
  command
      .add_option("--tool-diameter", options.default_tool_diameter_mm,
                  "Diameter (mm) of a tool the program does not describe (default 6)")
      ->check(CLI::PositiveNumber)
      ->group("Program without a job file");
}

io::Job job_or_program(const std::string& file, const pipeline::ProgramJobOptions& options) {
  const std::string ext = io::lower_extension(file);
  if (ext == ".yaml" || ext == ".yml") return io::read_job(file);
  if (ext == ".camotics") return io::read_camotics_project(file);
  return pipeline::job_for_program(file, options);
}

void add_job_command(CLI::App& app, JobCommand& c) {
  c.command = app.add_subcommand("job", "Write the job vcut assumes for a program given alone (YAML to stdout)");
  c.command->add_option("program", c.program, "NC program (G-code, SINUMERIK or APT)")->required();
  add_program_job_options(*c.command, c.options);
  c.command->add_option("--resolution", c.options.resolution_mm, "Voxel size in mm (default by the stock's size)")
      ->check(CLI::PositiveNumber);
}

bool run_job_command(const JobCommand& c) {
  if (!c.command || !*c.command) return false;
  const io::Job job = pipeline::job_for_program(c.program, c.options);
  const std::string text = io::job_yaml(job, c.program);
  std::fwrite(text.data(), 1, text.size(), stdout);
  return true;
}

}  // namespace vcut::cli
