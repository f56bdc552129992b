// The machine check's ground (machine_check.h) against forward kinematics and the pose engine:
// the bound its continuous part rests on (motion_bound_mm: on every bundled machine, for each
// node, random axis steps and random points of a sphere on the node never move apart faster
// than the bound says, |p(t) - p(s)| <= M |t - s|), and the playback's frames.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "vcut/io/job.h"
#include "vcut/io/machine_file.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/pipeline/machine_check.h"
#include "vcut/pipeline/poses.h"

namespace {

using vcut::kinematics::AxisValues;
using vcut::kinematics::Machine;

// Node coordinates (the frame at all-zero axes) -> F at q, by forward kinematics.
Eigen::Isometry3d node_frame(const Machine& m, const AxisValues& q, char node) {
  for (const auto& n : vcut::kinematics::node_frames(m, q))
    if (n.node == node) return n.pose;
  ADD_FAILURE() << "no node " << node;
  return Eigen::Isometry3d::Identity();
}

TEST(MachineMotionBound, NoPointOfANodeOutrunsIt) {
  std::mt19937 rng(25);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double tightest = 0.0;  // the largest observed speed / bound: how sharp the bound is
  for (const char* name :
       {"table-table-ac", "table-table-bc", "xyzac-trt", "head-table-bc", "head-head-ac", "gantry-wyxzcat", "3axis"}) {
    SCOPED_TRACE(name);
    const Machine m(vcut::io::read_machine_file(vcut::io::resolve_machine(name)));
    std::string nodes = m.axis_letters() + "FWT";
    for (int trial = 0; trial < 20; ++trial) {
      AxisValues q0 = m.zero(), q1 = m.zero();
      for (int k = 0; k < m.axis_count(); ++k) {
        const bool rotary = m.axis(k).kind == vcut::kinematics::AxisKind::Rotary;
        q0[k] = rotary ? unit(rng) * M_PI : unit(rng) * 300.0;
        q1[k] = q0[k] + (rotary ? unit(rng) * 0.6 : unit(rng) * 100.0);  // up to 34 deg, 100 mm
      }
      for (char node : nodes) {
        // A sphere of radius 50..250 mm somewhere within 600 mm of the frame's origin at zero.
        const Eigen::Vector3d centre_node(unit(rng) * 600.0, unit(rng) * 600.0, unit(rng) * 600.0);
        const double radius = 150.0 + 100.0 * unit(rng);
        const Eigen::Vector3d centre_f0 = node_frame(m, q0, node) * centre_node;
        const double bound = vcut::pipeline::motion_bound_mm(m, node, centre_f0, radius, q0, q1);
        for (int point = 0; point < 6; ++point) {
          Eigen::Vector3d d(unit(rng), unit(rng), unit(rng));
          if (d.norm() < 1e-3) continue;
          const Eigen::Vector3d p = centre_node + radius * d.normalized() * std::abs(unit(rng));
          constexpr int kSteps = 64;
          std::vector<Eigen::Vector3d> path;
          for (int i = 0; i <= kSteps; ++i) {
            const double t = static_cast<double>(i) / kSteps;
            path.push_back(node_frame(m, (1.0 - t) * q0 + t * q1, node) * p);
          }
          for (int i = 0; i < kSteps; ++i)
            for (int j : {i + 1, kSteps}) {
              const double dt = static_cast<double>(j - i) / kSteps;
              const double moved = (path[static_cast<std::size_t>(j)] - path[static_cast<std::size_t>(i)]).norm();
              ASSERT_LE(moved, bound * dt + 1e-9) << "node " << node << " trial " << trial;
              if (bound > 1e-9) tightest = std::max(tightest, moved / (bound * dt));
            }
        }
      }
    }
  }
  // A bound a hundred times too loose would still pass the check above: it must also be sharp
  // enough to be useful (for the halving to stop and poses to be skipped).
  EXPECT_GT(tightest, 0.3);
}

}  // namespace

namespace {

using vcut::pipeline::Playback;

// A frame's pose of slot k (machine_check.h: 12 floats, [R | t] row by row).
Eigen::Isometry3d frame_pose(const Playback& p, std::size_t frame, std::size_t k) {
  const float* f = p.frame_pose.data() + frame * p.floats_per_pose() + 12 * k;
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m.matrix()(r, c) = f[4 * r + c];
  return m;
}

vcut::pipeline::PoseRun run_of(const vcut::io::Job& job) {
  return vcut::pipeline::run_pose_engine(job, vcut::pipeline::read_job_program(job), job.resolution_mm);
}

}  // namespace

