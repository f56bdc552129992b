// Tests of the SINUMERIK 840D reader. Expected values are worked by hand from the SINUMERIK
// 840D sl programming manuals' semantics (noted where used): CR= centres from the chord and the
// radius, I J K relative to the start, AC/IC per coordinate, R-parameter arithmetic in degrees,
// normalised A3 B3 C3 vectors as closed forms, 25.4 mm/in; none is copied from the reader.
#include <gtest/gtest.h>
#include <vcut/io/input_error.h>
#include <vcut/io/program_reader.h>
#include <vcut/io/sinumerik_reader.h>
#include <vcut/kinematics/densify.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::FeedMode;
using kinematics::MotionKind;
using kinematics::OrientationMode;
using kinematics::Program;
using kinematics::SpindleState;

// Hand values are exact decimals or closed forms in double: only the rounding of a few
// operations separates them from the reader's results.
constexpr double kTol = 1e-9;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

Program read(const std::string& text, const SinumerikOptions& options = {}) {
  Program program;
  SinumerikState state;
  std::istringstream in(text);
  read_sinumerik(in, "test.mpf", options, program, state);
  return program;
}

InputError error_of(const std::string& text, const SinumerikOptions& options = {}) {
  try {
    read(text, options);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return InputError("none");
}

// The error names test.mpf:line:column first and contains `fragment`.
#define EXPECT_MPF_ERROR(text, line_, column_, fragment)                                         \
  do {                                                                                           \
    const InputError e_ = error_of(text);                                                        \
    const std::string where_ =                                                                   \
        std::string("test.mpf:") + std::to_string(line_) + ":" + std::to_string(column_) + ": "; \
    EXPECT_EQ(std::string(e_.what()).rfind(where_, 0), 0u) << e_.what();                         \
    EXPECT_NE(std::string(e_.what()).find(fragment), std::string::npos) << e_.what();            \
  } while (false)

void expect_vec(const Eigen::Vector3d& got, const Eigen::Vector3d& want, double tol = kTol) {
  EXPECT_LE((got - want).norm(), tol) << "got (" << got.transpose() << "), want (" << want.transpose() << ")";
}

// Seed 000, Fig. 6: the letter-space-number blocks of the gantry program, without TRAORI: axis
// blocks (tool_pose false) with A and C as axis values in rad.
TEST(SinumerikReader, SeedFig6AxisBlocks) {
  const Program p = read(
      "%_N_FIG6_MPF\n"
      ";$PATH=/_N_MPF_DIR\n"
      "N6 G1 F1000 ; feed for the blocks below\n"
      "N7 X -1320 Y -1320 Z 1000 A 0 C 0\n"
      "N8 X -1100 Y -1100 Z 800 A 45.330289 C 0\n"
      "N9 X -700 Y -700 Z 500 A 60.562182 C -33.005382\n");
  // N7 starts from an unknown position and does not turn (A 0 C 0 from 0): it only sets the
  // position, as the first move of the G-code reader does.
  ASSERT_EQ(p.blocks.size(), 2u);
  const Block& b = p.blocks[0];
  EXPECT_FALSE(b.tool_pose);
  EXPECT_EQ(b.kind, MotionKind::Linear);
  EXPECT_EQ(b.orientation, OrientationMode::Axes);
  expect_vec(b.start_mm, {-1320, -1320, 1000});
  expect_vec(b.end_mm, {-1100, -1100, 800});
  EXPECT_TRUE(b.start_rotary.given[0] && !b.start_rotary.given[1] && b.start_rotary.given[2]);
  EXPECT_NEAR(b.start_rotary.angle_rad[0], 0.0, kTol);
  EXPECT_NEAR(b.end_rotary.angle_rad[0], 45.330289 * kDeg, kTol);
  EXPECT_NEAR(b.end_rotary.angle_rad[2], 0.0, kTol);
  EXPECT_DOUBLE_EQ(b.feed_mm_per_min, 1000.0);
  EXPECT_EQ(b.source.line, 5);
  EXPECT_EQ(p.where(b.source), "test.mpf:5");
  const Block& c = p.blocks[1];
  EXPECT_NEAR(c.start_rotary.angle_rad[0], 45.330289 * kDeg, kTol);
  EXPECT_NEAR(c.end_rotary.angle_rad[0], 60.562182 * kDeg, kTol);
  EXPECT_NEAR(c.end_rotary.angle_rad[2], -33.005382 * kDeg, kTol);
  // Siemens' reset values: G1 (no motion code needed), G60 exact stop.
  EXPECT_TRUE(c.exact_stop);
  EXPECT_LT(c.blend_tolerance_mm, 0.0);
}

// The same block under TRAORI: X Y Z are the tip, A C rotary positions -> a tool pose with
// end_rotary (the pose engine solves the tool axis through the machine).
TEST(SinumerikReader, TraoriDirectAxes) {
  const Program p = read(
      "N5 TRAORI\n"
      "N6 G1 F1000 X0 Y0 Z0\n"
      "N7 X -1320 Y -1320 Z 1000 A 0 C 0\n"
      "N8 X 10 A30 C=-45\n"
      "N9 Y 5\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  const Block& a = p.blocks[0];
  EXPECT_TRUE(a.tool_pose);
  EXPECT_TRUE(a.end_rotary.any());
  expect_vec(a.end_mm, {-1320, -1320, 1000});
  EXPECT_FALSE(a.start_rotary.any());  // not known before N7: the engine keeps the machine's
  const Block& b = p.blocks[1];
  EXPECT_TRUE(b.tool_pose);
  expect_vec(b.end_mm, {10, -1320, 1000});
  EXPECT_TRUE(b.end_rotary.given[0] && !b.end_rotary.given[1] && b.end_rotary.given[2]);
  EXPECT_NEAR(b.end_rotary.angle_rad[0], 30 * kDeg, kTol);
  EXPECT_NEAR(b.end_rotary.angle_rad[2], -45 * kDeg, kTol);
  EXPECT_NEAR(b.start_rotary.angle_rad[0], 0.0, kTol);
  // N9 moves the tip only: the rotary axes hold (start = end rotary words).
  const Block& c = p.blocks[2];
  EXPECT_TRUE(c.tool_pose);
  EXPECT_TRUE(c.end_rotary.any());
  EXPECT_EQ(c.start_rotary.angle_rad, c.end_rotary.angle_rad);
  EXPECT_NEAR(c.end_rotary.angle_rad[0], 30 * kDeg, kTol);
}

// ORIVECT: A3 B3 C3 normalised, (3,0,4)/5 = (0.6,0,0.8); components not programmed are 0
// (Siemens: "vector components that have not been programmed are set to zero").
TEST(SinumerikReader, OrivectBlocks) {
  const Program p = read(
      "TRAORI\nORIWKS\nORIVECT\n"
      "G0 X0 Y0 Z0\n"
      "G1 F500 X10 A3=3 B3=0 C3=4\n"
      "X20 A3 = 2\n"
      "ORIPLANE\n"
      "X30 A3=0 B3=-1 C3=1\n"
      "ORIAXES\n"
      "X40 A3=0 B3=0 C3=1\n");
  ASSERT_EQ(p.blocks.size(), 4u);
  const Block& a = p.blocks[0];
  EXPECT_TRUE(a.tool_pose);
  EXPECT_FALSE(a.end_rotary.any());
  EXPECT_EQ(a.orientation, OrientationMode::Vector);
  expect_vec(a.start_axis, {0, 0, 1});  // the reader's start: the spindle axis (+Z)
  expect_vec(a.end_axis, {0.6, 0, 0.8});
  expect_vec(p.blocks[1].start_axis, {0.6, 0, 0.8});
  expect_vec(p.blocks[1].end_axis, {1, 0, 0});
  EXPECT_EQ(p.blocks[2].orientation, OrientationMode::Vector);  // ORIPLANE = ORIVECT
  const double h = std::sqrt(0.5);
  expect_vec(p.blocks[2].end_axis, {0, -h, h});
  EXPECT_EQ(p.blocks[3].orientation, OrientationMode::Axes);
  expect_vec(p.blocks[3].end_axis, {0, 0, 1});
  // A block repeating the vector does not reorient.
  const Program q = read("TRAORI\nG1 F1 X0 Y0 Z0 A3=0 B3=0 C3=1\nX1 A3=0 B3=0 C3=2\n");
  ASSERT_EQ(q.blocks.size(), 1u);
  expect_vec(q.blocks[0].start_axis, q.blocks[0].end_axis);
}

// ORICONCW: the axis turns on the cone about A6 B6 C6 (normalised); start (1,0,1)/sqrt2 and end
// (0,1,1)/sqrt2 both make 45 deg with (0,0,1). Siemens' clockwise is seen looking along the
// direction vector: a positive right-hand turn about it (vcut's ConeCounterClockwise).
TEST(SinumerikReader, OriconCone) {
  const Program p = read(
      "TRAORI\n"
      "G0 X0 Y0 Z0\n"
      "G1 F100 A3=1 B3=0 C3=1\n"
      "ORICONCW\n"
      "X10 A3=0 B3=1 C3=1 A6=0 B6=0 C6=2\n"
      "ORICONCCW\n"
      "X20 A3=-1 B3=0 C3=1\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  const double h = std::sqrt(0.5);
  const Block& b = p.blocks[1];
  EXPECT_EQ(b.orientation, OrientationMode::ConeCounterClockwise);
  expect_vec(b.cone_axis, {0, 0, 1});
  expect_vec(b.start_axis, {h, 0, h});
  expect_vec(b.end_axis, {0, h, h});
  EXPECT_EQ(p.blocks[2].orientation, OrientationMode::ConeClockwise);
  expect_vec(p.blocks[2].cone_axis, {0, 0, 1});  // A6 B6 C6 are kept
  // The end off the start's cone: 0 deg vs 45 deg from the axis.
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONCW\nG1 F1 X1 A3=0 C3=1 A6=0 B6=0 C6=1\n", 4, 10,
                   "expected both on one cone");
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0\nORICONCCW\nG1 F1 X1 A3=1 C3=1\n", 4, 10, "without a cone axis");
}

// The tool vector of a cone block at fraction s, by the pose engine (densify's block_pose).
Eigen::Vector3d axis_at(const Block& b, double s) { return kinematics::block_pose(b, s).axis; }

std::string vec3(const char* letters, const Eigen::Vector3d& v) {
  char buf[160];
  std::snprintf(buf, sizeof buf, " %c%c=%.17g %c%c=%.17g %c%c=%.17g", letters[0], letters[3], v.x(), letters[1],
                letters[3], v.y(), letters[2], letters[3], v.z());
  return buf;
}

// ORICONIO: the circle through start, intermediate and end. Hand case: start (s,0,c),
// intermediate (0,s,c), end (-s,0,c) with s = sin 15, c = cos 15 lie on the 15 deg cone about +Z
// and are met in that order turning counterclockwise about +Z: cone_axis +Z, counterclockwise,
// 180 deg; half way the pose engine is at the intermediate (90 deg). Back from (-s,0,c) through
// the same (0,s,c) to (s,0,c) is clockwise about +Z: the plane normal (m - a) x (c - a) =
// (s,s,0) x (2s,0,0) = (0, 0, -2 s^2), so counterclockwise about -Z.
TEST(SinumerikReader, OriconIntermediate) {
  const double s = std::sin(15 * kDeg), c = std::cos(15 * kDeg);
  const Program p = read(
      "TRAORI\n"
      "G0 X0 Y0 Z0 A3=SIN(15) B3=0 C3=COS(15)\n"
      "ORICONIO\n"
      "G1 F100 X10 A7=0 B7=SIN(15) C7=COS(15) A3=-SIN(15) B3=0 C3=COS(15)\n"
      "X20 A7=0 B7=SIN(15) C7=COS(15) A3=SIN(15) B3=0 C3=COS(15)\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  const Block& b = p.blocks[1];
  EXPECT_EQ(b.orientation, OrientationMode::ConeCounterClockwise);
  expect_vec(b.cone_axis, {0, 0, 1});
  expect_vec(b.start_axis, {s, 0, c});
  expect_vec(b.end_axis, {-s, 0, c});
  expect_vec(axis_at(b, 0.5), {0, s, c});
  expect_vec(axis_at(b, 1.0), {-s, 0, c});
  const Block& back = p.blocks[2];
  EXPECT_EQ(back.orientation, OrientationMode::ConeCounterClockwise);
  expect_vec(back.cone_axis, {0, 0, -1});
  expect_vec(axis_at(back, 0.5), {0, s, c});
  expect_vec(axis_at(back, 1.0), {s, 0, c});
  // ORICONIO is modal; the same end again with no A7 B7 C7 is no turn.
  EXPECT_EQ(read("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONIO\nX1 A3=1 C3=1\n").blocks.size(), 2u);

  // Errors, each naming line:column of the word at fault.
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONIO\nG1 F1 X1 A7=1 C7=1 A3=0 B3=1 C3=1\n", 4, 10,
                   "the intermediate and the start are 0 apart");
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONIO\nG1 F1 X1 A7=0 B7=1 C7=1 A3=0 B3=1 C3=1\n", 4, 10,
                   "the intermediate and the end");
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONIO\nG1 F1 X1 A7=0 B7=1 C7=1 A3=1 C3=1\n", 4, 10,
                   "the end and the start");
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONIO\nG1 F1 X1 A3=0 B3=1 C3=1\n", 4, 10,
                   "ORICONIO end vector without the intermediate orientation A7 B7 C7");
  EXPECT_MPF_ERROR("TRAORI\nG1 F1 X0 A7=1\n", 2, 10, "A7 B7 C7 outside ORICONIO");
  EXPECT_MPF_ERROR("TRAORI\nORICONIO\nG1 F1 X0 B7=1\n", 3, 10, "without the end vector A3 B3 C3");
  EXPECT_MPF_ERROR("TRAORI\nORICONIO\nG1 F1 X0 C6=1 A3=1\n", 3, 10, "cone axis A6 B6 C6 under ORICONIO");
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONIO\nG1 F1 X1 A7=0 A3=0 B3=1 C3=1\n", 4, 10,
                   "intermediate orientation A7 B7 C7 (0, 0, 0)");
}

