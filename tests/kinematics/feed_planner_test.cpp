// Feed planner: S-curve times against closed forms derived here, seed 000's worked case
// against the paper's eqs. 5-7, junction rules (exact stop, collinear, the blend corner
// derived from its geometry), G93, axis limits through the kinematics, pure rotations, the
// look-ahead, and randomized bounds on speed, acceleration and jerk from time stamps alone.
#include "vcut/kinematics/feed_planner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace vcut::kinematics {
namespace {

// The planner solves its roots to rounding; sums over a few thousand segments and the
// inverse of the cubic s(t) leave ~1e-13 relative. Closed forms are compared to this.
constexpr double kClosedForm = 1e-11;
// The bound on limits: speed, acceleration and jerk from time stamps may exceed the
// limits by this relative amount (rounding only: the mean-value bounds are exact, and the
// measured excess is ~3e-13 for a, ~3e-11 for the third differences giving j).
constexpr double kLimit = 1e-9;

Block line(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double feed_mm_per_min) {
  Block b;
  b.kind = MotionKind::Linear;
  b.start_mm = from;
  b.end_mm = to;
  b.feed_mm_per_min = feed_mm_per_min;
  return b;
}

// Program of straight blocks through the points, all at one feed.
Program polyline(const std::vector<Eigen::Vector3d>& points, double feed_mm_per_min) {
  Program p;
  p.files = {"test.ngc"};
  for (size_t i = 1; i < points.size(); ++i) p.blocks.push_back(line(points[i - 1], points[i], feed_mm_per_min));
  return p;
}

PoseSample sample(const Eigen::Vector3d& tip, const Eigen::Vector3d& axis, int block) {
  PoseSample s;
  s.pose.tip_mm = tip;
  s.pose.axis = axis;
  s.block = block;
  return s;
}

// Each block cut into q equal steps (seed 000 eq. 4), tool axis +Z.
std::vector<PoseSample> straight_samples(const Program& p, int q) {
  std::vector<PoseSample> s;
  s.push_back(sample(p.blocks.front().start_mm, Eigen::Vector3d::UnitZ(), -1));
  for (size_t i = 0; i < p.blocks.size(); ++i) {
    const Block& b = p.blocks[i];
    for (int k = 1; k <= q; ++k) {
      const Eigen::Vector3d tip =
          k == q ? b.end_mm : Eigen::Vector3d(b.start_mm + (b.end_mm - b.start_mm) * (double(k) / q));
      s.push_back(sample(tip, Eigen::Vector3d::UnitZ(), static_cast<int>(i)));
    }
  }
  return s;
}

FeedSettings limits(double a, double j) {
  FeedSettings s;
  s.path_acceleration_mm_per_s2 = a;
  s.path_jerk_mm_per_s3 = j;
  return s;
}

// Rest to rest with every limit reached. The speed change 0 -> v: jerk j for a/j (reaching
// a), constant a for v/a - a/j, jerk -j for a/j: Ta = v/a + a/j. The acceleration is
// symmetric in time, so the mean speed is v/2 and the change covers v Ta / 2; braking
// mirrors it. Cruise covers L - v Ta in (L - v Ta)/v. T = 2 Ta + L/v - Ta = L/v + v/a + a/j.
double full_limits_time(double L, double v, double a, double j) { return L / v + v / a + a / j; }

void expect_relative(double actual, double expected, double tol, const char* what) {
  EXPECT_NEAR(actual, expected, tol * std::abs(expected)) << what;
}

TEST(FeedScurve, RestToRestWithAllLimitsReached) {
  const double L = 100, v = 50, a = 1000, j = 40000;  // a^2/j = 25 <= v; v Ta = 3.75 <= L
  const Program p = polyline({{0, 0, 0}, {60, 80, 0}}, v * 60);
  const std::vector<PoseSample> s = straight_samples(p, 200);
  const FeedPlan plan = plan_feed(p, s, nullptr, limits(a, j));
  const double T = full_limits_time(L, v, a, j);
  expect_relative(plan.cycle_time_s, T, kClosedForm, "cycle time");
  expect_relative(plan.block_time_s[0], T, kClosedForm, "block time");
  expect_relative(plan.t_s[100], T / 2, kClosedForm, "midpoint: the profile is symmetric");
  expect_relative(plan.speed_mm_per_s[100], v, kClosedForm, "cruise at the midpoint");
  EXPECT_EQ(plan.speed_mm_per_s.front(), 0.0);
  EXPECT_NEAR(plan.speed_mm_per_s.back(), 0.0, 1e-9);
  // In the cruise, t(s) = Ta + (s - v Ta/2)/v; s = 25 mm is sample 50.
  const double Ta = v / a + a / j;
  expect_relative(plan.t_s[50], Ta + (25 - v * Ta / 2) / v, kClosedForm, "cruise time stamp");
  EXPECT_TRUE(plan.axis_limited_samples.empty());
}

TEST(FeedScurve, AccelerationLimitNotReached) {
  // v < a^2/j: the acceleration rises and falls in a triangle, peaking at sqrt(v j) < a, and
  // the change lasts Ta = 2 sqrt(v/j), covering v Ta / 2 = v sqrt(v/j). As above,
  // T = L/v + Ta = L/v + 2 sqrt(v/j).
  const double L = 100, v = 50, a = 1000, j = 10000;  // a^2/j = 100 > v
  const Program p = polyline({{0, 0, 0}, {0, 0, -100}}, v * 60);
  const FeedPlan plan = plan_feed(p, straight_samples(p, 100), nullptr, limits(a, j));
  expect_relative(plan.cycle_time_s, L / v + 2 * std::sqrt(v / j), kClosedForm, "cycle time");
  expect_relative(plan.speed_mm_per_s[50], v, kClosedForm, "cruise");
}

TEST(FeedScurve, CruiseNotReachedAccelerationReached) {
  // L < v (v/a + a/j): the peak vp >= a^2/j solves L = vp (vp/a + a/j), the quadratic
  // vp^2/a + (a/j) vp - L = 0: vp = (a/2)(-a/j + sqrt((a/j)^2 + 4L/a)); T = 2 (vp/a + a/j).
  const double L = 2, v = 50, a = 1000, j = 40000;
  const double vp = 0.5 * a * (-a / j + std::sqrt((a / j) * (a / j) + 4 * L / a));
  ASSERT_GE(vp, a * a / j);
  ASSERT_LT(vp, v);
  const Program p = polyline({{0, 0, 0}, {2, 0, 0}}, v * 60);
  const FeedPlan plan = plan_feed(p, straight_samples(p, 100), nullptr, limits(a, j));
  expect_relative(plan.cycle_time_s, 2 * (vp / a + a / j), kClosedForm, "cycle time");
  expect_relative(plan.speed_mm_per_s[50], vp, kClosedForm, "peak at the midpoint");
}

TEST(FeedScurve, NeitherCruiseNorAccelerationReached) {
  // Four jerk phases of tau each: the change 0 -> vp = j tau^2 covers vp tau (mean vp/2 over
  // 2 tau), so L = 2 j tau^3: tau = (L/(2j))^(1/3), T = 4 tau, vp = j tau^2.
  const double L = 0.5, v = 50, a = 1000, j = 40000;
  const double tau = std::cbrt(L / (2 * j));
  ASSERT_LT(j * tau, a);  // the acceleration peak stays below a
  const Program p = polyline({{0, 0, 0}, {0, 0.3, 0.4}}, v * 60);
  const FeedPlan plan = plan_feed(p, straight_samples(p, 100), nullptr, limits(a, j));
  expect_relative(plan.cycle_time_s, 4 * tau, kClosedForm, "cycle time");
  expect_relative(plan.speed_mm_per_s[50], j * tau * tau, kClosedForm, "peak at the midpoint");
}

// Finite differences of the planner's time stamps and speeds: the secant speed and the
// speed's secant are mean values of v and a over each step; the difference of adjacent mean
// accelerations over the distance of their centres is a mean of the jerk. Bounds on them
// show that position, speed and acceleration are continuous with bounded derivatives.
struct Differences {
  double speed = 0, acceleration = 0, jerk = 0;
  double trapezoid = 0;  // max |ds - (v0 + v1)/2 dt| / (j dt^3 / 12): <= 1 if v is s'
};

Differences differences(const std::vector<double>& s, const FeedPlan& plan, double j) {
  Differences d;
  std::vector<double> acc;
  for (size_t i = 1; i < s.size(); ++i) {
    const double dt = plan.t_s[i] - plan.t_s[i - 1];
    EXPECT_GT(dt, 0.0) << "sample " << i;
    d.speed = std::max(d.speed, (s[i] - s[i - 1]) / dt);
    acc.push_back((plan.speed_mm_per_s[i] - plan.speed_mm_per_s[i - 1]) / dt);
    d.acceleration = std::max(d.acceleration, std::abs(acc.back()));
    // trapezoid rule error for s = integral of v: |v''| <= j bounds it by j dt^3 / 12
    const double err = std::abs(s[i] - s[i - 1] - 0.5 * (plan.speed_mm_per_s[i] + plan.speed_mm_per_s[i - 1]) * dt);
    d.trapezoid = std::max(d.trapezoid, err / (j * dt * dt * dt / 12 + 1e-15 * std::abs(s[i])));
  }
  for (size_t i = 1; i < acc.size(); ++i) {
    const double centres = 0.5 * (plan.t_s[i + 1] - plan.t_s[i - 1]);
    d.jerk = std::max(d.jerk, std::abs(acc[i] - acc[i - 1]) / centres);
  }
  return d;
}

TEST(FeedScurve, ContinuousAndWithinLimits) {
  const double L = 20, v = 50, a = 1000, j = 40000;
  const Program p = polyline({{0, 0, 0}, {20, 0, 0}}, v * 60);
  const std::vector<PoseSample> samples = straight_samples(p, 2000);
  const FeedPlan plan = plan_feed(p, samples, nullptr, limits(a, j));
  std::vector<double> s;
  for (const PoseSample& x : samples) s.push_back(x.pose.tip_mm.x());
  const Differences d = differences(s, plan, j);
  EXPECT_LE(d.speed, v * (1 + kLimit));
  EXPECT_LE(d.acceleration, a * (1 + kLimit));
  EXPECT_LE(d.jerk, j * (1 + kLimit));
  EXPECT_LE(d.trapezoid, 1 + kLimit);
  // and the limits are used: the secants come within a step's variation of them
  EXPECT_GT(d.speed, v * (1 - 1e-6));
  EXPECT_GT(d.acceleration, a * (1 - 1e-6));
  EXPECT_GT(d.jerk, j * 0.99);
  for (double x : plan.speed_mm_per_s) EXPECT_LE(x, v * (1 + kLimit));
  expect_relative(plan.cycle_time_s, full_limits_time(L, v, a, j), kClosedForm, "cycle time");
}

// Randomized (fixed seed): zig-zags with random lengths, turns, feeds, G64 tolerances and
// exact stops. Speed, acceleration and jerk from the time stamps stay within the limits,
// each block's speed within its feed, and each corner within the blend rule.
TEST(FeedScurve, RandomProgramsStayWithinLimits) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> length(0.05, 8.0), turn(-2.5, 2.5), feed(300, 6000), unit(0, 1);
  const double a = 800, j = 30000;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::Vector3d> pts = {Eigen::Vector3d::Zero()};
    double heading = 0;
    for (int k = 0; k < 40; ++k) {
      heading += turn(rng);
      const double l = length(rng);
      pts.push_back(pts.back() + l * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.1 * turn(rng)));
    }
    Program p = polyline(pts, 1000);
    for (std::size_t k = 0; k < p.blocks.size(); ++k) {
      Block& b = p.blocks.edit(k);
      b.feed_mm_per_min = feed(rng);
      b.exact_stop = unit(rng) < 0.1;
      b.blend_tolerance_mm = unit(rng) < 0.5 ? 0.2 * unit(rng) : -1;
    }
    const std::vector<PoseSample> samples = straight_samples(p, 40);
    FeedSettings fs = limits(a, j);
    fs.lookahead_blocks = 1 + trial % 7;  // windows much shorter than the program too
    const FeedPlan plan = plan_feed(p, samples, nullptr, fs);
    std::vector<double> s = {0};
    for (size_t i = 1; i < samples.size(); ++i)
      s.push_back(s.back() + (samples[i].pose.tip_mm - samples[i - 1].pose.tip_mm).norm());
    const Differences d = differences(s, plan, j);
    EXPECT_LE(d.acceleration, a * (1 + kLimit)) << "trial " << trial;
    EXPECT_LE(d.jerk, j * (1 + kLimit)) << "trial " << trial;
    EXPECT_LE(d.trapezoid, 1 + kLimit) << "trial " << trial;
    for (size_t i = 1; i < samples.size(); ++i) {
      const Block& b = p.blocks[static_cast<size_t>(samples[i].block)];
      EXPECT_LE(plan.speed_mm_per_s[i], b.feed_mm_per_min / 60 * (1 + kLimit)) << "trial " << trial << " sample " << i;
    }
    for (size_t k = 0; k + 1 < p.blocks.size(); ++k) {
      const double v = plan.speed_mm_per_s[(k + 1) * 40];
      if (p.blocks[k].exact_stop) {
        EXPECT_EQ(v, 0.0);
      }
      const Eigen::Vector3d u = (p.blocks[k].end_mm - p.blocks[k].start_mm).normalized();
      const Eigen::Vector3d w = (p.blocks[k + 1].end_mm - p.blocks[k + 1].start_mm).normalized();
      const double theta = std::acos(std::clamp(u.dot(w), -1.0, 1.0));
      const double tol =
          p.blocks[k].blend_tolerance_mm >= 0 ? p.blocks[k].blend_tolerance_mm : fs.default_blend_tolerance_mm;
      const double radius = tol * std::cos(theta / 2) / (1 - std::cos(theta / 2));
      EXPECT_LE(v, std::sqrt(a * radius) * (1 + 1e-6) + 1e-12) << "trial " << trial << " corner " << k;
    }
    EXPECT_NEAR(plan.speed_mm_per_s.back(), 0.0, 1e-9);
  }
}

