// Tests of the APT CL-data reader and of the dialect detector. Expected values are worked by
// hand from the statements' meaning in ISO 4343 / APT (noted where used): unit conversions by
// 25.4 mm/in, normalised axes as closed forms, arc angles from the CIRCLE/ geometry; none is
// copied from the reader's own output.
#include <gtest/gtest.h>
#include <vcut/io/apt_reader.h>
#include <vcut/io/gcode_reader.h>
#include <vcut/io/input_error.h>
#include <vcut/io/program_reader.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::MotionKind;
using kinematics::OrientationMode;
using kinematics::SpindleState;
using removal::CutterType;

// Hand values are exact decimals or closed forms in double: only the rounding of a few
// operations separates them from the reader's results.
constexpr double kTol = 1e-9;
constexpr double kPi = 3.14159265358979323846;
constexpr double kInch = 25.4;

AptProgram read(const std::string& text, const AptOptions& options = {}) {
  AptProgram out;
  AptState state;
  std::istringstream in(text);
  read_apt(in, "test.apt", options, out, state);
  return out;
}

InputError error_of(const std::string& text) {
  try {
    read(text);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return InputError("none");
}

// The error names test.apt:line:column first and contains `fragment`.
#define EXPECT_APT_ERROR(text, line_, column_, fragment)                                    \
  do {                                                                                      \
    const InputError e_ = error_of(text);                                                   \
    EXPECT_EQ(e_.file(), "test.apt") << e_.what();                                          \
    EXPECT_EQ(e_.line(), line_) << e_.what();                                               \
    EXPECT_EQ(e_.column(), column_) << e_.what();                                           \
    EXPECT_NE(std::string(e_.what()).find(fragment), std::string::npos) << e_.what();       \
    const std::string where_ = std::string("test.apt:") + std::to_string(line_) +           \
                               ((column_) > 0 ? ":" + std::to_string(column_) : "") + ": "; \
    EXPECT_EQ(std::string(e_.what()).rfind(where_, 0), 0u) << e_.what();                    \
  } while (0)

void expect_vec(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected, double tol = kTol) {
  EXPECT_NEAR(actual.x(), expected.x(), tol) << actual.transpose();
  EXPECT_NEAR(actual.y(), expected.y(), tol) << actual.transpose();
  EXPECT_NEAR(actual.z(), expected.z(), tol) << actual.transpose();
}

// The swept angle of an arc as program.h defines it: from start to end about `normal` by the
// right-hand rule, in (0, 2*pi], plus 2*pi per extra turn.
double swept_angle(const Block& b) {
  const Eigen::Vector3d n = b.normal.normalized();
  Eigen::Vector3d u = b.start_mm - b.center_mm;
  Eigen::Vector3d v = b.end_mm - b.center_mm;
  u -= n * n.dot(u);
  v -= n * n.dot(v);
  double angle = std::atan2(n.dot(u.cross(v)), u.dot(v));
  if (angle <= 0.0) angle += 2.0 * kPi;
  return angle + 2.0 * kPi * (b.turns - 1);
}

// ---------------------------------------------------------------- motions

TEST(AptReader, FromGotoFedratMakeToolPoseBlocks) {
  const AptProgram a = read(
      "PARTNO TEST PART, 1\n"
      "FROM/0,0,10\n"
      "FEDRAT/100\n"
      "GOTO/0,0,0\n"
      "GOTO/10.5,-2,0\n");
  const auto& p = a.program;
  ASSERT_EQ(p.files.size(), 1u);
  EXPECT_EQ(p.files[0], "test.apt");
  ASSERT_EQ(p.blocks.size(), 2u);
  const Block& b0 = p.blocks[0];
  EXPECT_EQ(b0.kind, MotionKind::Linear);
  expect_vec(b0.start_mm, {0, 0, 10});  // FROM/ is where the first GOTO starts
  expect_vec(b0.end_mm, {0, 0, 0});
  EXPECT_EQ(b0.feed_mm_per_min, 100.0);  // FEDRAT/ without units: mm/min (UNITS default MM)
  EXPECT_EQ(b0.feed_mode, kinematics::FeedMode::UnitsPerMinute);
  EXPECT_TRUE(b0.tool_pose);
  EXPECT_EQ(b0.orientation, OrientationMode::Vector);
  expect_vec(b0.start_axis, {0, 0, 1});  // without MULTAX/TLAXIS the axis is +Z
  expect_vec(b0.end_axis, {0, 0, 1});
  EXPECT_EQ(b0.tool, 1);  // no LOADTL/: tool 1
  EXPECT_EQ(b0.source.line, 4);
  EXPECT_EQ(p.where(b0.source), "test.apt:4");
  expect_vec(p.blocks[1].start_mm, {0, 0, 0});
  expect_vec(p.blocks[1].end_mm, {10.5, -2, 0});
  EXPECT_EQ(p.blocks[1].source.line, 5);
  // PARTNO is not read: one warning naming its place.
  ASSERT_EQ(p.warnings.size(), 1u);
  EXPECT_EQ(p.warnings[0].rfind("test.apt:1:1: ", 0), 0u) << p.warnings[0];
  EXPECT_NE(p.warnings[0].find("PARTNO"), std::string::npos);
  EXPECT_TRUE(a.cutters.empty());
}

TEST(AptReader, FirstGotoWithoutFromOnlySetsThePosition) {
  // Where the tool is before the first GOTO/ is unknown: that GOTO/ makes no Block.
  const AptProgram a = read("RAPID\nGOTO/1,2,3\nFEDRAT/50\nGOTO/1,2,0\n");
  ASSERT_EQ(a.program.blocks.size(), 1u);
  expect_vec(a.program.blocks[0].start_mm, {1, 2, 3});
  expect_vec(a.program.blocks[0].end_mm, {1, 2, 0});
  EXPECT_EQ(a.program.blocks[0].kind, MotionKind::Linear);  // RAPID went with the first GOTO
}

TEST(AptReader, RapidAppliesToTheNextMotionOnly) {
  const AptProgram a = read(
      "FROM/0,0,50\n"
      "FEDRAT/200\n"
      "RAPID\n"
      "GOTO/0,0,5\n"
      "GOTO/0,0,0\n"
      "RAPID\n"
      "GODLTA/0,0,20\n"
      "GODLTA/5\n");
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[0].kind, MotionKind::Rapid);
  EXPECT_EQ(b[0].feed_mm_per_min, 0.0);  // rapids carry no feed
  EXPECT_EQ(b[1].kind, MotionKind::Linear);
  EXPECT_EQ(b[1].feed_mm_per_min, 200.0);
  EXPECT_EQ(b[2].kind, MotionKind::Rapid);
  expect_vec(b[2].end_mm, {0, 0, 20});  // GODLTA/dx,dy,dz: relative
  EXPECT_EQ(b[3].kind, MotionKind::Linear);
  expect_vec(b[3].end_mm, {0, 0, 25});  // GODLTA/d: along the tool axis (0,0,1)
}

TEST(AptReader, ZeroLengthMotionsAreDropped) {
  const AptProgram a = read("FROM/1,1,1\nFEDRAT/10\nGOTO/1,1,1\nGOTO/2,1,1\nGOTO/2,1,1\n");
  ASSERT_EQ(a.program.blocks.size(), 1u);
  EXPECT_EQ(a.program.blocks[0].source.line, 4);
}

TEST(AptReader, FeedUnitsAndInches) {
  // FEDRAT/f,IPM: f in/min = 25.4 f mm/min; FEDRAT/MMPM,f the same as f,MMPM. After
  // UNITS/INCHES, coordinates are inches and a FEDRAT/ without unit word is in/min.
  const AptProgram a = read(
      "FROM/0,0,0\n"
      "FEDRAT/10,IPM\n"
      "GOTO/1,0,0\n"
      "FEDRAT/IPM,2.5\n"
      "GOTO/2,0,0\n"
      "FEDRAT/MMPM,300\n"
      "GOTO/3,0,0\n"
      "UNITS/INCHES\n"
      "GOTO/1,2,3\n"
      "FEDRAT/5\n"
      "GOTO/1,2,0\n"
      "FEDRAT/40,MMPM\n"
      "GOTO/0,0,0.5\n"
      "UNITS/MM\n"
      "GOTO/7,8,9\n");
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 7u);
  EXPECT_NEAR(b[0].feed_mm_per_min, 254.0, kTol);
  expect_vec(b[0].end_mm, {1, 0, 0});             // still mm
  EXPECT_NEAR(b[1].feed_mm_per_min, 63.5, kTol);  // 2.5 * 25.4
  EXPECT_EQ(b[2].feed_mm_per_min, 300.0);
  expect_vec(b[3].start_mm, {3, 0, 0});  // the position stays in mm
  expect_vec(b[3].end_mm, {1 * kInch, 2 * kInch, 3 * kInch});
  EXPECT_EQ(b[3].feed_mm_per_min, 300.0);              // a feed once set keeps its mm/min
  EXPECT_NEAR(b[4].feed_mm_per_min, 5 * kInch, kTol);  // 127 mm/min
  expect_vec(b[4].end_mm, {25.4, 50.8, 0});
  EXPECT_EQ(b[5].feed_mm_per_min, 40.0);
  expect_vec(b[5].end_mm, {0, 0, 12.7});
  expect_vec(b[6].end_mm, {7, 8, 9});
}

