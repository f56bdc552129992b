// Swept-volume distances against independent references: the closed-form capsule
// (ball end mill), a profile written out by hand (flat, bull-nose), and a brute-force
// minimum over 10^5 cutter instances along the move (ramps).
#include "vcut/removal/sweep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "sanitized.h"

namespace vcut::removal {
namespace {

constexpr double kClosedForm_mm = 1e-9;  // double round-off on mm-sized distances

Cutter cutter(CutterType type, double d, double r, double flute) {
  Cutter c;
  c.type = type;
  c.diameter_mm = d;
  c.corner_radius_mm = r;
  c.flute_length_mm = flute;
  c.length_mm = flute;
  return c;
}

Move move(Eigen::Vector3d a, Eigen::Vector3d b) {
  Move m;
  m.start_mm = a;
  m.end_mm = b;
  return m;
}

double segment_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double t = std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (x - a - t * d).norm();
}

TEST(CutterDistance, FlatBallBullProfiles) {
  const Cutter flat = cutter(CutterType::Flat, 10, 0, 20);
  EXPECT_NEAR(cutter_distance(flat, {0, 0, -1}), 1.0, kClosedForm_mm);  // below the tip face
  EXPECT_NEAR(cutter_distance(flat, {7, 0, 5}), 2.0, kClosedForm_mm);   // beside the flank
  EXPECT_NEAR(cutter_distance(flat, {8, 0, -4}), 5.0, kClosedForm_mm);  // from the rim: 3-4-5
  EXPECT_NEAR(cutter_distance(flat, {0, 0, 1}), -1.0, kClosedForm_mm);  // inside, 1 above the face
  const Cutter ball = cutter(CutterType::Ball, 6, 3, 20);
  EXPECT_NEAR(cutter_distance(ball, {0, 0, -1}), 1.0, kClosedForm_mm);
  EXPECT_NEAR(cutter_distance(ball, {4, 0, 0}), std::hypot(4.0, 3.0) - 3.0, kClosedForm_mm);  // from the centre (0,0,3)
  const Cutter bull = cutter(CutterType::BullNose, 10, 2, 20);
  // Torus tube centre circle radius 3 at z = 2: point (6, 0, 0) is sqrt(3^2 + 2^2) - 2 away.
  EXPECT_NEAR(cutter_distance(bull, {6, 0, 0}), std::sqrt(13.0) - 2.0, kClosedForm_mm);
  EXPECT_NEAR(cutter_distance(bull, {2, 0, -0.5}), 0.5, kClosedForm_mm);  // under the flat part
  // V-bit, 90 deg included, 10 mm: the cone r = z up to z = 5, then the flank r = 5 up to 20.
  // In the (r, z) half-plane the slant is the line r = z: a point's distance to it is
  // |r - z| / sqrt 2 where its foot ((r + z) / 2, (r + z) / 2) lies on the cone's segment.
  Cutter vbit = cutter(CutterType::VBit, 10, 0, 20);
  vbit.tip_angle_deg = 90.0;
  EXPECT_NEAR(cutter_distance(vbit, {0, 0, -1}), 1.0, kClosedForm_mm);                   // below the point
  EXPECT_NEAR(cutter_distance(vbit, {3, 0, 0}), 3.0 / std::sqrt(2.0), kClosedForm_mm);   // foot (1.5, 1.5)
  EXPECT_NEAR(cutter_distance(vbit, {0, 4, 2}), 2.0 / std::sqrt(2.0), kClosedForm_mm);   // r 4, z 2: foot (3, 3)
  EXPECT_NEAR(cutter_distance(vbit, {0, 0, 2}), -2.0 / std::sqrt(2.0), kClosedForm_mm);  // inside, on the axis
  EXPECT_NEAR(cutter_distance(vbit, {7, 0, 8}), 2.0, kClosedForm_mm);                    // beside the flank
  // r 8, z 1: foot (4.5, 4.5) still on the slant, nearer than the rim (5, 5), 5 away.
  EXPECT_NEAR(cutter_distance(vbit, {8, 0, 1}), 7.0 / std::sqrt(2.0), kClosedForm_mm);
}

TEST(TranslationSweep, BallIsACapsule) {
  const Cutter ball = cutter(CutterType::Ball, 6, 3, 20);
  const Move m = move({0, 0, 0}, {10, 4, -2});  // a general ramp
  const TranslationSweep sweep(ball, m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-6, 16);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d x(u(rng), u(rng) * 0.6, u(rng) * 0.3);
    // Below the sphere centres' top the flute cylinder cannot be nearer than the sphere.
    const double capsule = segment_distance(x, Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(10, 4, 1)) - 3.0;
    if (x.z() > 0.5 || capsule > 1.0) continue;  // stay where the spherical end is the whole story
    EXPECT_NEAR(sweep.distance(x), capsule, kGeneralSweepTolerance_mm + kClosedForm_mm) << x.transpose();
  }
}

