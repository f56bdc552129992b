// Deviation from the design against designs built by hand from the analytic cut
// (issue 2: equal design -> no gouge; offset 0.05 mm either way -> gouge or excess of
// 0.05 +- v/10 at the right place, naming the cutting move).
#include "vcut/removal/compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "sanitized.h"
#include "test_meshes.h"
#include "vcut/removal/dexel_stock.h"
#include "vcut/removal/endpoint_check.h"
#include "vcut/removal/surface_difference.h"
#include "vcut/removal/vdb_stock.h"

namespace vcut::removal {
namespace {

constexpr double kV = 0.1;
constexpr double kOffset = 0.05;

TEST(DesignDistance, BoxSignsAndDistances) {
  const DesignDistance d(test::box_mesh({0, 0, 0}, {10, 10, 10}));
  EXPECT_TRUE(d.closed());
  EXPECT_NEAR(d.signed_distance({5, 5, 12}), 2.0, 1e-12);        // above a face
  EXPECT_NEAR(d.signed_distance({5, 5, 9}), -1.0, 1e-12);        // inside
  EXPECT_NEAR(d.signed_distance({13, 14, 5}), 5.0, 1e-12);       // beside an edge: 3-4-5
  EXPECT_NEAR(d.signed_distance({-1, -2, -2}), 3.0, 1e-12);      // beyond a corner
  EXPECT_NEAR(d.signed_distance({0.5, 0.5, 0.5}), -0.5, 1e-12);  // inside near a corner
}

// A mesh of lines only: nothing to measure against, an infinite distance (no crash).
TEST(DesignDistance, MeshWithoutAreaIsEmpty) {
  TriangleMesh line;
  line.vertices_mm = {{0, 0, 1}, {1, 1, 1}, {2, 2, 1}};
  line.triangles = {{0, 1, 2}};
  const DesignDistance d(line);
  EXPECT_TRUE(d.empty());
  EXPECT_EQ(d.signed_distance({0, 0, 0}), std::numeric_limits<double>::infinity());
  EXPECT_FALSE(DesignDistance(test::box_mesh({0, 0, 0}, {1, 1, 1})).empty());
}

// Distance from x to triangle abc by a second method: the foot on the plane when it lies
// inside (same side of all three edges), else the nearest of the three edges.
double brute_triangle_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3d foot = x - n.dot(x - a) * n;
  const bool inside =
      (b - a).cross(foot - a).dot(n) >= 0 && (c - b).cross(foot - b).dot(n) >= 0 && (a - c).cross(foot - c).dot(n) >= 0;
  if (inside) return std::abs(n.dot(x - a));
  auto segment = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    const double t = std::clamp((x - p).dot(q - p) / (q - p).squaredNorm(), 0.0, 1.0);
    return (x - (p + t * (q - p))).norm();
  };
  return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

double brute_distance(const TriangleMesh& mesh, const Eigen::Vector3d& x) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles)
    best = std::min(best, brute_triangle_distance(x, mesh.vertices_mm[static_cast<std::size_t>(t[0])],
                                                  mesh.vertices_mm[static_cast<std::size_t>(t[1])],
                                                  mesh.vertices_mm[static_cast<std::size_t>(t[2])]));
  return best;
}

// The triangles across each edge, found by brute force (every pair sharing two vertices):
// from a hint on one, a point just off the middle of the other's face (nearer to it than to
// any other triangle) is measured across the edge, and the hint handed back names it. Both
// ways across every edge of the slotted block and of a box (whose triangles' neighbours
// come before and after them in number).
TEST(DesignDistance, BoundLooksAcrossEveryEdgeBothWays) {
  for (const TriangleMesh& mesh : {test::box_mesh({0, 0, 0}, {10, 20, 30}), test::slotted_block(5.0, 2.0)}) {
    const DesignDistance design(mesh);
    const auto& t = mesh.triangles;
    auto vertex = [&](std::size_t f, int i) { return mesh.vertices_mm[static_cast<std::size_t>(t[f][i])]; };
    int pairs = 0;
    for (std::size_t f = 0; f < t.size(); ++f)
      for (std::size_t g = 0; g < t.size(); ++g) {
        int shared = 0;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) shared += t[f][i] == t[g][j];
        if (f == g || shared != 2) continue;
        const Eigen::Vector3d centre = (vertex(g, 0) + vertex(g, 1) + vertex(g, 2)) / 3.0;
        const Eigen::Vector3d normal = (vertex(g, 1) - vertex(g, 0)).cross(vertex(g, 2) - vertex(g, 0)).normalized();
        // Off the face by a tenth of the centre's distance to the nearest edge's line: g is nearest.
        double inset = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 3; ++i) {
          const Eigen::Vector3d a = vertex(g, i), e = (vertex(g, (i + 1) % 3) - a).normalized();
          inset = std::min(inset, ((centre - a) - (centre - a).dot(e) * e).norm());
        }
        const Eigen::Vector3d x = centre + 0.1 * inset * normal;
        DistanceHint hint;
        hint.triangle = f;
        const double bound = design.distance_bound(x, hint, 0.0);
        ASSERT_NEAR(bound, 0.1 * inset, 1e-9) << "from triangle " << f << " to " << g;
        ASSERT_EQ(hint.triangle, g) << "from triangle " << f;
        ++pairs;
      }
    EXPECT_EQ(pairs, static_cast<int>(3 * t.size()));  // closed: three neighbours each
  }
}

