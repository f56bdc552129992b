// A LinuxCNC tool table (.tbl): one tool per line, `T<n> P<pocket> [X Y Z A B C U V W I J Q
// offsets] D<diameter> ;comment`, in the machine's units (mm_per_unit: 1, or 25.4 for an inch
// machine). It gives the diameter and the length offset, not the shape: every tool is a flat
// end mill unless its comment names a ball, bull nose, drill, chamfer or V-bit cutter (the
// same words as a program's tool comments, io/program_header.h).
#pragma once

#include <map>
#include <string>

#include "vcut/removal/cutter.h"

namespace vcut::io {

struct TableTool {
  removal::Cutter cutter;    // type and diameter; lengths 0 (not in the table)
  double z_offset_mm = 0.0;  // the Z tool length offset
  std::string comment;       // after `;`
  std::string where;         // "file:line"
};

// Tools with a zero or missing D are left out (probes, empty pockets). Throws InputError
// naming file:line:column for a word that is not a letter with a number, a T outside 1..99999,
// a negative D, a number twice.
std::map<int, TableTool> read_tool_table(const std::string& path, double mm_per_unit = 1.0);

}  // namespace vcut::io
