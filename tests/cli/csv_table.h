// A CSV file as the CLI tests read vcut's outputs: a header and rows of text cells.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace vcut::cli::test {

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  bool has(const std::string& name) const { return std::find(header.begin(), header.end(), name) != header.end(); }
  int column(const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << "no column " << name;
    return it == header.end() ? 0 : static_cast<int>(it - header.begin());
  }
  const std::string& text(size_t row, const std::string& name) const { return rows.at(row).at(column(name)); }
  double num(size_t row, const std::string& name) const { return std::stod(text(row, name)); }
};

inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

inline Csv read_csv(const std::filesystem::path& path) {
  Csv csv;
  std::ifstream in(path);
  std::string line;
  if (std::getline(in, line)) csv.header = split_csv_line(line);
  while (std::getline(in, line))
    if (!line.empty()) csv.rows.push_back(split_csv_line(line));
  return csv;
}

}  // namespace vcut::cli::test
