// DexelStock::surface: the mesher (exact ray crossings, flat regions merged, each vertex with
// the move that made it).
#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <functional>
#include <optional>
#include <unordered_map>

#include "dexel_impl.h"
#include "surface_projection.h"
#include "vcut/removal/morton.h"
#include "vcut/removal/sweep.h"

namespace vcut::removal {

namespace {

// ---- The surface by dual contouring on the rays' lattice ----
//
// Nodes are the lattice points; a node's inside/outside comes from the z ray through it
// (one family decides, so neighbouring cells always agree). A cell (the cube between eight
// nodes) whose nodes differ holds the surface: one vertex, the mean of the crossings on
// its edges where the signs change (each the endpoint of the ray along that edge, exact);
// every edge where the sign changes gives a quad joining the four cells around it. Where
// the surface is flat, cells are merged: the lattice is cut into bricks of 16^3 cells, and
// within a brick an octree block of 2, 4, 8 or 16 cells a side whose cells' points lie
// within kMergeTolerance of one plane shares a single vertex; a quad whose corners now
// coincide becomes a triangle or disappears. Merging only renames vertices, so the mesh
// stays closed across merged and unmerged cells and across bricks. Bricks are meshed in
// parallel and joined in lattice order: the same mesh for any thread count.
constexpr int kBrick = 16;
constexpr int kBrickCells = kBrick * kBrick * kBrick;
constexpr int kBrickLevels = 4;  // 16 = 2^4
// A merged block's points lie within this fraction of the spacing of its plane. (0.04 since
// lone cells no longer keep their blocks apart: W1's height error at 2,000 points is then as
// before, RMS 0.00108 mm against 0.00107, max 0.0058 both, with 653 k vertices against 706 k;
// at 0.05 it was RMS 0.00125 with 464 k.)
constexpr double kMergeTolerance = 0.04;
// A crease-free cell's crossings lie within this fraction of the spacing of one plane.
constexpr double kFlatTolerance = 0.05;
// Crossings this close (mm) to one axis plane lie on it (float endpoints of one face agree).
constexpr double kExactPlane_mm = 1e-6;

// Sets bits first..last (inclusive) of a bit array.
void set_bits(std::uint64_t* words, int first, int last) {
  const int w0 = first >> 6, w1 = last >> 6;
  const std::uint64_t head = ~std::uint64_t{0} << (first & 63);
  const std::uint64_t tail = ~std::uint64_t{0} >> (63 - (last & 63));
  if (w0 == w1) {
    words[w0] |= head & tail;
    return;
  }
  words[w0] |= head;
  for (int w = w0 + 1; w < w1; ++w) words[w] = ~std::uint64_t{0};
  words[w1] |= tail;
}

// A cell's Morton code within its brick (bit 3b + a: bit b of its index along axis a),
// and back, through tables (both sit in the mesher's innermost loops).
constexpr std::array<int, kBrick> kMortonSpread = [] {
  std::array<int, kBrick> t{};
  for (int i = 0; i < kBrick; ++i)
    t[static_cast<std::size_t>(i)] = static_cast<int>(morton_spread(static_cast<std::uint64_t>(i)));
  return t;
}();
int morton(int x, int y, int z) {
  return kMortonSpread[static_cast<std::size_t>(x)] | kMortonSpread[static_cast<std::size_t>(y)] << 1 |
         kMortonSpread[static_cast<std::size_t>(z)] << 2;
}
struct MortonCell {
  std::uint8_t index[3];
};
const std::array<MortonCell, kBrickCells> kMortonCells = [] {
  std::array<MortonCell, kBrickCells> t{};
  for (int code = 0; code < kBrickCells; ++code)
    for (int b = 0; b < kBrickLevels; ++b)
      for (int a = 0; a < 3; ++a)
        t[static_cast<std::size_t>(code)].index[a] =
            static_cast<std::uint8_t>(t[static_cast<std::size_t>(code)].index[a] | ((code >> (3 * b + a)) & 1) << b);
  return t;
}();
// The cells of a brick's square face in Morton order: (i, j) for i's bits at the even places.
const std::array<std::array<int, 2>, kBrick* kBrick> kSquareMorton = [] {
  std::array<std::array<int, 2>, kBrick * kBrick> t{};
  for (int code = 0; code < kBrick * kBrick; ++code)
    for (int b = 0; b < kBrickLevels; ++b) {
      t[static_cast<std::size_t>(code)][0] |= ((code >> (2 * b)) & 1) << b;
      t[static_cast<std::size_t>(code)][1] |= ((code >> (2 * b + 1)) & 1) << b;
    }
  return t;
}();
std::array<int, 3> unmorton(int code) {
  const MortonCell& c = kMortonCells[static_cast<std::size_t>(code)];
  return {c.index[0], c.index[1], c.index[2]};
}

// Node signs of one brick: bit t of column (x, y) is node (x0 + x, y0 + y, z0 + t).
struct BrickSigns {
  std::array<std::uint32_t, (kBrick + 1) * (kBrick + 1)> column{};
  std::uint32_t at(int x, int y) const { return column[static_cast<std::size_t>(y * (kBrick + 1) + x)]; }
  bool inside(int x, int y, int z) const { return (at(x, y) >> z) & 1u; }
};

struct BrickMesh {
  std::array<int, 3> origin;          // lattice index of the brick's first node
  std::vector<std::uint16_t> cells;   // active cells, Morton codes ascending
  std::vector<std::uint32_t> vertex;  // per active cell: index into points
  std::vector<Vector3d> points;
  std::uint32_t first_vertex = 0;  // global index of points[0]
};

// The spread of points about their mean: the sums of d d^T over them, d = p - mean.
// By hand: Eigen's d * d^T into a 3x3 on the stack stalled on store forwarding (a fifth of
// the mesher's time on D32).
struct Spread {
  double xx = 0.0, xy = 0.0, xz = 0.0, yy = 0.0, yz = 0.0, zz = 0.0;
  void add(const Vector3d& d) {
    xx += d.x() * d.x();
    xy += d.x() * d.y();
    xz += d.x() * d.z();
    yy += d.y() * d.y();
    yz += d.y() * d.z();
    zz += d.z() * d.z();
  }
  void add(const Spread& o) {
    xx += o.xx;
    xy += o.xy;
    xz += o.xz;
    yy += o.yy;
    yz += o.yz;
    zz += o.zz;
  }
};

// Whether points of spread `s` lie within `tolerance` of one plane through their mean (the
// plane across the smallest spread), where `for_each` visits them (it calls its argument
// with each, in a fixed order) when the spread alone does not tell.
template <class ForEachPoint>
bool within_one_plane(const Spread& s, const Vector3d& mean, double tolerance, ForEachPoint&& for_each) {
  // The spread's smallest eigenvalue, the sum of the squared offsets from the least-squares
  // plane, is at most n^T S n / |n|^2 for any n. Across the two of its rows that span the
  // most (on a flat sheet, nearly its null direction), a value under tolerance^2 (less a
  // margin for rounding) puts every point within tolerance of that plane: most blocks pass
  // so, without the eigensolver and the second pass (D32: 6.1 M tests, 98 % flat).
  const Vector3d r0(s.xx, s.xy, s.xz), r1(s.xy, s.yy, s.yz), r2(s.xz, s.yz, s.zz);
  Vector3d across = r0.cross(r1);
  for (const Vector3d& c : {Vector3d(r0.cross(r2)), Vector3d(r1.cross(r2))})
    if (c.squaredNorm() > across.squaredNorm()) across = c;
  const double across2 = across.squaredNorm();
  if (across2 > 0.0) {
    const Vector3d s_across(r0.dot(across), r1.dot(across), r2.dot(across));
    if (across.dot(s_across) <= 0.999 * tolerance * tolerance * across2) return true;
  }
  Eigen::Matrix3d spread;
  spread << s.xx, s.xy, s.xz, s.xy, s.yy, s.yz, s.xz, s.yz, s.zz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(spread);
  const Vector3d normal = eig.eigenvectors().col(0);
  bool within = true;
  for_each([&](const Vector3d& p) { within = within && std::abs(normal.dot(p - mean)) <= tolerance; });
  return within;
}

// The same for the points `for_each` visits, their spread summed here.
template <class ForEachPoint>
bool within_one_plane(const Vector3d& mean, double tolerance, ForEachPoint&& for_each) {
  Spread s;
  for_each([&](const Vector3d& p) { s.add(p - mean); });
  return within_one_plane(s, mean, tolerance, for_each);
}

class Contour {
 public:
  explicit Contour(const DexelStock::Impl& m) : m_(m) {
    // Node index range per axis: the y rays span x as u, the x rays y and z.
    lo_ = {m.families[1].lo_u, m.families[0].lo_u, m.families[0].lo_w};
    count_ = {m.families[1].n_u, m.families[0].n_u, m.families[0].n_w};
    for (int a = 0; a < 3; ++a)
      bricks_[static_cast<std::size_t>(a)] = (count_[static_cast<std::size_t>(a)] - 1 + kBrick - 1) / kBrick;
  }