// The playback's frames (the report page poses the machine with them) against the pose
// engine: the tool's node, posed by forward kinematics, carries the gauge point less the tool
// length to the programmed tip and the spindle axis to the programmed tool axis, at every
// sample of an axis program (table-table-ac, the rotary table turning) and of a five-axis TCP
// program (the S-piece on its machine, also with its programming zero moved off the table's
// centre).
TEST(MachinePlayback, FramesPoseTheToolAtTheProgrammedTip) {
  for (const char* file :
       {"/examples/machine-collision/job.yaml", "/examples/s-piece/job.yaml", "/examples/s-piece/job.yaml+"}) {
    SCOPED_TRACE(file);
    std::string path = std::string(VCUT_SOURCE_DIR) + file;
    const bool moved = path.back() == '+';
    if (moved) path.pop_back();
    vcut::io::Job job = vcut::io::read_job(path);
    if (moved) job.machine_spec.workpiece_origin_mm = Eigen::Vector3d(15.0, -25.0, 40.0);
    const vcut::pipeline::PoseRun run = run_of(job);
    vcut::pipeline::MachineCheckOptions options;
    options.playback_frames = run.poses;  // every sample
    const Playback p = vcut::pipeline::check_machine(job, run, options).playback;
    const auto& samples = run.densified.samples;
    ASSERT_EQ(p.frame_sample.size(), samples.size());
    ASSERT_EQ(p.path_block.size(), samples.size());
    const auto t = std::find(p.nodes.begin(), p.nodes.end(), 'T');
    ASSERT_NE(t, p.nodes.end());
    const auto& spec = run.machine->spec();
    double worst_tip_mm = 0.0, worst_axis = 0.0;
    for (std::size_t f = 0; f < samples.size(); ++f) {
      ASSERT_EQ(p.frame_sample[f], f);
      const int block = samples[f].block;
      const int tool = block < 0 ? 0 : run.program.blocks[static_cast<std::size_t>(block)].tool;
      const auto length = run.densify_machine.tool_length_mm.find(tool);
      const double length_mm = length == run.densify_machine.tool_length_mm.end() ? 0.0 : length->second;
      EXPECT_EQ(p.frame_block[f], block);
      EXPECT_EQ(p.frame_tool[f], tool);
      if (block < 0) continue;  // the start: no block, no tool shown
      const Eigen::Isometry3d pose = frame_pose(p, f, static_cast<std::size_t>(t - p.nodes.begin()));
      const Eigen::Vector3d tip = pose * (spec.gauge_point_mm - length_mm * spec.spindle_axis);
      worst_tip_mm = std::max(worst_tip_mm, (tip - samples[f].pose.tip_mm).norm());
      worst_axis = std::max(worst_axis, (pose.linear() * spec.spindle_axis - samples[f].pose.axis).norm());
      const Eigen::Vector3d path(p.path_mm[3 * f], p.path_mm[3 * f + 1], p.path_mm[3 * f + 2]);
      EXPECT_LT((path - samples[f].pose.tip_mm).norm(), 1e-3);
    }
    // Floats: 1e-7 relative of positions up to about 1,000 mm.
    EXPECT_LT(worst_tip_mm, 2e-3);
    EXPECT_LT(worst_axis, 1e-5);
    // The bodies: everything checked but the stock, on the nodes listed.
    for (const Playback::Body& b : p.bodies) {
      EXPECT_NE(b.kind, vcut::pipeline::BodyKind::Stock);
      EXPECT_LT(static_cast<std::size_t>(b.node), p.nodes.size());
    }
  }
}

// Fewer frames than samples: sample p * n / max for p < max, and the last; the tool path ten
// times as dense.
TEST(MachinePlayback, FramesSpreadEvenlyOverTheSamples) {
  const vcut::io::Job job = vcut::io::read_job(std::string(VCUT_SOURCE_DIR) + "/examples/s-piece/job.yaml");
  const vcut::pipeline::PoseRun run = run_of(job);
  const std::size_t n = run.poses, max = 37;
  ASSERT_GT(n, 10 * max);
  vcut::pipeline::MachineCheckOptions options;
  options.playback_frames = max;
  const Playback p = vcut::pipeline::check_machine(job, run, options).playback;
  ASSERT_EQ(p.frame_sample.size(), max + 1);
  for (std::size_t k = 0; k < max; ++k) EXPECT_EQ(p.frame_sample[k], k * n / max);
  EXPECT_EQ(p.frame_sample.back(), n - 1);
  EXPECT_EQ(p.path_block.size(), 10 * max + 1);
  EXPECT_EQ(p.frame_pose.size(), (max + 1) * p.floats_per_pose());
  const auto& last = run.densified.samples.back().pose.tip_mm;
  EXPECT_LT((Eigen::Vector3d(p.path_mm[p.path_mm.size() - 3], p.path_mm[p.path_mm.size() - 2], p.path_mm.back()) - last)
                .norm(),
            1e-3);
}
