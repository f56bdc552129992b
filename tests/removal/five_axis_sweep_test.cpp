// Five-axis moves (issue #5 item 6): a tilting cutter's swept volume cut as translation
// pieces, against a brute-force minimum over 10^4 cutter instances of the rigid motion (tip
// straight, axis on the great circle, written out here with its own Rodrigues rotation).
// The difference must stay within the stated bound plus the brute force's own sampling error.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

#include "vcut/removal/move.h"
#include "vcut/removal/sweep.h"

namespace vcut::removal {
namespace {

Cutter make(CutterType type, double d, double r, double flute) {
  Cutter c;
  c.type = type;
  c.diameter_mm = d;
  c.corner_radius_mm = r;
  c.flute_length_mm = flute;
  c.length_mm = flute;
  c.tip_angle_deg = type == CutterType::VBit ? 90.0 : 0.0;
  return c;
}

// The rigid motion's instance at t: tip p0 + t (p1 - p0); the tool frame turned from a0 by
// the fraction t of the angle between a0 and a1 about their common normal.
struct RigidMotion {
  Eigen::Vector3d p0, p1, a0, a1;

  double instance_distance(const Cutter& c, const Eigen::Vector3d& x, double t) const {
    const Eigen::Vector3d n = a0.cross(a1);
    const double angle = std::atan2(n.norm(), a0.dot(a1));
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(t * angle, n.normalized()).toRotationMatrix();
    const Eigen::Matrix3d start = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), a0).toRotationMatrix();
    const Eigen::Matrix3d tool_to_work = turn * start;  // tool +Z -> the axis at t
    const Eigen::Vector3d tip = p0 + t * (p1 - p0);
    return cutter_distance(c, tool_to_work.transpose() * (x - tip));
  }
};

TEST(FiveAxisSweep, TiltingCuttersWithinTheStatedBound) {
  constexpr int kInstances = 10000;
  const double tilt = 30.0 * M_PI / 180.0;
  std::mt19937 rng(17);
  for (const Cutter& c : {make(CutterType::Flat, 10, 0, 20), make(CutterType::Ball, 6, 3, 15),
                          make(CutterType::BullNose, 8, 1, 12), make(CutterType::VBit, 6, 0, 5)}) {
    const RigidMotion motion{{0, 0, 0}, {2.0, 1.0, -0.5}, {0, 0, 1}, {std::sin(tilt), 0, std::cos(tilt)}};
    Move base;
    base.start_mm = motion.p0;
    base.end_mm = motion.p1;
    for (double bound : {0.05, 0.01}) {
      const int n = five_axis_pieces(c, motion.a0, motion.a1, bound);
      EXPECT_LE(rotation_error_mm(c, tilt, n), bound);
      EXPECT_GT(rotation_error_mm(c, tilt, n - 1), bound) << "not the fewest pieces";
      std::vector<Move> pieces;
      append_five_axis_move(pieces, base, motion.a0, motion.a1, n);
      ASSERT_EQ(static_cast<int>(pieces.size()), n);
      EXPECT_EQ(pieces.back().end_mm, motion.p1);
      std::vector<TranslationSweep> sweeps;
      for (const Move& m : pieces) sweeps.emplace_back(c, m);
      // Brute force: d_true <= d_brute <= d_true + V / (2 N), V the fastest cutter point's path.
      const double reach = std::hypot(c.radius_mm(), c.flute_length_mm);
      const double brute_error = ((motion.p1 - motion.p0).norm() + tilt * reach) / (2.0 * kInstances);
      std::uniform_real_distribution<double> x(-8, 10), y(-7, 8), z(-3, 20);
      int near_surface = 0;
      double worst = 0.0;
      while (near_surface < 150) {
        const Eigen::Vector3d p(x(rng), y(rng), z(rng));
        double pieces_d = 1e300;
        for (const TranslationSweep& s : sweeps) pieces_d = std::min(pieces_d, s.distance(p));
        if (std::abs(pieces_d) > 1.0) continue;  // near the swept surface only
        ++near_surface;
        double brute = 1e300;
        for (int i = 0; i <= kInstances; ++i)
          brute = std::min(brute, motion.instance_distance(c, p, static_cast<double>(i) / kInstances));
        worst = std::max(worst, std::abs(pieces_d - brute));
        EXPECT_LE(std::abs(pieces_d - brute), bound + brute_error + 1e-6)
            << to_string(c.type) << " bound " << bound << " at " << p.transpose();
      }
      // The bound is not vacuous: the error is a sizeable part of it for coarse bounds.
      if (bound == 0.05 && c.type == CutterType::Flat) {
        EXPECT_GT(worst, 0.1 * bound);
      }
    }
  }
}

}  // namespace
}  // namespace vcut::removal