  SurfaceMesh run() {
    const int columns = bricks_[0] * bricks_[1];
    std::vector<std::vector<BrickMesh>> by_column(static_cast<std::size_t>(columns));
    // Node signs a brick column at a time: each node column's inside nodes as bits over the
    // whole height, from which each brick takes its 17.
    const std::size_t words = column_words();
    tbb::enumerable_thread_specific<std::vector<std::uint64_t>> column_bits;
    tbb::enumerable_thread_specific<BrickScratch> scratches;
    tbb::parallel_for(tbb::blocked_range<int>(0, columns, 1), [&](const tbb::blocked_range<int>& range) {
      std::vector<std::uint64_t>& bits = column_bits.local();
      BrickScratch& scratch = scratches.local();
      std::vector<std::uint64_t> in_any(words), in_all(words);
      for (int c = range.begin(); c != range.end(); ++c) {
        const auto [x0, y0] = column_origin(c);
        node_bits(c, bits);
        // Nodes inside in any and in all of the brick column's node columns: a brick whose
        // nodes are all out, or all in, holds no surface (most of a stock's bricks).
        std::fill(in_any.begin(), in_any.end(), 0);
        std::fill(in_all.begin(), in_all.end(), ~std::uint64_t{0});
        for (std::size_t col = 0; col < kNodeColumns; ++col) {
          const std::uint64_t* row = bits.data() + col * words;
          for (std::size_t w = 0; w < words; ++w) {
            in_any[w] |= row[w];
            in_all[w] &= row[w];
          }
        }
        for (int bk = 0; bk < bricks_[2]; ++bk) {
          const int shift = bk * kBrick;
          if (levels(in_any.data(), shift) == 0 || levels(in_all.data(), shift) == kFullColumn) continue;
          BrickSigns sg;
          brick_signs(bits, shift, sg);
          BrickMesh b;
          b.origin = {x0, y0, lo_[2] + shift};
          if (plane(b, sg) || vertices(b, sg, scratch)) by_column[static_cast<std::size_t>(c)].push_back(std::move(b));
        }
      }
    });
    // Bricks in lattice order, numbered; vertices numbered brick after brick.
    column_first_.assign(static_cast<std::size_t>(columns) + 1, 0);
    for (int c = 0; c < columns; ++c)
      column_first_[static_cast<std::size_t>(c) + 1] =
          column_first_[static_cast<std::size_t>(c)] + by_column[static_cast<std::size_t>(c)].size();
    bricks_list_.reserve(column_first_.back());
    for (auto& column : by_column)
      for (BrickMesh& b : column) bricks_list_.push_back(std::move(b));
    by_column.clear();
    std::uint32_t next = 0;
    for (BrickMesh& b : bricks_list_) {
      b.first_vertex = next;
      next += static_cast<std::uint32_t>(b.points.size());
    }
    std::vector<std::vector<Triangle>> faces(bricks_list_.size());
    // Each thread's table of a brick's cells by position, -1 where no cell is, as every
    // brick leaves it.
    tbb::enumerable_thread_specific<CellTable> tables([] {
      CellTable t;
      t.fill(-1);
      return t;
    });
    // A brick column at a time again, its node bits found once for all its bricks.
    tbb::parallel_for(tbb::blocked_range<int>(0, columns, 1), [&](const tbb::blocked_range<int>& range) {
      CellTable& table = tables.local();
      std::vector<std::uint64_t>& bits = column_bits.local();
      for (int c = range.begin(); c != range.end(); ++c) {
        const std::size_t first = column_first_[static_cast<std::size_t>(c)],
                          last = column_first_[static_cast<std::size_t>(c) + 1];
        if (first == last) continue;
        node_bits(c, bits);
        for (std::size_t i = first; i < last; ++i) {
          BrickSigns sg;
          brick_signs(bits, bricks_list_[i].origin[2] - lo_[2], sg);
          quads(bricks_list_[i], sg, table, faces[i]);
        }
      }
    });
    // The bricks' vertices and faces into the mesh, side by side, each brick's lists freed as
    // it is copied (on one thread the copies and the freeing were 0.045 s of W1's 0.78 s
    // contour on two).
    SurfaceMesh mesh;
    std::vector<std::size_t> first_face(bricks_list_.size() + 1, 0);
    for (std::size_t i = 0; i < faces.size(); ++i) first_face[i + 1] = first_face[i] + faces[i].size();
    mesh.mesh.vertices_mm.resize(next);
    mesh.mesh.triangles.resize(first_face.back());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bricks_list_.size(), 64), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        BrickMesh& b = bricks_list_[i];
        std::copy(b.points.begin(), b.points.end(), mesh.mesh.vertices_mm.begin() + b.first_vertex);
        std::copy(faces[i].begin(), faces[i].end(),
                  mesh.mesh.triangles.begin() + static_cast<std::ptrdiff_t>(first_face[i]));
        b = BrickMesh{};
        faces[i] = std::vector<Triangle>{};
      }
    });
    return mesh;
  }

 private:
  using Triangle = Eigen::Vector3i;
  using CellTable = std::array<int, kBrickCells>;  // a brick's vertex per cell, -1: none

  // The runs [k0, k1] of inside nodes (within [k_lo, k_hi]) on the z ray through (i, j):
  // nodes k with lo <= position(k) <= hi for one of its intervals (a node on an endpoint
  // is inside).
  template <class Visit>
  void column_nodes(int i, int j, int k_lo, int k_hi, Visit&& visit) const {
    const Family& z = m_.families[2];
    if (!z.contains(i, j)) return;
    const SegmentList& ray = z.at(i, j);
    for (std::uint32_t s = 0; s < ray.size(); ++s) {
      const float lo = ray.data()[s].lo_mm, hi = ray.data()[s].hi_mm;
      int k0 = static_cast<int>(std::ceil(m_.index_of(lo)));
      while (m_.position(k0) < lo) ++k0;
      while (m_.position(k0 - 1) >= lo) --k0;
      int k1 = static_cast<int>(std::floor(m_.index_of(hi)));
      while (m_.position(k1) > hi) --k1;
      while (m_.position(k1 + 1) <= hi) ++k1;
      k0 = std::max(k0, k_lo);
      k1 = std::min(k1, k_hi);
      if (k0 <= k1) visit(k0, k1);
    }
  }

  static constexpr std::size_t kNodeColumns = (kBrick + 1) * (kBrick + 1);
  static constexpr std::uint32_t kFullColumn = (1u << (kBrick + 1)) - 1u;  // a brick's 17 nodes

  // Lattice x and y of brick column c's first node.
  std::pair<int, int> column_origin(int c) const {
    return {lo_[0] + (c % bricks_[0]) * kBrick, lo_[1] + (c / bricks_[0]) * kBrick};
  }

  // 64-bit words per node column over the lattice's height, with room for a brick's 17
  // bits read past the last node.
  std::size_t column_words() const { return static_cast<std::size_t>(count_[2] + 64) / 64 + 1; }

  // The inside nodes of brick column c's node columns (17 x 17, x fastest), a bit per node
  // over the lattice's height (the bricks' column bits are not kept between the passes:
  // 1.2 KB a brick).
  void node_bits(int c, std::vector<std::uint64_t>& bits) const {
    const std::size_t words = column_words();
    bits.assign(kNodeColumns * words, 0);
    const auto [x0, y0] = column_origin(c);
    for (std::size_t col = 0; col < kNodeColumns; ++col) {
      std::uint64_t* row = bits.data() + col * words;
      column_nodes(x0 + static_cast<int>(col % (kBrick + 1)), y0 + static_cast<int>(col / (kBrick + 1)), lo_[2],
                   lo_[2] + count_[2] - 1, [&](int k0, int k1) { set_bits(row, k0 - lo_[2], k1 - lo_[2]); });
    }
  }

  // Bits shift .. shift + kBrick of a node column's bits.
  static std::uint32_t levels(const std::uint64_t* row, int shift) {
    const std::size_t w = static_cast<std::size_t>(shift) >> 6;
    const int offset = shift & 63;
    std::uint64_t v = row[w] >> offset;
    if (offset > 64 - (kBrick + 1)) v |= row[w + 1] << (64 - offset);
    return static_cast<std::uint32_t>(v) & kFullColumn;
  }

  // The node signs of the brick `shift` nodes up its column, from the column's node bits.
  void brick_signs(const std::vector<std::uint64_t>& bits, int shift, BrickSigns& out) const {
    const std::size_t words = column_words();
    for (std::size_t col = 0; col < kNodeColumns; ++col) out.column[col] = levels(bits.data() + col * words, shift);
  }

  // Where the ray of family `axis` at (iu, iw) crosses between nodes n and n + 1: the
  // ray's endpoint there (the middle when the ray has none: the z rays decided otherwise).
  double crossing(int axis, int iu, int iw, int n) const {
    const Family& f = m_.families[static_cast<std::size_t>(axis)];
    const double a = m_.position(n), b = m_.position(n + 1);
    return f.contains(iu, iw) ? crossing_on(f.at(iu, iw), a, b) : 0.5 * (a + b);
  }
  // The same on a ray of the family, between positions a and b.
  static double crossing_on(const SegmentList& ray, double a, double b) {
    for (std::uint32_t s = 0; s < ray.size(); ++s) {
      const DexelSegment& seg = ray.data()[s];
      if (seg.lo_mm >= a && seg.lo_mm <= b) return seg.lo_mm;
      if (seg.hi_mm >= a && seg.hi_mm <= b) return seg.hi_mm;
      if (seg.lo_mm > b) break;
    }
    return 0.5 * (a + b);
  }

  // The brick's cells along each axis: kBrick, fewer at the lattice's far side.
  std::array<int, 3> cell_limits(const BrickMesh& b) const {
    std::array<int, 3> limit;
    for (std::size_t a = 0; a < 3; ++a) limit[a] = std::min(kBrick, lo_[a] + count_[a] - 1 - b.origin[a]);
    return limit;
  }

  // A whole brick crossed by one axis plane that no cut touched (a stock face, a level
  // floor): every node column steps once along one axis at the same place, and every
  // crossing on that axis is the same number. vertices() would merge all its cells into one
  // vertex; this gives the same cells and that vertex, the mean of their crossings, in
  // closed form (vertices() sums 4 per cell: the same point within rounding) without
  // looking at each cell's twelve edges. False: not such a brick.
  bool plane(BrickMesh& b, const BrickSigns& sg) const {
    // A brick at the lattice's far side holds fewer cells (vertices() stops there too): its
    // nodes beyond the last lattice node take no part (an untouched stock's top and far faces
    // lie in such bricks).
    const std::array<int, 3> limit = cell_limits(b);
    const std::uint32_t nodes = (1u << (limit[2] + 1)) - 1u;  // the z nodes within the lattice
    // Bit k of a pattern: node k inside; its steps: bit k when nodes k and k + 1 differ, for
    // the `cells` cells along the axis.
    auto single_step = [](std::uint32_t pattern, int cells, int& step) {
      const std::uint32_t steps = (pattern ^ (pattern >> 1)) & ((1u << cells) - 1u);
      if (steps == 0 || (steps & (steps - 1)) != 0) return false;
      step = __builtin_ctz(steps);
      return true;
    };
    auto all_columns = [&](auto&& holds) {
      for (int y = 0; y <= limit[1]; ++y)
        for (int x = 0; x <= limit[0]; ++x)
          if (!holds(x, y, sg.at(x, y) & nodes)) return false;
      return true;
    };
    int axis = -1, step = 0;
    const std::uint32_t first = sg.at(0, 0) & nodes;
    if (all_columns([&](int, int, std::uint32_t c) { return c == first; })) {
      if (!single_step(first, limit[2], step)) return false;
      axis = 2;
    } else {
      if (!all_columns([&](int, int, std::uint32_t c) { return c == 0 || c == nodes; })) return false;
      std::uint32_t along_x = 0, along_y = 0;
      for (int k = 0; k <= limit[0]; ++k) along_x |= ((sg.at(k, 0) & nodes) != 0 ? 1u : 0u) << k;
      for (int k = 0; k <= limit[1]; ++k) along_y |= ((sg.at(0, k) & nodes) != 0 ? 1u : 0u) << k;
      const bool by_x =
          all_columns([&](int x, int, std::uint32_t c) { return (c != 0) == (((along_x >> x) & 1u) != 0); });
      const bool by_y =
          all_columns([&](int, int y, std::uint32_t c) { return (c != 0) == (((along_y >> y) & 1u) != 0); });
      if (by_x && single_step(along_x, limit[0], step))
        axis = 0;
      else if (by_y && single_step(along_y, limit[1], step))
        axis = 1;
      else
        return false;
    }
    // The crossings: the rays along `axis` through the brick's nodes of the other two axes.
    const auto [o1, o2] = kOther[static_cast<std::size_t>(axis)];
    const int g = b.origin[static_cast<std::size_t>(axis)] + step;
    const int g1 = b.origin[static_cast<std::size_t>(o1)], g2 = b.origin[static_cast<std::size_t>(o2)];
    // crossing() takes (u, w) as its family orders them: z rays (x, y), x rays (y, z), y rays (x, z).
    const int n1 = limit[static_cast<std::size_t>(o1)], n2 = limit[static_cast<std::size_t>(o2)];
    const double value = crossing(axis, g1, g2, g);
    const Family& f = m_.families[static_cast<std::size_t>(axis)];
    if (f.contains(g1, g2) && f.contains(g1 + n1, g2 + n2)) {
      // All the rays in the family: a row of them at a time (a stock's side faces are such
      // bricks, 289 rays each).
      const double lo = m_.position(g), hi = m_.position(g + 1);
      for (int j = 0; j <= n2; ++j) {
        const SegmentList* row = &f.at(g1, g2 + j);
        for (int i = 0; i <= n1; ++i)
          if (crossing_on(row[i], lo, hi) != value) return false;
      }
    } else {
      for (int j = 0; j <= n2; ++j)
        for (int i = 0; i <= n1; ++i)
          if (crossing(axis, g1 + i, g2 + j, g) != value) return false;
    }
    // The cells at `step` along the axis, in Morton order: with the axis's bits fixed, a
    // code grows with the interleave of the other two indices, o1's bits (o1 < o2) the lower
    // (sorting the codes instead was 4 % of the mesh on an untouched stock).
    b.cells.clear();
    b.cells.reserve(static_cast<std::size_t>(n1 * n2));
    for (const auto [i, j] : kSquareMorton) {
      if (i >= n1 || j >= n2) continue;
      std::array<int, 3> cell;
      cell[static_cast<std::size_t>(axis)] = step;
      cell[static_cast<std::size_t>(o1)] = i;
      cell[static_cast<std::size_t>(o2)] = j;
      b.cells.push_back(static_cast<std::uint16_t>(morton(cell[0], cell[1], cell[2])));
    }
    const std::size_t n = b.cells.size();
    b.vertex.assign(n, 0);
    // The mean of the cells' crossings: `value` along the axis, and across it the middle of
    // the cells' span, nodes g .. g + n of spacing v (positions (g + 0.5) v).
    Vector3d mean;
    mean[axis] = value;
    mean[o1] = (g1 + 0.5 + 0.5 * n1) * m_.v;
    mean[o2] = (g2 + 0.5 + 0.5 * n2) * m_.v;
    b.points.assign(1, mean);
    return true;
  }

  // Per active cell: its crossings (a run of `points`) and which way the surface faces
  // across each of them (bit 2a: toward +a, bit 2a + 1: toward -a, from inside to outside).
  struct Cell {
    std::uint16_t code;
    std::uint8_t facing;
    std::uint8_t count;
    std::uint32_t first;
  };

  // The crossings on one brick's edges, each looked up once: a sign-changing edge is an edge
  // of the four cells around it, all active (D32's rays through its holes hold dozens of
  // intervals to search). Entries are valid while their stamp is the brick's.
  struct CrossingCache {
    static constexpr int kSide = kBrick + 1;
    std::vector<std::uint32_t> stamp = std::vector<std::uint32_t>(3 * kSide * kSide * kSide, 0);
    std::vector<double> value = std::vector<double>(3 * kSide * kSide * kSide);
    std::uint32_t current = 0;
    void next_brick() {
      if (++current == 0) {  // wrapped: every stamp is stale again
        std::fill(stamp.begin(), stamp.end(), 0);
        current = 1;
      }
    }
    // The crossing on the edge along `axis` from the brick's node (x, y, z), from `find`
    // the first time.
    template <class Find>
    double at(int axis, int x, int y, int z, Find&& find) {
      const std::size_t i = static_cast<std::size_t>(((axis * kSide + z) * kSide + y) * kSide + x);
      if (stamp[i] != current) {
        value[i] = find();
        stamp[i] = current;
      }
      return value[i];
    }
  };

  // A merge block's crossings: their box, which ways the surface faces across them (the
  // cells' facing bits together), and their sums about the brick's first node, from which
  // the spread about their mean follows. A level's blocks are summed from the level below's
  // (from every crossing again, flat() read W1's crossings three times over: a fifth of
  // its mesh).
  struct Block {
    Vector3d lo, hi;
    Vector3d sum = Vector3d::Zero();  // of d = p - origin (mm)
    Spread raw;                       // d d^T summed (mm^2)
    std::uint32_t count = 0;          // crossings
    std::uint32_t first = 0;          // its first cell
    std::uint8_t facing = 0;
    bool mergeable = true;  // every block below it is one vertex
    void add(const Vector3d& d) {
      sum += d;
      raw.add(d);
      ++count;
    }
    void add(const Block& o) {
      lo = lo.cwiseMin(o.lo);
      hi = hi.cwiseMax(o.hi);
      sum += o.sum;
      raw.add(o.raw);
      count += o.count;
      facing |= o.facing;
      mergeable = mergeable && o.mergeable;
    }
  };

  // A thread's working storage for vertices(), kept from brick to brick: the crossing cache
  // and the brick's lists (allocated per brick they cost W1's mesh 2 %).
  struct BrickScratch {
    CrossingCache crossings;
    std::vector<Cell> cells, sorted;
    std::vector<Vector3d> points;
    std::vector<std::uint32_t> group;
    std::vector<Block> blocks;
    std::vector<int> members;
  };

  // The brick's active cells and their (merged) vertices; false when it has none.
  bool vertices(BrickMesh& b, const BrickSigns& sg, BrickScratch& scratch) const {
    CrossingCache& crossings = scratch.crossings;
    crossings.next_brick();
    const std::array<int, 3> limit = cell_limits(b);
    std::vector<Cell>& cells = scratch.cells;
    std::vector<Vector3d>& points = scratch.points;
    cells.clear();
    points.clear();
    for (int y = 0; y < limit[1]; ++y) {
      for (int x = 0; x < limit[0]; ++x) {
        const std::uint32_t c00 = sg.at(x, y), c10 = sg.at(x + 1, y), c01 = sg.at(x, y + 1), c11 = sg.at(x + 1, y + 1);
        const std::uint32_t all = c00 & c10 & c01 & c11, any = c00 | c10 | c01 | c11;
        const std::uint32_t agree = ~(all ^ any);  // the four columns agree at this node
        const std::uint32_t uniform = agree & (agree >> 1) & ~(all ^ (all >> 1));
        std::uint32_t active = ~uniform & ((1u << limit[2]) - 1u);
        while (active != 0) {
          const int z = __builtin_ctz(active);
          active &= active - 1;
          Cell cell{static_cast<std::uint16_t>(morton(x, y, z)), 0, 0, static_cast<std::uint32_t>(points.size())};
          const int gx = b.origin[0] + x, gy = b.origin[1] + y, gz = b.origin[2] + z;
          // An edge whose ends differ: its crossing (looked up only then) joins the cell's.
          auto edge = [&](int axis, bool lower_inside, bool upper_inside, auto&& at) {
            if (lower_inside == upper_inside) return;
            cell.facing |= static_cast<std::uint8_t>(1u << (2 * axis + (lower_inside ? 0 : 1)));
            points.push_back(at());
            ++cell.count;
          };
          // Node (x + i, y + j, z + k) is bit z + k of corner[i + 2 j] (the four columns read
          // above, not looked up again for each of the 24 ends).
          const std::uint32_t corner[4] = {c00 >> z, c10 >> z, c01 >> z, c11 >> z};
          auto inside = [&](int i, int j, int k) { return ((corner[i + 2 * j] >> k) & 1u) != 0; };
          for (int d = 0; d < 4; ++d) {
            const int e1 = d & 1, e2 = d >> 1;
            edge(2, inside(e1, e2, 0), inside(e1, e2, 1), [&] {
              const double s = crossings.at(2, x + e1, y + e2, z, [&] { return crossing(2, gx + e1, gy + e2, gz); });
              return Vector3d(m_.position(gx + e1), m_.position(gy + e2), s);
            });
            edge(0, inside(0, e1, e2), inside(1, e1, e2), [&] {
              const double s = crossings.at(0, x, y + e1, z + e2, [&] { return crossing(0, gy + e1, gz + e2, gx); });
              return Vector3d(s, m_.position(gy + e1), m_.position(gz + e2));
            });
            edge(1, inside(e1, 0, e2), inside(e1, 1, e2), [&] {
              const double s = crossings.at(1, x + e1, y, z + e2, [&] { return crossing(1, gx + e1, gz + e2, gy); });
              return Vector3d(m_.position(gx + e1), s, m_.position(gz + e2));
            });
          }
          cells.push_back(cell);
        }
      }
    }
    if (cells.empty()) return false;
    // Into Morton order: a radix sort on the 12-bit codes, two passes of 6 bits (the codes are
    // distinct, so the order is the comparison sort's; that sort was 3.4 % of D32's mesh).
    static_assert(kBrickCells == 1 << 12, "two passes of 6 bits");
    std::vector<Cell>& sorted = scratch.sorted;
    sorted.resize(cells.size());
    for (int shift = 0; shift < 12; shift += 6) {
      std::array<std::uint32_t, 65> at{};
      for (const Cell& c : cells) ++at[((c.code >> shift) & 63u) + 1];
      for (std::size_t i = 0; i < 64; ++i) at[i + 1] += at[i];
      for (const Cell& c : cells) sorted[at[(c.code >> shift) & 63u]++] = c;
      cells.swap(sorted);
    }
    // Octree merging, level by level: a block's cells are a run of the Morton order.
    const std::size_t n = cells.size();
    std::vector<std::uint32_t>& group = scratch.group;  // the run start of each cell's merged block
    group.resize(n);
    for (std::size_t i = 0; i < n; ++i) group[i] = static_cast<std::uint32_t>(i);
    double tolerance = kMergeTolerance * m_.v;
    // Without flat merging only exact axis planes merge (untouched stock faces, floors of a
    // level flat end mill): such a block meets a differently inclined one only across
    // cells that hold both, so none of its triangles crosses a crease.
    const bool any_plane = m_.flat_merging;
    if (!any_plane) tolerance = kExactPlane_mm;
    // Level 0: a block per cell, its sums from its crossings.
    const Vector3d origin(m_.position(b.origin[0]), m_.position(b.origin[1]), m_.position(b.origin[2]));
    std::vector<Block>& blocks = scratch.blocks;
    blocks.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      Block& k = blocks[i];
      k = Block{};
      k.lo = k.hi = points[cells[i].first];
      for (std::uint32_t j = 0; j < cells[i].count; ++j) {
        const Vector3d& p = points[cells[i].first + j];
        k.lo = k.lo.cwiseMin(p);
        k.hi = k.hi.cwiseMax(p);
        k.add(p - origin);
      }
      k.first = static_cast<std::uint32_t>(i);
      k.facing = cells[i].facing;
    }
    std::size_t count = n;  // blocks at the level below
    for (int level = 1; level <= kBrickLevels; ++level) {
      const int shift = 3 * level;
      std::size_t made = 0;
      for (std::size_t first = 0; first < count;) {
        const int code = cells[blocks[first].first].code >> shift;
        std::size_t last = first;
        Block k = blocks[first];
        while (++last < count && (cells[blocks[last].first].code >> shift) == code) k.add(blocks[last]);
        const std::size_t cell_first = k.first, cell_last = last < count ? blocks[last].first : n;
        // A block of one cell is one vertex already: it stays mergeable. (It used to end
        // the merging of every larger block around it, so that a tilted or curved sheet,
        // whose blocks hold lone cells at their corners, kept nearly a vertex per cell: D32's
        // hole walls 2.79 M vertices, now 1.67 M.) Nor is a block alone in its larger one
        // tested again: the same crossings give the same answer.
        if (last - first > 1) {
          if (k.mergeable && flat(k, origin, cells, points, tolerance, any_plane, cell_last)) {
            for (std::size_t i = cell_first; i < cell_last; ++i) group[i] = static_cast<std::uint32_t>(cell_first);
          } else {
            k.mergeable = false;
          }
        }
        blocks[made++] = k;  // made <= first: the blocks below it are read already
        first = last;
      }
      count = made;
    }
    // Each vertex at the mean of its cells' crossings (the points' room taken once: grown
    // by doubling, they were most of the mesher's allocations).
    b.cells.resize(n);
    b.vertex.resize(n);
    std::size_t vertices = 0;
    for (std::size_t i = 0; i < n; ++i) vertices += group[i] == i;
    b.points.reserve(vertices);
    std::vector<int>& members = scratch.members;
    members.clear();
    for (std::size_t i = 0; i < n; ++i) {
      b.cells[i] = cells[i].code;
      if (group[i] == i) {
        b.points.push_back(Vector3d::Zero());
        members.push_back(0);
      }
      const std::uint32_t vertex = static_cast<std::uint32_t>(b.points.size() - 1);
      b.vertex[i] = vertex;
      for (std::uint32_t k = 0; k < cells[i].count; ++k) b.points[vertex] += points[cells[i].first + k];
      members[vertex] += cells[i].count;
    }
    for (std::size_t p = 0; p < b.points.size(); ++p) b.points[p] /= std::max(members[p], 1);
    return true;
  }

  // Whether block k (its cells up to cell_last) holds one flat sheet: the surface faces one
  // way along each axis (two sheets of a thin wall face opposite ways) and every crossing
  // lies within `tolerance` of one plane. Not an axis plane through the lattice's nodes:
  // crossings lie there where surfaces pass through the nodes (a 90 deg V-bit's walls one
  // cell apart at a row of nodes), and two such surfaces' crossings share the node plane
  // without being one sheet (a junction of two such grooves merged into one vertex sat
  // 0.03 mm above their floor). Such a sheet is left in cells: more triangles, never a cut
  // crease.
  template <class Cells>
  bool flat(const Block& k, const Vector3d& origin, const Cells& cells, const std::vector<Vector3d>& points,
            double tolerance, bool any_plane, std::size_t cell_last) const {
    for (int a = 0; a < 3; ++a)
      if (((k.facing >> (2 * a)) & 3u) == 3u) return false;
    int axis;
    if ((k.hi - k.lo).minCoeff(&axis) <= 2.0 * tolerance) {  // an axis plane
      const double at = m_.index_of(0.5 * (k.lo[axis] + k.hi[axis]));
      return std::abs(at - std::round(at)) * m_.v > kExactPlane_mm;
    }
    if (!any_plane) return false;
    // The spread about the mean from the sums about the origin: the crossings lie within 16
    // cells of it and the tolerance is 0.04 of a cell, so the difference's rounding stays
    // near 1e-10 of tolerance^2 a crossing (the quick test's margin is 1e-3 of it).
    const Vector3d mean = k.sum / static_cast<double>(k.count);
    const Spread& r = k.raw;
    const Spread spread{r.xx - k.sum.x() * mean.x(), r.xy - k.sum.x() * mean.y(), r.xz - k.sum.x() * mean.z(),
                        r.yy - k.sum.y() * mean.y(), r.yz - k.sum.y() * mean.z(), r.zz - k.sum.z() * mean.z()};
    return within_one_plane(spread, origin + mean, tolerance, [&](auto&& visit) {
      for (std::size_t i = k.first; i < cell_last; ++i)
        for (std::uint32_t j = 0; j < cells[i].count; ++j) visit(points[cells[i].first + j]);
    });
  }

  // The brick whose first node is at lattice index `origin`, null when it holds no surface
  // (or lies outside the lattice).
  const BrickMesh* brick_at(const std::array<int, 3>& origin) const {
    std::array<int, 3> brick;
    for (std::size_t a = 0; a < 3; ++a) {
      const int rel = origin[a] - lo_[a];
      if (rel < 0) return nullptr;
      brick[a] = rel / kBrick;
    }
    const std::size_t column = static_cast<std::size_t>(brick[1] * bricks_[0] + brick[0]);
    const auto first = bricks_list_.begin() + static_cast<std::ptrdiff_t>(column_first_[column]);
    const auto last = bricks_list_.begin() + static_cast<std::ptrdiff_t>(column_first_[column + 1]);
    const auto it = std::lower_bound(first, last, origin[2], [](const BrickMesh& b, int z) { return b.origin[2] < z; });
    return it == last || it->origin[2] != origin[2] ? nullptr : &*it;
  }

  // The vertex (global index) of brick b's cell (x, y, z), -1 when the cell is not active.
  static int vertex_in(const BrickMesh& b, int x, int y, int z) {
    const std::uint16_t code = static_cast<std::uint16_t>(morton(x, y, z));
    const auto c = std::lower_bound(b.cells.begin(), b.cells.end(), code);
    if (c == b.cells.end() || *c != code) return -1;
    return static_cast<int>(b.first_vertex + b.vertex[static_cast<std::size_t>(c - b.cells.begin())]);
  }

  // The faces of every sign-changing edge starting at one of the brick's active cells'
  // lowest node.
  void quads(const BrickMesh& b, const BrickSigns& sg, CellTable& local, std::vector<Triangle>& out) const {
    // The brick's own cells by position in `local` (most quads stay inside their brick),
    // cleared again on the way out.
    struct Clear {
      CellTable& local;
      const std::vector<std::uint16_t>& cells;
      ~Clear() {
        for (std::uint16_t code : cells) local[code] = -1;
      }
    } clear{local, b.cells};
    for (std::size_t i = 0; i < b.cells.size(); ++i) local[b.cells[i]] = static_cast<int>(b.first_vertex + b.vertex[i]);
    // A brick merged into one vertex (a flat sheet, a plane brick) has quads only across its
    // lower faces: one whose four cells all lie in the brick has four equal corners.
    const bool one_vertex = b.points.size() == 1;
    // The bricks below this one (bit a of the index: one brick down along a), each looked up
    // the first time a quad reaches into it (a lookup in the lattice per quad corner was a
    // third of this).
    std::array<const BrickMesh*, 8> below{};
    unsigned looked = 0;
    for (std::uint16_t code : b.cells) {
      const auto [x, y, z] = unmorton(code);
      if (one_vertex && x > 0 && y > 0 && z > 0) continue;
      const bool in = sg.inside(x, y, z);
      for (int a = 0; a < 3; ++a) {
        const bool other = a == 0 ? sg.inside(x + 1, y, z) : a == 1 ? sg.inside(x, y + 1, z) : sg.inside(x, y, z + 1);
        if (other == in) continue;
        // Cells around the edge, counter-clockwise seen from +a.
        const int e1 = (a + 1) % 3, e2 = (a + 2) % 3;
        std::array<int, 4> v;
        const int offsets[4][2] = {{0, 0}, {-1, 0}, {-1, -1}, {0, -1}};
        bool ok = true;
        for (int q = 0; q < 4; ++q) {
          std::array<int, 3> c = {x, y, z};
          c[static_cast<std::size_t>(e1)] += offsets[q][0];
          c[static_cast<std::size_t>(e2)] += offsets[q][1];
          if (c[0] >= 0 && c[1] >= 0 && c[2] >= 0) {
            v[static_cast<std::size_t>(q)] = local[static_cast<std::size_t>(morton(c[0], c[1], c[2]))];
          } else {
            // In a brick below (-1 along an axis: that brick's last cell, 15).
            const unsigned side = (c[0] < 0 ? 1u : 0u) | (c[1] < 0 ? 2u : 0u) | (c[2] < 0 ? 4u : 0u);
            if ((looked & (1u << side)) == 0) {
              looked |= 1u << side;
              std::array<int, 3> origin = b.origin;
              for (std::size_t k = 0; k < 3; ++k)
                if ((side >> k) & 1u) origin[k] -= kBrick;
              below[side] = brick_at(origin);
            }
            const BrickMesh* near = below[side];
            v[static_cast<std::size_t>(q)] =
                near == nullptr ? -1 : vertex_in(*near, c[0] & (kBrick - 1), c[1] & (kBrick - 1), c[2] & (kBrick - 1));
          }
          ok = ok && v[static_cast<std::size_t>(q)] >= 0;
        }
        if (!ok) continue;
        if (!in) std::swap(v[1], v[3]);  // the surface faces -a
        emit(v, out);
      }
    }
  }

  void emit(const std::array<int, 4>& v, std::vector<Triangle>& out) const {
    // Merged cells share vertices: drop repeated corners, keeping the cyclic order.
    std::array<int, 4> u;
    int n = 0;
    for (int q = 0; q < 4; ++q) {
      const int c = v[static_cast<std::size_t>(q)];
      if (n > 0 && u[static_cast<std::size_t>(n - 1)] == c) continue;
      u[static_cast<std::size_t>(n++)] = c;
    }
    if (n > 1 && u[static_cast<std::size_t>(n - 1)] == u[0]) --n;
    if (n == 3) {
      out.emplace_back(u[0], u[1], u[2]);
    } else if (n == 4) {
      out.emplace_back(u[0], u[1], u[2]);
      out.emplace_back(u[0], u[2], u[3]);
    }
  }

  const DexelStock::Impl& m_;
  std::array<int, 3> lo_{}, count_{}, bricks_{};
  std::vector<BrickMesh> bricks_list_;
  std::vector<std::size_t> column_first_;
};