// Closed as is_closed says (each edge once each way), for closed meshes, a box with a face's
// triangle missing, one turned over, one twice, and one of zero area added.
TEST(DesignDistance, ClosedAsEveryEdgeOnceEachWay) {
  const TriangleMesh box = test::box_mesh({0, 0, 0}, {10, 20, 30});
  TriangleMesh open = box, turned = box, twice = box, sliver = box;
  open.triangles.pop_back();
  std::swap(turned.triangles[3][1], turned.triangles[3][2]);
  twice.triangles.push_back(twice.triangles[5]);
  sliver.vertices_mm.push_back(0.5 * (box.vertices_mm[0] + box.vertices_mm[1]));  // on the line between them
  sliver.triangles.push_back({0, 1, static_cast<int>(sliver.vertices_mm.size()) - 1});
  const std::vector<std::pair<TriangleMesh, bool>> cases = {{box, true},    {test::slotted_block(5.0, 2.0), true},
                                                            {open, false},  {turned, false},
                                                            {twice, false}, {sliver, false}};
  for (const auto& [mesh, closed] : cases) {
    EXPECT_EQ(DesignDistance(mesh).closed(), closed) << mesh.triangles.size() << " triangles";
    EXPECT_EQ(is_closed(mesh), closed);
  }
}

// The grid behind the distance queries (cells listing the triangles that meet them, a
// search outward from the query's cell) against a brute-force minimum over all triangles
// and an analytic inside test, on meshes of long slivers beside small triangles (a fan-
// triangulated 600-gon prism, convex, 2,396 triangles; the slotted block, not convex), for points near and
// far, queried with and without hints and with hints from far away.
// The endpoint check's bound: from any hint, never below the distance (to the bit: the
// check compares them with a 1e-9 mm allowance only for CGAL's far points); from the nearest
// triangle's hint, the distance itself; looking across the hint's edges, never above the
// hint's own triangle. Points within 1 mm of the slotted block's surface, hints from other
// points' queries (many a triangle away).
TEST(DesignDistance, BoundFromAHintIsNeverBelowTheDistance) {
  const DesignDistance design(test::slotted_block(5.0, 2.0));
  std::mt19937 random(33);
  std::uniform_real_distribution<double> along(-1.0, 61.0), across(-1.0, 41.0), height(-21.0, 1.0);
  std::vector<DistanceHint> hints;
  int tested = 0, crossed = 0;
  for (int k = 0; k < 20000 && tested < 3000; ++k) {
    const Eigen::Vector3d x(along(random), across(random), height(random));
    DistanceHint own;
    const double d = design.signed_distance(x, own);
    if (std::abs(d) > 1.0) continue;
    ++tested;
    DistanceHint same = own;
    EXPECT_EQ(design.distance_bound(x, same, std::numeric_limits<double>::infinity()), std::abs(d));
    for (std::size_t h = hints.size() > 8 ? hints.size() - 8 : 0; h < hints.size(); ++h) {
      DistanceHint only = hints[h], across_edges = hints[h];
      const double plain = design.distance_bound(x, only, std::numeric_limits<double>::infinity());
      const double near = design.distance_bound(x, across_edges, 0.0);
      ASSERT_GE(plain, std::abs(d)) << x.transpose();
      ASSERT_GE(near, std::abs(d)) << x.transpose();
      ASSERT_LE(near, plain) << x.transpose();
      crossed += near < plain;
      // The hint it hands back names the triangle of that bound.
      DistanceHint again = across_edges;
      EXPECT_EQ(design.distance_bound(x, again, std::numeric_limits<double>::infinity()), near);
    }
    hints.push_back(own);
  }
  EXPECT_EQ(tested, 3000);
  EXPECT_GT(crossed, 100);
}

