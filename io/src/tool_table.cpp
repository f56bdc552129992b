#include "vcut/io/tool_table.h"

#include <cctype>
#include <cmath>
#include <fstream>

#include "program_header_words.h"
#include "vcut/io/input_error.h"

namespace vcut::io {

std::map<int, TableTool> read_tool_table(const std::string& path, double mm_per_unit) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "cannot open the tool table");
  std::map<int, TableTool> tools;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::size_t semicolon = line.find(';');
    const std::string comment = semicolon == std::string::npos ? "" : line.substr(semicolon + 1);
    const std::string words = line.substr(0, semicolon);
    int tool = 0;
    double diameter = 0.0, z = 0.0;
    std::size_t i = 0;
    while (i < words.size()) {
      if (std::isspace(static_cast<unsigned char>(words[i]))) {
        ++i;
        continue;
      }
      const int column = static_cast<int>(i + 1);
      const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(words[i])));
      if (std::string("TPXYZABCUVWIJQD").find(letter) == std::string::npos)
        throw InputError(path, number, column, "expected a tool table word T P X Y Z A B C U V W I J Q or D");
      std::size_t used = 0;
      double value = 0.0;
      try {
        value = std::stod(words.substr(i + 1), &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || !std::isfinite(value) ||
          (i + 1 + used < words.size() && !std::isspace(static_cast<unsigned char>(words[i + 1 + used]))))
        throw InputError(path, number, column, std::string("expected a number after ") + letter);
      if (letter == 'T') {
        if (value != std::floor(value) || value < 1 || value > 99999)
          throw InputError(path, number, column, "expected a T number from 1 to 99999");
        tool = static_cast<int>(value);
      } else if (letter == 'D') {
        if (value < 0.0) throw InputError(path, number, column, "expected a diameter D of at least 0");
        diameter = value * mm_per_unit;
      } else if (letter == 'Z') {
        z = value * mm_per_unit;
      }
      i += 1 + used;
    }
    if (tool == 0) {
      if (words.find_first_not_of(" \t") != std::string::npos)
        throw InputError(path, number, 1, "expected a T word on a tool line");
      continue;
    }
    if (tools.count(tool)) throw InputError(path, number, 1, "T" + std::to_string(tool) + " listed twice");
    if (!(diameter > 0.0)) continue;
    TableTool t;
    std::string upper = comment;
    for (char& ch : upper) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    t.cutter = detail::cutter_of_words(upper, diameter, 0.0, 0.0);
    t.z_offset_mm = z;
    t.comment = comment;
    t.where = path + ":" + std::to_string(number);
    tools.emplace(tool, t);
  }
  return tools;
}

}  // namespace vcut::io
