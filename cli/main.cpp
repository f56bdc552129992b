// vcut-core: the command line, started by vcut (cli/launcher.cpp). It only wires the
// libraries; every error from bad input is a vcut::InputError, printed here on one line with
// exit code 2.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "check_command.h"
#include "compensate_command.h"
#include "job_command.h"
#include "machine_commands.h"
#include "poses_command.h"
#include "program_command.h"
#include "simulate_command.h"
#include "study_command.h"
#include "vcut/io/input_error.h"

int main(int argc, char** argv) {
  CLI::App app{"vcut: virtual machining - NC program in, machined part and its gouges out"};
  app.require_subcommand(1);
  vcut::cli::SimulateCommand simulate;
  vcut::cli::add_simulate_command(app, simulate);
  vcut::cli::PosesCommand poses;
  vcut::cli::add_poses_command(app, poses);
  vcut::cli::CompensateCommand compensate;
  vcut::cli::add_compensate_command(app, compensate);
  vcut::cli::CheckCommand check;
  vcut::cli::add_check_command(app, check);
  vcut::cli::StudyCommand study;
  vcut::cli::add_study_command(app, study);
  vcut::cli::MachineCommands machine_commands;
  vcut::cli::add_machine_commands(app, machine_commands);
  vcut::cli::ProgramCommand program_command;
  vcut::cli::add_program_command(app, program_command);
  vcut::cli::JobCommand job_command;
  vcut::cli::add_job_command(app, job_command);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (const auto code = vcut::cli::run_simulate_command(simulate)) return *code;
    if (const auto code = vcut::cli::run_poses_command(poses)) return *code;
    if (const auto code = vcut::cli::run_compensate_command(compensate)) return *code;
    if (const auto code = vcut::cli::run_check_command(check)) return *code;
    if (const auto code = vcut::cli::run_study_command(study)) return *code;
    if (vcut::cli::run_machine_commands(machine_commands)) return 0;
    if (vcut::cli::run_program_command(program_command)) return 0;
    if (vcut::cli::run_job_command(job_command)) return 0;
  } catch (const vcut::InputError& e) {
    std::fprintf(stderr, "vcut: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vcut: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
