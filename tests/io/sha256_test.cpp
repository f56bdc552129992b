// The input hashes of report.json: SHA-256 of a file against the known answers of FIPS 180-2
// (appendix B: "abc" and one million "a") and of the empty message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "vcut/io/input_error.h"
#include "vcut/io/sha256.h"

namespace vcut::io {
namespace {
namespace fs = std::filesystem;

std::string hash_of(const std::string& bytes) {
  const fs::path path = fs::temp_directory_path() / "vcut_sha256_test.bin";
  {
    std::ofstream out(path, std::ios::binary);
    out << bytes;
  }
  const std::string hex = sha256_file(path.string());
  fs::remove(path);
  return hex;
}

TEST(Sha256, KnownAnswers) {
  EXPECT_EQ(hash_of(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(hash_of("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // More than one read buffer (64 KiB).
  EXPECT_EQ(hash_of(std::string(1000000, 'a')), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, MissingFileIsAnInputError) { EXPECT_THROW(sha256_file("/nonexistent/vcut/file.ngc"), InputError); }

}  // namespace
}  // namespace vcut::io
