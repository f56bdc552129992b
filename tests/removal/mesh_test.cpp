// Decimation for the report page (removal::decimate): a finely triangulated sphere reduced
// to a budget keeps only original vertices (their attributes carry over through `kept`),
// stays closed, and keeps the sphere's volume; the expectations are the sphere's closed
// forms, not the decimater's output.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>

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

TEST(Decimate, SphereToABudgetKeepsOriginalVerticesClosureAndVolume) {
  const double r = 10.0;
  const TriangleMesh sphere = uv_sphere(r, 60, 120);  // 2 * 120 * 59 = 14,160 triangles
  ASSERT_EQ(sphere.triangles.size(), 14160u);
  ASSERT_TRUE(is_closed(sphere));
  ASSERT_GT(signed_volume_mm3(sphere), 0.0);
  std::vector<int> kept;
  const TriangleMesh small = decimate(sphere, 2000, kept);
  EXPECT_LE(small.triangles.size(), 2000u);
  EXPECT_GT(small.triangles.size(), 1000u);
  ASSERT_EQ(kept.size(), small.vertices_mm.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    ASSERT_GE(kept[i], 0);
    ASSERT_LT(static_cast<std::size_t>(kept[i]), sphere.vertices_mm.size());
    EXPECT_EQ(small.vertices_mm[i], sphere.vertices_mm[static_cast<std::size_t>(kept[i])]) << i;
  }
  EXPECT_TRUE(is_closed(small));
  // 2,000 triangles on a 10 mm sphere: an edge of about 1.6 mm, a facet's sagitta under
  // 0.05 mm, so the volume falls short of 4/3 pi r^3 by well under 2 %.
  const double sphere_mm3 = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(signed_volume_mm3(small), sphere_mm3, 0.02 * sphere_mm3);
  EXPECT_LE(signed_volume_mm3(small), sphere_mm3);  // inscribed: every vertex on the sphere
}

// A closed mesh has every directed edge once and its reverse once (derived by hand on a box's
// twelve triangles: each of its 18 edges is shared by two triangles, one in each direction).
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

// In slabs (as the page's large meshes are decimated, in parallel): the same guarantees, the
// slabs meeting along the vertices they share, and the same triangles for 1 and 2 threads.
TEST(Decimate, InSlabsTheSlabsStillMeetForAnyThreadCount) {
  const double r = 10.0;
  const TriangleMesh sphere = uv_sphere(r, 60, 120);  // 14,160 triangles
  std::vector<int> kept;
  TriangleMesh one_thread;
  {
    tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
    one_thread = decimate(sphere, 4000, kept, 4);
  }
  std::vector<int> kept2;
  const TriangleMesh two_threads = decimate(sphere, 4000, kept2, 4);
  EXPECT_EQ(two_threads.triangles, one_thread.triangles);
  EXPECT_EQ(kept2, kept);
  EXPECT_LE(one_thread.triangles.size(), 4000u);
  EXPECT_GT(one_thread.triangles.size(), 2000u);
  ASSERT_EQ(kept.size(), one_thread.vertices_mm.size());
  std::vector<int> seen(sphere.vertices_mm.size(), 0);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    ASSERT_GE(kept[i], 0);
    ASSERT_LT(static_cast<std::size_t>(kept[i]), sphere.vertices_mm.size());
    EXPECT_EQ(one_thread.vertices_mm[i], sphere.vertices_mm[static_cast<std::size_t>(kept[i])]) << i;
    EXPECT_EQ(++seen[static_cast<std::size_t>(kept[i])], 1) << "vertex " << kept[i] << " twice";
  }
  EXPECT_TRUE(is_closed(one_thread));  // the slabs meet: no crack along their borders
  const double sphere_mm3 = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(signed_volume_mm3(one_thread), sphere_mm3, 0.01 * sphere_mm3);
  EXPECT_LE(signed_volume_mm3(one_thread), sphere_mm3);
  // One slab per 200,000 triangles of the mesh and of the budget, at most 16.
  EXPECT_EQ(decimation_slabs(3'300'000, 2'000'000), 10u);
  EXPECT_EQ(decimation_slabs(14'160, 4000), 1u);
  EXPECT_EQ(decimation_slabs(50'000'000, 40'000'000), 16u);
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
