// The six bundled machines, read from examples/machines as a user's job reads them: 10^4
// random axis vectors within limits each, IK(FK(q)) contains q and FK(IK(pose)) = pose
// (issue #3). The reference is the axis vector itself and the pose it made.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "vcut/io/machine_file.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/inverse_kinematics.h"

namespace {

using namespace vcut::kinematics;

// 1e-9 mm / 1e-9 rad: the bound; rounding on 3 m chains is ~1e-12.
constexpr double kRoundTrip = 1e-9;

class BundledMachine : public ::testing::TestWithParam<const char*> {};

TEST_P(BundledMachine, InverseOfForwardContainsTheAxesAndComesBack) {
  const std::string path = vcut::io::resolve_machine(GetParam());
  ASSERT_NE(path, GetParam()) << "not a bundled machine";
  std::vector<std::string> warnings;
  const Machine m(vcut::io::read_machine_file(path, &warnings));
  EXPECT_TRUE(warnings.empty());
  std::mt19937 rng(101);
  int singular = 0;
  for (int n = 0; n < 10000; ++n) {
    AxisValues q = m.zero();
    for (int i = 0; i < m.axis_count(); ++i) {
      const AxisSpec& a = m.axis(i);
      q[i] = a.limits ? std::uniform_real_distribution<double>(a.limits->first, a.limits->second)(rng)
                      : std::uniform_real_distribution<double>(-4 * M_PI, 4 * M_PI)(rng);
    }
    const double length = std::uniform_real_distribution<double>(0.0, 100.0)(rng);
    const ToolPose pose = forward(m, q, length);
    bool at_pole = false;
    if (m.rotary_count() == 2)
      at_pole = std::abs(pose.axis.dot(m.axis(m.rotary_axis(0)).direction)) >= std::cos(m.spec().singularity_angle_rad);
    singular += at_pole;
    const IkResult r = inverse(m, pose, length, at_pole ? &q : nullptr);
    ASSERT_TRUE(r.ok()) << GetParam() << " sample " << n << ": " << r.reason;
    double nearest = 1e300;
    for (const IkSolution& s : r.solutions) {
      double d = 0.0;
      for (int i = 0; i < m.axis_count(); ++i) {
        double diff = s.q[i] - q[i];
        if (m.axis(i).kind == AxisKind::Rotary && !m.axis(i).limits) diff = std::remainder(diff, 2 * M_PI);
        d = std::max(d, std::abs(diff));
      }
      nearest = std::min(nearest, d);
      if (!s.within_limits) continue;
      const ToolPose back = forward(m, s.q, length);
      EXPECT_LT((back.tip_mm - pose.tip_mm).norm(), kRoundTrip) << GetParam() << " sample " << n;
      EXPECT_LT((back.axis - pose.axis).norm(), kRoundTrip) << GetParam() << " sample " << n;
    }
    EXPECT_LT(nearest, kRoundTrip) << GetParam() << " sample " << n << ": IK(FK(q)) lacks q";
  }
  EXPECT_LT(singular, 100);
}

INSTANTIATE_TEST_SUITE_P(Examples, BundledMachine,
                         ::testing::Values("3axis", "table-table-ac", "table-table-bc", "head-table-bc", "head-head-ac",
                                           "gantry-wyxzcat", "xyzac-trt"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& c : n)
                             if (c == '-') c = '_';
                           return n;
                         });

}  // namespace
