// `vcut compensate JOB [--out FILE]`: the program whose axis commands cancel the machine's
// geometric errors, in the program's dialect.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace vcut::cli {

struct CompensateCommand {
  CLI::App* command = nullptr;
  std::string job, out;
  bool quiet = false;
};

void add_compensate_command(CLI::App& app, CompensateCommand& command);
// Runs it if it was given and returns its exit code; nothing when it was not. Bad input:
// vcut::InputError.
std::optional<int> run_compensate_command(const CompensateCommand& command);

}  // namespace vcut::cli