SurfaceMesh contour_mesh(const DexelStock::Impl& m) { return Contour(m).run(); }

// ---- Vertices on creases ----
//
// A cell's vertex at the mean of its crossings cuts a crease (the bottom of a V-bit's
// groove, a slot's top edge) by up to half a cell: the mean lies between the two surfaces,
// and the projection takes it to the nearer one. In a cell a crease may cross (the tests
// below), each crossing's plane is taken from the surface that made it (the gradient of its
// move's sweep distance, or of the initial stock's) and the vertex goes to the point nearest
// all those planes (dual contouring's quadratic error function; directions in which the
// planes do not fix it keep the mean), when that point lies within a cell of the cell (where
// the groove is exactly a cell wide at the nodes' height, its floor lies in the cell below,
// which holds no surface). A vertex of a merged flat block lies in a cell of its block,
// whose crossings are flat: it stays.
// The ray's intervals that reach [s_lo, s_hi] (only they can have an endpoint in it), in
// order: from the first that ends at or above s_lo, by binary search (the intervals are
// disjoint and in order; a ray through D32's holes holds dozens), to the last that starts at
// or below s_hi.
template <class Visit>
void for_each_reaching(const SegmentList& ray, double s_lo, double s_hi, Visit&& visit) {
  const DexelSegment* seg = ray.data();
  const DexelSegment* const end = seg + ray.size();
  // A few intervals (most rays hold one) are passed one by one.
  if (ray.size() > 4) seg = std::partition_point(seg, end, [&](const DexelSegment& g) { return g.hi_mm < s_lo; });
  for (; seg != end && seg->lo_mm <= s_hi; ++seg)
    if (seg->hi_mm >= s_lo) visit(*seg);
}