TEST(AptReader, ContinuationLinesAndComments) {
  // `$` continues the statement on the next line (what follows the `$` is a comment);
  // `$$` is a comment to the end of the line.
  const AptProgram a = read(
      "$$ a CL file from some CAM system\n"
      "FROM/0,0,0  $$ the start\n"
      "FEDRAT/$ the feed follows\n"
      "  120\n"
      "GOTO/ 1.5 ,$\n"
      "  -2.25, $\n"
      "  3\n"
      "gOtO/4,5,6 $$ lower case reads too\n"
      "$$ GOTO/7,7,7\n");
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b[0].feed_mm_per_min, 120.0);
  expect_vec(b[0].end_mm, {1.5, -2.25, 3});
  EXPECT_EQ(b[0].source.line, 5);  // a statement's source is its first line
  expect_vec(b[1].end_mm, {4, 5, 6});
  EXPECT_TRUE(a.program.warnings.empty());
}

TEST(AptReader, ErrorsInsideContinuationsNameTheirOwnLine) {
  EXPECT_APT_ERROR("FROM/0,0,0\nFEDRAT/10\nGOTO/1,$\n   2,x\n", 4, 6, "expected a number");
  EXPECT_APT_ERROR("FROM/0,0,0\nGOTO/1,2,$\n", 2, 0, "continuation at the end of the file");
}

TEST(AptReader, NumberForms) {
  // "1." "-.5" "+2" and exponents are numbers as in Fortran-printed CL files.
  const AptProgram a = read("FROM/0,0,0\nFEDRAT/1.5E+02\nGOTO/1.,-.5,+2\nGOTO/2.5e-1,0,0\n");
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b[0].feed_mm_per_min, 150.0);
  expect_vec(b[0].end_mm, {1, -0.5, 2});
  expect_vec(b[1].end_mm, {0.25, 0, 0});
}

TEST(AptReader, IgnoredStatementsWarnOncePerWord) {
  const AptProgram a = read(
      "FROM/0,0,0\n"
      "COOLNT/ON\n"
      "INTOL/0.01\n"
      "FEDRAT/100\n"
      "   COOLNT/OFF\n"
      "TOOL PATH/FACE_MILLING,TOOL,D10\n"
      "PPRINT anything, even GOTO/1,2 here $$ is text\n"
      "GOTO/1,0,0\n"
      "END\n"
      "FINI\n"
      "this line is never read, @#!\n");
  EXPECT_EQ(a.program.blocks.size(), 1u);
  ASSERT_EQ(a.program.warnings.size(), 3u);
  EXPECT_EQ(a.program.warnings[0].rfind("test.apt:2:1: ", 0), 0u) << a.program.warnings[0];
  EXPECT_NE(a.program.warnings[0].find("COOLNT"), std::string::npos);
  EXPECT_EQ(a.program.warnings[1].rfind("test.apt:3:1: ", 0), 0u) << a.program.warnings[1];
  EXPECT_NE(a.program.warnings[1].find("INTOL"), std::string::npos);
  EXPECT_EQ(a.program.warnings[2].rfind("test.apt:6:1: ", 0), 0u) << a.program.warnings[2];
  EXPECT_NE(a.program.warnings[2].find("TOOL PATH"), std::string::npos);
}

TEST(AptReader, Spindle) {
  const AptProgram a = read(
      "FROM/0,0,0\nFEDRAT/10\n"
      "SPINDL/1200,CCLW\nGOTO/1,0,0\n"
      "SPINDL/OFF\nGOTO/2,0,0\n"
      "SPINDL/ON\nGOTO/3,0,0\n"
      "SPINDL/RPM,800,CLW,RANGE,2\nGOTO/4,0,0\n"
      "SPINDL/500\nGOTO/5,0,0\n");
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 5u);
  EXPECT_EQ(b[0].spindle, SpindleState::CounterClockwise);
  EXPECT_EQ(b[0].spindle_rpm, 1200.0);
  EXPECT_EQ(b[1].spindle, SpindleState::Off);
  EXPECT_EQ(b[2].spindle, SpindleState::CounterClockwise);  // ON: the last direction again
  EXPECT_EQ(b[2].spindle_rpm, 1200.0);
  EXPECT_EQ(b[3].spindle, SpindleState::Clockwise);
  EXPECT_EQ(b[3].spindle_rpm, 800.0);
  EXPECT_EQ(b[4].spindle, SpindleState::Clockwise);  // APT's default direction
}

// ---------------------------------------------------------------- five-axis

TEST(AptReader, MultaxGotoCarriesTheToolAxis) {
  // (0,3,4) normalised is (0,0.6,0.8); a GOTO/ with 3 values under MULTAX keeps the axis;
  // TLAXIS/1,0,1 is (1,0,1)/sqrt(2) for the next motion.
  const AptProgram a = read(
      "MULTAX/ON\n"
      "FROM/0,0,0,0,0,1\n"
      "FEDRAT/100\n"
      "GOTO/1,0,0,0,3,4\n"
      "GOTO/2,0,0\n"
      "TLAXIS/1,0,1\n"
      "GOTO/3,0,0\n"
      "GOTO/3,0,0,0,0,1\n"
      "MULTAX/OFF\n"
      "GOTO/4,0,0\n");
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 5u);
  expect_vec(b[0].start_axis, {0, 0, 1});
  expect_vec(b[0].end_axis, {0, 0.6, 0.8});
  EXPECT_TRUE(b[0].tool_pose);
  EXPECT_EQ(b[0].orientation, OrientationMode::Vector);
  expect_vec(b[1].start_axis, {0, 0.6, 0.8});
  expect_vec(b[1].end_axis, {0, 0.6, 0.8});
  const double h = std::sqrt(0.5);
  expect_vec(b[2].start_axis, {0, 0.6, 0.8});  // TLAXIS/ takes effect over the next motion
  expect_vec(b[2].end_axis, {h, 0, h});
  // Only the axis turns: still a Block.
  expect_vec(b[3].start_mm, {3, 0, 0});
  expect_vec(b[3].end_mm, {3, 0, 0});
  expect_vec(b[3].end_axis, {0, 0, 1});
  expect_vec(b[4].end_axis, {0, 0, 1});  // MULTAX/OFF keeps the last axis
  EXPECT_DOUBLE_EQ(b[0].end_axis.norm(), 1.0);
}

TEST(AptReader, MultaxWordAloneMeansOn) {
  const AptProgram a = read("MULTAX\nFROM/0,0,0\nFEDRAT/1\nGOTO/1,0,0,1,0,0\n");
  ASSERT_EQ(a.program.blocks.size(), 1u);
  expect_vec(a.program.blocks[0].end_axis, {1, 0, 0});
}

// ---------------------------------------------------------------- arcs

TEST(AptReader, CircleCounterclockwiseAboutPlusZ) {
  // Convention (apt_reader.h): the tool turns about (i,j,k) by the right-hand rule. From
  // (10,0,0) to (0,10,0) about +Z around the origin is a quarter turn, pi/2.
  const AptProgram a = read(
      "FROM/10,0,0\n"
      "FEDRAT/100\n"
      "CIRCLE/0,0,0,0,0,1,10,0.01,0.5,10,0\n"
      "GOTO/0,10,0\n");
  ASSERT_EQ(a.program.blocks.size(), 1u);
  const Block& b = a.program.blocks[0];
  EXPECT_EQ(b.kind, MotionKind::Arc);
  expect_vec(b.center_mm, {0, 0, 0});
  expect_vec(b.normal, {0, 0, 1});
  EXPECT_EQ(b.turns, 1);
  EXPECT_NEAR(swept_angle(b), kPi / 2, kTol);
  EXPECT_EQ(b.feed_mm_per_min, 100.0);
  EXPECT_EQ(b.source.line, 4);  // the GOTO/ that ends the arc
}

