// rs274ngc beyond the three-axis core: parameters, expressions, o-word control flow and
// subroutines, offsets (G10, G92, G53), inverse time (G93) and canned cycles. Expected values
// are worked by hand from LinuxCNC's G-code documentation (G-code overview, O codes, G10,
// G92, G53, G73/G81/G82/G83/G85/G89, G98/G99); none is copied from the reader's output.
#include <gtest/gtest.h>
#include <vcut/io/gcode_reader.h>

#include "gcode_text.h"
#include <vcut/io/input_error.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::FeedMode;
using kinematics::MotionKind;
using kinematics::Program;

constexpr double kTol = 1e-9;

Program read(const std::string& text, const GcodeOptions& options = {}, const std::string& name = "test.ngc") {
  return gcode_test::read_text(text, options, name);
}

std::string error_of(const std::string& text, const GcodeOptions& options = {}) {
  return gcode_test::error_text(text, options, "test.ngc");
}

// The X the reader computes for `value` (a word value: number, parameter, expression).
double x_of(const std::string& value, const std::string& before = "") {
  const Program p = read("G0 X-1000 Y0 Z0\n" + before + "G0 X" + value + "\n");
  EXPECT_EQ(p.blocks.size(), 1u) << value;
  return p.blocks.empty() ? NAN : p.blocks.back().end_mm.x();
}

// End points of the blocks, as (x, y, z) rows.
std::vector<Eigen::Vector3d> ends(const Program& p) {
  std::vector<Eigen::Vector3d> out;
  for (const Block& b : p.blocks) out.push_back(b.end_mm);
  return out;
}

void expect_path(const Program& p, const std::vector<std::pair<MotionKind, Eigen::Vector3d>>& expected) {
  ASSERT_EQ(p.blocks.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(p.blocks[i].kind, expected[i].first) << "block " << i;
    EXPECT_LT((p.blocks[i].end_mm - expected[i].second).norm(), kTol)
        << "block " << i << ": " << p.blocks[i].end_mm.transpose() << " vs " << expected[i].second.transpose();
  }
}

constexpr MotionKind R = MotionKind::Rapid;
constexpr MotionKind F = MotionKind::Linear;

// ------------------------------------------------------------------ expressions

TEST(Rs274Expressions, PrecedenceAndAssociativity) {
  EXPECT_NEAR(x_of("[1 + 2 * 3]"), 7.0, kTol);
  EXPECT_NEAR(x_of("[[1 + 2] * 3]"), 9.0, kTol);
  EXPECT_NEAR(x_of("[10 - 4 - 3]"), 3.0, kTol);    // left to right
  EXPECT_NEAR(x_of("[2 ** 3 ** 2]"), 64.0, kTol);  // (2^3)^2: left to right as well
  EXPECT_NEAR(x_of("[2 * 3 ** 2]"), 18.0, kTol);   // ** before *
  EXPECT_NEAR(x_of("[12 / 4 / 3]"), 1.0, kTol);
  EXPECT_NEAR(x_of("[1 + 2 GT 2]"), 1.0, kTol);        // + before GT
  EXPECT_NEAR(x_of("[1 GT 2 OR 3 GT 2]"), 1.0, kTol);  // GT before OR
  EXPECT_NEAR(x_of("[1 AND 0 XOR 1]"), 1.0, kTol);     // (1 AND 0) XOR 1
  EXPECT_NEAR(x_of("[-2 * -3]"), 6.0, kTol);
  EXPECT_NEAR(x_of("-[2 + 3]"), -5.0, kTol);
  EXPECT_NEAR(x_of("[ 1 0 . 5 ]"), 10.5, kTol);  // blanks inside numbers are ignored
}

TEST(Rs274Expressions, ModuloComparisonAndLogic) {
  EXPECT_NEAR(x_of("[7 MOD 3]"), 1.0, kTol);
  EXPECT_NEAR(x_of("[-7 MOD 3]"), 2.0, kTol);  // never negative: -1 + 3
  EXPECT_NEAR(x_of("[7.5 mod 2]"), 1.5, kTol);
  EXPECT_NEAR(x_of("[1 EQ 1.00005]"), 1.0, kTol);  // EQ within 1e-4
  EXPECT_NEAR(x_of("[1 EQ 1.001]"), 0.0, kTol);
  EXPECT_NEAR(x_of("[1 NE 1.001]"), 1.0, kTol);
  EXPECT_NEAR(x_of("[2 GE 2]"), 1.0, kTol);
  EXPECT_NEAR(x_of("[2 LT 2]"), 0.0, kTol);
  EXPECT_NEAR(x_of("[2 LE 2]"), 1.0, kTol);
  EXPECT_NEAR(x_of("[0.5 AND 2]"), 1.0, kTol);
  EXPECT_NEAR(x_of("[0 OR 0]"), 0.0, kTol);
  EXPECT_NEAR(x_of("[1 XOR 1]"), 0.0, kTol);
}