// Seed 000 §5: F = 1000 mm/min, a = 500 mm/s^2, start and end speed 0, q = 100. The paper's
// profile (eqs. 5-7) has no jerk limit: eq. 6 gives the change times T1 = (F - vs)/a,
// T3 = (F - ve)/a, eq. 5 their distances S1 = (F + vs)/2 T1, S3 = (F + ve)/2 T3, and eq. 7
// stamps a pose in the constant phase at T1 + (S - S1)/F. Here T1 = T3 = 1/30 s and
// S1 = S3 = 5/18 mm = 0.2778 mm. The paper names no block length; its program (Fig. 6) starts
// N7 X-1320 Y-1320 Z1000 -> N8 X-1100 Y-1100 Z800, L = sqrt(220^2 + 220^2 + 200^2) =
// 369.86 mm, so every densified pose but the ends (3.7 mm apart) falls in the constant phase:
// T = T1 + T2 + T3 = L/F + F/a = 22.225 s, midpoint T/2 = 11.11 s. Our planner is
// jerk-limited; with j -> infinity it tends to this trapezoid: its jerk phases add a/j to the
// total time and shift the cruise stamps by a/(2j).
TEST(FeedSeed000, WorkedCaseMatchesThePapersTimeStamps) {
  const double F = 1000.0 / 60, a = 500, j = 1e9;
  const Eigen::Vector3d n7(-1320, -1320, 1000), n8(-1100, -1100, 800);
  const Program p = polyline({n7, n8}, 1000);
  const std::vector<PoseSample> samples = straight_samples(p, 100);
  const FeedPlan plan = plan_feed(p, samples, nullptr, limits(a, j));
  const double L = (n8 - n7).norm();
  const double T1 = F / a, T3 = F / a, S1 = F / 2 * T1, S3 = F / 2 * T3;
  const double T2 = (L - S1 - S3) / F;
  const double kJerkShift = a / j + 1e-12;  // our jerk phases, plus rounding of ~20 s stamps
  EXPECT_NEAR(plan.cycle_time_s, T1 + T2 + T3, kJerkShift);
  EXPECT_NEAR(plan.cycle_time_s, L / F + F / a, kJerkShift);
  EXPECT_NEAR(plan.t_s[50], (L / F + F / a) / 2, kJerkShift);
  for (int t = 1; t < 100; ++t) {
    const double S = L * t / 100;
    ASSERT_GT(S, S1);
    ASSERT_LT(S, L - S3);
    EXPECT_NEAR(plan.t_s[static_cast<size_t>(t)], T1 + (S - S1) / F, kJerkShift) << "pose " << t;
    EXPECT_NEAR(plan.speed_mm_per_s[static_cast<size_t>(t)], F, 1e-9) << "pose " << t;
  }
  EXPECT_NEAR(plan.cycle_time_s, 22.225, 0.001);  // the number quoted above
}

