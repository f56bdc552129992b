#include "vcut/io/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "vcut/io/input_error.h"

namespace vcut::io {
namespace fs = std::filesystem;

void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  const fs::path target(path);
  // Keep the extension last: some writers (assimp) choose the format by it.
  const std::string temporary = (target.parent_path() / ("." + target.stem().string() + ".tmp" +
                                                         std::to_string(::getpid()) + target.extension().string()))
                                    .string();
  try {
    write(temporary);
    std::error_code ec;
    fs::rename(temporary, target, ec);
    if (ec) throw InputError(path, 0, 0, "cannot write output: " + ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
}

void write_stream_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  write_atomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(path, 0, 0, "cannot write output (cannot create the file)");
    write(out);
    out.close();
    if (!out) throw InputError(path, 0, 0, "cannot write output (write failed: disk full?)");
  });
}

void write_text_atomically(const std::string& path, const std::string& text) {
  write_stream_atomically(
      path, [&](std::ostream& out) { out.write(text.data(), static_cast<std::streamsize>(text.size())); });
}

void ensure_writable_folder(const std::string& folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec || !fs::is_directory(folder))
    throw InputError(folder, 0, 0, "cannot create the output folder: " + ec.message());
  if (::access(folder.c_str(), W_OK) != 0) throw InputError(folder, 0, 0, "the output folder is not writable");
}

}  // namespace vcut::io
