// SINUMERIK machine-related words on the bundled machines: CYCLE800 (swivel), SUPA / G53 / G153,
// D0, G74 / G75. Expected frames are written by hand from the cycle's definition (the turn R
// from the axis order, the frame (X0 Y0 Z0) + R (p + (X1 Y1 Z1))) and expected axis angles from
// the machines' documented tool-axis formulas and axis lines (their files' headers), not from
// the reader.
#include <gtest/gtest.h>

#include <optional>
#include <vcut/io/input_error.h>
#include <vcut/io/machine_file.h>
#include <vcut/io/program_reader.h>
#include <vcut/io/sinumerik_reader.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::MotionKind;
using kinematics::Program;

constexpr double kTol = 1e-9;
constexpr double kDeg = M_PI / 180.0;
const double kS30 = 0.5, kC30 = std::sqrt(3.0) / 2.0;  // sin, cos 30 deg

// The options a job gives: the machine, and tools by number with their gauge lengths (mm).
SinumerikOptions on_machine(const std::string& name, const std::map<int, double>& lengths = {}) {
  GcodeOptions gcode;
  std::map<int, removal::Cutter> tools;
  for (const auto& [number, length] : lengths) {
    removal::Cutter c;
    c.gauge_length_mm = length;
    tools[number] = c;
  }
  set_machine(gcode, read_machine_file(resolve_machine(name)), tools);
  return sinumerik_options(gcode);
}

Program read(const std::string& text, const SinumerikOptions& options = {}) {
  Program program;
  SinumerikState state;
  std::istringstream in(text);
  read_sinumerik(in, "swivel.mpf", options, program, state);
  return program;
}