// CATIA V5's circle: INDIRV/ the direction at the start, TLON,GOFWD/ along the circle until on
// the check line. From (10,0,0) going +Y about the origin is counterclockwise about +Z; the
// line X = 0 crosses the circle at (0,10,0), met after a quarter turn, and (0,-10,0), after
// three quarters (the second intersection, 2,INTOF). Going -Y: clockwise, (0,-10,0) first.
TEST(AptReader, CatiaTlonCircleToTheCheckLine) {
  const AptProgram a = read(
      "FROM/10,0,5\n"
      "FEDRAT/100\n"
      "GOTO/10,0,0\n"
      "AUTOPS\n"
      "INDIRV/ 0,1,0\n"
      "TLON,GOFWD/ (CIRCLE/ 0,0,0,$\n"
      "10),ON,(LINE/ 0,0,0,0,10,0)\n"
      "INDIRV/ -1,0,0\n"
      "TLON,GOFWD/ (CIRCLE/ 0,0,0,$\n"
      "10),ON,2,INTOF,$\n"
      "(LINE/ 0,0,0,10,0,0)\n"
      "INDIRV/ 0,-1,0\n"
      "TLON,GOFWD/ CIRCLE/ 0,0,0,10,ON,LINE/ 0,0,0,-10,-10,0\n");
  ASSERT_EQ(a.program.blocks.size(), 4u);
  const Block& quarter = a.program.blocks[1];
  EXPECT_EQ(quarter.kind, MotionKind::Arc);
  expect_vec(quarter.end_mm, {0, 10, 0});
  expect_vec(quarter.normal, {0, 0, 1});
  EXPECT_NEAR(swept_angle(quarter), kPi / 2, kTol);
  EXPECT_EQ(quarter.source.line, 6);
  // From (0,10,0) going -X: counterclockwise; the line Y = 0 is met at (-10,0,0) first, then
  // at (10,0,0): the second is three quarters on.
  const Block& second = a.program.blocks[2];
  expect_vec(second.end_mm, {10, 0, 0});
  EXPECT_NEAR(swept_angle(second), 3 * kPi / 2, kTol);
  // From (10,0,0) going -Y: clockwise (normal -Z); the line y = x is met at (-7.07,-7.07) after
  // 135 deg.
  const Block& third = a.program.blocks[3];
  expect_vec(third.normal, {0, 0, -1});
  expect_vec(third.end_mm, {-10 / std::sqrt(2.0), -10 / std::sqrt(2.0), 0});
  EXPECT_NEAR(swept_angle(third), 3 * kPi / 4, kTol);
  EXPECT_APT_ERROR("FROM/10,0,0\nTLON,GOFWD/ (CIRCLE/ 0,0,0,10),ON,(LINE/ 0,0,0,0,10,0)\n", 2, 1, "without INDIRV/");
  // INDIRV/ is for the next TLON: a GOTO/ between them clears it.
  EXPECT_APT_ERROR(
      "FROM/10,0,1\nFEDRAT/100\nINDIRV/0,1,0\nGOTO/10,0,0\nTLON,GOFWD/ (CIRCLE/ 0,0,0,10),ON,(LINE/ 0,0,0,0,10,0)\n", 5,
      1, "without INDIRV/");
  EXPECT_APT_ERROR("FROM/10,0,0\nINDIRV/0,1,0\nTLON,GOFWD/ (CIRCLE/ 0,0,0,9),ON,(LINE/ 0,0,0,0,10,0)\n", 3, 28,
                   "mm from the circle's centre");
  EXPECT_APT_ERROR("FROM/10,0,0\nINDIRV/0,1,0\nTLON,GOFWD/ (CYLNDR/ 0,0,0,0,0,1,10),ON\n", 3, 14,
                   "CYLNDR/ is not supported");
  EXPECT_APT_ERROR("FROM/10,0,0\nINDIRV/0,1,0\nTLON,GOFWD/ (CIRCLE/ 0,0,0,10),TO,(LINE/ 0,0,0,0,10,0)\n", 3, 32,
                   "TO and PAST are not supported");
  EXPECT_APT_ERROR("FROM/10,0,0\nINDIRV/0,1,0\nTLON,GOFWD/ (CIRCLE/ 0,0,0,10),ON,(LINE/ 0,0,1,0,10,1)\n", 3, 1,
                   "does not lie in the circle's plane");
}

TEST(AptReader, CircleClockwiseAboutMinusZ) {
  // The same points about -Z: clockwise seen from +Z, through (0,-10,0) and (-10,0,0): 3*pi/2.
  const AptProgram a = read(
      "FROM/10,0,0\n"
      "FEDRAT/100\n"
      "CIRCLE/0,0,0,0,0,-1,10\n"
      "GOTO/0,10,0\n");
  ASSERT_EQ(a.program.blocks.size(), 1u);
  const Block& b = a.program.blocks[0];
  EXPECT_EQ(b.kind, MotionKind::Arc);
  expect_vec(b.normal, {0, 0, -1});
  EXPECT_NEAR(swept_angle(b), 3 * kPi / 2, kTol);
}

TEST(AptReader, CircleInATiltedPlaneHelixAndFullCircle) {
  // Circle about (0,1,0) (the ZX plane) centred at (0,7,0), radius 5, given with its centre
  // at y = 7 while the tool is at y = 2: the Block's centre lies in the start's plane, y = 2.
  // From (5,2,0) about +Y by the right-hand rule, +Z goes toward +X: a quarter turn reaches
  // (0,2,-5). Then a full circle (end = start), then a helix of 3 mm along the normal.
  const AptProgram a = read(
      "FROM/5,2,0\n"
      "FEDRAT/100\n"
      "CIRCLE/0,7,0,0,1,0,5\n"
      "GOTO/0,2,-5\n"
      "CIRCLE/0,0,0,0,2,0,5\n"
      "GOTO/0,2,-5\n"
      "CIRCLE/0,0,0,0,1,0,5\n"
      "GOTO/-5,5,0\n");
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 3u);
  expect_vec(b[0].center_mm, {0, 2, 0});
  expect_vec(b[0].normal, {0, 1, 0});
  EXPECT_NEAR(swept_angle(b[0]), kPi / 2, kTol);
  EXPECT_NEAR(swept_angle(b[1]), 2 * kPi, kTol);  // a full circle
  expect_vec(b[1].end_mm, {0, 2, -5});
  expect_vec(b[1].normal, {0, 1, 0});  // (0,2,0) normalised
  // (0,2,-5) -> (-5,5,0) about +Y: from -Z to -X is a quarter turn; y rises by 3.
  EXPECT_NEAR(swept_angle(b[2]), kPi / 2, kTol);
  expect_vec(b[2].center_mm, {0, 2, 0});
  expect_vec(b[2].end_mm, {-5, 5, 0});
}

TEST(AptReader, CircleInInches) {
  // UNITS/INCHES: centre and radius convert too: r = 1 in = 25.4 mm.
  const AptProgram a = read("UNITS/INCHES\nFROM/1,0,0\nFEDRAT/10\nCIRCLE/0,0,0,0,0,1,1\nGOTO/-1,0,0\n");
  ASSERT_EQ(a.program.blocks.size(), 1u);
  expect_vec(a.program.blocks[0].end_mm, {-kInch, 0, 0});
  EXPECT_NEAR(swept_angle(a.program.blocks[0]), kPi, kTol);
}

TEST(AptReader, ArcToleranceOption) {
  // 0.0015 mm off the radius passes the default 0.002 mm and fails at 0.001 mm.
  const std::string text = "FROM/10,0,0\nFEDRAT/1\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10.0015,0\n";
  EXPECT_EQ(read(text).program.blocks.size(), 1u);
  AptOptions strict;
  strict.arc_tolerance_mm = 0.001;
  EXPECT_THROW(read(text, strict), InputError);
}

// ---------------------------------------------------------------- cutters

TEST(AptReader, CutterWithOneTwoAndSevenParameters) {
  // Without LOADTL/ the first cutter is tool 1; each different one after it has cut is the
  // next number, and one seen before keeps its number.
  const AptProgram a = read(
      "FROM/0,0,0\nFEDRAT/10\n"
      "CUTTER/10\nGOTO/1,0,0\n"               // flat, h = 4 d = 40
      "CUTTER/8,4\nGOTO/2,0,0\n"              // ball, r = d/2
      "CUTTER/12,2\nGOTO/3,0,0\n"             // bull-nose
      "CUTTER/12,2,4,2,0,0,30\nGOTO/4,0,0\n"  // e = d/2 - r = 4, f = r = 2
      "CUTTER/10,5,0,5,0,0,25\nGOTO/5,0,0\n"  // ball: e = 0, f = 5
      "CUTTER/6,0,3,0,0,0,18\nGOTO/6,0,0\n"   // flat: e = d/2, f = 0
      "CUTTER/6,0,0,0,0,0,20\nGOTO/7,0,0\n"   // flat, corner printed as (0,0)
      "CUTTER/10\nGOTO/8,0,0\n");             // the first one again: tool 1
  const auto& c = a.cutters;
  ASSERT_EQ(c.size(), 7u);
  EXPECT_EQ(c.at(1).type, CutterType::Flat);
  EXPECT_EQ(c.at(1).diameter_mm, 10.0);
  EXPECT_EQ(c.at(1).corner_radius_mm, 0.0);
  EXPECT_EQ(c.at(1).flute_length_mm, 40.0);
  EXPECT_EQ(c.at(2).type, CutterType::Ball);
  EXPECT_EQ(c.at(2).corner_radius_mm, 4.0);
  EXPECT_EQ(c.at(3).type, CutterType::BullNose);
  EXPECT_EQ(c.at(3).corner_radius_mm, 2.0);
  EXPECT_EQ(c.at(4).type, CutterType::BullNose);
  EXPECT_EQ(c.at(4).flute_length_mm, 30.0);
  EXPECT_EQ(c.at(4).length_mm, 30.0);
  EXPECT_EQ(c.at(5).type, CutterType::Ball);
  EXPECT_EQ(c.at(5).corner_radius_mm, 5.0);
  EXPECT_EQ(c.at(6).type, CutterType::Flat);
  EXPECT_EQ(c.at(6).flute_length_mm, 18.0);
  EXPECT_EQ(c.at(7).type, CutterType::Flat);
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 8u);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(b[static_cast<size_t>(i)].tool, i + 1);
  EXPECT_EQ(b[7].tool, 1);
}

