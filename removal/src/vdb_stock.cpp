#include "vcut/removal/vdb_stock.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <optional>
#include <array>
#include <cmath>
#include <map>
#include <functional>
#include <mutex>
#include <stdexcept>

#include "vcut/removal/compare.h"
#include "vcut/removal/sweep.h"
#include "distance.h"
#include "initial_stock.h"
#include "move_batches.h"
#include "surface_projection.h"

namespace vcut::removal {
namespace {

using openvdb::Coord;
using FloatLeaf = openvdb::FloatTree::LeafNodeType;
constexpr int kLeafDim = 8;
constexpr int kLeafVoxels = kLeafDim * kLeafDim * kLeafDim;
constexpr int kCoarse = 4;  // leaves per side of a coarse culling cell
constexpr int kNoMove = -1;
constexpr std::size_t kBatchMoves = 8192;  // moves binned and cut together (memory bound)
// volumeToMesh adaptivity: merges cells on flat regions; vertices go back onto the exact
// surface afterwards, so only the triangles between them approximate it.
constexpr double kMeshAdaptivity = 0.05;

int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Fraction of a voxel inside material for level-set value phi (mm): exact for a plane
// crossing a column of voxels along its normal, the usual first-order volume estimate.
inline double inside_fraction(double phi, double voxel) { return std::clamp(0.5 - phi / voxel, 0.0, 1.0); }

enum class EntryKind : std::uint8_t { Clear, Near, Probe };
struct Entry {
  std::int64_t leaf;  // linear index into the occupancy map
  std::int32_t move;
  EntryKind kind;
  bool operator<(const Entry& o) const { return leaf != o.leaf ? leaf < o.leaf : move < o.move; }
};

// The move that last changed each voxel of a leaf block: the block's distinct move ids (a
// palette) and one byte per voxel into it. A block is shaped by a few moves, so this takes
// about a quarter of an Int32 grid's memory; a block with more than 255 distinct ids keeps
// them all.
class BlockIds {
 public:
  void read(std::int32_t* out) const {
    if (!full_.empty()) {
      std::copy(full_.begin(), full_.end(), out);
      return;
    }
    for (int n = 0; n < kLeafVoxels; ++n) out[n] = palette_[index_[static_cast<std::size_t>(n)]];
  }
  std::int32_t at(int n) const {
    return full_.empty() ? palette_[index_[static_cast<std::size_t>(n)]] : full_[static_cast<std::size_t>(n)];
  }
  void write(const std::int32_t* in) {
    palette_.clear();
    full_.clear();
    index_.resize(kLeafVoxels);
    for (int n = 0; n < kLeafVoxels; ++n) {
      const std::int32_t id = in[n];
      if (n > 0 && id == in[n - 1]) {
        index_[static_cast<std::size_t>(n)] = index_[static_cast<std::size_t>(n - 1)];
        continue;
      }
      const auto it = std::find(palette_.begin(), palette_.end(), id);
      if (it == palette_.end() && palette_.size() == 255) {
        full_.assign(in, in + kLeafVoxels);
        palette_.clear();
        index_.clear();
        index_.shrink_to_fit();
        return;
      }
      const std::size_t k = static_cast<std::size_t>(it - palette_.begin());  // palette_.size() when new
      if (k == palette_.size()) palette_.push_back(id);
      index_[static_cast<std::size_t>(n)] = static_cast<std::uint8_t>(k);
    }
    palette_.shrink_to_fit();
  }
  std::size_t bytes() const {
    return sizeof(*this) + palette_.capacity() * sizeof(std::int32_t) + index_.capacity() +
           full_.capacity() * sizeof(std::int32_t);
  }

