#include "vcut/removal/mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <tuple>
#include <vector>

namespace vcut::removal {
namespace {

Eigen::Vector3d area_normal(const TriangleMesh& mesh, const Eigen::Vector3i& t) {
  const auto& a = mesh.vertices_mm[static_cast<std::size_t>(t[0])];
  return (mesh.vertices_mm[static_cast<std::size_t>(t[1])] - a)
      .cross(mesh.vertices_mm[static_cast<std::size_t>(t[2])] - a);
}

}  // namespace

double signed_volume_mm3(const TriangleMesh& mesh) {
  double six_v = 0.0;
  for (const auto& t : mesh.triangles)
    six_v += mesh.vertices_mm[static_cast<std::size_t>(t[0])].dot(
        mesh.vertices_mm[static_cast<std::size_t>(t[1])].cross(mesh.vertices_mm[static_cast<std::size_t>(t[2])]));
  return six_v / 6.0;
}

// Summed directly, not through OpenMesh's half-edge mesh: building that took half of the
// S-piece's deviation.ply (0.1 of 0.2 s, one thread), and it refuses complex edges anyway.
std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh) {
  // Area-weighted: each triangle's unnormalised normal added to its corners, in triangle order.
  std::vector<Eigen::Vector3d> normals(mesh.vertices_mm.size(), Eigen::Vector3d::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d n = area_normal(mesh, t);
    for (int c = 0; c < 3; ++c) normals[static_cast<std::size_t>(t[c])] += n;
  }
  for (auto& n : normals) {
    const double len = n.norm();
    if (len > 0.0) n /= len;
  }
  return normals;
}

std::vector<double> vertex_areas_mm2(const TriangleMesh& mesh) {
  std::vector<double> area(mesh.vertices_mm.size(), 0.0);
  for (const auto& t : mesh.triangles) {
    const double third = area_normal(mesh, t).norm() / 6.0;
    for (int c = 0; c < 3; ++c) area[static_cast<std::size_t>(t[c])] += third;
  }
  return area;
}

namespace {

// A plane's quadric (Garland-Heckbert), upper triangle of the 4x4 form: the squared distance
// to the plane (times the triangle's doubled area) of a point p is [p 1] Q [p 1]^T.
using Quadric = std::array<double, 10>;

void add_plane(Quadric& q, const Eigen::Vector3d& n, double d, double weight) {
  q[0] += weight * n.x() * n.x();
  q[1] += weight * n.x() * n.y();
  q[2] += weight * n.x() * n.z();
  q[3] += weight * n.x() * d;
  q[4] += weight * n.y() * n.y();
  q[5] += weight * n.y() * n.z();
  q[6] += weight * n.y() * d;
  q[7] += weight * n.z() * n.z();
  q[8] += weight * n.z() * d;
  q[9] += weight * d * d;
}

double quadric_error(const Quadric& q, const Eigen::Vector3d& p) {
  const double x = p.x(), y = p.y(), z = p.z();
  return q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x + q[4] * y * y + 2 * q[5] * y * z +
         2 * q[6] * y + q[7] * z * z + 2 * q[8] * z + q[9];
}

// The cells of a grid of side `cell_mm` from `origin`, packed 21 bits per axis.
struct CellGrid {
  Eigen::Vector3d origin;
  double cell_mm;
  std::uint64_t key(const Eigen::Vector3d& p) const {
    std::uint64_t k = 0;
    for (int a = 0; a < 3; ++a) {
      const double i = std::floor((p[a] - origin[a]) / cell_mm);
      k = (k << 20) | static_cast<std::uint64_t>(std::clamp(i, 0.0, double((1 << 20) - 1)));
    }
    return k;
  }
};

}  // namespace

