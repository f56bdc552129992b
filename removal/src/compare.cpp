#include "vcut/removal/compare.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>

namespace vcut::removal {
namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

// Where on a triangle the point nearest to x lies.
enum class Feature { VertexA, VertexB, VertexC, EdgeAB, EdgeAC, EdgeBC, Face };

// The point of triangle abc nearest to x, and its feature: Ericson's region test
// (Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d nearest_on_triangle(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c, Feature& feature) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = x - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    feature = Feature::VertexA;
    return a;
  }
  const Eigen::Vector3d bp = x - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    feature = Feature::VertexB;
    return b;
  }
  const Eigen::Vector3d cp = x - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    feature = Feature::VertexC;
    return c;
  }
  const double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    feature = Feature::EdgeAB;
    return a + d1 / (d1 - d3) * ab;
  }
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    feature = Feature::EdgeAC;
    return a + d2 / (d2 - d6) * ac;
  }
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    feature = Feature::EdgeBC;
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  }
  feature = Feature::Face;
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// A uniform grid of cells over the design, each listing the triangles that meet it. A
// query searches outward from its own cell, shell by shell, and tests only the triangles of
// cells nearer than the best distance so far; a hint (the triangle nearest the previous
// point, a neighbour in Morton order) gives a first bound. The triangle nearest to x lies
// in a cell it meets, so none is missed. On the demo at v = 0.05 mm (8.8 million dexel
// endpoints, a design of 38,976 triangles with fans of long slivers) it tests about five
// triangles a query, and the compare stage took 3.9 s instead of 21.4 s with CGAL's tree
// (2 threads, the endpoints also listed and sorted in parallel now).
class TriangleGrid {
 public:
  TriangleGrid() = default;
  TriangleGrid(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3i>& corners) {
    if (corners.empty()) return;
    Eigen::AlignedBox3d box;
    std::vector<double> area_mm2;
    area_mm2.reserve(corners.size());
    for (const Eigen::Vector3i& t : corners) {
      for (int i = 0; i < 3; ++i) box.extend(points[static_cast<std::size_t>(t[i])]);
      area_mm2.push_back(0.5 *
                         (points[static_cast<std::size_t>(t[1])] - points[static_cast<std::size_t>(t[0])])
                             .cross(points[static_cast<std::size_t>(t[2])] - points[static_cast<std::size_t>(t[0])])
                             .norm());
    }
    // Cells about the size of a typical triangle (the median: a few large faces beside
    // many small ones do not count); at most kMaxCells cells.
    std::nth_element(area_mm2.begin(), area_mm2.begin() + static_cast<std::ptrdiff_t>(area_mm2.size() / 2),
                     area_mm2.end());
    const Eigen::Vector3d size = box.sizes().cwiseMax(1e-9);
    cell_mm_ = std::max(2.0 * std::sqrt(area_mm2[area_mm2.size() / 2]), 1e-6 * size.maxCoeff());
    const double cells = (size / cell_mm_).array().ceil().prod();
    if (cells > kMaxCells) cell_mm_ *= std::cbrt(cells / kMaxCells) * 1.01;
    origin_ = box.min();
    // The cells each triangle meets, listed once (in parallel, in fixed chunks of triangles),
    // then sorted by cell (a counting sort, each cell's triangles in ascending order). Many
    // large triangles among small ones would each be listed in many cells: past kMaxItems per
    // triangle the listing starts again with cells twice the size.
    constexpr std::size_t kChunk = 1024;  // triangles a task: the same lists for any thread count
    const std::size_t chunks = (corners.size() + kChunk - 1) / kChunk;
    std::vector<std::vector<std::uint32_t>> chunk_cells(chunks);
    std::vector<std::uint32_t> listed(corners.size());  // cells per triangle
    for (;;) {
      for (int a = 0; a < 3; ++a) n_[a] = std::max(1, static_cast<int>(std::ceil(size[a] / cell_mm_)));
      const std::uint64_t limit = kMaxItems * corners.size();
      std::atomic<std::uint64_t> items{0};
      tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t k) {
        std::vector<std::uint32_t>& cells = chunk_cells[k];
        cells.clear();
        const std::size_t end = std::min(corners.size(), (k + 1) * kChunk);
        for (std::size_t f = k * kChunk; f < end && items.load(std::memory_order_relaxed) <= limit; ++f) {
          const std::size_t before = cells.size();
          visit_cells(points, corners[f], [&](std::size_t cell) { cells.push_back(static_cast<std::uint32_t>(cell)); });
          listed[f] = static_cast<std::uint32_t>(cells.size() - before);
          items.fetch_add(listed[f], std::memory_order_relaxed);
        }
      });
      if (items.load() <= limit) break;  // then no chunk stopped early
      cell_mm_ *= 2.0;
    }
    std::vector<std::uint32_t> count(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2] + 1, 0);
    for (const std::vector<std::uint32_t>& cells : chunk_cells)
      for (const std::uint32_t cell : cells) ++count[cell + 1];
    for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    first_ = count;
    items_.resize(first_.back());
    for (std::size_t k = 0; k < chunks; ++k) {
      const std::vector<std::uint32_t>& cells = chunk_cells[k];
      std::size_t at = 0;
      for (std::size_t f = k * kChunk; at < cells.size(); ++f)
        for (std::uint32_t i = 0; i < listed[f]; ++i) items_[count[cells[at++]]++] = static_cast<std::uint32_t>(f);
    }
    box_lo_.resize(corners.size());
    box_hi_.resize(corners.size());
    for (std::size_t f = 0; f < corners.size(); ++f) {
      Eigen::AlignedBox3d b;
      for (int i = 0; i < 3; ++i) b.extend(points[static_cast<std::size_t>(corners[f][i])]);
      box_lo_[f] = b.min();
      box_hi_[f] = b.max();
    }
  }

  bool empty() const { return items_.empty(); }

  // Offers consider(f) every triangle that may lie nearer to x than `best` (the caller's
  // squared distance so far, infinity for none, which consider() lowers as it goes): the
  // cells in shells about x's cell, nearest shell first, each cell whose box lies within
  // the best distance so far, until the next shell lies beyond it. False when that takes
  // more than kMaxShells shells (x far from the design, or far outside the grid).
  template <class Consider>
  bool nearest(const Eigen::Vector3d& x, const double& best, Consider&& consider) const {
    int at[3];
    for (int a = 0; a < 3; ++a) {
      const double i = std::floor((x[a] - origin_[a]) / cell_mm_);
      if (!(i > -kMaxShells && i < n_[a] + kMaxShells)) return false;  // NaN too
      at[a] = static_cast<int>(i);
    }
    for (int shell = 0; shell <= kMaxShells; ++shell) {
      if (shell > 0) {
        // Every cell of this shell and beyond lies outside the cube of the shells before it:
        // at least x's distance from that cube's nearest face away (at least shell - 1 cells;
        // most queries, the hint's triangle at hand, end inside x's own cell).
        double wall = std::numeric_limits<double>::infinity();
        for (int a = 0; a < 3; ++a)
          wall = std::min({wall, x[a] - (origin_[a] + (at[a] - shell + 1) * cell_mm_),
                           origin_[a] + (at[a] + shell) * cell_mm_ - x[a]});
        if (wall > 0.0 && wall * wall > best) return true;
        // With a distance in hand, the cells that may hold a nearer triangle are those within
        // it of x: a box of them, usually a few beside x's own, instead of the shells'
        // surfaces (the first shell alone is 26 cells). A hair wider for rounding and ties.
        if (best < std::numeric_limits<double>::infinity()) {
          const double r = std::sqrt(best) * (1.0 + 1e-9) + 1e-12;
          int lo[3], hi[3];
          bool near = true;
          for (int a = 0; a < 3; ++a) {
            // Compared as doubles first: a far hint's distance may not fit an int in cells.
            const double lo_cell = std::floor((x[a] - r - origin_[a]) / cell_mm_),
                         hi_cell = std::floor((x[a] + r - origin_[a]) / cell_mm_);
            near = lo_cell >= at[a] - kMaxShells && hi_cell <= at[a] + kMaxShells;
            if (!near) break;
            lo[a] = std::max(static_cast<int>(lo_cell), 0);
            hi[a] = std::min(static_cast<int>(hi_cell), n_[a] - 1);
          }
          if (near) {
            for (int k = lo[2]; k <= hi[2]; ++k)
              for (int j = lo[1]; j <= hi[1]; ++j)
                for (int i = lo[0]; i <= hi[0]; ++i)
                  if (std::max({std::abs(i - at[0]), std::abs(j - at[1]), std::abs(k - at[2])}) >= shell)
                    scan_cell(x, best, consider, i, j, k);  // not among the shells before
            return true;
          }
        }
      }
      int lo[3], hi[3];
      bool any = true;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(0, at[a] - shell);
        hi[a] = std::min(n_[a] - 1, at[a] + shell);
        any = any && lo[a] <= hi[a];
      }
      if (!any) continue;
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j) {
          // Only the shell's surface: inside rows, the two cells at its ends.
          const bool inner = std::abs(k - at[2]) < shell && std::abs(j - at[1]) < shell;
          const int step = inner ? 2 * shell : 1;
          for (int i = at[0] - shell; i <= at[0] + shell; i += step) {
            if (i >= lo[0] && i <= hi[0]) scan_cell(x, best, consider, i, j, k);
          }
        }
    }
    return false;
  }

 private:
  // Offers consider() the triangles of cell (i, j, k) whose boxes lie within the best
  // distance, if the cell does.
  template <class Consider>
  void scan_cell(const Eigen::Vector3d& x, const double& best, Consider& consider, int i, int j, int k) const {
    const Eigen::Vector3d cell_lo = origin_ + cell_mm_ * Eigen::Vector3d(i, j, k);
    const Eigen::Vector3d cell_gap = (cell_lo - x).cwiseMax(x - (cell_lo.array() + cell_mm_).matrix()).cwiseMax(0.0);
    if (cell_gap.squaredNorm() > best) return;
    const std::size_t cell = (static_cast<std::size_t>(k) * n_[1] + j) * n_[0] + i;
    for (std::uint32_t e = first_[cell]; e < first_[cell + 1]; ++e) {
      const std::uint32_t f = items_[e];
      // The triangle's box within the best distance (a triangle listed in several cells is
      // tested again: cheaper than remembering it).
      const Eigen::Vector3d box_gap = (box_lo_[f] - x).cwiseMax(x - box_hi_[f]).cwiseMax(0.0);
      if (box_gap.squaredNorm() <= best) consider(f);
    }
  }

  static constexpr double kMaxCells = 4.0e6;
  static constexpr std::uint64_t kMaxItems = 16;  // cells listing a triangle, on average
  static constexpr int kMaxShells = 6;

  // Every cell the triangle meets: columns along the plane's steepest axis within the
  // triangle's box, each from the plane's lowest to its highest point over it, and of
  // those the cells that no separating axis parts from the triangle (a long sliver's box
  // spans many cells it never touches).
  template <class Visit>
  void visit_cells(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3i& t, Visit&& visit) const {
    const Eigen::Vector3d& a = points[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = points[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = points[static_cast<std::size_t>(t[2])];
    Eigen::AlignedBox3d box(a);
    box.extend(b);
    box.extend(c);
    int lo[3], hi[3];
    for (int ax = 0; ax < 3; ++ax) {
      lo[ax] = std::clamp(static_cast<int>(std::floor((box.min()[ax] - origin_[ax]) / cell_mm_)), 0, n_[ax] - 1);
      hi[ax] = std::clamp(static_cast<int>(std::floor((box.max()[ax] - origin_[ax]) / cell_mm_)), 0, n_[ax] - 1);
    }
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    int d = 0;
    normal.cwiseAbs().maxCoeff(&d);
    const int p = (d + 1) % 3, q = (d + 2) % 3;
    // A triangle inside one cell meets it; else the separating axes, made once per triangle.
    const bool single = lo[0] == hi[0] && lo[1] == hi[1] && lo[2] == hi[2];
    const SeparatingAxes axes(a, b, c, 0.5 * cell_mm_ * (1.0 + 1e-6));
    auto cell_of = [&](int along_d, int along_p, int along_q) {
      int idx[3];
      idx[d] = along_d;
      idx[p] = along_p;
      idx[q] = along_q;
      return (static_cast<std::size_t>(idx[2]) * n_[1] + idx[1]) * n_[0] + idx[0];
    };
    for (int i = lo[p]; i <= hi[p]; ++i)
      for (int j = lo[q]; j <= hi[q]; ++j) {
        int k0 = lo[d], k1 = hi[d];
        if (normal[d] != 0.0) {
          // The plane's height along d over the column's four corners (the column clipped
          // to the triangle's box), widened by a thousandth of a cell for rounding.
          double h_lo = std::numeric_limits<double>::infinity(), h_hi = -h_lo;
          const double x0 = std::max(origin_[p] + i * cell_mm_, box.min()[p]),
                       x1 = std::min(origin_[p] + (i + 1) * cell_mm_, box.max()[p]);
          const double y0 = std::max(origin_[q] + j * cell_mm_, box.min()[q]),
                       y1 = std::min(origin_[q] + (j + 1) * cell_mm_, box.max()[q]);
          for (double xp : {x0, x1})
            for (double yq : {y0, y1}) {
              const double h = a[d] - (normal[p] * (xp - a[p]) + normal[q] * (yq - a[q])) / normal[d];
              h_lo = std::min(h_lo, h);
              h_hi = std::max(h_hi, h);
            }
          const double slack = 1e-3 * cell_mm_;
          k0 = std::max(k0, static_cast<int>(std::floor((h_lo - slack - origin_[d]) / cell_mm_)));
          k1 = std::min(k1, static_cast<int>(std::floor((h_hi + slack - origin_[d]) / cell_mm_)));
        }
        for (int k = k0; k <= k1; ++k) {
          int idx[3];
          idx[d] = k;
          idx[p] = i;
          idx[q] = j;
          if (single || axes.meets(cell_centre(idx))) visit(cell_of(k, i, j));
        }
      }
  }

  // Whether triangle abc meets a cell (separating axes: the nine edge-cross-axis directions
  // and the plane's normal; the cell lies within the triangle's box already), the cell grown
  // by a millionth of its size so that rounding never drops a triangle. Each axis's span of
  // the triangle is made once (a cell's test was 40 % of a 2.3 M-triangle design's grid).
  struct SeparatingAxes {
    SeparatingAxes(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, double half) {
      const Eigen::Vector3d edges[3] = {b - a, c - b, a - c};
      int n = 0;
      for (const Eigen::Vector3d& e : edges)
        for (int ax = 0; ax < 3; ++ax) axis[n++] = Eigen::Vector3d::Unit(ax).cross(e);
      axis[n] = edges[0].cross(edges[1]);
      for (int k = 0; k < kAxes; ++k) {
        const double p0 = axis[k].dot(a), p1 = axis[k].dot(b), p2 = axis[k].dot(c);
        lo[k] = std::min({p0, p1, p2});
        hi[k] = std::max({p0, p1, p2});
        reach[k] = half * axis[k].cwiseAbs().sum();
      }
    }
    bool meets(const Eigen::Vector3d& centre) const {
      for (int k = 0; k < kAxes; ++k) {
        const double t = axis[k].dot(centre);
        if (lo[k] - t > reach[k] || hi[k] - t < -reach[k]) return false;
      }
      return true;
    }
    static constexpr int kAxes = 10;
    Eigen::Vector3d axis[kAxes];
    double lo[kAxes], hi[kAxes], reach[kAxes];
  };
  Eigen::Vector3d cell_centre(const int idx[3]) const {
    return origin_ + cell_mm_ * (Eigen::Vector3d(idx[0], idx[1], idx[2]).array() + 0.5).matrix();
  }

  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  double cell_mm_ = 1.0;
  int n_[3] = {0, 0, 0};
  std::vector<std::uint32_t> first_, items_;
  std::vector<Eigen::Vector3d> box_lo_, box_hi_;
};

}  // namespace