TEST(Rs274Expressions, Functions) {
  EXPECT_NEAR(x_of("COS[60]"), 0.5, 1e-12);  // degrees
  EXPECT_NEAR(x_of("SIN[30]"), 0.5, 1e-12);
  EXPECT_NEAR(x_of("TAN[45]"), 1.0, 1e-12);
  EXPECT_NEAR(x_of("ACOS[0]"), 90.0, 1e-12);
  EXPECT_NEAR(x_of("ASIN[-1]"), -90.0, 1e-12);
  EXPECT_NEAR(x_of("ATAN[1]/[-1]"), 135.0, 1e-12);  // the angle of (x, y) = (-1, 1)
  EXPECT_NEAR(x_of("ATAN[-1]/[0]"), -90.0, 1e-12);
  EXPECT_NEAR(x_of("SQRT[16]"), 4.0, kTol);
  EXPECT_NEAR(x_of("EXP[0]"), 1.0, kTol);
  EXPECT_NEAR(x_of("LN[1]"), 0.0, kTol);
  EXPECT_NEAR(x_of("ABS[-3]"), 3.0, kTol);
  EXPECT_NEAR(x_of("FIX[-2.5]"), -3.0, kTol);  // down
  EXPECT_NEAR(x_of("FUP[-2.5]"), -2.0, kTol);  // up
  EXPECT_NEAR(x_of("ROUND[2.5]"), 3.0, kTol);  // halves away from zero
  EXPECT_NEAR(x_of("ROUND[-2.5]"), -3.0, kTol);
  EXPECT_NEAR(x_of("[2 * abs[-1.5]]"), 3.0, kTol);  // case-insensitive
  EXPECT_NEAR(x_of("[EXISTS[#<a>] * 10 + EXISTS[#<b>]]", "#<a> = 1\n"), 10.0, kTol);
}

TEST(Rs274Expressions, Errors) {
  auto expect_error = [](const std::string& line, const std::string& where, const std::string& fragment) {
    const std::string e = error_of("G0 X0 Y0 Z0\n" + line + "\n");
    EXPECT_EQ(e.rfind("test.ngc:2:" + where + ": ", 0), 0u) << e;
    EXPECT_NE(e.find(fragment), std::string::npos) << e;
  };
  expect_error("G0 X[1 / 0]", "8", "division by zero");
  expect_error("G0 X[1 MOD 0]", "8", "division by zero");
  expect_error("G0 X[SQRT[-1]]", "6", "SQRT");
  expect_error("G0 X[LN[0]]", "6", "LN");
  expect_error("G0 X[ACOS[2]]", "6", "-1..1");
  expect_error("G0 X[-8 ** 0.5]", "9", "non-whole power");
  expect_error("G0 X[1 + 2", "5", "expected ']'");
  expect_error("G0 X[1 + ]", "10", "expected a number");
  expect_error("G0 X[FOO[1]]", "6", "unknown function 'FOO'");
  expect_error("G0 XATAN[1]", "12", "ATAN[y]/[x]");
  expect_error("G0 X[10 ** 400]", "9", "not a finite number");
  expect_error("G0 X#0", "6", "1..5601");
  expect_error("G0 X#1.5", "6", "whole number");
  expect_error("G0 X#<nope>", "5", "#<nope> is not defined");
  expect_error("G0 X#<a", "6", "'>'");
  expect_error("G0 X[1 + [2 * [3]]] X1", "21", "second X word");
  // Deeply nested brackets are refused, not a stack overflow.
  expect_error("G0 X" + std::string(100, '[') + "1" + std::string(100, ']'), "69", "nested");
}

// ------------------------------------------------------------------ parameters

TEST(Rs274Parameters, NumberedNamedAndIndirect) {
  EXPECT_NEAR(x_of("#1", "#1 = 4.5\n"), 4.5, kTol);
  EXPECT_NEAR(x_of("##2", "#2 = 7\n#7 = 3\n"), 3.0, kTol);  // #[#2] = #7
  EXPECT_NEAR(x_of("#[1 + 1]", "#2 = 8\n"), 8.0, kTol);
  EXPECT_NEAR(x_of("#<my depth>", "#<MyDepth> = 2.5\n"), 2.5, kTol);  // blanks and case ignored
  EXPECT_NEAR(x_of("#<_g>", "#<_g> = -1\n"), -1.0, kTol);
  EXPECT_NEAR(x_of("#99", ""), 0.0, kTol);              // unset numbered: 0
  EXPECT_NEAR(x_of("[#<_unset> + 1]", ""), 1.0, kTol);  // unset global: 0
  // Every value on a line is read before any parameter of the line is set.
  EXPECT_NEAR(x_of("#1", "#1 = 1\n#1 = 2 #2 = #1\n#1 = #2\n"), 1.0, kTol);
  EXPECT_NEAR(x_of("#3", "#3 = 1 #3 = 2\n"), 2.0, kTol);  // the last setting wins
}

TEST(Rs274Parameters, PositionAndModes) {
  // #5420.. and #<_x>..: the current position in program coordinates (G54 X offset 10 here).
  GcodeOptions options;
  options.work_offsets_mm["G54"] = Eigen::Vector3d(10, 0, 0);
  const Program p = read("G0 X1 Y2 Z3\nG0 X[#5420 + #<_y> + #5422]\n", options);
  ASSERT_EQ(p.blocks.size(), 1u);
  EXPECT_NEAR(p.blocks[0].end_mm.x(), 10 + 6.0, kTol);
  // #5220: the coordinate system (G55 = 2); #5221.. G54's offsets.
  const Program q = read("G55\nG0 X#5220 Y#5221 Z0\nG0 X0\n", options);
  ASSERT_EQ(q.blocks.size(), 1u);
  EXPECT_NEAR(q.blocks[0].start_mm.x(), 2.0, kTol);
  EXPECT_NEAR(q.blocks[0].start_mm.y(), 10.0, kTol);
  EXPECT_NE(error_of("#5420 = 1\n").find("read-only"), std::string::npos);
}

// ------------------------------------------------------------------ control flow

TEST(Rs274ControlFlow, IfElseifElse) {
  for (int n = 1; n <= 3; ++n) {
    const std::string program = "#1 = " + std::to_string(n) +
                                "\nG0 X0 Y0 Z0\n"
                                "o10 if [#1 EQ 1]\n  G0 X10\n"
                                "o10 elseif [#1 EQ 2]\n  G0 X20\n"
                                "o10 else\n  G0 X30\n"
                                "o10 endif\nG0 Y1\n";
    const Program p = read(program);
    ASSERT_EQ(p.blocks.size(), 2u);
    EXPECT_NEAR(p.blocks[0].end_mm.x(), 10.0 * n, kTol);
    EXPECT_EQ(p.blocks[0].source.line, 4 + 2 * (n - 1));
  }
}

