// Deviation from the design against designs built by hand from the analytic cut
// (issue 2: equal design -> no gouge; offset 0.05 mm either way -> gouge or excess of
// 0.05 +- v/10 at the right place, naming the cutting move).
#include "vcut/removal/compare.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_meshes.h"
#include "vcut/removal/vdb_stock.h"

namespace vcut::removal {
namespace {

constexpr double kV = 0.1;
constexpr double kOffset = 0.05;

TEST(DesignDistance, BoxSignsAndDistances) {
  const DesignDistance d(test::box_mesh({0, 0, 0}, {10, 10, 10}));
  EXPECT_TRUE(d.closed());
  EXPECT_NEAR(d.signed_distance({5, 5, 12}), 2.0, 1e-12);          // above a face
  EXPECT_NEAR(d.signed_distance({5, 5, 9}), -1.0, 1e-12);          // inside
  EXPECT_NEAR(d.signed_distance({13, 14, 5}), 5.0, 1e-12);         // beside an edge: 3-4-5
  EXPECT_NEAR(d.signed_distance({-1, -2, -2}), 3.0, 1e-12);        // beyond a corner
  EXPECT_NEAR(d.signed_distance({0.5, 0.5, 0.5}), -0.5, 1e-12);    // inside near a corner
}

SurfaceMesh machined_slot() {
  Cutter flat;
  flat.diameter_mm = 10;
  flat.flute_length_mm = 25;
  flat.length_mm = 40;
  MoveList list;
  list.cutters.push_back(flat);
  Move plunge, cut;
  plunge.start_mm = {-10, 20, 5};
  plunge.end_mm = {-10, 20, -2};
  cut.start_mm = plunge.end_mm;
  cut.end_mm = {70, 20, -2};
  list.moves = {plunge, cut};
  VdbStock stock(BoxShape{{0, 0, -20}, {60, 40, 0}}, kV);
  stock.cut(list, {});
  return stock.surface();
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
  EXPECT_EQ(c.gouges[0].moves, std::vector<int>{1});  // the cutting move, nothing else
  EXPECT_NEAR(c.gouges[0].centroid_mm.y(), 20.0, 1.0);  // the slot's floor and walls
  EXPECT_NEAR(c.gouges[0].deepest_mm.z(), -2.0, 2.0 + kV);
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

}  // namespace
}  // namespace vcut::removal