 private:
  std::vector<std::int32_t> palette_;
  std::vector<std::uint8_t> index_;  // kLeafVoxels, empty when `full_` holds the ids
  std::vector<std::int32_t> full_;
};

struct BlockResult {
  float value[kLeafVoxels];
  std::int32_t id[kLeafVoxels];
  bool all_outside = false;
  bool all_inside = false;      // every voxel at -w or deeper: never cut (no move ids either)
  bool changed = false;         // any value or move id differs from what the block held
  double removed_voxels = 0.0;  // in voxel volumes
  std::vector<Collision> probes;
};

}  // namespace

struct VdbStock::Impl {
  double v = 0.1;  // voxel size, mm
  double w = 0.3;  // narrow-band half width, mm
  openvdb::FloatGrid::Ptr grid;
  // Move ids by leaf block (the occupancy map's index); none: every voxel kNoMove.
  std::vector<std::unique_ptr<BlockIds>> block_ids;
  Eigen::AlignedBox3d shape_bounds;
  // Occupancy over leaf blocks: 1 where the block may hold material or near-surface values.
  // Only the region of the initial stock (+ band) can ever hold material.
  Coord leaf_min, leaf_dims, coarse_dims;
  std::vector<std::uint8_t> occupied;
  std::vector<std::int32_t> coarse_count;
  // For placing mesh vertices on the exact surface: the initial stock's signed distance and
  // every move cut so far (the move ids in block_ids index `moves`).
  std::function<double(const Eigen::Vector3d&)> initial_distance;
  std::shared_ptr<const DesignDistance> initial_mesh;
  detail::MoveRecord moves;
  std::vector<Cutter> cutters;

  std::int64_t leaf_index(int i, int j, int k) const {
    return (static_cast<std::int64_t>(k) * leaf_dims.y() + j) * leaf_dims.x() + i;
  }
  std::int64_t coarse_index(int i, int j, int k) const {
    return (static_cast<std::int64_t>(k) * coarse_dims.y() + j) * coarse_dims.x() + i;
  }
  Coord leaf_origin(int i, int j, int k) const {
    return Coord((leaf_min.x() + i) * kLeafDim, (leaf_min.y() + j) * kLeafDim, (leaf_min.z() + k) * kLeafDim);
  }
  Eigen::Vector3d voxel_position(const Coord& c) const { return Eigen::Vector3d(c.x() * v, c.y() * v, c.z() * v); }

  void setup_region(const Eigen::AlignedBox3d& bounds) {
    shape_bounds = bounds;
    const double pad = w + 2 * v;
    Coord lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = floor_div(static_cast<int>(std::floor((bounds.min()(a) - pad) / v)), kLeafDim);
      hi[a] = floor_div(static_cast<int>(std::ceil((bounds.max()(a) + pad) / v)), kLeafDim);
    }
    leaf_min = lo;
    leaf_dims = hi - lo + Coord(1);
    coarse_dims = Coord((leaf_dims.x() + kCoarse - 1) / kCoarse, (leaf_dims.y() + kCoarse - 1) / kCoarse,
                        (leaf_dims.z() + kCoarse - 1) / kCoarse);
    occupied.assign(static_cast<std::size_t>(leaf_dims.x()) * leaf_dims.y() * leaf_dims.z(), 0);
    block_ids.clear();
    block_ids.resize(occupied.size());
    coarse_count.assign(static_cast<std::size_t>(coarse_dims.x()) * coarse_dims.y() * coarse_dims.z(), 0);
  }

