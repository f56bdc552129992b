#include "vcut/io/mesh_io.h"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>

#include "vcut/io/atomic_file.h"
#include "vcut/io/input_error.h"

namespace vcut::io {

removal::TriangleMesh read_mesh(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, 0, 0, "mesh file not found");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw InputError(path, 0, 0, std::string("cannot read mesh: ") + importer.GetErrorString());
  removal::TriangleMesh mesh;
  // Weld by exact coordinates: STL stores each triangle's corners separately.
  std::map<std::array<float, 3>, int> index_of;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    std::vector<int> remap(am->mNumVertices);
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw InputError(path, 0, 0, "mesh has a vertex that is not a finite number");
      const auto [it, inserted] = index_of.emplace(std::array<float, 3>{p.x, p.y, p.z}, static_cast<int>(mesh.vertices_mm.size()));
      if (inserted) mesh.vertices_mm.emplace_back(p.x, p.y, p.z);
      remap[v] = it->second;
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not surface
      mesh.triangles.emplace_back(remap[face.mIndices[0]], remap[face.mIndices[1]], remap[face.mIndices[2]]);
    }
  }
  if (mesh.triangles.empty()) throw InputError(path, 0, 0, "mesh has no triangles");
  return mesh;
}

void write_stl(const std::string& path, const removal::TriangleMesh& mesh) {
  if (mesh.triangles.empty()) {
    // Nothing left (the stock cut away): a binary STL of no triangles, which assimp's
    // exporter refuses to write.
    write_atomically(path, [&](const std::string& temporary) {
      std::ofstream out(temporary, std::ios::binary);
      const std::string header = "vcut: empty mesh" + std::string(80 - 16, ' ');
      const char count[4] = {0, 0, 0, 0};
      out.write(header.data(), 80);
      out.write(count, 4);
      if (!out) throw InputError(path, 0, 0, "cannot write STL");
    });
    return;
  }
  aiScene scene;
  scene.mRootNode = new aiNode();
  scene.mMaterials = new aiMaterial*[1]{new aiMaterial()};
  scene.mNumMaterials = 1;
  scene.mMeshes = new aiMesh*[1]{new aiMesh()};
  scene.mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  aiMesh& am = *scene.mMeshes[0];
  am.mMaterialIndex = 0;
  am.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  am.mNumVertices = static_cast<unsigned>(mesh.vertices_mm.size());
  am.mVertices = new aiVector3D[am.mNumVertices];
  for (unsigned i = 0; i < am.mNumVertices; ++i) {
    const auto& p = mesh.vertices_mm[i];
    am.mVertices[i] = aiVector3D(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  am.mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  am.mFaces = new aiFace[am.mNumFaces];
  for (unsigned f = 0; f < am.mNumFaces; ++f) {
    aiFace& face = am.mFaces[f];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3];
    for (int c = 0; c < 3; ++c) face.mIndices[c] = static_cast<unsigned>(mesh.triangles[f][c]);
  }
  write_atomically(path, [&](const std::string& temporary) {
    Assimp::Exporter exporter;
    if (exporter.Export(&scene, "stlb", temporary) != AI_SUCCESS)
      throw InputError(path, 0, 0, std::string("cannot write STL: ") + exporter.GetErrorString());
  });
}

namespace {
template <class T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // x86-64 and every target we build for are little-endian
  out.append(bytes, sizeof(T));
}
}  // namespace

void write_deviation_ply(const std::string& path, const removal::TriangleMesh& mesh, const PlyAttributes& a) {
  const std::size_t n = mesh.vertices_mm.size();
  std::string out;
  out.reserve(256 + n * 39 + mesh.triangles.size() * 13);
  out += "ply\nformat binary_little_endian 1.0\ncomment vcut deviation map: deviation in mm, "
         "negative = gouge, positive = excess; move -1 = initial stock; line = NC source line\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property float nx\nproperty float ny\nproperty float nz\n";
  out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "property float deviation\nproperty int move\nproperty int line\n";
  out += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  out += "property list uchar int vertex_indices\nend_header\n";
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) put<float>(out, static_cast<float>(mesh.vertices_mm[i][c]));
    for (int c = 0; c < 3; ++c) put<float>(out, i < a.normals.size() ? static_cast<float>(a.normals[i][c]) : 0.0f);
    const std::array<std::uint8_t, 3> rgb = i < a.colors.size() ? a.colors[i] : std::array<std::uint8_t, 3>{255, 255, 255};
    for (int c = 0; c < 3; ++c) put<std::uint8_t>(out, rgb[static_cast<std::size_t>(c)]);
    put<float>(out, i < a.deviation_mm.size() ? static_cast<float>(a.deviation_mm[i]) : 0.0f);
    put<std::int32_t>(out, i < a.move.size() ? a.move[i] : -1);
    put<std::int32_t>(out, i < a.line.size() ? a.line[i] : 0);
  }
  for (const auto& t : mesh.triangles) {
    put<std::uint8_t>(out, 3);
    for (int c = 0; c < 3; ++c) put<std::int32_t>(out, t[c]);
  }
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
