// The binary STL writer against the format's layout (80-byte header, uint32 count, then
// 50-byte records: normal, three corners, attribute word), read back byte by byte here and
// through assimp; base64 against RFC 4648's test vectors (section 10).
#include <gtest/gtest.h>
#include <vcut/io/mesh_io.h>
#include <vcut/report/report_page.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace vcut::io {
namespace {
namespace fs = std::filesystem;

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

float float_at(const std::string& bytes, std::size_t offset) {
  float value;
  std::memcpy(&value, bytes.data() + offset, 4);
  return value;
}

TEST(MeshIo, BinaryStlHoldsEachTriangleWithItsNormal) {
  // A unit right tetrahedron, outward winding: its faces' normals are -z, -y, -x and
  // (1, 1, 1)/sqrt(3).
  removal::TriangleMesh mesh;
  mesh.vertices_mm = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const fs::path dir = fs::temp_directory_path() / "vcut_mesh_io_test";
  fs::create_directories(dir);
  const fs::path path = dir / "tetra.stl";
  write_stl(path.string(), mesh);
  const std::string bytes = read_bytes(path);
  ASSERT_EQ(bytes.size(), 84u + 4u * 50u);
  EXPECT_NE(bytes.compare(0, 5, "solid"), 0);  // would read as ASCII STL
  std::uint32_t count;
  std::memcpy(&count, bytes.data() + 80, 4);
  EXPECT_EQ(count, 4u);
  const float s = 1.0f / std::sqrt(3.0f);
  const float normals[4][3] = {{0, 0, -1}, {0, -1, 0}, {-1, 0, 0}, {s, s, s}};
  for (std::size_t f = 0; f < 4; ++f) {
    const std::size_t record = 84 + 50 * f;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(float_at(bytes, record + 4 * k), normals[f][k], 1e-6) << "face " << f;
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(float_at(bytes, record + 12 + 12 * c + 4 * k),
                  static_cast<float>(mesh.vertices_mm[static_cast<std::size_t>(mesh.triangles[f][c])][k]));
    EXPECT_EQ(bytes[record + 48], 0);
    EXPECT_EQ(bytes[record + 49], 0);
  }
  // And assimp reads it back as the same solid: four corners, four faces.
  const removal::TriangleMesh back = read_mesh(path.string());
  EXPECT_EQ(back.vertices_mm.size(), 4u);
  EXPECT_EQ(back.triangles.size(), 4u);
  fs::remove_all(dir);
}

// A mesh of more triangles than the writer fills at once (2^18), not a multiple of that:
// every record at its place with its own corners, none lost or repeated at a block's seam,
// and the attribute words zero. Triangle f's corners are (f, 0, 0), (f, 1, 0), (f, 0, 1)
// (exact in float32 up to 2^24).
TEST(MeshIo, BinaryStlAcrossTheWritersBlocks) {
  constexpr std::size_t kTriangles = (std::size_t{1} << 18) * 2 + 12345;
  removal::TriangleMesh mesh;
  mesh.vertices_mm.reserve(3 * kTriangles);
  for (std::size_t f = 0; f < kTriangles; ++f) {
    const double x = static_cast<double>(f);
    mesh.vertices_mm.insert(mesh.vertices_mm.end(), {{x, 0, 0}, {x, 1, 0}, {x, 0, 1}});
    const int v = static_cast<int>(3 * f);
    mesh.triangles.emplace_back(v, v + 1, v + 2);
  }
  const fs::path dir = fs::temp_directory_path() / "vcut_mesh_io_blocks_test";
  fs::create_directories(dir);
  const fs::path path = dir / "strip.stl";
  write_stl(path.string(), mesh);
  const std::string bytes = read_bytes(path);
  ASSERT_EQ(bytes.size(), 84u + 50u * kTriangles);
  std::uint32_t count;
  std::memcpy(&count, bytes.data() + 80, 4);
  EXPECT_EQ(count, kTriangles);
  std::size_t wrong = 0;
  for (std::size_t f = 0; f < kTriangles; ++f) {
    const std::size_t record = 84 + 50 * f;
    const float x = static_cast<float>(f);
    // Normal (1, 0, 0): (0, 1, 0) x (0, 0, 1).
    const float expected[12] = {1, 0, 0, x, 0, 0, x, 1, 0, x, 0, 1};
    bool same = bytes[record + 48] == 0 && bytes[record + 49] == 0;
    for (int k = 0; k < 12; ++k)
      same = same && float_at(bytes, record + 4 * static_cast<std::size_t>(k)) == expected[k];
    wrong += same ? 0 : 1;
  }
  EXPECT_EQ(wrong, 0u);
  fs::remove_all(dir);
}

TEST(MeshIo, Base64MatchesRfc4648) {
  const std::pair<std::string, std::string> vectors[] = {{"", ""},
                                                         {"f", "Zg=="},
                                                         {"fo", "Zm8="},
                                                         {"foo", "Zm9v"},
                                                         {"foob", "Zm9vYg=="},
                                                         {"fooba", "Zm9vYmE="},
                                                         {"foobar", "Zm9vYmFy"}};
  for (const auto& [in, out] : vectors) EXPECT_EQ(report::base64(in.data(), in.size()), out) << in;
  const unsigned char high[] = {0xfb, 0xff, 0xbf};  // the alphabet's last two characters
  EXPECT_EQ(report::base64(high, 3), "+/+/");
}

// Long inputs are encoded in chunks side by side: decoded group by group (RFC 4648's table,
// written out here) they give the bytes back, across every chunk's border and with one and
// two bytes left over.
TEST(MeshIo, Base64OfLongInputsDecodesBack) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (const std::size_t bytes : {std::size_t{600000}, std::size_t{600001}, std::size_t{600002}}) {
    std::vector<unsigned char> in(bytes);
    for (std::size_t i = 0; i < bytes; ++i) in[i] = static_cast<unsigned char>((i * 2654435761u) >> 13);
    const std::string text = report::base64(in.data(), in.size());
    ASSERT_EQ(text.size(), (bytes + 2) / 3 * 4);
    std::vector<unsigned char> out;
    for (std::size_t g = 0; g < text.size(); g += 4) {
      std::uint32_t v = 0;
      int pad = 0;
      for (int k = 0; k < 4; ++k) {
        const char c = text[g + static_cast<std::size_t>(k)];
        if (c == '=') {
          ++pad;
          v <<= 6;
          continue;
        }
        const std::size_t digit = alphabet.find(c);
        ASSERT_NE(digit, std::string::npos) << g;
        v = v << 6 | static_cast<std::uint32_t>(digit);
      }
      for (int k = 0; k < 3 - pad; ++k) out.push_back(static_cast<unsigned char>(v >> (16 - 8 * k)));
    }
    EXPECT_TRUE(out == in) << bytes;
  }
}

}  // namespace
}  // namespace vcut::io
