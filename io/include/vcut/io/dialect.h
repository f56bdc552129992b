// NC program dialects by name (program_reader.h reads them).
#pragma once

#include <string>

namespace vcut::io {

// The dialect a program is read in, as a job file (program.dialect) and `--dialect` name it:
// auto (detect_dialect per file), gcode, linuxcnc, fanuc (the G-code reader; gcode and auto
// read Fanuc custom macro B when the file reads like it), apt, sinumerik.
enum class Dialect { Auto, Gcode, LinuxCnc, Fanuc, Apt, Sinumerik };
const char* dialect_name(Dialect dialect);
// A vcut::InputError naming the accepted names for any other.
Dialect parse_dialect(const std::string& name);

}  // namespace vcut::io
