// The interpolator (kinematics/interpolator.h): the command every period along the timed
// path and the contour error against each block's true path.
//
// A loop with Kv = 0 and full velocity feed-forward, first order, moves by exactly the
// command's last increment every period: x[k+1] = x[k] + (c[k] - c[k-1]) with x[0] = c[0] -
// the actual axes are the command one period late, to rounding (the model's equations, not
// the code's). So the actual tip lies on the commanded curve at every instant and the contour
// error must vanish there, whatever the densification - if the curve is the machine's (an
// axis block's tip runs on a circle when C turns), not the densified chords.
#include "vcut/kinematics/interpolator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "axis_specs.h"

namespace vcut::kinematics {
namespace {

constexpr double kRounding = 1e-9;  // mm: forward kinematics and the golden section's end

using test::linear;
using test::rotary;

// A table-table AC, C about the z axis through the origin; the tool 0 mm from the nose.
Machine table_table() {
  MachineSpec s;
  s.name = "tt";
  s.topology = "WCAFXYZT";
  s.axes = {linear('X', {1, 0, 0}), linear('Y', {0, 1, 0}), linear('Z', {0, 0, 1}), rotary('A', {1, 0, 0}, {0, 0, 0}),
            rotary('C', {0, 0, 1}, {0, 0, 0})};
  return Machine(s);
}

// One program densified, timed and ready for the interpolator (tools 0 mm from the nose).
struct Timed {
  Densified densified;
  FeedPlan plan;
  std::vector<double> lengths;
  InterpolatorInput input;

  Timed(const Program& program, const Machine& m, const DensifySettings& settings) {
    DensifyMachine dm;
    dm.machine = &m;
    densified = densify(program, settings, dm);
    plan = plan_feed(program, densified.samples, &m, FeedSettings{});
    lengths.assign(densified.samples.size(), 0.0);
    input.program = &program;
    input.samples = &densified.samples;
    input.blocks = &densified.blocks;
    input.feed = &plan;
    input.machine = &m;
    input.tool_length_mm = &lengths;
  }
  Timed(const Timed&) = delete;
};

TEST(Interpolator, AxisBlockContourIsAgainstTheMachinesCurve) {
  const Machine m = table_table();
  // Axis program: at X28, C turns 0 -> 90 deg (the tip on a quarter circle of radius 28 in
  // the part), F 1000 deg/min.
  Program program;
  program.files = {"ring.ngc"};
  Block b;
  b.tool_pose = false;
  b.start_mm = b.end_mm = {28, 0, 0};
  b.start_rotary.given = {true, false, true};
  b.end_rotary.given = {true, false, true};
  b.end_rotary.angle_rad = {0.0, 0.0, M_PI / 2};
  b.feed_mm_per_min = 1000.0;
  b.source.line = 4;
  program.blocks.push_back(b);

  DensifySettings coarse;
  coarse.angle_step_rad = 30.0 * M_PI / 180.0;  // q = 3: chords 28 (1 - cos 15 deg) = 0.95 mm inside
  Timed timed(program, m, coarse);
  const Densified& d = timed.densified;
  ASSERT_EQ(d.samples.size(), 4u);
  InterpolatorInput& in = timed.input;
  in.servo.period_s = 0.001;
  ServoAxis delay;
  delay.kv_per_s = 0.0;
  delay.omega_n_per_s = 0.0;
  delay.feed_forward = 1.0;
  in.servo.axes = {delay};
  in.commanded_pose = true;

  std::vector<PeriodSample> periods;
  double polyline_worst = 0.0;
  const std::size_t count = for_each_period(in, [&](const PeriodSample& p) {
    if (p.stamp >= 0 || p.peak) return;
    periods.push_back(p);
    // The same tip against the chords: what a densified-polyline contour would read.
    double best = 1e9;
    for (std::size_t k = 1; k < d.samples.size(); ++k) {
      const Eigen::Vector3d a = d.samples[k - 1].pose.tip_mm, c = d.samples[k].pose.tip_mm;
      const double t = std::clamp((p.actual_pose.tip_mm - a).dot(c - a) / (c - a).squaredNorm(), 0.0, 1.0);
      best = std::min(best, (p.actual_pose.tip_mm - (a + t * (c - a))).norm());
    }
    polyline_worst = std::max(polyline_worst, best);
  });
  // 90 deg at 1000 deg/min: 5.4 s, at least 5,400 periods.
  ASSERT_GT(count, 5400u);
  ASSERT_EQ(periods.size(), count);
  for (std::size_t k = 1; k < periods.size(); ++k) {
    // One period late, and on the circle of radius 28.
    EXPECT_NEAR((periods[k].actual - periods[k - 1].commanded).cwiseAbs().maxCoeff(), 0.0, kRounding) << k;
    EXPECT_NEAR(periods[k].actual_pose.tip_mm.head<2>().norm(), 28.0, kRounding) << k;
    EXPECT_LT(periods[k].contour_error_mm, kRounding) << k;
    EXPECT_NEAR(periods[k].commanded_pose.tip_mm.head<2>().norm(), 28.0, kRounding) << k;
  }
  EXPECT_GT(polyline_worst, 0.9);  // the chords would have read the densification
}

// The loop state between instants (ServoLoop::within_last_period) against the instants, and
// the settling: the loops run on after the program until every axis is at rest on the end.
TEST(Interpolator, SettlesOnTheEnd) {
  const Machine m = table_table();
  Program program;
  program.files = {"line.ngc"};
  Block b;
  b.start_mm = {0, 0, 0};
  b.end_mm = {50, 0, 0};
  b.feed_mm_per_min = 3000.0;
  program.blocks.push_back(b);
  Timed timed(program, m, DensifySettings{});
  const Densified& d = timed.densified;
  const FeedPlan& plan = timed.plan;
  InterpolatorInput& in = timed.input;
  in.servo.axes = {ServoAxis{}};  // seed 004's loop, 5 ms
  PeriodSample last;
  double t_prev = -1.0;
  for_each_period(in, [&](const PeriodSample& p) {
    if (p.peak) return;
    EXPECT_GE(p.t_s, t_prev);  // time order
    t_prev = p.t_s;
    last = p;
  });
  EXPECT_GT(last.t_s, plan.cycle_time_s);
  EXPECT_NEAR((last.actual - d.samples.back().axes).cwiseAbs().maxCoeff(), 0.0, in.settle_tolerance);
  EXPECT_NEAR(last.actual_pose.tip_mm.x(), 50.0, in.settle_tolerance);
}

}  // namespace
}  // namespace vcut::kinematics
