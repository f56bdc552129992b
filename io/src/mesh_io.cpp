#include "vcut/io/mesh_io.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>

#include "vcut/io/atomic_file.h"
#include "vcut/io/input_error.h"

namespace vcut::io {

removal::TriangleMesh read_mesh(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, 0, 0, "mesh file not found");
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw InputError(path, 0, 0, std::string("cannot read mesh: ") + importer.GetErrorString());
  removal::TriangleMesh mesh;
  // Weld by exact coordinates (STL stores each triangle's corners separately): every
  // corner's coordinates sorted (in parallel; a std::map took 0.6 s of a 2.3 M-triangle
  // design's read), equal ones (as float compares: -0 and +0 too) become the vertex where
  // the first of them stands, numbered in the order of first appearance.
  std::vector<std::array<float, 3>> corner;
  std::vector<std::size_t> mesh_start(scene->mNumMeshes + 1, 0);
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) mesh_start[m + 1] = mesh_start[m] + scene->mMeshes[m]->mNumVertices;
  corner.reserve(mesh_start.back());
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw InputError(path, 0, 0, "mesh has a vertex that is not a finite number");
      corner.push_back({p.x, p.y, p.z});
    }
  }
  const std::size_t n = corner.size();
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  tbb::parallel_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return corner[a] < corner[b] || (!(corner[b] < corner[a]) && a < b);
  });
  std::vector<std::size_t> first(n);  // the first corner at the same place
  for (std::size_t k = 0; k < n; ++k)
    first[order[k]] = k > 0 && !(corner[order[k - 1]] < corner[order[k]]) ? first[order[k - 1]] : order[k];
  std::vector<int> remap(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (first[i] == i) {
      remap[i] = static_cast<int>(mesh.vertices_mm.size());
      mesh.vertices_mm.emplace_back(corner[i][0], corner[i][1], corner[i][2]);
    } else {
      remap[i] = remap[first[i]];
    }
  }
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    const std::size_t at = mesh_start[m];
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not surface
      mesh.triangles.emplace_back(remap[at + face.mIndices[0]], remap[at + face.mIndices[1]],
                                  remap[at + face.mIndices[2]]);
    }
  }
  if (mesh.triangles.empty()) throw InputError(path, 0, 0, "mesh has no triangles");
  return mesh;
}

void write_stl(const std::string& path, const removal::TriangleMesh& mesh) {
  // Binary STL written directly: an 80-byte header (not starting with "solid", which would
  // read as ASCII STL), the triangle count, then per triangle its unit normal, its three
  // corners (float32, mm) and a zero attribute word, 50 bytes each. Filled in parallel a
  // block of triangles at a time, each block written before the next is filled (the whole
  // file in memory was D32's 280 MB at its peak); a mesh of no triangles (the stock cut away)
  // is the header and a zero count.
  constexpr std::size_t kHeader = 84, kRecord = 50, kBlock = std::size_t{1} << 18;  // 13 MB a block
  const std::size_t n = mesh.triangles.size();
  if (n > std::numeric_limits<std::uint32_t>::max())
    throw InputError(path, 0, 0, "cannot write STL: more than 4,294,967,295 triangles");
  std::string header(kHeader, ' ');
  const std::string title = n == 0 ? "vcut: empty mesh" : "vcut: binary STL, mm";
  std::memcpy(header.data(), title.data(), title.size());
  const auto count = static_cast<std::uint32_t>(n);
  std::memcpy(header.data() + 80, &count, 4);  // little-endian, as on every target we build for
  write_atomically(path, [&](const std::string& temporary) {
    std::ofstream file(temporary, std::ios::binary);
    file.write(header.data(), static_cast<std::streamsize>(header.size()));
    std::string block(kRecord * std::min(n, kBlock), '\0');  // attribute words stay 0
    for (std::size_t first = 0; first < n && file; first += kBlock) {
      const std::size_t last = std::min(n, first + kBlock);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, 4096), [&](const auto& range) {
        for (std::size_t f = range.begin(); f != range.end(); ++f) {
          const auto& t = mesh.triangles[f];
          const Eigen::Vector3d& a = mesh.vertices_mm[static_cast<std::size_t>(t[0])];
          const Eigen::Vector3d& b = mesh.vertices_mm[static_cast<std::size_t>(t[1])];
          const Eigen::Vector3d& c = mesh.vertices_mm[static_cast<std::size_t>(t[2])];
          Eigen::Vector3d normal = (b - a).cross(c - a);
          const double length = normal.norm();
          normal = length > 0.0 ? Eigen::Vector3d(normal / length) : Eigen::Vector3d::Zero();
          float record[12];
          for (int k = 0; k < 3; ++k) {
            record[k] = static_cast<float>(normal[k]);
            record[3 + k] = static_cast<float>(a[k]);
            record[6 + k] = static_cast<float>(b[k]);
            record[9 + k] = static_cast<float>(c[k]);
          }
          std::memcpy(block.data() + kRecord * (f - first), record, sizeof record);
        }
      });
      file.write(block.data(), static_cast<std::streamsize>(kRecord * (last - first)));
    }
    if (!file) throw InputError(path, 0, 0, "cannot write STL");
  });
}