TEST(TranslationSweep, MatchesBruteForceMinimumOverInstances) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-8, 8);
  const Cutter cutters[] = {cutter(CutterType::Flat, 10, 0, 15), cutter(CutterType::BullNose, 10, 2, 15),
                            cutter(CutterType::Ball, 6, 3, 15)};
  const Move moves[] = {move({0, 0, 0}, {6, 0, 0}), move({0, 0, 0}, {0, 0, -5}), move({0, 0, 0}, {5, 3, -2}),
                        move({1, 1, 1}, {-4, 2, 6})};
  constexpr int kInstances = 100000;
  for (const Cutter& c : cutters)
    for (const Move& m : moves) {
      const TranslationSweep sweep(c, m);
      const double length = (m.end_mm - m.start_mm).norm();
      for (int i = 0; i < 40; ++i) {
        const Eigen::Vector3d x(u(rng), u(rng), u(rng));
        double brute = std::numeric_limits<double>::max();
        for (int k = 0; k <= kInstances; ++k) {
          const double t = static_cast<double>(k) / kInstances;
          brute = std::min(brute, cutter_distance(c, x - m.start_mm - t * (m.end_mm - m.start_mm)));
        }
        // The sampled minimum overestimates by at most half a sample step (1-Lipschitz).
        const double d = sweep.distance(x);
        EXPECT_LE(d, brute + kGeneralSweepTolerance_mm);
        EXPECT_GE(d, brute - 0.5 * length / kInstances - kGeneralSweepTolerance_mm);
      }
    }
}

// min over t in [0, 1] of a convex f, by ternary search (independent of the sweep's closed forms).
template <class F>
double convex_min(F&& f) {
  double a = 0.0, b = 1.0;
  for (int i = 0; i < 200; ++i) {
    const double m1 = a + (b - a) / 3.0, m2 = b - (b - a) / 3.0;
    if (f(m1) <= f(m2))
      b = m2;
    else
      a = m1;
  }
  return std::min({f(0.0), f(1.0), f(0.5 * (a + b))});
}