TEST(Rs274ControlFlow, WhileDoRepeatBreakContinue) {
  // while: X = 0, 1, 2 then stop at 3.
  Program p = read("G0 X0 Y0 Z0\n#1 = 1\no1 while [#1 LT 4]\n  G0 X#1\n  #1 = [#1 + 1]\no1 endwhile\nG0 Y5\n");
  std::vector<double> xs;
  for (const Block& b : p.blocks) xs.push_back(b.end_mm.x());
  EXPECT_EQ(xs, (std::vector<double>{1, 2, 3, 3}));
  // do runs its body once even when the test fails at once.
  p = read("G0 X0 Y0 Z0\no2 do\n  G0 X7\no2 while [0]\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  // repeat: three passes of an incremental move; repeat [0] skips its body.
  p = read("G0 X0 Y0 Z0\nG91\no3 repeat [3]\n  G0 X2\no3 endrepeat\no4 repeat [0]\n  G0 Y9\no4 endrepeat\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  EXPECT_NEAR(p.blocks[2].end_mm.x(), 6.0, kTol);
  // break leaves the loop; continue skips the rest of one pass (X 1..5, Y only for odd ones).
  p = read(
      "G0 X0 Y0 Z0\n#1 = 0\no5 while [1]\n  #1 = [#1 + 1]\n  o6 if [#1 GT 5]\n    o5 break\n  o6 endif\n"
      "  G0 X#1\n  o7 if [[#1 MOD 2] EQ 0]\n    o5 continue\n  o7 endif\n  G0 Y#1\no5 endwhile\nG0 Z1\n");
  std::vector<Eigen::Vector3d> expected = {{1, 0, 0}, {1, 1, 0}, {2, 1, 0}, {3, 1, 0}, {3, 3, 0},
                                           {4, 3, 0}, {5, 3, 0}, {5, 5, 0}, {5, 5, 1}};
  const auto got = ends(p);
  ASSERT_EQ(got.size(), expected.size());
  for (size_t i = 0; i < got.size(); ++i) EXPECT_LT((got[i] - expected[i]).norm(), kTol) << i;
}

TEST(Rs274ControlFlow, SubroutinesArgumentsScopeAndReturn) {
  const Program p = read(
      "o<square> sub\n"  // #1 = side, #2 = z
      "  #<half> = [#1 / 2]\n"
      "  G1 X#<half> Y[-#<half>] Z#2 F100\n"
      "  G1 Y#<half>\n"
      "  o<square> return [#1 * #1]\n"
      "o<square> endsub\n"
      "#1 = 99\n#<half> = 42\n"
      "G0 X0 Y0 Z5\n"
      "o<square> call [4] [-1]\n"
      "G0 X#<_value> Y#1 Z#<half>\n");
  expect_path(p, {{F, {2, -2, -1}}, {F, {2, 2, -1}}, {R, {16, 99, 42}}});
  EXPECT_EQ(p.blocks[0].source.line, 3);
  EXPECT_EQ(p.blocks[2].source.line, 11);
}

TEST(Rs274ControlFlow, SubroutineFileOnTheSearchPath) {
  const auto dir = std::filesystem::temp_directory_path() / "vcut_rs274_sub_test";
  std::filesystem::create_directories(dir / "lib");
  std::ofstream(dir / "lib" / "peck.ngc")
      << "(a subroutine file)\no<peck> sub\n  G1 Z#1 F50\n  G0 Z2\no<peck> endsub\nM2\n";
  GcodeOptions options;
  options.subroutine_path = {(dir / "lib").string()};
  const Program p =
      read("G0 X0 Y0 Z2\no<peck> call [-3]\nG0 X5\no<PECK> call [-4]\n", options, (dir / "main.ngc").string());
  expect_path(p, {{F, {0, 0, -3}}, {R, {0, 0, 2}}, {R, {5, 0, 2}}, {F, {5, 0, -4}}, {R, {5, 0, 2}}});
  ASSERT_EQ(p.files.size(), 2u);
  EXPECT_EQ(p.where(p.blocks[0].source), (dir / "lib" / "peck.ngc").string() + ":3");
  EXPECT_EQ(p.where(p.blocks[2].source), (dir / "main.ngc").string() + ":3");
  // An error inside the subroutine names the call chain.
  std::ofstream(dir / "lib" / "bad.ngc") << "o<bad> sub\n  G1 X[1/0]\no<bad> endsub\n";
  try {
    read("G0 X0 Y0 Z0\nF10\no<bad> call\n", options, (dir / "main.ngc").string());
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind((dir / "lib" / "bad.ngc").string() + ":2:", 0), 0u) << what;
    EXPECT_NE(what.find("in o<bad> called at " + (dir / "main.ngc").string() + ":3"), std::string::npos) << what;
  }
  EXPECT_NE(error_of("o<nowhere> call\n", options).find("no such subroutine"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Rs274ControlFlow, SubroutineDefinedAfterTheProgramEnd) {
  // rs274 reads ahead for a subroutine defined further down the file, past M2.
  const Program p = read("G0 X0 Y0 Z0\no<later> call [2]\nG0 Y1\nM2\no<later> sub\n  G0 X#1\no<later> endsub\n");
  expect_path(p, {{R, {2, 0, 0}}, {R, {2, 1, 0}}});
  EXPECT_EQ(p.blocks[0].source.line, 6);
}

// A file of subroutine definitions alone (LinuxCNC keeps one in a file of its name; a real
// probing routine was such a file) makes no motion: a warning names the sub and its line.
// Called, or in a program that moves, it says nothing.
TEST(Rs274ControlFlow, SubroutineFileAloneWarns) {
  const Program alone = read("(a probing routine)\no<probe> sub\n  G38.2 Z-5 F10\no<probe> endsub\nM2\n");
  EXPECT_TRUE(alone.blocks.empty());
  ASSERT_EQ(alone.warnings.size(), 1u);
  EXPECT_NE(alone.warnings[0].find(":2: o<probe> sub is defined but never called: the program makes no motion"),
            std::string::npos)
      << alone.warnings[0];
  EXPECT_TRUE(read("o<up> sub\n  G0 Z#1\no<up> endsub\nG0 X0 Y0 Z0\no<up> call [5]\nM2\n").warnings.empty());
  EXPECT_TRUE(read("o<set> sub\n  #<_depth> = 5\no<set> endsub\no<set> call\nM2\n").warnings.empty());
  const Program moves = read("o<up> sub\n  G0 Z#1\no<up> endsub\nG0 X1 Y0 Z0\nM2\n");
  for (const std::string& w : moves.warnings) EXPECT_EQ(w.find("never called"), std::string::npos) << w;
}

TEST(Rs274ControlFlow, Errors) {
  GcodeOptions limited;
  limited.max_lines = 1000;
  const std::string endless = error_of("o1 while [1]\no1 endwhile\n", limited);
  EXPECT_NE(endless.find("1000 lines"), std::string::npos) << endless;
  EXPECT_NE(endless.find("loop"), std::string::npos) << endless;
  EXPECT_NE(error_of("o1 if [1]\nG0 X0\n").find("ends inside o1 if, opened at test.ngc:1"), std::string::npos);
  EXPECT_NE(error_of("o1 if [0]\nG0 X0\n").find("before o1 elseif or o1 else or o1 endif (opened at test.ngc:1)"),
            std::string::npos);
  EXPECT_NE(error_of("o2 endif\n").find("without o2 if"), std::string::npos);
  EXPECT_NE(error_of("o3 endwhile\n").find("outside a loop"), std::string::npos);
  EXPECT_NE(error_of("o3 return\n").find("outside a subroutine"), std::string::npos);
  EXPECT_NE(error_of("o<s> sub\nG0 X0\n").find("before o<s> endsub"), std::string::npos);
  EXPECT_NE(error_of("o4 if\n").find("without its condition"), std::string::npos);
  EXPECT_NE(error_of("o4 frobnicate\n").find("unknown o-word keyword 'frobnicate'"), std::string::npos);
  // A subroutine that calls itself forever stops at the nesting limit.
  EXPECT_NE(error_of("o<r> sub\no<r> call\no<r> endsub\no<r> call\n").find("nested more than 64"), std::string::npos);
}

// ------------------------------------------------------------------ offsets

TEST(Rs274Offsets, G10G92G53) {
  // G10 L2 P1 X10: G54's X offset is 10 mm, so X0 is at 10.
  expect_path(read("G0 X0 Y0 Z0\nG10 L2 P1 X10\nG0 X0 Y1\n"), {{R, {10, 1, 0}}});
  // G10 L20 P0 X0 at X = 5: the active system's offset becomes 5, so X1 is at 6.
  expect_path(read("G0 X5 Y0 Z0\nG10 L20 P0 X0\nG0 X1\n"), {{R, {6, 0, 0}}});
  // G10 on an inactive system takes effect when it is selected.
  expect_path(read("G0 X0 Y0 Z0\nG10 L2 P2 Y-3\nG0 Y0\nG55 G0 Y0\n"), {{R, {0, -3, 0}}});
  // G92 X0 at X = 5 adds 5; G92.1 takes it away; G92.3 brings back the kept #5211.
  expect_path(read("G0 X5 Y0 Z0\nG92 X0\nG0 X1\nG92.1\nG0 X1\n"), {{R, {6, 0, 0}}, {R, {1, 0, 0}}});
  expect_path(read("G0 X5 Y0 Z0\nG92 X0\nG92.2\nG0 X2\nG92.3\nG0 X2\n"), {{R, {2, 0, 0}}, {R, {7, 0, 0}}});
  // G52 X5: the local origin 5 mm along X from the work zero (LinuxCNC keeps it in the G92
  // offsets: X1 at 6); a later G52 Y3 keeps X's; G52 X0 Y0 ends it. A G92 before it is replaced.
  expect_path(read("G0 X0 Y0 Z0\nG52 X5\nG0 X1\nG52 Y3\nG0 Y0\nG52 X0 Y0\nG0 X0\n"),
              {{R, {6, 0, 0}}, {R, {6, 3, 0}}, {R, {0, 3, 0}}});
  expect_path(read("G0 X4 Y0 Z0\nG92 X0\nG52 X1\nG0 X0\n"), {{R, {1, 0, 0}}});
  // G53: this line in machine (workpiece-frame) coordinates, whatever the offsets.
  GcodeOptions options;
  options.work_offsets_mm["G54"] = Eigen::Vector3d(10, 20, 0);
  expect_path(read("G0 X0 Y0 Z0\nG53 G0 X3\nG0 Y1\n", options), {{R, {3, 20, 0}}, {R, {3, 21, 0}}});
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG91 G53 G0 X3\n").find("G53 in incremental mode"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG53 X3 G2 I1\n").find("G53"), std::string::npos);
  EXPECT_NE(error_of("G92 X0\n").find("unknown"), std::string::npos);
  // G43.1 / G43.2 take their axis words as tool length offsets: no move, no effect on the tip.
  expect_path(read("G0 X0 Y0 Z10\nG43.1 Z0.25\nG0 X1\nG43.2 H1\nG49 G0 X2\n"), {{R, {1, 0, 10}}, {R, {2, 0, 10}}});
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG43.1 G1 Z1\n").find("both use the axis words"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG92 G1 X0\n").find("both use the axis words"), std::string::npos);
}

