#include "vcut/io/csv.h"

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "vcut/io/input_error.h"

namespace vcut::io {
namespace {

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// Fields with their 1-based starting columns.
std::vector<std::pair<std::string, int>> split(const std::string& line) {
  std::vector<std::pair<std::string, int>> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    const std::string field = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    out.push_back({trim(field), static_cast<int>(start) + 1});
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

int CsvTable::column(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

CsvTable read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, 0, "cannot open file for reading");
  CsvTable table;
  table.file = path;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    // A UTF-8 byte order mark (spreadsheets write one) is not part of the first name.
    if (number == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    // Lines end with \n or \r\n; a carriage return elsewhere would join lines into one.
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (const size_t cr = line.find('\r'); cr != std::string::npos)
      throw InputError(path, number, static_cast<int>(cr) + 1,
                       "lines that end with \\n or \\r\\n (a carriage return inside the line: "
                       "old Mac line ends?)");
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const auto fields = split(line);
    if (table.header.empty()) {
      for (const auto& [name, col] : fields) {
        if (name.empty()) throw InputError(path, number, col, "a column name in the header (empty name)");
        if (table.column(name) >= 0)
          throw InputError(path, number, col, "distinct column names (duplicate '" + name + "')");
        table.header.push_back(name);
      }
      continue;
    }
    if (fields.size() != table.header.size())
      throw InputError(
          path, number, 1,
          std::to_string(table.header.size()) + " fields as in the header (got " + std::to_string(fields.size()) + ")");
    std::vector<double> row;
    for (const auto& [text, col] : fields) {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      // Overflow gives +-inf; underflow (1e-400, ERANGE) rounds to zero or a subnormal, a
      // finite number as written.
      if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
        throw InputError(path, number, col, "a finite number, not '" + text + "'");
      row.push_back(v);
    }
    table.rows.push_back(std::move(row));
    table.lines.push_back(number);
  }
  if (in.bad()) throw InputError(path, 0, 0, "cannot read file");
  if (table.header.empty()) throw InputError(path, 1, 1, "a header row of column names (the file is empty)");
  return table;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace vcut::io
