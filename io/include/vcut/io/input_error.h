// The one exception type for bad input: it names the file, the 1-based line and column
// (0 when not known) and what was expected. Caught once in the cli, printed on one line.
#pragma once

#include <stdexcept>
#include <string>

namespace vcut {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, int line, int column, const std::string& message)
      : std::runtime_error(format(file, line, column, message)), file_(std::move(file)), line_(line), column_(column) {}
  explicit InputError(const std::string& message) : std::runtime_error(message) {}

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }

 private:
  static std::string format(const std::string& file, int line, int column, const std::string& message) {
    std::string where = file;
    if (line > 0) where += ":" + std::to_string(line);
    if (line > 0 && column > 0) where += ":" + std::to_string(column);
    return where.empty() ? message : where + ": " + message;
  }

  std::string file_;
  int line_ = 0;
  int column_ = 0;
};

}  // namespace vcut
