// A program given without a job file (pipeline/program_job.h): the machine, stock, tools and
// resolution assumed, each derived here by hand from the program's numbers.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "vcut/io/input_error.h"
#include "vcut/io/job.h"
#include "vcut/pipeline/program_job.h"
#include "vcut/pipeline/poses.h"

namespace {
namespace fs = std::filesystem;

class ProgramJob : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("vcut_program_job_" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return (dir / name).string();
  }
  vcut::io::Job job(const std::string& text, vcut::pipeline::ProgramJobOptions options = {}) {
    options.out_dir = (dir / "out").string();
    return vcut::pipeline::job_for_program(write("p.nc", text), options);
  }
  fs::path dir;
};

// A 4 mm tool cuts a rectangle X 10..50 Y 10..30 at Z-2: the stock is that box grown by the
// radius 2 (X 8..52, Y 8..32), from Z-2 less max(1, 5 % of 2) = 1 down to Z-3, up to Z0. The
// resolution: min(44 / 1000, 4 / 4) = 0.044 mm.
TEST_F(ProgramJob, StockFromTheCuttingMoves) {
  const vcut::io::Job j =
      job("(T1 D=4 CR=0 - ZMIN=-2 - flat end mill)\nG21 G90\nT1 M6\nG0 X10 Y10 Z5\nG1 Z-2 F100\nX50\nY30\nX10\nY10\n"
          "G0 Z5\nG0 X200 Y200\nM30\n");
  EXPECT_EQ(j.machine, "3axis");
  EXPECT_EQ(j.stock.kind, vcut::io::StockSpec::Kind::Box);
  EXPECT_TRUE(j.stock.box.min_mm.isApprox(Eigen::Vector3d(8, 8, -3), 1e-12)) << j.stock.box.min_mm.transpose();
  EXPECT_TRUE(j.stock.box.max_mm.isApprox(Eigen::Vector3d(52, 32, 0), 1e-12)) << j.stock.box.max_mm.transpose();
  EXPECT_NEAR(j.resolution_mm, 0.044, 1e-12);
  ASSERT_EQ(j.tools.count(1), 1u);
  EXPECT_DOUBLE_EQ(j.tools.at(1).diameter_mm, 4.0);
  EXPECT_DOUBLE_EQ(j.tools.at(1).flute_length_mm, 16.0);  // 4 diameters: deeper than the 2 mm cut
  EXPECT_EQ(j.initial_tool, 1);
  EXPECT_FALSE(j.design);
  EXPECT_GE(j.assumptions.size(), 5u);
}

// A 10 mm tool along a 2 m line at Z-0.2: the stock is X -5..2005, Y -5..5, Z -1.2..0 (Z-0.2
// less max(1, 5 % of 0.2) = 1). The longest side / 1000 is 2.01 mm and a quarter of the tool
// 2.5 mm, but the stock is 1.2 mm thick: a lattice of 2 mm would hold no node across it (a
// stock thinner than the resolution is refused), so the resolution is 1.2 mm.
TEST_F(ProgramJob, ResolutionNoCoarserThanTheStocksThinnestSide) {
  const vcut::io::Job j =
      job("(T1 D=10 CR=0 - ZMIN=-0.2 - flat end mill)\nG21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-0.2 F100\nX2000\n"
          "G0 Z5\nM30\n");
  EXPECT_TRUE(j.stock.box.min_mm.isApprox(Eigen::Vector3d(-5, -5, -1.2), 1e-12)) << j.stock.box.min_mm.transpose();
  EXPECT_TRUE(j.stock.box.max_mm.isApprox(Eigen::Vector3d(2005, 5, 0), 1e-12)) << j.stock.box.max_mm.transpose();
  EXPECT_NEAR(j.resolution_mm, 1.2, 1e-12);
}

