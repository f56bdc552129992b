// `vcut poses JOB [--out CSV] [--every-period]`: the densified, time-stamped tool poses of the
// job's program, per pose and per block (and per interpolation period of the servo).
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace vcut::cli {

struct PosesCommand {
  CLI::App* command = nullptr;
  std::string job, out;
  bool every_period = false;
  bool quiet = false;
};

void add_poses_command(CLI::App& app, PosesCommand& command);
// Runs it if it was given and returns its exit code; nothing when it was not. Bad input:
// vcut::InputError.
std::optional<int> run_poses_command(const PosesCommand& command);

}  // namespace vcut::cli
