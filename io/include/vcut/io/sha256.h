// SHA-256 of a file (OpenSSL's EVP), as lowercase hex: the input hashes in report.json.
#pragma once

#include <string>

namespace vcut::io {

// Throws vcut::InputError when the file cannot be read.
std::string sha256_file(const std::string& path);

}  // namespace vcut::io
