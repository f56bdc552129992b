// Fanuc custom macro B in the G-code reader. Expected values are worked by hand from the Fanuc
// Custom Macro B rules (the manual's: vacant #0, locals per G65 call, AND binding like *, FIX
// toward zero) or are closed forms (the sum 1 + ... + 10).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "gcode_text.h"
#include "vcut/io/gcode_reader.h"
#include "vcut/io/input_error.h"
#include "vcut/io/program_reader.h"

namespace vcut::io {
namespace {

using kinematics::Program;
namespace fs = std::filesystem;

// Fanuc's flavour, from 0.
GcodeOptions fanuc(GcodeOptions options) {
  options.flavor = GcodeOptions::Flavor::Fanuc;
  options.start_mm = Eigen::Vector3d::Zero();
  return options;
}
Program read(const std::string& text, const GcodeOptions& options = {}) {
  return gcode_test::read_text(text, fanuc(options), "macro.nc");
}
std::string error_of(const std::string& text, const GcodeOptions& options = {}) {
  return gcode_test::error_text(text, fanuc(options), "macro.nc");
}

Eigen::Vector3d last_end(const Program& p) {
  return p.blocks.empty() ? Eigen::Vector3d::Constant(-999) : p.blocks.back().end_mm;
}

TEST(FanucMacro, WhileLoopSumsOneToTen) {
  const Program p = read("#1=0\n#2=1\nWHILE[#2LE10]DO1\n#1=#1+#2\n#2=#2+1\nEND1\nG0 X#1\nM30\n");
  EXPECT_EQ(last_end(p), Eigen::Vector3d(55, 0, 0));
}

TEST(FanucMacro, IfGotoCountsDown) {
  // Three passes through N10 (X 3, 2, 1), then N20.
  const Program p = read("#1=3\nN10 IF[#1LE0]GOTO20\nG0 X#1\n#1=#1-1\nGOTO10\nN20 G0 Y9\nM30\n");
  ASSERT_EQ(p.blocks.size(), 4u);
  EXPECT_EQ(p.blocks[0].end_mm.x(), 3.0);
  EXPECT_EQ(p.blocks[2].end_mm.x(), 1.0);
  EXPECT_EQ(last_end(p), Eigen::Vector3d(1, 9, 0));
  // GOTO #i, and a target before the GOTO found from the top of the file.
  EXPECT_EQ(last_end(read("#5=30\nGOTO#5\nN20 G0 X1\nM30\nN30 G0 X2\nGOTO 20\n")), Eigen::Vector3d(1, 0, 0));
}

TEST(FanucMacro, G65ArgumentsAreLocalsOfTheCall) {
  // A -> #1, B -> #2, X -> #24; the caller's #1 comes back after M99; the macro's own #3 (no C
  // given) is vacant.
  const Program p = read("#1=7\nG65 P9001 A2 B3 X4\nG0 Y#1\nM30\nO9001\nG0 X[#1*#2+#24]\nIF[#3EQ#0]THEN#100=1\nM99\n");
  ASSERT_EQ(p.blocks.size(), 2u);
  EXPECT_EQ(p.blocks[0].end_mm.x(), 10.0);
  EXPECT_EQ(last_end(p), Eigen::Vector3d(10, 7, 0));
  // L repeats the call: the common #100 counts the passes.
  EXPECT_EQ(last_end(read("#100=0\nG65 P9002 L4\nG0 X#100\nM30\nO9002\n#100=#100+1\nM99\n")), Eigen::Vector3d(4, 0, 0));
}

TEST(FanucMacro, G66CallsTheMacroAfterEachMoveUntilG67) {
  // G66 P9000 Z-5 R2 F100: Z -> #26, R -> #18, F -> #9. After X10 and after X20 the macro
  // drills (G1 to Z-5, G0 back to Z2); its own moves call nothing; after G67, X30 is a move.
  const Program p = read(
      "G90 G0 X0 Y0 Z10\nG66 P9000 Z-5. R2. F100.\nX10.\nX20.\nG67\nX30.\nM30\n"
      "O9000\nG1 Z#26 F#9\nG0 Z#18\nM99\n");
  const std::vector<Eigen::Vector3d> want = {{0, 0, 10}, {10, 0, 10}, {10, 0, -5}, {10, 0, 2},
                                             {20, 0, 2}, {20, 0, -5}, {20, 0, 2},  {30, 0, 2}};
  ASSERT_EQ(p.blocks.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) EXPECT_EQ(p.blocks[k].end_mm, want[k]) << "block " << k;
  EXPECT_EQ(p.blocks[2].kind, kinematics::MotionKind::Linear);
  EXPECT_EQ(p.blocks[2].feed_mm_per_min, 100.0);
  EXPECT_EQ(p.blocks[2].source.line, 9);                       // from the macro's line
  EXPECT_EQ(p.blocks[4].kind, kinematics::MotionKind::Rapid);  // the G0 the macro left
  // A second G66, a call on a moving line, and a macro found nowhere are errors.
  EXPECT_NE(error_of("G66 P9000\nG66 P9000\nM30\nO9000\nM99\n").find("macro.nc:2:1: G66 while a modal call is on"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0\nG66 P9000\nX1 M98 P9000\nM30\nO9000\nM99\n")
                .find("macro.nc:3:4: M98 on a line that calls the G66 macro"),
            std::string::npos);
  EXPECT_NE(error_of("G66 P9123\nM30\n").find("macro.nc:1:5: G66 P9123: program O9123 found nowhere"),
            std::string::npos);
}

TEST(FanucMacro, VacantValues) {
  // #1 never set: EQ #0 is true, EQ 0 is not; in arithmetic it counts as 0.
  const Program p = read("IF[#1EQ#0]THEN#10=1\nIF[#1EQ0]THEN#11=1\n#12=#1+5\n#13=#0\nG0 X#10 Y#12\nM30\n");
  EXPECT_EQ(last_end(p), Eigen::Vector3d(1, 5, 0));
  // A vacant value where a number is needed is an error naming the word.
  const std::string e = error_of("IF[#1EQ0]THEN#11=1\nG0 Z#11\n");
  EXPECT_NE(e.find("macro.nc:2:4: vacant value in the Z word"), std::string::npos) << e;
}

TEST(FanucMacro, OperatorsAndFunctions) {
  // * before +; AND binds like *, OR like +: 5 OR [2 AND 3] = 5 OR 2 = 7; 6 AND 3 = 2 (bits).
  EXPECT_EQ(last_end(read("#1=2+3*4\n#2=5 OR 2 AND 3\n#3=6 AND 3\nG0 X#1 Y#2 Z#3\n")), Eigen::Vector3d(14, 7, 2));
  // POW[2,10] = 1024; ATAN[1,1] = 45 deg; BIN[18] (BCD 0x12) = 12; BCD[12] = 0x12 = 18.
  EXPECT_EQ(last_end(read("G0 X[POW[2,10]] Y[ATAN[1,1]] Z[BIN[18]]\nG0 A[BCD[12]]\n")).head<3>(),
            Eigen::Vector3d(1024, 45, 12));
  // FIX and FUP on the magnitude: FIX[-1.5] = -1, FUP[-1.2] = -2, FUP[1.2] = 2; ROUND[2.5] = 3.
  EXPECT_EQ(last_end(read("G0 X[FIX[-1.5]] Y[FUP[-1.2]+FUP[1.2]] Z[ROUND[2.5]]\n")), Eigen::Vector3d(-1, 0, 3));
  EXPECT_NE(error_of("#1=1/0\n").find("division by zero"), std::string::npos);
}

TEST(FanucMacro, SubprogramsM98M97M99) {
  // M98 P20003: Fanuc's count in P, O0003 twice; M98 P3 L3 three times more; M97 P50 the block
  // N50 of this program; M99 P40 returns to N40.
  const Program p = read(
      "#100=0\nM98 P20003\nM98 P3 L3\nM97 P50\nG0 X#100\nM30\nN40 G0 Y#100\nM30\nN50 #100=#100+100\nM99\n"
      "O0003\n#100=#100+1\nM99\n");
  EXPECT_EQ(last_end(p), Eigen::Vector3d(105, 0, 0));
  EXPECT_EQ(last_end(read("M98 P7\nG0 X1\nM30\nN40 G0 Y2\nM30\nO0007\nM99 P40\n")), Eigen::Vector3d(0, 2, 0));
  // M99 in the main program: read once, with a warning.
  const Program once = read("G0 X1\nM99\n");
  ASSERT_EQ(once.warnings.size(), 1u);
  EXPECT_NE(once.warnings[0].find("M99 in the main program"), std::string::npos);
}

// What follows the main program's end (its closing '%', or M99 read once) is read only to find
// subprograms: a program there that nothing called is not run, and a warning says so (a real
// file held a subprogram, then the main program that calls it, each between '%' lines: only
// the subprogram ran). Programs there that were called, and blanks and comments, say nothing.
TEST(FanucMacro, ProgramsAfterTheMainProgramsEnd) {
  const Program sub_first = read("%\nO1000\nG0 X1\nM99\n%\n\n%\nO0001 (MAIN)\nM98 P1000\nG0 Z50\nM30\n%\n");
  ASSERT_EQ(sub_first.blocks.size(), 1u);  // O1000's move, read once as the main program
  ASSERT_EQ(sub_first.warnings.size(), 2u);
  EXPECT_NE(sub_first.warnings[0].find("macro.nc:4:1: M99 in the main program"), std::string::npos);
  EXPECT_NE(sub_first.warnings[1].find("macro.nc:8:1: program O0001 after the main program's end on line 4 is "
                                       "not run"),
            std::string::npos)
      << sub_first.warnings[1];
  // After a closing '%': a called subprogram is run and says nothing; an uncalled one warns.
  const Program called = read("%\nO0001\nM98 P1000\nG0 X3\n%\n(SUBS)\n%\nO1000\nG0 Y2\nM99\n%\n");
  EXPECT_EQ(last_end(called), Eigen::Vector3d(3, 2, 0));
  EXPECT_TRUE(called.warnings.empty());
  const Program uncalled = read("%\nO0001\nG0 X1\n%\nO2000\nG0 Y2\nM99\n");
  EXPECT_EQ(last_end(uncalled), Eigen::Vector3d(1, 0, 0));
  ASSERT_EQ(uncalled.warnings.size(), 1u);
  EXPECT_NE(uncalled.warnings[0].find("macro.nc:5:1: program O2000 after the main program's end on line 4"),
            std::string::npos);
  // Blocks outside any program after the '%'.
  const Program stray = read("%\nG0 X1\n%\n\nG0 X5\n");
  EXPECT_EQ(last_end(stray), Eigen::Vector3d(1, 0, 0));
  ASSERT_EQ(stray.warnings.size(), 1u);
  EXPECT_NE(stray.warnings[0].find("macro.nc:5:1: this line and those after it follow the main program's end on "
                                   "line 3: not run"),
            std::string::npos);
}

TEST(FanucMacro, ProgramFileOnTheSearchPath) {
  const fs::path dir = fs::temp_directory_path() / ("vcut_fanuc_" + std::to_string(::getpid()));
  fs::create_directories(dir / "subs");
  std::ofstream(dir / "subs" / "O1234.nc") << "%\nO1234 (SUB)\nG0 X#24\nM99\n%\n";
  std::ofstream(dir / "subs" / "anything.nc") << "O4321\nG0 Y#25\nM99\n";
  std::ofstream(dir / "main.nc") << "G65 P1234 X8\nG65 P4321 Y9\nM30\n";
  GcodeOptions options;
  options.subroutine_path = {(dir / "subs").string()};
  options.start_mm = Eigen::Vector3d::Zero();
  options.flavor = GcodeOptions::Flavor::Fanuc;
  const Program p = read_gcode((dir / "main.nc").string(), options);
  EXPECT_EQ(last_end(p), Eigen::Vector3d(8, 9, 0));
  // Not found: the error names what was searched.
  std::ofstream(dir / "bad.nc") << "M98 P555\n";
  try {
    read_gcode((dir / "bad.nc").string(), options);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("bad.nc:1:1: M98 P555: program O0555 found nowhere"), std::string::npos) << m;
    EXPECT_NE(m.find((dir / "subs").string()), std::string::npos) << m;
  }
  // A G-code file that reads like Fanuc macro B is read as one (vacant #1 EQ #0).
  std::ofstream(dir / "auto.nc") << "IF[#1EQ#0]GOTO10\nG0 X1\nN10 G0 Y1\nM30\n";
  ProgramOptions from_zero;
  from_zero.gcode.start_mm = Eigen::Vector3d::Zero();
  const LoadedProgram loaded = read_program((dir / "auto.nc").string(), Dialect::Auto, from_zero);
  ASSERT_EQ(loaded.program.blocks.size(), 1u);
  EXPECT_EQ(loaded.program.blocks[0].end_mm, Eigen::Vector3d(0, 1, 0));
  // So is one whose only macro is an alarm #3000 (rs274ngc would take it as a plain parameter
  // and run on).
  std::ofstream(dir / "alarm.nc") << "O1000\nG0 X1\n#3000 = 1 (TOOL BROKEN)\nM30\n";
  try {
    read_program((dir / "alarm.nc").string(), Dialect::Auto, from_zero);
    ADD_FAILURE() << "no alarm";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("alarm.nc:3:1: alarm #3000 = 1: TOOL BROKEN"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(FanucMacro, AlarmsStopsAndBadFlow) {
  EXPECT_NE(error_of("G0 X1\n#3000=12 (TOOL BROKEN)\n").find("macro.nc:2:1: alarm #3000 = 12: TOOL BROKEN"),
            std::string::npos);
  const Program stop = read("#3006=1 (CHECK PART)\nG0 X1\n");
  ASSERT_EQ(stop.warnings.size(), 1u);
  EXPECT_NE(stop.warnings[0].find("stop #3006: CHECK PART"), std::string::npos);
  EXPECT_NE(error_of("GOTO 99\n").find("macro.nc:1:1: GOTO 99: no block N99"), std::string::npos);
  EXPECT_NE(error_of("END1\n").find("END1 without WHILE"), std::string::npos);
  EXPECT_NE(error_of("WHILE[1EQ2]DO1\nG0 X1\n").find("the file ends inside WHILE [...] DO1 opened at macro.nc:1"),
            std::string::npos);
  // A loop that never ends stops at max_lines, naming the line.
  GcodeOptions limited;
  limited.max_lines = 1000;
  EXPECT_NE(error_of("N1 G0 X1\nGOTO1\n", limited).find("read 1000 lines without reaching the end"), std::string::npos);
  EXPECT_NE(error_of("#5001=1\n").find("system variable the program cannot set"), std::string::npos);
  // System variables: the position and the modes.
  EXPECT_EQ(last_end(read("G0 X5 Y6\nG91\n#1=#5001+#4003\nG90 G0 X#1\n")), Eigen::Vector3d(96, 6, 0));
}

}  // namespace
}  // namespace vcut::io