TEST(DesignDistance, GridSearchMatchesBruteForce) {
  constexpr int kSides = 600;
  constexpr double kRadius = 10.0;
  std::vector<Eigen::Vector2d> polygon;
  std::vector<Eigen::Vector3i> fan;
  for (int i = 0; i < kSides; ++i) {
    const double t = 2.0 * M_PI * i / kSides;
    polygon.emplace_back(kRadius * std::cos(t), kRadius * std::sin(t));
    if (i >= 2) fan.emplace_back(0, i - 1, i);
  }
  const TriangleMesh prism = test::extrude_yz(polygon, fan, 0.0, 40.0);
  // Inside the prism: inside every side's half-plane and between the caps.
  auto inside_prism = [&](const Eigen::Vector3d& x) {
    if (x.x() <= 0.0 || x.x() >= 40.0) return false;
    for (int i = 0; i < kSides; ++i) {
      const Eigen::Vector2d& p = polygon[static_cast<std::size_t>(i)];
      const Eigen::Vector2d& q = polygon[static_cast<std::size_t>((i + 1) % kSides)];
      const Eigen::Vector2d e = q - p, r = Eigen::Vector2d(x.y(), x.z()) - p;
      if (e.x() * r.y() - e.y() * r.x() <= 0.0) return false;
    }
    return true;
  };
  const TriangleMesh block = test::slotted_block(5.0, 2.0);
  auto inside_block = [](const Eigen::Vector3d& x) {
    const bool in_box = x.x() > 0 && x.x() < 60 && x.y() > 0 && x.y() < 40 && x.z() > -20 && x.z() < 0;
    const bool in_slot = std::abs(x.y() - 20.0) < 5.0 && x.z() > -2.0;
    return in_box && !in_slot;
  };
  // Twelve large triangles (a 100 mm cube) and 1,200 tiny ones (300 tetrahedra of 1 um beside
  // it): the median triangle is tiny, so the grid's first cells would list each large
  // triangle thousands of times and it coarsens them; the triangles span the grid's chunks
  // of 1,024 that are listed in parallel.
  TriangleMesh cube = test::box_mesh({0, 0, 0}, {100, 100, 100});
  for (int k = 0; k < 300; ++k) {
    const int base = static_cast<int>(cube.vertices_mm.size());
    const Eigen::Vector3d o(120.0 + k % 15, 40.0 + k / 15, 50.0);
    for (const Eigen::Vector3d& e : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1e-3, 0, 0), Eigen::Vector3d(0, 1e-3, 0),
                                     Eigen::Vector3d(0, 0, 1e-3)})
      cube.vertices_mm.push_back(o + e);
    for (const Eigen::Vector3i& t :
         {Eigen::Vector3i(0, 2, 1), Eigen::Vector3i(0, 1, 3), Eigen::Vector3i(0, 3, 2), Eigen::Vector3i(1, 2, 3)})
      cube.triangles.push_back(t + Eigen::Vector3i::Constant(base));
  }
  auto inside_cube = [](const Eigen::Vector3d& x) { return (x.array() > 0.0).all() && (x.array() < 100.0).all(); };
  struct Case {
    const TriangleMesh* mesh;
    std::function<bool(const Eigen::Vector3d&)> inside;
    Eigen::Vector3d lo, hi;
  };
  const std::vector<Case> cases = {{&prism, inside_prism, {-2, -12, -12}, {42, 12, 12}},
                                   {&block, inside_block, {-2, -2, -22}, {62, 42, 2}},
                                   {&cube, inside_cube, {-5, -5, -5}, {135, 105, 105}}};
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Case& c : cases) {
    const DesignDistance d(*c.mesh);
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 1500; ++i) {
      const Eigen::Vector3d box_point =
          c.lo + (c.hi - c.lo).cwiseProduct(Eigen::Vector3d(unit(random), unit(random), unit(random)));
      points.push_back(box_point);
      // Near the surface: a vertex moved a little.
      const Eigen::Vector3d& v = c.mesh->vertices_mm[random() % c.mesh->vertices_mm.size()];
      points.push_back(v + 0.05 * Eigen::Vector3d(unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5));
    }
    points.emplace_back(500.0, 300.0, -200.0);  // far outside: beyond the grid's search
    DistanceHint carried;                       // hints from the previous, often far, point
    int tested = 0;
    for (const Eigen::Vector3d& x : points) {
      const double expected = brute_distance(*c.mesh, x);
      DistanceHint none;
      for (double got : {d.signed_distance(x), d.signed_distance(x, carried), d.signed_distance(x, none)}) {
        ASSERT_NEAR(std::abs(got), expected, 1e-9) << x.transpose();
        if (expected > 1e-6) {
          ASSERT_EQ(got < 0.0, c.inside(x)) << x.transpose() << " distance " << got;
          ++tested;
        }
      }
    }
    EXPECT_GT(tested, 8000);
  }
}

