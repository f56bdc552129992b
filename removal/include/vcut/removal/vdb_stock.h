// The stock as an OpenVDB narrow-band level set (voxel size v, half width kVdbHalfWidthVoxels = 2 voxels, world
// units mm) with a parallel grid holding, per voxel, the move whose sweep shaped it.
#pragma once

#include <cstddef>
#include <memory>

#include "vcut/removal/stock.h"

namespace vcut::removal {

inline constexpr double kVdbHalfWidthVoxels = 2.0;

// Bytes the stock will need at voxel size v: surface leaves of values and move ids.
std::size_t estimate_vdb_memory_bytes(const StockShape& shape, double voxel_mm);

class VdbStock final : public Stock {
 public:
  VdbStock(const StockShape& shape, double voxel_mm);
  ~VdbStock() override;

  using Stock::cut;
  CutResult cut(MoveSource& moves, const CutOptions& options) override;
  SurfaceMesh surface() const override;
  double volume_mm3() const override;
  std::size_t memory_bytes() const override;
  Eigen::AlignedBox3d bounds() const override;

  double voxel_mm() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vcut::removal
