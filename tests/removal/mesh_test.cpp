// Decimation for the report page (removal::decimate, vertex clustering): a finely
// triangulated sphere and box reduced to a budget keep only original vertices (their
// attributes carry over through `kept`), still wind once around their inside, keep the
// sphere's volume and the box's exactly; the expectations are closed forms, not the
// decimater's output.
#include <gtest/gtest.h>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <array>
#include <cmath>
#include <map>

#include "test_meshes.h"
#include "vcut/removal/mesh.h"

namespace vcut::removal {
namespace {

// A UV sphere of radius r: `rings` bands of `segments` quads (triangles at the poles),
// outward facing.
TriangleMesh uv_sphere(double r_mm, int rings, int segments) {
  TriangleMesh m;
  m.vertices_mm.push_back({0, 0, r_mm});
  for (int i = 1; i < rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2.0 * M_PI * j / segments;
      m.vertices_mm.push_back(
          {r_mm * std::sin(theta) * std::cos(phi), r_mm * std::sin(theta) * std::sin(phi), r_mm * std::cos(theta)});
    }
  }
  m.vertices_mm.push_back({0, 0, -r_mm});
  const int south = static_cast<int>(m.vertices_mm.size()) - 1;
  auto at = [&](int ring, int j) { return 1 + (ring - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, at(1, j), at(1, j + 1)});
  for (int i = 1; i < rings - 1; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  for (int j = 0; j < segments; ++j) m.triangles.push_back({south, at(rings - 1, j + 1), at(rings - 1, j)});
  return m;
}

// A box [lo, hi] with each face a k x k grid of quads (two triangles each), shared vertices,
// outward facing.
TriangleMesh tessellated_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int k) {
  TriangleMesh m;
  std::map<std::array<int, 3>, int> index;
  auto vertex = [&](std::array<int, 3> g) {
    const auto [it, inserted] = index.emplace(g, static_cast<int>(m.vertices_mm.size()));
    if (inserted)
      m.vertices_mm.push_back({lo.x() + (hi.x() - lo.x()) * g[0] / k, lo.y() + (hi.y() - lo.y()) * g[1] / k,
                               lo.z() + (hi.z() - lo.z()) * g[2] / k});
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // (u, v, axis) right-handed
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
          auto at = [&](int a, int b) {
            std::array<int, 3> g{};
            g[static_cast<std::size_t>(axis)] = side * k;
            g[static_cast<std::size_t>(u)] = a;
            g[static_cast<std::size_t>(v)] = b;
            return vertex(g);
          };
          const int p00 = at(i, j), p10 = at(i + 1, j), p11 = at(i + 1, j + 1), p01 = at(i, j + 1);
          if (side == 1) {  // normal +axis = u x v
            m.triangles.push_back({p00, p10, p11});
            m.triangles.push_back({p00, p11, p01});
          } else {
            m.triangles.push_back({p00, p11, p10});
            m.triangles.push_back({p00, p01, p11});
          }
        }
    }
  return m;
}

// The solid angle a triangle subtends at the origin, signed by its orientation (Van Oosterom
// and Strackee): the triangles of a closed surface sum to 4 pi times their winding about it.
double solid_angle(const TriangleMesh& m, const Eigen::Vector3i& t) {
  const Eigen::Vector3d a = m.vertices_mm[static_cast<std::size_t>(t[0])],
                        b = m.vertices_mm[static_cast<std::size_t>(t[1])],
                        c = m.vertices_mm[static_cast<std::size_t>(t[2])];
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  return 2.0 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la);
}

double winding_about_origin(const TriangleMesh& m) {
  double sum = 0.0;
  for (const auto& t : m.triangles) sum += solid_angle(m, t);
  return sum / (4.0 * M_PI);
}

// Every vertex of the result is an original one, once, and `kept` says which.
void expect_original_vertices(const TriangleMesh& small, const std::vector<int>& kept, const TriangleMesh& mesh) {
  ASSERT_EQ(kept.size(), small.vertices_mm.size());
  std::vector<int> seen(mesh.vertices_mm.size(), 0);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    ASSERT_GE(kept[i], 0);
    ASSERT_LT(static_cast<std::size_t>(kept[i]), mesh.vertices_mm.size());
    EXPECT_EQ(small.vertices_mm[i], mesh.vertices_mm[static_cast<std::size_t>(kept[i])]) << i;
    EXPECT_EQ(++seen[static_cast<std::size_t>(kept[i])], 1) << "vertex " << kept[i] << " twice";
  }
}

