// `vcut simulate PROGRAM` and `vcut job PROGRAM` with no job file, through the real binary.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_vcut.h"

namespace {
namespace fs = std::filesystem;
using vcut::cli::test::CommandResult;
using vcut::cli::test::expect_error;
using vcut::cli::test::fresh_test_dir;
using vcut::cli::test::run_vcut;
using vcut::cli::test::write;

// A 4 mm flat end mill (its Fusion comment) cuts one slot 2 mm deep from X10 to X50 at Y20:
// 40 x 4 x 2 = 320 mm3 and the two half-discs at its ends, pi 2^2 x 2 = 25.13 mm3. The stock
// is the cut's box (X 8..52, Y 18..22, Z -3..0: 528 mm3), so all of the slot is removed. The
// assumptions lead the terminal output and are in report.json.
TEST(ProgramAlone, SimulateAProgramWithoutAJob) {
  const fs::path dir = fresh_test_dir("vcut_alone_");
  write(dir / "slot.nc",
        "(T1 D=4 CR=0 - ZMIN=-2 - flat end mill)\nG21 G90\nT1 M6\nS10000 M3\nG0 X10 Y20 Z5\nG1 Z-2 F200\nX50\n"
        "G0 Z5\nM30\n");
  const CommandResult r = run_vcut("simulate " + (dir / "slot.nc").string() + " --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.rfind("vcut: assumed machine: 3axis", 0), 0u) << r.output;
  std::ifstream in(dir / "out" / "report.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("assumptions"));
  bool tool = false;
  for (const auto& a : j["assumptions"]) tool = tool || a.get<std::string>().rfind("T1: 4 mm flat end mill", 0) == 0;
  EXPECT_TRUE(tool) << j["assumptions"].dump(1);
  const double slot_mm3 = 40.0 * 4.0 * 2.0 + M_PI * 4.0 * 2.0;
  // The dexel grid (0.044 mm) snaps faces by at most half a cell: within 1 %.
  EXPECT_NEAR(j["summary"]["initial_volume_mm3"].get<double>(), 44.0 * 4.0 * 3.0, 0.01 * 528.0);
  EXPECT_NEAR(j["summary"]["removed_volume_mm3"].get<double>(), slot_mm3, 0.01 * slot_mm3);
  fs::remove_all(dir);
}

// `vcut job` writes a job that `vcut simulate` runs; a bad header stock names its line.
TEST(ProgramAlone, JobWrittenAndBadStock) {
  const fs::path dir = fresh_test_dir("vcut_alone_job_");
  write(dir / "p.nc", "(STOCK/BLOCK, 60, 40, 10, 0, 0, 10)\nG21\nT1 M6\nG0 X5 Y5 Z1\nG1 Z-1 F100\nX55\nM30\n");
  const CommandResult job = run_vcut("job " + (dir / "p.nc").string() + " --tool-diameter 3");
  ASSERT_EQ(job.exit_code, 0) << job.output;
  EXPECT_NE(job.output.find("stock: {box: {min: [0, 0, -10], max: [60, 40, 0]}}"), std::string::npos) << job.output;
  EXPECT_NE(job.output.find("1: {type: flat, diameter: 3,"), std::string::npos) << job.output;
  write(dir / "job.yaml", job.output);
  const CommandResult run = run_vcut("simulate " + (dir / "job.yaml").string() + " -q --out " + (dir / "o").string());
  EXPECT_EQ(run.exit_code, 0) << run.output;
  write(dir / "bad.nc", "(STOCK/BLOCK, 60, 0, 10, 0, 0, 10)\nG1 X1 F100\n");
  expect_error(run_vcut("simulate " + (dir / "bad.nc").string()),
               "bad.nc:1:2: expected a CutViewer STOCK/BLOCK stock size greater than 0");
  fs::remove_all(dir);
}

// A CAMotics project runs as a job: its 1/8 in flat end mill (3.175 mm) cuts a 20 mm slot 1 mm
// deep from X10 to X30 in its 40 x 20 x 5 mm workpiece: 20 x 3.175 x 1 + pi 1.5875^2 x 1 =
// 71.42 mm3.
TEST(ProgramAlone, CamoticsProject) {
  const fs::path dir = fresh_test_dir("vcut_camotics_");
  write(dir / "slot.nc", "G21 G90\nT1 M6\nS10000 M3\nG0 X10 Y10 Z5\nG1 Z-1 F200\nX30\nG0 Z5\nM30\n");
  write(dir / "p.camotics",
        R"({"units": "metric", "resolution": 0.05, "tools": {"1": {"units": "imperial", "shape": "cylindrical",
        "length": 0.5, "diameter": 0.125}}, "workpiece": {"automatic": false, "bounds": {"min": [0, 0, -5],
        "max": [40, 20, 0]}}, "files": ["slot.nc"]})");
  const CommandResult r = run_vcut("simulate " + (dir / "p.camotics").string() + " -q --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / "out" / "report.json");
  const auto j = nlohmann::json::parse(in);
  const double slot_mm3 = 20.0 * 3.175 + M_PI * 1.5875 * 1.5875;
  EXPECT_NEAR(j["summary"]["removed_volume_mm3"].get<double>(), slot_mm3, 0.02 * slot_mm3);
  EXPECT_NEAR(j["summary"]["initial_volume_mm3"].get<double>(), 4000.0, 40.0);
  EXPECT_TRUE(j.contains("assumptions"));
  fs::remove_all(dir);
}

}  // namespace
