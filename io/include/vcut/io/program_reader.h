// Which reader an NC program file needs (its dialect), and one entry point that reads any
// program into the canonical motion list (kinematics::Program, workpiece frame, mm).
// Bad input is a vcut::InputError naming file:line:column.
#pragma once

#include <vcut/io/apt_reader.h>
#include <vcut/io/dialect.h>
#include <vcut/io/gcode_reader.h>
#include <vcut/io/sinumerik_reader.h>
#include <vcut/kinematics/machine.h>
#include <vcut/kinematics/program.h>
#include <vcut/removal/cutter.h>

#include <map>
#include <string>
#include <vector>

namespace vcut::io {

// Gcode, Apt or Sinumerik. First the extension: .apt .cl .cls .aptsource -> apt;
// .mpf .spf -> sinumerik; .ngc .nc .tap .gcode -> gcode (case-insensitive). Otherwise the
// first meaningful lines: APT statements (GOTO/ FEDRAT/ CUTTER/ FROM/ ..., `$$` comments) ->
// apt; SINUMERIK words (TRAORI, ORIVECT, ORIWKS, CR=, DEF ..., or `;` comments with N blocks
// written letter-space-number, "N7 X -1320") -> sinumerik; anything else (and a file that
// cannot be read, which its reader then reports) -> gcode.
Dialect detect_dialect(const std::string& path);

// A path's extension in lower case, with its dot (".nc"; "" for none).
std::string lower_extension(const std::string& path);

// The machine's part in reading G-code, as its control runs a program: the start position and
// the G28 / G30 references (its home and second_home: the spindle's gauge point there, by
// forward kinematics, in the workpiece frame without work offsets), the M codes it declares,
// and each tool's gauge length and radius (for the tip under the gauge point and for cutter
// compensation). `axis_program`: the program moves the axes (rotary words without TCP): its
// X Y Z are the tip as it would stand with the rotary axes at zero (what the pose engine solves
// the linear axes from), so the start is the home's gauge point with the rotaries left out,
// the tip a tool length below it; M6 moves it by the difference of the tool lengths.
void set_machine(GcodeOptions& options, const kinematics::MachineSpec& machine,
                 const std::map<int, removal::Cutter>& tools, bool axis_program = false);
// The SINUMERIK reader's options from the G-code reader's (the job's offsets, limits, folders
// and, after set_machine, the machine).
SinumerikOptions sinumerik_options(const GcodeOptions& gcode);

struct ProgramOptions {
  GcodeOptions gcode;
  AptOptions apt;
};

// The reader a program file needs.
enum class ProgramReader { Gcode, Apt, Sinumerik };
const char* reader_name(ProgramReader reader);  // "gcode", "apt", "sinumerik"

struct LoadedProgram {
  kinematics::Program program;
  std::map<int, removal::Cutter> cutters;  // cutters the program itself defines (APT CUTTER/)
  ProgramReader reader = ProgramReader::Gcode;
};

// `dialect`: see Dialect; SINUMERIK is read with the G-code options' work offsets,
// unsupported-word mode and arc tolerance. A file with a NUL byte in its first 64 KiB is
// "not a text file". Several files run in sequence with one modal state; all must be of one
// dialect.
LoadedProgram read_program(const std::string& path, Dialect dialect, const ProgramOptions& options = {});
LoadedProgram read_programs(const std::vector<std::string>& paths, Dialect dialect, const ProgramOptions& options = {});

}  // namespace vcut::io