TEST(FeedJunction, ExactStopStopsAtTheJunction) {
  const double v = 50, a = 1000, j = 40000;
  Program p = polyline({{0, 0, 0}, {50, 0, 0}, {100, 0, 0}}, v * 60);
  p.blocks.edit(0).exact_stop = true;  // G9
  const FeedPlan plan = plan_feed(p, straight_samples(p, 10), nullptr, limits(a, j));
  EXPECT_EQ(plan.speed_mm_per_s[10], 0.0);
  expect_relative(plan.block_time_s[0], full_limits_time(50, v, a, j), kClosedForm, "first block");
  expect_relative(plan.block_time_s[1], full_limits_time(50, v, a, j), kClosedForm, "second block");
  expect_relative(plan.cycle_time_s, 2 * full_limits_time(50, v, a, j), kClosedForm, "cycle");
}

TEST(FeedJunction, CollinearBlocksKeepFullSpeed) {
  const double v = 50, a = 1000, j = 40000;
  const Program p = polyline({{0, 0, 0}, {50, 0, 0}, {100, 0, 0}}, v * 60);
  const FeedPlan plan = plan_feed(p, straight_samples(p, 10), nullptr, limits(a, j));
  expect_relative(plan.speed_mm_per_s[10], v, kClosedForm, "junction speed");
  expect_relative(plan.cycle_time_s, full_limits_time(100, v, a, j), kClosedForm, "one S-curve over both");
  expect_relative(plan.block_time_s[0], plan.cycle_time_s / 2, kClosedForm, "symmetric halves");
}