TEST(AptReader, SevenParameterVBitAndInches) {
  // alpha = 30 deg from the horizontal: included angle 180 - 2*30 = 120 deg; the corner
  // where the cone meets the side is at e = d/2 = 5, f = 5 tan 30 = 2.886751346.
  const AptProgram a = read(
      "LOADTL/7\nCUTTER/10,0,5,2.886751,30,0,20\nFROM/0,0,0\nRAPID\nGOTO/1,1,1\n"
      "UNITS/INCHES\nLOADTL/8\nCUTTER/0.5,0.25\nRAPID\nGOTO/0,0,1\n");
  ASSERT_EQ(a.cutters.size(), 2u);
  const auto& v = a.cutters.at(7);
  EXPECT_EQ(v.type, CutterType::VBit);
  EXPECT_NEAR(v.tip_angle_deg, 120.0, kTol);
  EXPECT_EQ(v.diameter_mm, 10.0);
  EXPECT_EQ(v.flute_length_mm, 20.0);
  EXPECT_EQ(v.gauge_length_mm, 20.0);  // h: the tool sits in the spindle nose
  const auto& ball = a.cutters.at(8);  // 0.5 in ball: d = 12.7 mm, r = 6.35 mm
  EXPECT_EQ(ball.type, CutterType::Ball);
  EXPECT_NEAR(ball.diameter_mm, 12.7, kTol);
  EXPECT_NEAR(ball.corner_radius_mm, 6.35, kTol);
  EXPECT_NEAR(ball.flute_length_mm, 4 * 12.7, kTol);
  ASSERT_EQ(a.program.blocks.size(), 2u);
  EXPECT_EQ(a.program.blocks[0].tool, 7);
  EXPECT_EQ(a.program.blocks[1].tool, 8);
}

TEST(AptReader, LoadtlNumbersCutters) {
  // CUTTER/ before or after LOADTL/ describes the tool of the next motion; going back to
  // tool 3 brings its cutter back; LOADTL/ parameters after the number warn once.
  const AptProgram a = read(
      "FROM/0,0,0\nFEDRAT/10\n"
      "LOADTL/3\nCUTTER/6\nGOTO/1,0,0\n"
      "CUTTER/4,2\nLOADTL/5,ADJUST,5\nGOTO/2,0,0\n"
      "LOADTL/3\nGOTO/3,0,0\n"
      "LOADTL/9\nGOTO/4,0,0\n");
  ASSERT_EQ(a.cutters.size(), 2u);
  EXPECT_EQ(a.cutters.at(3).diameter_mm, 6.0);
  EXPECT_EQ(a.cutters.at(5).type, CutterType::Ball);
  const auto& b = a.program.blocks;
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[0].tool, 3);
  EXPECT_EQ(b[1].tool, 5);
  EXPECT_EQ(b[2].tool, 3);
  EXPECT_EQ(b[3].tool, 9);  // its shape is not in the file: the tool library's business
  ASSERT_EQ(a.program.warnings.size(), 1u);
  EXPECT_EQ(a.program.warnings[0].rfind("test.apt:7:10: ", 0), 0u) << a.program.warnings[0];
}

// A corner radius printed within 0.002 mm (kCutterMatchMm) over d/2 is a ball, r = d/2, also
// where the difference rounds just over the tolerance (0.252 - 0.25 is 0.0020000000000000018
// in doubles: the fuzzer found the cutter kept r > d/2); 0.0021 mm over is the error.
TEST(AptReader, CornerRadiusAHairOverHalfTheDiameterIsABall) {
  for (const char* cutter : {"CUTTER/0.5,0.252", "CUTTER/10,5.0015"}) {
    const AptProgram a = read(std::string(cutter) + "\nFROM/0,0,1\nRAPID\nGOTO/1,0,1\n");
    ASSERT_EQ(a.cutters.size(), 1u);
    const auto& c = a.cutters.begin()->second;
    EXPECT_EQ(c.type, CutterType::Ball) << cutter;
    EXPECT_EQ(c.corner_radius_mm, 0.5 * c.diameter_mm) << cutter;
  }
  EXPECT_APT_ERROR("CUTTER/0.5,0.2521\n", 1, 12, "more than half the diameter");
}

TEST(AptReader, CutterErrors) {
  EXPECT_APT_ERROR("CUTTER/0\n", 1, 8, "expected d > 0");
  EXPECT_APT_ERROR("CUTTER/10,6\n", 1, 11, "more than half the diameter");
  EXPECT_APT_ERROR("CUTTER/10,2,3,2,0,5,50\n", 1, 19, "tapered cutter");
  EXPECT_APT_ERROR("CUTTER/10,1,4,1,30,0,50\n", 1, 17, "cannot be represented");
  EXPECT_APT_ERROR("CUTTER/10,2,4,2,0,0,50\n", 1, 13, "expected e = 3, f = 2");
  EXPECT_APT_ERROR("CUTTER/10,0,5,0,95,0,50\n", 1, 17, "expected 0 <= alpha < 90");
  EXPECT_APT_ERROR("CUTTER/10,2,3,2,0,0,1\n", 1, 21, "at least the corner radius");
  EXPECT_APT_ERROR("CUTTER/1,0,0,0,0,0,2,9\n", 1, 22, "expected d, d,r or d,r,e,f,alpha,beta,h");
  EXPECT_APT_ERROR("CUTTER/TOOL,10\n", 1, 8, "expected a number");
  // A second cutter for a tool number that has cut with another one.
  EXPECT_APT_ERROR("FROM/0,0,0\nFEDRAT/1\nLOADTL/1\nCUTTER/10\nGOTO/1,0,0\nCUTTER/8\nGOTO/2,0,0\n", 7, 1,
                   "has cut with another cutter");
}

// ---------------------------------------------------------------- bad input