SurfaceMesh machined_slot(double depth_mm = 2.0, double y_mm = 20.0) {
  Cutter flat;
  flat.diameter_mm = 10;
  flat.flute_length_mm = 25;
  flat.length_mm = 40;
  MoveList list;
  list.cutters.push_back(flat);
  Move plunge, cut;
  plunge.start_mm = {-10, y_mm, 5};
  plunge.end_mm = {-10, y_mm, -depth_mm};
  cut.start_mm = plunge.end_mm;
  cut.end_mm = {70, y_mm, -depth_mm};
  list.moves = {plunge, cut};
  VdbStock stock(BoxShape{{0, 0, -20}, {60, 40, 0}}, kV);
  stock.cut(list, {});
  return stock.surface();
}

// The figures over the vertices of both surfaces (the same whichever side comes first), the
// RMS within rms_slack_mm (its sum's order may differ).
void expect_same_figures(const SurfaceDifference& got, const SurfaceDifference& want, double rms_slack_mm) {
  EXPECT_EQ(got.max_mm, want.max_mm);
  EXPECT_EQ(got.p99_mm, want.p99_mm);
  EXPECT_NEAR(got.rms_mm, want.rms_mm, rms_slack_mm);
  EXPECT_EQ(got.vertices, want.vertices);
  EXPECT_EQ(got.edge_vertices, want.edge_vertices);
  EXPECT_EQ(got.edge_max_mm, want.edge_max_mm);
}

// Two slots 2 and 2.05 mm deep: their floors 0.05 mm apart, walls and top the same. Away
// from the sharp edges (the floor's and the top's, left out) the largest distance is the
// floors' 0.05 mm (within meshing's 1 um on flat faces), the sides' vertices 0: RMS below
// it. A side prepared once (a study's reference) gives the same figures to the bit, both
// ways round, also against a slot 0.5 mm aside (whose sharp edges are not the other's).
TEST(SurfaceDifference, SlotFloorsApartAndThePreparedSide) {
  const SurfaceMesh shallow = machined_slot(2.0), deep = machined_slot(2.05);
  const SurfaceDifference d = surface_difference(shallow, deep, kV, kSharpEdgeDeg);
  EXPECT_NEAR(d.max_mm, 0.05, 0.001);
  EXPECT_NEAR(d.max_where_mm.z(), -2.0, 0.051);
  EXPECT_GT(d.rms_mm, 0.0);
  EXPECT_LT(d.rms_mm, 0.05);
  EXPECT_GT(d.edge_vertices, 0u);
  EXPECT_EQ(d.vertices + d.edge_vertices, shallow.mesh.vertices_mm.size() + deep.mesh.vertices_mm.size());
  const SurfaceMesh aside = machined_slot(2.0, 20.5);
  int pair = 0;
  for (const auto& [a, b] : {std::pair<const SurfaceMesh&, const SurfaceMesh&>{shallow, deep},
                             {deep, shallow},
                             {shallow, aside},
                             {aside, shallow}}) {
    const bool sampled = pair++ % 3 == 0;         // the first and the last
    if (test::sanitized() && !sampled) continue;  // those alone under the sanitizers
    const SurfaceDifference plain = surface_difference(a, b, kV, kSharpEdgeDeg);
    const SurfaceDifference prepared = surface_difference(a, PreparedSurface(b, kSharpEdgeDeg), kV);
    expect_same_figures(prepared, plain, 0.0);
    EXPECT_EQ(prepared.max_where_mm, plain.max_where_mm);
    EXPECT_EQ(prepared.beyond_quarter, plain.beyond_quarter);
    // Both ways round the same vertices are measured against the same triangles, and the
    // same are left out (near a sharp edge of either surface).
    expect_same_figures(surface_difference(b, a, kV, kSharpEdgeDeg), plain, 1e-12);
  }
}

TEST(Compare, DesignEqualToTheCutHasNoGouge) {
  const SurfaceMesh machined = machined_slot();
  const DesignDistance design(test::slotted_block(5.0, 2.0));
  const Comparison c = compare(machined, design, {0.01, 0.01});
  EXPECT_TRUE(c.gouges.empty()) << c.gouges.size() << " regions, deepest " << c.max_gouge_mm;
  EXPECT_TRUE(c.excess.empty()) << c.excess.size() << " regions, thickest " << c.max_excess_mm;
  EXPECT_LT(c.max_gouge_mm, kV / 10);
}