struct DesignDistance::Impl {
  std::vector<Eigen::Vector3i> corners;              // vertex ids per kept triangle
  std::vector<Eigen::Vector3d> face_normal;          // unit
  std::vector<Eigen::Vector3d> vertex_normal;        // angle-weighted sum
  std::vector<std::uint32_t> edge_of;                // per kept triangle's edge i (corners i, i + 1): its edge
  std::vector<Eigen::Vector3d> edge_normal;          // per edge: the sum of its faces' normals
  std::vector<std::array<std::uint32_t, 3>> beside;  // per triangle: one across each edge (itself: none)
  std::vector<Eigen::Vector3d> points;
  TriangleGrid grid;
  bool closed = false;
  // CGAL's tree, for points far from the design only: made on the first such query (on a
  // machined surface of 2 M triangles it took 0.5 s of each surface difference's set-up,
  // and its triangles 140 MB, where every query is near).
  mutable std::once_flag tree_made;
  mutable std::vector<Triangle> triangles;
  mutable Tree tree;

  const Eigen::Vector3d& corner(std::size_t f, int i) const { return points[static_cast<std::size_t>(corners[f][i])]; }
  double squared_distance(std::size_t f, const Eigen::Vector3d& x) const {
    Feature unused;
    return (x - nearest_on_triangle(x, corner(f, 0), corner(f, 1), corner(f, 2), unused)).squaredNorm();
  }
  // edge_of, edge_normal and beside from the triangles' edges; true when they are closed.
  bool link_edges() {
    // The edges: every triangle's three, sorted by their two vertices and then by triangle and
    // edge number (a parallel sort: one loop filling hash maps of the edges took 3.3 s of the
    // set-up's 4.7 s on a 2 M-triangle machined surface; the set-up is now 0.7-0.9 s on 2
    // threads). Each edge's normal is its faces' normals summed in the triangles' order; a
    // triangle across each edge: for the edge's first triangle the second, for the others the
    // first.
    struct HalfEdge {
      std::uint64_t key;
      std::uint32_t at;  // 3 f + i (under 1.4 billion triangles)
      bool operator<(const HalfEdge& o) const { return key < o.key || (key == o.key && at < o.at); }
    };
    const std::size_t n = corners.size();
    std::vector<HalfEdge> edges(3 * n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t f) {
      for (int i = 0; i < 3; ++i)
        edges[3 * f + static_cast<std::size_t>(i)] = {edge_key(corners[f][i], corners[f][(i + 1) % 3]),
                                                      static_cast<std::uint32_t>(3 * f + static_cast<std::size_t>(i))};
    });
    tbb::parallel_sort(edges.begin(), edges.end());
    edge_of.resize(3 * n);
    beside.resize(n);
    for (std::uint32_t f = 0; f < n; ++f) beside[f] = {f, f, f};
    // Closed: every edge has two triangles, one along it each way (is_closed; on the design's
    // triangles of zero area too, where it has any).
    bool closed = true;
    for (std::size_t first = 0, next; first < edges.size(); first = next) {
      next = first + 1;
      while (next < edges.size() && edges[next].key == edges[first].key) ++next;
      if (closed && next - first == 2) {
        auto forward = [&](std::size_t e) {
          const std::uint32_t f = edges[e].at / 3, i = edges[e].at % 3;
          return corners[f][static_cast<int>(i)] < corners[f][static_cast<int>((i + 1) % 3)];
        };
        closed = forward(first) != forward(first + 1);
      } else {
        closed = false;
      }
      const auto id = static_cast<std::uint32_t>(edge_normal.size());
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      const std::uint32_t g = edges[first].at / 3;
      for (std::size_t e = first; e < next; ++e) {
        const std::uint32_t at = edges[e].at, f = at / 3;
        edge_of[at] = id;
        sum += face_normal[f];
        if (e > first) beside[f][at % 3] = g;
      }
      if (next > first + 1) beside[g][edges[first].at % 3] = edges[first + 1].at / 3;
      edge_normal.push_back(sum);
    }
    return closed;
  }
  const Tree& made_tree() const {
    std::call_once(tree_made, [&] {
      triangles.reserve(corners.size());
      for (std::size_t f = 0; f < corners.size(); ++f) {
        const Eigen::Vector3d &a = corner(f, 0), &b = corner(f, 1), &c = corner(f, 2);
        triangles.emplace_back(K::Point_3(a.x(), a.y(), a.z()), K::Point_3(b.x(), b.y(), b.z()),
                               K::Point_3(c.x(), c.y(), c.z()));
      }
      tree.insert(triangles.begin(), triangles.end());
      tree.build();
      // The KD-tree hint made tie-breaking between equally near triangles vary.
      tree.do_not_accelerate_distance_queries();
    });
    return tree;
  }
};