TEST(AptReader, BadInputNamesLineAndColumn) {
  EXPECT_APT_ERROR("FROM/0,0,0\nGOTO/1,2,3\n", 2, 1, "before any FEDRAT/");
  EXPECT_APT_ERROR("FROM/0,0,0\nFEDRAT/10\nGOTO/1,2\n", 3, 6, "expected x,y,z");
  EXPECT_APT_ERROR("FROM/0,0,0\nFEDRAT/10\nGOTO/1,2,3,4\n", 3, 12, "expected x,y,z");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1,abc,3\n", 2, 8, "expected a number for y");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1,NaN,3\n", 2, 8, "expected a number");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1,inf,3\n", 2, 8, "expected a number");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1,1e999,3\n", 2, 8, "out of range");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1,2e6,3\n", 2, 8, "out of range");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1,2.3.4,3\n", 2, 8, "malformed number");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1,,3\n", 2, 8, "empty parameter");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/1 2,3\n", 2, 8, "expected ','");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO 1,2,3\n", 2, 6, "expected '/'");
  EXPECT_APT_ERROR("FEDRAT/10\nGOTO/\n", 2, 6, "GOTO/ with 0 parameter(s) (expected x,y,z or x,y,z,i,j,k)");
  EXPECT_APT_ERROR("1.0,2.0,3.0\n", 1, 1, "expected a statement word");
  // Not CL data: G-code, APT source geometry.
  EXPECT_APT_ERROR("G0 X1 Y2\n", 1, 4, "unexpected 'X' after G0");
  EXPECT_APT_ERROR("P1=POINT/1,2,3\n", 1, 3, "unexpected '=' after P1");
  EXPECT_APT_ERROR("MULTAX\nFEDRAT/1\nGOTO/1,2,3,0,0,0\n", 3, 12, "zero tool axis");
  EXPECT_APT_ERROR("TLAXIS/0,0,0\n", 1, 8, "zero tool axis");
  EXPECT_APT_ERROR("TLAXIS/0,0\n", 1, 8, "expected i,j,k");
  EXPECT_APT_ERROR("FEDRAT/0\n", 1, 8, "expected a feed > 0");
  EXPECT_APT_ERROR("FEDRAT/-5\n", 1, 8, "expected a feed > 0");
  EXPECT_APT_ERROR("FEDRAT/2e6\n", 1, 8, "out of range");
  EXPECT_APT_ERROR("FEDRAT/0.2,MMPR\n", 1, 12, "feed per revolution");
  EXPECT_APT_ERROR("FEDRAT/10,FAST\n", 1, 11, "expected MMPM or IPM");
  EXPECT_APT_ERROR("UNITS/FEET\n", 1, 7, "INCHES or MM");
  // Cutter compensation: what it needs, named.
  EXPECT_APT_ERROR("CUTCOM/UP\n", 1, 8, "takes LEFT, RIGHT or OFF");
  EXPECT_APT_ERROR("CUTCOM/LEFT,1\n", 1, 8, "CUTCOM/LEFT before any CUTTER/");
  EXPECT_APT_ERROR("CUTTER/4\nMULTAX/ON\nCUTCOM/LEFT\n", 3, 8, "with MULTAX/ON");
  EXPECT_APT_ERROR("CUTTER/4\nCUTCOM/LEFT,YZPLAN\n", 2, 13, "expected XYPLAN or a register number");
  EXPECT_APT_ERROR("CUTTER/4\nCUTCOM/LEFT\nFROM/0,0,0\n", 3, 1, "FROM/ with CUTCOM on (expected CUTCOM/OFF first)");
  EXPECT_APT_ERROR("CUTTER/4\nCUTCOM/RIGHT\nLOADTL/2\n", 3, 1, "LOADTL/ with CUTCOM on");
  EXPECT_APT_ERROR("CUTTER/4\nFROM/0,0,0\nFEDRAT/100\nCUTCOM/LEFT\nGOTO/1,0,0\n", 5, 1,
                   "entry move of 1 mm in the plane is not longer than the tool radius 2 mm");
  EXPECT_APT_ERROR(
      "CUTTER/4\nFROM/0,0,0\nFEDRAT/100\nCUTCOM/LEFT\nGOTO/10,0,0\nCUTCOM/OFF\nCIRCLE/10,5,0,0,0,1,5\nGOTO/10,10,0\n",
      8, 1, "a CIRCLE/ just after CUTCOM/OFF");
  const AptProgram off = read("CUTCOM/OFF\nFROM/0,0,10\nFEDRAT/100\nGOTO/10,0,0\n");
  EXPECT_TRUE(off.program.warnings.empty());
  EXPECT_EQ(off.program.blocks.size(), 1u);
  EXPECT_APT_ERROR("LOADTL/1\nLOADTL/0\n", 2, 8, "from 1 to 99999");
  EXPECT_APT_ERROR("LOADTL/2.5\n", 1, 8, "whole number");
  EXPECT_APT_ERROR("MULTAX/MAYBE\n", 1, 8, "ON or OFF");
  EXPECT_APT_ERROR("SPINDL/1000,SIDEWAYS\n", 1, 13, "expected rpm, RPM, CLW, CCLW");
  EXPECT_APT_ERROR("SPINDL/1000,RPM,2000\n", 1, 17, "two speeds");
  EXPECT_APT_ERROR("RAPID/5\n", 1, 7, "no parameters");
  EXPECT_APT_ERROR("FEDRAT/1\nGODLTA/1,2,3\n", 2, 1, "unknown position");
  // A 180-degree turn of the tool axis has no single great circle.
  EXPECT_APT_ERROR("MULTAX\nFROM/0,0,0,0,0,1\nFEDRAT/1\nGOTO/1,0,0,0,0,-1\n", 4, 1, "opposite");
}

TEST(AptReader, CircleErrors) {
  const std::string head = "FROM/10,0,0\nFEDRAT/100\n";
  // The end point is 11 mm from the axis, the circle's radius 10.
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10\nGOTO/0,11,0\n", 4, 1, "expected a point on that circle");
  // The start (the current point) is not on the circle.
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,9\nGOTO/0,9,0\n", 3, 20, "the arc's start");
  // CIRCLE/ without its GOTO/: at the end of the file, or another motion first.
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10\n", 3, 1, "without the GOTO/");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10\nGODLTA/0,0,1\n", 4, 1, "expected the GOTO/");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10\nRAPID\nGOTO/0,10,0\n", 4, 1, "expected the GOTO/");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10\nCIRCLE/0,0,0,0,0,1,10\n", 4, 1, "second CIRCLE/");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10\nFINI\n", 4, 1, "expected the GOTO/");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,0,10\n", 3, 14, "zero circle axis");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,0\n", 3, 20, "expected r > 0");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0\n", 3, 8, "cx,cy,cz,i,j,k");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10,0.1,0.1,0.1,0.1,0.1\n", 3, 39, "more than 4 tolerances");
  EXPECT_APT_ERROR(head + "CIRCLE/0,0,0,0,0,1,10,TIMES,0\nGOTO/10,0,0\n", 3, 29, "whole number of turns");
  EXPECT_APT_ERROR("FEDRAT/1\nCIRCLE/0,0,0,0,0,1,10\n", 2, 1, "unknown position");
  EXPECT_APT_ERROR(head + "RAPID\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,0\n", 4, 1, "after RAPID");
}

TEST(AptReader, NotATextFile) {
  EXPECT_APT_ERROR(std::string("FROM/0,0,0\nGO\0TO/1", 18), 2, 3, "not a text file");
  EXPECT_APT_ERROR(std::string("\x7F"
                               "ELF\x02\x01\x01"),
                   1, 1, "not a text file");
  // A line longer than 1 MiB is not a CL statement (and is never held whole in memory).
  EXPECT_APT_ERROR(std::string(2u << 20, 'A'), 1, 0, "line longer than 1 MiB");
}

TEST(AptReader, FilesInSequenceShareTheState) {
  AptProgram out;
  AptState state;
  std::istringstream first("FROM/0,0,0\nFEDRAT/10\nUNITS/INCHES\nGOTO/1,0,0\n");
  std::istringstream second("GOTO/1,1,0\n");
  read_apt(first, "a.apt", {}, out, state);
  read_apt(second, "b.apt", {}, out, state);
  ASSERT_EQ(out.program.blocks.size(), 2u);
  EXPECT_EQ(out.program.where(out.program.blocks[1].source), "b.apt:1");
  expect_vec(out.program.blocks[1].start_mm, {kInch, 0, 0});
  expect_vec(out.program.blocks[1].end_mm, {kInch, kInch, 0});
}

TEST(AptReader, ManyLinesStreamWithOneBlockEach) {
  // 100000 GOTO/ lines: every one a Block with its own line number (the benchmark times 10^6).
  std::string text = "FROM/0,0,0\nFEDRAT/1000\n";
  constexpr int kLines = 100000;
  for (int i = 1; i <= kLines; ++i) {
    text += "GOTO/" + std::to_string(i % 100) + ".5," + std::to_string(i % 7) + ",-1\n";
  }
  const AptProgram a = read(text);
  ASSERT_EQ(a.program.blocks.size(), static_cast<size_t>(kLines));
  EXPECT_EQ(a.program.blocks.back().source.line, kLines + 2);
  expect_vec(a.program.blocks.back().end_mm, {kLines % 100 + 0.5, kLines % 7, -1});
}

// ---------------------------------------------------------------- files and dialects

class ProgramFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("vcut_apt_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const auto path = dir_ / name;
    std::ofstream(path, std::ios::binary) << text;
    return path.string();
  }
  std::filesystem::path dir_;
};

