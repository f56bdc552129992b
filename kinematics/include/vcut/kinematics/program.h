// The canonical motion list of an NC program: one Block per programmed motion, in the
// workpiece frame (mm, after work offsets and unit conversion), each with its source line.
// Readers (vcut::io) produce it; densification and cutting consume it.
#pragma once

#include <string>
#include <vector>

#include "vcut/kinematics/block_list.h"
#include "vcut/kinematics/program_block.h"

namespace vcut::kinematics {

struct Program {
  std::vector<std::string> files;     // files[SourceRef::file]
  BlockList blocks;                   // sealed by the reader as it goes (block_list.h)
  std::vector<std::string> warnings;  // "file:line:col: message"

  std::string where(const SourceRef& ref) const {
    return files.at(static_cast<size_t>(ref.file)) + ":" + std::to_string(ref.line);
  }
  // "file:12", or "file:12-19" for a span of several lines.
  std::string where(const SourceSpan& span) const {
    std::string s = files.at(static_cast<size_t>(span.file)) + ":" + std::to_string(span.first_line);
    if (span.last_line > span.first_line) s += "-" + std::to_string(span.last_line);
    return s;
  }
  // The lines of blocks first..last: from the first's line to the last's in one file, else
  // the first's line alone.
  SourceSpan span_of_blocks(int first, int last) const {
    const SourceRef a = blocks.at(static_cast<size_t>(first)).source, b = blocks.at(static_cast<size_t>(last)).source;
    return {a.file, a.line, b.file == a.file && b.line > a.line ? b.line : a.line};
  }
};

}  // namespace vcut::kinematics
