// Inverse kinematics and compensation: randomized round trips on machines of every
// topology (Ruckig's style: fixed seeds, many samples), the singular path, unreachable
// poses, the choice rule and error compensation. The references are forward kinematics
// (tested against hand-derived formulas in forward_kinematics_test.cpp) and the pose itself.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "vcut/kinematics/compensation.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/inverse_kinematics.h"
#include "test_machines.h"

namespace vcut::kinematics {
namespace {

// Round trips: the chain products carry ~1e-13 relative rounding on 3 m machines.
constexpr double kRoundTrip = 1e-9;

AxisValues random_within_limits(const Machine& m, std::mt19937& rng) {
  AxisValues q = m.zero();
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisSpec& a = m.axis(i);
    const double lo = a.limits ? a.limits->first : -2 * M_PI, hi = a.limits ? a.limits->second : 2 * M_PI;
    q[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  return q;
}

// Distance between axis vectors; continuous rotary axes compared modulo 2 pi.
double axis_distance(const Machine& m, const AxisValues& a, const AxisValues& b) {
  double d = 0.0;
  for (int i = 0; i < m.axis_count(); ++i) {
    double diff = a[i] - b[i];
    if (m.axis(i).kind == AxisKind::Rotary && !m.axis(i).limits) diff = std::remainder(diff, 2 * M_PI);
    d = std::max(d, std::abs(diff));
  }
  return d;
}

double pose_distance(const ToolPose& a, const ToolPose& b) {
  return std::max((a.tip_mm - b.tip_mm).norm(), (a.axis - b.axis).norm());
}

bool near_singular(const Machine& m, const ToolPose& pose) {
  if (m.rotary_count() < 2) return false;
  const Eigen::Vector3d k1 = m.axis(m.rotary_axis(0)).direction;
  return std::abs(pose.axis.dot(k1)) >= std::cos(m.spec().singularity_angle_rad);
}

TEST(InverseKinematics, RoundTripEveryTopology) {
  for (MachineSpec s : machines()) {
    const Machine m(s);
    std::mt19937 rng(20261123);
    int singular = 0;
    for (int n = 0; n < 10000; ++n) {
      const AxisValues q = random_within_limits(m, rng);
      const double length = std::uniform_real_distribution<double>(0.0, 120.0)(rng);
      const ToolPose pose = forward(m, q, length);
      // At a singularity the free angle is the previous one: give q as the previous pose.
      const bool at_pole = near_singular(m, pose);
      singular += at_pole;
      const IkResult r = inverse(m, pose, length, at_pole ? &q : nullptr);
      ASSERT_TRUE(r.ok()) << m.name() << " sample " << n << ": " << r.reason;
      double nearest = 1e300;
      for (const IkSolution& sol : r.solutions) {
        nearest = std::min(nearest, axis_distance(m, sol.q, q));
        if (sol.within_limits) {
          EXPECT_LT(pose_distance(forward(m, sol.q, length), pose), kRoundTrip) << m.name() << " sample " << n;
        }
      }
      EXPECT_LT(nearest, kRoundTrip) << m.name() << " sample " << n << ": IK(FK(q)) does not contain q";
      EXPECT_EQ(r.status == IkStatus::Singular, at_pole) << m.name() << " sample " << n;
    }
    EXPECT_LT(singular, 100) << m.name();  // uniform angles land within 0.1 deg of the pole ~0.1 % of the time
  }
}

TEST(InverseKinematics, RandomPosesComeBackExactly) {
  // Poses not made by forward kinematics: random tips and random axes in the upper
  // hemisphere; wherever the machine reaches them, FK(IK(pose)) = pose.
  for (MachineSpec s : machines()) {
    const Machine m(s);
    std::mt19937 rng(7);
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> coord(-100.0, 100.0);
    int reached = 0;
    const Eigen::Vector3d home = forward(m, m.zero(), 50.0).tip_mm;
    for (int n = 0; n < 2000; ++n) {
      ToolPose pose;
      pose.tip_mm = home + Eigen::Vector3d(coord(rng), coord(rng), coord(rng));
      pose.axis = Eigen::Vector3d(normal(rng), normal(rng), std::abs(normal(rng))).normalized();
      const IkResult r = inverse(m, pose, 50.0);
      if (!r.ok() || r.status == IkStatus::Singular) continue;
      ++reached;
      EXPECT_LT(pose_distance(forward(m, r.q(), 50.0), pose), kRoundTrip) << m.name() << " pose " << n;
    }
    if (m.rotary_count() == 2) {
      EXPECT_GT(reached, 1000) << m.name();
    }
  }
}

TEST(InverseKinematics, ContinuousAndWideAxesListEveryWinding) {
  const Machine bc(machines()[2]);  // C limited to [-360, 360]: two windings of every angle
  AxisValues q = bc.zero();
  q[bc.axis_index('B')] = 30 * kDeg;
  q[bc.axis_index('C')] = 100 * kDeg;
  const IkResult r = inverse(bc, forward(bc, q, 10.0), 10.0);
  ASSERT_TRUE(r.ok());
  int windings_of_q = 0;
  for (const IkSolution& s : r.solutions)
    if (std::abs(s.q[bc.axis_index('B')] - 30 * kDeg) < 1e-9 &&
        std::abs(std::remainder(s.q[bc.axis_index('C')] - 100 * kDeg, 2 * M_PI)) < 1e-9)
      ++windings_of_q;
  EXPECT_EQ(windings_of_q, 2);        // C = 100 and C = -260 deg
  EXPECT_EQ(r.solutions.size(), 4u);  // two branches (B = +-30) x two windings
}

TEST(InverseKinematics, LimitsManyTurnsWideListTheWindingsNearThePrevious) {
  // C limited to +-1e6 deg (2,778 turns each way): listing every winding would take seconds
  // and hundreds of MB (found by fuzzing). The four nearest the previous value are listed.
  MachineSpec s = machines()[2];
  s.axes[4].limits = std::make_pair(-1e6 * kDeg, 1e6 * kDeg);
  const Machine m(s);
  const int B = m.axis_index('B'), C = m.axis_index('C');
  AxisValues q = m.zero();
  q[B] = 30 * kDeg;
  q[C] = 100 * kDeg + 500 * 2 * M_PI;  // 500 turns out
  const ToolPose pose = forward(m, q, 10.0);
  const IkResult r = inverse(m, pose, 10.0, &q);
  ASSERT_TRUE(r.ok());
  EXPECT_LE(r.solutions.size(), 8u);  // two branches x four windings
  EXPECT_NEAR(r.q()[C], q[C], 1e-9);
  EXPECT_NEAR(r.q()[B], q[B], 1e-9);
}

TEST(MachineValidation, CoplanarLinearAxesAreAnErrorEvenAfterANormalisation) {
  // A warning (the spindle axis normalised) must not hide the error (found by fuzzing).
  MachineSpec s = machines()[0];
  s.axes[2].direction = Eigen::Vector3d(0.6, 0.8, 0.0);
  s.spindle_axis = Eigen::Vector3d(1e-7, 0, 1);
  bool coplanar = false;
  for (const SpecProblem& p : validate(s))
    coplanar = coplanar || (!p.warning && p.message.find("one plane") != std::string::npos);
  EXPECT_TRUE(coplanar);
  EXPECT_THROW(Machine{s}, std::invalid_argument);
}

TEST(InverseKinematics, LeastRotaryMotionAndPreferredSign) {
  const Machine hh(machines()[4]);  // head-head AC, C in [-360, 360]
  const int A = hh.axis_index('A'), C = hh.axis_index('C');
  AxisValues q = hh.zero();
  q[A] = 20 * kDeg;
  q[C] = 50 * kDeg;
  const ToolPose pose = forward(hh, q, 0.0);
  // From a previous pose near the other branch (A = -20, C = 230 deg) that branch wins.
  AxisValues prev = q;
  prev[A] = -19 * kDeg;
  prev[C] = 229 * kDeg;
  IkResult r = inverse(hh, pose, 0.0, &prev);
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(r.q()[A], -20 * kDeg, 1e-9);
  EXPECT_NEAR(r.q()[C], 230 * kDeg, 1e-9);
  // Without a previous pose: the preferred sign of A decides.
  IkSettings prefer_negative;
  prefer_negative.preferred_axis = 'A';
  prefer_negative.preferred_sign = -1;
  r = inverse(hh, pose, 0.0, nullptr, prefer_negative);
  ASSERT_TRUE(r.ok());
  EXPECT_LT(r.q()[A], 0.0);
  IkSettings prefer_positive = prefer_negative;
  prefer_positive.preferred_sign = 1;
  r = inverse(hh, pose, 0.0, nullptr, prefer_positive);
  EXPECT_NEAR(r.q()[A], 20 * kDeg, 1e-9);
  EXPECT_NEAR(r.q()[C], 50 * kDeg, 1e-9);
}

TEST(InverseKinematics, PathThroughTheSingularityKeepsTheFreeAngle) {
  // Table-table AC: the tool axis in the workpiece frame sweeps a great circle through the
  // C axis (workpiece +Z) at azimuth 35 deg; C's angle is free at the pole.
  const Machine m(machines()[1]);
  const int A = m.axis_index('A'), C = m.axis_index('C');
  IkSettings settings;
  settings.singularity_angle_rad = 1.0 * kDeg;
  const double azimuth = 35 * kDeg;
  AxisValues prev;
  bool have_prev = false;
  double c_before_pole = 0.0;
  int flagged = 0, expected_flagged = 0;
  for (int i = 0; i <= 400; ++i) {
    const double tilt = (-10.0 + 0.05 * i + 0.0123) * kDeg;  // never exactly on the 1 deg boundary
    ToolPose pose;
    pose.tip_mm = {10.0 + 0.1 * i, -5.0, 3.0};
    pose.axis = {std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt)};
    const bool within = std::abs(tilt) < settings.singularity_angle_rad;
    expected_flagged += within;
    const IkResult r = inverse(m, pose, 20.0, have_prev ? &prev : nullptr, settings);
    ASSERT_TRUE(r.ok()) << i << ": " << r.reason;
    EXPECT_EQ(r.status == IkStatus::Singular, within) << "tilt " << tilt / kDeg;
    if (within) {
      ++flagged;
      EXPECT_DOUBLE_EQ(r.q()[C], c_before_pole) << "the free angle must keep its previous value";
      // Off the pole by at most the singular angle: the reached axis misses by <= 2 x that.
      EXPECT_LE(r.orientation_error_rad, 2 * settings.singularity_angle_rad);
      EXPECT_LT((forward(m, r.q(), 20.0).tip_mm - pose.tip_mm).norm(), kRoundTrip);
    } else {
      c_before_pole = r.q()[C];
      EXPECT_LT(pose_distance(forward(m, r.q(), 20.0), pose), kRoundTrip);
    }
    if (have_prev) {
      EXPECT_LT(std::abs(r.q()[C] - prev[C]), 1e-9) << "C must not jump through the pole (tilt " << tilt / kDeg << ")";
      EXPECT_LT(std::abs(r.q()[A] - prev[A]), 0.2 * kDeg);
    }
    prev = r.q();
    have_prev = true;
  }
  EXPECT_EQ(flagged, expected_flagged);
  EXPECT_EQ(flagged, 40);  // tilts -0.9877 ... +0.9623 deg in steps of 0.05
}

TEST(InverseKinematics, UnreachablePosesSayWhy) {
  const std::vector<MachineSpec> all = machines();
  // 3-axis: any tilt is out of reach.
  const Machine three(all[0]);
  ToolPose tilted;
  tilted.axis = Eigen::Vector3d(0.1, 0, 1).normalized();
  IkResult r = inverse(three, tilted, 10.0);
  EXPECT_EQ(r.status, IkStatus::Unreachable);
  EXPECT_NE(r.reason.find("orientation out of reach"), std::string::npos) << r.reason;
  // Table-table AC with A in [-120, 30]: a tool axis 130 deg from the C axis needs |A| = 130.
  const Machine ac(all[1]);
  ToolPose steep;
  steep.axis = {std::sin(130 * kDeg), 0.0, std::cos(130 * kDeg)};
  r = inverse(ac, steep, 10.0);
  EXPECT_EQ(r.status, IkStatus::Unreachable);
  EXPECT_NE(r.reason.find("axis A limits [-120, 30]"), std::string::npos) << r.reason;
  // A tip beyond the X travel names X.
  ToolPose far;
  far.tip_mm = {5000, 0, 0};
  r = inverse(ac, far, 10.0);
  EXPECT_EQ(r.status, IkStatus::Unreachable);
  EXPECT_NE(r.reason.find("axis X limits"), std::string::npos) << r.reason;
  // A tool axis no pair of angles reaches: a head whose B axis is 45 deg from the spindle
  // reaches only the cone within 90 deg of it; C then turns the workpiece. Pointing the
  // tool straight down into the table is unreachable.
  const Machine nutating(all.back());
  ToolPose down;
  down.axis = {0, 0, -1};
  r = inverse(nutating, down, 10.0);
  EXPECT_EQ(r.status, IkStatus::Unreachable);
  EXPECT_NE(r.reason.find("orientation out of reach"), std::string::npos) << r.reason;
}

// Random realistic errors: offsets up to 50 um, tilts up to 100 urad, on every term.
void add_random_errors(MachineSpec& s, std::mt19937& rng) {
  std::uniform_real_distribution<double> um(-0.050, 0.050), urad(-100e-6, 100e-6);
  for (AxisSpec& a : s.axes) {
    for (int i = 0; i < 3; ++i) {
      // Tables over the travel for the component errors, two or three rows.
      const double lo = a.limits ? a.limits->first : -M_PI, hi = a.limits ? a.limits->second : M_PI;
      a.errors.translation_mm[static_cast<size_t>(i)].positions = {lo, 0.5 * (lo + hi), hi};
      a.errors.translation_mm[static_cast<size_t>(i)].values = {um(rng), um(rng), um(rng)};
      a.errors.rotation_rad[static_cast<size_t>(i)].positions = {lo, hi};
      a.errors.rotation_rad[static_cast<size_t>(i)].values = {urad(rng), urad(rng)};
    }
    if (a.kind == AxisKind::Rotary) a.location.offset_mm = {um(rng), um(rng), um(rng)};
    a.location.tilt_rad = {urad(rng), urad(rng), urad(rng)};
  }
}

TEST(Compensation, ResidualsBelowBoundsWithRandomErrors) {
  std::mt19937 rng(42);
  for (MachineSpec s : machines()) {
    add_random_errors(s, rng);
    const Machine m(s);
    ASSERT_TRUE(m.has_errors());
    for (int n = 0; n < 200; ++n) {
      AxisValues q = random_within_limits(m, rng);
      // Stay clear of the limits so that the corrected commands fit too.
      for (int i = 0; i < m.axis_count(); ++i)
        if (m.axis(i).limits) q[i] *= 0.9;
      const ToolPose nominal = forward(m, q, 40.0);
      if (near_singular(m, nominal)) continue;
      const CompensationResult c = compensate(m, nominal, 40.0, q);
      // Independent check of the residual: the error-aware forward kinematics at the
      // compensated commands against the nominal pose.
      const ToolPose reached = forward(m, c.q, 40.0, Geometry::Actual);
      const double tip_um = (reached.tip_mm - nominal.tip_mm).norm() * 1000.0;
      EXPECT_TRUE(c.converged) << m.name() << " " << n << ": " << c.note;
      EXPECT_LE(tip_um, 0.01) << m.name() << " " << n;
      if (m.rotary_count() == 2) {
        const double tilt_urad = reached.axis.cross(nominal.axis).norm() * 1e6;  // sin of the angle
        EXPECT_LE(tilt_urad, 0.01) << m.name() << " " << n;
        EXPECT_LE(c.residual_axis_urad, 0.01) << m.name() << " " << n;
      }
      // The uncompensated error is real (tens of um), so the test could fail.
      if (n == 0) {
        EXPECT_GT(pose_error(nominal, forward(m, q, 40.0, Geometry::Actual)).tip_um.norm(), 1.0) << m.name();
      }
    }
  }
}

TEST(Compensation, ThreeAxisMachineCorrectsTheTipOnly) {
  MachineSpec s = machines()[0];
  s.axes[0].errors.rotation_rad[1].values = {50e-6};  // a pitch of X tilts the tool: not correctable
  s.axes[1].location.tilt_rad = {0, 0, 30e-6};        // squareness of Y
  const Machine m(s);
  AxisValues q = m.zero();
  q << 120, -80, -40;
  const ToolPose nominal = forward(m, q, 30.0);
  const CompensationResult c = compensate(m, nominal, 30.0, q);
  EXPECT_TRUE(c.converged) << c.note;
  EXPECT_LE(c.residual_tip_um, 0.01);
  EXPECT_NEAR(c.residual_axis_urad, 50.0, 1e-3);
  EXPECT_NE(c.note.find("cannot be corrected"), std::string::npos) << c.note;
}

}  // namespace
}  // namespace vcut::kinematics