// U V W: LinuxCNC's extra linear axes, read as its interpreter does on a 9-axis machine. The
// expected values are worked by hand from the rules of the G-code manual: G90 absolute plus the
// G5x and G92 offsets of that axis, G91 incremental, G20 in inches, G53 in machine coordinates,
// G28 to #5167..#5169, G10 L2 / L20 and G92 setting #5227.. / #5217...
TEST(Rs274ExtraAxes, PositionsOffsetsAndHome) {
  auto extra = [](const Block& b) {
    return Eigen::Vector3d(b.end_extra.value_mm[0], b.end_extra.value_mm[1], b.end_extra.value_mm[2]);
  };
  // A move of W alone is a motion (X Y Z stand still); the start carries the previous value.
  {
    // (The first move, from an unknown start, is dropped: `vcut program` starts at 0.)
    const Program p = read("G0 X1 Y2 Z3\nG1 W-5 F100\nG91 G1 W2 U1\nG90 G0 V4\n");
    ASSERT_EQ(p.blocks.size(), 3u);
    EXPECT_EQ(p.blocks[0].kind, F);
    EXPECT_FALSE(p.blocks[0].start_extra.any());
    EXPECT_LT((p.blocks[0].end_mm - Eigen::Vector3d(1, 2, 3)).norm(), kTol);
    EXPECT_LT((extra(p.blocks[0]) - Eigen::Vector3d(0, 0, -5)).norm(), kTol);
    EXPECT_LT((extra(p.blocks[1]) - Eigen::Vector3d(1, 0, -3)).norm(), kTol);  // G91: -5 + 2, 0 + 1
    EXPECT_EQ(p.blocks[1].start_extra.value_mm[2], -5.0);
    EXPECT_LT((extra(p.blocks[2]) - Eigen::Vector3d(1, 4, -3)).norm(), kTol);
    EXPECT_TRUE(p.blocks[2].end_extra.given[0] && p.blocks[2].end_extra.given[1] && p.blocks[2].end_extra.given[2]);
  }
  // Inches: W1 is 25.4 mm. An arc moves W linearly with the helix, like A B C.
  {
    const Program p = read("G20 G0 X0 Y0 Z0\nG2 X1 Y0 I0.5 J0 W1 F10\n");
    ASSERT_EQ(p.blocks.size(), 1u);
    EXPECT_EQ(p.blocks[0].kind, MotionKind::Arc);
    EXPECT_NEAR(p.blocks[0].end_extra.value_mm[2], 25.4, kTol);
  }
  // Offsets: G10 L2 P1 W10 puts W0 at 10; G92 W0 at W = 12 adds 2 (W1 -> 13); #5428 reads the
  // program coordinate back (13 - 10 - 2 = 1); G92.1 takes the 2 away; G53 W3 is machine 3.
  {
    const Program p =
        read("G0 X0 Y0 Z0\nG10 L2 P1 W10\nG0 W0\nG0 W2\nG92 W0\nG0 W1\nG0 X#5428\nG92.1\nG0 W1\nG53 G0 W3\n");
    ASSERT_EQ(p.blocks.size(), 6u);
    EXPECT_NEAR(p.blocks[0].end_extra.value_mm[2], 10.0, kTol);
    EXPECT_NEAR(p.blocks[1].end_extra.value_mm[2], 12.0, kTol);
    EXPECT_NEAR(p.blocks[2].end_extra.value_mm[2], 13.0, kTol);
    EXPECT_NEAR(p.blocks[3].end_mm.x(), 1.0, kTol);
    EXPECT_NEAR(p.blocks[4].end_extra.value_mm[2], 11.0, kTol);
    EXPECT_NEAR(p.blocks[5].end_extra.value_mm[2], 3.0, kTol);
  }
  // G10 L20 P0 U0 at U = 7 makes the current U the program's 0: U2 is then at 9.
  {
    const Program p = read("G0 X0 Y0 Z0 U7\nG10 L20 P0 U0\nG0 X1 U2\n");
    EXPECT_NEAR(p.blocks.back().end_extra.value_mm[0], 9.0, kTol);
  }
  // M72 brings back the coordinate system M70 saved, U V W's offsets with it (G55's W5 while
  // it is on: W1 at 6; back in G54: W1 at 1), as LinuxCNC's interpreter gives it.
  {
    const Program p = read("G0 X0 Y0 Z0\nG10 L2 P2 W5\nG0 W0\nM70\nG55\nG0 W1\nM72\nG0 W1\n");
    ASSERT_EQ(p.blocks.size(), 2u);
    EXPECT_NEAR(p.blocks[0].end_extra.value_mm[2], 6.0, kTol);
    EXPECT_NEAR(p.blocks[1].end_extra.value_mm[2], 1.0, kTol);
  }
  // G28: named axes through the intermediate point to #5161.. (here #5169 = 20); G28.1 stores
  // the current W; G28 alone sends W home too once the program moved it.
  {
    const Program p = read("G0 X0 Y0 Z0\n#5169 = 20\nG0 W5\nG28 W8\nG0 W1\nG28\n");
    ASSERT_EQ(p.blocks.size(), 5u);
    EXPECT_NEAR(p.blocks[1].end_extra.value_mm[2], 8.0, kTol);   // the intermediate point
    EXPECT_NEAR(p.blocks[2].end_extra.value_mm[2], 20.0, kTol);  // home
    EXPECT_NEAR(p.blocks[4].end_extra.value_mm[2], 20.0, kTol);
    const Program q = read("G0 X0 Y0 Z0 W6\nG28.1\nG0 W0\nG28 W0\n");
    EXPECT_NEAR(q.blocks.back().end_extra.value_mm[2], 6.0, kTol);
  }
  // A machine without the axis (a job's) refuses the word at its column; U V W are refused
  // where they cannot move (canned cycles, compensation, G43.1), each naming the column.
  GcodeOptions no_w;
  no_w.extra_axes = "UV";
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG1 X1 W2 F10\n", no_w).find("test.ngc:2:7: W word: the machine has no W axis"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nG81 X1 Y1 Z-1 R1 W3 F10\n").find(":2:18: U V W words on a canned cycle line"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG41.1 D1\nG1 X5 V1 F10\n").find(":3:7: U V W words on a cutter compensation"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG43.1 Z1 W1\n").find("U V W words on a G43.1 line"), std::string::npos);
}

