// Cutter radius compensation, home returns and the start position of the G-code reader.
// Expected paths are the offset geometry worked by hand (a square's offset sides meet at the
// corners; a convex corner is an arc of the tool radius about the programmed corner); the
// LinuxCNC oracle (tests/oracle/rs274_oracle.py) checks the same code against rs274 on
// LinuxCNC's compensation programs and on random ones.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "gcode_text.h"
#include "vcut/io/gcode_reader.h"
#include "vcut/io/input_error.h"

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::MotionKind;
using kinematics::Program;

constexpr double kTol = 1e-9;

// From 0 unless the options say otherwise.
GcodeOptions from_zero(GcodeOptions options) {
  if (!options.start_mm) options.start_mm = Eigen::Vector3d::Zero();
  return options;
}
Program read(const std::string& text, const GcodeOptions& options = {}) {
  return gcode_test::read_text(text, from_zero(options), "comp.ngc");
}
std::string error_of(const std::string& text, const GcodeOptions& options = {}) {
  return gcode_test::error_text(text, from_zero(options), "comp.ngc");
}

void expect_point(const Eigen::Vector3d& got, const Eigen::Vector3d& want, const char* what) {
  EXPECT_LT((got - want).norm(), kTol) << what << ": got " << got.transpose() << ", want " << want.transpose();
}

void expect_line(const Block& b, const Eigen::Vector3d& start, const Eigen::Vector3d& end) {
  EXPECT_NE(b.kind, MotionKind::Arc);
  expect_point(b.start_mm, start, "start");
  expect_point(b.end_mm, end, "end");
}

// G41 (tool on the left) around a counterclockwise 10 mm square from its corner: every corner
// turns toward the tool, so the offset path is the square shrunk by r = 1 mm: its corners are
// where the offset sides meet. G40, then the exit move from the last offset point.
TEST(CutterComp, LeftInsideSquareMeetsAtTheCorners) {
  const Program p = read("G21 G17 G90 F100\nG41.1 D2\nG1 X10 Y0\nG1 X10 Y10\nG1 X0 Y10\nG40\nG1 X-5 Y10\nM2\n");
  ASSERT_EQ(p.blocks.size(), 4u);
  // Entry: from the uncompensated start to the end pushed r to the left of the move, then
  // pulled back along it to the corner of the next side's offset line.
  expect_line(p.blocks[0], {0, 0, 0}, {9, 1, 0});
  expect_line(p.blocks[1], {9, 1, 0}, {9, 9, 0});
  expect_line(p.blocks[2], {9, 9, 0}, {0, 9, 0});
  expect_line(p.blocks[3], {0, 9, 0}, {-5, 10, 0});
  EXPECT_EQ(p.blocks[1].source.line, 4);
}

// G42 (right) on the same path: the corners turn away from the tool (convex), so each gets a
// counterclockwise arc of radius r about the programmed corner.
TEST(CutterComp, RightOutsideCornerGetsAnArc) {
  const Program p = read("G21 G17 G90 F100\nG42.1 D2\nG1 X10 Y0\nG1 X10 Y10\nG40\nG1 X10 Y20\nM2\n");
  ASSERT_EQ(p.blocks.size(), 4u);
  expect_line(p.blocks[0], {0, 0, 0}, {10, -1, 0});
  const Block& arc = p.blocks[1];
  ASSERT_EQ(arc.kind, MotionKind::Arc);
  expect_point(arc.start_mm, {10, -1, 0}, "arc start");
  expect_point(arc.end_mm, {11, 0, 0}, "arc end");
  expect_point(arc.center_mm, {10, 0, 0}, "arc centre");
  EXPECT_EQ(arc.normal, Eigen::Vector3d(0, 0, 1));  // counterclockwise: G42 goes round the left of the corner
  expect_line(p.blocks[2], {11, 0, 0}, {11, 10, 0});
  expect_line(p.blocks[3], {11, 10, 0}, {10, 20, 0});
}