TEST(Compare, DesignIntoTheMaterialIsAGouge) {
  const SurfaceMesh machined = machined_slot();
  const DesignDistance design(test::slotted_block(5.0 - kOffset, 2.0 - kOffset));
  const Comparison c = compare(machined, design, {0.01, 0.1});
  ASSERT_FALSE(c.gouges.empty());
  // Floor and walls lie kOffset inside the design; at the floor-wall corner the design's
  // corner is kOffset away along both: sqrt(2) kOffset, the deepest any vertex can be.
  EXPECT_GE(c.gouges[0].depth_mm, kOffset - kV / 10);
  EXPECT_LE(c.gouges[0].depth_mm, std::sqrt(2.0) * kOffset + kV / 10);
  int floor = 0;
  for (std::size_t i = 0; i < machined.mesh.vertices_mm.size(); ++i) {
    const Eigen::Vector3d& p = machined.mesh.vertices_mm[i];
    if (p.x() < 1 || p.x() > 59 || std::abs(p.y() - 20) > 4 || std::abs(p.z() + 2) > 0.5) continue;
    EXPECT_NEAR(c.deviation_mm[i], -kOffset, kV / 10) << p.transpose();
    ++floor;
  }
  EXPECT_GT(floor, 100);
  EXPECT_EQ(c.gouges[0].moves, std::vector<int>{1});    // the cutting move, nothing else
  EXPECT_NEAR(c.gouges[0].centroid_mm.y(), 20.0, 1.0);  // the slot's floor and walls
  // The deepest point: deeper than the flat faces' kOffset only at the floor-wall corners
  // (z = -2, |y - 20| = 5); else on the floor or a wall.
  const Eigen::Vector3d& deepest = c.gouges[0].deepest_mm;
  if (c.gouges[0].depth_mm > kOffset + kV / 10) {
    EXPECT_NEAR(deepest.z(), -2.0, kV) << deepest.transpose();
    EXPECT_NEAR(std::abs(deepest.y() - 20.0), 5.0, kV) << deepest.transpose();
  } else {
    const bool floor_point = std::abs(deepest.z() + 2.0) <= kV && std::abs(deepest.y() - 20.0) <= 5.0 + kV;
    const bool wall_point = std::abs(std::abs(deepest.y() - 20.0) - 5.0) <= kV && deepest.z() >= -2.0 - kV;
    EXPECT_TRUE(floor_point || wall_point) << deepest.transpose();
  }
  // Floor 60 x 9.9 plus walls 2 x 60 x 1.95: the gouged area, within the edge strips.
  EXPECT_NEAR(c.gouges[0].area_mm2, 60 * 9.9 + 2 * 60 * 1.95, 60 * 4 * kV);
  EXPECT_TRUE(c.excess.empty());
}

TEST(Compare, DesignAwayFromTheMaterialIsExcess) {
  const SurfaceMesh machined = machined_slot();
  const DesignDistance design(test::slotted_block(5.0 + kOffset, 2.0 + kOffset));
  const Comparison c = compare(machined, design, {0.01, 0.02});
  EXPECT_TRUE(c.gouges.empty());
  ASSERT_FALSE(c.excess.empty());
  EXPECT_GE(c.excess[0].depth_mm, kOffset - kV / 10);
  EXPECT_LE(c.excess[0].depth_mm, std::sqrt(2.0) * kOffset + kV / 10);
  int floor = 0;
  for (std::size_t i = 0; i < machined.mesh.vertices_mm.size(); ++i) {
    const Eigen::Vector3d& p = machined.mesh.vertices_mm[i];
    if (p.x() < 1 || p.x() > 59 || std::abs(p.y() - 20) > 4 || std::abs(p.z() + 2) > 0.5) continue;
    EXPECT_NEAR(c.deviation_mm[i], kOffset, kV / 10) << p.transpose();
    ++floor;
  }
  EXPECT_GT(floor, 100);
}

