// `vcut program FILE [--dialect D] [--machine M] [--subroutine-path DIR]... [--max-lines N]`: the canonical motion list
// of an NC program as JSON lines, one record per Block (the contract later stages and outside checks use).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace vcut::cli {

struct ProgramCommand {
  CLI::App* program = nullptr;
  std::string file;
  std::string dialect = "auto";
  std::string machine;                       // validated, recorded for the stages that will need it
  std::vector<std::string> subroutine_path;  // G-code: folders for <name>.ngc subroutine files
  long long max_lines = 100'000'000;
  std::vector<int> tcp_on, tcp_off;  // G-code: M codes switching tool-centre-point kinematics
  std::string tools;                 // tool library (YAML): radii for cutter compensation, gauge lengths
};

void add_program_command(CLI::App& app, ProgramCommand& command);
// Runs it if it was given; false when it was not. Bad input: vcut::InputError.
bool run_program_command(const ProgramCommand& command);

}  // namespace vcut::cli