TEST_F(ProgramFiles, DetectDialectByExtensionThenContent) {
  // The extension wins over the content.
  EXPECT_EQ(detect_dialect(write("a.apt", "G0 X1\n")), Dialect::Apt);
  EXPECT_EQ(detect_dialect(write("a.CLS", "")), Dialect::Apt);
  EXPECT_EQ(detect_dialect(write("a.cl", "")), Dialect::Apt);
  EXPECT_EQ(detect_dialect(write("a.aptsource", "")), Dialect::Apt);
  EXPECT_EQ(detect_dialect(write("a.MPF", "GOTO/1,2,3\n")), Dialect::Sinumerik);
  EXPECT_EQ(detect_dialect(write("a.spf", "")), Dialect::Sinumerik);
  EXPECT_EQ(detect_dialect(write("a.ngc", "GOTO/1,2,3\n")), Dialect::Gcode);
  EXPECT_EQ(detect_dialect(write("a.nc", "")), Dialect::Gcode);
  EXPECT_EQ(detect_dialect(write("a.tap", "")), Dialect::Gcode);
  EXPECT_EQ(detect_dialect(write("a.gcode", "")), Dialect::Gcode);
  // Content.
  EXPECT_EQ(detect_dialect(write("b.txt", "\n$$ header\nGOTO/1,2,3\n")), Dialect::Apt);
  EXPECT_EQ(detect_dialect(write("c.txt", "PARTNO X\nCUTTER/10\n")), Dialect::Apt);
  EXPECT_EQ(detect_dialect(write("d.txt", "  fedrat / 100\n")), Dialect::Apt);
  EXPECT_EQ(detect_dialect(write("e.txt", "N10 G0 X0\nN20 TRAORI\n")), Dialect::Sinumerik);
  EXPECT_EQ(detect_dialect(write("f.txt", "N10 G2 X10 Y0 CR=5\n")), Dialect::Sinumerik);
  EXPECT_EQ(detect_dialect(write("g.txt", "DEF REAL R1\n")), Dialect::Sinumerik);
  EXPECT_EQ(detect_dialect(write("h.txt", "; seed 000\nN7 X -1320 Y -1320 Z 1000 A 0 C 0\n")), Dialect::Sinumerik);
  EXPECT_EQ(detect_dialect(write("i.txt", "%\n(TRAORI in a comment)\nG0 X1 Y2\n%\n")), Dialect::Gcode);
  EXPECT_EQ(detect_dialect(write("j.txt", "G21 G90\nG1 X1 F100 ; LinuxCNC comment\n")), Dialect::Gcode);
  EXPECT_EQ(detect_dialect(write("k", "")), Dialect::Gcode);
  EXPECT_EQ(detect_dialect((dir_ / "missing.txt").string()), Dialect::Gcode);
}

TEST_F(ProgramFiles, ReadProgramDispatches) {
  const std::string apt = write("p.cls", "CUTTER/6\nFROM/0,0,0\nFEDRAT/10\nGOTO/1,0,0\n");
  const LoadedProgram a = read_program(apt, Dialect::Auto);
  EXPECT_EQ(a.reader, ProgramReader::Apt);
  ASSERT_EQ(a.program.blocks.size(), 1u);
  ASSERT_EQ(a.cutters.size(), 1u);
  EXPECT_EQ(a.cutters.at(1).diameter_mm, 6.0);
  const std::string gcode = write("p.ngc", "G0 X0 Y0 Z0\nG1 X1 F10\n");
  const LoadedProgram g = read_program(gcode, Dialect::LinuxCnc);
  EXPECT_EQ(g.reader, ProgramReader::Gcode);
  ASSERT_EQ(g.program.blocks.size(), 1u);
  EXPECT_TRUE(g.cutters.empty());
  // An explicit dialect wins over the extension.
  const std::string named = write("q.ngc", "FROM/0,0,0\nFEDRAT/10\nGOTO/0,2,0\n");
  EXPECT_EQ(read_program(named, Dialect::Apt).program.blocks.size(), 1u);
  // Several files of one dialect in sequence.
  const std::string second = write("r.apt", "GOTO/3,0,0\n");
  const LoadedProgram both = read_programs({apt, second}, Dialect::Auto);
  ASSERT_EQ(both.program.blocks.size(), 2u);
  EXPECT_EQ(both.program.files.size(), 2u);
}

TEST_F(ProgramFiles, ReadProgramErrors) {
  auto message = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string mpf = write("s.mpf", "N10 TRAORI\nN20 ROTS X10\n");
  EXPECT_NE(message([&] { read_program(mpf, Dialect::Auto); }).find(":2:5: ROTS is not supported"), std::string::npos);
  EXPECT_NE(message([&] { parse_dialect("heidenhain"); }).find("unknown program dialect"), std::string::npos);
  const std::string binary = write("t.apt", std::string("GOTO/1\n\x01\x02\0\0", 11));
  const std::string m = message([&] { read_program(binary, Dialect::Auto); });
  EXPECT_EQ(m.rfind(binary + ":2:3: not a text file", 0), 0u) << m;
  const std::string gcode = write("u.ngc", "G0 X1\n");
  const std::string apt = write("v.apt", "FROM/0,0,0\n");
  EXPECT_NE(message([&] { read_programs({gcode, apt}, Dialect::Auto); }).find("one dialect"), std::string::npos);
  EXPECT_NE(message([&] { read_program((dir_ / "none.apt").string(), Dialect::Auto); }).find("cannot open"),
            std::string::npos);
  EXPECT_NE(message([&] { read_program(dir_.string(), Dialect::Auto); }).find("is a directory"), std::string::npos);
}

// CUTCOM/RIGHT around a square with a half-circle top, run counterclockwise: the tool (radius 2)
// outside. By hand: the bottom side runs at y = -2 to (20, -2), the convex corner is an arc
// about (20, 0) to (22, 0), the right side at x = 22, the half circle about (10, 20) with
// radius 10 + 2 ends at (-2, 20), the left side at x = -2 to (-2, 0). A second method: the same
// contour as G-code with G42.1 D4 (the G-code compensation that tests/oracle checks against
// LinuxCNC's rs274) gives the same moves.
TEST(AptReader, CutcomOffsetsTheContourAsG42) {
  const AptProgram apt = read(
      "UNITS/MM\nCUTTER/4\nFROM/-10,-10,5\nFEDRAT/200\nGOTO/-10,-10,-1\nCUTCOM/RIGHT,XYPLAN,1\nGOTO/0,0,-1\n"
      "GOTO/20,0,-1\nGOTO/20,20,-1\nCIRCLE/10,20,-1,0,0,1,10\nGOTO/0,20,-1\nGOTO/0,0,-1\nCUTCOM/OFF\nGOTO/"
      "-10,-10,-1\nFINI\n");
  const kinematics::BlockList& b = apt.program.blocks;
  ASSERT_EQ(b.size(), 8u);
  EXPECT_LT((b[2].end_mm - Eigen::Vector3d(20, -2, -1)).norm(), 1e-9);
  EXPECT_EQ(b[3].kind, kinematics::MotionKind::Arc);
  EXPECT_LT((b[3].center_mm - Eigen::Vector3d(20, 0, -1)).norm(), 1e-9);
  EXPECT_LT((b[3].end_mm - Eigen::Vector3d(22, 0, -1)).norm(), 1e-9);
  EXPECT_LT((b[4].end_mm - Eigen::Vector3d(22, 20, -1)).norm(), 1e-9);
  EXPECT_LT((b[5].end_mm - Eigen::Vector3d(-2, 20, -1)).norm(), 1e-9);
  EXPECT_LT((b[6].end_mm - Eigen::Vector3d(-2, 0, -1)).norm(), 1e-9);
  EXPECT_LT((b[7].end_mm - Eigen::Vector3d(-10, -10, -1)).norm(), 1e-9);
  EXPECT_EQ(b[5].source.line, 11);  // the CIRCLE/'s GOTO/
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d(-10, -10, 5);
  kinematics::Program gcode;
  GcodeState state;
  std::istringstream in(
      "G21 G90 G17 F200\nG1 Z-1\nG42.1 D4\nG1 X0 Y0\nX20\nY20\nG3 X0 Y20 I-10 J0\nG1 Y0\nG40\nG1 X-10 Y-10\nM2\n");
  read_gcode(in, "square.ngc", options, gcode, state);
  ASSERT_EQ(gcode.blocks.size(), b.size());
  for (size_t k = 0; k < b.size(); ++k) {
    EXPECT_EQ(gcode.blocks[k].kind, b[k].kind) << k;
    EXPECT_LT((gcode.blocks[k].end_mm - b[k].end_mm).norm(), 1e-9) << k;
    if (b[k].kind == kinematics::MotionKind::Arc) {
      EXPECT_LT((gcode.blocks[k].center_mm - b[k].center_mm).norm(), 1e-9) << k;
    }
  }
}