TEST(FeedJunction, RightAngleCornerFollowsTheBlendRule) {
  // Corner at B, in along +x, out along +y. The blend circle tangent to both lines has its
  // centre at (-R, R) from B, R sqrt(2) from the corner: it passes the corner at
  // R (sqrt(2) - 1) = tol, so R = tol / (sqrt(2) - 1), and v^2/R = a gives the speed.
  const double v = 100, a = 2000, j = 50000, tol = 0.05;
  Program p = polyline({{0, 0, 0}, {100, 0, 0}, {100, 100, 0}}, v * 60);
  p.blocks.edit(0).blend_tolerance_mm = tol;  // G64 P0.05
  const double expected = std::sqrt(a * tol / (std::sqrt(2.0) - 1));
  const FeedPlan plan = plan_feed(p, straight_samples(p, 20), nullptr, limits(a, j));
  expect_relative(plan.speed_mm_per_s[20], expected, kClosedForm, "corner speed");

  // Without P the settings' default tolerance applies; P0 stops.
  p.blocks.edit(0).blend_tolerance_mm = -1;
  FeedSettings fs = limits(a, j);
  fs.default_blend_tolerance_mm = 0.01;
  expect_relative(plan_feed(p, straight_samples(p, 20), nullptr, fs).speed_mm_per_s[20],
                  std::sqrt(a * 0.01 / (std::sqrt(2.0) - 1)), kClosedForm, "default tolerance");
  p.blocks.edit(0).blend_tolerance_mm = 0;
  EXPECT_EQ(plan_feed(p, straight_samples(p, 20), nullptr, fs).speed_mm_per_s[20], 0.0);
}