  template <class Sdf>
  void build_analytic(const Sdf& sdf) {
    const double half_diag = 3.5 * std::sqrt(3.0) * v;
    tbb::enumerable_thread_specific<std::vector<FloatLeaf*>> made;
    tbb::parallel_for(0, leaf_dims.z(), [&](int k) {
      auto& mine = made.local();
      for (int j = 0; j < leaf_dims.y(); ++j)
        for (int i = 0; i < leaf_dims.x(); ++i) {
          const Coord o = leaf_origin(i, j, k);
          const double s = sdf(voxel_position(o) + Eigen::Vector3d::Constant(3.5 * v));
          if (std::abs(s) > w + half_diag) continue;
          auto* leaf = new FloatLeaf(o, static_cast<float>(w));
          for (int n = 0; n < kLeafVoxels; ++n) {
            const double phi = sdf(voxel_position(leaf->offsetToGlobalCoord(n)));
            if (std::abs(phi) < w)
              leaf->setValueOn(n, static_cast<float>(phi));
            else
              leaf->setValueOff(n, static_cast<float>(phi < 0 ? -w : w));
          }
          mine.push_back(leaf);
        }
    });
    auto& tree = grid->tree();
    for (auto& list : made)
      for (FloatLeaf* leaf : list) tree.addLeaf(leaf);
    openvdb::tools::signedFloodFill(tree);
  }

  void compute_occupancy() {
    const auto& tree = grid->tree();
    for (int k = 0; k < leaf_dims.z(); ++k)
      for (int j = 0; j < leaf_dims.y(); ++j)
        for (int i = 0; i < leaf_dims.x(); ++i) {
          const Coord o = leaf_origin(i, j, k);
          bool material = false;
          if (const FloatLeaf* leaf = tree.probeConstLeaf(o)) {
            for (int n = 0; n < kLeafVoxels && !material; ++n) material = leaf->getValue(n) < w;
          } else {
            material = tree.getValue(o) < w;
          }
          if (material) mark(i, j, k, true);
        }
  }

  void mark(int i, int j, int k, bool on) {
    std::uint8_t& cell = occupied[static_cast<std::size_t>(leaf_index(i, j, k))];
    if (cell == static_cast<std::uint8_t>(on)) return;
    cell = on;
    coarse_count[static_cast<std::size_t>(coarse_index(i / kCoarse, j / kCoarse, k / kCoarse))] += on ? 1 : -1;
  }