// The first plunge: a rapid down to Z-2 over the cutting area, then a feed further down: the
// stock's top is no higher than Z-2 (CAM systems rapid to just above the stock). The box then
// runs from Z-4 less max(1, 5 % of 2) = 1 to Z-2. A rapid to depth followed by a level lead-in
// (a profile entering from outside) lowers nothing.
TEST_F(ProgramJob, StockTopNoHigherThanTheFirstPlunge) {
  const vcut::io::Job j = job("G21 G90\nT1 M6\nG0 X10 Y10 Z20\nG0 Z-2\nG1 Z-4 F100\nX50\nG0 Z20\nM30\n");
  EXPECT_NEAR(j.stock.box.max_mm.z(), -2.0, 1e-12);
  EXPECT_NEAR(j.stock.box.min_mm.z(), -5.0, 1e-12);
  EXPECT_NE(j.assumptions[1].find("where the first plunge's rapid ends"), std::string::npos) << j.assumptions[1];
  const vcut::io::Job profile = job("G21 G90\nT1 M6\nG0 X10 Y10 Z20\nG0 Z-4\nG1 X50 F100\nG0 Z20\nM30\n");
  EXPECT_NEAR(profile.stock.box.max_mm.z(), 0.0, 1e-12);
}

// An arc's own extent, not its circle's: G2 from (0, 0) to (20, 0) about (10, 0) clockwise
// passes over the top, reaching Y 10; nothing goes below Y 0. With the default 6 mm tool the
// box is X -3..23, Y -3..13.
TEST_F(ProgramJob, ArcsByTheirOwnExtent) {
  const vcut::io::Job j = job("G21 G90\nT3 M6\nG0 X0 Y0 Z1\nG1 Z-1 F100\nG2 X20 Y0 I10 J0\nG0 Z5\nM30\n");
  EXPECT_NEAR(j.stock.box.min_mm.x(), -3.0, 1e-9);
  EXPECT_NEAR(j.stock.box.max_mm.x(), 23.0, 1e-9);
  EXPECT_NEAR(j.stock.box.min_mm.y(), -3.0, 1e-9);
  EXPECT_NEAR(j.stock.box.max_mm.y(), 13.0, 0.01);  // the arc's top, sampled every 2 deg at most
  ASSERT_EQ(j.tools.count(3), 1u);
  EXPECT_DOUBLE_EQ(j.tools.at(3).diameter_mm, 6.0);  // the default diameter
}

// A declared size is placed where it holds the cutting moves: moves X 10..90 (middle 50) fit
// a 100 mm stock from X0; Y -40..-10 (middle -25) one from Y-50 to 0; cuts below Z0 put its
// top at Z0.
TEST_F(ProgramJob, DeclaredSizePlaced) {
  const vcut::io::Job j = job("(STOCK = 100 X 50 X 20)\nG21\nT1 M6\nG0 X10 Y-40 Z1\nG1 Z-5 F100\nX90 Y-10\nM30\n");
  EXPECT_EQ(j.stock.box.min_mm, Eigen::Vector3d(0, -50, -20));
  EXPECT_EQ(j.stock.box.max_mm, Eigen::Vector3d(100, 0, 0));
}

// A and C words: the bundled A/C trunnion; B words: the B/C table; a machine named wins.
TEST_F(ProgramJob, MachineByTheRotaryWords) {
  EXPECT_EQ(job("G21\nT1 M6\nG0 X0 Y0 Z5 A0 C0\nG1 Z-1 F100\nG1 X10 A10\nM30\n").machine, "xyzac-trt");
  // Rotary words that only hold the axes at 0 (a post's home line, here SUPA A0 C0 in a
  // SINUMERIK program): nothing turns, so the three-axis mill, and its poses all reachable.
  const std::string mpf = write("home.mpf",
                                "N10 T1 M6\nN20 SUPA G0 Z-10 D0\nN30 SUPA X0 Y0 A0 C0 D1\nN40 G54 G0 X10 Y10 Z5\n"
                                "N50 G1 Z-1 F100\nN60 X20\nN70 M30\n");
  vcut::pipeline::ProgramJobOptions alone;
  alone.out_dir = (dir / "out").string();
  const vcut::io::Job held = vcut::pipeline::job_for_program(mpf, alone);
  EXPECT_EQ(held.machine, "3axis");
  EXPECT_NE(held.assumptions.front().find("hold them at 0"), std::string::npos) << held.assumptions.front();
  const vcut::pipeline::JobProgram read = vcut::pipeline::read_job_program(held);
  ASSERT_EQ(read.program.blocks.size(), 4u);  // from the home: line 20 (Z), not 30 (home already)
  const vcut::pipeline::PoseRun run = vcut::pipeline::run_pose_engine(held, read, held.resolution_mm);
  for (const auto& e : run.events) EXPECT_NE(e.kind, vcut::pipeline::PoseEventKind::Unreachable) << e.detail;
  // A SINUMERIK 3+2 program without rotary words: CYCLE800 with its parameters turns the
  // rotaries, so the five-axis trunnion.
  const std::string swivel =
      write("swivel.mpf",
            "N10 T1 M6\nN20 G0 X0 Y0 Z50\nN30 CYCLE800(1,\"TC1\",0,57,0,0,0,20,0,0,0,0,0,-1,100,1)\n"
            "N40 G0 X10 Y0 Z5\nN50 G1 Z-1 F100\nN60 X20\nN70 M30\n");
  EXPECT_EQ(vcut::pipeline::job_for_program(swivel, alone).machine, "xyzac-trt");
  vcut::pipeline::ProgramJobOptions head;
  head.machine = "head-table-bc";
  EXPECT_EQ(job("G21\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nM30\n", head).machine, "head-table-bc");
}

