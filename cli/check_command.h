// `vcut check JOB [--json FILE]`: everything but the cut, as a go/no-go (exit 1 on errors).
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace vcut::cli {

struct CheckCommand {
  CLI::App* command = nullptr;
  std::string job, json;
  bool quiet = false;
};

void add_check_command(CLI::App& app, CheckCommand& command);
// Runs it if it was given and returns its exit code; nothing when it was not. Bad input:
// vcut::InputError.
std::optional<int> run_check_command(const CheckCommand& command);

}  // namespace vcut::cli