  // `continues`: the move follows on from the cutter's previous cutting move (same cutter and
  // axis, starting where it ended), so blocks where its start cutter is nearest change not.
  void bin(const TranslationSweep& sweep, bool rapid, bool continues, std::int32_t move,
           std::vector<Entry>& out) const {
    const double half_diag = 3.5 * std::sqrt(3.0) * v;
    const double coarse_half_diag = (kCoarse * kLeafDim * 0.5 - 0.5) * std::sqrt(3.0) * v;
    const Eigen::AlignedBox3d& b = sweep.bounds();
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = floor_div(static_cast<int>(std::floor((b.min()(a) - w) / v)), kLeafDim) - leaf_min[a];
      hi[a] = floor_div(static_cast<int>(std::ceil((b.max()(a) + w) / v)), kLeafDim) - leaf_min[a];
      lo[a] = std::max(lo[a], 0);
      hi[a] = std::min(hi[a], leaf_dims[a] - 1);
      if (lo[a] > hi[a]) return;
    }
    for (int ck = lo[2] / kCoarse; ck <= hi[2] / kCoarse; ++ck)
      for (int cj = lo[1] / kCoarse; cj <= hi[1] / kCoarse; ++cj)
        for (int ci = lo[0] / kCoarse; ci <= hi[0] / kCoarse; ++ci) {
          if (coarse_count[static_cast<std::size_t>(coarse_index(ci, cj, ck))] == 0) continue;
          const Coord co = leaf_origin(ci * kCoarse, cj * kCoarse, ck * kCoarse);
          const double sc =
              sweep.distance(voxel_position(co) + Eigen::Vector3d::Constant((kCoarse * kLeafDim * 0.5 - 0.5) * v),
                             w + coarse_half_diag + v);
          if (sc > w + coarse_half_diag) continue;
          if (continues &&
              sweep.start_dominates(Eigen::AlignedBox3d(
                  voxel_position(co), voxel_position(co) + Eigen::Vector3d::Constant((kCoarse * kLeafDim - 1) * v)))) {
            continue;
          }
          for (int k = std::max(lo[2], ck * kCoarse); k <= std::min(hi[2], ck * kCoarse + kCoarse - 1); ++k)
            for (int j = std::max(lo[1], cj * kCoarse); j <= std::min(hi[1], cj * kCoarse + kCoarse - 1); ++j)
              for (int i = std::max(lo[0], ci * kCoarse); i <= std::min(hi[0], ci * kCoarse + kCoarse - 1); ++i) {
                const std::int64_t index = leaf_index(i, j, k);
                if (!occupied[static_cast<std::size_t>(index)]) continue;
                const double s = sweep.distance(
                    voxel_position(leaf_origin(i, j, k)) + Eigen::Vector3d::Constant(3.5 * v), w + half_diag + v);
                if (s > w + half_diag) continue;
                const Eigen::Vector3d corner = voxel_position(leaf_origin(i, j, k));
                if (continues && !rapid &&
                    sweep.start_dominates(Eigen::AlignedBox3d(corner, corner + Eigen::Vector3d::Constant(7 * v)))) {
                  continue;
                }
                const EntryKind kind = rapid                  ? EntryKind::Probe
                                       : s < -(w + half_diag) ? EntryKind::Clear
                                                              : EntryKind::Near;
                out.push_back({index, move, kind});
              }
        }
  }

  Coord origin_of(std::int64_t index) const {
    const std::int64_t i = index % leaf_dims.x();
    const std::int64_t j = (index / leaf_dims.x()) % leaf_dims.y();
    const std::int64_t k = index / (static_cast<std::int64_t>(leaf_dims.x()) * leaf_dims.y());
    return leaf_origin(static_cast<int>(i), static_cast<int>(j), static_cast<int>(k));
  }

  // `id_offset` turns a batch-local move index into the move id stored in block_ids.
  void process(const Entry* begin, const Entry* end, const std::vector<TranslationSweep>& sweeps,
               const std::vector<std::uint8_t>& continues, int id_offset, BlockResult& r) const {
    const Coord o = origin_of(begin->leaf);
    const auto& tree = grid->tree();
    if (const FloatLeaf* leaf = tree.probeConstLeaf(o)) {
      for (int n = 0; n < kLeafVoxels; ++n) r.value[n] = leaf->getValue(n);
    } else {
      std::fill(r.value, r.value + kLeafVoxels, tree.getValue(o));
    }
    if (const BlockIds* ids = block_ids[static_cast<std::size_t>(begin->leaf)].get()) {
      ids->read(r.id);
    } else {
      std::fill(r.id, r.id + kLeafVoxels, kNoMove);
    }
    std::array<std::int32_t, kLeafVoxels> ids_before;
    std::array<float, kLeafVoxels> values_before;
    std::copy(r.id, r.id + kLeafVoxels, ids_before.begin());
    std::copy(r.value, r.value + kLeafVoxels, values_before.begin());
    const float wf = static_cast<float>(w);
    double before = 0.0;
    int not_outside = 0;
    for (int n = 0; n < kLeafVoxels; ++n) {
      before += inside_fraction(r.value[n], v);
      not_outside += r.value[n] < wf;
    }
    Eigen::Vector3d position[kLeafVoxels];
    for (int n = 0; n < kLeafVoxels; ++n) position[n] = voxel_position(FloatLeaf::offsetToLocalCoord(n) + o);

    for (const Entry* e = begin; e != end && not_outside > 0; ++e) {
      const TranslationSweep& sweep = sweeps[static_cast<std::size_t>(e->move)];
      switch (e->kind) {
        case EntryKind::Clear:
          for (int n = 0; n < kLeafVoxels; ++n)
            if (r.value[n] < wf) {
              r.value[n] = wf;
              r.id[n] = id_offset + e->move;
            }
          not_outside = 0;
          break;
        case EntryKind::Near: {
          const bool follows = continues[static_cast<std::size_t>(e->move)] != 0;
          for (int n = 0; n < kLeafVoxels; ++n) {
            if (r.value[n] >= wf) continue;
            if (follows && sweep.start_dominates(position[n])) continue;  // the previous move's end
            const double cut = -sweep.distance(position[n], w);
            if (cut > r.value[n]) {
              r.value[n] = static_cast<float>(std::min(cut, w));
              r.id[n] = id_offset + e->move;
              not_outside -= r.value[n] >= wf;
            }
          }
          break;
        }
        case EntryKind::Probe: {
          Collision deepest{e->move, 0.0, Eigen::Vector3d::Zero()};
          for (int n = 0; n < kLeafVoxels; ++n) {
            if (r.value[n] >= 0.0f) continue;
            if (sweep.distance(position[n]) >= 0.0) continue;
            // Depth below the material surface; the band stores at most w, deeper voxels
            // take the initial stock's depth (exact where no cut came near).
            const double depth =
                r.value[n] > -wf ? -static_cast<double>(r.value[n]) : std::max(w, -initial_distance(position[n]));
            if (depth > deepest.depth_mm) deepest = {e->move, depth, position[n]};
          }
          if (deepest.depth_mm > 0.0) r.probes.push_back(deepest);
          break;
        }
      }
    }
    double after = 0.0;
    for (int n = 0; n < kLeafVoxels; ++n) after += inside_fraction(r.value[n], v);
    r.removed_voxels = before - after;
    r.all_outside = not_outside == 0;
    r.all_inside = std::all_of(r.value, r.value + kLeafVoxels, [&](float phi) { return phi <= -wf; });
    r.changed = r.all_outside || !std::equal(r.value, r.value + kLeafVoxels, values_before.begin()) ||
                !std::equal(r.id, r.id + kLeafVoxels, ids_before.begin());
  }

  void write_back(const Coord& o, std::int64_t index, const BlockResult& r) {
    auto& tree = grid->tree();
    const float wf = static_cast<float>(w);
    std::unique_ptr<BlockIds>& ids = block_ids[static_cast<std::size_t>(index)];
    if (!r.changed) return;  // visited, not cut: no leaf made where a tile was
    if (r.all_inside) {
      // Solid material at -w and deeper, as the stock's interior tiles hold it.
      tree.addTile(1, o, -wf, false);
      ids.reset();
      return;
    }
    if (r.all_outside) {
      tree.addTile(1, o, wf, false);
      ids.reset();
      const int i = static_cast<int>(index % leaf_dims.x());
      const int j = static_cast<int>((index / leaf_dims.x()) % leaf_dims.y());
      const int k = static_cast<int>(index / (static_cast<std::int64_t>(leaf_dims.x()) * leaf_dims.y()));
      mark(i, j, k, false);
      return;
    }
    FloatLeaf* leaf = tree.touchLeaf(o);
    for (int n = 0; n < kLeafVoxels; ++n) {
      const float phi = r.value[n];
      if (std::abs(phi) < wf)
        leaf->setValueOn(n, phi);
      else
        leaf->setValueOff(n, phi < 0 ? -wf : wf);
    }
    if (std::all_of(r.id, r.id + kLeafVoxels, [](std::int32_t id) { return id == kNoMove; })) {
      ids.reset();
    } else {
      if (!ids) ids = std::make_unique<BlockIds>();
      ids->write(r.id);
    }
  }

  // The move id of a voxel (kNoMove: never cut, or outside the stock's region).
  std::int32_t id_at(const Coord& c) const {
    Coord leaf;
    for (int a = 0; a < 3; ++a) {
      leaf[a] = floor_div(c[a], kLeafDim) - leaf_min[a];
      if (leaf[a] < 0 || leaf[a] >= leaf_dims[a]) return kNoMove;
    }
    const BlockIds* ids = block_ids[static_cast<std::size_t>(leaf_index(leaf.x(), leaf.y(), leaf.z()))].get();
    return ids ? ids->at(static_cast<int>(FloatLeaf::coordToOffset(c))) : kNoMove;
  }
};