// A ball end's nearest point of its core's sweep (the projection's closed form): on that
// sweep (the core segment, centres r to max(r, H - r) up the axis, at some instant), as far
// from x as the nearest instance's core segment (a ternary search over the move), on tilted
// axes, for motion across the axis, along it and in general, and for a ball whose core is a
// point (H = 2r).
TEST(TranslationSweep, BallCoreNearestPointOnTheCoreSweep) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Cutter balls[] = {cutter(CutterType::Ball, 6, 3, 15), cutter(CutterType::Ball, 6, 3, 6)};
  int checked = 0;
  for (const Cutter& c : balls) {
    const double lo = 3.0, hi = std::max(3.0, c.flute_length_mm - 3.0);
    for (int trial = 0; trial < 60; ++trial) {
      Move m;
      m.axis = Eigen::Vector3d(0.6 * u(rng), 0.6 * u(rng), 1.0).normalized();
      m.start_mm = Eigen::Vector3d(u(rng), u(rng), u(rng));
      Eigen::Vector3d delta(4 * u(rng), 4 * u(rng), 4 * u(rng));
      if (trial % 3 == 0) delta -= delta.dot(m.axis) * m.axis;  // across the axis
      if (trial % 3 == 1) delta = delta.dot(m.axis) * m.axis;   // along it
      m.end_mm = m.start_mm + delta;
      const TranslationSweep sweep(c, m);
      auto core_distance = [&](const Eigen::Vector3d& x) {
        return convex_min([&](double t) {
          const Eigen::Vector3d tip = m.start_mm + t * delta;
          return segment_distance(x, tip + lo * m.axis, tip + (hi > lo ? hi : lo + 1e-12) * m.axis);
        });
      };
      for (int i = 0; i < 20; ++i) {
        const Eigen::Vector3d x = m.start_mm + Eigen::Vector3d(9 * u(rng), 9 * u(rng), 6 + 12 * u(rng));
        Eigen::Vector3d q;
        double radius = 0.0;
        ASSERT_TRUE(sweep.ball_core_nearest(x, q, radius));
        EXPECT_EQ(radius, 3.0);
        EXPECT_LT(core_distance(q), 1e-9) << "off the core's sweep: " << q.transpose();
        EXPECT_NEAR((x - q).norm(), core_distance(x), 1e-9) << x.transpose();
        EXPECT_NEAR(sweep.distance(x), (x - q).norm() - 3.0, kClosedForm_mm);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2400);
  Eigen::Vector3d q;
  double radius;
  EXPECT_FALSE(TranslationSweep(cutter(CutterType::BullNose, 10, 2, 15), move({0, 0, 0}, {1, 2, 3}))
                   .ball_core_nearest({0, 0, 0}, q, radius));
}

// The projection's step for a flat or bull-nose end mill ramping or contouring (the motion
// neither square to the axis nor along it): where it answers, the point lies on the sweep's
// surface and is as far from x as the sweep is, both against a ternary search over the move
// of the cutter's own distance (its profile, checked by hand above); where it does not, x
// lies in the core's sweep (at least r inside the sweep). Tilted and upright axes; a V-bit
// and the motions with a closed form do not answer.
TEST(TranslationSweep, FlatAndBullNoseSurfacePointIsTheNearest) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Cutter cutters[] = {cutter(CutterType::Flat, 8, 0, 12), cutter(CutterType::BullNose, 8, 2, 12),
                            cutter(CutterType::BullNose, 6, 1, 5)};
  int answered = 0, inside = 0;
  for (const Cutter& c : cutters) {
    for (int trial = 0; trial < 20; ++trial) {
      Move m = move(Eigen::Vector3d(u(rng), u(rng), u(rng)), Eigen::Vector3d::Zero());
      m.axis =
          trial % 4 == 0 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(0.6 * u(rng), 0.6 * u(rng), 1.0).normalized();
      const Eigen::Vector3d delta = Eigen::Vector3d(5 * u(rng), 5 * u(rng), 2 * u(rng)) + 1.5 * u(rng) * m.axis;
      m.end_mm = m.start_mm + delta;
      const TranslationSweep sweep(c, m);
      auto sweep_distance = [&](const Eigen::Vector3d& x) {
        return convex_min([&](double t) {
          const Eigen::Vector3d q = x - m.start_mm - t * delta;
          const double along = q.dot(m.axis);
          return cutter_distance(c, {(q - along * m.axis).norm(), 0.0, along});
        });
      };
      for (int i = 0; i < 25; ++i) {
        const Eigen::Vector3d x = m.start_mm + 0.5 * delta + Eigen::Vector3d(8 * u(rng), 8 * u(rng), 3 + 8 * u(rng));
        Eigen::Vector3d on;
        const double d = sweep_distance(x);
        if (sweep.surface_point(x, on)) {
          EXPECT_NEAR(sweep_distance(on), 0.0, 1e-6) << x.transpose();
          EXPECT_NEAR((x - on).norm(), std::abs(d), 1e-6) << x.transpose();
          EXPECT_GT(d, -c.corner_radius_mm - 1e-6) << x.transpose();
          ++answered;
        } else {
          EXPECT_LE(d, -c.corner_radius_mm + 1e-6) << x.transpose();
          ++inside;
        }
      }
    }
  }
  EXPECT_GT(answered, 1000);
  EXPECT_GT(inside, 50);
  Eigen::Vector3d on;
  Cutter v = cutter(CutterType::VBit, 6, 0, 10);
  v.tip_angle_deg = 90;
  EXPECT_FALSE(TranslationSweep(v, move({0, 0, 0}, {3, 1, 2})).surface_point({9, 9, 9}, on));
  EXPECT_FALSE(TranslationSweep(cutters[1], move({0, 0, 0}, {3, 1, 0})).surface_point({9, 9, 9}, on));  // square
  EXPECT_FALSE(TranslationSweep(cutters[1], move({0, 0, 0}, {0, 0, 3})).surface_point({9, 9, 9}, on));  // along
  EXPECT_TRUE(TranslationSweep(cutters[1], move({0, 0, 0}, {3, 1, 2})).surface_point({9, 9, 9}, on));
}

Cutter vbit(double d, double angle_deg, double flute) {
  Cutter c = cutter(CutterType::VBit, d, 0, flute);
  c.tip_angle_deg = angle_deg;
  return c;
}

