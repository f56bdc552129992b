// Machine files (YAML, ARCHITECTURE §3): topology, axes, spindle, workpiece zero, models and
// geometric errors, read into a validated kinematics::MachineSpec. File units: mm, deg,
// mm/min and deg/min, mm/s^2, mm/s^3 (deg/s^2, deg/s^3 for rotary axes), um and urad for
// errors; inside, mm and rad.
#pragma once

#include <string>
#include <vector>

#include "vcut/kinematics/machine.h"

namespace vcut::io {

// Throws vcut::InputError naming file:line:column, the key and what was expected.
// Repairs that kinematics::validate makes (a vector normalised) come back as warnings
// "file:line:column: message".
kinematics::MachineSpec read_machine_file(const std::string& path, std::vector<std::string>* warnings = nullptr);

// A bundled machine's name ("table-table-ac") -> its file in examples/machines; anything
// else is taken as a path and returned as it is.
std::string resolve_machine(const std::string& name_or_path);

}  // namespace vcut::io