// ORICONTO after ORIVECT: the great circle (0,0,1) -> a = (s,0,c) (s = sin 15, c = cos 15) in the
// XZ plane ends moving along t = (c, 0, -s). The circle through a with tangent t through
// e = (0,1,0): n = t x (e - a) = (c,0,-s) x (-s,1,-c) = (s, 1, c), |n| = sqrt 2; a.n = e.n = 1, so
// both lie on the 45 deg cone about (s,1,c)/sqrt2, and n x a = (c,0,-s) = +t: counterclockwise.
// Continuing the same great circle to (sin 30, 0, cos 30) gives the great circle's own axis +Y.
// After a cone block the tangent is k x end (counterclockwise) or -(k x end) (clockwise): ORICONTO
// then stays on that cone.
TEST(SinumerikReader, OriconTangent) {
  const double s = std::sin(15 * kDeg), c = std::cos(15 * kDeg), r = std::sqrt(0.5);
  const Program p = read(
      "TRAORI\n"
      "G0 X0 Y0 Z0 A3=0 B3=0 C3=1\n"
      "G1 F100 X10 A3=SIN(15) B3=0 C3=COS(15)\n"
      "ORICONTO\n"
      "X20 A3=0 B3=1 C3=0\n");
  ASSERT_EQ(p.blocks.size(), 2u);  // the G0 neither moves (start unknown) nor turns
  const Block& b = p.blocks[1];
  EXPECT_EQ(b.orientation, OrientationMode::ConeCounterClockwise);
  expect_vec(b.cone_axis, Eigen::Vector3d(s, 1, c) * r);
  expect_vec(axis_at(b, 1.0), {0, 1, 0});
  // Leaves a along +t: the engine's first small step (its chord leaves the tangent by about half
  // the step's angle, ~1e-7 rad).
  const Eigen::Vector3d step = axis_at(b, 1e-7) - axis_at(b, 0.0);
  expect_vec(step.normalized(), {c, 0, -s}, 1e-6);

  const Program q = read(
      "TRAORI\nG0 X0 Y0 Z0 A3=0 B3=0 C3=1\nG1 F100 X10 A3=SIN(15) B3=0 C3=COS(15)\n"
      "ORICONTO X20 A3=SIN(30) B3=0 C3=COS(30)\n");
  ASSERT_EQ(q.blocks.size(), 2u);
  expect_vec(q.blocks[1].cone_axis, {0, 1, 0});
  expect_vec(axis_at(q.blocks[1], 1.0), {std::sin(30 * kDeg), 0, std::cos(30 * kDeg)});

  // ORICONCW (a positive turn) about +Z to (0,s,c) ends moving along k x (0,s,c) = (-s,0,0);
  // ORICONTO to (-s,0,c) goes on counterclockwise about +Z. ORICONCCW (a negative turn) about +Z
  // to (0,s,c) (270 deg) ends moving along +X; ORICONTO to (0,-s,c) goes on clockwise about +Z,
  // i.e. counterclockwise about -Z.
  const Program cone = read(
      "TRAORI\nG0 X0 Y0 Z0 A3=SIN(15) B3=0 C3=COS(15)\n"
      "ORICONCW G1 F100 X1 A3=0 B3=SIN(15) C3=COS(15) A6=0 B6=0 C6=1\n"
      "ORICONTO X2 A3=-SIN(15) B3=0 C3=COS(15)\n"
      "ORICONCCW X3 A3=SIN(15) B3=0 C3=COS(15) A6=0 B6=0 C6=1\n"
      "X4 A3=0 B3=SIN(15) C3=COS(15)\n"
      "ORICONTO X5 A3=0 B3=-SIN(15) C3=COS(15)\n");
  ASSERT_EQ(cone.blocks.size(), 6u);
  expect_vec(cone.blocks[2].cone_axis, {0, 0, 1});
  EXPECT_EQ(cone.blocks[2].orientation, OrientationMode::ConeCounterClockwise);
  expect_vec(axis_at(cone.blocks[2], 0.5), {-s * r, s * r, c});  // 135 deg about +Z
  expect_vec(cone.blocks[5].cone_axis, {0, 0, -1});
  EXPECT_EQ(cone.blocks[5].orientation, OrientationMode::ConeCounterClockwise);
  expect_vec(axis_at(cone.blocks[5], 0.5), {s, 0, c});  // from +Y through +X to -Y: 0 deg half way

  // No tangent: at the start, after a block that did not turn the tool, after rotary axes.
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0\nORICONTO\nG1 F1 X1 A3=1 C3=1\n", 4, 10, "ORICONTO without a tangent");
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nG1 F1 X5\nORICONTO\nX6 A3=0 B3=1 C3=1\n", 5, 4,
                   "ORICONTO without a tangent");
  EXPECT_MPF_ERROR("TRAORI\nORIAXES\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONTO\nX6 A3=0 B3=1 C3=1\n", 5, 4,
                   "ORICONTO without a tangent");
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONTO C6=1\n", 3, 10, "cone axis A6 B6 C6 under ORICONTO");
}