// A plane direction counts where its eigenvalue is above this share of the largest (singular
// values above 0.32 of the largest): on curved sweeps a narrow fan of planes is a bent sheet,
// and solving along it throws vertices across the sheet (with 0.02 the impeller's mesh folds
// 28,829 edges by more than 150 deg against 20,311).
constexpr double kCreaseRank = 0.1;
// Where only V-bit sweeps made the crossings: planes and cones, whose tangent planes all pass
// through the tip's path, so a narrow fan of them is a cone's apex where a groove ends or a
// junction, fixed by them (with 0.1 a groove's end sat up to 0.012 mm above its floor).
constexpr double kVBitCreaseRank = 0.02;

void place_on_creases(const DexelStock::Impl& m, SurfaceMesh& mesh) {
  const double v = m.v, flat_mm = kFlatTolerance * v;
  const std::size_t count = mesh.mesh.vertices_mm.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256), [&](const auto& range) {
    std::vector<Vector3d> points;
    std::vector<int> made_by;
    detail::SweepCache sweeps(m.moves, m.cutters);
    std::vector<int> used;  // the moves that made this cell's crossings
    // Each crossing's unit normal once per range: an edge's crossing is one of the four cells'
    // around it (keys: family, ray and the endpoint's bits; NaN: no plane there).
    std::vector<std::uint64_t> keys;
    std::unordered_map<std::uint64_t, Vector3d> normals;
    for (std::size_t p = range.begin(); p != range.end(); ++p) {
      Vector3d& x = mesh.mesh.vertices_mm[p];
      Eigen::Vector3i base;
      for (int a = 0; a < 3; ++a) base[a] = static_cast<int>(std::floor(m.index_of(x[a])));
      // The crossings on the cell's twelve edges: the endpoints of the rays along its edges
      // between its two nodes.
      points.clear();
      made_by.clear();
      keys.clear();
      unsigned facing = 0;  // bit 2a: a crossing along axis a where material begins, 2a + 1: where it ends
      for (const Family& f : m.families) {
        const auto [a1, a2] = kOther[static_cast<std::size_t>(f.axis)];
        const double s_lo = m.position(base[f.axis]), s_hi = m.position(base[f.axis] + 1);
        for (int iw = base[a2]; iw <= base[a2] + 1; ++iw) {
          for (int iu = base[a1]; iu <= base[a1] + 1; ++iu) {
            if (!f.contains(iu, iw)) continue;
            const SegmentList& ray = f.at(iu, iw);
            const std::uint64_t ray_key = static_cast<std::uint64_t>(f.axis) << 62 |
                                          static_cast<std::uint64_t>((iw - f.lo_w) * f.n_u + (iu - f.lo_u)) << 32;
            auto add = [&](float s, int move, unsigned side) {
              if (s < s_lo || s > s_hi) return;
              std::uint32_t bits;
              std::memcpy(&bits, &s, sizeof bits);
              keys.push_back(ray_key | bits);
              facing |= side << (2 * f.axis);
              Vector3d q;
              q[f.axis] = s;
              q[a1] = m.position(iu);
              q[a2] = m.position(iw);
              points.push_back(q);
              made_by.push_back(move);
            };
            for_each_reaching(ray, s_lo, s_hi, [&](const DexelSegment& seg) {
              add(seg.lo_mm, seg.lo_move, 1u);
              add(seg.hi_mm, seg.hi_move, 2u);
            });
          }
        }
      }
      if (points.size() < 3) continue;
      // The surfaces that made the crossings: the moves' sweeps (made_by, then their index in
      // `sweeps`) and the initial stock's (kNoMove).
      bool stock = false, opposite = false;
      used.clear();
      for (int id : made_by) {
        if (id == kNoMove)
          stock = true;
        else if (std::find(used.begin(), used.end(), id) == used.end())
          used.push_back(id);
      }
      if (used.empty()) continue;  // the stock's own faces: planes, or its own shape
      for (int a = 0; a < 3; ++a) opposite = opposite || ((facing >> (2 * a)) & 3u) == 3u;
      Vector3d mean = Vector3d::Zero();
      for (const Vector3d& q : points) mean += q;
      mean /= static_cast<double>(points.size());
      // A crease crosses the cell where the initial stock's face meets a cut, where material
      // both begins and ends along one axis (a groove's two walls, whose crossings may lie in
      // one lattice plane), where a V-bit cut (an engraving: every such cell), or where the
      // crossings do not lie on one plane within a flat block's tolerance (a smooth sheet
      // bends by its sagitta: under 1e-4 mm on a 4 mm radius at 0.05 mm cells). A ball end
      // mill's own sweep is smooth: with one move and no other surface, none.
      bool smooth = true, vbit = false, all_vbit = true;
      for (int id : used) {
        const Cutter& c = m.cutters[static_cast<std::size_t>(m.moves.at(id).cutter)];
        smooth = smooth && c.type != CutterType::VBit && core_of(c).core_radius_mm == 0.0;
        vbit = vbit || c.type == CutterType::VBit;
        all_vbit = all_vbit && c.type == CutterType::VBit;
      }
      if (!stock && !opposite) {
        if (used.size() == 1 && smooth) continue;
        if (!vbit && within_one_plane(mean, flat_mm, [&](auto&& visit) {
              for (const Vector3d& q : points) visit(q);
            }))
          continue;
      }
      // The moves' sweeps (kept from cell to cell: neighbours share moves); made_by then
      // holds each crossing's index into them.
      sweeps.make_room(used.size());
      for (int& id : made_by)
        if (id != kNoMove) id = static_cast<int>(sweeps.index_of(id));
      // Each crossing's plane: the unit gradient of the distance of the surface that made it.
      Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
      Vector3d atb = Vector3d::Zero();
      for (std::size_t i = 0; i < points.size(); ++i) {
        const int k = made_by[i];
        const TranslationSweep* sweep = k == kNoMove ? nullptr : &sweeps[static_cast<std::size_t>(k)];
        auto [at_key, fresh] = normals.try_emplace(keys[i]);
        if (fresh) {
          auto distance = [&](const Vector3d& y) { return sweep ? sweep->distance(y) : m.initial_distance(y); };
          // Forward differences (four distances, not six): the step's error, about the step
          // over the surface's radius, is far below what tilts a plane by a visible angle.
          constexpr double kStep_mm = 1e-5;
          const double here = distance(points[i]);
          Vector3d g;
          for (int a = 0; a < 3; ++a) {
            Vector3d h = Vector3d::Zero();
            h[a] = kStep_mm;
            g[a] = (distance(points[i] + h) - here) / kStep_mm;
          }
          const double norm = g.norm();
          // At a kink of that surface: no plane.
          at_key->second = norm > 0.5 ? Vector3d(g / norm) : Vector3d::Constant(std::nan(""));
        }
        const Vector3d n = at_key->second;
        if (!n.allFinite()) continue;
        ata += n * n.transpose();
        atb += n * n.dot(points[i] - mean);
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
      eig.computeDirect(ata);
      const double largest = eig.eigenvalues()(2);
      if (!(largest > 0.0)) continue;
      const double rank = all_vbit && !stock ? kVBitCreaseRank : kCreaseRank;
      Vector3d offset = Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        const double lambda = eig.eigenvalues()(k);
        if (lambda <= rank * largest) continue;
        const Vector3d u = eig.eigenvectors().col(k);
        offset += u * (u.dot(atb) / lambda);
      }
      const Vector3d at = mean + offset;
      bool inside = true;
      for (int a = 0; a < 3; ++a)
        inside = inside && at[a] >= m.position(base[a] - 1) && at[a] <= m.position(base[a] + 2);
      if (inside) x = at;
    }
  });
}

}  // namespace

