// Forward kinematics (ARCHITECTURE §4, §6) against independent references: closed-form tool
// poses derived by hand from each machine's geometry (table-table AC and BC, cross-checked
// with LinuxCNC's published xyzac-trt / xyzbc-trt maps; head-table BC; head-head AC),
// node and model poses of the paper's gantry WYXZCAT worked by hand (seed 000 eqs. 8-13,
// Tables 5-7), and geometric errors worked by hand (ISO 230-1 names). Expected values are
// never computed with the code under test: each is a formula written out below or a number
// worked on paper, with its derivation in a comment.
//
// Notation: Tr(v) translation, Rx Ry Rz right-hand rotations about the frame's axes,
// t the tool tip in the frame F, g the gauge point (spindle nose at all-zero axes), L the
// tool length, o the workpiece origin, e_z = (0, 0, 1) the spindle axis at zero.
#include "vcut/kinematics/forward_kinematics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "axis_specs.h"
#include "vcut/kinematics/machine.h"

namespace vcut::kinematics {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Closed form vs chain product: both are a dozen double operations on coordinates below
// 1e4 mm (eps 2.2e-16 -> ~1e-11 mm); 1e-9 mm is the bound for exact kinematics.
constexpr double kExactMm = 1e-9;
// Unit vectors: components of size <= 1, the same dozen operations.
constexpr double kExactUnit = 1e-12;
// Error displacements in um are differences of ~1e3 mm coordinates: ~1e-13 mm of rounding,
// i.e. 1e-10 um; 1e-6 um (= 1e-9 mm) keeps the bound.
constexpr double kExactUm = 1e-6;
// A tilt between two unit vectors 1e-4 rad apart, taken through acos or atan2 of their dot
// or cross product: a rounding of 1e-16 in the dot becomes ~1e-12 rad = 1e-6 urad.
constexpr double kTiltUrad = 1e-5;

std::string str(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.12g, %.12g, %.12g)", v.x(), v.y(), v.z());
  return buf;
}