Eigen::AlignedBox3d bounds_of(const StockShape& shape) {
  if (const auto* box = std::get_if<BoxShape>(&shape)) return {box->min_mm, box->max_mm};
  Eigen::AlignedBox3d b;
  if (const auto* c = std::get_if<CylinderShape>(&shape)) {
    // Box of the two end disks: per axis, the disk extends radius * sqrt(1 - axis_a^2).
    const Eigen::Vector3d ext =
        (Eigen::Vector3d::Ones() - c->axis.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt() * c->radius_mm;
    for (const Eigen::Vector3d& p : {c->base_center_mm, Eigen::Vector3d(c->base_center_mm + c->height_mm * c->axis)}) {
      b.extend(p - ext);
      b.extend(p + ext);
    }
    return b;
  }
  for (const auto& p : std::get<TriangleMesh>(shape).vertices_mm) b.extend(p);
  return b;
}

double surface_area_mm2(const StockShape& shape) {
  if (const auto* box = std::get_if<BoxShape>(&shape)) {
    const Eigen::Vector3d e = box->max_mm - box->min_mm;
    return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  }
  if (const auto* c = std::get_if<CylinderShape>(&shape))
    return 2.0 * M_PI * c->radius_mm * (c->radius_mm + c->height_mm);
  const auto& mesh = std::get<TriangleMesh>(shape);
  double area = 0.0;
  for (const auto& t : mesh.triangles) {
    const auto& a = mesh.vertices_mm[static_cast<std::size_t>(t[0])];
    area += 0.5 * (mesh.vertices_mm[static_cast<std::size_t>(t[1])] - a)
                      .cross(mesh.vertices_mm[static_cast<std::size_t>(t[2])] - a)
                      .norm();
  }
  return area;
}

std::size_t estimate_vdb_memory_bytes(const StockShape& shape, double voxel_mm) {
  // A surface of area A crosses about 1.5 A / (8v)^2 leaves (the band straddles leaf
  // boundaries); each holds 512 values and 512 one-byte move-id indices, plus a palette,
  // masks and node overhead.
  const double leaf_side = kLeafDim * voxel_mm;
  const double leaves = 1.5 * surface_area_mm2(shape) / (leaf_side * leaf_side);
  const double per_leaf = kLeafVoxels * (sizeof(float) + sizeof(std::uint8_t)) + 384.0;
  const Eigen::Vector3d extent = bounds_of(shape).sizes();
  const double map_bytes = (extent / leaf_side + Eigen::Vector3d::Constant(4.0)).prod();
  return static_cast<std::size_t>(leaves * per_leaf + map_bytes);
}

VdbStock::VdbStock(const StockShape& shape, double voxel_mm) : impl_(std::make_unique<Impl>()) {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
  if (!(voxel_mm > 0.0)) throw std::invalid_argument("voxel size must be positive");
  Impl& m = *impl_;
  m.v = voxel_mm;
  m.w = kVdbHalfWidthVoxels * voxel_mm;
  const auto transform = openvdb::math::Transform::createLinearTransform(voxel_mm);
  m.setup_region(bounds_of(shape));
  if (!std::holds_alternative<TriangleMesh>(shape)) {
    m.grid = openvdb::FloatGrid::create(static_cast<float>(m.w));
    m.grid->setTransform(transform);
    m.initial_distance = detail::initial_distance(shape, m.initial_mesh);
    m.build_analytic(m.initial_distance);
  } else {
    const auto& mesh = std::get<TriangleMesh>(shape);
    m.initial_distance = detail::initial_distance(shape, m.initial_mesh);
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    for (const auto& p : mesh.vertices_mm)
      points.emplace_back(static_cast<float>(p.x() / voxel_mm), static_cast<float>(p.y() / voxel_mm),
                          static_cast<float>(p.z() / voxel_mm));
    for (const auto& t : mesh.triangles)
      triangles.emplace_back(static_cast<unsigned>(t[0]), static_cast<unsigned>(t[1]), static_cast<unsigned>(t[2]));
    openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(points, triangles);
    m.grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
        adapter, *transform, static_cast<float>(kVdbHalfWidthVoxels), static_cast<float>(kVdbHalfWidthVoxels));
  }
  m.grid->setGridClass(openvdb::GRID_LEVEL_SET);
  m.compute_occupancy();
}

