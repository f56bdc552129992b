// SHA-256 (FIPS 180-4) of a file, as lowercase hex: the input hashes in report.json.
#pragma once

#include <string>

namespace vcut::io {

std::string sha256_hex(const std::string& bytes);
// Throws vcut::InputError when the file cannot be read.
std::string sha256_file(const std::string& path);

}  // namespace vcut::io