// Regions against a flood fill over a height field: a grid of vertices 1 mm apart, each
// square split along its diagonal, on the top face of a design box, so a vertex's deviation is
// its height. Two bumps above the excess tolerance (one only just), a dip below the gouge
// tolerance, a row of excess vertices edge to edge with a row of gouge vertices, and a row
// along the mesh's open edge (whose edges only one triangle lists, one way): six regions,
// each vertex of them in exactly one, none across the sign change; the areas sum to the
// mesh's.
TEST(Compare, RegionsAreTheConnectedPartsBeyondEachTolerance) {
  constexpr int kSide = 41;
  auto index = [](int i, int j) { return j * kSide + i; };
  SurfaceMesh machined;
  std::vector<int> label(kSide * kSide, 0);  // 0: within the tolerances, else the part's move
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      double z = 0.0;
      int move = 0;
      if ((i - 10) * (i - 10) + (j - 10) * (j - 10) <= 9) z = 0.5, move = 7;
      if ((i - 30) * (i - 30) + (j - 10) * (j - 10) <= 9) z = 0.21, move = 9;
      if ((i - 20) * (i - 20) + (j - 30) * (j - 30) <= 16) z = -0.4, move = 4;
      if (j == 36 && i >= 5 && i <= 7) z = 0.3, move = 11;
      if (j == 36 && i >= 8 && i <= 10) z = -0.3, move = 12;
      if (j == kSide - 1 && i >= 15 && i <= 20) z = 0.6, move = 13;  // along the open edge
      machined.mesh.vertices_mm.emplace_back(i, j, z);
      machined.vertex_move.push_back(move);
      label[static_cast<std::size_t>(index(i, j))] = move;
    }
  for (int j = 0; j + 1 < kSide; ++j)
    for (int i = 0; i + 1 < kSide; ++i) {
      const int a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1), d = index(i, j + 1);
      machined.mesh.triangles.emplace_back(a, b, c);
      machined.mesh.triangles.emplace_back(a, c, d);
    }
  const DesignDistance design(test::box_mesh({-5, -5, -10}, {45, 45, 0}));
  const Comparison c = compare(machined, design, {0.1, 0.2});
  for (std::size_t v = 0; v < machined.mesh.vertices_mm.size(); ++v)
    ASSERT_NEAR(c.deviation_mm[v], machined.mesh.vertices_mm[v].z(), 1e-12) << v;
  // The parts by a flood fill over the grid's edges (the four sides and the diagonal).
  struct Part {
    int vertices = 0, move = 0;
    double depth = 0.0;
  };
  std::vector<Part> excess, gouges;
  std::vector<char> seen(label.size(), 0);
  for (int start = 0; start < kSide * kSide; ++start) {
    if (seen[static_cast<std::size_t>(start)] || label[static_cast<std::size_t>(start)] == 0) continue;
    const int move = label[static_cast<std::size_t>(start)];
    Part part{0, move, 0.0};
    std::vector<int> todo{start};
    seen[static_cast<std::size_t>(start)] = 1;
    while (!todo.empty()) {
      const int v = todo.back();
      todo.pop_back();
      ++part.vertices;
      part.depth = std::max(part.depth, std::abs(machined.mesh.vertices_mm[static_cast<std::size_t>(v)].z()));
      const int i = v % kSide, j = v / kSide;
      for (const auto& [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}}) {
        const int ni = i + di, nj = j + dj;
        if (ni < 0 || nj < 0 || ni >= kSide || nj >= kSide) continue;
        const int u = index(ni, nj);
        if (seen[static_cast<std::size_t>(u)] || label[static_cast<std::size_t>(u)] != move) continue;
        seen[static_cast<std::size_t>(u)] = 1;
        todo.push_back(u);
      }
    }
    (machined.mesh.vertices_mm[static_cast<std::size_t>(start)].z() > 0 ? excess : gouges).push_back(part);
  }
  ASSERT_EQ(excess.size(), 4u);
  ASSERT_EQ(gouges.size(), 2u);
  auto same = [](std::vector<Part> parts, const std::vector<Region>& regions) {
    ASSERT_EQ(parts.size(), regions.size());
    std::stable_sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) { return a.depth > b.depth; });
    for (std::size_t k = 0; k < parts.size(); ++k) {
      EXPECT_EQ(regions[k].vertices, parts[k].vertices) << "region " << k;
      EXPECT_NEAR(regions[k].depth_mm, parts[k].depth, 1e-12) << "region " << k;
      EXPECT_EQ(regions[k].moves, std::vector<int>{parts[k].move}) << "region " << k;
    }
  };
  same(excess, c.excess);
  same(gouges, c.gouges);
  double area = 0.0, vertex_area = 0.0;
  for (const auto& t : machined.mesh.triangles) {
    const auto& x = machined.mesh.vertices_mm;
    area += 0.5 * (x[static_cast<std::size_t>(t[1])] - x[static_cast<std::size_t>(t[0])])
                      .cross(x[static_cast<std::size_t>(t[2])] - x[static_cast<std::size_t>(t[0])])
                      .norm();
  }
  for (double a : c.vertex_area_mm2) vertex_area += a;
  EXPECT_NEAR(vertex_area, area, 1e-9 * area);
}