// A three-axis machine built in code: X Y Z stacked on the frame, limits as given.
Machine xyz_machine(double vx, double vy, double ay) {
  MachineSpec spec;
  spec.name = "xyz";
  spec.topology = "WFXYZT";
  const Eigen::Vector3d dirs[3] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  for (int k = 0; k < 3; ++k) {
    AxisSpec ax;
    ax.letter = "XYZ"[k];
    ax.direction = dirs[k];
    ax.max_velocity_per_s = k == 0 ? vx : k == 1 ? vy : 0.0;
    ax.max_acceleration_per_s2 = k == 1 ? ay : 0.0;
    spec.axes.push_back(ax);
  }
  return Machine(spec);
}

// The samples with their machine axes X Y Z = the tip.
std::vector<PoseSample> with_axes(std::vector<PoseSample> s) {
  for (PoseSample& x : s) x.axes = AxisValues(x.pose.tip_mm);
  return s;
}

TEST(FeedInverseTime, BlockTakesOneOverFMinutes) {
  Program p = polyline({{0, 0, 0}, {30, 40, 0}}, 2);  // G93 F2: half a minute
  p.blocks.edit(0).feed_mode = FeedMode::InverseTime;
  const FeedPlan plan = plan_feed(p, straight_samples(p, 50), nullptr, limits(500, 50000));
  expect_relative(plan.block_time_s[0], 30.0, kClosedForm, "G93 F2");

  // F600 asks for 0.1 s, beyond an X axis of 10 mm/s: the block runs rest to rest at the
  // axis's speed, L/v + v/a + a/j.
  p = polyline({{0, 0, 0}, {50, 0, 0}}, 600);
  p.blocks.edit(0).feed_mode = FeedMode::InverseTime;
  const Machine m = xyz_machine(10.0, 0.0, 0.0);
  const std::vector<PoseSample> s = with_axes(straight_samples(p, 50));
  const double a = 50, j = 5000;  // a^2/j = 0.5 < v: all limits reached
  const FeedPlan limited = plan_feed(p, s, &m, limits(a, j));
  expect_relative(limited.block_time_s[0], full_limits_time(50, 10, a, j), kClosedForm, "limited by X");
  EXPECT_EQ(limited.axis_limited_samples.size(), 50u);
}