// Points near the surface of flat, bull-nose and V-bit sweeps in general directions (the
// secant search on the derivative: the core's, or the V-bit profile's gradient), inside and
// out, and the `far` contract: exact below far, at least far beyond it. The V-bits: 90 deg,
// and 60 deg cut off at its flute length below its full diameter.
TEST(TranslationSweep, GeneralSweepNearItsSurface) {
  std::mt19937 rng(5);
  const Cutter cutters[] = {cutter(CutterType::Flat, 10, 0, 15), cutter(CutterType::BullNose, 10, 2, 15),
                            cutter(CutterType::BullNose, 6, 3, 15), vbit(10, 90, 15), vbit(10, 60, 6)};
  const Move moves[] = {move({0, 0, 0}, {0.5, 0, -0.2}), move({0, 0, 0}, {3, 4, 2}), move({0, 0, 0}, {0.01, 0, 8})};
  constexpr int kInstances = 20000;
  for (const Cutter& c : cutters)
    for (const Move& m : moves) {
      const TranslationSweep sweep(c, m);
      const double length = (m.end_mm - m.start_mm).norm();
      std::uniform_real_distribution<double> across(-6.5, 6.5), along(-1.5, 17);
      for (int i = 0; i < 300; ++i) {
        Eigen::Vector3d x(across(rng), across(rng), along(rng));
        x += std::uniform_real_distribution<double>(0, 1)(rng) * (m.end_mm - m.start_mm);
        if (test::sanitized() && i % 3 != 0) continue;  // every third point under the sanitizers
        double brute = std::numeric_limits<double>::max();
        for (int k = 0; k <= kInstances; ++k) {
          const double t = static_cast<double>(k) / kInstances;
          brute = std::min(brute, cutter_distance(c, x - m.start_mm - t * (m.end_mm - m.start_mm)));
        }
        const double d = sweep.distance(x);
        EXPECT_LE(d, brute + kGeneralSweepTolerance_mm) << x.transpose();
        EXPECT_GE(d, brute - 0.5 * length / kInstances - kGeneralSweepTolerance_mm) << x.transpose();
        const double far = 0.3, near = sweep.distance(x, far);
        if (d < far - 1e-9)
          EXPECT_NEAR(near, d, kGeneralSweepTolerance_mm) << x.transpose();
        else
          EXPECT_GE(near, far - kGeneralSweepTolerance_mm) << x.transpose();
      }
    }
}

// distances() takes a tilted flat or bull-nose cutter's points four at a time (the march's
// lanes), in AVX2 lanes or not: the same values as distance(), to the bit, for groups of 1 to
// 9 points, for every cutter and kind of motion (those it does not take together go one by
// one); on a long general move, points behind, ahead and beside its middle, whose nearest
// instance is the start, the end or one between, and points where the core's distance
// changes its case at an end: on the axis, at the core's middle height, on its side and its
// rims.
TEST(TranslationSweep, DistancesTogetherAreEachDistance) {
  std::mt19937 rng(29);
  const Cutter cutters[] = {cutter(CutterType::Flat, 10, 0, 15), cutter(CutterType::BullNose, 8, 1, 25),
                            cutter(CutterType::Ball, 6, 3, 15), vbit(10, 90, 15)};
  Move tilted = move({0, 0, 0}, {8, 3, 1.5});
  tilted.axis = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const Move moves[] = {tilted, move({0, 0, 0}, {3, 4, 2}), move({0, 0, 0}, {5, 0, 0}), move({0, 0, 0}, {0, 0, 4})};
  std::uniform_real_distribution<double> unit(0.0, 1.0), across(-7, 7), along(-3, 20);
  int compared = 0;
  for (const Cutter& c : cutters)
    for (const Move& m : moves) {
      const TranslationSweep sweep(c, m);
      // In the tool frame at either end: (radius from the axis, height above the tip).
      const Eigen::Vector3d a = m.axis.normalized(), side = a.unitOrthogonal();
      const CutterCore core = core_of(c);
      const double radii[] = {0.0, core.core_radius_mm, core.core_radius_mm + 1.5};
      const double heights[] = {core.z_low_mm, 0.5 * (core.z_low_mm + core.z_high_mm), core.z_high_mm, -2.0};
      std::vector<Eigen::Vector3d> cases;
      for (const Eigen::Vector3d& tip : {m.start_mm, m.end_mm})
        for (const double radius : radii)
          for (const double height : heights) cases.push_back(tip + height * a + radius * side);
      for (int n = 1; n <= 9; ++n)
        for (int trial = 0; trial < 40; ++trial) {
          std::vector<Eigen::Vector3d> x(static_cast<std::size_t>(n));
          for (Eigen::Vector3d& p : x) {
            const double t = -0.5 + 2.0 * unit(rng);  // behind the start to ahead of the end
            p = m.start_mm + t * (m.end_mm - m.start_mm) + Eigen::Vector3d(across(rng), across(rng), along(rng));
            if (trial % 4 == 0) p = cases[rng() % cases.size()];
          }
          for (const bool lanes : {true, false}) {
            std::vector<double> together(static_cast<std::size_t>(n));
            sweep.distances(x.data(), n, together.data(), lanes);
            for (int j = 0; j < n; ++j) {
              const double alone = sweep.distance(x[static_cast<std::size_t>(j)]);
              EXPECT_EQ(together[static_cast<std::size_t>(j)], alone)
                  << to_string(c.type) << " point " << j << " of " << n << (lanes ? ", lanes" : "");
              ++compared;
            }
          }
        }
    }
  EXPECT_EQ(compared, 2 * 4 * 4 * 40 * 45);
}

