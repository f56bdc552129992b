// Five-axis densification (issue #5 item 1): ORIVECT, ORIAXES and cone orientation, axis
// programs and their non-linear tip error, q from lambda and phi, and the tolerance mode.
// References: the great-circle and cone geometry, and the table-table AC trunnion's closed
// form (u = (sin a sin c, sin a cos c, cos a), the tip turned about the A and C lines,
// derived in forward_kinematics_test.cpp), evaluated here by hand, never through densify.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

#include "test_machines.h"
#include "vcut/kinematics/densify.h"

namespace vcut::kinematics {
namespace {

constexpr double kExact = 1e-9;  // mm and unit-vector components after a few chained rotations

Eigen::Matrix3d rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
Eigen::Matrix3d rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

// machines()[1]: table-table AC, A about x through (0, 20, 10), C about z through 0, spindle
// nose (0, 0, 150), programming zero (5, -3, 40).
const Eigen::Vector3d kCenterA(0, 20, 10), kGauge(0, 0, 150), kOrigin(5, -3, 40);

Eigen::Vector3d trt_axis(double a, double c) {
  return {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
}

// The tip in the workpiece frame for tool tip t in the frame: W is turned by Rx(a) about
// the A line after Rz(c) about the C line (through the origin).
Eigen::Vector3d trt_tip(double a, double c, const Eigen::Vector3d& t) {
  return rz(-c) * (rx(-a) * (t - kCenterA) + kCenterA) - kOrigin;
}

Block tool_pose_block(Eigen::Vector3d p0, Eigen::Vector3d u0, Eigen::Vector3d p1, Eigen::Vector3d u1,
                      OrientationMode mode = OrientationMode::Vector) {
  Block b;
  b.kind = MotionKind::Linear;
  b.start_mm = p0;
  b.end_mm = p1;
  b.start_axis = u0.normalized();
  b.end_axis = u1.normalized();
  b.orientation = mode;
  b.feed_mm_per_min = 1000;
  return b;
}

// An axis-program block on the AC trunnion: X Y Z programmed points, A and C in rad.
Block axis_block(Eigen::Vector3d p0, double a0, double c0, Eigen::Vector3d p1, double a1, double c1) {
  Block b;
  b.kind = MotionKind::Linear;
  b.tool_pose = false;
  b.start_mm = p0;
  b.end_mm = p1;
  b.start_rotary.angle_rad = {a0, 0.0, c0};
  b.start_rotary.given = {true, false, true};
  b.end_rotary.angle_rad = {a1, 0.0, c1};
  b.end_rotary.given = {true, false, true};
  b.feed_mm_per_min = 1000;
  return b;
}

TEST(DensifyFiveAxis, OrivectVectorsOnTheGreatCircleEvenlySpaced) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n;
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d u0 = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const Eigen::Vector3d u1 = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    Program p;
    p.files = {"t"};
    p.blocks.push_back(tool_pose_block({0, 0, 0}, u0, {10, 0, 0}, u1));
    DensifySettings s;
    s.angle_step_rad = 2 * kDeg;
    const auto samples = densify(p, s);
    const double theta = std::atan2(u0.cross(u1).norm(), u0.dot(u1));
    const int q = static_cast<int>(samples.size()) - 1;
    EXPECT_EQ(q, std::max(1, static_cast<int>(std::ceil(theta / (2 * kDeg)))));
    for (int k = 0; k <= q; ++k) {
      const Eigen::Vector3d u = samples[static_cast<size_t>(k)].pose.axis;
      EXPECT_NEAR(u.norm(), 1.0, kExact);
      EXPECT_NEAR(u0.cross(u1).normalized().dot(u), 0.0, kExact) << "out of the plane of start and end";
      EXPECT_NEAR(std::atan2(u0.cross(u).norm(), u0.dot(u)), theta * k / q, kExact) << "not evenly spaced";
    }
  }
}

TEST(DensifyFiveAxis, QIsTheLargerOfTheStepAndAngleCounts) {
  // L = 10 mm, theta = 30 deg: lambda 1 mm -> 10, phi 1 deg -> 30; lambda 0.25 mm -> 40.
  Program p;
  p.files = {"t"};
  p.blocks.push_back(tool_pose_block({0, 0, 0}, {0, 0, 1}, {6, 8, 0}, {std::sin(30 * kDeg), 0, std::cos(30 * kDeg)}));
  DensifySettings s;
  s.step_mm = 1.0;
  s.angle_step_rad = 1.0 * kDeg;
  EXPECT_EQ(densify(p, s).size(), 31u);
  s.step_mm = 0.25;
  EXPECT_EQ(densify(p, s).size(), 41u);
}

TEST(DensifyFiveAxis, ConeKeepsTheOpeningAngleAndTurnsTheRightWay) {
  // Start 20 deg off the cone axis +Z at azimuth 0, end at azimuth 90: counterclockwise
  // turns +90 deg, clockwise -270 deg, the tool axis always 20 deg from +Z.
  const double tilt = 20 * kDeg;
  const Eigen::Vector3d u0(std::sin(tilt), 0, std::cos(tilt)), u1(0, std::sin(tilt), std::cos(tilt));
  for (const auto& [mode, turn] : {std::make_pair(OrientationMode::ConeCounterClockwise, 90.0 * kDeg),
                                   std::make_pair(OrientationMode::ConeClockwise, -270.0 * kDeg)}) {
    Program p;
    p.files = {"t"};
    Block b = tool_pose_block({0, 0, 0}, u0, {0, 0, 0}, u1, mode);
    b.cone_axis = {0, 0, 1};
    p.blocks.push_back(b);
    DensifySettings s;
    s.angle_step_rad = 1 * kDeg;
    const auto samples = densify(p, s);
    // The axis travels the cone's circle: arc length |turn| sin(20 deg) on the unit sphere.
    const int q = static_cast<int>(samples.size()) - 1;
    EXPECT_EQ(q, static_cast<int>(std::ceil(std::abs(turn) * std::sin(tilt) / kDeg - 1e-9)));
    for (int k = 0; k <= q; ++k) {
      const Eigen::Vector3d u = samples[static_cast<size_t>(k)].pose.axis;
      EXPECT_NEAR(std::acos(u.z()), tilt, 1e-9);
      const double azimuth = std::atan2(u.y(), u.x());
      EXPECT_NEAR(std::remainder(azimuth - turn * k / q, 2 * M_PI), 0.0, 1e-9) << k;
    }
  }
}

TEST(DensifyFiveAxis, OriaxesFollowsLinearlyInterpolatedAngles) {
  const Machine m(machines()[1]);
  DensifyMachine dm;
  dm.machine = &m;
  dm.tool_length_mm = {{1, 30.0}};
  const double a0 = -20 * kDeg, c0 = 10 * kDeg, a1 = -50 * kDeg, c1 = 70 * kDeg;
  Program p;
  p.files = {"t"};
  Block b = tool_pose_block({1, 2, 3}, trt_axis(a0, c0), {11, -4, 8}, trt_axis(a1, c1), OrientationMode::Axes);
  b.tool = 1;
  p.blocks.push_back(b);
  DensifySettings s;
  s.angle_step_rad = 1 * kDeg;
  const Densified d = densify(p, s, dm);
  ASSERT_EQ(d.samples.size(), 61u);  // max(|dA|, |dC|) = 60 deg in 1 deg steps
  const int A = m.axis_index('A'), C = m.axis_index('C');
  for (size_t k = 0; k < d.samples.size(); ++k) {
    const double f = static_cast<double>(k) / 60.0;
    const double a = a0 + f * (a1 - a0), c = c0 + f * (c1 - c0);
    EXPECT_LT((d.samples[k].pose.axis - trt_axis(a, c)).norm(), kExact) << k;
    EXPECT_LT((d.samples[k].pose.tip_mm - (b.start_mm + f * (b.end_mm - b.start_mm))).norm(), kExact)
        << "TCP keeps the tip on its line";
    EXPECT_NEAR(d.samples[k].axes[A], a, kExact);
    EXPECT_NEAR(d.samples[k].axes[C], c, kExact);
  }
}

TEST(DensifyFiveAxis, TcpRotaryWordsSetTheAxesAndKeepTheTip) {
  // G43.4: X Y Z the tip in the workpiece frame, A C the rotary axes themselves. The axes go
  // linearly from the start's words to the end's; the tool axis is the trunnion's closed form.
  const Machine m(machines()[1]);
  DensifyMachine dm;
  dm.machine = &m;
  dm.tool_length_mm = {{1, 30.0}};
  const double a0 = -20 * kDeg, c0 = 10 * kDeg, a1 = -50 * kDeg, c1 = 70 * kDeg;
  Program p;
  p.files = {"t"};
  Block b = tool_pose_block({1, 2, 3}, Eigen::Vector3d::UnitZ(), {11, -4, 8}, Eigen::Vector3d::UnitZ(),
                            OrientationMode::Axes);
  b.tool = 1;
  b.start_rotary.angle_rad = {a0, 0.0, c0};
  b.start_rotary.given = {true, false, true};
  b.end_rotary.angle_rad = {a1, 0.0, c1};
  b.end_rotary.given = {true, false, true};
  p.blocks.push_back(b);
  DensifySettings s;
  s.angle_step_rad = 1 * kDeg;
  const Densified d = densify(p, s, dm);
  ASSERT_EQ(d.samples.size(), 61u);
  const int A = m.axis_index('A'), C = m.axis_index('C');
  for (size_t k = 0; k < d.samples.size(); ++k) {
    const double f = static_cast<double>(k) / 60.0;
    const double a = a0 + f * (a1 - a0), c = c0 + f * (c1 - c0);
    EXPECT_NEAR(d.samples[k].axes[A], a, kExact) << k;
    EXPECT_NEAR(d.samples[k].axes[C], c, kExact) << k;
    EXPECT_LT((d.samples[k].pose.axis - trt_axis(a, c)).norm(), kExact) << k;
    EXPECT_LT((d.samples[k].pose.tip_mm - (b.start_mm + f * (b.end_mm - b.start_mm))).norm(), kExact) << k;
  }
}

TEST(DensifyFiveAxis, AxisProgramNonlinearErrorOfAPureRotation) {
  // C turns 60 deg at A = 0 with X Y Z still: the tip circles the C axis at radius R, and
  // its largest distance from the chord is the sagitta R (1 - cos(30 deg)). Program point
  // P = (45, 3, 0) puts the tool tip in the frame at P + origin = (50, 0, 40): R = 50.
  const Machine m(machines()[1]);
  DensifyMachine dm;
  dm.machine = &m;
  Program p;
  p.files = {"t"};
  p.blocks.push_back(axis_block({45, 3, 0}, 0.0, 0.0, {45, 3, 0}, 0.0, 60 * kDeg));
  DensifySettings s;
  s.angle_step_rad = 5 * kDeg;
  const Densified d = densify(p, s, dm);
  const double expected = 50.0 * (1.0 - std::cos(30 * kDeg));
  EXPECT_NEAR(d.blocks[0].nonlinear_error_mm, expected, 1e-9);
  // Where: the middle of the arc, C = 30 deg: Rz(-30 deg) (50, 0, 40) - origin.
  const Eigen::Vector3d mid = rz(-30 * kDeg) * Eigen::Vector3d(50, 0, 40) - kOrigin;
  EXPECT_LT((d.blocks[0].nonlinear_at_mm - mid).norm(), 1e-6);
  EXPECT_EQ(d.samples.size(), 13u);
  for (const PoseSample& sample : d.samples)
    EXPECT_NEAR((sample.pose.tip_mm + kOrigin).head<2>().norm(), 50.0, 1e-9) << "the tip stays on the circle";
}

// The controller's pose of an axis block on the AC trunnion at fraction f, by hand.
ToolPose trt_truth(const Block& b, double f) {
  const double a = b.start_rotary.angle_rad[0] + f * (b.end_rotary.angle_rad[0] - b.start_rotary.angle_rad[0]);
  const double c = b.start_rotary.angle_rad[2] + f * (b.end_rotary.angle_rad[2] - b.start_rotary.angle_rad[2]);
  const Eigen::Vector3d program = b.start_mm + f * (b.end_mm - b.start_mm);
  return {trt_tip(a, c, program + kOrigin), trt_axis(a, c)};
}

// Measured deviation of the moves through `poses` (uniform in f) from the truth, densely:
// points on the axis up to `length` above the tip and `radius` off it.
double measured_deviation(const Block& b, const std::vector<ToolPose>& poses, double length, double radius) {
  double worst = 0.0;
  const int q = static_cast<int>(poses.size()) - 1;
  for (int k = 0; k < q; ++k) {
    const ToolPose& p0 = poses[static_cast<size_t>(k)];
    const ToolPose& p1 = poses[static_cast<size_t>(k + 1)];
    const double theta = std::atan2(p0.axis.cross(p1.axis).norm(), p0.axis.dot(p1.axis));
    for (int j = 1; j < 40; ++j) {
      const double t = j / 40.0;
      const ToolPose truth = trt_truth(b, (k + t) / q);
      const Eigen::Vector3d tip = p0.tip_mm + t * (p1.tip_mm - p0.tip_mm);
      // Great circle by the spherical interpolation formula (independent of Rodrigues).
      const Eigen::Vector3d axis =
          theta < 1e-12 ? p0.axis
                        : Eigen::Vector3d((std::sin((1 - t) * theta) * p0.axis + std::sin(t * theta) * p1.axis) /
                                          std::sin(theta));
      for (double h : {0.0, length}) {
        const double d = ((truth.tip_mm + h * truth.axis) - (tip + h * axis)).norm();
        const double angle = std::atan2(truth.axis.cross(axis).norm(), truth.axis.dot(axis));
        worst = std::max(worst, d + radius * angle);
      }
    }
  }
  return worst;
}

TEST(DensifyFiveAxis, ToleranceModeMeetsEpsilonWithNearMinimalQ) {
  const Machine m(machines()[1]);
  DensifyMachine dm;
  dm.machine = &m;
  DensifySettings s;
  s.tolerance_mm = 0.01;
  s.cutter_length_mm = 20.0;
  s.cutter_radius_mm = 5.0;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(-30, 30), angle(-40 * kDeg, 10 * kDeg), turn(-60 * kDeg, 60 * kDeg);
  for (int trial = 0; trial < 20; ++trial) {
    const double a0 = angle(rng), c0 = turn(rng);
    const Block b = axis_block({coord(rng), coord(rng), coord(rng)}, a0, c0, {coord(rng), coord(rng), coord(rng)},
                               angle(rng), c0 + turn(rng));
    Program p;
    p.files = {"t"};
    p.blocks.push_back(b);
    const Densified d = densify(p, s, dm);
    std::vector<ToolPose> poses;
    for (const PoseSample& sample : d.samples) poses.push_back(sample.pose);
    const int q = d.blocks[0].q;
    EXPECT_LE(measured_deviation(b, poses, s.cutter_length_mm, s.cutter_radius_mm), s.tolerance_mm) << trial;
    // The smallest uniform q that meets epsilon, by brute force with the same measurement.
    int q_min = 1;
    for (;; ++q_min) {
      std::vector<ToolPose> uniform;
      for (int k = 0; k <= q_min; ++k) uniform.push_back(trt_truth(b, static_cast<double>(k) / q_min));
      if (measured_deviation(b, uniform, s.cutter_length_mm, s.cutter_radius_mm) <= s.tolerance_mm) break;
    }
    EXPECT_LE(q, 1.5 * q_min) << trial << ": q " << q << " vs smallest " << q_min;
  }
}

TEST(DensifyFiveAxis, UnreachableAndSingularPosesAreReportedPerBlock) {
  const Machine m(machines()[1]);  // A in [-120, 30]
  DensifyMachine dm;
  dm.machine = &m;
  Program p;
  p.files = {"t"};
  // Through the pole (tool axis along C): singular; then 130 deg from C: out of A's reach.
  p.blocks.push_back(tool_pose_block({0, 0, 0}, trt_axis(-10 * kDeg, 0.0), {1, 0, 0}, trt_axis(10 * kDeg, 0.0)));
  p.blocks.push_back(tool_pose_block({1, 0, 0}, trt_axis(10 * kDeg, 0.0), {2, 0, 0}, trt_axis(-130 * kDeg, 0.0)));
  DensifySettings s;
  s.angle_step_rad = 0.05 * kDeg;
  const Densified d = densify(p, s, dm);
  EXPECT_TRUE(d.blocks[0].singular);
  EXPECT_TRUE(d.blocks[0].unreachable.empty()) << d.blocks[0].unreachable;
  EXPECT_NE(d.blocks[1].unreachable.find("axis A limits"), std::string::npos) << d.blocks[1].unreachable;
}

}  // namespace
}  // namespace vcut::kinematics