// G43.1 sets the control's tool length: G28 puts the gauge point at home, so the programmed
// (tip) Z there is home - the offset, as LinuxCNC's interpreter prints it (cone.ngc's second
// pass: G43.1 Z50, then G91 G28 Z0 ends at Z-50). G49 ends it.
TEST(Rs274Offsets, DynamicToolLengthAndHome) {
  // (The first move and G91 G28 Z0's intermediate point do not move: dropped.)
  const Program p = read("G0 X0 Y0 Z10\nG43.1 Z50\nG91 G28 Z0\nG90 G49\nG28\n");
  ASSERT_EQ(p.blocks.size(), 2u);
  EXPECT_NEAR(p.blocks[0].end_mm.z(), -50.0, kTol);  // home: 0 - 50
  EXPECT_NEAR(p.blocks[1].end_mm.z(), 0.0, kTol);    // G49: the tip at home
  // G43.2 adds to a G43.1 offset: 50 + 5.
  const Program q = read("G0 X0 Y0 Z10\nG43.1 Z50\nG43.2 Z5\nG28 Z0\n");
  EXPECT_NEAR(q.blocks.back().end_mm.z(), -55.0, kTol);
}

TEST(Rs274Feed, InverseTime) {
  const Program p = read("G0 X0 Y0 Z0\nG93 G1 X10 F2\nG1 X20 F0.5\nG94 F100 G1 X30\n");
  ASSERT_EQ(p.blocks.size(), 3u);
  EXPECT_EQ(p.blocks[0].feed_mode, FeedMode::InverseTime);
  EXPECT_NEAR(p.blocks[0].feed_mm_per_min, 2.0, kTol);  // 1/F = 0.5 min for this move
  EXPECT_NEAR(p.blocks[1].feed_mm_per_min, 0.5, kTol);
  EXPECT_EQ(p.blocks[2].feed_mode, FeedMode::UnitsPerMinute);
  EXPECT_NEAR(p.blocks[2].feed_mm_per_min, 100.0, kTol);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG93 G1 X10 F2\nG1 X20\n").find("without F"), std::string::npos);
}