VdbStock::~VdbStock() = default;

double VdbStock::voxel_mm() const { return impl_->v; }

CutResult VdbStock::cut(MoveSource& source, const CutOptions& options) {
  Impl& m = *impl_;
  CutResult result;
  const std::size_t total = source.size_hint();
  const std::vector<Cutter>& cutters = source.cutters();
  std::map<int, Collision> collisions;
  double removed_voxels = 0.0;
  // Move ids count across calls: remember every move with its cutter.
  const int id_base = m.moves.next_id();
  const int cutter_base = detail::remember_cutters(cutters, m.cutters);
  // Moves that follow on from the cutter's previous cutting move (rapids and probes cut
  // nothing in between): where their start cutter is the nearest, the previous move has
  // already cut exactly that, and they are not evaluated there.
  std::optional<Move> last_cut;
  detail::MoveBatches batches(source);
  std::vector<Move> batch;
  for (std::size_t first = 0;; first += batch.size()) {
    const std::size_t count = std::min(kBatchMoves, batches.fill(kBatchMoves));
    if (count == 0) break;
    batch.assign(batches.held().begin(), batches.held().begin() + static_cast<std::ptrdiff_t>(count));
    batches.drop(count);
    const std::size_t last = first + count;
    m.moves.append(batch.data(), batch.size(), cutter_base);
    std::vector<std::uint8_t> batch_follows(batch.size(), 0);
    for (std::size_t i = 0; i < batch.size(); ++i) {
      const Move& move = batch[i];
      if (move.rapid) continue;
      if (last_cut)
        batch_follows[i] =
            last_cut->cutter == move.cutter && last_cut->end_mm == move.start_mm && last_cut->axis == move.axis;
      last_cut = move;
    }
    std::vector<TranslationSweep> sweeps;
    sweeps.reserve(last - first);
    for (const Move& move : batch) sweeps.emplace_back(cutters.at(static_cast<std::size_t>(move.cutter)), move);
    // 1. Bin every move of the batch to the leaf blocks its sweep can change.
    tbb::enumerable_thread_specific<std::vector<Entry>> binned;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, 16), [&](const auto& range) {
      auto& out = binned.local();
      for (std::size_t i = range.begin(); i != range.end(); ++i)
        m.bin(sweeps[i - first], batch[i - first].rapid, batch_follows[i - first] != 0,
              static_cast<std::int32_t>(i - first), out);
    });
    std::vector<Entry> entries;
    for (auto& part : binned) entries.insert(entries.end(), part.begin(), part.end());
    // (leaf, move) pairs are unique, so the order after sorting does not depend on threads.
    tbb::parallel_sort(entries.begin(), entries.end());
    std::vector<std::size_t> group_start;
    for (std::size_t e = 0; e < entries.size(); ++e)
      if (e == 0 || entries[e].leaf != entries[e - 1].leaf) group_start.push_back(e);
    group_start.push_back(entries.size());
    // 2. Cut every block (within a block the moves apply in program order), then write
    // back serially in block order; blocks go in chunks to bound the scratch memory.
    const std::size_t groups = group_start.size() - 1;
    constexpr std::size_t kChunk = 16384;
    std::vector<BlockResult> blocks(std::min(groups, kChunk));
    for (std::size_t g0 = 0; g0 < groups; g0 += kChunk) {
      const std::size_t g1 = std::min(groups, g0 + kChunk);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(g0, g1, 4), [&](const auto& range) {
        for (std::size_t g = range.begin(); g != range.end(); ++g) {
          BlockResult& r = blocks[g - g0];
          r.probes.clear();
          m.process(entries.data() + group_start[g], entries.data() + group_start[g + 1], sweeps, batch_follows,
                    id_base + static_cast<int>(first), r);
        }
      });
      for (std::size_t g = g0; g < g1; ++g) {
        const BlockResult& r = blocks[g - g0];
        const std::int64_t index = entries[group_start[g]].leaf;
        m.write_back(m.origin_of(index), index, r);
        removed_voxels += r.removed_voxels;
        for (Collision c : r.probes) {
          c.move += static_cast<int>(first);
          auto [it, inserted] = collisions.emplace(c.move, c);
          if (!inserted && c.depth_mm > it->second.depth_mm) it->second = c;
        }
      }
    }
    if (options.progress) options.progress(last, std::max(total, last));
  }
  // Leaves left uniform (all +w or all -w, clamped values) become tiles: less to keep and to mesh.
  openvdb::tools::pruneLevelSet(m.grid->tree());
  result.removed_volume_mm3 = removed_voxels * m.v * m.v * m.v;
  for (const auto& [move, c] : collisions)
    if (c.depth_mm > options.collision_tolerance_mm) result.collisions.push_back(c);
  return result;
}