// A line then a tangent counterclockwise arc with the tool inside it: the arc's offset has
// radius 10 - 1 = 9 about the same centre and starts where the line's offset ends.
TEST(CutterComp, TangentArcInsideKeepsItsCentre) {
  const Program p = read("G21 G17 G90 F100\nG41.1 D2\nG1 X10 Y0\nG3 X20 Y10 R10\nG40\nG1 X30 Y10\nM2\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_line(p.blocks[0], {0, 0, 0}, {10, 1, 0});
  const Block& arc = p.blocks[1];
  ASSERT_EQ(arc.kind, MotionKind::Arc);
  expect_point(arc.start_mm, {10, 1, 0}, "arc start");
  expect_point(arc.end_mm, {19, 10, 0}, "arc end");
  expect_point(arc.center_mm, {10, 10, 0}, "arc centre");
  expect_line(p.blocks[2], {19, 10, 0}, {30, 10, 0});
}

// A line meeting an inside arc 0.04 rad off tangent, under rs274's 0.05 rad threshold
// (TOLERANCE_CONCAVE_CORNER in convert_arc_comp2, "convex, one arc needed"): no corner, and
// the arc starts where the line's offset ends. By hand, with r = 5: the line heads at 0.04
// rad into (0, 0), so its offset end is (-5 sin 0.04, 5 cos 0.04), 0.2254 mm from the arc's
// centre (0, 5.1); the arc ends at its end (5.1, 5.1) moved 5 toward the centre, (0.1, 5.1),
// 0.1 mm from it: a spiral, within the 0.05 r = 0.25 mm the tangent rule allows (the fuzz
// drivers' bound, from max_radius_mm).
TEST(CutterComp, NearlyTangentInsideArcStartsWhereTheLineEnds) {
  const double h = 0.04;  // rad
  std::ostringstream text;
  text.precision(17);
  text << "G21 G17 G90 F100\nG0 X" << -10.0 * std::cos(h) - 10.0 << " Y" << -10.0 * std::sin(h) << "\nG41.1 D10\nG1 X"
       << -10.0 * std::cos(h) << " Y" << -10.0 * std::sin(h)
       << "\nG1 X0 Y0\nG3 X5.1 Y5.1 I0 J5.1\nG1 X5.1 Y20\nG40\nM2\n";
  GcodeState state;
  std::istringstream in(text.str());
  Program p;
  read_gcode(in, "comp.ngc", from_zero({}), p, state);
  ASSERT_EQ(p.blocks.size(), 5u);
  const Eigen::Vector3d corner(-5.0 * std::sin(h), 5.0 * std::cos(h), 0.0);
  expect_point(p.blocks[2].end_mm, corner, "line end");
  const Block& arc = p.blocks[3];
  ASSERT_EQ(arc.kind, MotionKind::Arc);
  expect_point(arc.start_mm, corner, "arc start");
  expect_point(arc.center_mm, {0, 5.1, 0}, "arc centre");
  expect_point(arc.end_mm, {0.1, 5.1, 0}, "arc end");
  const double r_start = (arc.start_mm - arc.center_mm).norm();
  EXPECT_NEAR(r_start, std::hypot(5.0 * std::sin(h), 5.1 - 5.0 * std::cos(h)), 1e-12);
  EXPECT_GT(r_start - 0.1, 0.07);  // beyond LinuxCNC's arc tolerance: the rule, not rounding
  EXPECT_LT(r_start - 0.1, 0.05 * 5.0);
  EXPECT_EQ(state.comp.max_radius_mm, 5.0);
}

// Radii from the tool library: G41 D3 takes tool 3's; G41 alone the tool in the spindle's.
// A Z move with compensation on keeps the offset point.
TEST(CutterComp, ToolLibraryRadiusAndZMoves) {
  GcodeOptions options;
  options.tool_radius_mm = {{3, 0.5}, {4, 2.0}};
  const Program p = read("G21 F100\nG41 D3\nG1 X10 Y0\nG1 Z-1\nG40\nG1 X20\nT4 M6\nG41\nG1 X30\nG40\nM2\n", options);
  ASSERT_GE(p.blocks.size(), 4u);
  expect_line(p.blocks[0], {0, 0, 0}, {10, 0.5, 0});
  expect_line(p.blocks[1], {10, 0.5, 0}, {10, 0.5, -1});
  expect_line(p.blocks[2], {10, 0.5, -1}, {20, 0, -1});
  expect_line(p.blocks[3], {20, 0, -1}, {30, 2, -1});
  EXPECT_NE(error_of("G41 D7\nG1 X10\n", options).find("comp.ngc:1:5: G41: tool 7 has no radius"), std::string::npos);
}

// What cannot be compensated is an error naming the line and the radius.
TEST(CutterComp, ImpossibleCompensationIsAnError) {
  // Entry move no longer than the radius.
  EXPECT_NE(error_of("F100\nG41.1 D4\nG1 X1\n").find("comp.ngc:3:1: cutter compensation entry move of 1 mm"),
            std::string::npos);
  // r = 5 in a 3 mm wide notch: the up move's offset would have to run backwards (its end
  // moves from (5, 5) to (5, -2) against its direction +Y).
  const std::string gouge = error_of("F100\nG41.1 D10\nG1 X10 Y0\nG1 X10 Y3\nG1 X0 Y3\n");
  EXPECT_NE(gouge.find("comp.ngc:5:1: cutter compensation: the straight move before this one would run backwards"),
            std::string::npos)
      << gouge;
  EXPECT_NE(gouge.find("tool radius 5 mm"), std::string::npos) << gouge;
  // An arc smaller than the tool with the tool inside it.
  EXPECT_NE(error_of("F100\nG41.1 D4\nG1 X10\nG3 X10 Y3 R1.5\n")
                .find("arc of radius 1.5 mm with the tool (radius 2 mm) on its inside"),
            std::string::npos);
  // What LinuxCNC refuses while compensation is on.
  EXPECT_NE(error_of("F100\nG41.1 D2\nG1 X10\nG18\n").find("G18 with cutter compensation on"), std::string::npos);
  EXPECT_NE(error_of("F100\nG41.1 D2\nG1 X10\nG81 X0 Z-1 R1\n").find("G81 with cutter compensation on"),
            std::string::npos);
  EXPECT_NE(error_of("F100\nG41.1 D2\nG41.1 D2\n").find("already on"), std::string::npos);
  EXPECT_NE(error_of("F100\nG41.1 D2\nG1 X10\nG40\nG2 X20 R5\n").find("arc just after G40"), std::string::npos);
  EXPECT_NE(error_of("G19\nG41.1 D2\n").find("G41.1 in G19"), std::string::npos);
  // A stop sends the held move ending where the tool is: an arc after it into a concave corner
  // would start off its offset circle (found by the fuzzer). After a straight it is no matter,
  // nor where the arc continues tangentially.
  const std::string stopped = error_of("G0 X-5 Y0 Z1\nG41.1 D4\nM1 X20 Y0\nG3 X30 Y10 R74 F300\nG1 X30 Y30\n");
  EXPECT_NE(stopped.find("comp.ngc:4:1: cutter compensation: this G3 arc turns into a concave corner after a stop"),
            std::string::npos)
      << stopped;
  EXPECT_NO_THROW(read("G0 X-5 Y0 Z1\nG41.1 D4\nG0 X20 Y0\nG3 X30 Y10 R74 F300\nG1 X30 Y30\n"));
  EXPECT_NO_THROW(read("G0 X-5 Y0 Z1\nG41.1 D4\nM1 X20 Y0\nG1 X30 Y10 F300\nG1 X30 Y30\n"));
  // From an unknown position (no start position given): the offset needs the plane's axes
  // before the move, and a held block the third axis by its end.
  GcodeOptions unknown;
  EXPECT_NE(gcode_test::error_text("G0 X-5\nG41.1 D4\nG1 X0 Y5 F100\n", unknown, "u.ngc")
                .find("u.ngc:3:1: cutter compensation while the Y position is unknown"),
            std::string::npos);
  EXPECT_NE(gcode_test::error_text("G0 X-5 Y0\nG41.1 D4\nG1 X0 Y5 F100\n", unknown, "u.ngc")
                .find("u.ngc:3:1: cutter compensation while the Z position is unknown"),
            std::string::npos);
  const Program known =
      gcode_test::read_text("G0 X-5 Y0\nG41.1 D4\nG1 X0 Y5 Z1 F100\nG1 X10\nG40 G0 X20\n", unknown, "u.ngc");
  ASSERT_FALSE(known.blocks.empty());
  EXPECT_EQ(known.blocks.back().end_mm, Eigen::Vector3d(20, 5, 1));
}

// G28 / G30: through the named point, then the named axes (all when none is named) to the
// reference, whose gauge point puts the tip a tool length below it. G28.1 stores the position.
TEST(HomeReturn, ThroughTheIntermediatePointToTheReference) {
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d(0, 0, 100);
  options.reference_mm = {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, 5, 6)};
  options.tool_length_mm = {{1, 10.0}};
  const Program p = read("T1 M6\nG0 X5 Y5 Z5\nG91 G28 Z0\nG90 G28 X7\nG30\nG28.1\nG0 X0 Y0 Z0\nG28\nM2\n", options);
  ASSERT_EQ(p.blocks.size(), 7u);
  // T1 M6: the spindle stays at the start's gauge point (0, 0, 100); the tip is 10 below.
  expect_line(p.blocks[0], {0, 0, 90}, {5, 5, 5});
  expect_line(p.blocks[1], {5, 5, 5}, {5, 5, -7});   // Z only: 3 - 10
  expect_line(p.blocks[2], {5, 5, -7}, {7, 5, -7});  // the intermediate point X7
  expect_line(p.blocks[3], {7, 5, -7}, {1, 5, -7});  // X only to the reference
  expect_line(p.blocks[4], {1, 5, -7}, {4, 5, -4});  // G30: every axis, tip 6 - 10
  expect_line(p.blocks[5], {4, 5, -4}, {0, 0, 0});
  expect_line(p.blocks[6], {0, 0, 0}, {4, 5, -4});  // G28 to what G28.1 stored
  for (const Block& b : p.blocks) EXPECT_EQ(b.kind, MotionKind::Rapid);
  EXPECT_NE(error_of("G28.1 X1\n").find("G28.1 with axis words"), std::string::npos);
  EXPECT_NE(error_of("G0 G28 X1\n").find("both use the axis words"), std::string::npos);
}

