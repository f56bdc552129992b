// libFuzzer entry point for the numeric CSV reader: any bytes are a table (the reader takes a
// path, so they go to a temporary file first). The only exception allowed out of the
// reader is vcut::InputError, and a table it returns must be well formed: distinct
// non-empty column names, every row as long as the header and finite, ascending lines.
#include <unistd.h>
#include <vcut/io/csv.h>
#include <vcut/io/input_error.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

// A broken invariant is a crash, so that the fuzzer keeps the input.
void require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "csv_fuzz: broken invariant: %s\n", what);
  std::abort();
}

// VCUT_FUZZ_VERBOSE=1 prints what each input gave (to write and check corpus seeds).
bool verbose() {
  static const bool on = std::getenv("VCUT_FUZZ_VERBOSE") != nullptr;
  return on;
}

const std::string& temp_path() {
  static const std::string path = (std::filesystem::temp_directory_path() /
                                   ("vcut_csv_fuzz_" + std::to_string(static_cast<long>(::getpid())) + ".csv"))
                                      .string();
  return path;
}

void check(const vcut::io::CsvTable& table, const std::string& path, const uint8_t* data, size_t size) {
  require(table.file == path, "the table names its file");
  require(!table.header.empty(), "a header");
  for (size_t i = 0; i < table.header.size(); ++i) {
    const std::string& name = table.header[i];
    require(!name.empty(), "non-empty column names");
    require(name.find_first_of(",\r\n") == std::string::npos, "a column name is one field");
    require(table.column(name) == static_cast<int>(i), "distinct column names");
  }
  // A UTF-8 byte order mark that starts the file is not part of the first name (any other one
  // is junk, part of a name).
  const std::string text(reinterpret_cast<const char*>(data), size);
  const char* bom = "\xEF\xBB\xBF";
  if (text.rfind(bom, 0) == 0 && text.find(bom, 3) == std::string::npos)
    require(table.header.front().rfind(bom, 0) != 0, "no byte order mark in a name");
  require(table.rows.size() == table.lines.size(), "a line for every row");
  int previous = 0;
  for (size_t r = 0; r < table.rows.size(); ++r) {
    require(table.rows[r].size() == table.header.size(), "rows as long as the header");
    for (double v : table.rows[r]) require(std::isfinite(v), "finite values");
    require(table.lines[r] > previous, "ascending lines after the header");
    require(static_cast<size_t>(table.lines[r]) <= size + 1, "a line inside the file");
    previous = table.lines[r];
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = temp_path();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    require(static_cast<bool>(out), "writing the temporary file");
  }
  try {
    const vcut::io::CsvTable table = vcut::io::read_csv(path);
    check(table, path, data, size);
    if (verbose()) std::fprintf(stderr, "read %zu column(s), %zu row(s)\n", table.header.size(), table.rows.size());
  } catch (const vcut::InputError& e) {
    // Expected for bad input; it names this file and a position in it.
    if (verbose()) std::fprintf(stderr, "InputError: %s\n", e.what());
    require(e.file() == path, "the error names the file");
    require(e.line() >= 1 && e.column() >= 1, "the error names a line and column");
    require(static_cast<size_t>(e.line()) <= size + 1, "the error's line is inside the file");
  }
  std::remove(path.c_str());
  return 0;
}
