#include "vcut/removal/compare.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

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

}  // namespace

struct DesignDistance::Impl {
  std::vector<Triangle> triangles;
  std::vector<Eigen::Vector3i> corners;          // vertex ids per kept triangle
  std::vector<Eigen::Vector3d> face_normal;      // unit
  std::vector<Eigen::Vector3d> vertex_normal;    // angle-weighted sum
  std::unordered_map<std::uint64_t, Eigen::Vector3d> edge_normal;  // sum of adjacent faces
  std::vector<Eigen::Vector3d> points;
  Tree tree;
  bool closed = false;
};

DesignDistance::DesignDistance(const TriangleMesh& design) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.points = design.vertices_mm;
  m.vertex_normal.assign(design.vertices_mm.size(), Eigen::Vector3d::Zero());
  for (const auto& t : design.triangles) {
    const Eigen::Vector3d& a = m.points[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = m.points[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = m.points[static_cast<std::size_t>(t[2])];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() <= 1e-14 * std::max(1.0, (b - a).squaredNorm() + (c - a).squaredNorm())) continue;  // degenerate
    const Eigen::Vector3d unit = n.normalized();
    m.triangles.emplace_back(K::Point_3(a.x(), a.y(), a.z()), K::Point_3(b.x(), b.y(), b.z()),
                             K::Point_3(c.x(), c.y(), c.z()));
    m.corners.push_back(t);
    m.face_normal.push_back(unit);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d& p = m.points[static_cast<std::size_t>(t[i])];
      const Eigen::Vector3d e1 = (m.points[static_cast<std::size_t>(t[(i + 1) % 3])] - p).normalized();
      const Eigen::Vector3d e2 = (m.points[static_cast<std::size_t>(t[(i + 2) % 3])] - p).normalized();
      const double angle = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
      m.vertex_normal[static_cast<std::size_t>(t[i])] += angle * unit;
      // Eigen vectors are not zero-initialised: insert an explicit zero first.
      m.edge_normal.try_emplace(edge_key(t[i], t[(i + 1) % 3]), Eigen::Vector3d::Zero()).first->second += unit;
    }
  }
  m.closed = is_closed(design);
  m.tree.insert(m.triangles.begin(), m.triangles.end());
  m.tree.build();
  m.tree.do_not_accelerate_distance_queries();  // the KD-tree hint made tie-breaking between equally near triangles vary
}

DesignDistance::~DesignDistance() = default;
DesignDistance::DesignDistance(DesignDistance&&) noexcept = default;
bool DesignDistance::closed() const { return impl_->closed; }

double DesignDistance::signed_distance(const Eigen::Vector3d& x) const {
  DistanceHint none;
  return signed_distance(x, none);
}

double DesignDistance::signed_distance(const Eigen::Vector3d& x, DistanceHint& hint) const {
  const Impl& m = *impl_;
  // CGAL finds the nearest triangle (starting from the hint's distance as a bound, when
  // there is one); the nearest point on it and its feature (vertex, edge, face) come from
  // Ericson's region test (Real-Time Collision Detection, 5.1.5), so the pseudo-normal that
  // signs the distance is chosen exactly.
  const K::Point_3 query(x.x(), x.y(), x.z());
  const auto hit = hint.triangle < m.triangles.size()
      ? m.tree.closest_point_and_primitive(
            query, std::make_pair(K::Point_3(hint.point_mm.x(), hint.point_mm.y(), hint.point_mm.z()),
                                  m.triangles.begin() + static_cast<std::ptrdiff_t>(hint.triangle)))
      : m.tree.closest_point_and_primitive(query);
  const std::size_t f = static_cast<std::size_t>(hit.second - m.triangles.begin());
  hint.triangle = f;
  hint.point_mm = Eigen::Vector3d(hit.first.x(), hit.first.y(), hit.first.z());
  const Eigen::Vector3i& t = m.corners[f];
  const Eigen::Vector3d& a = m.points[static_cast<std::size_t>(t[0])];
  const Eigen::Vector3d& b = m.points[static_cast<std::size_t>(t[1])];
  const Eigen::Vector3d& c = m.points[static_cast<std::size_t>(t[2])];
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = x - a;
  Eigen::Vector3d nearest;
  Eigen::Vector3d normal;
  auto edge = [&](int i, int j) { return m.edge_normal.at(edge_key(t[i], t[j])); };
  auto vertex = [&](int i) { return m.vertex_normal[static_cast<std::size_t>(t[i])]; };
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const Eigen::Vector3d bp = x - b, cp = x - c;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp), d5 = ab.dot(cp), d6 = ac.dot(cp);
  const double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
  if (d1 <= 0.0 && d2 <= 0.0) {
    nearest = a; normal = vertex(0);
  } else if (d3 >= 0.0 && d4 <= d3) {
    nearest = b; normal = vertex(1);
  } else if (d6 >= 0.0 && d5 <= d6) {
    nearest = c; normal = vertex(2);
  } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    nearest = a + d1 / (d1 - d3) * ab; normal = edge(0, 1);
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    nearest = a + d2 / (d2 - d6) * ac; normal = edge(0, 2);
  } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    nearest = b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b); normal = edge(1, 2);
  } else {
    const double denom = 1.0 / (va + vb + vc);
    nearest = a + ab * (vb * denom) + ac * (vc * denom);
    normal = m.face_normal[f];
  }
  const Eigen::Vector3d d = x - nearest;
  const double distance = d.norm();
  return d.dot(normal) < 0.0 ? -distance : distance;
}

Comparison compare(const SurfaceMesh& machined, const DesignDistance& design, const CompareSettings& settings) {
  Comparison result;
  const TriangleMesh& mesh = machined.mesh;
  const std::size_t n = mesh.vertices_mm.size();
  result.deviation_mm.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i)
      result.deviation_mm[i] = design.signed_distance(mesh.vertices_mm[i]);
  });
  for (double d : result.deviation_mm) {
    result.max_gouge_mm = std::max(result.max_gouge_mm, -d);
    result.max_excess_mm = std::max(result.max_excess_mm, d);
  }
  // Regions: connected components of the vertices beyond a tolerance, through the
  // triangles' edges.
  std::vector<std::vector<int>> neighbours(n);
  for (const auto& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      neighbours[static_cast<std::size_t>(t[c])].push_back(t[(c + 1) % 3]);
      neighbours[static_cast<std::size_t>(t[(c + 1) % 3])].push_back(t[c]);
    }
  const std::vector<double> area = vertex_areas_mm2(mesh);
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
        if (depth > r.depth_mm) { r.depth_mm = depth; r.deepest_mm = mesh.vertices_mm[v]; }
        r.area_mm2 += area[v];
        r.centroid_mm += area[v] * mesh.vertices_mm[v];
        weight += area[v];
        r.moves.push_back(machined.vertex_move.empty() ? -1 : machined.vertex_move[v]);
        ++r.vertices;
        for (int u : neighbours[v]) {
          const std::size_t uu = static_cast<std::size_t>(u);
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