// The endpoint check read row by row (hinted queries, rows in parallel, points whose hint's
// triangle puts them within both tolerances measured only where they could be the deepest or
// thickest) against a plain loop over the lattice's rays (DexelStock::ray) with unhinted
// queries of every point: the same count, the same largest gouge and excess to the bit, the
// same counts beyond the tolerances and the same deepest point, the first of equally deep
// ones.
EndpointDeviation plain_endpoint_deviation(const DexelStock& stock, const DesignDistance& design,
                                           const CompareSettings& settings, double v) {
  EndpointDeviation plain;
  const int index_lo[3] = {-3, -3, -103}, index_hi[3] = {303, 203, 3};  // the lattice and a margin
  for (int family = 0; family < 3; ++family) {
    const int a1 = family == 0 ? 1 : 0, a2 = family == 2 ? 1 : 2;
    for (int iw = index_lo[a2]; iw < index_hi[a2]; ++iw)
      for (int iu = index_lo[a1]; iu < index_hi[a1]; ++iu)
        for (const DexelSegment& seg : stock.ray(family, iu, iw))
          for (const auto& [along, move] : {std::pair<float, int>{seg.lo_mm, seg.lo_move}, {seg.hi_mm, seg.hi_move}}) {
            Eigen::Vector3d x;
            x[family] = along;
            x[a1] = (iu + 0.5) * v;
            x[a2] = (iw + 0.5) * v;
            const double d = design.signed_distance(x);
            ++plain.points;
            if (-d > plain.max_gouge_mm) {
              plain.max_gouge_mm = -d;
              plain.deepest_mm = x;
              plain.deepest_move = move;
            }
            plain.max_excess_mm = std::max(plain.max_excess_mm, d);
            plain.gouge_points += -d > settings.gouge_tolerance_mm;
            plain.excess_points += d > settings.excess_tolerance_mm;
          }
  }
  return plain;
}

// A flat end mill D10 moves from start to end through the block 60 x 40 x 20 (v = 0.2 mm):
// the endpoint check against `design`, and the plain loop's figures in `plain`.
EndpointDeviation flat_d10_endpoints(const Eigen::Vector3d& start, const Eigen::Vector3d& end,
                                     const TriangleMesh& design_mesh, const CompareSettings& settings,
                                     EndpointDeviation& plain) {
  Cutter flat;
  flat.type = CutterType::Flat;
  flat.diameter_mm = 10;
  flat.flute_length_mm = 20;
  flat.length_mm = 40;
  MoveList list;
  list.cutters = {flat};
  Move move;
  move.start_mm = start;
  move.end_mm = end;
  list.moves = {move};
  const double v = 0.2;
  DexelStock stock(BoxShape{{0, 0, -20}, {60, 40, 0}}, v);
  stock.cut(list, {});
  const DesignDistance design(design_mesh);
  plain = plain_endpoint_deviation(stock, design, settings, v);
  return endpoint_deviation(stock, design, settings);
}

// The D10 cuts a slot along x from (y, z) to (y_end, z_end) (by default the same); the design
// is the block with a slot 10 wide, 2 deep at y = 20.
EndpointDeviation slot_endpoints(double y, double z, const CompareSettings& settings, EndpointDeviation& plain,
                                 double y_end = std::nan(""), double z_end = std::nan("")) {
  return flat_d10_endpoints({-10, y, z}, {70, std::isnan(y_end) ? y : y_end, std::isnan(z_end) ? z : z_end},
                            test::slotted_block(5.0, 2.0), settings, plain);
}

void expect_same(const EndpointDeviation& rows, const EndpointDeviation& plain) {
  EXPECT_GT(plain.points, 100000u);
  EXPECT_EQ(rows.points, plain.points);
  EXPECT_EQ(rows.max_gouge_mm, plain.max_gouge_mm);
  EXPECT_EQ(rows.max_excess_mm, plain.max_excess_mm);
  EXPECT_EQ(rows.gouge_points, plain.gouge_points);
  EXPECT_EQ(rows.excess_points, plain.excess_points);
  EXPECT_EQ(rows.deepest_mm, plain.deepest_mm);
  EXPECT_EQ(rows.deepest_move, plain.deepest_move);
}

// The slot 0.3 mm off the design's centre line and 0.1 mm too deep: deepest along the edge
// where its wall meets its floor, the same at every ray along x.
TEST(EndpointDeviation, RowByRowMatchesThePlainLoop) {
  const CompareSettings settings{0.05, 0.1};
  EndpointDeviation plain;
  const EndpointDeviation rows = slot_endpoints(20.3, -2.1, settings, plain);
  expect_same(rows, plain);
  // The figures themselves: the wall 0.3 mm into the design, the floor 0.1 mm; the deepest
  // point where they meet, at the first ray along x (at 0.1, 0.3, 0.5 mm ...) that lies
  // farther than that from the design's end face x = 0.
  EXPECT_NEAR(rows.max_gouge_mm, std::hypot(0.3, 0.1), 0.02);
  EXPECT_EQ(rows.deepest_move, 0);
  EXPECT_NEAR(rows.deepest_mm.x(), 0.5, 1e-6);
  EXPECT_NEAR(rows.deepest_mm.y(), 25.3, 0.2);
  EXPECT_GT(rows.gouge_points, 1000u);
  EXPECT_GT(rows.excess_points, 1000u);
}