TEST(FeedAxisLimits, SlowAxisBoundsThePathSpeedByItsRatio) {
  // Block 0 along (3, 4, 0)/5: Y moves 0.8 mm per mm of path. Y's 5 mm/s and 200 mm/s^2 bound
  // the path to 5/0.8 = 6.25 mm/s and 200/0.8 = 250 mm/s^2 (F = 20 mm/s asks for more);
  // a^2/j = 1.25 <= 6.25, all limits reached. Block 1 along X (no X limit): F and the path
  // limits, a^2/j = 5 <= 20. G9 between them keeps both rest to rest.
  const double a = 500, j = 50000;
  Program p = polyline({{0, 0, 0}, {30, 40, 0}, {130, 40, 0}}, 1200);
  p.blocks.edit(0).exact_stop = true;
  const Machine m = xyz_machine(0.0, 5.0, 200.0);
  const std::vector<PoseSample> s = with_axes(straight_samples(p, 25));
  const FeedPlan plan = plan_feed(p, s, &m, limits(a, j));
  expect_relative(plan.block_time_s[0], full_limits_time(50, 5 / 0.8, 200 / 0.8, j), kClosedForm, "Y-limited block");
  expect_relative(plan.block_time_s[1], full_limits_time(100, 20, a, j), kClosedForm, "free block");
  std::vector<int> expected;
  for (int i = 1; i <= 25; ++i) expected.push_back(i);
  EXPECT_EQ(plan.axis_limited_samples, expected);
  for (size_t i = 0; i <= 25; ++i) EXPECT_LE(plan.speed_mm_per_s[i] * 0.8, 5 * (1 + kLimit));
}

TEST(FeedAxisLimits, RapidsRunAtTheAxesSpeed) {
  // G0 along (1, 1, 0): X 100 and Y 50 mm/s with ratio 1/sqrt(2) each: the path may run
  // 50 sqrt(2) mm/s. Without a machine the settings' rapid speed.
  const double a = 1000, j = 100000;  // a^2/j = 10 <= v
  Program p = polyline({{0, 0, 0}, {100, 100, 0}}, 0);
  p.blocks.edit(0).kind = MotionKind::Rapid;
  const Machine m = xyz_machine(100.0, 50.0, 0.0);
  const std::vector<PoseSample> s = with_axes(straight_samples(p, 10));
  const double L = 100 * std::sqrt(2.0);
  FeedSettings fs = limits(a, j);
  expect_relative(plan_feed(p, s, &m, fs).cycle_time_s, full_limits_time(L, 50 * std::sqrt(2.0), a, j), kClosedForm,
                  "axis speed");
  fs.rapid_mm_per_min = 3000;
  expect_relative(plan_feed(p, s, nullptr, fs).cycle_time_s, full_limits_time(L, 50, a, j), kClosedForm,
                  "settings' rapid");
  EXPECT_TRUE(plan_feed(p, s, &m, fs).axis_limited_samples.empty());  // rapids are axis-speed by definition
}

TEST(FeedRotation, PureRotationIsTimedInDegreesPerMinute) {
  // The tip stays at the origin while the tool turns 90 deg about Y at F600: 10 deg/s.
  // Path limits read deg/s^2 and deg/s^3: a^2/j = 80 > 10, so T = 90/10 + 2 sqrt(10/j).
  const double a = 2000, j = 50000;
  Program p;
  p.files = {"r.ngc"};
  p.blocks.push_back(line(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 600));
  p.blocks.edit(0).end_axis = Eigen::Vector3d::UnitX();
  std::vector<PoseSample> s;
  for (int k = 0; k <= 90; ++k) {
    const double phi = k * M_PI / 180;
    s.push_back(sample(Eigen::Vector3d::Zero(), Eigen::Vector3d(std::sin(phi), 0, std::cos(phi)), k == 0 ? -1 : 0));
  }
  const FeedPlan plan = plan_feed(p, s, nullptr, limits(a, j));
  expect_relative(plan.cycle_time_s, 9 + 2 * std::sqrt(10 / j), kClosedForm, "rotation time");
  expect_relative(plan.t_s[45], plan.cycle_time_s / 2, kClosedForm, "symmetric");
  for (double v : plan.speed_mm_per_s) EXPECT_EQ(v, 0.0);  // the tip does not move
}