// Randomized (fixed seed): ORICONIO's densified vectors stay on one cone, pass the intermediate
// orientation before the end and end at the end; ORICONTO's start along the tangent of the great
// circle before and end at the end.
TEST(SinumerikReader, OriconRandomCircles) {
  constexpr double kPoseTol = 1e-9;  // Rodrigues rotations and normalisation in double
  std::mt19937 rng(20240611);
  std::normal_distribution<double> normal;
  auto unit = [&] { return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized(); };
  int cases = 0;
  while (cases < 200) {
    const Eigen::Vector3d a = unit(), m = unit(), e = unit(), u0 = unit();
    if ((a - m).norm() < 0.1 || (m - e).norm() < 0.1 || (a - e).norm() < 0.1 || (u0 - a).norm() < 0.1 ||
        (u0 + a).norm() < 0.1) {
      continue;
    }
    ++cases;
    const Program p = read("TRAORI\nG0 X0 Y0 Z0" + vec3("ABC3", a) + "\nORICONIO G1 F100 X1" + vec3("ABC7", m) +
                           vec3("ABC3", e) + "\n");
    ASSERT_EQ(p.blocks.size(), 2u);
    const Block& b = p.blocks[1];
    const Eigen::Vector3d k = b.cone_axis;
    // The turn (counterclockwise about k) from a to a vector on the cone, in [0, 2 pi).
    auto turn = [&](const Eigen::Vector3d& v) {
      const Eigen::Vector3d x = a - a.dot(k) * k, y = v - v.dot(k) * k;
      const double t = std::atan2(k.dot(x.cross(y)), x.dot(y));
      return t < 0 ? t + 2 * M_PI : t;
    };
    EXPECT_NEAR(m.dot(k), a.dot(k), kPoseTol);
    EXPECT_NEAR(e.dot(k), a.dot(k), kPoseTol);
    const double sm = turn(m) / turn(e);
    EXPECT_GT(sm, 0.0);
    EXPECT_LT(sm, 1.0);
    expect_vec(axis_at(b, sm), m, kPoseTol);
    expect_vec(axis_at(b, 1.0), e, kPoseTol);
    for (int i = 0; i <= 8; ++i) EXPECT_NEAR(axis_at(b, i / 8.0).dot(k), a.dot(k), kPoseTol);

    const Program q = read("TRAORI\nG0 X0 Y0 Z0" + vec3("ABC3", u0) + "\nG1 F100 X1" + vec3("ABC3", a) +
                           "\nORICONTO X2" + vec3("ABC3", e) + "\n");
    ASSERT_EQ(q.blocks.size(), 3u);
    const Block& t = q.blocks[2];
    // Great circle u0 -> a: at a it moves along the part of a - u0 perpendicular to a.
    const Eigen::Vector3d tangent = ((a - u0) - (a - u0).dot(a) * a).normalized();
    EXPECT_GT((axis_at(t, 1e-7) - axis_at(t, 0.0)).normalized().dot(tangent), 1.0 - 1e-6);
    EXPECT_NEAR(t.cone_axis.dot(tangent), 0.0, kPoseTol);
    expect_vec(axis_at(t, 1.0), e, kPoseTol);
    for (int i = 0; i <= 8; ++i) EXPECT_NEAR(axis_at(t, i / 8.0).dot(t.cone_axis), a.dot(t.cone_axis), kPoseTol);
  }
}

// A6 B6 C6 without an end vector under ORICONCW/CCW: a full turn on the cone (the manual's
// example, "goes through a full revolution on the outside of the same taper"). Start (h,0,h),
// h = sqrt(1/2), ORICONCCW: a negative turn about +Z, a quarter of the way at (0,-h,h), half
// way at (-h,0,h).
// The manual's own example: ORICONCW about (0,0,1) from (0,1,1)/sqrt2 to (1,0,1)/sqrt2 turns
// 270 deg: a third of the way (90 deg on) the tool axis is at (-1,0,1)/sqrt2.
TEST(SinumerikReader, OriconcwIsAPositiveTurnAsInTheManual) {
  const double h = std::sqrt(0.5);
  const Program p = read("TRAORI\nG0 X0 Y0 Z0 A3=0 B3=1 C3=1\nORICONCW\nG1 F1 X1 A3=1 B3=0 C3=1 A6=0 B6=0 C6=1\n");
  ASSERT_EQ(p.blocks.size(), 2u);  // the G0 turns the tool from +Z to the start vector
  expect_vec(axis_at(p.blocks[1], 1.0 / 3.0), {-h, 0, h});
  expect_vec(axis_at(p.blocks[1], 2.0 / 3.0), {0, -h, h});
}