// Our own clustering, not OpenMesh's decimater: on D32's 5.58 M triangles the decimater took
// 135 s (2 threads, in slabs), this about 1 s.
TriangleMesh decimate(const TriangleMesh& mesh, std::size_t max_triangles, std::vector<int>& kept) {
  kept.clear();
  const std::size_t n = mesh.triangles.size();
  if (n <= max_triangles) {
    kept.resize(mesh.vertices_mm.size());
    for (std::size_t i = 0; i < kept.size(); ++i) kept[i] = static_cast<int>(i);
    return mesh;
  }
  // The grid starts at the box's corner (the quadrics take positions from there: smaller terms).
  // The first cell from the area: a surface of area A crosses about 1.5 A / c^2 cells of side
  // c, each left with about two triangles.
  Eigen::AlignedBox3d box;
  for (const auto& p : mesh.vertices_mm) box.extend(p);
  double area_mm2 = 0.0;
  for (const auto& t : mesh.triangles) area_mm2 += 0.5 * area_normal(mesh, t).norm();
  const std::size_t nv = mesh.vertices_mm.size();
  std::vector<std::uint64_t> key(nv);
  // Which way each vertex faces: the largest component of its triangles' normals and its sign,
  // where all its triangles agree, a seventh group where they do not, an eighth in no triangle.
  // So the vertices of a cell on two sides of a sharp edge fall in two groups, and those along
  // the edge in a third, whose vertex stays on the edge. A vertex's group does not depend on
  // the order its triangles come in (one side when all agree, else mixed): the triangles side
  // by side, each vertex's group updated atomically.
  constexpr std::uint8_t kUnset = 0xff, kMixed = 6;
  std::vector<std::uint8_t> facing(nv);
  {
    std::vector<std::atomic<std::uint8_t>> group(nv);
    tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) { group[v].store(kUnset, std::memory_order_relaxed); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const Eigen::Vector3i& t = mesh.triangles[i];
        const Eigen::Vector3d a = area_normal(mesh, t);
        int axis = 0;
        a.cwiseAbs().maxCoeff(&axis);
        const auto side = static_cast<std::uint8_t>(2 * axis + (a[axis] < 0 ? 1 : 0));
        for (int c = 0; c < 3; ++c) {
          std::atomic<std::uint8_t>& f = group[static_cast<std::size_t>(t[c])];
          std::uint8_t now = f.load(std::memory_order_relaxed);
          while (true) {
            const std::uint8_t next = now == kUnset || now == side ? side : kMixed;
            if (next == now || f.compare_exchange_weak(now, next, std::memory_order_relaxed)) break;
          }
        }
      }
    });
    tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) { facing[v] = group[v].load(std::memory_order_relaxed); });
  }
  auto outside = [&](const Eigen::Vector3i& t) {
    const std::size_t a = static_cast<std::size_t>(t[0]), b = static_cast<std::size_t>(t[1]),
                      c = static_cast<std::size_t>(t[2]);
    return key[a] != key[b] && key[b] != key[c] && key[a] != key[c];
  };
  CellGrid grid{box.min(),
                std::max(std::sqrt(3.0 * area_mm2 / static_cast<double>(std::max<std::size_t>(max_triangles, 1))),
                         1e-9 * std::max(1.0, box.sizes().maxCoeff()))};
  // The cell: the number of triangles spanning three cells goes about as 1 / c^2, so each try
  // scales the cell by the root of its count over the budget, until a cell leaves between
  // 90 % and 100 % of the budget (the cancellation below only removes more); the smallest cell
  // found within the budget is taken.
  auto spanning_count = [&](double cell_mm) {
    grid.cell_mm = cell_mm;
    tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) {
      key[v] = (grid.key(mesh.vertices_mm[v]) << 3) | std::min<std::uint8_t>(facing[v], 7);
    });
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n), std::size_t{0},
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t count) {
          for (std::size_t i = r.begin(); i != r.end(); ++i) count += outside(mesh.triangles[i]) ? 1 : 0;
          return count;
        },
        std::plus<>());
  };
  const double budget = static_cast<double>(max_triangles);
  double cell_mm = grid.cell_mm, within_mm = std::numeric_limits<double>::infinity();
  for (int attempt = 0; attempt < 12; ++attempt) {
    const double count = static_cast<double>(spanning_count(cell_mm));
    if (count <= budget) {
      within_mm = std::min(within_mm, cell_mm);
      if (count >= 0.9 * budget) break;
    }
    double next = count > 0.0 ? cell_mm * std::sqrt(count / (0.95 * budget)) : 0.5 * cell_mm;
    next = count > budget ? std::max(next, 1.01 * cell_mm) : std::min(next, 0.99 * cell_mm);
    if (next >= within_mm) break;  // a cell at least as large already fits
    cell_mm = next;
  }
  if (!(within_mm < std::numeric_limits<double>::infinity())) {  // none fitted: grow until one does
    within_mm = grid.cell_mm;
    do within_mm *= 1.1;
    while (static_cast<double>(spanning_count(within_mm)) > budget);
  }
  if (grid.cell_mm != within_mm) spanning_count(within_mm);
  // Clusters in the order of their cells (vertex index within one: the same for any thread count).
  std::vector<std::pair<std::uint64_t, int>> by_cell(nv);
  tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) { by_cell[v] = {key[v], static_cast<int>(v)}; });
  tbb::parallel_sort(by_cell.begin(), by_cell.end());
  std::vector<int> cluster(nv);
  std::vector<std::size_t> first{0};  // the clusters' ranges in by_cell
  for (std::size_t i = 0; i < nv; ++i) {
    if (i > 0 && by_cell[i].first != by_cell[i - 1].first) first.push_back(i);
    cluster[static_cast<std::size_t>(by_cell[i].second)] = static_cast<int>(first.size() - 1);
  }
  const std::size_t clusters = first.size();
  first.push_back(nv);
  // The clusters' vertices (from their quadrics, summed in triangle order on one thread) and
  // the triangles left (from the clusters alone) side by side.
  std::vector<int> chosen(clusters);
  std::vector<std::pair<int, Eigen::Vector3i>> left;
  tbb::parallel_invoke(
      [&] {
        // Each cluster's quadric: the planes of every triangle at its vertices, area-weighted
        // (Lindstrom's out-of-core clustering), summed in triangle order.
        std::vector<Quadric> quadric(clusters, Quadric{});
        std::vector<double> weight(clusters, 0.0);  // the quadric's total weight: its error over it is in mm^2
        for (const auto& t : mesh.triangles) {
          const Eigen::Vector3d a = mesh.vertices_mm[static_cast<std::size_t>(t[0])] - grid.origin;
          const Eigen::Vector3d normal = area_normal(mesh, t);
          const double doubled_area = normal.norm();
          if (doubled_area == 0.0) continue;
          const Eigen::Vector3d unit = normal / doubled_area;
          for (int c = 0; c < 3; ++c) {
            const auto k = static_cast<std::size_t>(cluster[static_cast<std::size_t>(t[c])]);
            add_plane(quadric[k], unit, -unit.dot(a), doubled_area);
            weight[k] += doubled_area;
          }
        }
        // Each cluster's vertex: the original vertex nearest its planes (a corner where three meet,
        // an edge where two do), among near equals (within 1e-4 of the cell in root mean square
        // distance) the one nearest the cluster's centre, so that vertices on a plane spread evenly.
        const double slack_mm2 = 1e-8 * grid.cell_mm * grid.cell_mm;
        tbb::parallel_for(std::size_t{0}, clusters, [&](std::size_t k) {
          Eigen::Vector3d centre = Eigen::Vector3d::Zero();
          for (std::size_t i = first[k]; i < first[k + 1]; ++i)
            centre += mesh.vertices_mm[static_cast<std::size_t>(by_cell[i].second)];
          centre /= static_cast<double>(first[k + 1] - first[k]);
          double best = std::numeric_limits<double>::infinity(), best_d = 0.0;
          int best_v = -1;
          for (std::size_t i = first[k]; i < first[k + 1]; ++i) {
            const int v = by_cell[i].second;
            const Eigen::Vector3d& p = mesh.vertices_mm[static_cast<std::size_t>(v)];
            const double e = weight[k] > 0.0 ? quadric_error(quadric[k], p - grid.origin) / weight[k] : 0.0;
            const double d = (p - centre).squaredNorm();
            if (best_v < 0 || e < best - slack_mm2 || (e <= best + slack_mm2 && d < best_d))
              best = std::min(best, e), best_d = d, best_v = v;
          }
          chosen[k] = best_v;
        });
      },
      [&] {
        // The triangles that span three clusters, each a triple of clusters with an orientation; a
        // triple met in both orientations (the two sides of a wall thinner than a cell) cancels, so
        // the result bounds what the mesh bounded.
        struct Spanning {
          std::array<int, 3> sorted;  // the clusters, ascending
          int sign;                   // +1 where the triangle runs sorted[0] -> sorted[1] -> sorted[2]
          int index;                  // the original triangle
          bool operator<(const Spanning& o) const { return std::tie(sorted, index) < std::tie(o.sorted, o.index); }
        };
        // Found in fixed chunks of the triangles side by side and joined in chunk order.
        constexpr std::size_t kChunk = std::size_t{1} << 16;
        std::vector<std::vector<Spanning>> found((n + kChunk - 1) / kChunk);
        tbb::parallel_for(std::size_t{0}, found.size(), [&](std::size_t k) {
          for (std::size_t i = k * kChunk; i < std::min(n, (k + 1) * kChunk); ++i) {
            const Eigen::Vector3i& t = mesh.triangles[i];
            if (!outside(t)) continue;
            std::array<int, 3> c{cluster[static_cast<std::size_t>(t[0])], cluster[static_cast<std::size_t>(t[1])],
                                 cluster[static_cast<std::size_t>(t[2])]};
            // An even permutation of (c0 c1 c2) keeps the orientation: rotate the smallest first.
            const int m = c[0] < c[1] ? (c[0] < c[2] ? 0 : 2) : (c[1] < c[2] ? 1 : 2);
            std::rotate(c.begin(), c.begin() + m, c.end());
            const int sign = c[1] < c[2] ? 1 : -1;
            if (sign < 0) std::swap(c[1], c[2]);
            found[k].push_back({c, sign, static_cast<int>(i)});
          }
        });
        std::vector<Spanning> spanning;
        for (std::vector<Spanning>& f : found) spanning.insert(spanning.end(), f.begin(), f.end());
        found.clear();
        tbb::parallel_sort(spanning.begin(), spanning.end());
        // What is left, in the order of the triangles that first made each triple.
        for (std::size_t i = 0; i < spanning.size();) {
          std::size_t j = i;
          int sum = 0;
          for (; j < spanning.size() && spanning[j].sorted == spanning[i].sorted; ++j) sum += spanning[j].sign;
          const auto& s = spanning[i].sorted;
          for (int copy = 0; copy < std::abs(sum); ++copy)
            left.push_back(
                {spanning[i].index, sum > 0 ? Eigen::Vector3i(s[0], s[1], s[2]) : Eigen::Vector3i(s[0], s[2], s[1])});
          i = j;
        }
        // Two entries of one triangle are copies of one triple (its sum's |sum| copies): any sort by
        // the triangle gives the same list.
        tbb::parallel_sort(left.begin(), left.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      });
  TriangleMesh out;
  out.triangles.reserve(left.size());
  std::vector<int> index(clusters, -1);
  for (const auto& [original, t] : left) {
    Eigen::Vector3i local;
    for (int c = 0; c < 3; ++c) {
      int& at = index[static_cast<std::size_t>(t[c])];
      if (at < 0) {
        at = static_cast<int>(out.vertices_mm.size());
        const int v = chosen[static_cast<std::size_t>(t[c])];
        out.vertices_mm.push_back(mesh.vertices_mm[static_cast<std::size_t>(v)]);
        kept.push_back(v);
      }
      local[c] = at;
    }
    out.triangles.push_back(local);
  }
  return out;
}

bool is_closed(const TriangleMesh& mesh) {
  // Each directed edge must appear once and its reverse once: the sorted directed edges have
  // no repeat and equal the sorted reversed ones. (Two parallel sorts: on a closed sphere of
  // 3.6 M triangles, 2 threads, 0.57-0.81 s against 2.5-2.7 s for a hash map of the edges.)
  auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
  };
  const std::size_t n = mesh.triangles.size() * 3;
  std::vector<std::uint64_t> directed(n), reversed(n);
  tbb::parallel_for(std::size_t{0}, mesh.triangles.size(), [&](std::size_t i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    for (int c = 0; c < 3; ++c) {
      directed[3 * i + static_cast<std::size_t>(c)] = key(t[c], t[(c + 1) % 3]);
      reversed[3 * i + static_cast<std::size_t>(c)] = key(t[(c + 1) % 3], t[c]);
    }
  });
  tbb::parallel_sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  tbb::parallel_sort(reversed.begin(), reversed.end());
  return directed == reversed;
}

}  // namespace vcut::removal
