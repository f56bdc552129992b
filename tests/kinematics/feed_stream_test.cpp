// The streamed feed plan (stream_feed: two densifiers, a bounded look-ahead) against the
// plan over the whole program held at once (densify, then plan_feed): the two compute the same
// steps in the same order, so every sample's time and speed, every block's time and
// axis-limited flag and the cycle time must be the same bytes. The programs mix what changes
// the spans (corners, exact stops, blend tolerances, rapids, G93, arcs, blocks that do not
// move, rotations with the tip still) and the look-ahead is as short as one span, so that the
// windows close and the spans are timed and dropped many times within a program.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "test_machines.h"
#include "vcut/kinematics/densify.h"
#include "vcut/kinematics/feed_planner.h"

namespace vcut::kinematics {
namespace {

struct Streamed {
  std::vector<PoseSample> samples;
  std::vector<double> t_s, speed;
  std::vector<double> block_time_s;
  std::vector<int> q;
  std::vector<bool> axis_limited;
  double cycle_time_s = 0.0;
};

Streamed stream(const Program& p, const DensifySettings& ds, const DensifyMachine& dm, const FeedSettings& fs) {
  Streamed out;
  FeedStreamVisitor visit;
  visit.sample = [&](std::size_t i, const PoseSample& s, double t, double v) {
    EXPECT_EQ(i, out.samples.size());
    out.samples.push_back(s);
    out.t_s.push_back(t);
    out.speed.push_back(v);
  };
  visit.block = [&](std::size_t b, const BlockReport& r, double time_s, bool limited) {
    EXPECT_EQ(b, out.block_time_s.size());
    out.block_time_s.push_back(time_s);
    out.q.push_back(r.q);
    out.axis_limited.push_back(limited);
  };
  out.cycle_time_s = stream_feed(p, ds, dm, fs, visit);
  return out;
}

// Both ways on one program: the same bytes.
void expect_same(const Program& p, const DensifySettings& ds, const DensifyMachine& dm, const FeedSettings& fs,
                 const std::string& what) {
  const Densified d = densify(p, ds, dm);
  const FeedPlan plan = plan_feed(p, d.samples, dm.machine, fs);
  const Streamed s = stream(p, ds, dm, fs);
  ASSERT_EQ(s.samples.size(), d.samples.size()) << what;
  for (std::size_t i = 0; i < d.samples.size(); ++i) {
    ASSERT_EQ(s.samples[i].pose.tip_mm, d.samples[i].pose.tip_mm) << what << " sample " << i;
    ASSERT_EQ(s.samples[i].pose.axis, d.samples[i].pose.axis) << what << " sample " << i;
    ASSERT_EQ(s.samples[i].block, d.samples[i].block) << what << " sample " << i;
    ASSERT_EQ(s.t_s[i], plan.t_s[i]) << what << " sample " << i;
    ASSERT_EQ(s.speed[i], plan.speed_mm_per_s[i]) << what << " sample " << i;
  }
  ASSERT_EQ(s.block_time_s.size(), p.blocks.size()) << what;
  std::vector<bool> limited(p.blocks.size(), false);
  for (int i : plan.axis_limited_samples)
    limited[static_cast<std::size_t>(d.samples[static_cast<std::size_t>(i)].block)] = true;
  for (std::size_t b = 0; b < p.blocks.size(); ++b) {
    EXPECT_EQ(s.block_time_s[b], plan.block_time_s[b]) << what << " block " << b;
    EXPECT_EQ(s.q[b], d.blocks[b].q) << what << " block " << b;
    EXPECT_EQ(s.axis_limited[b], limited[b]) << what << " block " << b;
  }
  EXPECT_EQ(s.cycle_time_s, plan.cycle_time_s) << what;
}

// A random three-axis program: lines with corners of every angle, helical arcs, rapids, exact
// stops, G64 P, G93 blocks, repeated points (blocks that do not move) and collinear runs
// (long spans).
Program random_program(std::mt19937& rng, int blocks) {
  std::uniform_real_distribution<double> unit(0.0, 1.0), turn(-2.5, 2.5), length(0.05, 6.0);
  Program p;
  p.files = {"random.ngc"};
  Eigen::Vector3d at(0, 0, 5);
  double heading = 0.0;
  for (int k = 0; k < blocks; ++k) {
    Block b;
    b.start_mm = at;
    const double kind = unit(rng);
    if (unit(rng) < 0.6) heading += turn(rng);  // else collinear with the last
    const Eigen::Vector3d dir(std::cos(heading), std::sin(heading), 0.05 * turn(rng));
    if (kind < 0.1) {
      b.kind = MotionKind::Rapid;
      b.end_mm = at + 3.0 * length(rng) * dir;
    } else if (kind < 0.25) {
      // A helical arc in G17 about a centre beside the start.
      b.kind = MotionKind::Arc;
      b.center_mm = at + Eigen::Vector3d(length(rng), 0.0, 0.0);
      b.normal = unit(rng) < 0.5 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
      const double r = (at - b.center_mm).head<2>().norm(), a = 3.0 * unit(rng);
      b.end_mm = b.center_mm + Eigen::Vector3d(-r * std::cos(a), r * std::sin(a) * b.normal.z(), 0.3 * turn(rng));
      b.end_mm.z() = at.z() + 0.3 * turn(rng);
    } else if (kind < 0.3) {
      b.kind = MotionKind::Linear;
      b.end_mm = at;  // does not move
    } else {
      b.kind = MotionKind::Linear;
      b.end_mm = at + length(rng) * dir;
    }
    if (b.kind != MotionKind::Rapid) {
      b.feed_mm_per_min = 300.0 + 5000.0 * unit(rng);
      if (unit(rng) < 0.1) b.feed_mode = FeedMode::InverseTime, b.feed_mm_per_min = 5.0 + 200.0 * unit(rng);
    }
    b.exact_stop = unit(rng) < 0.08;
    b.blend_tolerance_mm = unit(rng) < 0.3 ? 0.1 * unit(rng) : -1.0;
    b.source = {0, k + 1};
    at = b.end_mm;
    p.blocks.push_back(b);
  }
  return p;
}

// X slow and Y with a low acceleration: axis limits set the speed on some blocks.
Machine slow_xyz() {
  MachineSpec s =
      spec("xyz", "WFXYZT",
           {linear('X', Eigen::Vector3d::UnitX(), -1000, 1000), linear('Y', Eigen::Vector3d::UnitY(), -1000, 1000),
            linear('Z', Eigen::Vector3d::UnitZ(), -1000, 1000)});
  s.axes[0].max_velocity_per_s = 40.0;
  s.axes[1].max_acceleration_per_s2 = 300.0;
  s.axes[2].max_jerk_per_s3 = 20000.0;
  return Machine(s);
}

TEST(StreamedFeed, SameBytesAsThePlanOnRandomPrograms) {
  std::mt19937 rng(22);
  const Machine m = slow_xyz();
  DensifyMachine dm;
  dm.machine = &m;
  for (int trial = 0; trial < 24; ++trial) {
    const Program p = random_program(rng, 120 + 40 * (trial % 4));
    DensifySettings ds;
    if (trial % 2 == 0) {
      ds.tolerance_mm = 0.005;  // vcut's default: to the tolerance, arcs by their chords too
      ds.arcs_by_chord = true;
      ds.chord_tolerance_mm = 0.002;
    } else {
      ds.step_mm = 0.7;  // several samples a block
    }
    FeedSettings fs;
    fs.path_acceleration_mm_per_s2 = 1500.0;
    fs.path_jerk_mm_per_s3 = 40000.0;
    fs.timing = false;
    // Windows of 1, 2, 3 ... spans, and one longer than the program.
    fs.lookahead_blocks = trial % 6 == 5 ? 1000 : 1 + trial % 6;
    if (trial % 3 == 1) fs.end_speed_mm_per_s = 5.0, fs.start_speed_mm_per_s = 2.0;
    expect_same(p, ds, dm, fs, "trial " + std::to_string(trial));
  }
}

// Five-axis tool poses on the AC trunnion: the inverse kinematics of every sample follows the
// previous one (the second densifier must make the same choices), rotations with the tip
// still are timed in degrees, and the rotary axes' limits bind.
TEST(StreamedFeed, SameBytesAsThePlanOnATurningTool) {
  MachineSpec trt = machines()[1];
  for (AxisSpec& a : trt.axes)
    if (a.kind == AxisKind::Rotary) a.max_velocity_per_s = 0.5, a.max_acceleration_per_s2 = 4.0;
  const Machine m(trt);
  DensifyMachine dm;
  dm.machine = &m;
  dm.tool_length_mm = {{1, 30.0}};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Program p;
  p.files = {"five.apt"};
  Eigen::Vector3d at(0, 0, 10), axis = Eigen::Vector3d::UnitZ();
  for (int k = 0; k < 150; ++k) {
    Block b;
    b.start_mm = at;
    b.start_axis = axis;
    const double a = 40.0 * kDeg * unit(rng), c = 2.0 * M_PI * unit(rng);
    b.end_axis =
        unit(rng) < 0.3 ? axis : Eigen::Vector3d(std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a));
    b.end_mm = unit(rng) < 0.15
                   ? at
                   : Eigen::Vector3d(at + Eigen::Vector3d(4 * unit(rng) - 2, 4 * unit(rng) - 2, unit(rng) - 0.5));
    b.kind = unit(rng) < 0.1 ? MotionKind::Rapid : MotionKind::Linear;
    b.feed_mm_per_min = b.kind == MotionKind::Rapid ? 0.0 : 500.0 + 3000.0 * unit(rng);
    b.orientation = unit(rng) < 0.3 ? OrientationMode::Axes : OrientationMode::Vector;
    b.tool = 1;
    b.source = {0, k + 1};
    at = b.end_mm;
    axis = b.end_axis;
    p.blocks.push_back(b);
  }
  for (int w : {1, 2, 5, 1000}) {
    DensifySettings ds;
    ds.tolerance_mm = 0.01;
    ds.cutter_length_mm = 20.0;
    ds.cutter_radius_mm = 5.0;
    FeedSettings fs;
    fs.timing = false;
    fs.lookahead_blocks = w;
    expect_same(p, ds, dm, fs, "window " + std::to_string(w));
  }
}

// The densifier alone, rewound: the same samples a second time.
TEST(StreamedFeed, DensifierRewoundGivesTheSameSamples) {
  std::mt19937 rng(3);
  const Program p = random_program(rng, 200);
  DensifySettings ds;
  ds.step_mm = 0.5;
  Densifier d(p, ds, DensifyMachine{});
  std::vector<PoseSample> first, second;
  BlockReport r;
  while (!d.done()) d.next_block(first, r);
  d.rewind();
  EXPECT_EQ(d.last().pose.tip_mm, p.blocks.front().start_mm);
  while (!d.done()) d.next_block(second, r);
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i].pose.tip_mm, second[i].pose.tip_mm) << i;
}

}  // namespace
}  // namespace vcut::kinematics