std::string error_of(const std::string& text, const SinumerikOptions& options = {}) {
  try {
    read(text, options);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return "";
}

void expect_vec(const Eigen::Vector3d& got, const Eigen::Vector3d& want, double tol = kTol) {
  EXPECT_LE((got - want).norm(), tol) << "got (" << got.transpose() << "), want (" << want.transpose() << ")";
}

Block last_of_line(const Program& program, int line) {
  std::optional<Block> found;
  for (const Block& b : program.blocks)
    if (b.source.line == line) found = b;
  EXPECT_TRUE(found.has_value()) << "no block from line " << line;
  return found.value_or(Block{});
}

// Rx(30 deg) by hand: x stays, y -> (0, c, s), z -> (0, -s, c).
Eigen::Vector3d rx30(const Eigen::Vector3d& p) {
  return {p.x(), kC30 * p.y() - kS30 * p.z(), kS30 * p.y() + kC30 * p.z()};
}

// table-table-ac's header: the A axis line runs through (0, -20, -100) along x, the table
// turns a point w of the workpiece to c + Rx(A) (w - c) in the machine; so the tip standing at
// machine point m lies at w = c + Rx(-A) (m - c) on the workpiece.
Eigen::Vector3d on_ac_table_turned_by_minus_30(const Eigen::Vector3d& m) {
  const Eigen::Vector3d c(0, -20, -100);
  return c + rx30(m - c);
}

TEST(SinumerikSwivel, Cycle800AxisByAxisXyzPlacesPointsAndTurnsTheAcTable) {
  SinumerikOptions options = on_machine("table-table-ac");
  options.work_offsets_mm["G54"] = Eigen::Vector3d(1, 2, 3);
  // _MODE 57: X, then Y, then Z; _A 30 about X. X0 (100, 0, 0), X1 (0, 0, 2); _DIR -1.
  const Program p = read(
      "N10 G54 G0 X10 Y20 Z5\n"
      "N20 CYCLE800(0,\"TC1\",0,57,100,0,0,30,0,0,0,0,2,-1,0,1)\n"
      "N30 G0 X10 Y20 Z5\n"
      "N40 G1 X0 F1000\n",
      options);
  // Point: G54 + X0 + R (p + X1).
  expect_vec(last_of_line(p, 3).end_mm, Eigen::Vector3d(1, 2, 3) + Eigen::Vector3d(100, 0, 0) + rx30({10, 20, 7}));
  expect_vec(last_of_line(p, 4).end_mm, Eigen::Vector3d(1, 2, 3) + Eigen::Vector3d(100, 0, 0) + rx30({0, 20, 7}));
  // The tool along R z = (0, -1/2, sqrt3/2); the header's tool axis (sin A sin C, sin A cos C,
  // cos A) gives A = -30, C = 0 (the solution with A <= 0 for _DIR -1).
  const Block& b = last_of_line(p, 4);
  EXPECT_NEAR(b.end_rotary.angle_rad[0], -30 * kDeg, 1e-9);
  EXPECT_NEAR(b.end_rotary.angle_rad[2], 0.0, 1e-9);
  EXPECT_TRUE(b.tool_pose);
  expect_vec(b.end_axis, {0, -kS30, kC30});
  // The swing: the rotaries turn in steps of at most 1 deg with the linear axes held, so the
  // tip (at the gauge point: no tool) ends where the turned table carries it.
  int steps = 0;
  for (const Block& s : p.blocks) steps += s.source.line == 2 ? 1 : 0;
  EXPECT_EQ(steps, 30);
  expect_vec(last_of_line(p, 2).end_mm, on_ac_table_turned_by_minus_30(Eigen::Vector3d(11, 22, 8)), 1e-9);
  // _DIR +1: A >= 0, so A = 30 and C = 180 (or -180).
  const Program plus = read("N10 G0 X10 Y20 Z5\nN20 CYCLE800(0,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,1,0,1)\nN30 X0\n",
                            on_machine("table-table-ac"));
  EXPECT_NEAR(last_of_line(plus, 3).end_rotary.angle_rad[0], 30 * kDeg, 1e-9);
  EXPECT_NEAR(std::abs(last_of_line(plus, 3).end_rotary.angle_rad[2]), 180 * kDeg, 1e-9);
}

TEST(SinumerikSwivel, Cycle800ZyxOrderTurnsAboutTheNewAxes) {
  // _MODE 27: Z, then Y, then X; _A 90 about Z, then _B 30 about the new Y: R = Rz(90) Ry(30).
  // R x = Rz(90) (cos30, 0, -sin30) = (0, cos30, -sin30); R z = (0, 1/2, sqrt3/2).
  const Program p = read(
      "N10 G0 X0 Y0 Z50\n"
      "N20 CYCLE800(0,\"TC1\",0,27,0,0,0,90,30,0,0,0,0,1,0,1)\n"
      "N30 G0 X1 Y0 Z0\n",
      on_machine("table-table-ac"));
  expect_vec(last_of_line(p, 3).end_mm, {0, kC30, -kS30});
  // Tool (0, 1/2, sqrt3/2) = (sin A sin C, sin A cos C, cos A): A = 30, C = 0 for _DIR +1.
  EXPECT_NEAR(last_of_line(p, 3).end_rotary.angle_rad[0], 30 * kDeg, 1e-9);
  EXPECT_NEAR(last_of_line(p, 3).end_rotary.angle_rad[2], 0.0, 1e-9);
}

TEST(SinumerikSwivel, Cycle800RotaryAxesDirectGivesTheTablesFrame) {
  // _MODE 192: _A is rotary axis 1, the one next to the bed (A, under C in WCAFXYZT), _B axis 2.
  // A = -30 tilts the tool to (0, -1/2, sqrt3/2) in the workpiece, the frame Rx(30) of the
  // first test: the same points.
  const Program p = read(
      "N10 G0 X10 Y20 Z5\n"
      "N20 CYCLE800(0,\"TC1\",0,192,0,0,0,-30,0,0,0,0,0,1,0,1)\n"
      "N30 G0 X10 Y20 Z5\n",
      on_machine("table-table-ac"));
  expect_vec(last_of_line(p, 3).end_mm, rx30({10, 20, 5}), 1e-9);
  EXPECT_NEAR(last_of_line(p, 3).end_rotary.angle_rad[0], -30 * kDeg, 1e-12);
  EXPECT_NEAR(last_of_line(p, 3).end_rotary.angle_rad[2], 0.0, 1e-12);
  expect_vec(last_of_line(p, 3).end_axis, {0, -kS30, kC30}, 1e-9);
}

TEST(SinumerikSwivel, Cycle800TurnsTheBcHeadAboutItsPivot) {
  // head-table-bc's header: tool axis (sin B, 0, cos B) turned by the C table; the B pivot 180
  // mm above the spindle nose. _MODE 57, _B 30 about Y: R z = (1/2, 0, sqrt3/2), so B = 30,
  // C = 0 for _DIR +1. No tool: the tip is the nose, at (10, 0, 5), the pivot 180 above it;
  // B turns the nose about the pivot: (10, 0, 185) + Ry(30) (0, 0, -180) = (-80, 0, 185 - 180
  // cos 30).
  const SinumerikOptions bc = on_machine("head-table-bc");
  const Program p = read(
      "N10 G0 X10 Y0 Z5\n"
      "N20 CYCLE800(0,\"TC1\",0,57,0,0,0,0,30,0,0,0,0,1,0,1)\n"
      "N30 G0 X1 Y2 Z3\n",
      bc);
  expect_vec(last_of_line(p, 2).end_mm, {10 - 180 * kS30, 0, 185 - 180 * kC30}, 1e-9);
  // Ry(30) (1, 2, 3) = (cos30 + 3 sin30, 2, -sin30 + 3 cos30).
  expect_vec(last_of_line(p, 3).end_mm, {kC30 + 3 * kS30, 2, -kS30 + 3 * kC30}, 1e-9);
  EXPECT_NEAR(last_of_line(p, 3).end_rotary.angle_rad[1], 30 * kDeg, 1e-9);
  EXPECT_NEAR(last_of_line(p, 3).end_rotary.angle_rad[2], 0.0, 1e-9);
  // _MODE 192 on a head-table machine: rotary axis 1 is the head's B, axis 2 the table's C
  // (Siemens' kinematics type M); B 30 gives the same frame.
  const Program direct = read(
      "N10 G0 X10 Y0 Z5\n"
      "N20 CYCLE800(0,\"TC1\",0,192,0,0,0,30,0,0,0,0,0,1,0,1)\n"
      "N30 G0 X1 Y2 Z3\n",
      bc);
  expect_vec(last_of_line(direct, 3).end_mm, {kC30 + 3 * kS30, 2, -kS30 + 3 * kC30}, 1e-9);
  EXPECT_NEAR(last_of_line(direct, 3).end_rotary.angle_rad[1], 30 * kDeg, 1e-12);
}

// Projection angles (_MODE 128 + the axis order), as ROTS defines them (Siemens K2): alpha 30
// about X, beta 45 about Y are the angles of the plane's traces, so its normal is along
// (tan beta, -tan alpha, 1) (the YZ trace turned alpha about X from Z, the ZX trace beta about Y),
// and the new X axis is the old X turned beta about Y: (cos 45, 0, -sin 45), in the old ZX
// plane. Order X Y (185 = 128 + 57) and Y X (182 = 128 + 54, _A then about Y) give one frame.
TEST(SinumerikSwivel, Cycle800ProjectionAnglesAsRotsDefinesThem) {
  const Eigen::Vector3d z = Eigen::Vector3d(1.0, -std::tan(30 * kDeg), 1.0).normalized();
  const Eigen::Vector3d x(std::sqrt(0.5), 0, -std::sqrt(0.5));
  const Eigen::Vector3d y = z.cross(x);
  for (const char* call :
       {"CYCLE800(0,\"\",0,185,0,0,0,30,45,0,0,0,0,0,0,1)", "CYCLE800(0,\"\",0,182,0,0,0,45,30,0,0,0,0,0,0,1)"}) {
    const Program p = read(std::string("N10 G0 X0 Y0 Z0\n") + call + "\nN30 G0 X1 Y0 Z0\nN40 X0 Y1\nN50 Y0 Z1\n");
    expect_vec(last_of_line(p, 3).end_mm, x, 1e-12);
    expect_vec(last_of_line(p, 4).end_mm, y, 1e-12);
    expect_vec(last_of_line(p, 5).end_mm, z, 1e-12);
  }
  // The third angle turns about the new Z: 90 deg takes the frame's X to the plane's Y.
  const Program third = read("N10 G0 X0 Y0 Z0\nCYCLE800(0,\"\",0,185,0,0,0,30,45,90,0,0,0,0,0,1)\nN30 G0 X1 Y0 Z0\n");
  expect_vec(last_of_line(third, 3).end_mm, y, 1e-12);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nCYCLE800(0,\"\",0,185,0,0,0,90,45,0,0,0,0,0,0,1)\n").find("expected within -90..90"),
            std::string::npos);
}

