// The pose-engine commands for machine builders: `vcut machine`, `vcut fk`, `vcut ik`.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace vcut::cli {

struct MachineCommands {
  CLI::App* machine = nullptr;
  CLI::App* fk = nullptr;
  CLI::App* ik = nullptr;
  std::string file, axes, tip, axis, previous, prefer, csv_in, csv_out;
  double tool_length_mm = 0.0;
  double singular_deg = -1.0;  // < 0: the machine's
  bool errors = false;
};

void add_machine_commands(CLI::App& app, MachineCommands& commands);
// Runs whichever of the three was given; false when none was. Bad input: vcut::InputError.
bool run_machine_commands(const MachineCommands& commands);

}  // namespace vcut::cli