::testing::AssertionResult near(const Eigen::Vector3d& got, const Eigen::Vector3d& want, double tol) {
  const double err = (got - want).cwiseAbs().maxCoeff();
  if (err <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << str(got) << ", want " << str(want) << ": max error " << err << " > "
                                       << tol;
}

::testing::AssertionResult near_rotation(const Eigen::Matrix3d& got, const Eigen::Matrix3d& want, double tol) {
  const double err = (got - want).cwiseAbs().maxCoeff();
  if (err <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "rotation\n" << got << "\nwant\n" << want << "\nmax error " << err;
}

using test::linear;
using test::rotary;

// Axis values by letter (mm, rad), in the machine's axis order.
AxisValues values(const Machine& m, std::initializer_list<std::pair<char, double>> by_letter) {
  AxisValues q = m.zero();
  for (const auto& [letter, v] : by_letter) {
    const int i = m.axis_index(letter);
    EXPECT_GE(i, 0) << "no axis " << letter;
    if (i >= 0) q[i] = v;
  }
  return q;
}

// By value: callers pass the temporary that node_poses() returns.
NodePose node(const std::vector<NodePose>& poses, char letter) {
  for (const NodePose& p : poses)
    if (p.node == letter) return p;
  ADD_FAILURE() << "no pose for node " << letter;
  return NodePose{};
}

const ModelPose& model(const std::vector<ModelPose>& poses, const std::string& file) {
  for (const ModelPose& p : poses)
    if (p.file == file) return p;
  ADD_FAILURE() << "no pose for model " << file;
  static const ModelPose none;
  return none;
}

Eigen::Vector3d random_vector(std::mt19937& rng, double half_range) {
  std::uniform_real_distribution<double> d(-half_range, half_range);
  const double x = d(rng), y = d(rng), z = d(rng);
  return {x, y, z};
}

// Elementary rotation matrices written out (right-hand rule), for expected orientations.
Eigen::Matrix3d rx(double a) {
  Eigen::Matrix3d m;
  m << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return m;
}
Eigen::Matrix3d rz(double a) {
  Eigen::Matrix3d m;
  m << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return m;
}

// ---------------------------------------------------------------------------------------
// Table-table AC (WCAFXYZT), the chain of LinuxCNC's xyzac-trt.

MachineSpec table_table_ac(const Eigen::Vector3d& center_a, const Eigen::Vector3d& center_c,
                           const Eigen::Vector3d& gauge, const Eigen::Vector3d& origin) {
  MachineSpec s;
  s.name = "table-table-ac";
  s.topology = "WCAFXYZT";
  s.axes = {linear('X', {1, 0, 0}), linear('Y', {0, 1, 0}), linear('Z', {0, 0, 1}), rotary('A', {1, 0, 0}, center_a),
            rotary('C', {0, 0, 1}, center_c)};
  s.gauge_point_mm = gauge;
  s.workpiece_origin_mm = origin;
  return s;
}

// Hand derivation (ARCHITECTURE §2-4, WCAFXYZT):
//   frame -> tool:      Tr(x, y, z) (X, Y, Z on the frame, directions +x +y +z), so the tip is
//                       t = (x, y, z) + g - L e_z.
//   frame -> workpiece: T_W = T_A T_C Tr(o), T_A = Tr(cA) Rx(a) Tr(-cA), T_C = Tr(cC) Rz(c)
//   Tr(-cC). p_w = T_W^-1 t = Rz(-c) [Rx(-a)(t - cA) + cA - cC] + cC - o,   u_w = Rz(-c) Rx(-a)
//   e_z.
// Written out in scalars, with d = t - cA:
//   e_x = d_x + cA_x - cC_x
//   e_y = cos a d_y + sin a d_z + cA_y - cC_y
//   e_z = -sin a d_y + cos a d_z + cA_z - cC_z
//   p = (cos c e_x + sin c e_y, -sin c e_x + cos c e_y, e_z) + cC - o
//   u = (sin a sin c, sin a cos c, cos a)
// LinuxCNC cross-check: xyzac-trt's forward map (trtfuncs.c), rewritten in vectors with its
// joints j (the tool position), is pos = Rz(-c)[Rx(-a)(j - r_A) + r_A - r_C] + r_C with
// r_C = (x-rot-point, y-rot-point, .) and r_A = (., y-rot-point + y-offset, z-rot-point +
// z-offset) (tool-offset 0): term by term the formula above with o = 0. So the conventions
// agree: LinuxCNC's positive A and C turn the table right-hand about +x and +z, as the axis
// vectors [1,0,0] and [0,0,1] do here (its header calls that "the opposite of the
// conventional axis directions", ISO 841's primed table axes).
ToolPose table_table_ac_closed_form(double x, double y, double z, double a, double c, double L,
                                    const Eigen::Vector3d& cA, const Eigen::Vector3d& cC, const Eigen::Vector3d& g,
                                    const Eigen::Vector3d& o) {
  const double tx = x + g.x(), ty = y + g.y(), tz = z + g.z() - L;
  const double dx = tx - cA.x(), dy = ty - cA.y(), dz = tz - cA.z();
  const double ex = dx + cA.x() - cC.x();
  const double ey = std::cos(a) * dy + std::sin(a) * dz + cA.y() - cC.y();
  const double ez = -std::sin(a) * dy + std::cos(a) * dz + cA.z() - cC.z();
  ToolPose p;
  p.tip_mm = {std::cos(c) * ex + std::sin(c) * ey + cC.x() - o.x(),
              -std::sin(c) * ex + std::cos(c) * ey + cC.y() - o.y(), ez + cC.z() - o.z()};
  p.axis = {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
  return p;
}

TEST(ForwardTableTableAC, ClosedFormOnRandomGeometriesAndAxes) {
  std::mt19937 rng(3001);
  std::uniform_real_distribution<double> lin(-500.0, 500.0), a_deg(-120.0, 30.0), c_deg(-720.0, 720.0),
      length(0.0, 250.0);
  for (int m = 0; m < 20; ++m) {
    const Eigen::Vector3d cA = random_vector(rng, 200.0), cC = random_vector(rng, 200.0);
    const Eigen::Vector3d g = random_vector(rng, 600.0), o = random_vector(rng, 150.0);
    const Machine machine(table_table_ac(cA, cC, g, o));
    for (int k = 0; k < 50; ++k) {
      const double x = lin(rng), y = lin(rng), z = lin(rng), a = a_deg(rng) * kDeg, c = c_deg(rng) * kDeg;
      const double L = length(rng);
      const AxisValues q = values(machine, {{'X', x}, {'Y', y}, {'Z', z}, {'A', a}, {'C', c}});
      const ToolPose got = forward(machine, q, L);
      const ToolPose want = table_table_ac_closed_form(x, y, z, a, c, L, cA, cC, g, o);
      SCOPED_TRACE("machine " + std::to_string(m) + " sample " + std::to_string(k));
      EXPECT_TRUE(near(got.tip_mm, want.tip_mm, kExactMm));
      EXPECT_TRUE(near(got.axis, want.axis, kExactUnit));

      // The workpiece node at its programming zero: T_W = T_A T_C Tr(o), so its origin is
      // cA + Rx(a)(cC + Rz(c)(o - cC) - cA) and its rotation Rx(a) Rz(c).
      const NodePose w = node(node_poses(machine, q), 'W');
      EXPECT_TRUE(near(w.pose.translation(), cA + rx(a) * (cC + rz(c) * (o - cC) - cA), kExactMm));
      EXPECT_TRUE(near_rotation(w.pose.linear(), rx(a) * rz(c), kExactUnit));
    }
  }
}

TEST(ForwardTableTableAC, HandWorkedQuarterTurns) {
  // cA = (0, -20, -100), cC = 0, g = (0, 0, 500), o = 0, L = 100, X = 10, Y = 20, Z = -300:
  // t = (10, 20, 100). A = -90 deg: Rx(90)(t - cA) = Rx(90)(10, 40, 200) = (10, -200, 40);
  // + cA = (10, -220, -60). C = 90 deg: Rz(-90)(10, -220, -60) = (-220, -10, -60).
  // Tool axis: Rz(-90) Rx(90) e_z = Rz(-90)(0, -1, 0) = (-1, 0, 0).
  const Machine machine(table_table_ac({0, -20, -100}, {0, 0, 0}, {0, 0, 500}, {0, 0, 0}));
  const ToolPose p =
      forward(machine, values(machine, {{'X', 10}, {'Y', 20}, {'Z', -300}, {'A', -90 * kDeg}, {'C', 90 * kDeg}}), 100);
  EXPECT_TRUE(near(p.tip_mm, {-220, -10, -60}, kExactMm));
  EXPECT_TRUE(near(p.axis, {-1, 0, 0}, kExactUnit));
}

// ---------------------------------------------------------------------------------------
// Table-table BC (WCBFXYZT), the chain of LinuxCNC's xyzbc-trt.

MachineSpec table_table_bc(const Eigen::Vector3d& center_b, const Eigen::Vector3d& center_c,
                           const Eigen::Vector3d& gauge, const Eigen::Vector3d& origin) {
  MachineSpec s;
  s.name = "table-table-bc";
  s.topology = "WCBFXYZT";
  s.axes = {linear('X', {1, 0, 0}), linear('Y', {0, 1, 0}), linear('Z', {0, 0, 1}), rotary('B', {0, 1, 0}, center_b),
            rotary('C', {0, 0, 1}, center_c)};
  s.gauge_point_mm = gauge;
  s.workpiece_origin_mm = origin;
  return s;
}

// Hand derivation (WCBFXYZT), as for AC with B about +y:
//   p_w = Rz(-c) [Ry(-b)(t - cB) + cB - cC] + cC - o,   u_w = Rz(-c) Ry(-b) e_z.
// With d = t - cB, and Ry(-b)(x, y, z) = (cos b x - sin b z, y, sin b x + cos b z):
//   e_x = cos b d_x - sin b d_z + cB_x - cC_x
//   e_y = d_y + cB_y - cC_y
//   e_z = sin b d_x + cos b d_z + cB_z - cC_z
//   p = (cos c e_x + sin c e_y, -sin c e_x + cos c e_y, e_z) + cC - o
//   u = (-sin b cos c, sin b sin c, cos b)
// LinuxCNC cross-check: xyzbc-trt's forward map in vectors is
// pos = Rz(-c)[Ry(-b)(j - r_B) + r_B - r_C] + r_C with r_C = (x-rot-point, y-rot-point, .) and
// r_B = (x-rot-point + x-offset, ., z-rot-point + z-offset): the same formula with o = 0, so
// its positive B and C also turn the table right-hand about +y and +z, as here.
ToolPose table_table_bc_closed_form(double x, double y, double z, double b, double c, double L,
                                    const Eigen::Vector3d& cB, const Eigen::Vector3d& cC, const Eigen::Vector3d& g,
                                    const Eigen::Vector3d& o) {
  const double tx = x + g.x(), ty = y + g.y(), tz = z + g.z() - L;
  const double dx = tx - cB.x(), dy = ty - cB.y(), dz = tz - cB.z();
  const double ex = std::cos(b) * dx - std::sin(b) * dz + cB.x() - cC.x();
  const double ey = dy + cB.y() - cC.y();
  const double ez = std::sin(b) * dx + std::cos(b) * dz + cB.z() - cC.z();
  ToolPose p;
  p.tip_mm = {std::cos(c) * ex + std::sin(c) * ey + cC.x() - o.x(),
              -std::sin(c) * ex + std::cos(c) * ey + cC.y() - o.y(), ez + cC.z() - o.z()};
  p.axis = {-std::sin(b) * std::cos(c), std::sin(b) * std::sin(c), std::cos(b)};
  return p;
}

TEST(ForwardTableTableBC, ClosedFormOnRandomGeometriesAndAxes) {
  std::mt19937 rng(3002);
  std::uniform_real_distribution<double> lin(-500.0, 500.0), b_deg(-110.0, 110.0), c_deg(-720.0, 720.0),
      length(0.0, 250.0);
  for (int m = 0; m < 20; ++m) {
    const Eigen::Vector3d cB = random_vector(rng, 200.0), cC = random_vector(rng, 200.0);
    const Eigen::Vector3d g = random_vector(rng, 600.0), o = random_vector(rng, 150.0);
    const Machine machine(table_table_bc(cB, cC, g, o));
    for (int k = 0; k < 50; ++k) {
      const double x = lin(rng), y = lin(rng), z = lin(rng), b = b_deg(rng) * kDeg, c = c_deg(rng) * kDeg;
      const double L = length(rng);
      const ToolPose got = forward(machine, values(machine, {{'X', x}, {'Y', y}, {'Z', z}, {'B', b}, {'C', c}}), L);
      const ToolPose want = table_table_bc_closed_form(x, y, z, b, c, L, cB, cC, g, o);
      SCOPED_TRACE("machine " + std::to_string(m) + " sample " + std::to_string(k));
      EXPECT_TRUE(near(got.tip_mm, want.tip_mm, kExactMm));
      EXPECT_TRUE(near(got.axis, want.axis, kExactUnit));
    }
  }
}

TEST(ForwardTableTableBC, HandWorkedQuarterTurns) {
  // cB = (0, 0, -120), cC = 0, g = (0, 0, 450), o = 0, L = 50, X = 30, Y = -40, Z = -200:
  // t = (30, -40, 200). B = 90 deg: Ry(-90)(t - cB) = Ry(-90)(30, -40, 320) = (-320, -40, 30)
  // [Ry(-90): (x, y, z) -> (-z, y, x)]; + cB = (-320, -40, -90). C = -90 deg:
  // Rz(90)(-320, -40, -90) = (40, -320, -90). Axis: Rz(90) Ry(-90) e_z = Rz(90)(-1, 0, 0) = (0, -1,
  // 0).
  const Machine machine(table_table_bc({0, 0, -120}, {0, 0, 0}, {0, 0, 450}, {0, 0, 0}));
  const ToolPose p =
      forward(machine, values(machine, {{'X', 30}, {'Y', -40}, {'Z', -200}, {'B', 90 * kDeg}, {'C', -90 * kDeg}}), 50);
  EXPECT_TRUE(near(p.tip_mm, {40, -320, -90}, kExactMm));
  EXPECT_TRUE(near(p.axis, {0, -1, 0}, kExactUnit));
}

// ---------------------------------------------------------------------------------------
// Head-table BC (WCFXYZBT) and head-head AC (WFXYZCAT).

TEST(ForwardHeadTableBC, ClosedFormOnRandomGeometriesAndAxes) {
  // Hand derivation: frame -> tool Tr(x, y, z) T_B, T_B = Tr(cB) Ry(b) Tr(-cB), so
  //   t = v + cB + Ry(b)(g - L e_z - cB),  u_F = Ry(b) e_z = (sin b, 0, cos b);
  // frame -> workpiece T_C Tr(o): p_w = Rz(-c)(t - cC) + cC - o, u_w = Rz(-c) u_F.
  std::mt19937 rng(3003);
  std::uniform_real_distribution<double> lin(-500.0, 500.0), b_deg(-110.0, 110.0), c_deg(-360.0, 360.0),
      length(0.0, 250.0);
  for (int m = 0; m < 10; ++m) {
    const Eigen::Vector3d cB = random_vector(rng, 600.0), cC = random_vector(rng, 200.0);
    const Eigen::Vector3d g = random_vector(rng, 600.0), o = random_vector(rng, 150.0);
    MachineSpec s;
    s.topology = "WCFXYZBT";
    s.axes = {linear('X', {1, 0, 0}), linear('Y', {0, 1, 0}), linear('Z', {0, 0, 1}), rotary('B', {0, 1, 0}, cB),
              rotary('C', {0, 0, 1}, cC)};
    s.gauge_point_mm = g;
    s.workpiece_origin_mm = o;
    const Machine machine(s);
    for (int k = 0; k < 50; ++k) {
      const double x = lin(rng), y = lin(rng), z = lin(rng), b = b_deg(rng) * kDeg, c = c_deg(rng) * kDeg;
      const double L = length(rng);
      const double hx = g.x() - cB.x(), hy = g.y() - cB.y(), hz = g.z() - L - cB.z();
      const double tx = x + cB.x() + std::cos(b) * hx + std::sin(b) * hz;
      const double ty = y + cB.y() + hy;
      const double tz = z + cB.z() - std::sin(b) * hx + std::cos(b) * hz;
      const double ux = std::sin(b), uz = std::cos(b);
      // Rz(-c)(v) = (cos c v_x + sin c v_y, -sin c v_x + cos c v_y, v_z).
      const Eigen::Vector3d want_tip(std::cos(c) * (tx - cC.x()) + std::sin(c) * (ty - cC.y()) + cC.x() - o.x(),
                                     -std::sin(c) * (tx - cC.x()) + std::cos(c) * (ty - cC.y()) + cC.y() - o.y(),
                                     tz - o.z());
      const Eigen::Vector3d want_axis(std::cos(c) * ux, -std::sin(c) * ux, uz);
      const ToolPose got = forward(machine, values(machine, {{'X', x}, {'Y', y}, {'Z', z}, {'B', b}, {'C', c}}), L);
      SCOPED_TRACE("machine " + std::to_string(m) + " sample " + std::to_string(k));
      EXPECT_TRUE(near(got.tip_mm, want_tip, kExactMm));
      EXPECT_TRUE(near(got.axis, want_axis, kExactUnit));
    }
  }
}

TEST(ForwardHeadHeadAC, ClosedFormOnRandomGeometriesAndAxes) {
  // Hand derivation: frame -> tool Tr(v) T_C T_A with T_C = Tr(cC) Rz(c) Tr(-cC),
  // T_A = Tr(cA) Rx(a) Tr(-cA):
  //   t = v + cC + Rz(c)(cA + Rx(a)(g - L e_z - cA) - cC),
  //   u = Rz(c) Rx(a) e_z = (sin a sin c, -sin a cos c, cos a);  W on the frame: p_w = t - o.
  std::mt19937 rng(3004);
  std::uniform_real_distribution<double> lin(-800.0, 800.0), a_deg(-105.0, 105.0), c_deg(-360.0, 360.0),
      length(0.0, 250.0);
  for (int m = 0; m < 10; ++m) {
    const Eigen::Vector3d cC = random_vector(rng, 800.0), cA = random_vector(rng, 800.0);
    const Eigen::Vector3d g = random_vector(rng, 800.0), o = random_vector(rng, 150.0);
    MachineSpec s;
    s.topology = "WFXYZCAT";
    s.axes = {linear('X', {1, 0, 0}), linear('Y', {0, 1, 0}), linear('Z', {0, 0, 1}), rotary('C', {0, 0, 1}, cC),
              rotary('A', {1, 0, 0}, cA)};
    s.gauge_point_mm = g;
    s.workpiece_origin_mm = o;
    const Machine machine(s);
    for (int k = 0; k < 50; ++k) {
      const double x = lin(rng), y = lin(rng), z = lin(rng), a = a_deg(rng) * kDeg, c = c_deg(rng) * kDeg;
      const double L = length(rng);
      // h = g - L e_z - cA; Rx(a) h = (h_x, cos a h_y - sin a h_z, sin a h_y + cos a h_z).
      const double hx = g.x() - cA.x(), hy = g.y() - cA.y(), hz = g.z() - L - cA.z();
      const double kx = cA.x() + hx - cC.x();
      const double ky = cA.y() + std::cos(a) * hy - std::sin(a) * hz - cC.y();
      const double kz = cA.z() + std::sin(a) * hy + std::cos(a) * hz - cC.z();
      // Rz(c)(k) = (cos c k_x - sin c k_y, sin c k_x + cos c k_y, k_z).
      const Eigen::Vector3d want_tip(x + cC.x() + std::cos(c) * kx - std::sin(c) * ky - o.x(),
                                     y + cC.y() + std::sin(c) * kx + std::cos(c) * ky - o.y(), z + cC.z() + kz - o.z());
      const Eigen::Vector3d want_axis(std::sin(a) * std::sin(c), -std::sin(a) * std::cos(c), std::cos(a));
      const ToolPose got = forward(machine, values(machine, {{'X', x}, {'Y', y}, {'Z', z}, {'C', c}, {'A', a}}), L);
      SCOPED_TRACE("machine " + std::to_string(m) + " sample " + std::to_string(k));
      EXPECT_TRUE(near(got.tip_mm, want_tip, kExactMm));
      EXPECT_TRUE(near(got.axis, want_axis, kExactUnit));
    }
  }
}

TEST(ForwardThreeAxis, TableAxesWithNegativeDirections) {
  // WXYFZT with X, Y moving the table (directions -x, -y): T_W = Tr(-Y e_y) Tr(-X e_x) Tr(o),
  // so p_w = t + X e_x + Y e_y - o with t = (0, 0, Z) + g - L e_z: a positive X moves the tool
  // +X relative to the part. g = (0, 0, 400), o = (5, 6, 7), X = 12, Y = -34, Z = -250, L = 40:
  // p_w = (12 - 5, -34 - 6, -250 + 400 - 40 - 7) = (7, -40, 103).
  MachineSpec s;
  s.topology = "WXYFZT";
  s.axes = {linear('X', {-1, 0, 0}), linear('Y', {0, -1, 0}), linear('Z', {0, 0, 1})};
  s.gauge_point_mm = {0, 0, 400};
  s.workpiece_origin_mm = {5, 6, 7};
  const Machine machine(s);
  const ToolPose p = forward(machine, values(machine, {{'X', 12}, {'Y', -34}, {'Z', -250}}), 40);
  EXPECT_TRUE(near(p.tip_mm, {7, -40, 103}, kExactMm));
  EXPECT_TRUE(near(p.axis, {0, 0, 1}, kExactUnit));
}

// ---------------------------------------------------------------------------------------
// The paper's gantry WYXZCAT (seed 000 §5): F -> Y -> X -> Z -> C -> A -> spindle, W on F.
// Table 6: C centre (0, 0, 2800) about z, A centre (0, -75, 2800) about x; spindle nose
// (0, 0, 2400). Table 7 model origins. Node poses chained as in Table 5 (eqs. 8-13).

MachineSpec gantry() {
  MachineSpec s;
  s.name = "gantry-wyxzcat";
  s.topology = "WYXZCAT";
  s.axes = {linear('Y', {0, 1, 0}), linear('X', {1, 0, 0}), linear('Z', {0, 0, 1}),
            rotary('C', {0, 0, 1}, {0, 0, 2800}), rotary('A', {1, 0, 0}, {0, -75, 2800})};
  s.gauge_point_mm = {0, 0, 2400};
  s.models['Y'] = {{"y.stl", {1575, -1500, 6000}}};
  s.models['X'] = {{"x.stl", {375, 3100, 2550}}};
  s.models['Z'] = {{"z.stl", {-1500, -1500, 5000}}};
  s.models['C'] = {{"c.stl", {-1500, -1500, -1300}}};
  s.models['A'] = {{"a.stl", {1500, 1575, 1300}}};
  return s;
}

TEST(GantryWYXZCAT, AllZeroEveryNodeOnTheFrame) {
  // At all-zero axes every node frame is the frame F; the spindle nose T sits at g, the
  // workpiece W at its origin (0), each model at its Table 7 origin.
  const Machine machine(gantry());
  const std::vector<NodePose> nodes = node_poses(machine, machine.zero());
  for (char n : std::string("YXZCAW")) {
    SCOPED_TRACE(std::string("node ") + n);
    EXPECT_TRUE(near(node(nodes, n).pose.translation(), Eigen::Vector3d::Zero(), kExactMm));
    EXPECT_TRUE(near_rotation(node(nodes, n).pose.linear(), Eigen::Matrix3d::Identity(), kExactUnit));
  }
  EXPECT_TRUE(near(node(nodes, 'T').pose.translation(), {0, 0, 2400}, kExactMm));
  const std::vector<ModelPose> models = model_poses(machine, machine.zero());
  EXPECT_EQ(models.size(), 5u);
  EXPECT_TRUE(near(model(models, "a.stl").pose.translation(), {1500, 1575, 1300}, kExactMm));
  EXPECT_TRUE(near(model(models, "y.stl").pose.translation(), {1575, -1500, 6000}, kExactMm));
  const ToolPose p = forward(machine, machine.zero(), 300);
  EXPECT_TRUE(near(p.tip_mm, {0, 0, 2100}, kExactMm));
  EXPECT_TRUE(near(p.axis, {0, 0, 1}, kExactUnit));
}

TEST(GantryWYXZCAT, A90SwingsTheSpindleNoseAboutTheALine) {
  // A = 90 deg, all else 0: T_A = Tr(cA) Rx(90) Tr(-cA), cA = (0, -75, 2800);
  // Rx(90): (x, y, z) -> (x, -z, y).
  // Nose: g - cA = (0, 75, -400) -> (0, 400, 75); + cA = (0, 325, 2875).
  // A node origin: cA + Rx(90)(0 - cA) = cA - Rx(90) cA = (0, -75, 2800) - (0, -2800, -75) = (0,
  // 2725, 2875). Tip, L = 200: (0, 75, -600) -> (0, 600, 75) + cA = (0, 525, 2875); axis Rx(90) e_z
  // = (0, -1, 0). A model: (1500, 1575, 1300) - cA = (1500, 1650, -1500) -> (1500, 1500, 1650) + cA
  //          = (1500, 1425, 4450). The C node and model do not move.
  const Machine machine(gantry());
  const AxisValues q = values(machine, {{'A', 90 * kDeg}});
  const std::vector<NodePose> nodes = node_poses(machine, q);
  EXPECT_TRUE(near(node(nodes, 'T').pose.translation(), {0, 325, 2875}, kExactMm));
  EXPECT_TRUE(near_rotation(node(nodes, 'T').pose.linear(), rx(kPi / 2), kExactUnit));
  EXPECT_TRUE(near(node(nodes, 'A').pose.translation(), {0, 2725, 2875}, kExactMm));
  EXPECT_TRUE(near_rotation(node(nodes, 'A').pose.linear(), rx(kPi / 2), kExactUnit));
  EXPECT_TRUE(near(node(nodes, 'C').pose.translation(), {0, 0, 0}, kExactMm));
  EXPECT_TRUE(near_rotation(node(nodes, 'C').pose.linear(), Eigen::Matrix3d::Identity(), kExactUnit));
  const std::vector<ModelPose> models = model_poses(machine, q);
  EXPECT_TRUE(near(model(models, "a.stl").pose.translation(), {1500, 1425, 4450}, kExactMm));
  EXPECT_TRUE(near(model(models, "c.stl").pose.translation(), {-1500, -1500, -1300}, kExactMm));
  const ToolPose p = forward(machine, q, 200);
  EXPECT_TRUE(near(p.tip_mm, {0, 525, 2875}, kExactMm));
  EXPECT_TRUE(near(p.axis, {0, -1, 0}, kExactUnit));
}

TEST(GantryWYXZCAT, C90TurnsTheALineAboutTheRam) {
  // C = 90 deg, all else 0: T_C = Tr(cC) Rz(90) Tr(-cC), cC = (0, 0, 2800) on the z axis, so
  // T_C is the pure rotation Rz(90): (x, y, z) -> (-y, x, z). The A node = T_C (A = 0).
  // Nose: Rz(90)(0, 0, 2400) = (0, 0, 2400). The A line's point (0, -75, 2800) goes to
  // (75, 0, 2800). C model: Rz(90)(-1500, -1500, -1300) = (1500, -1500, -1300);
  // A model: Rz(90)(1500, 1575, 1300) = (-1575, 1500, 1300).
  const Machine machine(gantry());
  const AxisValues q = values(machine, {{'C', 90 * kDeg}});
  const std::vector<NodePose> nodes = node_poses(machine, q);
  EXPECT_TRUE(near(node(nodes, 'C').pose.translation(), {0, 0, 0}, kExactMm));
  EXPECT_TRUE(near_rotation(node(nodes, 'C').pose.linear(), rz(kPi / 2), kExactUnit));
  EXPECT_TRUE(near(node(nodes, 'A').pose * Eigen::Vector3d(0, -75, 2800), {75, 0, 2800}, kExactMm));
  EXPECT_TRUE(near(node(nodes, 'T').pose.translation(), {0, 0, 2400}, kExactMm));
  const std::vector<ModelPose> models = model_poses(machine, q);
  EXPECT_TRUE(near(model(models, "c.stl").pose.translation(), {1500, -1500, -1300}, kExactMm));
  EXPECT_TRUE(near(model(models, "a.stl").pose.translation(), {-1575, 1500, 1300}, kExactMm));
  EXPECT_TRUE(near_rotation(model(models, "a.stl").pose.linear(), rz(kPi / 2), kExactUnit));
}

TEST(GantryWYXZCAT, AllAxesMoved) {
  // X = 100, Y = 200, Z = -300, C = 90 deg, A = 90 deg; v = (100, 200, -300).
  // Y node Tr(0, 200, 0); X node Tr(100, 200, 0); Z node Tr(v).
  // C node: Tr(v) T_C = Tr(v) Rz(90) (cC on the z axis): origin v, rotation Rz(90).
  // A node: C node * Tr(cA) Rx(90) Tr(-cA): origin v + Rz(90)(cA - Rx(90) cA);
  //   Rx(90) cA = (0, -2800, -75), cA - that = (0, 2725, 2875), Rz(90) -> (-2725, 0, 2875),
  //   + v = (-2625, 200, 2575); rotation Rz(90) Rx(90).
  // Nose: T_A g = (0, 325, 2875) (previous test), Rz(90) -> (-325, 0, 2875), + v = (-225, 200,
  // 2575). Tip, L = 150: T_A (0, 0, 2250) = (0, 475, 2875) -> (-475, 0, 2875) + v = (-375, 200,
  // 2575);
  //   axis Rz(90) Rx(90) e_z = Rz(90)(0, -1, 0) = (1, 0, 0).
  // Models: Y (1575, -1300, 6000); X (475, 3300, 2550); Z (-1400, -1300, 4700);
  //   C: v + Rz(90)(-1500, -1500, -1300) = (100 + 1500, 200 - 1500, -300 - 1300) = (1600, -1300,
  //   -1600); A: T_A (1500, 1575, 1300) = (1500, 1425, 4450); Rz(90) -> (-1425, 1500, 4450); + v =
  //   (-1325, 1700, 4150).
  const Machine machine(gantry());
  const AxisValues q = values(machine, {{'X', 100}, {'Y', 200}, {'Z', -300}, {'C', 90 * kDeg}, {'A', 90 * kDeg}});
  const std::vector<NodePose> nodes = node_poses(machine, q);
  EXPECT_TRUE(near(node(nodes, 'Y').pose.translation(), {0, 200, 0}, kExactMm));
  EXPECT_TRUE(near(node(nodes, 'X').pose.translation(), {100, 200, 0}, kExactMm));
  EXPECT_TRUE(near(node(nodes, 'Z').pose.translation(), {100, 200, -300}, kExactMm));
  EXPECT_TRUE(near(node(nodes, 'C').pose.translation(), {100, 200, -300}, kExactMm));
  EXPECT_TRUE(near_rotation(node(nodes, 'C').pose.linear(), rz(kPi / 2), kExactUnit));
  EXPECT_TRUE(near(node(nodes, 'A').pose.translation(), {-2625, 200, 2575}, kExactMm));
  EXPECT_TRUE(near_rotation(node(nodes, 'A').pose.linear(), rz(kPi / 2) * rx(kPi / 2), kExactUnit));
  EXPECT_TRUE(near(node(nodes, 'T').pose.translation(), {-225, 200, 2575}, kExactMm));
  EXPECT_TRUE(near(node(nodes, 'W').pose.translation(), {0, 0, 0}, kExactMm));
  const std::vector<ModelPose> models = model_poses(machine, q);
  EXPECT_TRUE(near(model(models, "y.stl").pose.translation(), {1575, -1300, 6000}, kExactMm));
  EXPECT_TRUE(near(model(models, "x.stl").pose.translation(), {475, 3300, 2550}, kExactMm));
  EXPECT_TRUE(near(model(models, "z.stl").pose.translation(), {-1400, -1300, 4700}, kExactMm));
  EXPECT_TRUE(near(model(models, "c.stl").pose.translation(), {1600, -1300, -1600}, kExactMm));
  EXPECT_TRUE(near(model(models, "a.stl").pose.translation(), {-1325, 1700, 4150}, kExactMm));
  const ToolPose p = forward(machine, q, 150);
  EXPECT_TRUE(near(p.tip_mm, {-375, 200, 2575}, kExactMm));
  EXPECT_TRUE(near(p.axis, {1, 0, 0}, kExactUnit));
}

TEST(GantryWYXZCAT, GeneralAnglesNoseAndTip) {
  // C = 30 deg, A = -45 deg, X = -1320, Y = -1320, Z = 1000 (the paper's N7 line with angles).
  // Nose: T_A g = cA + Rx(a)(0, 75, -400) = (0, -75 + 75 cos a + 400 sin a, 2800 + 75 sin a - 400
  // cos a); then T_C: Rz(c) of that (cC on the z axis), + v. Axis Rz(c) Rx(a) e_z = (sin a sin c,
  // -sin a cos c, cos a).
  const double a = -45 * kDeg, c = 30 * kDeg;
  const Machine machine(gantry());
  const AxisValues q = values(machine, {{'X', -1320}, {'Y', -1320}, {'Z', 1000}, {'C', c}, {'A', a}});
  const double ny = -75 + 75 * std::cos(a) + 400 * std::sin(a);
  const double nz = 2800 + 75 * std::sin(a) - 400 * std::cos(a);
  const Eigen::Vector3d nose(-1320 - std::sin(c) * ny, -1320 + std::cos(c) * ny, 1000 + nz);
  EXPECT_TRUE(near(node(node_poses(machine, q), 'T').pose.translation(), nose, kExactMm));
  const Eigen::Vector3d axis(std::sin(a) * std::sin(c), -std::sin(a) * std::cos(c), std::cos(a));
  const ToolPose p = forward(machine, q, 250);
  EXPECT_TRUE(near(p.axis, axis, kExactUnit));
  EXPECT_TRUE(near(p.tip_mm, nose - 250 * axis, kExactMm));
}

// ---------------------------------------------------------------------------------------
// ErrorTable: constants and tables over position, linear between knots, held beyond them.

TEST(ErrorTableAt, ConstantEmptyAndTable) {
  ErrorTable constant;
  constant.values = {5e-3};
  EXPECT_DOUBLE_EQ(constant.at(-1e6), 5e-3);
  EXPECT_DOUBLE_EQ(constant.at(123.0), 5e-3);
  EXPECT_TRUE(ErrorTable{}.empty());
  EXPECT_DOUBLE_EQ(ErrorTable{}.at(10.0), 0.0);

  // E_YX: {table: [[-300, 0], [300, 4]]} um: 2 um at 0, 3 um at 150 (a quarter of the span
  // beyond the middle), held at the ends.
  ErrorTable t;
  t.positions = {-300.0, 300.0};
  t.values = {0.0, 4e-3};
  EXPECT_NEAR(t.at(0.0), 2e-3, 1e-15);
  EXPECT_NEAR(t.at(150.0), 3e-3, 1e-15);
  EXPECT_NEAR(t.at(-300.0), 0.0, 1e-15);
  EXPECT_NEAR(t.at(300.0), 4e-3, 1e-15);
  EXPECT_NEAR(t.at(-1000.0), 0.0, 1e-15);
  EXPECT_NEAR(t.at(1000.0), 4e-3, 1e-15);

  // Three knots, a sign change: 0 at 0, 10 at 100, -10 at 200 -> 5 at 50, 0 at 150, -5 at 175.
  ErrorTable v;
  v.positions = {0.0, 100.0, 200.0};
  v.values = {0.0, 10.0, -10.0};
  EXPECT_NEAR(v.at(50.0), 5.0, 1e-12);
  EXPECT_NEAR(v.at(100.0), 10.0, 1e-12);
  EXPECT_NEAR(v.at(150.0), 0.0, 1e-12);
  EXPECT_NEAR(v.at(175.0), -5.0, 1e-12);
  EXPECT_NEAR(v.at(250.0), -10.0, 1e-12);
}

// ---------------------------------------------------------------------------------------
// Geometric errors on the table-table AC machine of examples/machines: cA = (0, -20, -100),
// cC = 0, g = (0, 0, 500), o = 0. Error model (machine.h): a linear node is
// Tr(value Rot(squareness) direction) Tr(delta(value)) Rot(eps(value)) (rotation about the
// frame origin carried by the axis); a rotary node is
// Tr(c) Tr(offset) Rot(tilt) R(axis, value) Tr(-c) (component errors, none here, after R).

const Eigen::Vector3d kCenterA(0, -20, -100), kCenterC(0, 0, 0), kGauge(0, 0, 500), kOrigin(0, 0, 0);

MachineSpec ac_spec() { return table_table_ac(kCenterA, kCenterC, kGauge, kOrigin); }

AxisSpec& axis_of(MachineSpec& s, char letter) {
  for (AxisSpec& a : s.axes)
    if (a.letter == letter) return a;
  throw std::logic_error("no axis");
}

ErrorTable constant(double v) {
  ErrorTable t;
  t.values = {v};
  return t;
}

TEST(ErrorLocation, X0CDisplacesTheTableInTheFrameAtEveryAngle) {
  // E_X0C = 10 um: T_C = Tr(cC) Tr(d) Rz(c) Tr(-cC) = Tr(d) T_C_ideal, d = (0.010, 0, 0) in C's
  // parent (A) frame. p_w = T_C^-1 T_A^-1 t, so the tip in the part moves by -Rz(-c) d
  // = (-10 cos c, +10 sin c, 0) um whatever A is: C = 0 -> (-10, 0, 0), 90 -> (0, 10, 0),
  // 180 -> (10, 0, 0). The axis does not turn.
  MachineSpec s = ac_spec();
  axis_of(s, 'C').location.offset_mm = {0.010, 0, 0};
  const Machine machine(s);
  ASSERT_TRUE(machine.has_errors());
  const struct {
    double c_deg;
    Eigen::Vector3d tip_um;
  } cases[] = {{0, {-10, 0, 0}}, {90, {0, 10, 0}}, {180, {10, 0, 0}}};
  for (double a_deg : {0.0, -60.0}) {
    for (const auto& k : cases) {
      SCOPED_TRACE("A = " + std::to_string(a_deg) + ", C = " + std::to_string(k.c_deg));
      const AxisValues q =
          values(machine, {{'X', 30}, {'Y', -40}, {'Z', -200}, {'A', a_deg * kDeg}, {'C', k.c_deg * kDeg}});
      const ToolPose nominal = forward(machine, q, 100);
      const ToolPose actual = forward(machine, q, 100, Geometry::Actual);
      const PoseError e = pose_error(nominal, actual);
      EXPECT_TRUE(near(e.tip_um, k.tip_um, kExactUm));
      EXPECT_NEAR(e.axis_tilt_urad, 0.0, kTiltUrad);
      // Against the closed form with the exact nominal: p_w + (-Rz(-c) d).
      const ToolPose ideal = table_table_ac_closed_form(30, -40, -200, a_deg * kDeg, k.c_deg * kDeg, 100, kCenterA,
                                                        kCenterC, kGauge, kOrigin);
      EXPECT_TRUE(near(actual.tip_mm, ideal.tip_mm + k.tip_um * 1e-3, kExactMm));
    }
  }
  // The C node itself (A = 0, C = 90): Tr(d) Rz(90) about cC = 0 -> origin d = (0.010, 0, 0).
  const NodePose c_node = node(node_poses(machine, values(machine, {{'C', 90 * kDeg}}), Geometry::Actual), 'C');
  EXPECT_TRUE(near(c_node.pose.translation(), {0.010, 0, 0}, kExactMm));
  EXPECT_TRUE(near_rotation(c_node.pose.linear(), rz(kPi / 2), kExactUnit));
}

TEST(ErrorLocation, A0CTiltsTheToolAxisBy100urad) {
  // E_A0C = 100 urad: T_C = Tr(cC) Rx(e) Rz(c) Tr(-cC), applied before the rotation, so the
  // carried part is tilted about x at every C. p_w = Rz(-c) Rx(-e)(T_A^-1 t - cC) + cC - o and
  // u_w = Rz(-c) Rx(-e) Rx(-a) e_z = (sin(a+e) sin c, sin(a+e) cos c, cos(a+e)): the tilt adds
  // to A (both about x), 100 urad from the nominal axis at every A and C.
  const double e = 100e-6;
  MachineSpec s = ac_spec();
  axis_of(s, 'C').location.tilt_rad = {e, 0, 0};
  const Machine machine(s);
  for (double a_deg : {0.0, -60.0}) {
    for (double c_deg : {0.0, 90.0, 180.0}) {
      SCOPED_TRACE("A = " + std::to_string(a_deg) + ", C = " + std::to_string(c_deg));
      const double a = a_deg * kDeg, c = c_deg * kDeg;
      const AxisValues q = values(machine, {{'X', 30}, {'Y', -40}, {'Z', -200}, {'A', a}, {'C', c}});
      const ToolPose actual = forward(machine, q, 100, Geometry::Actual);
      EXPECT_TRUE(near(actual.axis, {std::sin(a + e) * std::sin(c), std::sin(a + e) * std::cos(c), std::cos(a + e)},
                       kExactUnit));
      EXPECT_NEAR(pose_error(forward(machine, q, 100), actual).axis_tilt_urad, 100.0, kTiltUrad);
      // Tip: t = (30, -40, -200 + 500 - 100) = (30, -40, 200); T_A^-1 t = cA + Rx(-a)(t - cA), then
      // Rx(-e), then Rz(-c).
      const Eigen::Vector3d t(30, -40, 200);
      const Eigen::Vector3d in_a = kCenterA + rx(-a) * (t - kCenterA);
      EXPECT_TRUE(near(actual.tip_mm, rz(-c) * rx(-e) * (in_a - kCenterC) + kCenterC - kOrigin, kExactMm));
    }
  }
}

TEST(ErrorSquareness, C0YShearsYTowardMinusX) {
  // E_C0Y = 100 urad on Y: T_Y = Tr(y Rz(e) e_y), Rz(e) e_y = (-sin e, cos e, 0). A, C = 0, so
  // the part frame is F: the tip moves by y (-sin e, cos e - 1, 0). Y = 100 mm: x error
  // -100 sin(1e-4) mm = -9.99999983 um, y error 100 (cos(1e-4) - 1) mm = -5e-4 um; Y = -100
  // shears the other way; the axis does not turn.
  const double e = 100e-6;
  MachineSpec s = ac_spec();
  axis_of(s, 'Y').location.tilt_rad = {0, 0, e};
  const Machine machine(s);
  for (double y : {100.0, -100.0}) {
    const AxisValues q = values(machine, {{'X', 20}, {'Y', y}, {'Z', -150}});
    const PoseError err = pose_error(forward(machine, q, 100), forward(machine, q, 100, Geometry::Actual));
    EXPECT_TRUE(near(err.tip_um, Eigen::Vector3d(-y * std::sin(e), y * (std::cos(e) - 1), 0) * 1e3, kExactUm));
    EXPECT_NEAR(err.axis_tilt_urad, 0.0, kTiltUrad);
  }
  // With A = -30 deg, C = 45 deg the frame displacement y (-sin e, cos e - 1, 0) reaches the
  // part turned by the inverse table rotation: Rz(-c) Rx(-a) applied to it.
  const double a = -30 * kDeg, c = 45 * kDeg;
  const AxisValues q = values(machine, {{'X', 20}, {'Y', 100}, {'Z', -150}, {'A', a}, {'C', c}});
  const PoseError err = pose_error(forward(machine, q, 100), forward(machine, q, 100, Geometry::Actual));
  const Eigen::Vector3d frame_shift_um = Eigen::Vector3d(-100 * std::sin(e), 100 * (std::cos(e) - 1), 0) * 1e3;
  EXPECT_TRUE(near(err.tip_um, rz(-c) * rx(-a) * frame_shift_um, kExactUm));
}

TEST(ErrorComponent, BXPitchWithAbbeOffset) {
  // E_BX (pitch of X, rotation about y) from the table {[-300, 0], [300, 40]} urad: at
  // X = 150 it is 30 urad. The X node is Tr(x e_x) Ry(e), turning about the frame origin
  // carried by X; what rides on X (Y, Z, spindle) sits at t_X = (0, y, z) + g - L e_z in X's
  // frame: Y = 40, Z = -150, L = 100 -> t_X = (0, 40, 250), an Abbe offset of 250 mm.
  // Tip in F: x e_x + Ry(e) t_X, so the error is (250 sin e, 0, 250 (cos e - 1)) mm
  // = (7.4999999989, 0, -1.125e-4) um, and the tool axis turns by e: Ry(e) e_z = (sin e, 0, cos e).
  MachineSpec s = ac_spec();
  ErrorTable pitch;
  pitch.positions = {-300.0, 300.0};
  pitch.values = {0.0, 40e-6};
  axis_of(s, 'X').errors.rotation_rad[1] = pitch;
  const Machine machine(s);
  const double e = 30e-6;
  const AxisValues q = values(machine, {{'X', 150}, {'Y', 40}, {'Z', -150}});
  const ToolPose actual = forward(machine, q, 100, Geometry::Actual);
  const PoseError err = pose_error(forward(machine, q, 100), actual);
  EXPECT_TRUE(near(err.tip_um, Eigen::Vector3d(250 * std::sin(e), 0, 250 * (std::cos(e) - 1)) * 1e3, kExactUm));
  EXPECT_NEAR(err.axis_tilt_urad, 30.0, kTiltUrad);
  EXPECT_TRUE(near(actual.axis, {std::sin(e), 0, std::cos(e)}, kExactUnit));
  EXPECT_TRUE(near(actual.tip_mm, Eigen::Vector3d(150 + 250 * std::sin(e), 40, 250 * std::cos(e)), kExactMm));
}

TEST(ErrorComponent, XXPositioningTable) {
  // E_XX from {[-300, 0], [300, 4]} um: 3 um at X = 150, a pure shift of everything on X
  // along x; A = C = 0, so the part sees (3, 0, 0) um. At X = -300 the table gives 0.
  MachineSpec s = ac_spec();
  ErrorTable exx;
  exx.positions = {-300.0, 300.0};
  exx.values = {0.0, 4e-3};
  axis_of(s, 'X').errors.translation_mm[0] = exx;
  const Machine machine(s);
  for (const auto& [x, want_um] : {std::pair{150.0, 3.0}, std::pair{-300.0, 0.0}, std::pair{0.0, 2.0}}) {
    const AxisValues q = values(machine, {{'X', x}, {'Y', 10}, {'Z', -100}});
    const PoseError err = pose_error(forward(machine, q, 50), forward(machine, q, 50, Geometry::Actual));
    EXPECT_TRUE(near(err.tip_um, {want_um, 0, 0}, kExactUm)) << "X = " << x;
  }
}

TEST(ErrorComposition, OffsetThenTiltThenRotationOnOneAxis) {
  // E_Y0C and E_A0C together on C, deliberately large (d = 1 mm, e = 0.01 rad) so that the
  // order of the two, a second-order term e d ~ 1e-2 mm, is far above the tolerance:
  //   T_C = Tr(cC) Tr(d) Rx(e) Rz(c) Tr(-cC)  (offset, then tilt, then the rotation)
  //   p_w = Rz(-c) Rx(-e) (T_A^-1 t - cC - d) + cC - o.
  // The other order, Tr(cC) Rx(e) Tr(d) Rz(c) Tr(-cC), would give Rz(-c)(Rx(-e)(.. - cC) - d):
  // different by Rz(-c)(Rx(-e) d - d) = Rz(-c)(0, cos e - 1, -sin e) mm, about 10 um in z.
  // Hand numbers for A = 0, C = 90 deg, t = (30, -40, -200 + 500 - 100) = (30, -40, 200), cC = 0:
  //   t - d = (30, -41, 200); Rx(-e): (30, -41 cos e + 200 sin e, 41 sin e + 200 cos e);
  //   Rz(-90): (x, y, z) -> (y, -x, z).
  const double e = 0.01;
  MachineSpec s = ac_spec();
  axis_of(s, 'C').location.offset_mm = {0, 1.0, 0};
  axis_of(s, 'C').location.tilt_rad = {e, 0, 0};
  const Machine machine(s);
  const AxisValues q = values(machine, {{'X', 30}, {'Y', -40}, {'Z', -200}, {'C', 90 * kDeg}});
  const ToolPose actual = forward(machine, q, 100, Geometry::Actual);
  const Eigen::Vector3d want(-41 * std::cos(e) + 200 * std::sin(e), -30, 41 * std::sin(e) + 200 * std::cos(e));
  EXPECT_TRUE(near(actual.tip_mm, want, kExactMm));
  // u_w = Rz(-90) Rx(-e) e_z = Rz(-90)(0, sin e, cos e) = (sin e, 0, cos e).
  EXPECT_TRUE(near(actual.axis, {std::sin(e), 0, std::cos(e)}, kExactUnit));
}

TEST(ErrorComposition, XYawCarriesTheSquarenessOfY) {
  // E_CX = 50 urad (yaw of X, about z) and E_C0Y = 100 urad (squareness of Y), gauge point
  // moved to (30, 0, 500) so that the yaw's pivot (X's origin, not the tip) shows:
  //   tip in F = x e_x + Rz(e1) (y Rz(e2) e_y + z e_z + g - L e_z)
  //            = (x, 0, 0) + y (-sin(e1 + e2), cos(e1 + e2), 0) + (30 cos e1, 30 sin e1, z + 500 -
  //            L).
  // X = 100, Y = 200, Z = -100, L = 100: x error 200 (-sin 150e-6) + 30 (cos 50e-6 - 1) mm
  // = -29.99999944 um; y error 200 (cos 150e-6 - 1) + 30 sin 50e-6 mm = 1.4977500 um. Were X's
  // yaw not carried through Y, the x error would be -200 sin 100e-6 mm = -20 um.
  const double e1 = 50e-6, e2 = 100e-6;
  MachineSpec s = ac_spec();
  s.gauge_point_mm = {30, 0, 500};
  axis_of(s, 'X').errors.rotation_rad[2] = constant(e1);
  axis_of(s, 'Y').location.tilt_rad = {0, 0, e2};
  const Machine machine(s);
  const AxisValues q = values(machine, {{'X', 100}, {'Y', 200}, {'Z', -100}});
  const ToolPose actual = forward(machine, q, 100, Geometry::Actual);
  const Eigen::Vector3d want(100 - 200 * std::sin(e1 + e2) + 30 * std::cos(e1),
                             200 * std::cos(e1 + e2) + 30 * std::sin(e1), 300);
  EXPECT_TRUE(near(actual.tip_mm, want, kExactMm));
  const PoseError err = pose_error(forward(machine, q, 100), actual);
  EXPECT_TRUE(near(err.tip_um,
                   Eigen::Vector3d(-200 * std::sin(e1 + e2) + 30 * (std::cos(e1) - 1),
                                   200 * (std::cos(e1 + e2) - 1) + 30 * std::sin(e1), 0) *
                       1e3,
                   kExactUm));
  EXPECT_NEAR(err.axis_tilt_urad, 0.0, kTiltUrad);  // a yaw about z leaves e_z alone
}

TEST(ErrorComposition, ComponentErrorOnXAndLocationErrorOnC) {
  // E_XX = 5 um on X (tool side) and E_X0C = 10 um on C (part side), C = 90 deg, A = 0: the tip
  // moves (0.005, 0, 0) in F, the table (0.010, 0, 0); in the part the tip moves
  // Rz(-90)((0.005, 0, 0) - (0.010, 0, 0)) = Rz(-90)(-0.005, 0, 0) = (0, 0.005, 0) mm
  // [Rz(-90): (x, y, z) -> (y, -x, z)], i.e. (0, 5, 0) um.
  MachineSpec s = ac_spec();
  axis_of(s, 'X').errors.translation_mm[0] = constant(0.005);
  axis_of(s, 'C').location.offset_mm = {0.010, 0, 0};
  const Machine machine(s);
  const AxisValues q = values(machine, {{'X', -50}, {'Y', 60}, {'Z', -250}, {'C', 90 * kDeg}});
  const PoseError err = pose_error(forward(machine, q, 80), forward(machine, q, 80, Geometry::Actual));
  EXPECT_TRUE(near(err.tip_um, {0, 5, 0}, kExactUm));
  EXPECT_NEAR(err.axis_tilt_urad, 0.0, kTiltUrad);
}

}  // namespace
}  // namespace vcut::kinematics
