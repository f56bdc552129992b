#include "vcut/removal/surface_difference.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "vcut/removal/compare.h"

namespace vcut::removal {

namespace {

// How far from a sharp edge (in voxels) two meshings of nearly one solid may differ by the
// edge's chamfer.
constexpr double kEdgeReach = 2.0;

// Per vertex: does an incident face's normal stray more than `limit_deg` from the mean of
// the incident faces' normals (area weighted)?
std::vector<bool> sharp_vertices(const TriangleMesh& mesh, double limit_deg) {
  const std::size_t n = mesh.vertices_mm.size();
  std::vector<Eigen::Vector3d> mean(n, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> face(mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    const Eigen::Vector3d& p0 = mesh.vertices_mm[static_cast<std::size_t>(t[0])];
    face[f] = (mesh.vertices_mm[static_cast<std::size_t>(t[1])] - p0)
                  .cross(mesh.vertices_mm[static_cast<std::size_t>(t[2])] - p0);
    for (int c = 0; c < 3; ++c) mean[static_cast<std::size_t>(t[c])] += face[f];
  }
  const double cos_limit = std::cos(limit_deg * M_PI / 180.0);
  std::vector<bool> sharp(n, false);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const double area2 = face[f].norm();
    if (area2 <= 0.0) continue;
    for (int c = 0; c < 3; ++c) {
      const std::size_t i = static_cast<std::size_t>(mesh.triangles[f][c]);
      const double m = mean[i].norm();
      if (m <= 0.0 || face[f].dot(mean[i]) < cos_limit * area2 * m) sharp[i] = true;
    }
  }
  return sharp;
}

// Vertices of `mesh` within `radius_mm` of any of `points`: a grid of that cell size, the
// points sorted by cell; a vertex looks in the 27 cells about its own only when its own is
// next to one holding a point (a sorted list of those), which most are not.
std::vector<char> near_points(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& points, double radius_mm) {
  using Cell = std::array<long, 3>;
  auto cell = [&](const Eigen::Vector3d& p) {
    return Cell{static_cast<long>(std::floor(p.x() / radius_mm)), static_cast<long>(std::floor(p.y() / radius_mm)),
                static_cast<long>(std::floor(p.z() / radius_mm))};
  };
  std::vector<std::pair<Cell, Eigen::Vector3d>> sorted;
  sorted.reserve(points.size());
  for (const auto& p : points) sorted.emplace_back(cell(p), p);
  std::sort(sorted.begin(), sorted.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<Cell> around;  // the cells next to (or at) a point's
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    if (i > 0 && sorted[i].first == sorted[i - 1].first) continue;
    const Cell& c = sorted[i].first;
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) around.push_back({c[0] + dx, c[1] + dy, c[2] + dz});
  }
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  std::vector<char> near(mesh.vertices_mm.size(), 0);  // char: written from several threads
  tbb::parallel_for(std::size_t{0}, mesh.vertices_mm.size(), [&](std::size_t i) {
    const Eigen::Vector3d& v = mesh.vertices_mm[i];
    const Cell c = cell(v);
    if (!std::binary_search(around.begin(), around.end(), c)) return;
    for (long dx = -1; dx <= 1 && !near[i]; ++dx)
      for (long dy = -1; dy <= 1 && !near[i]; ++dy)
        for (long dz = -1; dz <= 1 && !near[i]; ++dz) {
          const Cell at{c[0] + dx, c[1] + dy, c[2] + dz};
          auto it = std::lower_bound(sorted.begin(), sorted.end(), at,
                                     [](const auto& x, const Cell& key) { return x.first < key; });
          for (; it != sorted.end() && it->first == at; ++it)
            if ((it->second - v).squaredNorm() <= radius_mm * radius_mm) {
              near[i] = 1;
              break;
            }
        }
  });
  return near;
}

// Where surface `mesh` has sharp edges (none when limit_deg is 0).
std::vector<Eigen::Vector3d> sharp_points_of(const TriangleMesh& mesh, double limit_deg) {
  std::vector<Eigen::Vector3d> out;
  if (!(limit_deg > 0.0)) return out;
  const std::vector<bool> sharp = sharp_vertices(mesh, limit_deg);
  for (std::size_t i = 0; i < sharp.size(); ++i)
    if (sharp[i]) out.push_back(mesh.vertices_mm[i]);
  return out;
}

}  // namespace