TEST(Rs274Modes, SaveRestoreToolAndUnitsOfF) {
  // M70 saves G91 and F100; after G90 F50, M72 brings back G91 and F100.
  Program p = read("G0 X0 Y0 Z0\nG91 F100\nM70\nG90 F50\nM72\nG1 X1\n");
  expect_path(p, {{F, {1, 0, 0}}});
  EXPECT_NEAR(p.blocks[0].feed_mm_per_min, 100.0, kTol);
  p = read("G0 X5 Y0 Z0\nG91 F100\nM70\nG90\nM72\nG1 X1\n");
  expect_path(p, {{F, {6, 0, 0}}});  // incremental again
  // M72 restores which coordinate system is active, with its offsets as they are at M72: G54's
  // X offset set to 5 after M70 stays (LinuxCNC's rs274 prints G0 X1 with SET_G5X_OFFSET X5).
  p = read("G0 X0 Y0 Z0\nM70\nG10 L2 P1 X5\nG55\nM72\nG0 X1\n");
  expect_path(p, {{R, {6, 0, 0}}});
  // ... and the G92 (and G52) offsets as they were at M70: rs274 prints SET_G92_OFFSET(-5) for
  // G92 X5 at X0 (X1 at -4), then SET_G92_OFFSET(0) at M72 (X2 at 2).
  p = read("G0 X0 Y0 Z0\nM70\nG92 X5\nG0 X1\nM72\nG0 X2\n");
  expect_path(p, {{R, {-4, 0, 0}}, {R, {2, 0, 0}}});
  p = read("G0 X0 Y0 Z0\nM70\nG52 X5\nG0 X1\nM72\nG0 X2\n");
  expect_path(p, {{R, {6, 0, 0}}, {R, {2, 0, 0}}});
  // M73 in a subroutine: its mode changes end with the call.
  p = read("o<s> sub\nM73\nG91\nG1 X1\no<s> endsub\nG0 X0 Y0 Z0\nF10\no<s> call\nG1 X3\n");
  expect_path(p, {{F, {1, 0, 0}}, {F, {3, 0, 0}}});  // G90 again after the call
  EXPECT_NE(error_of("M72\n").find("M70"), std::string::npos);
  // M61 Q: the tool in the spindle without a change.
  p = read("M61 Q7\nG0 X0 Y0 Z0\nG0 X1\n");
  EXPECT_EQ(p.blocks[0].tool, 7);
  // F on a G21 line is in the units before it (inch/min here): 10 in/min = 254 mm/min.
  p = read("G20 G0 X0 Y0 Z0\nG21 G1 X10 F10\n");
  ASSERT_EQ(p.blocks.size(), 1u);
  EXPECT_NEAR(p.blocks[0].feed_mm_per_min, 254.0, kTol);
  EXPECT_NEAR(p.blocks[0].end_mm.x(), 10.0, kTol);
  // Two M codes of one group on a line, M7 with M8 included, are refused as by rs274.
  EXPECT_NE(error_of("M7 M8\n").find("two M codes"), std::string::npos);
  // I/O M codes take their words and leave the path alone.
  p = read("G0 X0 Y0 Z0\nM64 P1\nM66 P0 L3 Q2\nM68 E0 Q0.5\nG0 X1\n");
  expect_path(p, {{R, {1, 0, 0}}});
  EXPECT_NE(error_of("G0 X0 E1\n").find("'E'"), std::string::npos);
}