bool degenerate_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return (b - a).cross(c - a).norm() <= 1e-14 * std::max(1.0, (b - a).squaredNorm() + (c - a).squaredNorm());
}

DesignDistance::DesignDistance(const TriangleMesh& design) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.points = design.vertices_mm;
  // The triangles of nonzero area, in order.
  const std::size_t all = design.triangles.size();
  std::vector<char> kept(all);
  tbb::parallel_for(std::size_t{0}, all, [&](std::size_t f) {
    const auto& t = design.triangles[f];
    kept[f] = !degenerate_triangle(m.points[static_cast<std::size_t>(t[0])], m.points[static_cast<std::size_t>(t[1])],
                                   m.points[static_cast<std::size_t>(t[2])]);
  });
  m.corners.reserve(all);
  for (std::size_t f = 0; f < all; ++f)
    if (kept[f]) m.corners.push_back(design.triangles[f]);
  const std::size_t n = m.corners.size();
  // Per triangle its unit normal and each corner's share of its vertex's normal (the angle
  // there times the normal), in parallel; the shares summed in the triangles' order.
  m.face_normal.resize(n);
  std::vector<std::array<Eigen::Vector3d, 3>> share(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t f) {
    const Eigen::Vector3d unit = (m.corner(f, 1) - m.corner(f, 0)).cross(m.corner(f, 2) - m.corner(f, 0)).normalized();
    m.face_normal[f] = unit;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d& p = m.corner(f, i);
      const Eigen::Vector3d e1 = (m.corner(f, (i + 1) % 3) - p).normalized();
      const Eigen::Vector3d e2 = (m.corner(f, (i + 2) % 3) - p).normalized();
      share[f][static_cast<std::size_t>(i)] = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0)) * unit;
    }
  });
  m.vertex_normal.assign(m.points.size(), Eigen::Vector3d::Zero());
  for (std::size_t f = 0; f < n; ++f)
    for (int i = 0; i < 3; ++i) m.vertex_normal[static_cast<std::size_t>(m.corners[f][i])] += share[f][i];
  share = {};
  const bool closed = m.link_edges();
  m.closed = n == all ? closed : is_closed(design);
  m.grid = TriangleGrid(m.points, m.corners);
}