// A straight meeting an arc 0.03 rad off tangent (under rs274's 0.05 rad corner threshold,
// TOLERANCE_CONCAVE_CORNER): LinuxCNC's convert_arc_comp2 takes it as tangent ("convex, one arc
// needed") and starts the arc where the straight's offset ends, off the arc's offset circle.
// By hand, CUTCOM/LEFT with a radius 2 tool: the straight heads at 0.03 rad into (10, 0), so
// its offset end is (10 - 2 sin 0.03, 2 cos 0.03); the arc about (10, 10) ends at its programmed
// end (20, 10) moved 2 toward the centre, (18, 10). No corner arc between them. The start's
// distance from the centre differs from the end's by less than the tool radius times 0.05 (a
// bound the APT fuzz driver relies on).
TEST(AptReader, CutcomNearlyTangentArcStartsWhereTheStraightEnds) {
  const double h = 0.03;  // rad
  const std::string start =
      "GOTO/" + std::to_string(10.0 - 10.0 * std::cos(h)) + "," + std::to_string(-10.0 * std::sin(h)) + ",-1\n";
  const AptProgram apt =
      read("UNITS/MM\nCUTTER/4\nFROM/-20,-20,5\nFEDRAT/200\nGOTO/-20,-20,-1\nCUTCOM/LEFT\n" + start +
           "GOTO/10,0,-1\nCIRCLE/10,10,-1,0,0,1,10\nGOTO/20,10,-1\nGOTO/20,20,-1\nCUTCOM/OFF\nGOTO/30,30,-1\n");
  const kinematics::BlockList& b = apt.program.blocks;
  ASSERT_EQ(b.size(), 7u);
  const Eigen::Vector3d corner(10.0 - 2.0 * std::sin(h), 2.0 * std::cos(h), -1.0);
  EXPECT_EQ(b[3].kind, kinematics::MotionKind::Linear);
  EXPECT_LT((b[3].end_mm - corner).norm(), 1e-5);  // the GOTO/'s six decimals
  ASSERT_EQ(b[4].kind, kinematics::MotionKind::Arc);
  EXPECT_EQ(b[4].start_mm, b[3].end_mm);
  EXPECT_LT((b[4].center_mm - Eigen::Vector3d(10, 10, -1)).norm(), 1e-9);
  EXPECT_LT((b[4].end_mm - Eigen::Vector3d(18, 10, -1)).norm(), 1e-9);
  const double r_start = (b[4].start_mm - b[4].center_mm).norm();
  EXPECT_GT(std::abs(r_start - 8.0), 1e-4);
  EXPECT_LT(std::abs(r_start - 8.0), 2.0 * 0.05);
}

// ---------------------------------------------------------------- CAM output as written
// The forms below are copied in shape (not in content) from CL files of SolidWorks CAM, NX,
// CATIA and Creo in public repositories (docs/PROGRAMS.md lists them); expected values are
// worked by hand.

// SPINDL/ in the three orders CAM systems write.
TEST(AptReader, SpindleAsCamSystemsWriteIt) {
  auto spindle_of = [](const std::string& spindl) {
    const AptProgram p = read(spindl + "\nFROM/0,0,0\nFEDRAT/100\nGOTO/1,0,0\n");
    return std::make_pair(p.program.blocks.at(0).spindle, p.program.blocks.at(0).spindle_rpm);
  };
  EXPECT_EQ(spindle_of("SPINDL/3500,RPM,CLW"), std::make_pair(SpindleState::Clockwise, 3500.0));
  EXPECT_EQ(spindle_of("SPINDL / RPM, 9000.000000,  CCLW"), std::make_pair(SpindleState::CounterClockwise, 9000.0));
  EXPECT_EQ(spindle_of("SPINDL/400,CLW"), std::make_pair(SpindleState::Clockwise, 400.0));
  EXPECT_EQ(spindle_of("SPINDL/1200"), std::make_pair(SpindleState::Clockwise, 1200.0));
}

// NX and SolidWorks CAM give GOTO/ its tool axis without MULTAX/ON; RAPID/ with its slash;
// a CUTTER/ that ends in a comma (CAMWorks).
TEST(AptReader, GotoAxisWithoutMultaxRapidSlashTrailingComma) {
  const AptProgram p =
      read("CUTTER/10.,0,5.,0,0,0,50.,\nFROM/0,0,10\nRAPID/\nGOTO/0,0,5,0,0.6,0.8\nFEDRAT/100\nGOTO/1,0,5\n");
  ASSERT_EQ(p.program.blocks.size(), 2u);
  EXPECT_EQ(p.program.blocks[0].kind, MotionKind::Rapid);
  expect_vec(p.program.blocks[0].end_axis, Eigen::Vector3d(0, 0.6, 0.8));
  expect_vec(p.program.blocks[1].end_axis, Eigen::Vector3d(0, 0.6, 0.8));  // kept
  EXPECT_DOUBLE_EQ(p.cutters.at(1).flute_length_mm, 50.0);
}

// CIRCLE/ without its radius (SolidWorks CAM): the start's distance from the axis; NX's
// TIMES,2 goes round twice: a quarter from (10, 0) to (0, 10) then a whole turn, 5 pi / 2.
TEST(AptReader, CircleWithoutRadiusAndTimes) {
  const std::string head = "FROM/10,0,0\nFEDRAT/100\n";
  const AptProgram p = read(head + "CIRCLE/0,0,0,0,0,1.\nGOTO/0,10,0\n");
  ASSERT_EQ(p.program.blocks.size(), 1u);
  EXPECT_EQ(p.program.blocks[0].kind, MotionKind::Arc);
  EXPECT_NEAR(swept_angle(p.program.blocks[0]), kPi / 2.0, kTol);
  const AptProgram twice = read(head + "CIRCLE/0,0,0,0,0,1,10,0.06,0.5,125,1,TIMES,2\nGOTO/0,10,0\n");
  ASSERT_EQ(twice.program.blocks.size(), 1u);
  EXPECT_EQ(twice.program.blocks[0].turns, 2);
  EXPECT_NEAR(swept_angle(twice.program.blocks[0]), 2.5 * kPi, kTol);
}

// CSYS/ (SolidWorks CAM): a setup turned about Z or moved writes its motions in its own frame,
// part = R setup + t. With t = (-59.5, -59.5, 19) the point (59.5, 99.5, -24) is (0, 40, -5);
// turned 180 deg about Z and moved by (456.34944, 197.0266, 0), (295.42522, 106.3578, 0) is
// (160.92422, 90.6688, 0). A tilted setup's motions are in the part frame already.
TEST(AptReader, CsysPlacesASetupsMotions) {
  const AptProgram moved =
      read("CSYS/1.,0,0,-59.5,0,1.,0,-59.5,0,0,1.,19.\nFROM/59.5,99.5,25.\nFEDRAT/100\nGOTO/59.5,99.5,-24.\n");
  ASSERT_EQ(moved.program.blocks.size(), 1u);
  expect_vec(moved.program.blocks[0].start_mm, Eigen::Vector3d(0, 40, 44));
  expect_vec(moved.program.blocks[0].end_mm, Eigen::Vector3d(0, 40, -5));
  const AptProgram turned = read(
      "CSYS/-1.,0,0,456.34944,0,-1.,0,197.0266,0,0,1.,0\nFROM/295.42522,106.3578,25\nFEDRAT/100\n"
      "GOTO/295.42522,106.3578,0\n");
  expect_vec(turned.program.blocks.at(0).end_mm, Eigen::Vector3d(160.92422, 90.6688, 0), 1e-9);
  const AptProgram tilted = read(
      "CSYS/0,0,-1.,0,-1.,0,0,0,0,1.,0,0\nFROM/-25.,101.4375,-47.085194,-1.,0,0\nFEDRAT/100\n"
      "GOTO/3.,101.4375,-47.085194,-1.,0,0\n");
  expect_vec(tilted.program.blocks.at(0).end_mm, Eigen::Vector3d(3, 101.4375, -47.085194));
  expect_vec(tilted.program.blocks.at(0).end_axis, Eigen::Vector3d(-1, 0, 0));
  EXPECT_APT_ERROR("CSYS/1.,0,0,0,0,2.,0,0,0,0,1.,0\n", 1, 6, "not a rotation");
  EXPECT_APT_ERROR("CSYS/-1.,0,0,0,0,1.,0,0,0,0,1.,0\n", 1, 6, "not a rotation");  // a mirror: det -1
  EXPECT_APT_ERROR("CSYS/1.,0,0,0,0,1.,0,0,0,0,1.\n", 1, 6, "expected r11");
}

// MSYS/ (NX): the first is the workpiece frame, its motions read as written. The first has
// o1 = (393, -297.5, 3), X1 = (0, 1, 0), Y1 = (1, 0, 0), Z1 = X1 x Y1 = (0, 0, -1); the second
// o2 = (493, -297.5, 3), X2 = (1, 0, 0), Y2 = (0, -1, 0), Z2 = (0, 0, -1). Its (10, 0, 0) is
// o2 + (10, 0, 0) absolute, (110, 0, 0) from o1: along X1, Y1, Z1 that is (0, 110, 0); its
// (10, 1, 0) is (110, -1, 0) from o1: (-1, 110, 0); its tool axis Z2 is Z1's own: (0, 0, 1).
TEST(AptReader, MsysLaterSetupsPlacedInTheFirst) {
  const AptProgram p = read(
      "MSYS/393.0000,-297.5000,3.0000,0.0000000,1.0000000,0.0000000,1.0000000,0.0000000,0.0000000\n"
      "FROM/0,0,50\nFEDRAT/100\nGOTO/1,2,3\n"
      "MSYS/493.0000,-297.5000,3.0000,1.0000000,0.0000000,0.0000000,0.0000000,-1.0000000,0.0000000\n"
      "GOTO/10,0,0\nGOTO/10,1,0\n");
  ASSERT_EQ(p.program.blocks.size(), 3u);
  expect_vec(p.program.blocks[0].end_mm, Eigen::Vector3d(1, 2, 3));  // the first MSYS/: as written
  expect_vec(p.program.blocks[1].end_mm, Eigen::Vector3d(0, 110, 0));
  expect_vec(p.program.blocks[2].end_mm, Eigen::Vector3d(-1, 110, 0));
  expect_vec(p.program.blocks[2].end_axis, Eigen::Vector3d(0, 0, 1));
  EXPECT_APT_ERROR("MSYS/0,0,0,1,0,0,1,0,0\n", 1, 6, "not a rotation");
}