TEST(SinumerikSwivel, Cycle800AdditiveFollowsTheFrameAndNewReplacesIt) {
  // _DIR 0: the frame only, no machine needed. 10 deg, then 20 more (additive, _ST 1) = 30.
  const Program p = read(
      "N10 G0 X0 Y0 Z0\n"
      "N20 CYCLE800(0,\"\",0,57,0,0,0,10,0,0,0,0,0,0,0,1)\n"
      "N30 CYCLE800(0,\"\",1,57,0,0,0,20,0,0,0,0,0,0,0,1)\n"
      "N40 G0 X10 Y20 Z5\n"
      "N50 CYCLE800(0,\"\",0,57,0,0,0,30,0,0,0,0,0,0,0,1)\n"
      "N60 G0 X1 Y2 Z3\n"
      "N70 CYCLE800()\n"
      "N80 G0 X1 Y2 Z3\n");
  expect_vec(last_of_line(p, 4).end_mm, rx30({10, 20, 5}), 1e-9);
  expect_vec(last_of_line(p, 6).end_mm, rx30({1, 2, 3}), 1e-9);  // new: 30, not 60
  expect_vec(last_of_line(p, 8).end_mm, {1, 2, 3});              // deselected, rotaries at zero
  EXPECT_FALSE(last_of_line(p, 4).end_rotary.any());             // nothing turned
}

