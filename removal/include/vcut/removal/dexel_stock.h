// The stock as a tri-dexel model: three families of rays parallel to the x, y and z axes on
// a lattice of spacing v (the rays through the lattice nodes (i v, j v, k v)), each ray a
// sorted list of material intervals whose endpoints carry the move that made them.
// Exact along its rays; the surface mesh comes from the dexel hits (ARCHITECTURE §8).
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "vcut/removal/stock.h"

namespace vcut::removal {

// One material interval of a ray: axis coordinates (mm) of its two ends and the moves that
// made them (-1: the initial stock). Floats: at |x| <= 1000 mm they resolve 0.06 um, far
// below the 1 um the endpoints are held to (measured in the dexel tests).
struct DexelSegment {
  float lo_mm, hi_mm;
  std::int32_t lo_move, hi_move;
};

// A point of the stock's surface where a ray enters or leaves material.
struct DexelEndpoint {
  Eigen::Vector3d x_mm;
  int move;  // -1: a face of the initial stock
  int axis;  // the ray family: 0 x, 1 y, 2 z
};

// Bytes the rays of a stock of this shape need at spacing v (one interval per ray).
std::size_t estimate_dexel_memory_bytes(const StockShape& shape, double spacing_mm);

class DexelStock final : public Stock {
 public:
  // A mesh stock must be closed (std::invalid_argument otherwise): rays are classified by
  // the winding of the triangles they cross.
  DexelStock(const StockShape& shape, double spacing_mm);
  ~DexelStock() override;

  using Stock::cut;
  CutResult cut(MoveSource& moves, const CutOptions& options) override;
  SurfaceMesh surface() const override;
  double volume_mm3() const override;
  std::size_t memory_bytes() const override;
  Eigen::AlignedBox3d bounds() const override;

  // The surface merges flat regions (octree blocks of up to 16 cells whose crossings lie
  // within v/25 of one plane) into larger triangles; off, only exact axis planes merge
  // (untouched stock faces, level floors), so that no triangle crosses a crease: for
  // measurements that compare two meshes to within v/100, as studies and machine-error
  // runs do.
  void set_flat_merging(bool on);

  double spacing_mm() const;
  // The intervals of the ray of family `axis` through the lattice point whose other two
  // coordinates (increasing axis order) are (u, w) = (iu v, iw v); empty outside the lattice.
  std::vector<DexelSegment> ray(int axis, int iu, int iw) const;
  // Every interval endpoint of every ray, family by family in lattice order.
  std::vector<DexelEndpoint> endpoints() const;
  // The same a row of rays at a time, without the whole list (9.3 M endpoints, 296 MB on the
  // S-piece at 0.05 mm): the rows of the three families in turn, row r's endpoints into
  // `out` (replaced) in the order endpoints() lists them.
  std::size_t endpoint_rows() const;
  void row_endpoints(std::size_t row, std::vector<DexelEndpoint>& out) const;

  struct Impl;  // the rays and the moves (dexel_stock.cpp)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace vcut::removal