DesignDistance::~DesignDistance() = default;
DesignDistance::DesignDistance(DesignDistance&&) noexcept = default;
bool DesignDistance::closed() const { return impl_->closed; }
bool DesignDistance::empty() const { return impl_->corners.empty(); }

double DesignDistance::signed_distance(const Eigen::Vector3d& x) const {
  DistanceHint none;
  return signed_distance(x, none);
}

double DesignDistance::signed_distance(const Eigen::Vector3d& x, DistanceHint& hint) const {
  const Impl& m = *impl_;
  if (m.corners.empty()) return std::numeric_limits<double>::infinity();
  // The nearest triangle (of equally near ones, the lowest-numbered): from the grid, starting from
  // the hint's triangle when there is one; from CGAL's tree for a point far from the design.
  const std::size_t count = m.corners.size();
  std::size_t f = count;
  if (!m.grid.empty()) {
    // A first bound from the hint's triangle, then the grid's cells outward from x's.
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_f = count;
    auto consider = [&](std::uint32_t g) {
      const double d2 = m.squared_distance(g, x);
      if (d2 < best || (d2 == best && g < best_f)) {
        best = d2;
        best_f = g;
      }
    };
    if (hint.triangle < count) consider(static_cast<std::uint32_t>(hint.triangle));
    if (m.grid.nearest(x, best, consider) && best_f < count) f = best_f;
  }
  if (f == count) {
    const Tree& tree = m.made_tree();
    const K::Point_3 query(x.x(), x.y(), x.z());
    const auto hit =
        hint.triangle < count
            ? tree.closest_point_and_primitive(
                  query, std::make_pair(K::Point_3(hint.point_mm.x(), hint.point_mm.y(), hint.point_mm.z()),
                                        m.triangles.begin() + static_cast<std::ptrdiff_t>(hint.triangle)))
            : tree.closest_point_and_primitive(query);
    f = static_cast<std::size_t>(hit.second - m.triangles.begin());
  }
  // The nearest point on it and its feature (vertex, edge, face) choose the pseudo-normal
  // that signs the distance exactly.
  Feature feature;
  const Eigen::Vector3d nearest = nearest_on_triangle(x, m.corner(f, 0), m.corner(f, 1), m.corner(f, 2), feature);
  hint.triangle = f;
  hint.point_mm = nearest;
  const Eigen::Vector3i& t = m.corners[f];
  auto edge = [&](int i) { return m.edge_normal[m.edge_of[3 * f + static_cast<std::size_t>(i)]]; };
  Eigen::Vector3d normal = m.face_normal[f];
  switch (feature) {
    case Feature::VertexA:
      normal = m.vertex_normal[static_cast<std::size_t>(t[0])];
      break;
    case Feature::VertexB:
      normal = m.vertex_normal[static_cast<std::size_t>(t[1])];
      break;
    case Feature::VertexC:
      normal = m.vertex_normal[static_cast<std::size_t>(t[2])];
      break;
    case Feature::EdgeAB:
      normal = edge(0);
      break;
    case Feature::EdgeAC:
      normal = edge(2);
      break;
    case Feature::EdgeBC:
      normal = edge(1);
      break;
    case Feature::Face:
      break;
  }
  const Eigen::Vector3d d = x - nearest;
  const double distance = d.norm();
  return d.dot(normal) < 0.0 ? -distance : distance;
}

