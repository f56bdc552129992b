// The canonical motion list of an NC program: one Block per programmed motion, in the
// workpiece frame (mm, after work offsets and unit conversion), each with its source line.
// Readers (vcut::io) produce it; densification and cutting consume it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vcut/kinematics/block_list.h"
#include "vcut/kinematics/program_block.h"

namespace vcut::kinematics {

struct Program {
  std::vector<std::string> files;     // files[SourceRef::file]
  BlockList blocks;                   // sealed by the reader as it goes (block_list.h)
  std::vector<std::string> warnings;  // "file:line:col: message"

  // The one way a source reference is written: "file:12", "file:12-19" for lines of one file,
  // "a.ngc:12 to b.ngc:3" across files (a last line before the first is left out).
  std::string where(const SourceRange& range) const {
    std::string s = files.at(static_cast<size_t>(range.first.file)) + ":" + std::to_string(range.first.line);
    if (range.last.file != range.first.file)
      s += " to " + files.at(static_cast<size_t>(range.last.file)) + ":" + std::to_string(range.last.line);
    else if (range.last.line > range.first.line)
      s += "-" + std::to_string(range.last.line);
    return s;
  }
  std::string where(const SourceRef& ref) const { return where(SourceRange{ref, ref}); }
  std::string where(const std::optional<SourceRef>& ref) const { return ref ? where(*ref) : std::string(); }
  std::vector<std::string> where(const std::vector<SourceSpan>& spans) const {
    std::vector<std::string> out;
    for (const SourceSpan& s : spans) out.push_back(where(s));
    return out;
  }
  std::string where(const SourceSpan& span) const {
    return where(SourceRange{{span.file, span.first_line}, {span.file, span.last_line}});
  }
  // The lines of blocks first..last, across files too.
  SourceRange range_of_blocks(int first, int last) const {
    return {blocks.at(static_cast<size_t>(first)).source, blocks.at(static_cast<size_t>(last)).source};
  }
  // The lines of a range within its first line's file: to the last line when that is in the
  // same file and later, else the first line alone.
  static SourceSpan span_in_first_file(const SourceRange& r) {
    const bool on = r.last.file == r.first.file && r.last.line > r.first.line;
    return {r.first.file, r.first.line, on ? r.last.line : r.first.line};
  }
};

}  // namespace vcut::kinematics