TEST(SinumerikSwivel, Cycle800RetractsThenSwingsAndDeselectKeepsTheTurnedAxes) {
  // T1 100 mm long. table-table-ac has no home: all-zero axes, the spindle nose 500 mm above the
  // table top (header), so the retracted tip is at Z 400.
  const SinumerikOptions options = on_machine("table-table-ac", {{1, 100.0}});
  const Program p = read(
      "N10 T1 M6\n"
      "N20 G0 X10 Y20 Z5\n"
      "N30 CYCLE800(1,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,-1,0,1)\n"
      "N40 CYCLE800()\n"
      "N50 G0 X0 Y0 Z50\n",
      options);
  // The first block of line 3 is the retraction, straight up.
  std::optional<Block> first;
  for (const Block& b : p.blocks)
    if (b.source.line == 3 && !first) first = b;
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->kind, MotionKind::Rapid);
  expect_vec(first->start_mm, {10, 20, 5});
  expect_vec(first->end_mm, {10, 20, 400});
  // Then the table turns under the held tip: it ends where the turned table carries (10 20 400).
  expect_vec(last_of_line(p, 3).end_mm, on_ac_table_turned_by_minus_30({10, 20, 400}), 1e-9);
  // CYCLE800(): the frame goes but the table stays turned, so X Y Z are the machine's axes.
  expect_vec(last_of_line(p, 5).end_mm, on_ac_table_turned_by_minus_30({0, 0, 50}), 1e-9);
  EXPECT_NEAR(last_of_line(p, 5).end_rotary.angle_rad[0], -30 * kDeg, 1e-9);
  // _FR 5: _FR_I 20 mm along the tool (still upright) before the turn.
  const Program up =
      read("N10 T1 M6\nN20 G0 X10 Y20 Z5\nN30 CYCLE800(5,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,-1,20,1)\n", options);
  std::optional<Block> lift;
  for (const Block& b : up.blocks)
    if (b.source.line == 3 && !lift) lift = b;
  ASSERT_TRUE(lift.has_value());
  expect_vec(lift->start_mm, {10, 20, 5});
  expect_vec(lift->end_mm, {10, 20, 25});
}

TEST(SinumerikSwivel, MachineCoordinatesAndToolOffsetOff) {
  // 3axis: spindle nose 400 mm above the table top at all-zero axes (header), so machine
  // coordinates count from (0, 0, 400) on the workpiece; T1 100 mm.
  SinumerikOptions options = on_machine("3axis", {{1, 100.0}});
  options.work_offsets_mm["G54"] = Eigen::Vector3d(0, 0, -300);
  const Program p = read(
      "N10 T1 M6 D1\n"
      "N20 G54 G0 X10 Y20 Z5\n"
      "N30 SUPA G0 Z-10 D0\n"  // the gauge point at machine Z -10 (390): the tip 100 below
      "N40 G53 X5\n"           // machine X 5; Y and Z stay
      "N50 G0 Z=20 D1\n"       // the work frame again, the tip at G54 Z 20
      "N60 G153 Z=-50\n"       // machine Z -50 (350), D1: the tip there
      "N70 G74 X1=0 Z1=0\n"    // reference point: home = all-zero axes, gauge at Z 400
      "N80 G75 FP=2 Y1=0\n",   // fixed point 2: no second home, so the home again
      options);
  // From the machine's home (all-zero axes: the gauge point at 400, T1's tip 100 below).
  expect_vec(last_of_line(p, 2).start_mm, {0, 0, 300});
  expect_vec(last_of_line(p, 2).end_mm, {10, 20, -295});
  expect_vec(last_of_line(p, 3).end_mm, {10, 20, 290});
  expect_vec(last_of_line(p, 4).end_mm, {5, 20, 290});
  expect_vec(last_of_line(p, 5).end_mm, {5, 20, -280});
  expect_vec(last_of_line(p, 6).end_mm, {5, 20, 350});
  expect_vec(last_of_line(p, 7).end_mm, {0, 20, 300});
  expect_vec(last_of_line(p, 8).end_mm, {0, 0, 300});
}

