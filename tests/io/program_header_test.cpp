// What a program's comments declare (io/program_header.h) and LinuxCNC tool tables
// (io/tool_table.h). Expected values are the comments' numbers converted by hand.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "vcut/io/camotics_project.h"
#include "vcut/io/input_error.h"
#include "vcut/io/program_header.h"
#include "vcut/io/tool_table.h"

namespace {
namespace fs = std::filesystem;
using vcut::removal::CutterType;

std::string write_temp(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("vcut_header_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

vcut::io::ProgramHeader header_of(const std::string& text, const std::string& name = "p.nc") {
  const std::string path = write_temp(name, text);
  vcut::io::ProgramHeader h = vcut::io::read_program_header(path);
  fs::remove(path);
  return h;
}

// Fusion 360's tool table lines: the shape from the last words, the taper as a chamfer mill's
// half angle and a drill's point angle.
TEST(ProgramHeader, FusionToolLines) {
  const auto h = header_of(
      "%\n(T1 D=6. CR=0. - ZMIN=-5. - flat end mill)\n(T2 D=8 CR=4 - ZMIN=-3 - ball end mill)\n"
      "(T3 D=10 CR=1 - ZMIN=-2 - bull nose end mill)\n(T4 D=6 CR=0 TAPER=45deg - ZMIN=-1 - chamfer mill)\n"
      "(T5 D=5 CR=0 TAPER=118deg - ZMIN=-9 - drill)\nG21\nT1 M6\nG1 X1 F100\n");
  ASSERT_EQ(h.tools.size(), 5u);
  EXPECT_EQ(h.tools.at(1).cutter.type, CutterType::Flat);
  EXPECT_DOUBLE_EQ(h.tools.at(1).cutter.diameter_mm, 6.0);
  EXPECT_EQ(h.tools.at(2).cutter.type, CutterType::Ball);
  EXPECT_DOUBLE_EQ(h.tools.at(2).cutter.corner_radius_mm, 4.0);
  EXPECT_EQ(h.tools.at(3).cutter.type, CutterType::BullNose);
  EXPECT_DOUBLE_EQ(h.tools.at(3).cutter.corner_radius_mm, 1.0);
  EXPECT_EQ(h.tools.at(4).cutter.type, CutterType::VBit);
  EXPECT_DOUBLE_EQ(h.tools.at(4).cutter.tip_angle_deg, 90.0);
  EXPECT_EQ(h.tools.at(5).cutter.type, CutterType::VBit);
  EXPECT_DOUBLE_EQ(h.tools.at(5).cutter.tip_angle_deg, 118.0);
  EXPECT_EQ(h.tools.at(1).form, "Fusion");
  EXPECT_NE(h.tools.at(1).where.find(":2"), std::string::npos);
  EXPECT_FALSE(h.inch);
  EXPECT_EQ(h.first_tool, 1);
  EXPECT_FALSE(h.stock);
}

// Values without a unit are in the program's units: G20 makes D=0.25 a 6.35 mm tool and the
// stock 3.6 x 2 x 1 in 91.44 x 50.8 x 25.4 mm; an explicit IN stays inches in an mm program.
TEST(ProgramHeader, ProgramUnitsAndExplicitUnits) {
  const auto inch = header_of("(STOCK = 3.6 X 2. X 1.)\n(T1 D=0.25 CR=0. - ZMIN=-0.2 - flat end mill)\nG20 G90\n");
  ASSERT_TRUE(inch.stock);
  EXPECT_TRUE(inch.inch);
  EXPECT_FALSE(inch.stock->placed);
  EXPECT_NEAR(inch.stock->size_mm.x(), 91.44, 1e-9);
  EXPECT_NEAR(inch.stock->size_mm.y(), 50.8, 1e-9);
  EXPECT_NEAR(inch.stock->size_mm.z(), 25.4, 1e-9);
  EXPECT_NEAR(inch.tools.at(1).cutter.diameter_mm, 6.35, 1e-9);
  const auto mm = header_of("(STOCK 6061AL DX 3.50IN DY 2.50IN DZ 0.75IN, AFTER SQUARING)\nG21\n");
  ASSERT_TRUE(mm.stock);
  EXPECT_NEAR(mm.stock->size_mm.x(), 88.9, 1e-9);
  EXPECT_NEAR(mm.stock->size_mm.y(), 63.5, 1e-9);
  EXPECT_NEAR(mm.stock->size_mm.z(), 19.05, 1e-9);
  // An allowance is not a stock.
  EXPECT_FALSE(header_of("(T1 | 1/2 FLAT ENDMILL | H1 | XY STOCK TO LEAVE - 0. | Z STOCK TO LEAVE - 0.)\n").stock);
}

// CutViewer's STOCK/BLOCK places the stock: program zero at (ox, oy, oz) from its low corner;
// its TOOL/MILL is the tool of the next T word. Carbide Create writes both forms.
TEST(ProgramHeader, CutViewerAndCarbideCreate) {
  const auto h = header_of(
      "(STOCK/BLOCK,100.00, 60.00, 10.00, 20.00, 30.00, 10.00)\nG21\n(TOOL/MILL,6.35, 0.00, 20.00, 0.00)\nM6T102\n"
      "(TOOL/MILL,3.175, 1.5875, 12.00, 0.00)\nG0 Z5\nM6 T7\n(TOOL/MILL,0.1, 0, 5, 30)\nT8 M6\n");
  ASSERT_TRUE(h.stock);
  EXPECT_TRUE(h.stock->placed);
  EXPECT_EQ(h.stock->min_mm, Eigen::Vector3d(-20, -30, -10));
  EXPECT_EQ(h.stock->size_mm, Eigen::Vector3d(100, 60, 10));
  ASSERT_EQ(h.tools.size(), 3u);
  EXPECT_EQ(h.tools.at(102).cutter.type, CutterType::Flat);
  EXPECT_DOUBLE_EQ(h.tools.at(102).flute_length_mm, 20.0);
  EXPECT_EQ(h.tools.at(7).cutter.type, CutterType::Ball);  // corner radius = d / 2
  EXPECT_EQ(h.tools.at(8).cutter.type, CutterType::VBit);  // a taper of 30 deg: 60 deg included
  EXPECT_DOUBLE_EQ(h.tools.at(8).cutter.tip_angle_deg, 60.0);
  // Each value in its own unit: max (4, 1, 0) in = (101.6, 25.4, 0) mm.
  const auto carbide = header_of("(stockMin:0.00mm, -5.00mm, -1.00mm)\n(stockMax:4.00in, 1.00in, 0.00in)\n");
  ASSERT_TRUE(carbide.stock);
  EXPECT_EQ(carbide.stock->min_mm, Eigen::Vector3d(0, -5, -1));
  EXPECT_NEAR(carbide.stock->size_mm.x(), 101.6, 1e-9);
  EXPECT_NEAR(carbide.stock->size_mm.y(), 30.4, 1e-9);
  EXPECT_NEAR(carbide.stock->size_mm.z(), 1.0, 1e-9);
}

// Vectric's Material Size (program units), its tool names with {size}, CamBam's "T1 : d", and
// a diameter in the tool change's own comment.
TEST(ProgramHeader, VectricCamBamAndToolChangeComments) {
  const auto h = header_of(
      "( Material Size)\n( X= 24.000, Y= 12.000, Z= 0.750)\n(T2 = End Mill {0.25 inches})\n( T3 : 3.175 )\n"
      "G20\nT5 M06 ( 19.1mm CHAMDRILL )\nT6 M6 (ISO 1.5 THREAD MILL)\n");
  ASSERT_TRUE(h.stock);
  EXPECT_NEAR(h.stock->size_mm.x(), 609.6, 1e-9);
  EXPECT_NEAR(h.stock->size_mm.z(), 19.05, 1e-9);
  EXPECT_NEAR(h.tools.at(2).cutter.diameter_mm, 6.35, 1e-9);
  EXPECT_NEAR(h.tools.at(3).cutter.diameter_mm, 3.175 * 25.4, 1e-9);  // CamBam's number in program units
  EXPECT_NEAR(h.tools.at(5).cutter.diameter_mm, 19.1, 1e-9);
  EXPECT_EQ(h.tools.at(5).cutter.type, CutterType::VBit);
  EXPECT_EQ(h.tools.count(6), 0u);  // no unit, no diameter
  EXPECT_EQ(h.tool_numbers, (std::set<int>{5, 6}));
}

// SolidWorks CAM's CL data declares its stock in an INSERT/; UNITS/INCHES makes it inches.
TEST(ProgramHeader, AptInsertStockSize) {
  const auto mm = header_of("PARTNO/1\nUNIT/MM\nINSERT/Stock Size X465.40922 Y243.942457 Z6.\nGOTO/1,2,3\n", "p.apt");
  ASSERT_TRUE(mm.stock);
  EXPECT_FALSE(mm.stock->placed);
  EXPECT_NEAR(mm.stock->size_mm.x(), 465.40922, 1e-9);
  EXPECT_NEAR(mm.stock->size_mm.y(), 243.942457, 1e-9);
  EXPECT_NEAR(mm.stock->size_mm.z(), 6.0, 1e-9);
  const auto inch = header_of("UNITS/INCHES\n$$ STOCK SIZE X 4 Y 2 Z 1\n", "q.apt");
  ASSERT_TRUE(inch.stock);
  EXPECT_NEAR(inch.stock->size_mm.x(), 101.6, 1e-9);
}

// Rotary words in the code, not in comments or inside function names.
TEST(ProgramHeader, RotaryLetters) {
  EXPECT_EQ(header_of("(A90 in a comment)\nG1 X1 A90 F100\n#1=ABS[-2]\nG1 X[ATAN[1]/[1]]\n").rotary_letters,
            (std::set<char>{'A'}));
  EXPECT_EQ(header_of("G1 X1 B-30.5 C10\n").rotary_letters, (std::set<char>{'B', 'C'}));
  EXPECT_TRUE(header_of("G1 X1 Y2 Z3 F100 ; C5 in a comment\n").rotary_letters.empty());
}

// A stock form with a zero size or the wrong count is an error naming file:line:column.
TEST(ProgramHeader, BadStockIsAnError) {
  const std::string path = write_temp("bad.nc", "G21\n  (STOCK/BLOCK, 100, 0, 10, 0, 0, 10)\n");
  try {
    vcut::io::read_program_header(path);
    FAIL() << "a zero-width stock was accepted";
  } catch (const vcut::InputError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.column(), 4);
    EXPECT_NE(std::string(e.what()).find("greater than 0"), std::string::npos) << e.what();
  }
  const std::string four = write_temp("four.nc", "(STOCK/BLOCK, 100, 50, 10, 0)\n");
  EXPECT_THROW(vcut::io::read_program_header(four), vcut::InputError);
  fs::remove(path);
  fs::remove(four);
}

// LinuxCNC's tool table: D and Z in the machine's units, the shape from the comment.
TEST(ToolTable, LinuxCncTbl) {
  const std::string path = write_temp("t.tbl",
                                      "T1 P1 D6.35 Z+25.4 ;1/4 end mill\nT2 P2 X0 Z10 D0.5 ;ball nose\n"
                                      "T99 P99 Z0 D0 ;probe\n\n");
  const auto inch = vcut::io::read_tool_table(path, 25.4);
  ASSERT_EQ(inch.size(), 2u);  // the probe (D0) left out
  EXPECT_NEAR(inch.at(1).cutter.diameter_mm, 6.35 * 25.4, 1e-9);
  EXPECT_NEAR(inch.at(1).z_offset_mm, 25.4 * 25.4, 1e-9);
  EXPECT_EQ(inch.at(1).cutter.type, CutterType::Flat);
  EXPECT_EQ(inch.at(2).cutter.type, CutterType::Ball);
  EXPECT_NEAR(inch.at(2).cutter.corner_radius_mm, 0.25 * 25.4, 1e-9);
  fs::remove(path);
  const std::string bad = write_temp("bad.tbl", "T1 P1 D6\nT2 P2 Dx\n");
  try {
    vcut::io::read_tool_table(bad);
    FAIL() << "D without a number was accepted";
  } catch (const vcut::InputError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.column(), 7);
  }
  fs::remove(bad);
}

// A CAMotics project read as a job: each tool in its own units (0.125 in ball = 3.175 mm; a
// conical tool of diameter 10 and length 12.071068 has 2 atan(5 / 12.071068) = 45 deg
// included), the workpiece bounds and the resolution in mm, files beside the project.
TEST(CamoticsProject, ReadAsAJob) {
  const std::string path = write_temp("p.camotics",
                                      R"({"units": "imperial", "resolution-mode": "manual", "resolution": 0.5,
  "tools": {"1": {"units": "imperial", "shape": "ballnose", "length": 1, "diameter": 0.125, "description": ""},
            "30": {"units": "metric", "shape": "conical", "length": 12.071068, "diameter": 10}},
  "workpiece": {"automatic": true, "margin": 5, "bounds": {"min": [-227.8, -228.2, -13.5], "max": [227.5, 228, 0]}},
  "files": ["aztec.nc"]})");
  const vcut::io::Job job = vcut::io::read_camotics_project(path);
  EXPECT_EQ(job.machine, "3axis");
  ASSERT_EQ(job.tools.size(), 2u);
  EXPECT_EQ(job.tools.at(1).type, CutterType::Ball);
  EXPECT_NEAR(job.tools.at(1).diameter_mm, 3.175, 1e-12);
  EXPECT_NEAR(job.tools.at(1).flute_length_mm, 25.4, 1e-12);
  EXPECT_EQ(job.tools.at(30).type, CutterType::VBit);
  EXPECT_NEAR(job.tools.at(30).tip_angle_deg, 45.0, 1e-5);
  EXPECT_EQ(job.stock.box.min_mm, Eigen::Vector3d(-227.8, -228.2, -13.5));
  EXPECT_EQ(job.stock.box.max_mm, Eigen::Vector3d(227.5, 228, 0));
  EXPECT_DOUBLE_EQ(job.resolution_mm, 0.5);
  ASSERT_EQ(job.program_files.size(), 1u);
  EXPECT_EQ(fs::path(job.program_files[0]), fs::path(path).parent_path() / "aztec.nc");
  EXPECT_FALSE(job.assumptions.empty());
  fs::remove(path);
}

// Not JSON: the line and column where parsing stopped; shapes vcut has no cutter for.
TEST(CamoticsProject, BadInput) {
  const std::string broken = write_temp("broken.camotics", "{\n  \"files\": [\"a.nc\"],\n  \"tools\": {,}\n}\n");
  try {
    vcut::io::read_camotics_project(broken);
    FAIL() << "broken JSON was accepted";
  } catch (const vcut::InputError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.column(), 13);
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
  }
  const std::string snub = write_temp(
      "snub.camotics",
      R"({"files": ["a.nc"], "tools": {"1": {"shape": "snubnose", "diameter": 3, "length": 5}}, "workpiece": {"bounds": {"min": [0,0,-1], "max": [1,1,0]}}})");
  EXPECT_THROW(vcut::io::read_camotics_project(snub), vcut::InputError);
  const std::string tpl =
      write_temp("tpl.camotics",
                 R"({"files": ["box.tpl"], "tools": {}, "workpiece": {"bounds": {"min": [0,0,-1], "max": [1,1,0]}}})");
  EXPECT_THROW(vcut::io::read_camotics_project(tpl), vcut::InputError);
  fs::remove(broken);
  fs::remove(snub);
  fs::remove(tpl);
}

}  // namespace
