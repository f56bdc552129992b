// The workpiece material being cut, behind one interface for the stock engines
// (tri-dexel, the default, and OpenVDB level set). Workpiece frame, mm.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <functional>
#include <variant>
#include <vector>

#include "vcut/removal/mesh.h"
#include "vcut/removal/move.h"

namespace vcut::removal {

struct BoxShape {
  Eigen::Vector3d min_mm, max_mm;
};
struct CylinderShape {
  Eigen::Vector3d base_center_mm;  // centre of the bottom face
  Eigen::Vector3d axis;            // unit, from the bottom face to the top face
  double radius_mm, height_mm;
};
// A mesh stock is a closed TriangleMesh (outward-facing triangles).
using StockShape = std::variant<BoxShape, CylinderShape, TriangleMesh>;

Eigen::AlignedBox3d bounds_of(const StockShape& shape);
double surface_area_mm2(const StockShape& shape);

struct Collision {
  int move = -1;
  double depth_mm = 0.0;  // deepest penetration into material
  Eigen::Vector3d where_mm = Eigen::Vector3d::Zero();
};

struct CutResult {
  double removed_volume_mm3 = 0.0;
  std::vector<Collision> collisions;  // rapids into material, deeper than the tolerance
};

struct CutOptions {
  double collision_tolerance_mm = 0.01;
  // Called now and then with (moves done, moves in all); from the calling thread only.
  std::function<void(std::size_t, std::size_t)> progress;
};

// A triangle mesh of the stock's surface; each vertex knows the move that made it
// (-1: a face of the initial stock never cut).
struct SurfaceMesh {
  TriangleMesh mesh;
  std::vector<int> vertex_move;
};

class Stock {
 public:
  virtual ~Stock() = default;
  // Removes every non-rapid move's swept volume, in program order; probes rapids. Moves
  // are pulled from the source a batch at a time; their ids (SurfaceMesh::vertex_move,
  // Collision::move) count on across calls. Collision::move counts from this call's first.
  virtual CutResult cut(MoveSource& moves, const CutOptions& options) = 0;
  CutResult cut(const MoveList& moves, const CutOptions& options) {
    ListSource source(moves);
    return cut(source, options);
  }
  virtual SurfaceMesh surface() const = 0;
  virtual double volume_mm3() const = 0;
  virtual std::size_t memory_bytes() const = 0;
  virtual Eigen::AlignedBox3d bounds() const = 0;
};

}  // namespace vcut::removal