// The job written out (vcut job) reads back to the same job.
TEST_F(ProgramJob, WrittenJobReadsBack) {
  const vcut::io::Job j =
      job("(T2 D=3 CR=1.5 - ZMIN=-1 - ball end mill)\nG21\nT2 M6\nG0 X0 Y0 Z1\nG1 Z-1 F50\nX10\nM30\n");
  write("job.yaml", vcut::io::job_yaml(j, "p.nc"));
  const vcut::io::Job back = vcut::io::read_job((dir / "job.yaml").string());
  EXPECT_EQ(back.machine, j.machine);
  EXPECT_EQ(back.stock.box.min_mm, j.stock.box.min_mm);
  EXPECT_EQ(back.stock.box.max_mm, j.stock.box.max_mm);
  EXPECT_EQ(back.resolution_mm, j.resolution_mm);
  EXPECT_EQ(back.initial_tool, 2);
  ASSERT_EQ(back.tools.size(), 1u);
  const vcut::removal::Cutter& c = back.tools.at(2);
  EXPECT_EQ(c.type, vcut::removal::CutterType::Ball);
  EXPECT_EQ(c.diameter_mm, 3.0);
  EXPECT_EQ(c.flute_length_mm, j.tools.at(2).flute_length_mm);
  EXPECT_EQ(c.gauge_length_mm, j.tools.at(2).gauge_length_mm);
  EXPECT_EQ(back.program_files, std::vector<std::string>{(dir / "p.nc").string()});
}

// Nothing that cuts: an error naming the file.
TEST_F(ProgramJob, NoCuttingMoveIsAnError) { EXPECT_THROW(job("G21\nG0 X10 Y10\nM30\n"), vcut::InputError); }

// Tools from a CAMotics tool table (--tool-table x.json) and a LinuxCNC one (x.tbl): they win
// over the program's comment; T1's 0.25 in ball is 6.35 mm, T2's D3 flat 3 mm (mm machine).
TEST_F(ProgramJob, ToolTables) {
  const std::string program =
      "(T1 D=10 CR=0 - ZMIN=-1 - flat end mill)\nG21\nT1 M6\nG0 X0 Y0 Z1\nG1 Z-1 F100\nX10\nT2 M6\nX20\nM30\n";
  vcut::pipeline::ProgramJobOptions json;
  json.tool_table =
      write("tools.json", R"({"1": {"units": "imperial", "shape": "ballnose", "length": 1, "diameter": 0.25}})");
  const vcut::io::Job a = job(program, json);
  EXPECT_EQ(a.tools.at(1).type, vcut::removal::CutterType::Ball);
  EXPECT_NEAR(a.tools.at(1).diameter_mm, 6.35, 1e-12);
  EXPECT_DOUBLE_EQ(a.tools.at(2).diameter_mm, 6.0);  // not in the table: the default
  vcut::pipeline::ProgramJobOptions tbl;
  tbl.tool_table = write("tools.tbl", "T1 P1 D6.35 Z50 ;ball\nT2 P2 D3 Z40 ;end mill\n");
  const vcut::io::Job b = job(program, tbl);
  EXPECT_EQ(b.tools.at(1).type, vcut::removal::CutterType::Ball);
  EXPECT_DOUBLE_EQ(b.tools.at(2).diameter_mm, 3.0);
  EXPECT_EQ(b.tools.at(2).type, vcut::removal::CutterType::Flat);
}

}  // namespace