TEST(FeedRotation, RotaryAxisLimitBoundsARotation) {
  // The same turn on a machine whose A axis (about X) does it: the path is A's motion in
  // degrees, and A's 5 deg/s bounds the F600 (10 deg/s): T = 90/5 + 2 sqrt(5/j).
  const double a = 2000, j = 50000;
  MachineSpec spec;
  spec.name = "xyza";
  spec.topology = "WAFXYZT";
  const Eigen::Vector3d dirs[4] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
                                   Eigen::Vector3d::UnitX()};
  for (int k = 0; k < 4; ++k) {
    AxisSpec ax;
    ax.letter = "XYZA"[k];
    ax.kind = k == 3 ? AxisKind::Rotary : AxisKind::Linear;
    ax.direction = dirs[k];
    ax.max_velocity_per_s = k == 3 ? 5 * M_PI / 180 : 0.0;
    spec.axes.push_back(ax);
  }
  const Machine m(spec);
  Program p;
  p.files = {"r.ngc"};
  p.blocks.push_back(line(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 600));
  std::vector<PoseSample> s;
  for (int k = 0; k <= 90; ++k) {
    const double phi = k * M_PI / 180;
    s.push_back(sample(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, -std::sin(phi), std::cos(phi)), k == 0 ? -1 : 0));
    s.back().axes = AxisValues(4);
    s.back().axes << 0, 0, 0, phi;
  }
  const FeedPlan plan = plan_feed(p, s, &m, limits(a, j));
  expect_relative(plan.cycle_time_s, 90.0 / 5 + 2 * std::sqrt(5 / j), kClosedForm, "A-limited rotation");
  EXPECT_EQ(plan.axis_limited_samples.size(), 90u);
}

TEST(FeedArc, CentripetalAccelerationBoundsTheSpeed) {
  // A half circle of R = 5 mm at F6000 (100 mm/s): v^2/R <= a gives sqrt(a R) = 70.7 mm/s
  // (the jerk's v^3/R^2 <= j allows cbrt(j R^2) = 100). Rest to rest with all limits reached
  // (a^2/j = 25 <= 70.7) over the chords' length.
  const double a = 1000, j = 40000, R = 5;
  Program p;
  p.files = {"arc.ngc"};
  Block b = line({R, 0, 0}, {-R, 0, 0}, 6000);
  b.kind = MotionKind::Arc;
  b.center_mm = Eigen::Vector3d::Zero();
  b.normal = Eigen::Vector3d::UnitZ();
  p.blocks.push_back(b);
  std::vector<PoseSample> s;
  double L = 0;
  for (int k = 0; k <= 1000; ++k) {
    const double phi = M_PI * k / 1000;
    s.push_back(sample({R * std::cos(phi), R * std::sin(phi), 0}, Eigen::Vector3d::UnitZ(), k == 0 ? -1 : 0));
    if (k > 0) L += (s[k].pose.tip_mm - s[k - 1].pose.tip_mm).norm();
  }
  const FeedPlan plan = plan_feed(p, s, nullptr, limits(a, j));
  expect_relative(plan.cycle_time_s, full_limits_time(L, std::sqrt(a * R), a, j), kClosedForm, "arc");
}

TEST(FeedLookahead, ShortCollinearBlocksReachCruise) {
  // 2000 blocks of 0.05 mm: each far too short to reach 50 mm/s from rest (that takes
  // 3.75 mm), yet the whole run times as one block of 100 mm.
  const double v = 50, a = 1000, j = 40000;
  std::vector<Eigen::Vector3d> pts;
  for (int k = 0; k <= 2000; ++k) pts.push_back(Eigen::Vector3d(0.05 * k, 0, 0));
  const Program p = polyline(pts, v * 60);
  const FeedPlan plan = plan_feed(p, straight_samples(p, 2), nullptr, limits(a, j));
  expect_relative(plan.cycle_time_s, full_limits_time(100, v, a, j), kClosedForm, "as one block");
  expect_relative(plan.speed_mm_per_s[2000], v, kClosedForm, "cruise in the middle");
}

TEST(FeedLookahead, GentleCornersDoNotSlowThePath) {
  // 500 blocks of 0.2 mm turning 1 deg each way. The blend rule allows sqrt(a R) with
  // R = min(tol cos(theta/2)/(1 - cos(theta/2)), 0.1 mm / tan(theta/2)) = 11.5 mm: 107 mm/s,
  // above F, so the corners do not bind and the run times as one block of 100 mm.
  const double v = 50, a = 1000, j = 40000;
  std::vector<Eigen::Vector3d> pts = {Eigen::Vector3d::Zero()};
  for (int k = 0; k < 500; ++k) {
    const double h = (k % 2 ? 0.5 : -0.5) * M_PI / 180;
    pts.push_back(pts.back() + 0.2 * Eigen::Vector3d(std::cos(h), std::sin(h), 0));
  }
  const Program p = polyline(pts, v * 60);
  const FeedPlan plan = plan_feed(p, straight_samples(p, 1), nullptr, limits(a, j));
  expect_relative(plan.cycle_time_s, full_limits_time(100, v, a, j), kClosedForm, "as one block");
}

