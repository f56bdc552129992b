// What an NC program (G-code, SINUMERIK, APT) says about itself in its comments, for simulating it
// without a job file (`vcut simulate part.nc`): the stock its CAM system declared, the tools
// it lists, its units and the rotary axes it moves. Comments only; the motions are the
// readers' (io/program_reader.h).
//
// Stock, in the forms CAM systems and people write (case-insensitive):
//   (STOCK/BLOCK, dx, dy, dz, ox, oy, oz)       CutViewer (Carbide Create, many Mach3 posts):
//                                               the program's zero lies at (ox, oy, oz) from
//                                               the stock's low corner
//   (stockMin:x, y, z) with (stockMax:x, y, z)  Carbide Create, units mm or in after each value
//   ( Material Size) then ( X= dx, Y= dy, Z= dz)  Vectric
//   (STOCK ... DX a DY b DZ c)  (STOCK = a X b X c)  people and shop posts; a value may carry
//                                               IN, MM or " after it
//   INSERT/Stock Size X a Y b Z c               SolidWorks CAM's CL data (APT: `$$` comments,
//                                               INSERT/ and PPRINT/ texts; UNITS/ for units)
// The last three give the size only: the pipeline places it around the cutting moves
// (pipeline/program_job.h). A size that is not positive is an error naming file:line:column.
//
// Tools:
//   (T1 D=6. CR=0. [TAPER=45deg] - ZMIN=-5. - flat end mill)   Fusion 360 / HSM posts
//   (TOOL/MILL, d, r, h, taper)  (TOOL/DRILL, d, angle, h)      CutViewer: the tool of the next T
//   T5 M6 (19.1mm CHAMDRILL)  (T1 - .5 END MILL)  (T1 : 3.175)   a diameter with its T number
// The type comes from the words (ball, bull, chamfer, spot, drill, engrave, V-bit; otherwise
// a flat end mill); values are in the program's units unless a unit follows them.
#pragma once

#include <Eigen/Core>

#include <map>
#include <optional>
#include <set>
#include <string>

#include "vcut/removal/cutter.h"

namespace vcut::io {

struct DeclaredStock {
  Eigen::Vector3d size_mm = Eigen::Vector3d::Zero();
  bool placed = false;                               // min_mm is known (CutViewer, Carbide Create)
  Eigen::Vector3d min_mm = Eigen::Vector3d::Zero();  // placed only: the low corner, program frame
  std::string form;                                  // "CutViewer STOCK/BLOCK", ...
  std::string where;                                 // "file:line"
};

struct DeclaredTool {
  removal::Cutter cutter;        // diameter, corner radius, type, tip angle; lengths 0 (not declared)
  double flute_length_mm = 0.0;  // when the comment gives one (CutViewer's height)
  std::string form;              // "Fusion", "CutViewer", "comment"
  std::string where;             // "file:line"
  std::string text;              // the comment as written
};

struct ProgramHeader {
  std::optional<DeclaredStock> stock;  // the first declared
  std::map<int, DeclaredTool> tools;   // by T number, the first declaration of each
  bool inch = false;                   // the first G20/G21 (G70/G71 in SINUMERIK) is G20
  std::set<char> rotary_letters;       // A, B, C words in the code (not in comments)
  bool swivels = false;                // SINUMERIK CYCLE800(...) with parameters: a five-axis machine
  std::set<int> tool_numbers;          // T words, and D and H registers, in the code
  int first_tool = 0;                  // the first T word (0: none)
};

// Reads the program's comments. A stock form with a size that is not positive, or with too
// few values, is an InputError naming file:line:column.
ProgramHeader read_program_header(const std::string& path);

}  // namespace vcut::io