// ------------------------------------------------------------------ tool centre point

TEST(Rs274Tcp, Blocks) {
  const Program p = read(
      "G0 X0 Y0 Z10 A0 C0\nF100\n"
      "G43.4 H1\nG1 X1 A30 C90\n"
      "G49\nG1 X2\n"
      "G43.5 H1\nG1 X3 I0 J3 K4\nK1\n");
  ASSERT_EQ(p.blocks.size(), 4u);
  // G43.4: a tool pose whose rotary words are the axes.
  EXPECT_TRUE(p.blocks[0].tool_pose);
  EXPECT_EQ(p.blocks[0].orientation, kinematics::OrientationMode::Axes);
  EXPECT_NEAR(p.blocks[0].end_rotary.angle_rad[0], 30 * M_PI / 180, kTol);
  EXPECT_NEAR(p.blocks[0].end_rotary.angle_rad[2], 90 * M_PI / 180, kTol);
  // G49: axis words again.
  EXPECT_FALSE(p.blocks[1].tool_pose);
  // G43.5: I J K normalised; K1 alone means (0, 0, 1): the components not given are 0.
  EXPECT_TRUE(p.blocks[2].tool_pose);
  EXPECT_LT((p.blocks[2].start_axis - Eigen::Vector3d(0, 0, 1)).norm(), kTol);
  EXPECT_LT((p.blocks[2].end_axis - Eigen::Vector3d(0, 0.6, 0.8)).norm(), kTol);
  EXPECT_LT((p.blocks[3].end_axis - Eigen::Vector3d(0, 0, 1)).norm(), kTol);
  EXPECT_LT((p.blocks[3].end_mm - p.blocks[3].start_mm).norm(), kTol);  // a turn in place
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nF100\nG43.5\nG1 X1 I0 J0 K0\n").find("zero length"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nF100\nG43.5\nG1 X1 A10\n").find("G43.5"), std::string::npos);
  // A job-mapped M code switches TCP like G43.4; unmapped it is an unknown M code.
  GcodeOptions options;
  options.tcp_m_codes = {{428, true}, {429, false}};
  const Program q = read("G0 X0 Y0 Z10 A0\nF100\nM428\nG1 X1 A10\nM429\nG1 X2\n", options);
  ASSERT_EQ(q.blocks.size(), 2u);
  EXPECT_TRUE(q.blocks[0].tool_pose);
  EXPECT_FALSE(q.blocks[1].tool_pose);
  // Unmapped: an M code the machine does not declare, a warning naming it (and the motion goes on).
  const Program r = read("G0 X0 Y0 Z10\nM428\nG0 X1\n");
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("test.ngc:2:1: M code M428 is not one the machine file declares"), std::string::npos);
}

// ------------------------------------------------------------------ canned cycles

TEST(Rs274Cycles, G81G98AndG99) {
  // From Z10: rapid over the hole, rapid to R2, feed to Z-5, back to the starting height
  // (G98) or to R (G99). The second hole, in G99, starts at R: no rapid down.
  expect_path(read("G0 X0 Y0 Z10\nF100\nG98 G81 X5 Y5 Z-5 R2\nG99 X8\nG80\n"), {{R, {5, 5, 10}},
                                                                                {R, {5, 5, 2}},
                                                                                {F, {5, 5, -5}},
                                                                                {R, {5, 5, 10}},
                                                                                {R, {8, 5, 10}},
                                                                                {R, {8, 5, 2}},
                                                                                {F, {8, 5, -5}},
                                                                                {R, {8, 5, 2}}});
  // Starting below R: first a rapid straight up to R.
  expect_path(read("G0 X0 Y0 Z0\nF100\nG81 X1 Z-1 R3\n"),
              {{R, {0, 0, 3}}, {R, {1, 0, 3}}, {F, {1, 0, -1}}, {R, {1, 0, 3}}});
  // G91 with L3: R from the current Z (5 - 3 = 2), Z from R (2 - 4 = -2), holes 2 mm apart.
  const Program p = read("G0 X0 Y0 Z5\nF100\nG91 G99 G81 X2 R-3 Z-4 L3\n");
  expect_path(p, {{R, {2, 0, 5}},
                  {R, {2, 0, 2}},
                  {F, {2, 0, -2}},
                  {R, {2, 0, 2}},
                  {R, {4, 0, 2}},
                  {F, {4, 0, -2}},
                  {R, {4, 0, 2}},
                  {R, {6, 0, 2}},
                  {F, {6, 0, -2}},
                  {R, {6, 0, 2}}});
  EXPECT_NEAR(p.blocks[2].feed_mm_per_min, 100.0, kTol);
}