// Within both tolerances everywhere: the slot where the design has it (every point within
// rounding of the design, thousands equally far), and 0.02 mm too deep and 0.01 mm to the
// side (the floor's points all 0.02 mm deep, the wall's 0.01 mm: the deepest is the first of
// hundreds of equal ones, found among the points set aside). Nothing counts beyond a
// tolerance; the figures and the deepest point are the plain loop's.
TEST(EndpointDeviation, WithinTheTolerancesMatchesThePlainLoop) {
  const CompareSettings settings{0.05, 0.1};
  for (const auto& [y, z] : {std::pair{20.0, -2.0}, {20.01, -2.02}, {19.987, -1.996}}) {
    SCOPED_TRACE(testing::Message() << "slot at y " << y << ", z " << z);
    EndpointDeviation plain;
    const EndpointDeviation rows = slot_endpoints(y, z, settings, plain);
    expect_same(rows, plain);
    EXPECT_EQ(rows.gouge_points, 0u);
    EXPECT_EQ(rows.excess_points, 0u);
    EXPECT_LE(rows.max_gouge_mm, 0.021);
  }
}

// 24 slots a little askew and sloping, both ways, within the tolerances and past them: the
// deepest and thickest points lie anywhere along the rows, set aside or not.
TEST(EndpointDeviation, AskewSlotsMatchThePlainLoop) {
  std::mt19937 random(24);
  std::uniform_real_distribution<double> off(-0.04, 0.04);
  for (int k = 0; k < 24; ++k) {
    const double y = 20 + off(random), z = -2 + off(random), y_end = 20 + off(random), z_end = -2 + off(random);
    const CompareSettings settings{k % 2 ? 0.05 : 0.02, k % 2 ? 0.1 : 0.03};
    if (test::sanitized() && k % 3 != 0) continue;  // a third of them (both settings) under the sanitizers
    SCOPED_TRACE(testing::Message() << "slot from y " << y << ", z " << z << " to y " << y_end << ", z " << z_end);
    EndpointDeviation plain;
    expect_same(slot_endpoints(y, z, settings, plain, y_end, z_end), plain);
  }
}

// The block 60 x 40 x 20 whose top face comes first, in two parts: x 0..40 as two triangles
// (their diagonal from (0, 0) to (40, 40)), x 40..60 as strips 0.01 mm wide, none sharing a
// vertex with another part; then the whole box (its top triangles, as near, numbered later).
TriangleMesh block_with_a_striped_top() {
  TriangleMesh m;
  auto quad = [&](double x0, double x1) {
    const int n = static_cast<int>(m.vertices_mm.size());
    m.vertices_mm.insert(m.vertices_mm.end(), {{x0, 0, 0}, {x1, 0, 0}, {x1, 40, 0}, {x0, 40, 0}});
    m.triangles.emplace_back(n, n + 1, n + 2);
    m.triangles.emplace_back(n, n + 2, n + 3);
  };
  quad(0.0, 40.0);
  for (int i = 0; i < 2000; ++i) quad(40.0 + 0.01 * i, 40.0 + 0.01 * (i + 1));
  const TriangleMesh box = test::box_mesh({0, 0, -20}, {60, 40, 0});
  const int n = static_cast<int>(m.vertices_mm.size());
  m.vertices_mm.insert(m.vertices_mm.end(), box.vertices_mm.begin(), box.vertices_mm.end());
  for (const Eigen::Vector3i& t : box.triangles) m.triangles.emplace_back(t[0] + n, t[1] + n, t[2] + n);
  return m;
}

// Equally deep points measured in both passes: a flat end mill D10 takes 0.02 mm off the top
// from x = 34 on, around y = 10 (within the tolerances). Along the first row with such points
// (y = 5.1) those up to x = 40 lie on their hint's triangle and are set aside; the first past
// x = 40 lies on a strip 0.1 mm from that triangle and every triangle beside it, and is
// measured at once, equally deep: the deepest point is still the row's first, found among
// those set aside.
TEST(EndpointDeviation, TheFirstOfEquallyDeepPointsAcrossThePasses) {
  EndpointDeviation plain;
  const EndpointDeviation rows =
      flat_d10_endpoints({35, 10, -0.02}, {70, 10, -0.02}, block_with_a_striped_top(), {0.05, 0.1}, plain);
  expect_same(rows, plain);
  EXPECT_NEAR(plain.max_gouge_mm, 0.02, 1e-6);
  EXPECT_NEAR(plain.deepest_mm.y(), 5.1, 1e-9);
  EXPECT_LT(plain.deepest_mm.x(), 35.0);
}

}  // namespace
}  // namespace vcut::removal
