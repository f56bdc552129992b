// Densification of three-axis blocks. Expected values are worked by hand from the arc
// geometry (sagitta r(1 - cos(a/2)), right-hand rule about the arc normal).
#include "vcut/kinematics/densify.h"

#include <gtest/gtest.h>

#include <cmath>

namespace vcut::kinematics {
namespace {

constexpr double kExact = 1e-12;  // double round-off on mm-sized values

Block arc(Eigen::Vector3d start, Eigen::Vector3d end, Eigen::Vector3d center, Eigen::Vector3d normal, int turns = 1) {
  Block b;
  b.kind = MotionKind::Arc;
  b.start_mm = start;
  b.end_mm = end;
  b.center_mm = center;
  b.normal = normal;
  b.turns = turns;
  return b;
}

TEST(ArcChordCount, QuarterCircleRadius10Tolerance001) {
  // Max chord angle 2 acos(1 - 0.001) = 0.0894462 rad; (pi/2) / 0.0894462 = 17.56 -> 18.
  EXPECT_EQ(arc_chord_count(10.0, M_PI / 2, 0.01), 18);
  // A tolerance larger than the radius still gives at least one chord per quarter turn.
  EXPECT_EQ(arc_chord_count(0.001, 2 * M_PI, 0.01), 4);
}

TEST(ArcAngle, ClockwiseAndCounterClockwiseQuarter) {
  // G2 in G17 (normal -Z) from +X to -Y turns a quarter; G3 (normal +Z) three quarters.
  EXPECT_NEAR(arc_angle_rad(arc({10, 0, 0}, {0, -10, 0}, {0, 0, 0}, -Eigen::Vector3d::UnitZ())), M_PI / 2, kExact);
  EXPECT_NEAR(arc_angle_rad(arc({10, 0, 0}, {0, -10, 0}, {0, 0, 0}, Eigen::Vector3d::UnitZ())), 3 * M_PI / 2, kExact);
}

TEST(ArcAngle, FullCircleAndExtraTurns) {
  EXPECT_NEAR(arc_angle_rad(arc({10, 0, 0}, {10, 0, 0}, {0, 0, 0}, Eigen::Vector3d::UnitZ())), 2 * M_PI, kExact);
  EXPECT_NEAR(arc_angle_rad(arc({10, 0, 0}, {10, 0, 0}, {0, 0, 0}, Eigen::Vector3d::UnitZ(), 2)), 4 * M_PI, kExact);
}

TEST(ArcPoint, HelixHalfway) {
  // A full helical turn rising 5 mm: half way it is opposite the start, 2.5 mm up.
  const Block b = arc({10, 0, 0}, {10, 0, 5}, {0, 0, 0}, Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d p = arc_point(b, 0.5);
  EXPECT_NEAR(p.x(), -10.0, 1e-9);
  EXPECT_NEAR(p.y(), 0.0, 1e-9);
  EXPECT_NEAR(p.z(), 2.5, 1e-9);
  // A quarter of a G3 turn in G17 from +X goes to +Y.
  const Eigen::Vector3d q = arc_point(arc({10, 0, 0}, {10, 0, 0}, {0, 0, 0}, Eigen::Vector3d::UnitZ()), 0.25);
  EXPECT_NEAR(q.y(), 10.0, 1e-9);
}

TEST(ArcPoint, XZPlaneArc) {
  // Normal +Y: right-hand rotation takes +Z toward +X.
  const Block b = arc({0, 0, 10}, {10, 0, 0}, {0, 0, 0}, Eigen::Vector3d::UnitY());
  EXPECT_NEAR(arc_angle_rad(b), M_PI / 2, kExact);
  const Eigen::Vector3d mid = arc_point(b, 0.5);
  EXPECT_NEAR(mid.x(), 10.0 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(mid.z(), 10.0 / std::sqrt(2.0), 1e-9);
}

TEST(Densify, ArcChordsStayWithinTolerance) {
  Program p;
  p.files = {"t.ngc"};
  p.blocks.push_back(arc({10, 0, 0}, {10, 0, 0}, {0, 0, 0}, -Eigen::Vector3d::UnitZ()));
  DensifySettings s;
  s.chord_tolerance_mm = 0.01;
  const auto samples = densify(p, s);
  ASSERT_GE(samples.size(), 3u);
  double worst = 0.0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    EXPECT_NEAR(samples[i].pose.tip_mm.norm(), 10.0, 1e-9);  // on the circle
    EXPECT_EQ(samples[i].block, 0);
    const Eigen::Vector3d mid = 0.5 * (samples[i].pose.tip_mm + samples[i - 1].pose.tip_mm);
    worst = std::max(worst, 10.0 - mid.norm());  // sagitta of this chord
  }
  EXPECT_LE(worst, 0.01 + 1e-12);
  EXPECT_GT(worst, 0.005);  // not needlessly fine: chords are as long as the tolerance allows
  EXPECT_EQ(samples.front().block, -1);
  // Clockwise: the first chord goes from +X toward -Y.
  EXPECT_LT(samples[1].pose.tip_mm.y(), 0.0);
}

TEST(Densify, LinesSplitByStep) {
  Program p;
  p.files = {"t.ngc"};
  Block b;
  b.kind = MotionKind::Linear;
  b.start_mm = {0, 0, 0};
  b.end_mm = {10, 0, 0};
  p.blocks.push_back(b);
  DensifySettings s;
  s.step_mm = 3.0;  // ceil(10 / 3) = 4 equal steps of 2.5 mm
  const auto samples = densify(p, s);
  ASSERT_EQ(samples.size(), 5u);
  for (int i = 0; i <= 4; ++i) EXPECT_NEAR(samples[static_cast<std::size_t>(i)].pose.tip_mm.x(), 2.5 * i, kExact);
}

}  // namespace
}  // namespace vcut::kinematics