TEST(SinumerikSwivel, ProgramsAsFusionWritesThem) {
  // A Fusion 840D post's tool change: named tools, SUPA home moves, FNORM, SETMS, G505.
  SinumerikOptions options = on_machine("3axis", {{1, 50.0}, {2, 60.0}});
  options.work_offsets_mm["G505"] = Eigen::Vector3d(0, 0, -200);
  const Program p = read(
      "N10 DEF REAL _Z_HOME\n"
      "N20 _Z_HOME=-10\n"
      "N30 G17 G710 G94 G90 FNORM\n"
      "N40 T=\"DRILL 8.5\" M6\n"
      "N50 SUPA G0 Z=_Z_HOME D0\n"
      "N60 G505 SETMS(1)\n"
      "N70 G0 X1 Y2 Z3 D1\n"
      "N80 T=\"FLAT 6\" M6\n"
      "N90 G0 X4\n"
      "N100 T=\"DRILL 8.5\" M6\n"
      "N110 G0 X5\n",
      options);
  EXPECT_EQ(last_of_line(p, 7).tool, 1);
  expect_vec(last_of_line(p, 7).end_mm, {1, 2, -197});
  EXPECT_EQ(last_of_line(p, 9).tool, 2);
  EXPECT_EQ(last_of_line(p, 11).tool, 1);
  ASSERT_GE(p.warnings.size(), 2u);
  EXPECT_NE(p.warnings[0].find("swivel.mpf:4:5: tool T=\"DRILL 8.5\" taken as tool 1"), std::string::npos)
      << p.warnings[0];
}