// G53: machine coordinates count from the gauge point at all-zero axes (machine_zero_mm, here
// (0, 0, 400) as the bundled 3axis mill has it). Fanuc and Haas move the gauge point there, so
// with T1 (10 mm) the tip stops 10 below, G43 or not; LinuxCNC puts the tip there under G43.
TEST(HomeReturn, G53CountsFromTheMachineZero) {
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d(0, 0, 400);
  options.machine_zero_mm = Eigen::Vector3d(0, 0, 400);
  options.tool_length_mm = {{1, 10.0}};
  options.work_offsets_mm["G54"] = Eigen::Vector3d(0, 0, -300);
  const std::string text = "T1 M6\nG54 G43 H1 G0 X5 Y5 Z5\nG53 G0 Z-20\nG49\nG53 G0 Z-30\nM2\n";
  options.flavor = GcodeOptions::Flavor::Fanuc;
  const Program fanuc = read(text, options);
  ASSERT_EQ(fanuc.blocks.size(), 3u);
  expect_line(fanuc.blocks[0], {0, 0, 390}, {5, 5, -295});
  expect_line(fanuc.blocks[1], {5, 5, -295}, {5, 5, 370});  // 400 - 20 - 10
  expect_line(fanuc.blocks[2], {5, 5, 370}, {5, 5, 360});   // 400 - 30 - 10
  options.flavor = GcodeOptions::Flavor::LinuxCnc;
  const Program linuxcnc = read(text, options);
  ASSERT_EQ(linuxcnc.blocks.size(), 3u);
  expect_line(linuxcnc.blocks[1], {5, 5, -295}, {5, 5, 380});  // G43: the tip at 400 - 20
  expect_line(linuxcnc.blocks[2], {5, 5, 380}, {5, 5, 360});   // G49: the gauge point at 370
}

