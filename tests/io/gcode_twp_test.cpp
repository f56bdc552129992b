// Tilted work plane (Fanuc/Haas G68.2, G53.1, G53.6, G69) on the bundled AC and BC trunnions,
// checked against frames and axis angles derived by hand from the Euler angles and from the
// machines' documented tool-axis formulas (their files' headers).
#include <gtest/gtest.h>

#include <optional>

#include <cmath>
#include <map>
#include <sstream>
#include <string>

#include "gcode_text.h"
#include "vcut/io/input_error.h"
#include "vcut/io/machine_file.h"
#include "vcut/io/program_reader.h"
#include "vcut/kinematics/forward_kinematics.h"

namespace vcut::io {
namespace {

using gcode_test::error_text;
using gcode_test::read_text;
using kinematics::Block;

constexpr double kDeg = M_PI / 180.0;

GcodeOptions machine_options(const std::string& name) {
  GcodeOptions options;
  options.flavor = GcodeOptions::Flavor::Fanuc;
  set_machine(options, read_machine_file(resolve_machine(name)), {});
  return options;
}

// Fanuc's flavour, no machine, the tip starting 100 mm above the origin.
GcodeOptions fanuc_at_z100() {
  GcodeOptions options;
  options.flavor = GcodeOptions::Flavor::Fanuc;
  options.start_mm = Eigen::Vector3d(0, 0, 100);
  return options;
}

// Z-X-Z Euler angles (alpha about Z, beta about the new X, gamma about the new Z): the
// feature frame's axes as the columns of the textbook closed form.
Eigen::Matrix3d euler_zxz(double alpha_deg, double beta_deg, double gamma_deg) {
  const double ca = std::cos(alpha_deg * kDeg), sa = std::sin(alpha_deg * kDeg);
  const double cb = std::cos(beta_deg * kDeg), sb = std::sin(beta_deg * kDeg);
  const double cg = std::cos(gamma_deg * kDeg), sg = std::sin(gamma_deg * kDeg);
  Eigen::Matrix3d r;
  r << ca * cg - sa * cb * sg, -ca * sg - sa * cb * cg, sa * sb,  //
      sa * cg + ca * cb * sg, -sa * sg + ca * cb * cg, -ca * sb,  //
      sb * sg, sb * cg, cb;
  return r;
}

// The last block made by line `line` of the program.
Block last_of_line(const kinematics::Program& program, int line) {
  std::optional<Block> found;
  for (const Block& b : program.blocks)
    if (b.source.line == line) found = b;
  EXPECT_TRUE(found.has_value()) << "no block from line " << line;
  return found.value_or(Block{});
}

void expect_near(const Eigen::Vector3d& got, const Eigen::Vector3d& want, double tol, const std::string& what) {
  EXPECT_LT((got - want).norm(), tol) << what << ": got " << got.transpose() << ", want " << want.transpose();
}

TEST(TiltedPlane, FeaturePointsGoThroughTheEulerFrame) {
  // No G53.1: the frame alone (the rotaries stay where they are). G54 moves the program
  // zero; G68.2's origin counts from it.
  GcodeOptions options;
  options.flavor = GcodeOptions::Flavor::Fanuc;
  options.start_mm = Eigen::Vector3d(0, 0, 200);
  options.work_offsets_mm["G54"] = Eigen::Vector3d(100, 50, 0);
  const auto program = read_text(
      "G21 G90 G54\n"
      "G68.2 X10. Y20. Z5. I30. J45. K60.\n"
      "G0 X1. Y2. Z3.\n"
      "G1 X-4. Y0.5 Z0. F500\n"
      "G91 G1 Z-2.\n"
      "G90 G69\n"
      "G0 X1. Y2. Z3.\n",
      options, "twp.nc");
  const Eigen::Matrix3d r = euler_zxz(30, 45, 60);
  const Eigen::Vector3d origin(110, 70, 5);
  expect_near(last_of_line(program, 3).end_mm, origin + r * Eigen::Vector3d(1, 2, 3), 1e-9, "G0 in the plane");
  expect_near(last_of_line(program, 4).end_mm, origin + r * Eigen::Vector3d(-4, 0.5, 0), 1e-9, "G1 in the plane");
  // G91 Z counts along the feature frame's Z.
  expect_near(last_of_line(program, 5).end_mm, origin + r * Eigen::Vector3d(-4, 0.5, -2), 1e-9, "G91 along feature Z");
  expect_near(last_of_line(program, 7).end_mm, Eigen::Vector3d(101, 52, 3), 1e-9, "after G69");
  EXPECT_TRUE(last_of_line(program, 3).tool_pose);
  // The tool has not turned: its axis is still the spindle's.
  expect_near(last_of_line(program, 4).end_axis, Eigen::Vector3d::UnitZ(), 1e-12, "tool axis");
}

TEST(TiltedPlane, ArcsTurnWithThePlane) {
  const GcodeOptions options = fanuc_at_z100();
  // J90: the feature Z is the workpiece -Y (the part's front face), feature Y is +Z.
  const auto program = read_text(
      "G68.2 X0 Y0 Z0 I0 J90. K0\n"
      "G0 X10. Y0 Z0\n"
      "G3 X0 Y10. I-10. J0 F300\n",
      options, "arc.nc");
  const Block& arc = last_of_line(program, 3);
  ASSERT_EQ(arc.kind, kinematics::MotionKind::Arc);
  expect_near(arc.start_mm, Eigen::Vector3d(10, 0, 0), 1e-9, "start");
  expect_near(arc.end_mm, Eigen::Vector3d(0, 0, 10), 1e-9, "end");
  expect_near(arc.center_mm, Eigen::Vector3d(0, 0, 0), 1e-9, "centre");
  // G3 turns about the feature +Z, which is the workpiece -Y.
  expect_near(arc.normal, Eigen::Vector3d(0, -1, 0), 1e-12, "normal");
}

TEST(TiltedPlane, G531TurnsTheAcTrunnionToTheHandDerivedAngles) {
  // table-table-ac: tool axis in the workpiece (sin A sin C, sin A cos C, cos A), A in
  // [-120, 30]. I30 J45 K0: the feature Z is (sin 30 sin 45, -cos 30 sin 45, cos 45), which
  // A = -45, C = -30 gives (A = +45 is beyond the limit).
  const GcodeOptions options = machine_options("table-table-ac");
  const auto program = read_text(
      "G21 G90\n"
      "G68.2 X0 Y0 Z0 I30. J45. K0\n"
      "G53.1\n"
      "G0 X0 Y0 Z20.\n"
      "G1 Z0 F200\n"
      "G69\n",
      options, "ac.nc");
  const Block& turned = last_of_line(program, 3);
  EXPECT_NEAR(turned.end_rotary.angle_rad[0], -45 * kDeg, 1e-9);
  EXPECT_NEAR(turned.end_rotary.angle_rad[2], -30 * kDeg, 1e-9);
  const Block& down = last_of_line(program, 5);
  EXPECT_TRUE(down.tool_pose);
  EXPECT_EQ(down.orientation, kinematics::OrientationMode::Axes);
  expect_near(down.end_mm, Eigen::Vector3d::Zero(), 1e-9, "feature zero");
  expect_near(last_of_line(program, 4).end_mm, 20 * euler_zxz(30, 45, 0).col(2), 1e-9, "20 mm above along feature Z");
  // A second method: the machine's forward kinematics at those angles points the tool along
  // the feature Z.
  const kinematics::Machine machine(read_machine_file(resolve_machine("table-table-ac")));
  kinematics::AxisValues q = machine.zero();
  q[machine.axis_index('A')] = down.end_rotary.angle_rad[0];
  q[machine.axis_index('C')] = down.end_rotary.angle_rad[2];
  expect_near(kinematics::forward(machine, q, 0.0).axis, euler_zxz(30, 45, 0).col(2), 1e-9, "forward kinematics");
}

TEST(TiltedPlane, G531TurnsTheBcTrunnionWithTheLeastRotaryMotion) {
  // table-table-bc: tool axis (-sin B cos C, sin B sin C, cos B). For the feature Z
  // (0.35355, -0.61237, 0.70711): B = 45, C = -120 or B = -45, C = 60; from B = C = 0 the
  // second turns less (105 deg against 165).
  const GcodeOptions options = machine_options("table-table-bc");
  const auto program = read_text("G68.2 I30. J45. K0\nG53.1\nG69\n", options, "bc.nc");
  const Block& turned = last_of_line(program, 2);
  EXPECT_NEAR(turned.end_rotary.angle_rad[1], -45 * kDeg, 1e-9);
  EXPECT_NEAR(turned.end_rotary.angle_rad[2], 60 * kDeg, 1e-9);
  EXPECT_FALSE(turned.end_rotary.given[0]);
  // P1 (LinuxCNC's remap): the tilting axis B positive - the other solution; P2: B negative.
  const auto p1 = read_text("G68.2 I30. J45. K0\nG53.1 P1\nG69\n", options, "bc1.nc");
  const Block& positive = last_of_line(p1, 2);
  EXPECT_NEAR(positive.end_rotary.angle_rad[1], 45 * kDeg, 1e-9);
  EXPECT_NEAR(positive.end_rotary.angle_rad[2], -120 * kDeg, 1e-9);
  const auto p2 = read_text("G68.2 I30. J45. K0\nG53.1 P2\nG69\n", options, "bc2.nc");
  const Block& negative = last_of_line(p2, 2);
  EXPECT_NEAR(negative.end_rotary.angle_rad[1], -45 * kDeg, 1e-9);
}

TEST(TiltedPlane, G531HoldsTheLinearAxesAndG536TheTip) {
  // table-table-ac, A axis 100 mm below the table top and 20 mm in front of C: the centre
  // (0, -20, -100). The tip at (0, 0, 100) with A = C = 0; J90 needs A = -90, C = 0. With the
  // linear axes held the table turns under the tip: the tip, in the workpiece, goes to
  // c + Rx(+90) (p - c) = (0, -220, -80), through c + Rx(45) (p - c) = (0, -147.28, 55.56)
  // half way - an arc about the A axis, not the chord.
  GcodeOptions options = machine_options("table-table-ac");
  options.start_mm = Eigen::Vector3d(0, 0, 100);
  const auto program = read_text("G68.2 I0 J90. K0\nG53.1\nG69\n", options, "swing.nc");
  ASSERT_EQ(program.blocks.size(), 90u);  // 1 deg of A each
  const Eigen::Vector3d c(0, -20, -100), p(0, 0, 100);
  auto rx = [](double deg) { return Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix(); };
  expect_near(program.blocks.back().end_mm, Eigen::Vector3d(0, -220, -80), 1e-9, "end of the swing");
  expect_near(program.blocks[44].end_mm, c + rx(45) * (p - c), 1e-9, "half way");
  expect_near(program.blocks[44].end_mm,
              Eigen::Vector3d(0, -20 + 20 * M_SQRT1_2 - 200 * M_SQRT1_2, -100 + 220 * M_SQRT1_2), 1e-9,
              "half way, by hand");
  EXPECT_NEAR(program.blocks.back().end_rotary.angle_rad[0], -90 * kDeg, 1e-9);
  EXPECT_NEAR(program.blocks.back().end_rotary.angle_rad[2], 0.0, 1e-9);
  // G53.6: one move, the tip held on the part.
  const auto held = read_text("G68.2 I0 J90. K0\nG53.6\nG69\n", options, "hold.nc");
  ASSERT_EQ(held.blocks.size(), 1u);
  expect_near(held.blocks[0].end_mm, p, 1e-9, "G53.6 keeps the tip");
  EXPECT_NEAR(held.blocks[0].end_rotary.angle_rad[0], -90 * kDeg, 1e-9);
}

TEST(TiltedPlane, AfterG69TheRotariesStayAndXyzAreTheMachines) {
  // table-table-ac, A centre (0, -20, -100). J90 turns A to -90 (C 0); the tip on the feature
  // zero, the workpiece origin. After G69 the table stays turned: the machine point under the
  // tip is c + Rx(-90) (0 - c) = (0, 80, -120). G91 G28 Z0 raises the spindle to its
  // reference (the gauge point at Z 500 at all-zero axes, no tool length here): the machine
  // point (0, 80, 500), which on the turned part is c + Rx(+90) ((0, 80, 500) - c) =
  // (0, -620, 0) - along the tool axis, the part's -Y. G0 A0 C0 then turns the table back
  // with the linear axes held: the tip ends at the machine point itself.
  GcodeOptions options = machine_options("table-table-ac");
  const auto program = read_text(
      "G68.2 I0 J90. K0\n"
      "G53.1\n"
      "G0 X0 Y0 Z0\n"
      "G69\n"
      "G91 G28 Z0\n"
      "G90 G0 A0 C0\n"
      "G0 X10.\n",
      options, "after.nc");
  expect_near(last_of_line(program, 3).end_mm, Eigen::Vector3d::Zero(), 1e-9, "feature zero");
  expect_near(last_of_line(program, 5).end_mm, Eigen::Vector3d(0, -620, 0), 1e-9, "G28 along the tool axis");
  EXPECT_NEAR(last_of_line(program, 5).end_rotary.angle_rad[0], -90 * kDeg, 1e-9);
  const Block& back = last_of_line(program, 6);
  expect_near(back.end_mm, Eigen::Vector3d(0, 80, 500), 1e-9, "A0 C0 with the linear axes held");
  EXPECT_NEAR(back.end_rotary.angle_rad[0], 0.0, 1e-12);
  EXPECT_TRUE(back.tool_pose);
  // Untilted, X Y Z are the part's again.
  expect_near(last_of_line(program, 7).end_mm, Eigen::Vector3d(10, 80, 500), 1e-9, "X10 after");
}

TEST(TiltedPlane, RotaryWordsThatTurnNothingKeepATipProgram) {
  // A0 C0 where the rotaries are (posts write them on their first positioning line) leave a
  // program of tool tips as it is; a rotary word that turns, without G43 or G68.2, makes it an
  // axis program (LinuxCNC's trivial kinematics: X Y Z are the joints).
  const GcodeOptions options = machine_options("table-table-ac");
  const auto tips = read_text("G0 X10 Y0 Z50 A0 C0\nG1 Z0 F100\n", options, "tips.nc");
  ASSERT_EQ(tips.blocks.size(), 2u);
  EXPECT_TRUE(tips.blocks[0].tool_pose);
  EXPECT_TRUE(tips.blocks[1].tool_pose);
  const auto axes = read_text("G0 X10 Y0 Z50 A0 C0\nG0 A-30\nG1 Z0 F100\n", options, "axes.nc");
  EXPECT_FALSE(axes.blocks.back().tool_pose);
  // With G43 the same turn holds the linear axes and the program stays one of tips.
  const auto g43 = read_text("G43 H1 G0 X10 Y0 Z50 A0 C0\nG0 A-30\nG1 Z0 F100\n", options, "g43.nc");
  EXPECT_TRUE(g43.blocks.back().tool_pose);
}

TEST(TiltedPlane, AMoveToWhereTheMachineStandsMakesNoBlock) {
  // After a G43 turn the tip's frame is the machine's X Y Z: Z50 where Z already is moves
  // nothing, whatever rounding the turn's frame has (the fuzzer found a block that was a few
  // ulps long in the frame and none on the part). Every block that is not an arc moves.
  const GcodeOptions options = machine_options("table-table-ac");
  for (int a = -1; a >= -113; a -= 7) {
    for (int c = -170; c <= 170; c += 37) {
      const std::string text = "G43 H1 G0 X10.3 Y-7.1 Z50.7 A0 C0\nG0 A" + std::to_string(a) + " C" +
                               std::to_string(c) + "\nG0 Z50.7\nX10.3 Y-7.1\nG1 X11 F100\n";
      const auto program = read_text(text, options, "stand.nc");
      for (const Block& b : program.blocks) {
        EXPECT_NE(b.source.line, 3) << "A" << a << " C" << c;
        EXPECT_NE(b.source.line, 4) << "A" << a << " C" << c;
        if (b.kind != kinematics::MotionKind::Arc) {
          EXPECT_TRUE(b.start_mm != b.end_mm || b.start_rotary.angle_rad != b.end_rotary.angle_rad)
              << "A" << a << " C" << c << " line " << b.source.line;
        }
      }
      EXPECT_EQ(program.blocks.back().source.line, 5);
    }
  }
}

// A turn of the rotaries with G43 and no TCP goes out as 1 deg steps, each a block: a turn of
// more than 1,000 revolutions in one move is refused (a fuzzed C901011 made 900,000 blocks,
// 390 MB, from one line), and every step counts toward max_lines as a line does (the fuzzer's
// limit of 10,000 lines, or an endless loop of turns).
TEST(TiltedPlane, ALongRotaryTurnIsRefusedAndItsStepsCountAsLines) {
  GcodeOptions options = machine_options("table-table-ac");
  const std::string head = "G43 H1 G0 X10 Y0 Z50 A0 C0\n";
  const std::string refused = error_text(head + "G1 C901011 F100\n", options, "c.nc");
  EXPECT_NE(refused.find("c.nc:2:4: the rotaries turn by 901011 deg in one move, which goes out as steps of 1 deg "
                         "(expected at most 360000 deg, 1000 turns, in one move: split it)"),
            std::string::npos)
      << refused;
  EXPECT_NE(error_text(head + "G1 C360001 F100\n", options, "d.nc").find("d.nc:2:4: the rotaries turn by 360001 deg"),
            std::string::npos);
  // 1,000 turns exactly: 360,000 steps, the last at C 360000.
  const auto most = read_text(head + "G1 C360000 F100\n", options, "most.nc");
  ASSERT_EQ(most.blocks.size(), 360001u);
  EXPECT_NEAR(most.blocks.back().end_rotary.angle_rad[2], 360000 * kDeg, 1e-6);
  // 360 steps and two lines: within 400 lines, not within 300.
  options.max_lines = 400;
  EXPECT_EQ(read_text(head + "G1 C360 F100\n", options, "ok.nc").blocks.size(), 361u);
  options.max_lines = 300;
  const std::string endless = error_text(head + "G1 C360 F100\n", options, "loop.nc");
  EXPECT_NE(endless.find("loop.nc:2:4: read 300 lines and rotary steps without reaching the end"), std::string::npos)
      << endless;
}

TEST(TiltedPlane, RollPitchYawWithP1) {
  // P1: I about X, then J about Y, then K about Z, all fixed axes: R = Rz(K) Ry(J) Rx(I).
  // I90 alone: feature Y goes to +Z, feature Z to -Y.
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d(0, 0, 100);
  const auto program = read_text("G68.2 P1 I90. J0 K0\nG0 X1. Y2. Z3.\nG69\n", options, "p1.nc");
  expect_near(last_of_line(program, 2).end_mm, Eigen::Vector3d(1, -3, 2), 1e-9, "Rx(90) (1, 2, 3)");
  // I0 J90 K0: feature Z goes to +X.
  const auto pitch = read_text("G68.2 P1 I0 J90. K0\nG0 X0 Y0 Z5.\nG69\n", options, "p1j.nc");
  expect_near(last_of_line(pitch, 2).end_mm, Eigen::Vector3d(5, 0, 0), 1e-9, "Ry(90) (0, 0, 5)");
}

// An error inside a tilted plane: what was read before it is in the workpiece frame, as the
// blocks after G69 would be (the fuzzer found them left in the feature frame). The frame: the
// origin X10 (G54 = 0), no turn.
TEST(TiltedPlane, BlocksBeforeAnErrorAreOnTheWorkpiece) {
  kinematics::Program program;
  GcodeState state;
  std::istringstream in("G68.2 X10. Y0 Z0 I0 J0 K0\nG0 X0 Y0 Z5.\nG1 X1. F100\nG1 X1. S\n");
  EXPECT_THROW(read_gcode(in, "err.nc", fanuc_at_z100(), program, state), InputError);
  ASSERT_EQ(program.blocks.size(), 2u);
  expect_near(program.blocks[0].end_mm, Eigen::Vector3d(10, 0, 5), 1e-12, "G0 on the workpiece");
  expect_near(program.blocks[1].end_mm, Eigen::Vector3d(11, 0, 5), 1e-12, "G1 on the workpiece");
}

TEST(TiltedPlane, WhatItRefusesNamesTheLine) {
  const GcodeOptions options = fanuc_at_z100();
  EXPECT_NE(
      error_text("G53.1\n", options, "a.nc").find("a.nc:1:1: G53.1 without a tilted work plane (expected G68.2 first)"),
      std::string::npos);
  EXPECT_NE(
      error_text("G68.2 I0 J45. K0\nG53.1\n", options, "b.nc").find("b.nc:2:1: G53.1 needs the machine's rotary axes"),
      std::string::npos);
  EXPECT_NE(error_text("G68.2 P2 X0 Y0 Z0\n", options, "c.nc").find("c.nc:1:7: G68.2 P2 (expected P0"),
            std::string::npos);
  EXPECT_NE(
      error_text("G68.2 I0 J45. K0\nG0 A10.\n", options, "d.nc").find("d.nc:2:4: A word with a tilted work plane on"),
      std::string::npos);
  EXPECT_NE(
      error_text("G68.2 I0 J45. K0\nG91 G28 Z0\n", options, "e.nc").find("e.nc:2:5: G28 with a tilted work plane on"),
      std::string::npos);
  EXPECT_NE(error_text("G68.2 I0 J45. K0\nG55\n", options, "f.nc").find("f.nc:2:1: G55 with a tilted work plane on"),
            std::string::npos);
  // A parameter that moves the active offset (G54's X) would move the plane's frame too.
  EXPECT_NE(error_text("G68.2 I0 J45. K0\n#5221 = 5.\n", options, "p.nc")
                .find("p.nc:2:1: a work offset change with a tilted work plane on"),
            std::string::npos);
  EXPECT_NE(error_text("G68.2 I0 J45. K0\nG68.2 I0 J30. K0\n", options, "g.nc")
                .find("g.nc:2:1: G68.2 with a tilted work plane on"),
            std::string::npos);
  // The AC trunnion's A stops at -120: a tool axis 150 deg from vertical is out of reach.
  const GcodeOptions ac = machine_options("table-table-ac");
  const std::string unreachable = error_text("G68.2 I0 J150. K0\nG53.1\n", ac, "h.nc");
  EXPECT_NE(unreachable.find("h.nc:2:1: G53.1: the machine cannot turn the tool to the tilted plane's Z"),
            std::string::npos)
      << unreachable;
  EXPECT_NE(unreachable.find("outside its limits [-120, 30]"), std::string::npos) << unreachable;
}

TEST(TiltedPlane, CannedCyclesDrillAlongTheFeatureZ) {
  const GcodeOptions options = fanuc_at_z100();
  // I0 J90 K0: feature (x, y, z) is workpiece (x, -z, y).
  const auto program = read_text(
      "G68.2 I0 J90. K0\n"
      "G0 X5. Y5. Z10.\n"
      "G98 G81 X5. Y5. Z-3. R2. F100\n"
      "G80\n"
      "G69\n",
      options, "drill.nc");
  Eigen::Vector3d deepest(0, -1e9, 0);
  for (const Block& b : program.blocks) {
    if (b.source.line == 3 && b.end_mm.y() > deepest.y()) deepest = b.end_mm;
  }
  expect_near(deepest, Eigen::Vector3d(5, 3, 5), 1e-9, "the hole's bottom, 3 mm into the -Y face");
}

}  // namespace
}  // namespace vcut::io
