// Mesh files: any format assimp reads (STL, OBJ, PLY, glTF, ...) in, binary STL out, and
// the deviation PLY with vcut's per-vertex attributes.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "vcut/removal/mesh.h"

namespace vcut::io {

// Reads all meshes of the file (node transforms applied), welds coincident vertices.
// A missing, unreadable or empty file is a vcut::InputError.
removal::TriangleMesh read_mesh(const std::string& path);

// Binary STL (float32 corners in mm, unit face normals), written atomically; a mesh of no
// triangles gives the 80-byte header and a count of 0.
void write_stl(const std::string& path, const removal::TriangleMesh& mesh);

struct PlyAttributes {
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::array<std::uint8_t, 3>> colors;
  std::vector<double> deviation_mm;
  std::vector<int> move;  // -1: initial stock
  std::vector<int> line;  // NC source line, 0 when none
};

// Binary little-endian PLY: x y z nx ny nz red green blue deviation move line; atomic.
void write_deviation_ply(const std::string& path, const removal::TriangleMesh& mesh, const PlyAttributes& attributes);

// Diverging colour map: white at 0, red for gouges (negative), blue for excess
// (positive), saturated at +-scale_mm.
std::array<std::uint8_t, 3> deviation_color(double deviation_mm, double scale_mm);

}  // namespace vcut::io