void write_deviation_ply(const std::string& path, const removal::TriangleMesh& mesh, const PlyAttributes& a) {
  const std::size_t n = mesh.vertices_mm.size();
  std::string out =
      "ply\nformat binary_little_endian 1.0\ncomment vcut deviation map: deviation in mm, "
      "negative = gouge, positive = excess; move -1 = initial stock; line = NC source line\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property float nx\nproperty float ny\nproperty float nz\n";
  out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "property float deviation\nproperty int move\nproperty int line\n";
  out += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  out += "property list uchar int vertex_indices\nend_header\n";
  // Records of fixed size (vertex 39 bytes, face 13), filled side by side (on one thread
  // the S-piece's 23 MB took 0.05 s, the writing stage's longest task on many threads).
  constexpr std::size_t kVertex = 39, kFace = 13;
  const std::size_t header = out.size(), faces_at = header + n * kVertex;
  out.resize(faces_at + mesh.triangles.size() * kFace);
  auto store = [&out](std::size_t& at, auto value) {
    std::memcpy(out.data() + at, &value, sizeof value);  // x86-64 and every target we build for are little-endian
    at += sizeof value;
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      std::size_t at = header + i * kVertex;
      for (int c = 0; c < 3; ++c) store(at, static_cast<float>(mesh.vertices_mm[i][c]));
      for (int c = 0; c < 3; ++c) store(at, i < a.normals.size() ? static_cast<float>(a.normals[i][c]) : 0.0f);
      const std::array<std::uint8_t, 3> rgb =
          i < a.colors.size() ? a.colors[i] : std::array<std::uint8_t, 3>{255, 255, 255};
      for (int c = 0; c < 3; ++c) store(at, rgb[static_cast<std::size_t>(c)]);
      store(at, i < a.deviation_mm.size() ? static_cast<float>(a.deviation_mm[i]) : 0.0f);
      store(at, static_cast<std::int32_t>(i < a.move.size() ? a.move[i] : -1));
      store(at, static_cast<std::int32_t>(i < a.line.size() ? a.line[i] : 0));
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 8192), [&](const auto& range) {
    for (std::size_t f = range.begin(); f != range.end(); ++f) {
      std::size_t at = faces_at + f * kFace;
      store(at, std::uint8_t{3});
      for (int c = 0; c < 3; ++c) store(at, static_cast<std::int32_t>(mesh.triangles[f][c]));
    }
  });
  write_text_atomically(path, out);
}

std::array<std::uint8_t, 3> deviation_color(double deviation_mm, double scale_mm) {
  const double t = scale_mm > 0.0 ? std::clamp(deviation_mm / scale_mm, -1.0, 1.0) : 0.0;
  // White fades to red (t -> -1: gouge) or to blue (t -> +1: excess).
  const auto fade = [](double s) { return static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - s))); };
  if (t < 0.0) return {255, fade(-t * 0.85), fade(-t * 0.85)};
  return {fade(t * 0.85), fade(t * 0.55), 255};
}

}  // namespace vcut::io