SurfaceMesh VdbStock::surface() const {
  const Impl& m = *impl_;
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*m.grid, points, triangles, quads, 0.0, kMeshAdaptivity);
  SurfaceMesh mesh = detail::mesh_from_polygons(points, triangles, quads);
  // Each vertex goes onto the exact machined surface F(x) = max(initial(x), -s_m(x)) = 0,
  // where the moves m are those that shaped the voxels around it, by Newton steps; it
  // takes the id of the move whose sweep is its surface (-1: the initial stock).
  const std::size_t count = points.size();
  mesh.vertex_move.assign(count, kNoMove);
  auto nearby = [&](std::size_t v, std::vector<int>& list) {
    list.clear();
    const auto& p = points[v];
    const Coord base(static_cast<int>(std::floor(p.x() / m.v)) - 1, static_cast<int>(std::floor(p.y() / m.v)) - 1,
                     static_cast<int>(std::floor(p.z() / m.v)) - 1);
    for (int c = 0; c < 64; ++c) {
      const int id = m.id_at(base.offsetBy(c & 3, (c >> 2) & 3, (c >> 4) & 3));
      if (id != kNoMove && std::find(list.begin(), list.end(), id) == list.end()) list.push_back(id);
    }
    std::sort(list.begin(), list.end());
  };
  // A vertex lies in its voxel cell, so the surface is within a cell diagonal (sqrt(3) v).
  detail::project_onto_machined_surface(m.moves, m.cutters, m.initial_distance, nearby, 2.0 * m.v, mesh);
  return mesh;
}

double VdbStock::volume_mm3() const {
  const Impl& m = *impl_;
  double voxels = 0.0;
  for (auto it = m.grid->tree().cbeginValueAll(); it; ++it) {
    const double f = inside_fraction(*it, m.v);
    voxels += it.isVoxelValue() ? f : f * static_cast<double>(it.getVoxelCount());
  }
  return voxels * m.v * m.v * m.v;
}

std::size_t VdbStock::memory_bytes() const {
  const Impl& m = *impl_;
  std::size_t ids = m.block_ids.size() * sizeof(m.block_ids[0]);
  for (const auto& b : m.block_ids)
    if (b) ids += b->bytes();
  return m.grid->memUsage() + ids + m.occupied.size() + m.coarse_count.size() * sizeof(std::int32_t);
}

Eigen::AlignedBox3d VdbStock::bounds() const { return impl_->shape_bounds; }

}  // namespace vcut::removal
