// Tests of the G-code reader. Expected values are worked by hand from the RS274/NGC
// semantics as LinuxCNC documents and implements them (G-code reference pages; rs274ngc
// interp_convert.cc / interp_arc.cc), each noted where it is used; none is copied from the
// reader's own output.
#include <gtest/gtest.h>
#include <vcut/io/gcode_reader.h>
#include <vcut/io/input_error.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::MotionKind;
using kinematics::Program;
using kinematics::SpindleState;

// Hand-computed values are exact decimals or closed forms evaluated in double: only the
// rounding of a few operations separates them from the reader's results.
constexpr double kTol = 1e-9;
constexpr double kPi = 3.14159265358979323846;

Program read(const std::string& text, const GcodeOptions& options = {}) {
  Program program;
  GcodeState state;
  std::istringstream in(text);
  read_gcode(in, "test.ngc", options, program, state);
  return program;
}

// The error a program raises; fails the test if it raises none.
InputError error_of(const std::string& text, const GcodeOptions& options = {}) {
  try {
    read(text, options);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return InputError("none");
}

#define EXPECT_INPUT_ERROR(text, line_, column_, fragment) \
  EXPECT_INPUT_ERROR_WITH(text, line_, column_, fragment, GcodeOptions{})
#define EXPECT_INPUT_ERROR_WITH(text, line_, column_, fragment, options)                                       \
  do {                                                                                                         \
    const InputError e_ = error_of(text, options);                                                             \
    EXPECT_EQ(e_.file(), "test.ngc");                                                                          \
    EXPECT_EQ(e_.line(), line_) << e_.what();                                                                  \
    EXPECT_EQ(e_.column(), column_) << e_.what();                                                              \
    EXPECT_NE(std::string(e_.what()).find(fragment), std::string::npos) << e_.what();                          \
    EXPECT_EQ(std::string(e_.what()).rfind(                                                                    \
                  std::string("test.ngc:") + std::to_string(line_) + ":" + std::to_string(column_) + ": ", 0), \
              0u)                                                                                              \
        << e_.what();                                                                                          \
  } while (0)

void expect_vec(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected, double tol = kTol) {
  EXPECT_NEAR(actual.x(), expected.x(), tol) << actual.transpose();
  EXPECT_NEAR(actual.y(), expected.y(), tol) << actual.transpose();
  EXPECT_NEAR(actual.z(), expected.z(), tol) << actual.transpose();
}

// The swept angle of an arc as program.h defines it: from start to end about `normal`, in
// (0, 2*pi], plus 2*pi per extra turn.
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

// ---------------------------------------------------------------- motion kinds

TEST(GcodeReader, RapidAndLinearMovesWithFeedAndSource) {
  // Straight moves: the end points are the programmed values (G21 G90, no offset).
  const Program p = read(
      "G17 G21 G40 G49 G80 G90 G94\n"
      "G0 X0 Y0 Z10\n"
      "G1 Z0 F100\n"
      "G1 X10\n"
      "G0 Z10\n");
  ASSERT_EQ(p.files.size(), 1u);
  EXPECT_EQ(p.files[0], "test.ngc");
  // Line 2 starts from an unknown position, so it moves nothing and is dropped.
  ASSERT_EQ(p.blocks.size(), 3u);
  EXPECT_EQ(p.blocks[0].kind, MotionKind::Linear);
  expect_vec(p.blocks[0].start_mm, {0, 0, 10});
  expect_vec(p.blocks[0].end_mm, {0, 0, 0});
  EXPECT_EQ(p.blocks[0].feed_mm_per_min, 100.0);
  EXPECT_EQ(p.blocks[0].source.file, 0);
  EXPECT_EQ(p.blocks[0].source.line, 3);
  EXPECT_EQ(p.blocks[1].kind, MotionKind::Linear);
  expect_vec(p.blocks[1].start_mm, {0, 0, 0});
  expect_vec(p.blocks[1].end_mm, {10, 0, 0});
  EXPECT_EQ(p.blocks[1].source.line, 4);
  EXPECT_EQ(p.blocks[2].kind, MotionKind::Rapid);
  expect_vec(p.blocks[2].end_mm, {10, 0, 10});
  EXPECT_EQ(p.blocks[2].feed_mm_per_min, 0.0);  // rapids carry no feed
  EXPECT_EQ(p.blocks[2].source.line, 5);
  EXPECT_TRUE(p.warnings.empty());
}

TEST(GcodeReader, FirstMovesOnlyMoveProgrammedAxes) {
  // Brief: an unknown axis's start takes the end value, so each of the first three lines
  // moves nothing (dropped); the fourth runs from (5, 7, 3).
  const Program p = read("G0 X5\nG0 Y7\nG0 Z3\nG1 X6 F10\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  expect_vec(p.blocks[0].start_mm, {5, 7, 3});
  expect_vec(p.blocks[0].end_mm, {6, 7, 3});
  EXPECT_EQ(p.blocks[0].source.line, 4);
}

TEST(GcodeReader, MoveWhileAnAxisIsUnknownHoldsItAtItsFirstValue) {
  // Z is unknown during line 2; it is first programmed (5) on line 3, so line 2's move holds
  // Z at 5 and line 3 moves nothing. A warning says so.
  const Program p = read("G0 X0 Y0\nG1 X10 F100\nG0 Z5\nG1 Y1\n");
  ASSERT_EQ(p.blocks.size(), 2u);
  expect_vec(p.blocks[0].start_mm, {0, 0, 5});
  expect_vec(p.blocks[0].end_mm, {10, 0, 5});
  expect_vec(p.blocks[1].start_mm, {10, 0, 5});
  expect_vec(p.blocks[1].end_mm, {10, 1, 5});
  ASSERT_EQ(p.warnings.size(), 1u);
  EXPECT_NE(p.warnings[0].find("test.ngc:3:"), std::string::npos) << p.warnings[0];
  EXPECT_NE(p.warnings[0].find("Z"), std::string::npos) << p.warnings[0];
}

TEST(GcodeReader, ZeroLengthMovesAreDropped) {
  // Convention of this reader: a straight move that does not move makes no Block.
  const Program p = read("G0 X0 Y0 Z0\nG1 X0 F10\nG0 Y0 Z0\nG1 X1\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  EXPECT_EQ(p.blocks[0].source.line, 4);
}

TEST(GcodeReader, ModalMotionRepeats) {
  // A line with only coordinates repeats the last motion code (rs274ngc modal group 1).
  const Program p = read("G0 X0 Y0 Z0\nG1 X10 F200\nY5\nX0 Y0\nG0 Z5\nX3\n");
  ASSERT_EQ(p.blocks.size(), 5u);
  EXPECT_EQ(p.blocks[1].kind, MotionKind::Linear);
  expect_vec(p.blocks[1].end_mm, {10, 5, 0});
  EXPECT_EQ(p.blocks[1].feed_mm_per_min, 200.0);
  EXPECT_EQ(p.blocks[2].kind, MotionKind::Linear);
  expect_vec(p.blocks[2].end_mm, {0, 0, 0});
  EXPECT_EQ(p.blocks[4].kind, MotionKind::Rapid);
  expect_vec(p.blocks[4].end_mm, {3, 0, 5});
}

// ---------------------------------------------------------------- arcs

TEST(GcodeReader, ArcG17IjkCentreNormalAndSweep) {
  // From (10,0): centre = start + (I,J) = (0,0). G3 turns about +Z (program.h), so (10,0) to
  // (0,10) is a quarter turn; G2 about -Z, so (10,0) to (0,-10) is a quarter turn too.
  const Program p = read("G0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F100\nG0 X10 Y0\nG2 X0 Y-10 I-10\n");
  // The first G0 starts from an unknown position: it moves nothing and is dropped.
  ASSERT_EQ(p.blocks.size(), 3u);
  const Block& ccw = p.blocks[0];
  EXPECT_EQ(ccw.kind, MotionKind::Arc);
  expect_vec(ccw.center_mm, {0, 0, 0});
  expect_vec(ccw.normal, {0, 0, 1});
  expect_vec(ccw.end_mm, {0, 10, 0});
  EXPECT_EQ(ccw.turns, 1);
  EXPECT_EQ(ccw.feed_mm_per_min, 100.0);
  EXPECT_NEAR(swept_angle(ccw), kPi / 2, kTol);
  const Block& cw = p.blocks[2];
  expect_vec(cw.center_mm, {0, 0, 0});
  expect_vec(cw.normal, {0, 0, -1});
  EXPECT_NEAR(swept_angle(cw), kPi / 2, kTol);
}

TEST(GcodeReader, ArcG18FollowsLinuxCncZxPlane) {
  // rs274ngc convert_arc passes (Z, X) as the plane's (first, second) axes in G18 and G3 is
  // counterclockwise from first to second: a right-hand turn about Z x X = +Y. Rotating
  // (10,0,0) by +90 deg about +Y gives (0,0,-10): G3 X0 Z-10 from X10 Z0 about the origin is a
  // quarter turn. G2 turns about -Y: (10,0,0) -> (0,0,10) is a quarter turn.
  const Program p = read("G18\nG0 X10 Y0 Z0\nG3 X0 Z-10 I-10 K0 F100\nG0 X10 Z0\nG2 X0 Z10 I-10\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_vec(p.blocks[0].center_mm, {0, 0, 0});
  expect_vec(p.blocks[0].normal, {0, 1, 0});
  EXPECT_NEAR(swept_angle(p.blocks[0]), kPi / 2, kTol);
  expect_vec(p.blocks[2].normal, {0, -1, 0});
  EXPECT_NEAR(swept_angle(p.blocks[2]), kPi / 2, kTol);
}

TEST(GcodeReader, ArcG19YzPlane) {
  // G19: plane (Y, Z), G3 about Y x Z = +X. Rotating (0,10,0) by +90 deg about +X gives
  // (0,0,10): a quarter turn with centre (0,0,0) = start + (J,K).
  const Program p = read("G19\nG0 X0 Y10 Z0\nG3 Y0 Z10 J-10 K0 F100\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  expect_vec(p.blocks[0].center_mm, {0, 0, 0});
  expect_vec(p.blocks[0].normal, {1, 0, 0});
  expect_vec(p.blocks[0].end_mm, {0, 0, 10});
  EXPECT_NEAR(swept_angle(p.blocks[0]), kPi / 2, kTol);
}

TEST(GcodeReader, RArcsShortAndLongBothDirections) {
  // (0,0) -> (10,0) with |R| = 10: centre on x = 5 at y = +-sqrt(100 - 25) = +-8.660254...
  // rs274ngc arc_data_r: right of start->end (y < 0) for G2 R>0 and G3 R<0, else left.
  // The short arc subtends 2*asin(5/10) = pi/3, the long one 2*pi - pi/3.
  const double h = std::sqrt(75.0);
  struct Case {
    const char* code;
    double center_y;
    double normal_z;
    double angle;
  } cases[] = {{"G2 X10 R10", -h, -1, kPi / 3},
               {"G2 X10 R-10", h, -1, 2 * kPi - kPi / 3},
               {"G3 X10 R10", h, 1, kPi / 3},
               {"G3 X10 R-10", -h, 1, 2 * kPi - kPi / 3}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.code);
    const Program p = read(std::string("G0 X0 Y0 Z0\nF100\n") + c.code + "\n");
    ASSERT_EQ(p.blocks.size(), 1u);
    expect_vec(p.blocks[0].center_mm, {5, c.center_y, 0});
    expect_vec(p.blocks[0].normal, {0, 0, c.normal_z});
    EXPECT_NEAR(swept_angle(p.blocks[0]), c.angle, kTol);
  }
  // A semicircle (|R| = half the chord): centre at the chord's midpoint.
  const Program semi = read("G0 X0 Y0 Z0\nG2 X10 R5 F100\n");
  expect_vec(semi.blocks.at(0).center_mm, {5, 0, 0});
  EXPECT_NEAR(swept_angle(semi.blocks[0]), kPi, kTol);
}

TEST(GcodeReader, FullCircleWithIjk) {
  // Start == end with I J K: one full turn (2*pi) about centre (0,0).
  for (const char* line : {"G2 I-10", "G3 X10 Y0 I-10 J0"}) {
    SCOPED_TRACE(line);
    const Program p = read(std::string("G0 X10 Y0 Z0\nF100\n") + line + "\n");
    ASSERT_EQ(p.blocks.size(), 1u);
    EXPECT_EQ(p.blocks[0].start_mm, p.blocks[0].end_mm);
    expect_vec(p.blocks[0].center_mm, {0, 0, 0});
    EXPECT_NEAR(swept_angle(p.blocks[0]), 2 * kPi, kTol);
  }
}

TEST(GcodeReader, HelixWithTurns) {
  // Full circle in XY while Z falls 5 mm, P2 = two turns (4*pi); the centre lies in the
  // start's plane (z = 0) per program.h.
  const Program p = read("G0 X10 Y0 Z0\nG3 X10 Y0 Z-5 I-10 P2 F100\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  const Block& b = p.blocks[0];
  expect_vec(b.start_mm, {10, 0, 0});
  expect_vec(b.end_mm, {10, 0, -5});
  expect_vec(b.center_mm, {0, 0, 0});
  EXPECT_EQ(b.turns, 2);
  EXPECT_NEAR(swept_angle(b), 4 * kPi, kTol);
}

TEST(GcodeReader, ArcToleranceBoundary) {
  // LinuxCNC 2.9's rs274 (run on these arcs): from X0 Y0 about I r, an end at X 2r + d is
  // accepted for r = 10 mm, d = 0.028 and refused for d = 0.029 (2 * 0.01 * sqrt 2 = 0.0283 mm);
  // for r = 1000, d = 1.0 passes and 1.01 does not (0.1 % of the larger radius); for r = 10000,
  // d = 2.8 passes and 2.9 does not (100 x 0.0283 mm); in G20, r = 1 in: d = 0.0028 in passes
  // and 0.0029 in does not.
  auto arc = [](const char* units, double r, double d) {
    char text[160];
    std::snprintf(text, sizeof text, "%s G17 G90\nG0 X0 Y0 Z0\nG2 X%.4f Y0 I%.4f J0 F100\n", units, 2 * r + d, r);
    return std::string(text);
  };
  EXPECT_NO_THROW(read(arc("G21", 10, 0.028)));
  EXPECT_INPUT_ERROR(arc("G21", 10, 0.029), 3, 1, "not on its circle");
  EXPECT_NO_THROW(read(arc("G21", 1000, 1.0)));
  EXPECT_INPUT_ERROR(arc("G21", 1000, 1.01), 3, 1, "not on its circle");
  EXPECT_NO_THROW(read(arc("G21", 10000, 2.8)));
  EXPECT_INPUT_ERROR(arc("G21", 10000, 2.9), 3, 1, "not on its circle");
  EXPECT_NO_THROW(read(arc("G20", 1, 0.0028)));
  EXPECT_INPUT_ERROR(arc("G20", 1, 0.0029), 3, 1, "not on its circle");
  // The end off the circle is kept: the control cuts a spiral to it.
  const Program p = read(arc("G21", 10, 0.028));
  EXPECT_NEAR(p.blocks.back().end_mm.x(), 20.028, 1e-12);
  // A job's tolerance replaces the absolute one.
  GcodeOptions strict;
  strict.arc_tolerance_mm = 0.01;
  strict.arc_tolerance_relative = 0.0;
  EXPECT_INPUT_ERROR_WITH(arc("G21", 10, 0.011), 3, 1, "not on its circle", strict);
  EXPECT_NO_THROW(read(arc("G21", 10, 0.009), strict));
}

TEST(GcodeReader, RandomArcsLieOnTheirCircles) {
  // Property (fixed seed): for R arcs in every plane, start and end are |R| from the centre
  // in the plane, and the sweep is <= pi for R > 0 and >= pi for R < 0 (rs274 / NCMS rule).
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> coord(-50.0, 50.0);
  std::uniform_real_distribution<double> extra(1.0, 3.0);
  const char* planes[] = {"G17", "G18", "G19"};
  const int axes[3][2] = {{0, 1}, {2, 0}, {1, 2}};
  for (int i = 0; i < 300; ++i) {
    const int plane = i % 3;
    const bool cw = (i / 3) % 2 == 0;
    const bool long_arc = (i / 6) % 2 == 0;
    const Eigen::Vector3d s(coord(rng), coord(rng), coord(rng));
    const Eigen::Vector3d e(coord(rng), coord(rng), coord(rng));
    const int a = axes[plane][0], b = axes[plane][1];
    const double half = std::hypot(e[a] - s[a], e[b] - s[b]) / 2.0;
    const double r = half * extra(rng);
    char text[512];
    std::snprintf(text, sizeof text, "%s G0 X%.6f Y%.6f Z%.6f\n%s X%.6f Y%.6f Z%.6f R%.6f F100\n", planes[plane], s.x(),
                  s.y(), s.z(), cw ? "G2" : "G3", e.x(), e.y(), e.z(), long_arc ? -r : r);
    SCOPED_TRACE(text);
    const Program p = read(text);
    ASSERT_EQ(p.blocks.size(), 1u);  // the first G0 moves nothing
    const Block& arc = p.blocks[0];
    const double r_read = std::round(r * 1e6) / 1e6;  // as printed
    const Eigen::Vector3d c = arc.center_mm;
    EXPECT_NEAR(std::hypot(arc.start_mm[a] - c[a], arc.start_mm[b] - c[b]), r_read, 1e-6);
    EXPECT_NEAR(std::hypot(arc.end_mm[a] - c[a], arc.end_mm[b] - c[b]), r_read, 1e-6);
    const double angle = swept_angle(arc);
    if (long_arc) {
      EXPECT_GE(angle, kPi - 1e-9);
    } else {
      EXPECT_LE(angle, kPi + 1e-9);
    }
  }
}

// ---------------------------------------------------------------- modes

TEST(GcodeReader, InchesConvertCoordinatesCentresRadiiAndFeed) {
  // G20: every length and F times 25.4 (exact).
  const Program p = read("G20\nG0 X1 Y0 Z0.5\nG1 X2 F10\nG3 X1 Y1 I-1 J0\nG2 X0 Y0 R-1\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_vec(p.blocks[0].start_mm, {25.4, 0, 12.7});
  expect_vec(p.blocks[0].end_mm, {50.8, 0, 12.7});
  EXPECT_DOUBLE_EQ(p.blocks[0].feed_mm_per_min, 254.0);
  // (2,0) in + (I,J) = (1,0) in.
  expect_vec(p.blocks[1].center_mm, {25.4, 0, 12.7});
  expect_vec(p.blocks[1].end_mm, {25.4, 25.4, 12.7});
  // (1,1) -> (0,0) in, R -1 in: the circles of radius 1 through both points have centres
  // (1,0) and (0,1); clockwise about (1,0) from 90 deg to 180 deg is 270 deg, the long arc
  // that a negative R asks for. So the centre is (1,0) in = (25.4, 0) mm.
  expect_vec(p.blocks[2].center_mm, {25.4, 0, 12.7});
  EXPECT_NEAR(swept_angle(p.blocks[2]), 1.5 * kPi, kTol);
  // Back to G21: numbers are mm again; the feed in effect stays 254 mm/min.
  const Program q = read("G20 G0 X1 Y0 Z0\nF10\nG21 G1 X10\n");
  expect_vec(q.blocks.at(0).end_mm, {10, 0, 0});
  EXPECT_DOUBLE_EQ(q.blocks[0].feed_mm_per_min, 254.0);
}

TEST(GcodeReader, IncrementalDistanceMode) {
  // G91: each axis word adds to the current position.
  const Program p = read("G0 X1 Y1 Z1\nG91\nG1 X2 F100\nY-3\nG90 X0\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_vec(p.blocks[0].start_mm, {1, 1, 1});
  expect_vec(p.blocks[0].end_mm, {3, 1, 1});
  expect_vec(p.blocks[1].end_mm, {3, -2, 1});
  expect_vec(p.blocks[2].end_mm, {0, -2, 1});
  // Incremental arcs: the end is start + (X, Y), the centre start + (I, J) as always.
  const Program a = read("G0 X10 Y0 Z0\nG91 G3 X-10 Y10 I-10 F100\n");
  expect_vec(a.blocks.at(0).end_mm, {0, 10, 0});
  expect_vec(a.blocks[0].center_mm, {0, 0, 0});
}

TEST(GcodeReader, AbsoluteArcCentreG901) {
  // G90.1: I J K are the centre's coordinates in the active system (LinuxCNC G90.1), so a
  // G54 offset applies to them as to X Y Z.
  const Program p = read("G90.1\nG0 X10 Y0 Z0\nG3 X0 Y10 I0 J0 F100\n");
  expect_vec(p.blocks.at(0).center_mm, {0, 0, 0});
  GcodeOptions options;
  options.work_offsets_mm["G54"] = Eigen::Vector3d(100, 200, 0);
  const Program q = read("G90.1\nG0 X10 Y0 Z0\nG3 X0 Y10 I0 J0 F100\nG91.1 G2 X10 Y0 I0 J-10\n", options);
  ASSERT_EQ(q.blocks.size(), 2u);
  expect_vec(q.blocks[0].center_mm, {100, 200, 0});
  expect_vec(q.blocks[0].end_mm, {100, 210, 0});
  // Back in G91.1: centre = start (100,210) + (0,-10).
  expect_vec(q.blocks[1].center_mm, {100, 200, 0});
}

TEST(GcodeReader, WorkOffsetsApply) {
  // Brief: block coordinates = programmed (mm) + the active offset. Changing the system does
  // not move the tool (LinuxCNC): unprogrammed axes keep their workpiece-frame position.
  GcodeOptions options;
  options.work_offsets_mm["G54"] = Eigen::Vector3d(100, 0, -50);
  options.work_offsets_mm["G55"] = Eigen::Vector3d(0, 300, 0);
  options.work_offsets_mm["G59.1"] = Eigen::Vector3d(1, 1, 1);
  const Program p = read("G0 X1 Y2 Z3\nG1 X2 F10\nG55 G1 X3\nY0\nG59.1 Z0\n", options);
  ASSERT_EQ(p.blocks.size(), 4u);
  expect_vec(p.blocks[0].start_mm, {101, 2, -47});
  expect_vec(p.blocks[0].end_mm, {102, 2, -47});
  expect_vec(p.blocks[1].end_mm, {3, 2, -47});
  expect_vec(p.blocks[2].end_mm, {3, 300, -47});
  expect_vec(p.blocks[3].end_mm, {3, 300, 1});
}

TEST(GcodeReader, CommentsPercentBlockDeleteLineNumbersAndNumberForms) {
  const Program p = read(
      "%\n"
      "(header comment)\n"
      "N10 G0 X0 Y0 Z0 ; trailing comment\n"
      "/G1 X100 F1\n"
      "  / G1 X100 F1\n"
      "n20 g1 x1 (mid-line comment) y2 f50\n"
      "N30 G4 P0.5\n"
      "G1 X 1 0.5 Y -1320 Z+3\n"  // LinuxCNC drops blanks: X10.5
      "G1 X1. Y.5 Z-0.25\n"
      "%\n"
      "G1 X999\n"
      "garbage after the closing percent\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_vec(p.blocks[0].end_mm, {1, 2, 0});
  EXPECT_EQ(p.blocks[0].source.line, 6);
  EXPECT_EQ(p.blocks[0].feed_mm_per_min, 50.0);
  expect_vec(p.blocks[1].end_mm, {10.5, -1320, 3});
  EXPECT_EQ(p.blocks[1].source.line, 8);
  expect_vec(p.blocks[2].end_mm, {1, 0.5, -0.25});
  // CRLF line ends, tabs, a Fanuc program number and G01-style codes.
  const Program q = read("O1234 (PART)\r\nG00\tX0 Y0 Z0\r\nG01 X5 F100\r\n");
  ASSERT_EQ(q.blocks.size(), 1u);
  expect_vec(q.blocks[0].end_mm, {5, 0, 0});
}

TEST(GcodeReader, ProgramEndIgnoresLaterLinesAndResetsModes) {
  const Program p = read("G0 X0 Y0 Z0\nG1 X1 F10\nM2\nG1 X5\nthis is not G-code\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  // M30 on a motion line: the motion runs first (rs274ngc order of execution).
  const Program q = read("G0 X0 Y0 Z0\nG1 X2 F10 M30\nG1 X5\n");
  ASSERT_EQ(q.blocks.size(), 1u);
  expect_vec(q.blocks[0].end_mm, {2, 0, 0});
  // LinuxCNC M2: G54 G17 G90 M5 and motion mode G1; position, units and feed stay.
  Program program;
  GcodeState state;
  std::istringstream in("G20 G18 G55 G0 X0 Y0 Z0\nG91 S100 M3 F5\nG0 M2\n");
  read_gcode(in, "a.ngc", {}, program, state);
  EXPECT_EQ(state.work_offset, "G54");
  EXPECT_EQ(state.plane, GcodeState::Plane::XY);
  EXPECT_FALSE(state.incremental);
  EXPECT_TRUE(state.inches);
  EXPECT_EQ(state.spindle, SpindleState::Off);
  EXPECT_EQ(state.motion, GcodeState::Motion::Linear);
}

TEST(GcodeReader, ToolChangeAndSpindleState) {
  // T only selects; M6 loads the selected tool (LinuxCNC). M5 on a motion line stops the
  // spindle before the motion (rs274ngc: spindle control precedes motion).
  const Program p = read("T1 M6\nS1000 M3\nG0 X0 Y0 Z0\nG1 X1 F10\nT2\nG1 X2\nM6\nM4 S500\nG1 X3\nM5 G1 X4\n");
  ASSERT_EQ(p.blocks.size(), 4u);
  EXPECT_EQ(p.blocks[0].tool, 1);
  EXPECT_EQ(p.blocks[0].spindle, SpindleState::Clockwise);
  EXPECT_EQ(p.blocks[0].spindle_rpm, 1000.0);
  EXPECT_EQ(p.blocks[1].tool, 1);
  EXPECT_EQ(p.blocks[2].tool, 2);
  EXPECT_EQ(p.blocks[2].spindle, SpindleState::CounterClockwise);
  EXPECT_EQ(p.blocks[2].spindle_rpm, 500.0);
  EXPECT_EQ(p.blocks[3].spindle, SpindleState::Off);
  // T and M6 on one line in either order: T is read first.
  EXPECT_EQ(read("M6 T7\nG0 X0 Y0 Z0\nG0 X1\n").blocks.at(0).tool, 7);
}

TEST(GcodeReader, StateCarriesAcrossFiles) {
  Program program;
  GcodeState state;
  std::istringstream first("G0 X0 Y0 Z0\nG1 X1 F100\nG20\n");
  read_gcode(first, "first.ngc", {}, program, state);
  std::istringstream second("X1\n");  // modal G1, inches, F100 mm/min carried over
  read_gcode(second, "second.ngc", {}, program, state);
  ASSERT_EQ(program.files.size(), 2u);
  EXPECT_EQ(program.files[1], "second.ngc");
  ASSERT_EQ(program.blocks.size(), 2u);
  EXPECT_EQ(program.blocks[1].source.file, 1);
  EXPECT_EQ(program.blocks[1].source.line, 1);
  expect_vec(program.blocks[1].start_mm, {1, 0, 0});
  expect_vec(program.blocks[1].end_mm, {25.4, 0, 0});
  EXPECT_EQ(program.blocks[1].feed_mm_per_min, 100.0);
  EXPECT_EQ(program.where(program.blocks[1].source), "second.ngc:1");
}

TEST(GcodeReader, UnknownAxisResolvedInALaterFile) {
  // Z is unknown through the first file: its move holds Z still (warning at the end of the
  // file) and takes Z = 2 when the second file first programs it (second warning).
  Program program;
  GcodeState state;
  std::istringstream first("G0 X0 Y0\nG1 X1 F10\n");
  read_gcode(first, "first.ngc", {}, program, state);
  ASSERT_EQ(program.warnings.size(), 1u);
  EXPECT_NE(program.warnings[0].find("Z has not been programmed"), std::string::npos);
  std::istringstream second("G0 Z2\n");
  read_gcode(second, "second.ngc", {}, program, state);
  ASSERT_EQ(program.blocks.size(), 1u);
  expect_vec(program.blocks[0].start_mm, {0, 0, 2});
  expect_vec(program.blocks[0].end_mm, {1, 0, 2});
  ASSERT_EQ(program.warnings.size(), 2u);
  EXPECT_EQ(program.warnings[1].rfind("second.ngc:1:4: ", 0), 0u) << program.warnings[1];
}

TEST(GcodeReader, ReadsAFileByPath) {
  const std::string path = testing::TempDir() + "vcut_gcode_reader_test.ngc";
  {
    std::ofstream out(path);
    out << "G0 X0 Y0\nG1 X1 F10\n";
  }
  const Program p = read_gcode(path, {});
  ASSERT_EQ(p.files.size(), 1u);
  EXPECT_EQ(p.files[0], path);
  ASSERT_EQ(p.blocks.size(), 1u);
  EXPECT_EQ(p.blocks[0].source.file, 0);
  EXPECT_EQ(p.where(p.blocks[0].source), path + ":2");
  // Z was never programmed: the block holds it at 0 and a warning says so.
  ASSERT_EQ(p.warnings.size(), 1u);
  EXPECT_NE(p.warnings[0].find("Z has not been programmed"), std::string::npos) << p.warnings[0];
}

TEST(GcodeReader, LongLinesAndManyLines) {
  // A 1 MB comment and 1 MB of blanks inside one line; then 200000 short lines.
  const std::string long_line = "G0 X0 Y0 Z0 (" + std::string(1 << 20, 'c') + ")" + std::string(1 << 20, ' ') + "\n";
  EXPECT_TRUE(read(long_line).blocks.empty());
  std::string many = "G0 X0 Y0 Z0\nG1 F100\n";
  for (int i = 1; i <= 200000; ++i) many += (i % 2 ? "X1\n" : "X0\n");
  const Program p = read(many);
  EXPECT_EQ(p.blocks.size(), 200000u);
  EXPECT_EQ(p.blocks.back().source.line, 200002);
}

// What controls and senders accept and rs274ngc may not: each a documented choice.
TEST(GcodeReader, WhatControlsTolerate) {
  // A lone CR ends a line (old Macintosh files); CR LF is one line end. Lines count per end.
  const Program cr = read("G0 X0 Y0 Z0\rG0 X1\r\nG0 X2\rG0 X3\n");
  ASSERT_EQ(cr.blocks.size(), 3u);
  expect_vec(cr.blocks[2].end_mm, {3, 0, 0});
  EXPECT_EQ(cr.blocks[2].source.line, 4);
  EXPECT_INPUT_ERROR("G0 X0\rG0 Q1\n", 2, 4, "Q word");

  // A '(' inside a comment: the comment ends at the first ')'; LinuxCNC's flavour warns.
  const Program nested = read("G0 X0 Y0 Z0 (a (b c)\nG0 X1\n");
  EXPECT_EQ(nested.blocks.size(), 1u);
  EXPECT_TRUE(nested.warnings.empty());
  GcodeOptions linuxcnc;
  linuxcnc.flavor = GcodeOptions::Flavor::LinuxCnc;
  const Program warned = read("G0 X0 Y0 Z0 (a (b c)\nG0 X1\n", linuxcnc);
  ASSERT_EQ(warned.warnings.size(), 1u);
  EXPECT_EQ(warned.warnings[0].rfind("test.ngc:1:16: '(' inside a comment", 0), 0u) << warned.warnings[0];

  // "G0 G80": Fanuc's G80 is the cycle cancel (group 9), so the line is a rapid that ends a
  // drilling series; rs274ngc has both in group 1 and refuses the pair.
  const Program g80 = read("G0 X0 Y0 Z10\nG81 X5 Z-1 R1 F100\nG0 G80 Z20\nX6\n");
  ASSERT_FALSE(g80.blocks.empty());
  expect_vec(g80.blocks.back().end_mm, {6, 0, 20});
  EXPECT_EQ(g80.blocks.back().kind, MotionKind::Rapid);
  EXPECT_INPUT_ERROR_WITH("G0 G80 Z20\n", 1, 4, "motion (group 1)", linuxcnc);

  // Block delete: '/' lines are skipped with the switch on (the default), run with it off.
  GcodeOptions run_deleted;
  run_deleted.block_delete = false;
  EXPECT_EQ(read("G0 X0 Y0 Z0\n/G0 X1\n").blocks.size(), 0u);
  const Program deleted = read("G0 X0 Y0 Z0\n/G0 X1\n", run_deleted);
  ASSERT_EQ(deleted.blocks.size(), 1u);
  expect_vec(deleted.blocks[0].end_mm, {1, 0, 0});

  // rs274 numbers have no exponent: a letter after digits starts the next word.
  EXPECT_NO_THROW(read("m66e0l0\n"));
  EXPECT_NO_THROW(read("G0X1Y2Z3\nm5m9\n"));

  // An M code the reader does not know: a warning (once per code) naming file:line; the
  // motion goes on. An error when asked, never for M98/M99 (they change the path), and no
  // warning for the machine's declared codes.
  const Program m = read("G0 X0 Y0 Z0\nM31\nG0 X1 M31\nM101\n");
  EXPECT_EQ(m.blocks.size(), 1u);
  ASSERT_EQ(m.warnings.size(), 2u);
  EXPECT_EQ(m.warnings[0].rfind("test.ngc:2:1: M code M31 is not one the machine file declares", 0), 0u);
  EXPECT_EQ(m.warnings[1].rfind("test.ngc:4:1: M code M101", 0), 0u);
  GcodeOptions strict;
  strict.unknown_m_code_as_error = true;
  EXPECT_INPUT_ERROR_WITH("G0 X0\n  M123\n", 2, 3, "unknown M code M123", strict);
  EXPECT_INPUT_ERROR("G0 X0\nM98 P100\n", 2, 1, "M98");
  GcodeOptions declared;
  declared.m_codes_ignored = {31};
  EXPECT_TRUE(read("G0 X0 Y0 Z0\nM31\n", declared).warnings.empty());
}

TEST(GcodeReader, NurbsG52G53) {
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d::Zero();
  // A rational quadratic with the middle weight cos 45 deg is a circular arc: (10, 0), (10, 10)
  // w 0.7071, (0, 10) is the quarter circle of radius 10 about the origin. Every vertex lies on
  // it and every chord within 1 um of it (its sagitta R - distance of the chord's middle).
  const Program p =
      read("G21 G90 G17 F100\nG0 X10 Y0 Z2\nG5.2 X10 Y10 P0.70710678118654752 L3\nX0 Y10 P1\nG5.3\nG1 X-5\n", options);
  ASSERT_GT(p.blocks.size(), 50u);  // chords of 1 um sagitta on R 10: at most 0.283 mm long
  double worst_vertex = 0.0, worst_sagitta = 0.0;
  for (size_t k = 1; k + 1 < p.blocks.size(); ++k) {
    const Block& b = p.blocks[k];
    EXPECT_EQ(b.source.line, 5);
    EXPECT_EQ(b.end_mm.z(), 2.0);
    worst_vertex = std::max(worst_vertex, std::abs(b.end_mm.head<2>().norm() - 10.0));
    worst_sagitta = std::max(worst_sagitta, 10.0 - (0.5 * (b.start_mm + b.end_mm)).head<2>().norm());
  }
  EXPECT_LT(worst_vertex, 1e-9);
  EXPECT_LE(worst_sagitta, 0.001 + 1e-12);
  expect_vec(p.blocks[p.blocks.size() - 2].end_mm, {0, 10, 2});
  expect_vec(p.blocks.back().end_mm, {-5, 10, 2});  // G1 after G5.3
  // Uniform quadratic B-spline (all weights 1), knots 0 0 0 1 2 2 2: at the inner knot the
  // curve passes through the middle of the second and third control points.
  const Program q = read("G21 G90 F100\nG0 X0 Y0\nG5.2 X10 Y0 L3\nX10 Y10 P1\nX20 Y10 P1\nG5.3\n", options);
  bool through = false;
  for (const Block& b : q.blocks) through = through || (b.end_mm - Eigen::Vector3d(10, 5, 0)).norm() < 1e-12;
  EXPECT_TRUE(through);
  expect_vec(q.blocks.back().end_mm, {20, 10, 0});
  // What LinuxCNC's rs274 refuses, refused.
  EXPECT_NE(std::string(error_of("G0 X0 Y0\nF10\nG5.2 X1 Y1 L4\nX2 Y0 P1\nG5.3\n", options).what())
                .find("test.ngc:5:1: G5.3: a NURBS of order 4 needs at least 4 control points"),
            std::string::npos);
  EXPECT_NE(std::string(error_of("G0 X0 Y0\nF10\nG5.2 X1 Y1\nX2 Y0\n", options).what())
                .find("test.ngc:4:1: a NURBS control point without P"),
            std::string::npos);
  EXPECT_NE(std::string(error_of("G0 X0 Y0\nF10\nG5.2 X1 Y1\nG1 X2\n", options).what())
                .find("test.ngc:4:1: G1 inside a G5.2 NURBS block"),
            std::string::npos);
}

TEST(GcodeReader, CoordinateSystemRotationG10L2R) {
  // LinuxCNC: workpiece = Rz(R) (programmed + G92) + G5x (emccanon's rotate_and_offset_pos).
  // G54 at (10, 5) turned 30 deg; each point by hand: (x cos 30 - y sin 30 + 10, x sin 30 +
  // y cos 30 + 5).
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d::Zero();
  const Program p = read(
      "G21 G90\nG10 L2 P1 X10 Y5 R30\nG54\nG0 X10 Y0 Z1\nG1 X20 Y10 F100\nG2 X30 Y0 I10 J0\nG91 G1 X5\nG90\n"
      "G10 L2 P1 R0\nG0 X0 Y0\n",
      options);
  const double c = std::cos(kPi / 6), s = std::sin(kPi / 6);
  auto turned = [&](double x, double y) { return Eigen::Vector3d(x * c - y * s + 10, x * s + y * c + 5, 1); };
  ASSERT_EQ(p.blocks.size(), 5u);
  expect_vec(p.blocks[0].end_mm, turned(10, 0));
  expect_vec(p.blocks[1].end_mm, turned(20, 10));
  expect_vec(p.blocks[2].end_mm, turned(30, 0));
  expect_vec(p.blocks[2].center_mm, turned(30, 10));  // I J along the turned axes
  expect_vec(p.blocks[3].end_mm, turned(35, 0));      // G91 X5 along the turned X
  expect_vec(p.blocks[4].end_mm, {10, 5, 1});         // R0: unturned again
  // #5420.. read the programmed (turned) coordinates.
  const Program q = read("G21 G90\nG10 L2 P1 R90\nG0 X3 Y4\nG0 X[#5420 + 1]\n", options);
  expect_vec(q.blocks.back().end_mm, {-4, 4, 0});
  // G92 and G10 L20 in a turned system count in its axes (LinuxCNC's rs274 prints SET_G92_OFFSET
  // X10 for G92 X0 at X10 Y5 under G10 L2 P1 X3 Y4 R30, and SET_G5X_OFFSET X11.6603 Y9 for
  // G10 L20 P1 X0 there): G92: w = Rz(30)(p + (10, 0)) + (3, 4); L20: the G5x offset becomes
  // w_now - Rz(30)(0, 5), and p = (1, 1) lands at Rz(30)(1, 1) + that.
  auto rz = [&](double x, double y) { return Eigen::Vector2d(x * c - y * s, x * s + y * c); };
  const Program g92 = read("G10 L2 P1 X3 Y4 R30\nG0 X10 Y5 Z1\nG92 X0\nG0 X1 Y1\n", options);
  const Eigen::Vector2d g92_end = rz(11, 1) + Eigen::Vector2d(3, 4);
  expect_vec(g92.blocks.back().end_mm, {g92_end.x(), g92_end.y(), 1});
  const Program l20 = read("G10 L2 P1 X3 Y4 R30\nG0 X10 Y5 Z1\nG10 L20 P1 X0\nG0 X1 Y1\n", options);
  const Eigen::Vector2d offset = rz(10, 5) + Eigen::Vector2d(3, 4) - rz(0, 5);
  EXPECT_NEAR(offset.x(), 11.6603, 1e-4);  // as rs274 prints it
  EXPECT_NEAR(offset.y(), 9.0, 1e-4);
  const Eigen::Vector2d l20_end = rz(1, 1) + offset;
  expect_vec(l20.blocks.back().end_mm, {l20_end.x(), l20_end.y(), 1});
  EXPECT_NE(std::string(error_of("G10 L20 P1 X0 R30\n", options).what()).find("test.ngc:1:15: G10 L20 with R"),
            std::string::npos);
  EXPECT_NE(std::string(error_of("G10 L2 P1 R30\nG18\nG0 X0 Y0 Z0\nG2 X10 Z0 K5 F10\n", options).what())
                .find("test.ngc:4:1: G2 outside G17 with the XY rotation on"),
            std::string::npos);
}

TEST(GcodeReader, UnsupportedWordsAsWarnings) {
  GcodeOptions options;
  options.unsupported_as_warning = true;
  const Program p = read(
      "G0 X0 Y0 Z0\nG96\nG96\nM123\nG1 X1 G7 F10\nG71 X9 F10\n"
      "G0 X2\n",
      options);
  // One warning per distinct word (G96, M123, G7, G71), each naming its first place.
  ASSERT_EQ(p.warnings.size(), 4u);
  EXPECT_EQ(p.warnings[0].rfind("test.ngc:2:1: ", 0), 0u) << p.warnings[0];
  EXPECT_NE(p.warnings[0].find("G96"), std::string::npos);
  EXPECT_EQ(p.warnings[1].rfind("test.ngc:4:1: ", 0), 0u) << p.warnings[1];
  EXPECT_EQ(p.warnings[2].rfind("test.ngc:5:7: ", 0), 0u) << p.warnings[2];
  EXPECT_EQ(p.warnings[3].rfind("test.ngc:6:1: ", 0), 0u) << p.warnings[3];
  // Mach3 writes G71 for mm (a real file: G71G91.1): the message says what to write instead.
  EXPECT_NE(p.warnings[3].find("G71 (lathe cycle); if it means mm units, as on Mach3, write G21"), std::string::npos)
      << p.warnings[3];
  // The ignored lathe cycle leaves X unknown: the G0 X2 after it only re-establishes X.
  ASSERT_EQ(p.blocks.size(), 1u);
  expect_vec(p.blocks[0].end_mm, {1, 0, 0});
  // A lathe cycle (ignored) leaves its axes unknown: the next Z only re-establishes Z.
  const Program q = read("G0 X0 Y0 Z0\nG71 Z-5 F10\nG0 Z5\n", options);
  EXPECT_TRUE(q.blocks.empty());
}

// ---------------------------------------------------------------- errors: line and column

TEST(GcodeReaderErrors, UnknownGAndMCodes) {
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG1 X1 F10 G5\n", 2, 11, "G5");
  EXPECT_INPUT_ERROR("G12.7\n", 1, 1, "unknown G code G12.7");
  EXPECT_INPUT_ERROR("G84 X0 Y0 Z-1 R1\n", 1, 1, "G84");
  EXPECT_INPUT_ERROR("G0 G28 Z0\n", 1, 4, "G28");
  EXPECT_INPUT_ERROR("G41 D1\n", 1, 5, "tool 1 has no radius");
}

TEST(GcodeReaderErrors, UnknownLettersAndCharacters) {
  EXPECT_INPUT_ERROR("G0 E5\n", 1, 4, "'E'");
  EXPECT_INPUT_ERROR("G0 X1 $\n", 1, 7, "'$'");
  EXPECT_INPUT_ERROR("G0 X1 @2\n", 1, 4, "X word with polar");
  // Polar words name X and Y without their words: the range check holds there too (found by
  // the fuzzer: sqrt(2) 999999 mm from the origin at angle 0 went through).
  EXPECT_INPUT_ERROR("G0 X999999 Y999999\nG0 ^0\n", 2, 4, "X position 1414212.148 mm from polar @/^ is out of range");
  EXPECT_INPUT_ERROR("#1 + 5\n", 1, 4, "expected '='");
  EXPECT_INPUT_ERROR("G0 [1+2]\n", 1, 4, "expected a letter before '['");
  EXPECT_INPUT_ERROR("G0 X0 O100\n", 1, 7, "o-word");
  GcodeOptions no_uvw;  // a job's machine: U V W words are errors at the word
  no_uvw.extra_axes.clear();
  try {
    read("G0 X0 U10\n", no_uvw);
    ADD_FAILURE() << "U10 read on a machine without U";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_EQ(e.column(), 7);
    EXPECT_NE(std::string(e.what()).find("no U axis"), std::string::npos) << e.what();
  }
  EXPECT_INPUT_ERROR("G0 A10000000\n", 1, 4, "out of range");
  EXPECT_INPUT_ERROR("G0 X1.2.3\n", 1, 8, "'.'");
}

TEST(GcodeReaderErrors, ArcEndNotOnCircle) {
  // r_start = 10, r_end = 10.1: 0.1 mm > 0.0283 mm and > 0.1 % of r. Reported at the G2 word,
  // or at the first axis word when the arc is modal (r_end = 10.198 there).
  EXPECT_INPUT_ERROR("G0 X10 Y0 Z0\nG2 X0 Y-10.1 I-10 F100\n", 2, 1, "not on its circle");
  EXPECT_INPUT_ERROR("G0 X10 Y0 Z0\nG2 X0 Y-10 I-10 F100\n  X10 Y2 J10\n", 3, 3, "not on its circle");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG2 X0 Y0 I0 J0 F10\n", 2, 1, "zero-radius");
}

TEST(GcodeReaderErrors, RadiusTooSmall) {
  // Half the chord is 5 mm > 4.9: impossible. |R| short by 1e-10 is rounding: accepted.
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG2 X10 R4.9 F100\n", 2, 8, "less than half the chord");
  EXPECT_NO_THROW(read("G0 X0 Y0 Z0\nG2 X10 R4.9999999999 F100\n"));
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG2 X0 R5 F10\n", 2, 7, "ends where it starts");
}

TEST(GcodeReaderErrors, FeedMoveWithoutF) {
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG1 X1\n", 2, 1, "feed move without F");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG1\n Y1\n", 3, 2, "feed move without F");
  EXPECT_INPUT_ERROR("G0 X10 Y0 Z0\nG2 X0 Y-10 I-10\n", 2, 1, "feed move without F");
}

TEST(GcodeReaderErrors, BadNumbers) {
  EXPECT_INPUT_ERROR("G0 Xnan\n", 1, 4, "expected a number after 'X'");
  EXPECT_INPUT_ERROR("G0 X inf\n", 1, 4, "expected a number after 'X'");
  // rs274 numbers have no exponent: "X1e5" is X1 and an E word with no M66..M68 to use it.
  EXPECT_INPUT_ERROR("G0 X1e400\n", 1, 6, "word letter 'E'");
  EXPECT_INPUT_ERROR("G0 X1e5\n", 1, 6, "word letter 'E'");
  EXPECT_INPUT_ERROR("G0 X1000001\n", 1, 4, "out of range");
  EXPECT_INPUT_ERROR("G0 X" + std::string(400, '9') + "\n", 1, 4, "out of range");
  // 40000 in = 1016000 mm, beyond 1e6 mm after conversion.
  EXPECT_INPUT_ERROR("G20 G0 X40000\n", 1, 8, "out of range");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG91\nG0 X600000\n X600000\n", 4, 2, "out of range");
  EXPECT_INPUT_ERROR("G1 X1 F2000000000\n", 1, 7, "out of range");
  EXPECT_INPUT_ERROR("S1000001 M3\n", 1, 1, "out of range");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG3 I-1 P0.5 F10\n", 2, 8, "turns");
  EXPECT_INPUT_ERROR("T1.5 M6\n", 1, 1, "tool number");
  EXPECT_INPUT_ERROR("S-1\n", 1, 1, "spindle speed");
}

TEST(GcodeReaderErrors, CommentsAndMissingNumbers) {
  EXPECT_INPUT_ERROR("G0 X1 (oops\n", 1, 7, "unterminated comment");
  EXPECT_NO_THROW(read("G0 X1 (a (b))\n"));                     // comments nest (CAM posts write them)
  EXPECT_INPUT_ERROR("G0 X1 (a))\n", 1, 10, "unexpected ')'");  // one ')' too many
  EXPECT_INPUT_ERROR("G0 X\n", 1, 4, "expected a number after 'X', found end of line");
  EXPECT_INPUT_ERROR("G0 X Y1\n", 1, 4, "found 'Y'");
  EXPECT_INPUT_ERROR("G\n", 1, 1, "expected a number after 'G'");
  EXPECT_INPUT_ERROR("G1 X-\n", 1, 4, "expected a number after 'X'");
}

TEST(GcodeReaderErrors, SameModalGroupTwiceAndRepeatedWords) {
  EXPECT_INPUT_ERROR("G0 G1 X1\n", 1, 4, "motion (group 1)");
  EXPECT_INPUT_ERROR("G90 G91\n", 1, 5, "distance mode");
  EXPECT_INPUT_ERROR("G20 G21\n", 1, 5, "units");
  EXPECT_INPUT_ERROR("M3 M4\n", 1, 4, "M3 and M4");
  EXPECT_INPUT_ERROR("G0 X1 X2\n", 1, 7, "second X word");
  EXPECT_INPUT_ERROR("G0 N10 X1\n", 1, 4, "N word");
}

TEST(GcodeReaderErrors, ArcWithoutCentreOrWithBadWords) {
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG2 X1 Y1 F100\n", 2, 1, "without I/J/K or R");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG2 X1 Y1 K1 F10\n", 2, 10, "K word in a XY-plane arc");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG2 X2 I1 R1 F10\n", 2, 10, "both R and I/J/K");
  EXPECT_INPUT_ERROR("G90.1 G0 X10 Y0 Z0\nG3 X0 Y10 I0 F100\n", 2, 1, "J word missing");
  EXPECT_INPUT_ERROR("F10\nG2 X1 Y1 I1\n", 2, 1, "unknown X position");
}

TEST(GcodeReaderErrors, NonPositiveFeed) {
  EXPECT_INPUT_ERROR("F0\n", 1, 1, "expected a feed > 0");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG1 X1 F-5\n", 2, 7, "expected a feed > 0");
}

TEST(GcodeReaderErrors, WordsWithoutUsersAndModes) {
  EXPECT_INPUT_ERROR("X1\n", 1, 1, "no motion mode");
  EXPECT_INPUT_ERROR("G0 X0\nG80 X1\n", 2, 5, "no motion mode");
  EXPECT_INPUT_ERROR("G0 X1 R5\n", 1, 7, "R word with no G2/G3");
  EXPECT_INPUT_ERROR("G0 X0 Y0 Z0\nG1 X1 F10 P2\n", 2, 11, "P word");
  EXPECT_INPUT_ERROR("G4\n", 1, 1, "G4 dwell without P");
  EXPECT_INPUT_ERROR("G91 G0 X1\n", 1, 8, "position is unknown");
  EXPECT_INPUT_ERROR("G0 X1\n%\n", 2, 1, "did not open with '%'");
}

TEST(GcodeReaderErrors, MissingOrUnreadableFile) {
  const std::string missing = "/nonexistent/vcut/no_such_program.ngc";
  try {
    read_gcode(missing, {});
    ADD_FAILURE() << "no error for a missing file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), missing);
    EXPECT_EQ(e.line(), 0);
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
  try {
    read_gcode(VCUT_SOURCE_DIR, {});  // a directory
    ADD_FAILURE() << "no error for a directory";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), VCUT_SOURCE_DIR);
  }
}

TEST(GcodeReaderErrors, BadOptions) {
  GcodeOptions options;
  options.work_offsets_mm["G60"] = Eigen::Vector3d::Zero();
  try {
    read("G0 X0\n", options);
    ADD_FAILURE() << "no error for a bad offset name";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("G60"), std::string::npos);
  }
}

}  // namespace
}  // namespace vcut::io

namespace vcut::io {
namespace {

TEST(GcodeReaderRotary, AxisProgramWithAbsoluteAndIncrementalRotaryWords) {
  // A B C are degrees whatever G20/G21 says; G91 adds to the last value. Once a rotary word
  // appears the blocks are axis blocks: X Y Z are the linear axes, the words axis values.
  const Program p = read("G20 G0 X1 Y0 Z0\nG1 A30 C-45 F10\nG91 G1 X1 C90\nG90 G0 B5\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  const auto& turn = p.blocks[0];
  EXPECT_FALSE(turn.tool_pose);
  EXPECT_EQ(turn.start_mm, turn.end_mm);  // a pure rotation is still a block
  EXPECT_NEAR(turn.end_rotary.angle_rad[0], 30 * M_PI / 180, 1e-15);
  EXPECT_NEAR(turn.end_rotary.angle_rad[2], -45 * M_PI / 180, 1e-15);
  EXPECT_TRUE(turn.end_rotary.given[0] && turn.end_rotary.given[2] && !turn.end_rotary.given[1]);
  EXPECT_FALSE(turn.start_rotary.given[0]);
  const auto& inc = p.blocks[1];
  EXPECT_NEAR(inc.end_mm.x(), 2 * 25.4, 1e-12);
  EXPECT_NEAR(inc.start_rotary.angle_rad[2], -45 * M_PI / 180, 1e-15);
  EXPECT_NEAR(inc.end_rotary.angle_rad[2], 45 * M_PI / 180, 1e-15);
  EXPECT_NEAR(inc.end_rotary.angle_rad[0], 30 * M_PI / 180, 1e-15);  // A holds
  EXPECT_NEAR(p.blocks[2].end_rotary.angle_rad[1], 5 * M_PI / 180, 1e-15);
  EXPECT_EQ(p.blocks[2].kind, kinematics::MotionKind::Rapid);
}

TEST(GcodeReaderPathControl, ExactStopAndBlendingReachTheBlocks) {
  // G61 stops at every block end until G64; G9 stops at the end of its own line only; G64 P
  // is the blending tolerance (in program units: 0.002 in = 0.0508 mm).
  const Program p = read("G0 X0 Y0 Z0\nG61 G1 X1 F100\nX2\nG64 P0.05 X3\nG9 X4\nX5\nG20 G64 P0.002 X0.5\n");
  ASSERT_EQ(p.blocks.size(), 6u);
  EXPECT_TRUE(p.blocks[0].exact_stop);
  EXPECT_TRUE(p.blocks[1].exact_stop);
  EXPECT_FALSE(p.blocks[2].exact_stop);
  EXPECT_DOUBLE_EQ(p.blocks[2].blend_tolerance_mm, 0.05);
  EXPECT_TRUE(p.blocks[3].exact_stop);
  EXPECT_FALSE(p.blocks[4].exact_stop);
  EXPECT_DOUBLE_EQ(p.blocks[4].blend_tolerance_mm, 0.05);
  EXPECT_NEAR(p.blocks[5].blend_tolerance_mm, 0.0508, 1e-12);
  EXPECT_LT(read("G0 X0 Y0 Z0\nG64 G1 X1 F100\n").blocks[0].blend_tolerance_mm, 0.0);
}

TEST(GcodeReaderRotary, ThreeAxisProgramsStayToolPoses) {
  const Program p = read("G0 X1 Y2 Z3\nG1 X4 F100\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  EXPECT_TRUE(p.blocks[0].tool_pose);
  EXPECT_FALSE(p.blocks[0].end_rotary.any());
}

}  // namespace
}  // namespace vcut::io