TEST(Rs274Cycles, PeckingG83AndG73) {
  // Q2 from R1 to Z-5: pecks to -1 and -3, then the bottom. G83 retracts to R after each
  // peck and comes back to 0.254 mm (0.010 in) above it; G73 only backs off 0.254 mm.
  expect_path(read("G0 X0 Y0 Z5\nF100\nG98 G83 Z-5 R1 Q2\n"), {{R, {0, 0, 1}},
                                                               {F, {0, 0, -1}},
                                                               {R, {0, 0, 1}},
                                                               {R, {0, 0, -0.746}},
                                                               {F, {0, 0, -3}},
                                                               {R, {0, 0, 1}},
                                                               {R, {0, 0, -2.746}},
                                                               {F, {0, 0, -5}},
                                                               {R, {0, 0, 5}}});
  expect_path(read("G0 X0 Y0 Z5\nF100\nG98 G73 Z-5 R1 Q2\n"), {{R, {0, 0, 1}},
                                                               {F, {0, 0, -1}},
                                                               {R, {0, 0, -0.746}},
                                                               {F, {0, 0, -3}},
                                                               {R, {0, 0, -2.746}},
                                                               {F, {0, 0, -5}},
                                                               {R, {0, 0, 5}}});
}

TEST(Rs274Cycles, BoringG85AndDwellG82G89) {
  // G85 feeds back out to R, then rapids to the G98 height; G89 feeds all the way out to the
  // G98 height (rs274 prints STRAIGHT_FEED to the initial Z for G98 G89).
  expect_path(read("G0 X0 Y0 Z5\nF100\nG98 G85 Z-2 R1\n"),
              {{R, {0, 0, 1}}, {F, {0, 0, -2}}, {F, {0, 0, 1}}, {R, {0, 0, 5}}});
  expect_path(read("G0 X0 Y0 Z5\nF100\nG99 G89 Z-2 R1 P0.5\n"), {{R, {0, 0, 1}}, {F, {0, 0, -2}}, {F, {0, 0, 1}}});
  expect_path(read("G0 X0 Y0 Z5\nF100\nG98 G89 Z-2 R1 P0.5\n"), {{R, {0, 0, 1}}, {F, {0, 0, -2}}, {F, {0, 0, 5}}});
  expect_path(read("G0 X0 Y0 Z5\nF100\nG98 G82 Z-2 R1 P0.5\n"), {{R, {0, 0, 1}}, {F, {0, 0, -2}}, {R, {0, 0, 5}}});
  // Without G98 or G99 the return is rs274's power-on G99 (LinuxCNC 2.9's rs274 on
  // "G0 Z5 / G81 Z-1 R1" retracts to R1); Fanuc's power-on mode is G98.
  expect_path(read("G0 X0 Y0 Z5\nF100\nG81 Z-2 R1\n"), {{R, {0, 0, 1}}, {F, {0, 0, -2}}, {R, {0, 0, 1}}});
  GcodeOptions fanuc;
  fanuc.flavor = GcodeOptions::Flavor::Fanuc;
  expect_path(read("G0 X0 Y0 Z5\nF100\nG81 Z-2 R1\n", fanuc), {{R, {0, 0, 1}}, {F, {0, 0, -2}}, {R, {0, 0, 5}}});
}

TEST(Rs274Polar, DistanceAndAngle) {
  // G90: @ and ^ about the program origin; the one not given keeps the current point's.
  expect_path(read("G0 X10 Y0 Z0\nG0 ^90\nG0 @5\nG0 @2 ^180\n"), {{R, {0, 10, 0}}, {R, {0, 5, 0}}, {R, {-2, 0, 0}}});
  // G91: both add to the current point's distance and angle.
  expect_path(read("G0 X10 Y0 Z0\nG91 G0 ^90\nG0 @-4\n"), {{R, {0, 10, 0}}, {R, {0, 6, 0}}});
  // A bolt circle: G91 G81 turning 120 deg per hole from (15, 0); R from the series' start Z0.
  const double s = 15 * std::sqrt(3.0) / 2;
  expect_path(read("G0 X15 Y0 Z0\nG91 G81 R1 Z-5 ^120 L3 F10\n"), {{R, {15, 0, 1}},
                                                                   {R, {-7.5, s, 1}},
                                                                   {F, {-7.5, s, -4}},
                                                                   {R, {-7.5, s, 1}},
                                                                   {R, {-7.5, -s, 1}},
                                                                   {F, {-7.5, -s, -4}},
                                                                   {R, {-7.5, -s, 1}},
                                                                   {R, {15, 0, 1}},
                                                                   {F, {15, 0, -4}},
                                                                   {R, {15, 0, 1}}});
  EXPECT_NE(error_of("G0 @1\n").find("unknown"), std::string::npos);
}

TEST(Rs274Cycles, IncrementalRCountsFromTheSeriesStart) {
  // rs274: a G91 cycle line that continues a series takes R from the height the series began
  // at (Z0 here), not from where the previous hole left the tool (R = 1).
  expect_path(read("G0 X0 Y0 Z0\nF10\nG91 G81 X1 R1 Z-5\nX1\n"), {{R, {0, 0, 1}},
                                                                  {R, {1, 0, 1}},
                                                                  {F, {1, 0, -4}},
                                                                  {R, {1, 0, 1}},
                                                                  {R, {2, 0, 1}},
                                                                  {F, {2, 0, -4}},
                                                                  {R, {2, 0, 1}}});
}

TEST(Rs274Cycles, Errors) {
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nF100\nG81 Z-2\n").find("without R"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nF100\nG81 Z2 R1\n").find("above R"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nF100\nG83 Z-2 R1\n").find("Q > 0"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nG81 Z-2 R1\n").find("without F"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0\nF100\nG81 Z-2 R1\n").find("unknown Z"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z5\nF100\nG18 G81 Z-2 R1\n").find("XY plane"), std::string::npos);
}

}  // namespace
}  // namespace vcut::io