// Found in review: in an axis program (A B C without TRAORI) X Y Z are the machine's already,
// so SUPA does not turn them again; M6 takes D1 again after D0; G74 goes on to the block's
// M30; CYCLE800( ) with a blank deselects; a new plane of zero angles is no plane, so rotary
// words may follow it.
TEST(SinumerikSwivel, ReviewFindings) {
  const SinumerikOptions ac = on_machine("table-table-ac", {{1, 100.0}, {2, 50.0}});
  const Program axes = read("N10 G0 X0 Y0 Z100 A30\nN20 G0 SUPA Z0\n", ac);
  EXPECT_FALSE(last_of_line(axes, 2).tool_pose);
  expect_vec(last_of_line(axes, 2).end_mm, {0, 0, 500});  // the axes' point: machine Z 0, no tool
  const Program edge = read("N10 T1 M6 D0\nN20 G0 X0 Y0 Z50\nN30 T2 M6\nN40 G0 Z60\n", ac);
  expect_vec(last_of_line(edge, 2).end_mm, {0, 0, -50});  // D0: the gauge point at Z50
  expect_vec(last_of_line(edge, 4).end_mm, {0, 0, 60});   // M6: D1, the tip at Z60
  const Program end = read("N10 G0 X0 Y0 Z5\nN20 G74 Z1=0 M30\nN30 G0 X7\n", ac);
  EXPECT_EQ(end.blocks.back().source.line, 2);  // M30 ended the program: no line 30
  const Program blank = read(
      "N10 G0 X0 Y0 Z5\nN20 CYCLE800(0,\"\",0,57,0,0,0,30,0,0,0,0,0,0,0,1)\nN30 CYCLE800( )\nN40 G0 X1 Y2 Z3\n", ac);
  expect_vec(last_of_line(blank, 4).end_mm, {1, 2, 3});
  EXPECT_NO_THROW(read("N10 G0 X0 Y0 Z5\nN20 CYCLE800(1,\"TC1\",0,57,0,0,0,0,0,0,0,0,0,1,100,1)\nN30 G0 A0 C0\n", ac));
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nCYCLE800(0,\"T\",0,192,0,0,0,1000000,0,0,0,0,0,1)\n", ac)
                .find("expected within +-720 deg"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nCYCLE800(0,\"T\",1,192,0,0,0,10,0,0,0,0,0,1)\n", ac).find("additive"),
            std::string::npos);
  // The swing goes out as 1 deg steps: from C 900000 back to 0 is more than 1,000 turns.
  const std::string spun = error_of("G0 X0 Y0 Z5 C900000\nCYCLE800(0,\"T\",0,192,0,0,0,10,0,0,0,0,0,1)\n", ac);
  EXPECT_NE(spun.find(":2:1: CYCLE800: the rotaries turn by 900000 deg in one move"), std::string::npos) << spun;
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nCYCLE81(\"x\",0,2,-5)\n").find("CYCLE81 with a text parameter"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nG3 TURN=2\n").find("TURN= outside an arc"), std::string::npos);
}

// Taps feed at their pitch times the speed: PIT 1.5 at SST 500 in, SST1 250 out; MPIT 10 (M10,
// coarse pitch 1.5 mm) at S 400; CYCLE85 at FFR in and RFF out.
TEST(SinumerikSwivel, TapsFeedAtTheirPitch) {
  auto feeds = [](const std::string& text) {
    std::vector<double> f;
    for (const Block& b : read(text).blocks)
      if (b.kind == MotionKind::Linear) f.push_back(b.feed_mm_per_min);
    return f;
  };
  EXPECT_EQ(feeds("S500 M3\nG0 X0 Y0 Z10\nCYCLE84(10,0,2,-20,,0,3,,1.5,0,500,250)\n"), (std::vector<double>{750, 375}));
  EXPECT_EQ(feeds("S400 M3\nG0 X0 Y0 Z10\nCYCLE84(10,0,2,-20,,0,3,10)\n"), (std::vector<double>{600, 600}));
  EXPECT_EQ(feeds("F100\nG0 X0 Y0 Z10\nCYCLE85(10,0,2,-5,,0,300,500)\n"), (std::vector<double>{300, 500}));
  EXPECT_NE(error_of("G0 X0 Y0 Z10\nCYCLE84(10,0,2,-20)\n").find("without its pitch and speed"), std::string::npos);
  EXPECT_NE(error_of("S400\nG0 X0 Y0 Z10\nCYCLE84(10,0,2,-20,,0,3,11)\n").find("MPIT 11"), std::string::npos);
}

TEST(SinumerikSwivel, BadInputNamesTheLine) {
  const SinumerikOptions ac = on_machine("table-table-ac");
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nCYCLE800(0,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,-1,0,1)\n")
                .find("swivel.mpf:2:1: CYCLE800 turns the rotary axes (_DIR -1): it needs the machine"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nCYCLE800(0,\"TC1\",0,64,0,0,0,30,0,0,0,0,0,-1,0,1)\n", ac)
                .find("swivel.mpf:2:1: CYCLE800 _MODE 64 (solid angle) is not supported"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nCYCLE800(3,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,-1,0,1)\n", ac).find("CYCLE800 _FR 3"),
            std::string::npos);
  EXPECT_NE(error_of("CYCLE800(5,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,0,10,1)\n")
                .find("swivel.mpf:1:1: CYCLE800 from an unknown X position (expected X, Y and Z programmed before "
                      "it, or the job's start: position"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nCYCLE800(0,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,-1,0,1) X1\n", ac)
                .find("CYCLE800 with axis words"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nCYCLE800(0,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,-1,0,1)\nG0 A0\n", ac)
                .find("swivel.mpf:3:4: rotary axis words with CYCLE800's plane on"),
            std::string::npos);
  EXPECT_NE(
      error_of("G0 X0 Y0 Z0\nCYCLE800(0,\"TC1\",0,9,0,0,0,30,0,10,0,0,0,0,0,1)\n").find("names no axis for turn 3"),
      std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nCYCLE800(0,\"TC1\",0,57,0,0,0,30,0,0,0,0,0,-1,0,1\n", ac).find("swivel.mpf:2:"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG0 X1=0\n").find("swivel.mpf:2:4: a machine axis X1= Y1= Z1= outside G74 / G75"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG74 X1=0\n").find("G74 goes to a point of the machine: it needs the machine"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG75 X1=0\n", ac).find("G75 without FP="), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG91 SUPA Z10\n").find("incremental Z in machine coordinates"), std::string::npos);
}

}  // namespace
}  // namespace vcut::io
