// The bound the machine check's continuous part rests on (machine_check.h, motion_bound_mm),
// against forward kinematics: on every bundled machine, for each node, random axis steps and
// random points of a sphere on the node, the points' positions along the linear axis path
// never move apart faster than the bound says: |p(t) - p(s)| <= M |t - s|.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "vcut/io/machine_file.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/pipeline/machine_check.h"

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
