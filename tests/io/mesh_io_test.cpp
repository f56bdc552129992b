// The binary STL writer against the format's layout (80-byte header, uint32 count, then
// 50-byte records: normal, three corners, attribute word), read back byte by byte here and
// through assimp; the deviation map's PLY likewise; base64 against RFC 4648's test vectors (section 10).
#include <gtest/gtest.h>
#include <vcut/io/mesh_io.h>
#include <vcut/report/report_page.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
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

// STL repeats each triangle's corners; reading welds equal ones into one vertex, numbered
// in the order the corners first appear, at the first one's coordinates: -0 and +0 are one
// place (as floats compare). A square pyramid written with its apex once as (0, 0, 1) and
// once as (-0, -0, 1), and its base corners in the order the faces first use them.
TEST(MeshIo, ReadingWeldsEqualCornersInOrderOfFirstAppearance) {
  removal::TriangleMesh pyramid;
  pyramid.vertices_mm = {{0, 0, 1}, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {-0.0, -0.0, 1}};
  pyramid.triangles = {{0, 1, 2}, {5, 2, 3}, {0, 3, 4}, {5, 4, 1}, {1, 4, 3}, {1, 3, 2}};
  const fs::path dir = fs::temp_directory_path() / "vcut_mesh_io_weld_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path path = dir / "pyramid.stl";
  write_stl(path.string(), pyramid);
  const removal::TriangleMesh back = read_mesh(path.string());
  ASSERT_EQ(back.vertices_mm.size(), 5u);
  for (std::size_t v = 0; v < 5; ++v) EXPECT_EQ(back.vertices_mm[v], pyramid.vertices_mm[v]) << v;
  EXPECT_FALSE(std::signbit(back.vertices_mm[0].x()));  // the apex as it first appears
  const std::vector<Eigen::Vector3i> expected = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}, {1, 4, 3}, {1, 3, 2}};
  ASSERT_EQ(back.triangles.size(), expected.size());
  for (std::size_t f = 0; f < expected.size(); ++f) EXPECT_EQ(back.triangles[f], expected[f]) << f;
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

// The deviation map's binary PLY against the format's layout as its header states it
// (little-endian records: vertex x y z nx ny nz float32, red green blue uint8, deviation
// float32, move and line int32; face: a uint8 count 3 and three int32 indices), read here
// byte by byte at the offsets the header's properties give, and through assimp. Enough
// vertices and faces that the writer fills them in many blocks: vertex i at (i, 2i, -i) mm
// with its own normal, colour, deviation, move and line; face f joins f, f + 1, f + 2.
TEST(MeshIo, DeviationPlyHoldsEveryVertexAndFaceAtItsPlace) {
  constexpr std::size_t kVertices = 50001, kFaces = kVertices - 2;
  removal::TriangleMesh mesh;
  PlyAttributes a;
  for (std::size_t i = 0; i < kVertices; ++i) {
    const double x = static_cast<double>(i);
    mesh.vertices_mm.emplace_back(x, 2 * x, -x);
    a.normals.emplace_back(0.0, i % 2 ? 1.0 : 0.0, i % 2 ? 0.0 : 1.0);
    a.colors.push_back({static_cast<std::uint8_t>(i % 256), static_cast<std::uint8_t>(i % 7), 200});
    a.deviation_mm.push_back(0.001 * static_cast<double>(i % 1000) - 0.5);
    a.move.push_back(static_cast<int>(i % 5000) - 1);
    a.line.push_back(static_cast<int>(i / 3));
  }
  for (std::size_t f = 0; f < kFaces; ++f)
    mesh.triangles.emplace_back(static_cast<int>(f), static_cast<int>(f + 1), static_cast<int>(f + 2));
  const fs::path dir = fs::temp_directory_path() / "vcut_mesh_io_ply_test";
  fs::create_directories(dir);
  const fs::path path = dir / "deviation.ply";
  write_deviation_ply(path.string(), mesh, a);
  const std::string bytes = read_bytes(path);
  const std::size_t body = bytes.find("end_header\n");
  ASSERT_NE(body, std::string::npos);
  const std::string header = bytes.substr(0, body);
  EXPECT_NE(header.find("format binary_little_endian 1.0\n"), std::string::npos);
  EXPECT_NE(header.find("element vertex " + std::to_string(kVertices) + "\n"), std::string::npos);
  EXPECT_NE(header.find("element face " + std::to_string(kFaces) + "\n"), std::string::npos);
  // The vertex properties' offsets from the header's list, in its order.
  std::size_t vertex_size = 0;
  std::map<std::string, std::size_t> at;
  for (std::size_t p = header.find("property "); p < header.find("element face"); p = header.find("property ", p + 1)) {
    const std::size_t end = header.find('\n', p);
    const std::string line = header.substr(p + 9, end - p - 9);  // "<type> <name>"
    const std::string type = line.substr(0, line.find(' ')), name = line.substr(line.find(' ') + 1);
    at[name] = vertex_size;
    vertex_size += type == "uchar" ? 1 : 4;
  }
  ASSERT_EQ(vertex_size, 39u);
  const std::size_t vertices = body + 11, faces = vertices + kVertices * vertex_size;
  ASSERT_EQ(bytes.size(), faces + kFaces * 13);
  auto value = [&](std::size_t offset, auto zero) {
    decltype(zero) v;
    std::memcpy(&v, bytes.data() + offset, sizeof v);
    return v;
  };
  std::size_t wrong_vertices = 0, wrong_faces = 0;
  for (std::size_t i = 0; i < kVertices; ++i) {
    const std::size_t r = vertices + i * vertex_size;
    bool same = true;
    for (int k = 0; k < 3; ++k) {
      same = same && value(r + at[std::string(1, "xyz"[k])], 0.0f) == static_cast<float>(mesh.vertices_mm[i][k]);
      same = same && value(r + at[std::string("n") + "xyz"[k]], 0.0f) == static_cast<float>(a.normals[i][k]);
    }
    same = same && value(r + at["red"], std::uint8_t{}) == a.colors[i][0] &&
           value(r + at["green"], std::uint8_t{}) == a.colors[i][1] &&
           value(r + at["blue"], std::uint8_t{}) == a.colors[i][2] &&
           value(r + at["deviation"], 0.0f) == static_cast<float>(a.deviation_mm[i]) &&
           value(r + at["move"], std::int32_t{}) == a.move[i] && value(r + at["line"], std::int32_t{}) == a.line[i];
    wrong_vertices += same ? 0 : 1;
  }
  for (std::size_t f = 0; f < kFaces; ++f) {
    const std::size_t r = faces + f * 13;
    bool same = value(r, std::uint8_t{}) == 3;
    for (int c = 0; c < 3; ++c)
      same = same && value(r + 1 + 4 * static_cast<std::size_t>(c), std::int32_t{}) == mesh.triangles[f][c];
    wrong_faces += same ? 0 : 1;
  }
  EXPECT_EQ(wrong_vertices, 0u);
  EXPECT_EQ(wrong_faces, 0u);
  // And assimp reads the same corners back (its own PLY reader).
  const removal::TriangleMesh back = read_mesh(path.string());
  EXPECT_EQ(back.triangles.size(), kFaces);
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
