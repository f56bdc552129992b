// The tool library (YAML): cutters keyed by T number. Lengths in mm.
//   tools: {1: {type: flat|ball|bull, diameter: 10, corner_radius: 0, flute_length: 25,
//               shank_diameter: 10, length: 40, holder_diameter: 32, holder_length: 50,
//               gauge_length: 90}}
// length: out of the holder; gauge_length: spindle nose to tip (default length + holder).
#pragma once

#include <map>
#include <string>

#include "vcut/removal/cutter.h"

namespace vcut::io {

using ToolLibrary = std::map<int, removal::Cutter>;

// Throws vcut::InputError naming file:line:column and the key for anything invalid.
ToolLibrary read_tool_library(const std::string& path);

// The lengths of a tool known by its shape only (a program's comment, a tool table, a CAMotics
// project): flutes as given (else 4 diameters, at least the corner radius), a shank of its
// diameter, out of the holder as long as its flutes, and a gauge length of 100 mm (or its
// length, if longer): the tool sits in no holder that is checked.
constexpr double kAssumedGaugeLengthMm = 100.0;
void assume_lengths(removal::Cutter& cutter, double flute_mm);

// The library as YAML (`tools:` and one line per tool, the keys above), read back the same.
std::string tool_library_yaml(const ToolLibrary& tools, const std::string& indent = "");

}  // namespace vcut::io
