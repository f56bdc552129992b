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

// The library as YAML (`tools:` and one line per tool, the keys above), read back the same.
std::string tool_library_yaml(const ToolLibrary& tools, const std::string& indent = "");

}  // namespace vcut::io