TEST(FeedLookahead, LongerWindowsAreNeverSlower) {
  // Blocks of 0.5 mm turning 20 deg each way: the blend rule (tol 0.01 mm) allows
  // sqrt(a R), R = 0.01 cos(10 deg) / (1 - cos(10 deg)) = 0.648 mm: 25.5 mm/s < F. A window
  // of one or two blocks assumes a stop 0.5 to 1 mm ahead, and from 25.5 mm/s braking takes
  // 25.5/2 (25.5/a + a/j) = 0.64 mm in one S-curve, more across blocks: short windows are
  // slower; once the window holds the whole program, longer ones change nothing.
  const double v = 50, a = 1000, j = 40000;
  std::vector<Eigen::Vector3d> pts = {Eigen::Vector3d::Zero()};
  for (int k = 0; k < 400; ++k) {
    const double h = (k % 2 ? 10.0 : -10.0) * M_PI / 180;
    pts.push_back(pts.back() + 0.5 * Eigen::Vector3d(std::cos(h), std::sin(h), 0));
  }
  const Program p = polyline(pts, v * 60);
  const std::vector<PoseSample> s = straight_samples(p, 1);
  const double corner = std::sqrt(a * 0.01 * std::cos(M_PI / 18) / (1 - std::cos(M_PI / 18)));
  std::vector<double> times;
  for (int w : {1, 2, 4, 16, 64, 400, 100000}) {
    FeedSettings fs = limits(a, j);
    fs.lookahead_blocks = w;
    const FeedPlan plan = plan_feed(p, s, nullptr, fs);
    if (!times.empty()) {
      EXPECT_LE(plan.cycle_time_s, times.back() * (1 + kClosedForm)) << "window " << w;
    }
    times.push_back(plan.cycle_time_s);
    for (size_t i = 1; i + 1 < s.size(); ++i) {
      EXPECT_GT(plan.speed_mm_per_s[i], 0.0) << "window " << w;
      EXPECT_LE(plan.speed_mm_per_s[i], corner * (1 + kLimit)) << "window " << w;
    }
    if (w >= 400) expect_relative(plan.speed_mm_per_s[200], corner, kClosedForm, "corner speed mid-program");
  }
  EXPECT_GT(times.front(), times.back() * 1.01);  // one block of look-ahead costs time
  expect_relative(times[5], times[6], kClosedForm, "window beyond the program");
}

}  // namespace
}  // namespace vcut::kinematics

namespace vcut::kinematics {
namespace {

// PathCursor: the path between the samples, at any instant. One 100 mm line from rest at
// 100 mm/s, a = 1000 mm/s^2, j = 1e5 mm/s^3, cut into 4 samples. The first jerk phase lasts
// a/j = 0.01 s with s(t) = j t^3 / 6 (closed form); the cruise at v; the samples' own instants
// map onto the samples; the fraction within a move is (s - s_start) / 25.
TEST(PathCursor, FollowsTheSCurveBetweenSamples) {
  const Program p = polyline({{0, 0, 0}, {100, 0, 0}}, 6000.0);
  const std::vector<PoseSample> s = straight_samples(p, 4);
  FeedSettings settings;
  settings.path_acceleration_mm_per_s2 = 1000.0;
  settings.path_jerk_mm_per_s3 = 1e5;
  const FeedPlan plan = plan_feed(p, s, nullptr, settings);
  PathCursor cursor(plan);
  const auto s_at = [&](double t) {
    const PathPosition at = cursor.at(t);
    return 25.0 * (static_cast<double>(at.segment) - 1.0 + at.fraction);
  };
  for (double t : {0.0, 0.002, 0.005, 0.0099}) EXPECT_NEAR(s_at(t), 1e5 * t * t * t / 6.0, kClosedForm * 100.0);
  // Acceleration over: v = a^2/(2j) + a (t - a/j) at the end of the constant-acceleration
  // phase (0.1 - a/j long); cruise from then at 100 mm/s: compare two instants in cruise.
  const double t0 = plan.cycle_time_s / 2.0 - 0.05;
  EXPECT_NEAR(s_at(t0 + 0.1) - s_at(t0), 10.0, kClosedForm * 100.0);
  for (size_t i = 1; i < s.size(); ++i)  // back in time: the cursor restarts
    EXPECT_NEAR(s_at(plan.t_s[i]), 25.0 * static_cast<double>(i), 1e-9);
  EXPECT_NEAR(s_at(plan.cycle_time_s + 1.0), 100.0, 1e-12);  // held after the end
}

}  // namespace
}  // namespace vcut::kinematics