SurfaceMesh DexelStock::surface() const {
  const Impl& m = *impl_;
  const double v = m.v;
  SurfaceMesh mesh = contour_mesh(m);
  place_on_creases(m, mesh);
  // The moves that made the crossings around each vertex: its candidates on the exact surface.
  auto nearby = [&](std::size_t p, std::vector<int>& ids) {
    ids.clear();
    // A vertex's 48 rays name a few moves many times over: each is kept once as it comes
    // (the repeats' sort was a third of this search).
    auto add = [&ids](int id) {
      if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);
    };
    const Vector3d& x = mesh.mesh.vertices_mm[p];
    Eigen::Vector3i base;
    for (int a = 0; a < 3; ++a) base[a] = static_cast<int>(std::floor(m.index_of(x[a])));
    for (const Family& f : m.families) {
      const auto [a1, a2] = kOther[static_cast<std::size_t>(f.axis)];
      const double s_lo = m.position(base[f.axis] - 1), s_hi = m.position(base[f.axis] + 2);
      // The 4 x 4 rays within the family, a row at a time.
      const int u0 = std::max(base[a1] - 1, f.lo_u), u1 = std::min(base[a1] + 2, f.lo_u + f.n_u - 1);
      const int w0 = std::max(base[a2] - 1, f.lo_w), w1 = std::min(base[a2] + 2, f.lo_w + f.n_w - 1);
      for (int iw = w0; iw <= w1 && u0 <= u1; ++iw) {
        const SegmentList* row = &f.at(u0, iw);
        for (int iu = u0; iu <= u1; ++iu) {
          for_each_reaching(row[iu - u0], s_lo, s_hi, [&](const DexelSegment& seg) {
            if (seg.lo_move != kNoMove && seg.lo_mm >= s_lo) add(seg.lo_move);
            if (seg.hi_move != kNoMove && seg.hi_mm <= s_hi) add(seg.hi_move);
          });
        }
      }
    }
    std::sort(ids.begin(), ids.end());
  };
  // A vertex lies in its lattice cell, so the surface is within a cell diagonal.
  detail::project_onto_machined_surface(m.moves, m.cutters, m.initial_distance, nearby, 2.0 * v, mesh);
  return mesh;
}

}  // namespace vcut::removal