// The march's Newton steps take the distance's slope along a ray family (distances() with
// `slope`): where it is given, the derivative of distance() along that axis, by central
// differences of distance() itself (h = 1e-4 mm: the second-order term about h^2 / r, the
// points' own tolerance 1e-7 / h at most), the same bits with and without lanes; given for
// most points (those whose nearest instance is an end), never for a ball or a V-bit, nor inside the
// core's sweep.
TEST(TranslationSweep, SlopesAlongTheRaysAreTheDistancesDerivative) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0), across(-7, 7), along(-3, 20);
  Move tilted = move({0, 0, 0}, {8, 3, 1.5}), steep = move({0, 0, 0}, {0.5, -0.4, -3});
  tilted.axis = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  steep.axis = Eigen::Vector3d(-0.4, 0.1, 1.0).normalized();
  int known = 0, points = 0;
  for (const Cutter& c : {cutter(CutterType::BullNose, 8, 1, 25), cutter(CutterType::Flat, 10, 0, 15)})
    for (const Move& m : {tilted, steep}) {
      const TranslationSweep sweep(c, m);
      for (int trial = 0; trial < 2000; ++trial) {
        const double t = -0.5 + 2.0 * unit(rng);
        const Eigen::Vector3d x =
            m.start_mm + t * (m.end_mm - m.start_mm) + Eigen::Vector3d(across(rng), across(rng), along(rng));
        for (int axis = 0; axis < 3; ++axis) {
          double value[2], slope[2];
          for (const bool lanes : {true, false}) sweep.distances(&x, 1, &value[lanes], lanes, axis, &slope[lanes]);
          ++points;
          EXPECT_EQ(value[0], value[1]);
          if (std::isnan(slope[1])) {
            EXPECT_TRUE(std::isnan(slope[0]));
            continue;
          }
          ++known;
          EXPECT_EQ(slope[0], slope[1]);
          EXPECT_GT(value[1], -c.corner_radius_mm) << "a slope inside the core's sweep";
          const double h = 1e-4;
          const Eigen::Vector3d e = Eigen::Vector3d::Unit(axis);
          const double central = (sweep.distance(x + h * e) - sweep.distance(x - h * e)) / (2 * h);
          EXPECT_NEAR(slope[1], central, 2e-3) << to_string(c.type) << " at " << x.transpose() << ", axis " << axis;
        }
      }
    }
  EXPECT_GT(known, points / 2);
  for (const Cutter& c : {cutter(CutterType::Ball, 6, 3, 15), vbit(10, 90, 15)}) {
    const TranslationSweep sweep(c, tilted);
    const Eigen::Vector3d x(4, 8, 2);
    double value, slope;
    sweep.distances(&x, 1, &value, true, 2, &slope);
    EXPECT_TRUE(std::isnan(slope));
    EXPECT_EQ(value, sweep.distance(x));
  }
}

TEST(TranslationSweep, BoundsContainTheCutterAtBothEnds) {
  const Cutter flat = cutter(CutterType::Flat, 10, 0, 20);
  const TranslationSweep sweep(flat, move({0, 0, 0}, {10, 0, -3}));
  EXPECT_TRUE(sweep.bounds().contains(Eigen::Vector3d(-5, -5, 0)));
  EXPECT_TRUE(sweep.bounds().contains(Eigen::Vector3d(15, 5, 17)));
  EXPECT_FALSE(sweep.bounds().contains(Eigen::Vector3d(16, 0, 0)));
}

}  // namespace
}  // namespace vcut::removal