TEST(Decimate, SphereToABudgetKeepsOriginalVerticesWindingAndVolume) {
  const double r = 10.0;
  const TriangleMesh sphere = uv_sphere(r, 100, 200);  // 2 * 200 * 99 = 39,600 triangles
  ASSERT_EQ(sphere.triangles.size(), 39600u);
  ASSERT_TRUE(is_closed(sphere));
  ASSERT_NEAR(winding_about_origin(sphere), 1.0, 1e-9);
  std::vector<int> kept;
  TriangleMesh one_thread;
  {
    tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
    one_thread = decimate(sphere, 4000, kept);
  }
  EXPECT_LE(one_thread.triangles.size(), 4000u);
  EXPECT_GT(one_thread.triangles.size(), 2000u);  // the budget used, not wasted
  expect_original_vertices(one_thread, kept, sphere);
  // A hole or a triangle turned over would change the winding: it is still once about the centre.
  EXPECT_NEAR(winding_about_origin(one_thread), 1.0, 1e-9);
  // 2,000-4,000 triangles on a 10 mm sphere: an edge of about 1.5 mm, a facet's sagitta under
  // 0.05 mm, so the volume falls short of 4/3 pi r^3 by well under 2 %.
  const double sphere_mm3 = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(signed_volume_mm3(one_thread), sphere_mm3, 0.02 * sphere_mm3);
  EXPECT_LE(signed_volume_mm3(one_thread), sphere_mm3);  // every vertex on the sphere
  // The same triangles for 1 and 2 threads.
  std::vector<int> kept2;
  const TriangleMesh two_threads = decimate(sphere, 4000, kept2);
  EXPECT_EQ(two_threads.triangles, one_thread.triangles);
  EXPECT_EQ(kept2, kept);
}

// A box's corners and edges stay where they are: each group of vertices keeps the one nearest
// its triangles' planes, a corner where three faces meet, an edge vertex where two do. Then
// every triangle left lies in a face of the box and the volume is the box's to rounding.
TEST(Decimate, BoxKeepsItsCornersEdgesAndVolume) {
  const Eigen::Vector3d lo(-3, 1, 2), hi(17, 11, 7);     // 20 x 10 x 5 mm
  const TriangleMesh box = tessellated_box(lo, hi, 40);  // 6 * 40 * 40 * 2 = 19,200 triangles
  ASSERT_EQ(box.triangles.size(), 19200u);
  ASSERT_TRUE(is_closed(box));
  const double box_mm3 = 20.0 * 10.0 * 5.0;
  ASSERT_NEAR(signed_volume_mm3(box), box_mm3, 1e-9);
  std::vector<int> kept;
  const TriangleMesh small = decimate(box, 1500, kept);
  EXPECT_LE(small.triangles.size(), 1500u);
  EXPECT_GT(small.triangles.size(), 750u);
  expect_original_vertices(small, kept, box);
  int corners = 0;
  for (const auto& p : small.vertices_mm)
    corners += ((p - lo).cwiseAbs().array() < 1e-12 || (p - hi).cwiseAbs().array() < 1e-12).all() ? 1 : 0;
  EXPECT_EQ(corners, 8);
  EXPECT_NEAR(signed_volume_mm3(small), box_mm3, 1e-9);
}

// A plate thinner than the clustering's cell (0.2 mm against about 1.3 mm): its top and bottom
// vertices share cells, and only their facing (+z, -z, the rims mixed) keeps them in separate
// clusters; merged, each top triangle's triple would cancel its bottom twin's and the plate
// would vanish. Its faces stay; the rims (top and bottom edges both mixed) may fold within a
// cell of the edge: at most the 80 mm perimeter x about 1.3 mm x 0.2 mm, 21 mm3 of 80. Every
// vertex kept lies on the plate, so no more than the plate. The same for one thread and an
// arena of seven (each vertex's facing gathered from its triangles in any order).
TEST(Decimate, PlateThinnerThanACellKeepsBothFaces) {
  const Eigen::Vector3d lo(0, 0, 0), hi(20, 20, 0.2);
  const TriangleMesh plate = tessellated_box(lo, hi, 40);
  ASSERT_TRUE(is_closed(plate));
  const double plate_mm3 = 20.0 * 20.0 * 0.2;
  ASSERT_NEAR(signed_volume_mm3(plate), plate_mm3, 1e-9);
  auto run = [&](int threads, std::vector<int>& kept) {
    TriangleMesh small;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
      small = decimate(plate, 1500, kept);
    });
    return small;
  };
  std::vector<int> kept1, kept7;
  const TriangleMesh one = run(1, kept1), seven = run(7, kept7);
  EXPECT_LE(one.triangles.size(), 1500u);
  EXPECT_GT(one.triangles.size(), 200u);
  expect_original_vertices(one, kept1, plate);
  EXPECT_GT(signed_volume_mm3(one), plate_mm3 - 80.0 * 1.3 * 0.2);
  EXPECT_LE(signed_volume_mm3(one), plate_mm3 + 1e-9);
  EXPECT_EQ(seven.triangles, one.triangles);
  EXPECT_EQ(kept7, kept1);
}