// A start position: the first moves go from it; G91 and G10 L20 work at once.
TEST(StartPosition, MovesGoFromTheStart) {
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d(0, 0, 50);
  const Program p = read("G0 X10\nG91 G0 Y5\nG90 G10 L20 P1 Z0\nG0 Z-5\nM2\n", options);
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_line(p.blocks[0], {0, 0, 50}, {10, 0, 50});
  expect_line(p.blocks[1], {10, 0, 50}, {10, 5, 50});
  expect_line(p.blocks[2], {10, 5, 50}, {10, 5, 45});  // G54's Z zero is now at Z 50
  EXPECT_TRUE(p.warnings.empty());
}

// Lexing that CAM posts and Fanuc controls produce.
TEST(GcodeLexing, PostsAndFanucTapes) {
  // A UTF-8 byte order mark, a ':' program number, nested comments.
  const Program p = read("\xEF\xBB\xBF:0097 (FANUC)\nG0 X1\nG0 X2 (DRILL 4.5MM (R))\nG0 X3 (A (B C)\nM2\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_line(p.blocks[2], {2, 0, 0}, {3, 0, 0});
  // K0 in a G17 arc (Fanuc and sender posts): ignored; LinuxCNC refuses it.
  EXPECT_NO_THROW(read("F100\nG2 X10 Y0 I5 J0 K0\n"));
  GcodeOptions linuxcnc;
  linuxcnc.flavor = GcodeOptions::Flavor::LinuxCnc;
  EXPECT_NE(error_of("F100\nG2 X10 Y0 I5 J0 K0\n", linuxcnc).find("K word in a XY-plane arc"), std::string::npos);
  // An R arc whose |R| falls short of half the chord by up to 0.00005 in (0.00127 mm)
  // (LinuxCNC's RADIUS_TOLERANCE) is a half circle; by 0.002 mm it is an error.
  const Program r = read("F100\nG2 X10 Y0 R4.999\n");
  expect_point(r.blocks[0].center_mm, {5, 0, 0}, "centre");
  EXPECT_NE(error_of("F100\nG2 X10 Y0 R4.998\n").find("less than half the chord"), std::string::npos);
}

// G5.1 (quadratic) and G5 (cubic) splines as straight moves: every vertex lies on the Bezier
// curve B(t) = sum C(n,k) (1-t)^(n-k) t^k P_k (the closed form, evaluated here by the
// binomial sum, not by de Casteljau), and no chord strays more than 1 um from it.
TEST(GcodeSplines, VerticesOnTheCurveChordsWithinAMicron) {
  const Program p = read("G21 G17 F100\nG5.1 X10 Y0 I5 J5\nG5 X20 Y0 I2 J2 P-2 Q2\nX30 Y0 P-2 Q2\nM2\n");
  auto bezier = [](const std::vector<Eigen::Vector2d>& c, double t) {
    const int n = static_cast<int>(c.size()) - 1;
    Eigen::Vector2d b = Eigen::Vector2d::Zero();
    double binomial = 1.0;
    for (int k = 0; k <= n; ++k) {
      b += binomial * std::pow(1.0 - t, n - k) * std::pow(t, k) * c[static_cast<size_t>(k)];
      binomial = binomial * (n - k) / (k + 1);
    }
    return b;
  };
  // The curves: quadratic (0,0) (5,5) (10,0); cubic (10,0) (12,2) (18,2) (20,0); the next cubic
  // without I J starts with the mirror of (18,2) through (20,0): (22,-2), then (28,2), (30,0).
  const std::vector<std::vector<Eigen::Vector2d>> curves = {
      {{0, 0}, {5, 5}, {10, 0}}, {{10, 0}, {12, 2}, {18, 2}, {20, 0}}, {{20, 0}, {22, -2}, {28, 2}, {30, 0}}};
  const int lines[] = {2, 3, 4};
  for (size_t c = 0; c < curves.size(); ++c) {
    std::vector<Block> run;
    for (const Block& b : p.blocks) {
      if (b.source.line == lines[c]) run.push_back(b);
    }
    ASSERT_GE(run.size(), 10u) << "curve " << c;
    expect_point(run.front().start_mm, {curves[c].front().x(), curves[c].front().y(), 0}, "start");
    expect_point(run.back().end_mm, {curves[c].back().x(), curves[c].back().y(), 0}, "end");
    // Vertices: at t = i / n (uniform steps).
    const double n = static_cast<double>(run.size());
    for (size_t i = 0; i < run.size(); ++i) {
      const Eigen::Vector2d want = bezier(curves[c], (i + 1) / n);
      EXPECT_LT((run[i].end_mm.head<2>() - want).norm(), 1e-9) << "curve " << c << " vertex " << i;
      // The chord's midpoint against the curve's point half way.
      const Eigen::Vector2d mid = (run[i].start_mm.head<2>() + run[i].end_mm.head<2>()) / 2.0;
      EXPECT_LT((mid - bezier(curves[c], (i + 0.5) / n)).norm(), 0.001 + 1e-12) << "curve " << c << " chord " << i;
    }
  }
  EXPECT_NE(error_of("F100\nG5 X10 Y0 P1 Q1\n").find("G5 without I J"), std::string::npos);
  EXPECT_NE(error_of("F100\nG18\nG5.1 X10 I1 J1\n").find("outside G17"), std::string::npos);
}

// Fanuc G68 X Y R: programmed X Y turn by R about the centre (hand-rotated points: (x, y) about
// (cx, cy) by 90 deg is (cx - (y - cy), cy + (x - cx))); G91 increments and I J turn too;
// G69 ends it.
TEST(CoordinateRotation, G68TurnsPointsIncrementsAndCentres) {
  const Program p =
      read("G21 G17 G90 F100\nG68 X10 Y0 R90\nG1 X20 Y0\nG91 G1 X5\nG90 G2 X20 Y0 I-2.5 J0\nG69\nG1 X0 Y0\nM2\n");
  ASSERT_EQ(p.blocks.size(), 4u);
  expect_line(p.blocks[0], {0, 0, 0}, {10, 10, 0});    // (20, 0) about (10, 0)
  expect_line(p.blocks[1], {10, 10, 0}, {10, 15, 0});  // the increment (5, 0) turned to (0, 5)
  const Block& arc = p.blocks[2];                      // program (25, 0) -> (20, 0) about (22.5, 0)
  ASSERT_EQ(arc.kind, MotionKind::Arc);
  expect_point(arc.end_mm, {10, 10, 0}, "arc end");
  expect_point(arc.center_mm, {10, 12.5, 0}, "arc centre");
  expect_line(p.blocks[3], {10, 10, 0}, {0, 0, 0});
  // A drilling cycle's holes turn with it: (10, 0) about the origin by 90 deg is (0, 10).
  const Program drill = read("G21 G17 G90 G98 F100\nG0 Z5\nG68 X0 Y0 R90\nG81 X10 Y0 Z-1 R1\nG80\nM2\n");
  ASSERT_GE(drill.blocks.size(), 2u);
  expect_point(drill.blocks[1].end_mm, {0, 10, 5}, "over the hole");
  EXPECT_NE(error_of("G68 X0 Y0\n").find("G68 without R"), std::string::npos);
  GcodeOptions linuxcnc;
  linuxcnc.flavor = GcodeOptions::Flavor::LinuxCnc;
  EXPECT_NE(error_of("G68 X0 Y0 R10\n", linuxcnc).find("unknown G code G68"), std::string::npos);
}

// Fanuc ,R and ,C between two G1 lines: a left turn of 90 deg at (10, 0). ,R2 needs
// t = 2 tan(45 deg) = 2 mm of each line: the first ends at (8, 0), a counterclockwise arc about
// (8, 2) reaches (10, 2); ,C1 cuts from (9, 0) to (10, 1).
TEST(CornerRounding, RadiusAndChamferBetweenLines) {
  const Program r = read("G21 G17 F100\nG1 X10 Y0 ,R2\nG1 X10 Y10\nM2\n");
  ASSERT_EQ(r.blocks.size(), 3u);
  expect_line(r.blocks[0], {0, 0, 0}, {8, 0, 0});
  ASSERT_EQ(r.blocks[1].kind, MotionKind::Arc);
  expect_point(r.blocks[1].end_mm, {10, 2, 0}, "arc end");
  expect_point(r.blocks[1].center_mm, {8, 2, 0}, "arc centre");
  EXPECT_EQ(r.blocks[1].normal, Eigen::Vector3d(0, 0, 1));
  expect_line(r.blocks[2], {10, 2, 0}, {10, 10, 0});
  const Program c = read("G21 G17 F100\nG1 X10 Y0 ,C1\nG1 X10 Y10\nM2\n");
  ASSERT_EQ(c.blocks.size(), 3u);
  expect_line(c.blocks[0], {0, 0, 0}, {9, 0, 0});
  expect_line(c.blocks[1], {9, 0, 0}, {10, 1, 0});
  expect_line(c.blocks[2], {10, 1, 0}, {10, 10, 0});
  EXPECT_NE(error_of("F100\nG1 X10 ,R20\nG1 Y10\n").find("expected a smaller corner"), std::string::npos);
  EXPECT_NE(error_of("F100\nG1 X10 ,R1\nG0 Y10\n").find("needs a G1 line next"), std::string::npos);
}

// G33: a straight feed at K per revolution times S; G33.1: down and back at that feed.
TEST(SpindleSynchronized, ThreadingAndRigidTapping) {
  const Program p = read("G21 S600 M3\nG0 X1 Y2 Z5\nG33 Z-5 K1.25\nG0 Z5\nG33.1 Z-10 K0.7\nM2\n");
  ASSERT_EQ(p.blocks.size(), 5u);
  expect_line(p.blocks[1], {1, 2, 5}, {1, 2, -5});
  EXPECT_DOUBLE_EQ(p.blocks[1].feed_mm_per_min, 1.25 * 600);
  expect_line(p.blocks[3], {1, 2, 5}, {1, 2, -10});
  expect_line(p.blocks[4], {1, 2, -10}, {1, 2, 5});
  EXPECT_DOUBLE_EQ(p.blocks[4].feed_mm_per_min, 0.7 * 600);
  EXPECT_NE(error_of("G33 Z-5 K1\n").find("spindle stopped"), std::string::npos);
  EXPECT_NE(error_of("S100 M3\nG33.1 X1 Z-5 K1\n").find("G33.1 with X or Y"), std::string::npos);
}

}  // namespace
}  // namespace vcut::io
