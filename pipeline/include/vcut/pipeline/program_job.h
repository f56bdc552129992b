// A job for a program given alone (`vcut simulate part.nc`, `vcut job part.nc`): what a job
// file would say, taken from the program and written down as assumptions for the user to
// confirm (io::Job::assumptions).
// - Machine: the one named, else 3axis; xyzac-trt (the bundled A/C trunnion) for A or C
//   words, table-table-bc for B words, and for tool-pose programs whose tool axis tilts (APT
//   MULTAX, SINUMERIK TRAORI).
// - Stock: the one the program declares (io/program_header.h); a declared size without a
//   placement goes where it holds the cutting moves best (top at Z0 when they cut below it,
//   else bottom at Z0; in X and Y a low corner, a centre or a high corner at 0). Else the
//   cutting moves' box grown by the largest tool's radius in X and Y (no margin: approaches
//   start outside the part), from their lowest Z less 5 % of their depth (at least 1 mm) up
//   to Z0 (where CAM systems put the stock's top) or, for a program that cuts above Z0
//   only, its highest cutting level.
// - Tools: a LinuxCNC tool table when given, else the program's own comments, APT CUTTER/;
//   any other T number the program uses is a flat end mill of the default diameter. Their
//   length: flutes 4 diameters, at least as deep as the tool cuts, in a 100 mm gauge length.
// - Resolution: the longest stock side / 1000, at most a quarter of the smallest tool's
//   diameter, to two significant digits.
// - No design: the report shows the cut part, its collisions and times, no gouges.
#pragma once

#include <string>

#include "vcut/io/job.h"

namespace vcut::pipeline {

struct ProgramJobOptions {
  std::string machine;     // a bundled machine's name or a machine file; empty: by the program
  std::string tool_table;  // a LinuxCNC tool table (.tbl) or a CAMotics one (.json); empty: none
  double default_tool_diameter_mm = 6.0;
  double resolution_mm = 0.0;  // 0: by the stock's size and the tools
  io::Dialect dialect = io::Dialect::Auto;
  std::string out_dir;  // empty: out/<program name> in the current folder
};

// Reads the program (and the tool table) to make its job. Bad input is an InputError naming
// file:line:column: a program with no cutting move, a declared stock of zero size.
io::Job job_for_program(const std::string& program_path, const ProgramJobOptions& options = {});

}  // namespace vcut::pipeline