// CYCLE/DRILL (SolidWorks CAM's form): from (0, 0, 25), the hole at (25, 50, 0): rapid across
// at 25, down to RAPTO 3, feed 5 below at 100 mm/min, rapid back to RTRCTO 25.
TEST(AptReader, CycleDrillMakesTheHolesMotions) {
  const AptProgram p = read(
      "FROM/0,0,25\nCYCLE/INIT\nCYCLE/DRILL,FEDTO,5.,MMPM,100.,RAPTO,3.,RTRCTO,25.,DWELL,0\nGOTO/25,50,0\nCYCLE/OFF\n");
  ASSERT_EQ(p.program.blocks.size(), 4u);
  const MotionKind kinds[4] = {MotionKind::Rapid, MotionKind::Rapid, MotionKind::Linear, MotionKind::Rapid};
  const Eigen::Vector3d ends[4] = {{25, 50, 25}, {25, 50, 3}, {25, 50, -5}, {25, 50, 25}};
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(p.program.blocks[k].kind, kinds[k]) << k;
    expect_vec(p.program.blocks[k].end_mm, ends[k]);
    EXPECT_EQ(p.program.blocks[k].source.line, 4) << k;
  }
  EXPECT_DOUBLE_EQ(p.program.blocks[2].feed_mm_per_min, 100.0);
}

// CYCLE/DEEP pecks of INCR 3 to FEDTO 7 from RAPTO 2, back to RAPTO after each and rapid down
// to where the last stopped: feeds end at -3, -6, -7. The FEDRAT/ is back after CYCLE/OFF.
TEST(AptReader, CycleDeepPecks) {
  const AptProgram p = read(
      "FROM/0,0,10\nFEDRAT/50\nCYCLE/DEEP,FEDTO,7,INCR,3,MMPM,100,RAPTO,2,RTRCTO,10\nGOTO/0,0,0\nCYCLE/OFF\n"
      "GOTO/5,0,10\n");
  const double z[] = {2, -3, 2, -3, -6, 2, -6, -7, 10, 10};
  const MotionKind R = MotionKind::Rapid, L = MotionKind::Linear;
  const MotionKind kinds[] = {R, L, R, R, L, R, R, L, R, L};
  ASSERT_EQ(p.program.blocks.size(), 10u);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(p.program.blocks[k].kind, kinds[k]) << k;
    EXPECT_NEAR(p.program.blocks[k].end_mm.z(), z[k], kTol) << k;
  }
  EXPECT_DOUBLE_EQ(p.program.blocks[9].feed_mm_per_min, 50.0);
  // SolidWorks CAM's DEEP2: a first peck of 5, then 2: feeds end at -5, -7, -9, -10.
  const AptProgram deep2 = read(
      "FROM/0,0,30\nCYCLE/DEEP2,FEDTO,10,1STPECK,5.,SUBPECK,2.,MMPM,382.27,RAPTO,3.,RTRCTO,27.5\nGOTO/0,0,0\n"
      "LOADTL/2\nFEDRAT/10\nGOTO/1,0,0\n");
  std::vector<double> feeds;
  for (const Block& b : deep2.program.blocks)
    if (b.kind == MotionKind::Linear) feeds.push_back(b.end_mm.z());
  EXPECT_EQ(feeds, (std::vector<double>{-5, -7, -9, -10, 0}));  // the tool change ended the cycle
  EXPECT_APT_ERROR("CYCLE/DRILL,RAPTO,3\n", 1, 7, "without its depth");
  EXPECT_APT_ERROR("CYCLE/SPIRAL,FEDTO,1\n", 1, 7, "not supported");
  EXPECT_APT_ERROR("CYCLE/DRILL,FEDTO\n", 1, 13, "FEDTO without its number");
  EXPECT_APT_ERROR("CYCLE/DRILL,FEDTO,1,SPEEDY,2\n", 1, 21, "unknown CYCLE/ parameter SPEEDY");
}

// NX's TLDATA/MILL (diameter, lower radius, length, taper, tip angle) and LOAD/TOOL,0.
TEST(AptReader, NxTldataAndToolZero) {
  const AptProgram p = read(
      "TOOL PATH/CAVITY_MILL,TOOL,MILL_10\nTLDATA/MILL,10.0000,2.0000,50.0000,0.0000,0.0000\nLOAD/TOOL,0,ADJUST,1\n"
      "FROM/0,0,0\nFEDRAT/MMPM,250\nGOTO/1,0,0\nEND-OF-PATH\n");
  ASSERT_EQ(p.cutters.count(1), 1u);
  const removal::Cutter& c = p.cutters.at(1);
  EXPECT_EQ(c.type, CutterType::BullNose);
  EXPECT_DOUBLE_EQ(c.diameter_mm, 10.0);
  EXPECT_DOUBLE_EQ(c.corner_radius_mm, 2.0);
  EXPECT_DOUBLE_EQ(c.flute_length_mm, 50.0);
  EXPECT_EQ(p.program.blocks.at(0).tool, 1);
  EXPECT_APT_ERROR("TLDATA/MILL,10,0,50,5,0\n", 1, 21, "tapered cutter");
}

// CUTCOM/ on the tool's centre path (NX's "$$ centerline data", SolidWorks CAM's CSI_
// statements, program.cutcom: centre): no offset, one warning. Without either, APT's contour.
TEST(AptReader, CutcomOnACentrePath) {
  const std::string path = "CUTTER/14\nFROM/0,0,0\nFEDRAT/100\nCUTCOM/LEFT\nGOTO/1,0,0\nGOTO/20,0,0\nCUTCOM/OFF\n";
  for (const std::string& marker : {std::string("$$ centerline data\n"), std::string("CSI_SET_FLUTE_LENGTH/4.\n")}) {
    const AptProgram p = read(marker + path);
    ASSERT_EQ(p.program.blocks.size(), 2u) << marker;
    expect_vec(p.program.blocks[1].end_mm, Eigen::Vector3d(20, 0, 0));
    bool warned = false;
    for (const auto& w : p.program.warnings) warned = warned || w.find("CUTCOM/ on") != std::string::npos;
    EXPECT_TRUE(warned) << marker;
  }
  AptOptions centre;
  centre.cutcom_on_centre = true;
  EXPECT_EQ(read(path, centre).program.blocks.size(), 2u);
  EXPECT_APT_ERROR(path, 5, 1, "set program.cutcom: centre");  // a 1 mm entry for a 7 mm radius
}

// GOHOME (NX): a rapid to the point given, else back to the FROM/ point.
TEST(AptReader, Gohome) {
  const AptProgram p = read("FROM/0,0,100\nFEDRAT/100\nGOTO/10,0,0\nGOHOME\nGOTO/5,5,5\nGOHOME/650,-393,964\n");
  ASSERT_EQ(p.program.blocks.size(), 4u);
  EXPECT_EQ(p.program.blocks[1].kind, MotionKind::Rapid);
  expect_vec(p.program.blocks[1].end_mm, Eigen::Vector3d(0, 0, 100));
  EXPECT_EQ(p.program.blocks[3].kind, MotionKind::Rapid);
  expect_vec(p.program.blocks[3].end_mm, Eigen::Vector3d(650, -393, 964));
  EXPECT_APT_ERROR("GOHOME\n", 1, 1, "before any FROM/");
}

// Creo's commented-out statements continue with '$'; NX's information listing has a header
// and a last line that are not CL data.
TEST(AptReader, CreoCommentsAndNxListing) {
  const AptProgram creo = read(
      "$$-> CSYS / 1.0000000000, 0.0000000000, 0.0000000000, 0.0000000000,  $\n"
      "            0.0000000000, 1.0000000000, 0.0000000000, 0.0000000000,  $\n"
      "            0.0000000000, 0.0000000000, 1.0000000000, 0.0000000000\n"
      "LOADTL / 1\nFROM / 0, 0, 0\nFEDRAT / 400.000000,  MMPM\nGOTO / 1, 0, 0\n");
  EXPECT_EQ(creo.program.blocks.size(), 1u);
  const AptProgram nx = read(
      "\nInformation listing created by\tphill\nDate\t18-Dec-2021 21:07:42\nNode name\tlaptop\n\n"
      "TOOL PATH/CAVITY_MILL,TOOL,MILL\nFROM/0,0,0\nFEDRAT/MMPM,530\nGOTO/1,0,0\nTool Path Listing has 350 lines.\n");
  EXPECT_EQ(nx.program.blocks.size(), 1u);
}

}  // namespace
}  // namespace vcut::io