double DesignDistance::distance_bound(const Eigen::Vector3d& x, DistanceHint& hint, double enough_mm) const {
  const Impl& m = *impl_;
  if (hint.triangle >= m.corners.size()) return std::numeric_limits<double>::infinity();
  double best = m.squared_distance(hint.triangle, x);
  if (!(best <= enough_mm * enough_mm)) {
    const std::size_t from = hint.triangle;
    for (std::uint32_t g : m.beside[from]) {
      if (g == from) continue;
      const double d2 = m.squared_distance(g, x);
      if (d2 < best) {
        best = d2;
        hint.triangle = g;
      }
    }
    if (hint.triangle != from) {
      Feature unused;
      hint.point_mm = nearest_on_triangle(x, m.corner(hint.triangle, 0), m.corner(hint.triangle, 1),
                                          m.corner(hint.triangle, 2), unused);
    }
  }
  return std::sqrt(best);
}

void hinted_queries(std::size_t count, const std::function<void(std::size_t, DistanceHint&)>& query) {
  constexpr std::size_t kChunk = 1024;
  tbb::parallel_for(std::size_t{0}, (count + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    DistanceHint hint;
    for (std::size_t i = chunk * kChunk; i < std::min(count, (chunk + 1) * kChunk); ++i) query(i, hint);
  });
}