// A closed mesh has every directed edge once and its reverse once (derived by hand on a box's
// twelve triangles: each of its 18 edges is shared by two triangles, one in each direction).
// A regular octahedron: each corner meets four equal faces symmetric about its axis, so its
// area-weighted normal is the corner's own direction. A fin of three triangles on one edge
// (a complex edge, as thin walls give): normals (0, 0, 1), (0, -1, 0) and (0, 0, -1) by the
// right-hand rule, so the edge's ends sum to (0, -1, 0); each free corner keeps its own
// triangle's normal. A vertex no triangle uses: zero.
TEST(VertexNormals, AreaWeightedAtEveryCornerAndOnComplexEdges) {
  TriangleMesh octahedron;
  octahedron.vertices_mm = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int x : {0, 1})
    for (int y : {2, 3})
      for (int z : {4, 5}) {
        // Counter-clockwise seen from outside: (x, y, z) in the octant's positive orientation.
        const bool positive = (x == 0) == (y == 2) ? z == 4 : z == 5;
        octahedron.triangles.push_back(positive ? Eigen::Vector3i(x, y, z) : Eigen::Vector3i(x, z, y));
      }
  const std::vector<Eigen::Vector3d> n = vertex_normals(octahedron);
  ASSERT_EQ(n.size(), 6u);
  for (std::size_t v = 0; v < 6; ++v) EXPECT_LT((n[v] - octahedron.vertices_mm[v]).norm(), 1e-12) << v;

  TriangleMesh fin;
  fin.vertices_mm = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}, {5, 5, 5}};
  fin.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}};
  const std::vector<Eigen::Vector3d> f = vertex_normals(fin);
  ASSERT_EQ(f.size(), 6u);
  EXPECT_LT((f[0] - Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
  EXPECT_LT((f[1] - Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
  EXPECT_LT((f[2] - Eigen::Vector3d(0, 0, 1)).norm(), 1e-12);
  EXPECT_LT((f[3] - Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
  EXPECT_LT((f[4] - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_EQ(f[5], Eigen::Vector3d::Zero());
}

TEST(IsClosed, BoxesAndTheWaysToOpenThem) {
  const TriangleMesh box = test::box_mesh({0, 0, 0}, {1, 2, 3});
  ASSERT_EQ(box.triangles.size(), 12u);
  EXPECT_TRUE(is_closed(box));
  TriangleMesh two = box;  // two disjoint boxes: still closed
  const TriangleMesh other = test::box_mesh({5, 0, 0}, {6, 1, 1});
  const int offset = static_cast<int>(two.vertices_mm.size());
  two.vertices_mm.insert(two.vertices_mm.end(), other.vertices_mm.begin(), other.vertices_mm.end());
  for (const Eigen::Vector3i& t : other.triangles) two.triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  EXPECT_TRUE(is_closed(two));
  TriangleMesh missing = box;  // a hole
  missing.triangles.pop_back();
  EXPECT_FALSE(is_closed(missing));
  TriangleMesh flipped = box;  // one triangle turned over: its edges run the way their neighbours' do
  std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
  EXPECT_FALSE(is_closed(flipped));
  TriangleMesh doubled = box;  // a triangle twice
  doubled.triangles.push_back(box.triangles[0]);
  EXPECT_FALSE(is_closed(doubled));
  TriangleMesh pair = box;  // a triangle and its reverse added: every edge has its reverse, but some twice
  pair.triangles.push_back(box.triangles[0]);
  pair.triangles.push_back({box.triangles[0][0], box.triangles[0][2], box.triangles[0][1]});
  EXPECT_FALSE(is_closed(pair));
}

TEST(Decimate, SmallMeshComesBackAsItIs) {
  const TriangleMesh box = test::box_mesh({0, 0, 0}, {1, 2, 3});
  std::vector<int> kept;
  const TriangleMesh same = decimate(box, 100, kept);
  EXPECT_EQ(same.triangles, box.triangles);
  EXPECT_EQ(same.vertices_mm, box.vertices_mm);
  ASSERT_EQ(kept.size(), box.vertices_mm.size());
  for (std::size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(kept[i], static_cast<int>(i));
}

}  // namespace
}  // namespace vcut::removal