TEST(SinumerikReader, OriconFullTurn) {
  const double h = std::sqrt(0.5);
  const Program p = read("TRAORI\nG0 X0 Y0 Z0 A3=1 C3=1\nORICONCCW\nG1 F1 X1 A6=0 B6=0 C6=1\n");
  ASSERT_EQ(p.blocks.size(), 2u);
  const Block& b = p.blocks[1];
  EXPECT_EQ(b.orientation, OrientationMode::ConeClockwise);
  expect_vec(b.start_axis, {h, 0, h});
  expect_vec(b.end_axis, {h, 0, h});
  expect_vec(axis_at(b, 0.25), {0, -h, h});
  expect_vec(axis_at(b, 0.5), {-h, 0, h});
  expect_vec(axis_at(b, 1.0), {h, 0, h});
  EXPECT_MPF_ERROR("TRAORI\nG0 X0 Y0 Z0\nORICONCW\nG1 F1 X1 A6=0 B6=0 C6=1\n", 4, 10,
                   "with the tool vector along its axis");
  // Without TRAORI A6 B6 C6 only set the axis.
  EXPECT_EQ(read("G0 X0 Y0 Z0\nORICONCW A6=0 B6=0 C6=1\n").blocks.size(), 0u);
}

// CR= arcs: chord (0,0)->(10,0); |CR| = 5 is a half circle about (5,0); |CR| = 10 puts the centre
// sqrt(100 - 25) = 8.660254 off the chord's midpoint: G2 CR>0 and G3 CR<0 to the right of
// start->end (below), G2 CR<0 to the left (the long arc, more than 180 deg).
TEST(SinumerikReader, CrArcs) {
  const Program p = read(
      "G17 G0 X0 Y0 Z0\n"
      "G2 X10 Y0 CR=5 F200\n"
      "G0 X0\n"
      "G3 X10 CR=-10\n"
      "G0 X0\n"
      "G2 X10 CR=-10\n"
      "G0 X0\n"
      "G2 X10 CR=10\n");
  ASSERT_EQ(p.blocks.size(), 7u);
  const double d = std::sqrt(75.0);
  const Block& a = p.blocks[0];
  EXPECT_EQ(a.kind, MotionKind::Arc);
  expect_vec(a.center_mm, {5, 0, 0});
  expect_vec(a.normal, {0, 0, -1});  // G2 in G17: right-hand rule about -Z
  EXPECT_EQ(a.turns, 1);
  EXPECT_DOUBLE_EQ(a.feed_mm_per_min, 200.0);
  expect_vec(p.blocks[2].center_mm, {5, -d, 0}, 1e-12);
  expect_vec(p.blocks[2].normal, {0, 0, 1});
  expect_vec(p.blocks[4].center_mm, {5, d, 0}, 1e-12);
  expect_vec(p.blocks[6].center_mm, {5, -d, 0}, 1e-12);
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nG2 X10 CR=4 F1\n", 2, 8, "less than half the chord");
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nG2 X0 CR=4 F1\n", 2, 7, "ends where it starts");
  EXPECT_MPF_ERROR("G0 X0 Y0\nG2 X10 CR=5 I5 F1\n", 2, 8, "both CR= and I J K");
}

// I J K: relative to the start; I=AC(..) is the centre in the active frame (G54 offset added).
TEST(SinumerikReader, IjkArcsAndOffsets) {
  SinumerikOptions options;
  options.work_offsets_mm["G54"] = Eigen::Vector3d(100, 0, 0);
  options.work_offsets_mm["G55"] = Eigen::Vector3d(0, 50, 0);
  const Program p = read(
      "G54 G0 X10 Y0 Z0\n"
      "G3 X0 Y10 I-10 J0 F100\n"
      "G0 X10 Y0\n"
      "G3 X0 Y10 I=AC(0) J=AC(0)\n"
      "G18 G0 X10 Y0 Z0\n"
      "G2 X0 Z10 I-10\n"
      "G500 G0 X1\n"
      "G55 G0 Y1\n",
      options);
  ASSERT_EQ(p.blocks.size(), 7u);
  expect_vec(p.blocks[0].start_mm, {110, 0, 0});
  expect_vec(p.blocks[0].center_mm, {100, 0, 0});
  expect_vec(p.blocks[0].end_mm, {100, 10, 0});
  expect_vec(p.blocks[2].center_mm, {100, 0, 0});
  // G18: the ZX plane, G2 turns about -Y; K missing is 0 relative to the start.
  expect_vec(p.blocks[4].center_mm, {100, 0, 0});
  expect_vec(p.blocks[4].normal, {0, -1, 0});
  expect_vec(p.blocks[4].end_mm, {100, 0, 10});
  expect_vec(p.blocks[5].end_mm, {1, 0, 10});   // G500: no offset
  expect_vec(p.blocks[6].end_mm, {1, 51, 10});  // G55
  EXPECT_MPF_ERROR("G0 X10 Y0 Z0\nG3 X0 Y11 I-10 F1\n", 2, 1, "not on its circle");
  EXPECT_MPF_ERROR("G0 X10 Y0 Z0\nG3 X0 Y10 I-10 K1 F1\n", 2, 16, "K in a XY-plane arc");
  EXPECT_MPF_ERROR("G0 X0\nG3 X1 Y1 I1 F1\n", 2, 1, "unknown Y position");
}

// AC( and IC( on one coordinate override G90/G91 for that coordinate only.
TEST(SinumerikReader, AbsoluteAndIncremental) {
  const Program p = read(
      "G90 G0 X10 Y0 Z0\n"
      "G91 G1 X5 Y=AC(20) F100\n"
      "G90 X=IC(5) Z = 2\n"
      "G70 X1\n"
      "G700 X2 F10\n"
      "G710 X0\n");
  ASSERT_EQ(p.blocks.size(), 5u);
  expect_vec(p.blocks[0].end_mm, {15, 20, 0});
  expect_vec(p.blocks[1].end_mm, {20, 20, 2});
  // G70: lengths in inches, the feed stays in mm/min; G700: the feed in inches too.
  expect_vec(p.blocks[2].end_mm, {25.4, 20, 2});
  EXPECT_DOUBLE_EQ(p.blocks[2].feed_mm_per_min, 100.0);
  expect_vec(p.blocks[3].end_mm, {50.8, 20, 2});
  EXPECT_DOUBLE_EQ(p.blocks[3].feed_mm_per_min, 254.0);
  expect_vec(p.blocks[4].end_mm, {0, 20, 2});
  EXPECT_MPF_ERROR("G91 G0 X5\n", 1, 8, "incremental X from an unknown X position");
}