Comparison compare(const SurfaceMesh& machined, const DesignDistance& design, const CompareSettings& settings) {
  Comparison result;
  const TriangleMesh& mesh = machined.mesh;
  const std::size_t n = mesh.vertices_mm.size();
  result.deviation_mm.resize(n);
  // The mesher's consecutive vertices are neighbours.
  hinted_queries(n, [&](std::size_t i, DistanceHint& hint) {
    result.deviation_mm[i] = design.signed_distance(mesh.vertices_mm[i], hint);
  });
  for (double d : result.deviation_mm) {
    result.max_gouge_mm = std::max(result.max_gouge_mm, -d);
    result.max_excess_mm = std::max(result.max_excess_mm, d);
  }
  // Regions: connected components of the vertices beyond a tolerance, through the
  // triangles' edges. Only the edges between two vertices beyond one tolerance or the other
  // are listed (a walk from a region's vertex takes no other), each vertex's in the order
  // of the triangles as before: the same walks. (A list per vertex of the whole mesh was the
  // comparison's longest stretch on one thread: the S-piece's 353 k vertices, 0.06 s of its
  // 0.09 s with the lists' freeing.)
  std::vector<char> beyond(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = result.deviation_mm[i];
    beyond[i] = -d > settings.gouge_tolerance_mm || d > settings.excess_tolerance_mm;
  }
  std::vector<std::size_t> first(n + 1, 0);  // vertex v's neighbours: listed[first[v] .. first[v + 1])
  std::vector<int> listed;
  auto for_each_edge = [&](auto&& visit) {
    for (const auto& t : mesh.triangles)
      for (int c = 0; c < 3; ++c) {
        const int a = t[c], b = t[(c + 1) % 3];
        if (!beyond[static_cast<std::size_t>(a)] || !beyond[static_cast<std::size_t>(b)]) continue;
        visit(a, b);
        visit(b, a);
      }
  };
  for_each_edge([&](int v, int) { ++first[static_cast<std::size_t>(v) + 1]; });
  for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
  listed.resize(first[n]);
  {
    std::vector<std::size_t> fill(first.begin(), first.end() - 1);
    for_each_edge([&](int v, int u) { listed[fill[static_cast<std::size_t>(v)]++] = u; });
  }
  result.vertex_area_mm2 = vertex_areas_mm2(mesh);
  const std::vector<double>& area = result.vertex_area_mm2;
  auto regions = [&](double sign, double tolerance) {
    std::vector<Region> out;
    std::vector<char> seen(n, 0);
    for (std::size_t seed = 0; seed < n; ++seed) {
      if (seen[seed] || sign * result.deviation_mm[seed] <= tolerance) continue;
      Region r;
      std::vector<std::size_t> stack{seed};
      seen[seed] = 1;
      double weight = 0.0;
      while (!stack.empty()) {
        const std::size_t v = stack.back();
        stack.pop_back();
        const double depth = sign * result.deviation_mm[v];
        if (depth > r.depth_mm) {
          r.depth_mm = depth;
          r.deepest_mm = mesh.vertices_mm[v];
        }
        r.area_mm2 += area[v];
        r.centroid_mm += area[v] * mesh.vertices_mm[v];
        weight += area[v];
        r.moves.push_back(machined.vertex_move.empty() ? -1 : machined.vertex_move[v]);
        ++r.vertices;
        for (std::size_t k = first[v]; k < first[v + 1]; ++k) {
          const std::size_t uu = static_cast<std::size_t>(listed[k]);
          if (!seen[uu] && sign * result.deviation_mm[uu] > tolerance) {
            seen[uu] = 1;
            stack.push_back(uu);
          }
        }
      }
      r.centroid_mm = weight > 0.0 ? Eigen::Vector3d(r.centroid_mm / weight) : r.deepest_mm;
      std::sort(r.moves.begin(), r.moves.end());
      r.moves.erase(std::unique(r.moves.begin(), r.moves.end()), r.moves.end());
      out.push_back(std::move(r));
    }
    std::stable_sort(out.begin(), out.end(), [](const Region& a, const Region& b) { return a.depth_mm > b.depth_mm; });
    return out;
  };
  result.gouges = regions(-1.0, settings.gouge_tolerance_mm);
  result.excess = regions(1.0, settings.excess_tolerance_mm);
  return result;
}

}  // namespace vcut::removal
