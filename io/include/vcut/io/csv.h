// Numeric CSV tables (batch input of `vcut fk` / `vcut ik`): a header row of column names,
// then rows of numbers separated by commas. Blank lines and lines starting with '#' are
// skipped. Errors name file:line:column and what was expected.
#pragma once

#include <string>
#include <vector>

namespace vcut::io {

struct CsvTable {
  std::string file;
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;  // each as long as the header
  std::vector<int> lines;                 // 1-based source line of each row

  int column(const std::string& name) const;  // -1 when absent
};

// Throws vcut::InputError: unreadable file, empty or duplicate column names, a row with the
// wrong number of fields, a field that is not a finite number.
CsvTable read_csv(const std::string& path);

// A text field of a CSV file we write: as is, or quoted (RFC 4180) when it holds a comma, a
// quote or a line break.
std::string csv_field(const std::string& text);

}  // namespace vcut::io