// R parameters: arithmetic in degrees. SIN(30) = 0.5; SQRT(16) + TRUNC(-2.7) + ROUND(2.5) +
// ABS(-3) = 4 - 2 + 3 + 3 = 8; ACOS(0.5) - ASIN(1) + TAN(45) * COS(60) = 60 - 90 + 0.5;
// (1+2)*3 - 1.5EX2 / -(50) = 9 + 3; POT(3) - ATAN2(1, 1) / 45 = 9 - 1.
TEST(SinumerikReader, RParameters) {
  const Program p = read(
      "G0 X0 Y0 Z0\n"
      "R1=10 R2=R1*2+SIN(30)\n"
      "R3=SQRT(16)+TRUNC(-2.7)+ROUND(2.5)+ABS(-3) R4 = ACOS(0.5)-ASIN(1)+TAN(45)*COS(60)\n"
      "R5=(1+2)*3-1.5EX2/-(50)\n"
      "X=R2 Y=R1+5 Z=POT(3)-ATAN2(1,1)/45\n"
      "X=R3 Y=R4 Z=R5\n"
      "R999=-R5 X=R999 ; assigned before it is used, left to right\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  expect_vec(p.blocks[0].end_mm, {20.5, 15, 8}, 1e-12);
  expect_vec(p.blocks[1].end_mm, {8, -29.5, 12}, 1e-12);
  expect_vec(p.blocks[2].end_mm, {-12, -29.5, 12}, 1e-12);
  EXPECT_MPF_ERROR("R1=1/0\n", 1, 5, "division by zero");
  EXPECT_MPF_ERROR("R1=1/(R2-R2)\n", 1, 5, "division by zero");
  EXPECT_MPF_ERROR("R1000=1\n", 1, 1, "R1000 (expected R0..R999)");
  EXPECT_MPF_ERROR("G0 X=R1000\n", 1, 6, "R1000 (expected R0..R999)");
  EXPECT_MPF_ERROR("G0 X=AC(10\n", 1, 11, "AC( without its closing ')'");
  EXPECT_MPF_ERROR("G0 X=SQRT(-1)\n", 1, 6, "SQRT of -1");
  EXPECT_MPF_ERROR("G0 X=ASIN(2)\n", 1, 6, "ASIN of 2");
  EXPECT_MPF_ERROR("G0 X=FOO(2)\n", 1, 6, "unknown function FOO(");
  EXPECT_MPF_ERROR("G0 X=Q\n", 1, 6, "unknown name Q");
  EXPECT_MPF_ERROR("G0 X=1+AC(2)\n", 1, 8, "AC( inside an expression");
  EXPECT_MPF_ERROR("R1=(1+2\n", 1, 8, "'(' without its closing ')'");
  EXPECT_MPF_ERROR("R1 5\n", 1, 1, "R parameter without '='");
  EXPECT_MPF_ERROR("R1=" + std::string(100, '(') + "1" + std::string(100, ')') + "\n", 1, 69,
                   "nested more than 64 deep");
}

TEST(SinumerikReader, NumbersAndRanges) {
  EXPECT_MPF_ERROR("G0 X1EX999\n", 1, 5, "out of range");
  EXPECT_MPF_ERROR("G0 X 2000000 Y0 Z0\n", 1, 4, "out of range (expected within +-1e6 mm)");
  EXPECT_MPF_ERROR("G0 X=1EX300*1EX300\n", 1, 12, "not a finite number");
  EXPECT_MPF_ERROR("G0 X Y1\n", 1, 6, "expected a number");
  EXPECT_MPF_ERROR("G0 X1EX\n", 1, 8, "EX without its exponent");
  EXPECT_MPF_ERROR("G0 X1 X2\n", 1, 7, "X programmed twice");
  EXPECT_MPF_ERROR("G0 G1 X1\n", 1, 4, "two motion codes");
  EXPECT_MPF_ERROR("G1.5 X1\n", 1, 1, "expected a whole G code");
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nG1 X1 F0\n", 2, 7, "feed F0");
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nG1 X1\n", 2, 1, "without a feed");
  EXPECT_MPF_ERROR("G0 X0 # 5\n", 1, 7, "unexpected '#'");
  EXPECT_MPF_ERROR("G0 X0\nG0 X1\x01\n", 2, 6, "control byte");
}

// Feed, spindle, tool, modes carried into the blocks.
TEST(SinumerikReader, TechnologyAndBlending) {
  const Program p = read(
      "n10 t1 m6 d1 ; lower case is read\n"
      "N20 S12000 M3\n"
      "N30 G0 X0 Y0 Z0\n"
      "N40 G64 ADIS=0.05 ADISPOS=0.5 G1 X1 F2000\n"
      "N50 G0 X2\n"
      "N60 G9 G1 X3\n"
      "N70 G60 X4\n"
      "N80 T=\"2\" M6 M5 G93 G1 X5 F2\n"
      "N90 G4 F3\n"
      "N100 G94 X6\n"
      "N110 M30\n"
      "N120 this is never read\n");
  ASSERT_EQ(p.blocks.size(), 6u);
  const Block& a = p.blocks[0];
  EXPECT_EQ(a.tool, 1);
  EXPECT_EQ(a.spindle, SpindleState::Clockwise);
  EXPECT_DOUBLE_EQ(a.spindle_rpm, 12000.0);
  EXPECT_FALSE(a.exact_stop);
  EXPECT_DOUBLE_EQ(a.blend_tolerance_mm, 0.05);
  EXPECT_DOUBLE_EQ(p.blocks[1].blend_tolerance_mm, 0.5);  // G0: ADISPOS
  EXPECT_EQ(p.blocks[1].kind, MotionKind::Rapid);
  EXPECT_DOUBLE_EQ(p.blocks[1].feed_mm_per_min, 0.0);
  EXPECT_TRUE(p.blocks[2].exact_stop);  // G9: this block only
  EXPECT_DOUBLE_EQ(p.blocks[2].feed_mm_per_min, 2000.0);
  EXPECT_TRUE(p.blocks[3].exact_stop);  // G60
  EXPECT_EQ(p.blocks[4].tool, 2);
  EXPECT_EQ(p.blocks[4].spindle, SpindleState::Off);
  EXPECT_EQ(p.blocks[4].feed_mode, FeedMode::InverseTime);
  EXPECT_DOUBLE_EQ(p.blocks[4].feed_mm_per_min, 2.0);
  // G4 F3 is a dwell of 3 s, not a feed; G94 takes the last mm/min feed again.
  EXPECT_EQ(p.blocks[5].feed_mode, FeedMode::UnitsPerMinute);
  EXPECT_DOUBLE_EQ(p.blocks[5].feed_mm_per_min, 2000.0);
  EXPECT_EQ(p.blocks[5].source.line, 10);
  EXPECT_MPF_ERROR("T=\"\" M6\n", 1, 1, "tool name T=\"\" (expected 1..64 characters)");
  EXPECT_MPF_ERROR("M6\n", 1, 1, "M6 without a tool selected");
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nG93 G1 X1\n", 2, 5, "G93 (inverse time) motion without F");
  EXPECT_MPF_ERROR("G4 F1 X2\n", 1, 1, "G4 (dwell) with axis words");
}

TEST(SinumerikReader, RefusedWords) {
  EXPECT_MPF_ERROR("TRAORI\nG1 F1 X0 NUT=30\n", 2, 10, "NUT= (the cone's opening angle) is not supported");
  EXPECT_MPF_ERROR("TRAORI\nORIMKS\nG1 F1 X0 Y0 Z0 A3=1 C3=1\n", 3, 16, "under ORIMKS");
  EXPECT_MPF_ERROR("G1 F1 X0 Y0 Z0 A3=1 C3=1\n", 1, 16, "without TRAORI");
  EXPECT_MPF_ERROR("TRAORI\nG1 F1 X0 Y0 Z0 A10\nX1 A3=1 C3=1\n", 3, 4,
                   "after the orientation was set by rotary axes A B C (line 2)");
  // A cone mode selected after rotary axes, with no end vector: the axes hold, and the block
  // carries no cone (found by the fuzzer: it had a cone mode with a zero cone axis).
  const Program held = read("TRAORI\nG1 F1 X0 Y0 Z0 A10\nORICONCCW X1\n");
  ASSERT_EQ(held.blocks.size(), 2u);
  EXPECT_EQ(held.blocks[1].orientation, OrientationMode::Vector);
  EXPECT_TRUE(held.blocks[1].start_rotary.angle_rad == held.blocks[1].end_rotary.angle_rad);
  EXPECT_DOUBLE_EQ(held.blocks[1].end_rotary.angle_rad[0], 10.0 * M_PI / 180.0);
  EXPECT_MPF_ERROR("TRAORI(2)\n", 1, 1, "expected TRAORI or TRAORI(1)");
  EXPECT_MPF_ERROR("N10 PCALL SUB\n", 1, 5, "PCALL (program flow");
  EXPECT_MPF_ERROR("N10 ROTS X10\n", 1, 5, "ROTS is not supported: it changes the frame");
  EXPECT_MPF_ERROR("N10 G110 X10\n", 1, 5, "G110 is not supported");
  EXPECT_MPF_ERROR("N10 G95 F0.1\n", 1, 5, "G95 is not supported");
  // A machine's own M code: a warning once (an error when the job asks), M202(0.0024) too.
  const Program m = read("N10 M123\nN20 M123 M202(0.0024)\n");
  ASSERT_EQ(m.warnings.size(), 2u);
  EXPECT_EQ(m.warnings[0].rfind("test.mpf:1:5: M123 is not an M code vcut knows", 0), 0u) << m.warnings[0];
  SinumerikOptions strict;
  strict.unknown_m_code_as_error = true;
  EXPECT_NE(std::string(error_of("N10 M123\n", strict).what()).find("test.mpf:1:5: M123 is not an M code"),
            std::string::npos);
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nN10 CYCLE800(1,\"TC\")\n", 2, 5,
                   "CYCLE800 _FR 1 retracts to the machine's home: it needs the machine");
  EXPECT_MPF_ERROR("N10 H1=5\n", 1, 5, "H1= is not supported");
  EXPECT_MPF_ERROR(
      "N10 POCKET4(1,2)\n", 1, 5,
      "POCKET4 is not supported (not a cycle vcut reads, and no subprogram: expected POCKET4.SPF or .MPF in");
  EXPECT_MPF_ERROR("N10 L100\n", 1, 5, "subprogram L100 not found");
  EXPECT_MPF_ERROR("N10 G1 X=$AA_IM[X]\n", 1, 10, "system variables");
  // Accepted and ignored: MSG, G40, G601, coolant.
  EXPECT_NO_THROW(read("N10 MSG(\"roughing; pass 1\") G40 G601 M8 M9 D1\n"));
}

// With unsupported_as_warning: one warning per distinct word, the rest of the block is read.
TEST(SinumerikReader, UnsupportedAsWarning) {
  SinumerikOptions options;
  options.unsupported_as_warning = true;
  const Program p = read(
      "N10 G0 X0 Y0 Z0 SOFT\n"
      "N20 CYCLE832(0.01,1) G1 X1 F10 SOFT\n"
      "N30 G95 H1=2 X2\n",
      options);
  ASSERT_EQ(p.blocks.size(), 2u);
  expect_vec(p.blocks[1].end_mm, {2, 0, 0});
  ASSERT_EQ(p.warnings.size(), 4u);
  EXPECT_EQ(p.warnings[0].rfind("test.mpf:1:17: SOFT is not supported", 0), 0u) << p.warnings[0];
  EXPECT_EQ(p.warnings[1].rfind("test.mpf:2:5: CYCLE832 (high-speed settings) read as a note", 0), 0u) << p.warnings[1];
  EXPECT_EQ(p.warnings[2].rfind("test.mpf:3:5: G95 is not supported", 0), 0u) << p.warnings[2];
  EXPECT_EQ(p.warnings[3].rfind("test.mpf:3:9: H1= is not supported", 0), 0u) << p.warnings[3];
  // The refused words stay errors.
  EXPECT_THROW(read("NUT=30\n", options), InputError);
}

// Unknown start: the first programmed value of an axis does not move it; moves before Z is
// programmed hold Z and take its first value (as the G-code reader does).
TEST(SinumerikReader, UnknownStart) {
  const Program p = read("G1 F100 X10 Y0\nX20\nZ3\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  expect_vec(p.blocks[0].start_mm, {10, 0, 3});
  expect_vec(p.blocks[0].end_mm, {20, 0, 3});
  ASSERT_EQ(p.warnings.size(), 1u);
  EXPECT_NE(p.warnings[0].find("test.mpf:3:1: 1 earlier move(s) (first at test.mpf:2) ran while Z"), std::string::npos)
      << p.warnings[0];
}

TEST(SinumerikReader, ReadProgramDispatch) {
  const auto dir = std::filesystem::temp_directory_path() / "vcut_sinumerik_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "part.mpf").string();
  std::ofstream(path) << "%_N_PART_MPF\nN10 G54 G0 X0 Y0 Z0\nN20 G1 X1 F100\nN30 M30\n";
  ProgramOptions options;
  options.gcode.work_offsets_mm["G54"] = Eigen::Vector3d(0, 0, 5);
  const LoadedProgram loaded = read_program(path, Dialect::Auto, options);
  EXPECT_EQ(loaded.reader, ProgramReader::Sinumerik);
  ASSERT_EQ(loaded.program.blocks.size(), 1u);
  expect_vec(loaded.program.blocks[0].end_mm, {1, 0, 5});
  EXPECT_EQ(loaded.program.where(loaded.program.blocks[0].source), path + ":3");
  std::filesystem::remove_all(dir);
}

// R parameters and modes carry from one file to the next (one state).
TEST(SinumerikReader, StateAcrossFiles) {
  Program program;
  SinumerikState state;
  std::istringstream a("R7=3 G0 X0 Y0 Z0 TRAORI\nG91\nM30\n"), b("G1 F10 X=R7\n");
  read_sinumerik(a, "a.mpf", {}, program, state);
  read_sinumerik(b, "b.spf", {}, program, state);
  ASSERT_EQ(program.blocks.size(), 1u);
  expect_vec(program.blocks[0].end_mm, {3, 0, 0});  // M30 reset G91 to G90
  EXPECT_EQ(program.where(program.blocks[0].source), "b.spf:1");
}

// Programmable frames (Siemens, Programming Manual Fundamentals, "Frames"), worked by hand:
// TRANS X10 Y20 moves program zero to (10, 20, 0); AROT Z90 then turns the axes a quarter
// about Z, so a programmed (5, 0, 0) is (10, 20) + Rz(90) (5, 0) = (10, 25, 0); ATRANS X1
// after it moves along the turned X, the new zero at (10, 21); TRANS alone clears it all.
TEST(SinumerikReader, FramesPlaceTheProgrammedPoints) {
  const Program p =
      read("G0 X0 Y0 Z5\nTRANS X10 Y20\nG1 F100 X5 Y0 Z0\nAROT Z90\nX5 Y0\nATRANS X1\nX0 Y0\nTRANS\nX0 Y0\n");
  // (The first G0 only sets the position: no block.)
  ASSERT_EQ(p.blocks.size(), 4u);
  expect_vec(p.blocks[0].end_mm, {15, 20, 0});
  expect_vec(p.blocks[1].end_mm, {10, 25, 0});
  expect_vec(p.blocks[2].end_mm, {10, 21, 0});
  expect_vec(p.blocks[3].end_mm, {0, 0, 0});
  // MIRROR X: the tool at (-10, 0) is at (10, 0) in the mirrored frame; G2 there from (10, 0)
  // about (0, 0) to (0, -10) is a clockwise quarter; mirrored back it runs from (-10, 0) to
  // (0, -10), from 180 to 270 deg: counterclockwise about +Z.
  const Program m = read("G0 X-10 Y0 Z0\nMIRROR X0\nG2 F100 X0 Y-10 I-10 J0\n");
  ASSERT_EQ(m.blocks.size(), 1u);
  expect_vec(m.blocks[0].end_mm, {0, -10, 0});
  expect_vec(m.blocks[0].center_mm, {0, 0, 0});
  expect_vec(m.blocks[0].normal, {0, 0, 1});
  // SCALE X2 Y2: (5, 5) is (10, 10); CR=5 becomes a 10 mm radius; unequal factors make an
  // arc an ellipse: refused.
  const Program s = read("G0 X0 Y0 Z0\nSCALE X2 Y2\nG1 F100 X5 Y5\nG3 X0 Y10 CR=5\n");
  ASSERT_EQ(s.blocks.size(), 2u);
  expect_vec(s.blocks[0].end_mm, {10, 10, 0});
  expect_vec(s.blocks[1].end_mm, {0, 20, 0});
  EXPECT_NEAR((s.blocks[1].end_mm - s.blocks[1].center_mm).norm(), 10.0, 1e-9);
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nSCALE X2 Y3\nG2 F100 X1 Y1 CR=1\n", 3, 1, "ellipse");
  // ROT Y90 tilts: a programmed (0, 0, 10) is Ry(90) (0, 0, 10) = (10, 0, 0); the tool vector
  // C3=1 turns with it to +X.
  const Program t = read("G0 X0 Y0 Z0\nROT Y90\nTRAORI\nG1 F100 Z10 C3=1\n");
  ASSERT_EQ(t.blocks.size(), 1u);
  expect_vec(t.blocks[0].end_mm, {10, 0, 0});
  expect_vec(t.blocks[0].end_axis, {1, 0, 0});
  // ROT RPL=30 in G17: about Z.
  const Program r = read("G0 X0 Y0 Z0\nROT RPL=30\nG1 F100 X10\n");
  expect_vec(r.blocks.at(0).end_mm, {10 * std::cos(30 * kDeg), 10 * std::sin(30 * kDeg), 0});
  EXPECT_MPF_ERROR("ROT X10\nG1 F1 X1\n", 2, 7, "unknown X position");
  EXPECT_MPF_ERROR("SCALE X0\n", 1, 7, "expected > 0");
  EXPECT_MPF_ERROR("TRANS RPL=3\n", 1, 7, "expected ROT or AROT");
}

// CYCLE81 at the current X Y (G17): rapid to RFP + SDIS = 2, feed to DP = -10, rapid to RTP
// = 10; MCALL makes it end every positioning block until MCALL alone. CYCLE83 pecks: the first
// FDPR = 4 below RFP 0, then DAM = 1 less each time but at least 1: -4, -7, -9, -10, back to
// RFP + SDIS = 1 after each (VARI = 1) and rapid down again to where it stopped.
TEST(SinumerikReader, DrillingCycles) {
  const Program p = read("G0 X5 Y5 Z20\nF100\nCYCLE81(10, 0, 2, -10)\nMCALL CYCLE81(10, 0, 2, , 3)\nX8\nMCALL\nX9\n");
  std::vector<std::pair<MotionKind, double>> z;
  for (const Block& b : p.blocks) z.emplace_back(b.kind, b.end_mm.z());
  const MotionKind R = MotionKind::Rapid, L = MotionKind::Linear;
  // (The first G0 only sets the position: no block.)
  const std::vector<std::pair<MotionKind, double>> want = {
      {R, 2},  {L, -10}, {R, 10},                     // CYCLE81 at (5, 5)
      {R, 10}, {R, 2},   {L, -3}, {R, 10}, {R, 10}};  // X8, then its cycle (DPR 3 below RFP), X9
  EXPECT_EQ(z, want);
  expect_vec(p.blocks[3].end_mm, {8, 5, 10});
  expect_vec(p.blocks[7].end_mm, {9, 5, 10});
  const Program deep = read("G0 X0 Y0 Z5\nF100\nCYCLE83(5, 0, 1, -10, , , 4, 1, 0, 0, 0.5, 1)\n");
  std::vector<double> feeds, rapids;
  for (const Block& b : deep.blocks) (b.kind == L ? feeds : rapids).push_back(b.end_mm.z());
  EXPECT_EQ(feeds, (std::vector<double>{-4, -7, -9, -10}));
  EXPECT_EQ(rapids, (std::vector<double>{1, 1, -4, 1, -7, 1, -9, 5}));
  EXPECT_DOUBLE_EQ(deep.blocks.at(1).feed_mm_per_min, 50.0);  // the first peck at F x FRF
  // Tapping and boring (Programming Manual Cycles): CYCLE84/840/85/89 feed back out to RFP +
  // SDIS, CYCLE86/87/88 rapid out from the depth.
  for (const char* name : {"CYCLE84", "CYCLE840", "CYCLE85", "CYCLE89", "CYCLE86", "CYCLE87", "CYCLE88"}) {
    const Program c = read(std::string("G0 X0 Y0 Z10\nF100\n") + name + "(10, 0, 2, -5)\n");
    std::vector<std::pair<MotionKind, double>> steps;
    for (const Block& b : c.blocks) steps.emplace_back(b.kind, b.end_mm.z());
    const bool feeds_out = std::string(name) == "CYCLE84" || std::string(name) == "CYCLE840" ||
                           std::string(name) == "CYCLE85" || std::string(name) == "CYCLE89";
    const std::vector<std::pair<MotionKind, double>> expected =
        feeds_out ? std::vector<std::pair<MotionKind, double>>{{R, 2}, {L, -5}, {L, 2}, {R, 10}}
                  : std::vector<std::pair<MotionKind, double>>{{R, 2}, {L, -5}, {R, 10}};
    EXPECT_EQ(steps, expected) << name;
  }
  EXPECT_MPF_ERROR("G0 X0 Y0\nCYCLE81(10, 0, 2, -10)\n", 2, 1, "unknown Z position");
  EXPECT_MPF_ERROR("G0 X0 Y0 Z1\nCYCLE81(10)\n", 2, 1, "without RTP and RFP");
  EXPECT_MPF_ERROR("G0 X0 Y0 Z1\nCYCLE81(10, 0, 2)\n", 2, 1, "without its depth");
}

// Program flow, worked by hand: FOR runs PASS 1, 2, 3 (Z -0.5, -1, -1.5); WHILE twice (Y 5, 10);
// IF ... GOTOF jumps over X100 to the label; the IF block takes its first branch (X20, not
// X30); REPEAT runs until R2 = 3; GOTOB goes back to a block number.
TEST(SinumerikReader, ProgramFlow) {
  const Program p = read(
      "DEF REAL DEPTH=2, STEP\nDEF INT PASS\nN10 G0 X0 Y0 Z5\nF500\nSTEP = 0.5\nFOR PASS = 1 TO 3\n"
      "  G1 Z=-PASS*STEP\nENDFOR\nR1 = 0\nWHILE R1 < 2\n  R1 = R1 + 1\n  G1 Y=R1*5\nENDWHILE\n"
      "IF R1 == 2 GOTOF SKIP\nG1 X100\nSKIP: G0 Z5\nIF DEPTH > 1 AND NOT STEP == 1\n  G1 X20\nELSE\n  G1 X30\nENDIF\n"
      "REPEAT\n  R2 = R2 + 1\nUNTIL R2 >= 3\nG1 X=R2\nN90 R3 = R3 + 1\nIF R3 < 2 GOTOB N90\nG1 X=R3\nM30\n");
  std::vector<double> x, y, z;
  for (const Block& b : p.blocks) {
    x.push_back(b.end_mm.x());
    y.push_back(b.end_mm.y());
    z.push_back(b.end_mm.z());
  }
  EXPECT_EQ(z, (std::vector<double>{-0.5, -1, -1.5, -1.5, -1.5, 5, 5, 5, 5}));
  EXPECT_EQ(y, (std::vector<double>{0, 0, 0, 5, 10, 10, 10, 10, 10}));
  EXPECT_EQ(x, (std::vector<double>{0, 0, 0, 0, 0, 0, 20, 3, 2}));
  EXPECT_EQ(p.blocks[5].source.line, 16);  // the labelled block
  // A loop that never ends stops at max_lines; structures must close; jumps must land.
  SinumerikOptions few;
  few.max_lines = 1000;
  const InputError endless = error_of("LOOP\nG1 X1 F1\nENDLOOP\n", few);
  EXPECT_NE(std::string(endless.what()).find("more than 1000 blocks run"), std::string::npos) << endless.what();
  EXPECT_MPF_ERROR("WHILE 1\nG1 X1 F1\n", 1, 1, "WHILE without its ENDWHILE");
  // A flow word after more than the scan's first 80 bytes of blanks (the fuzzer's ENDFOR after
  // 170 form feeds, followed to line -1): paired as any, or refused naming it.
  const std::string indent(100, ' '), feeds(170, '\f');
  const Program deep = read("DEF INT KK\nG0 X0 Y0 Z0\nFOR KK = 1 TO 3\nG1 X=KK F1\n" + indent + "ENDFOR\nG1 Y1\n");
  ASSERT_EQ(deep.blocks.size(), 4u);  // X1, X2, X3 (G0 to where it stands makes none), Y1
  EXPECT_EQ(deep.blocks[2].end_mm.x(), 3.0);
  EXPECT_EQ(deep.blocks[3].end_mm.y(), 1.0);
  EXPECT_MPF_ERROR("G1 X1 F1\n" + feeds + "ENDFOR\n", 2, 171, "ENDFOR without its FOR");
  EXPECT_MPF_ERROR("G1 X1 F1\nENDIF\n", 2, 1, "ENDIF without its IF");
  EXPECT_MPF_ERROR("GOTOF NOWHERE\n", 1, 7, "no such label");
  EXPECT_MPF_ERROR("IF R1 == 0 ; GOTO in a comment\nG1 X1 F1\nENDIF\n", 3, 1, "ENDIF without its IF");
  EXPECT_MPF_ERROR("IF R1 == 0 ; GOTO in a comment\nG1 X1 F1\n", 1, 1, "without its ENDIF");
  EXPECT_MPF_ERROR("DEF STRING[8] NAME\n", 1, 4, "DEF STRING is not supported");
  // CASE: the first equal constant's jump, else DEFAULT's, else the next block; R1 = 2, 7, 9.
  for (const auto& [r1, want] : std::vector<std::pair<int, double>>{{2, 2.0}, {7, 3.0}, {1, 1.0}}) {
    const Program c = read("R1=" + std::to_string(r1) +
                           "\nG0 X0 Y0 Z0\nCASE (R1) OF 1 GOTOF ONE 2 GOTOF TWO DEFAULT GOTOF OTHER\n"
                           "ONE: G1 X1 F100\nGOTOF END\nTWO: G1 X2 F100\nGOTOF END\nOTHER: G1 X3 F100\nEND: M30\n");
    ASSERT_EQ(c.blocks.size(), 1u) << r1;
    EXPECT_EQ(c.blocks[0].end_mm.x(), want) << r1;
  }
  const Program none = read("G0 X0 Y0 Z0\nCASE (5) OF 1 GOTOF ONE\nG1 X7 F1\nONE: G1 Y1\n");
  ASSERT_EQ(none.blocks.size(), 2u);  // no case taken: on to the next block
  EXPECT_EQ(none.blocks[0].end_mm.x(), 7.0);
  EXPECT_MPF_ERROR("CASE (1) OF 1 GOTOF NOWHERE\n", 1, 21, "no such label");
  EXPECT_MPF_ERROR("CASE (1) OF 1 X\n", 1, 15, "without its jump");
  // A condition in parentheses (IF (A <= B) AND (C > 2)), and parentheses that belong to an
  // expression ((R1 + 2) > 3 with R1 = 1: false).
  const Program paren = read(
      "R1=1\nR2=3\nG0 X0 Y0 Z0\nIF (R1 <= R2) AND (R2 > 2)\nG1 X1 F10\nENDIF\nIF (R1 + 2) > 3\nG1 X2\nENDIF\n"
      "WHILE(R1 < 3)\nR1=R1+1\nG1 Y=R1\nENDWHILE\n");
  std::vector<double> px, py;
  for (const Block& b : paren.blocks) {
    px.push_back(b.end_mm.x());
    py.push_back(b.end_mm.y());
  }
  EXPECT_EQ(px, (std::vector<double>{1, 1, 1}));
  EXPECT_EQ(py, (std::vector<double>{0, 2, 3}));
  // TURN=n: n more full turns (a helix from (10, 0, 0) back over itself 3 times in all).
  const Program helix = read("G0 X10 Y0 Z0\nG3 X10 Y0 Z-3 I-10 J0 TURN=2 F100\n");
  ASSERT_EQ(helix.blocks.size(), 1u);
  EXPECT_EQ(helix.blocks[0].turns, 3);
  EXPECT_MPF_ERROR("G0 X0 Y0 Z0\nG1 X1 TURN=1 F1\n", 2, 7, "TURN= outside an arc");
}

// Subprograms, worked by hand: POCKET(3, 3) runs its FOR with DEPTH 3 and PASSES 3 (Z -1, -2,
// -3, X 10 and back) in the caller's TRANS X20 frame; L10 P2 runs L10.SPF twice (its second
// run does not move); a subprogram found on subroutine_path; one that is not found names the
// folders searched.
TEST(SinumerikReader, Subprograms) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("vcut_spf_" + std::to_string(::getpid()));
  const fs::path lib = dir / "lib";
  fs::create_directories(lib);
  auto write = [](const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; };
  write(dir / "POCKET.SPF",
        "PROC POCKET(REAL DEPTH, INT PASSES) SAVE\nDEF INT KK\nFOR KK = 1 TO PASSES\n  G1 Z=-KK*DEPTH/PASSES\n  X10\n"
        "  X0\nENDFOR\nG0 Z5\nM17\n");
  write(lib / "l10.spf", "G1 X5 F100\nRET\n");
  write(dir / "main.mpf", "G0 X0 Y0 Z5\nF200\nTRANS X20\nPOCKET(3, 3)\nTRANS\nL10 P2\nM30\n");
  SinumerikOptions options;
  options.subroutine_path = {lib.string()};
  const Program p = read_sinumerik((dir / "main.mpf").string(), options);
  std::vector<Eigen::Vector3d> ends;
  for (const Block& b : p.blocks) ends.push_back(b.end_mm);
  const std::vector<Eigen::Vector3d> want = {{0, 0, -1},  {30, 0, -1}, {20, 0, -1}, {20, 0, -2},
                                             {30, 0, -2}, {20, 0, -2}, {20, 0, -3}, {30, 0, -3},
                                             {20, 0, -3}, {20, 0, 5},  {5, 0, 5}};
  ASSERT_EQ(ends.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) expect_vec(ends[k], want[k]);
  EXPECT_EQ(p.where(p.blocks[0].source), (dir / "POCKET.SPF").string() + ":4");
  EXPECT_EQ(p.where(p.blocks[10].source), (lib / "l10.spf").string() + ":1");
  write(dir / "missing.mpf", "G0 X0 Y0 Z0\nL77\n");
  try {
    read_sinumerik((dir / "missing.mpf").string(), options);
    ADD_FAILURE() << "a missing subprogram was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.mpf:2:1: subprogram L77 not found"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(lib.string()), std::string::npos) << e.what();
  }
  write(dir / "self.mpf", "G0 X0 Y0 Z0\nSELF\n");
  write(dir / "SELF.SPF", "SELF\n");
  EXPECT_THROW(read_sinumerik((dir / "self.mpf").string(), options), InputError);  // nested 16 deep
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vcut::io