PreparedSurface::PreparedSurface(const SurfaceMesh& surface, double sharp_edge_deg)
    : surface_(surface), distance_(surface.mesh), sharp_edge_deg_(sharp_edge_deg) {
  sharp_points_ = sharp_points_of(surface.mesh, sharp_edge_deg);
}

namespace {

// Every vertex of each surface against the other's triangles.
SurfaceDifference measure(const PreparedSurface& prepared_a, const PreparedSurface& prepared_b, double v) {
  const SurfaceMesh &a = prepared_a.surface(), &b = prepared_b.surface();
  const DesignDistance &to_a = prepared_a.distance(), &to_b = prepared_b.distance();
  const std::size_t na = a.mesh.vertices_mm.size();
  std::vector<double> d(na + b.mesh.vertices_mm.size());
  std::vector<Eigen::Vector3d> where(d.size());
  std::vector<bool> skip(d.size(), false);
  if (prepared_b.sharp_edge_deg() > 0.0) {
    // Near a sharp edge of either surface: the other meshing may cut that edge's corner
    // anywhere within a cell or two of it.
    std::vector<Eigen::Vector3d> edge_points = prepared_a.sharp_points();
    edge_points.insert(edge_points.end(), prepared_b.sharp_points().begin(), prepared_b.sharp_points().end());
    std::vector<char> sa, sb;
    tbb::parallel_invoke([&] { sa = near_points(a.mesh, edge_points, kEdgeReach * v); },
                         [&] { sb = near_points(b.mesh, edge_points, kEdgeReach * v); });
    std::copy(sa.begin(), sa.end(), skip.begin());
    std::copy(sb.begin(), sb.end(), skip.begin() + static_cast<std::ptrdiff_t>(na));
  }
  hinted_queries(d.size(), [&](std::size_t i, DistanceHint& hint) {
    const bool in_a = i < na;
    if (i == na) hint = DistanceHint();  // the other mesh's triangles from here
    where[i] = in_a ? a.mesh.vertices_mm[i] : b.mesh.vertices_mm[i - na];
    d[i] = std::abs((in_a ? to_b : to_a).signed_distance(where[i], hint));
  });
  SurfaceDifference e;
  e.done = true;
  double squares = 0.0;
  std::vector<double> counted;
  counted.reserve(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (skip[i]) {
      ++e.edge_vertices;
      e.edge_max_mm = std::max(e.edge_max_mm, d[i]);
      continue;
    }
    counted.push_back(d[i]);
    squares += d[i] * d[i];
    e.beyond_quarter += d[i] > 0.25 * v;
    if (d[i] > e.max_mm) {
      e.max_mm = d[i];
      e.max_where_mm = where[i];
    }
  }
  e.vertices = counted.size();
  e.rms_mm = counted.empty() ? 0.0 : std::sqrt(squares / static_cast<double>(counted.size()));
  if (!counted.empty()) {
    const std::size_t k = static_cast<std::size_t>(0.99 * static_cast<double>(counted.size() - 1));
    std::nth_element(counted.begin(), counted.begin() + static_cast<std::ptrdiff_t>(k), counted.end());
    e.p99_mm = counted[k];
  }
  return e;
}

}  // namespace

SurfaceDifference surface_difference(const SurfaceMesh& a, const SurfaceMesh& b, double v, double sharp_edge_deg) {
  // The two sides side by side (each partly serial).
  std::optional<PreparedSurface> prepared_a, prepared_b;
  tbb::parallel_invoke([&] { prepared_b.emplace(b, sharp_edge_deg); }, [&] { prepared_a.emplace(a, sharp_edge_deg); });
  return measure(*prepared_a, *prepared_b, v);
}

SurfaceDifference surface_difference(const SurfaceMesh& a, const PreparedSurface& b, double v) {
  return measure(PreparedSurface(a, b.sharp_edge_deg()), b, v);
}

}  // namespace vcut::removal
