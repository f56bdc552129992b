// `vcut check` through the real binary (issue 7): the go/no-go listing without cutting.
// Expected depths are worked from the geometry in the comments, never the binary's output.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "run_vcut.h"

namespace {
namespace fs = std::filesystem;
using vcut::cli::test::CommandResult;
using vcut::cli::test::expect_error;
using vcut::cli::test::fresh_test_dir;
using vcut::cli::test::run_vcut;
using vcut::cli::test::write;

class Check : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fresh_test_dir("vcut_check_");
    // 10 mm flat end mill: 5 mm of flutes, an 8 mm shank up to 20 mm, a 30 mm holder above.
    write(dir / "tools.yaml",
          "tools:\n  1: {type: flat, diameter: 10, flute_length: 5, shank_diameter: 8, length: 20, holder_diameter: "
          "30, holder_length: 40}\n");
    job =
        "job: check\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: p.ngc}\n"
        "stock: {box: {min: [0, 0, -30], max: [60, 40, 0]}}\nreport: {out: out}\n";
  }
  void TearDown() override { fs::remove_all(dir); }
  CommandResult check(const std::string& program) {
    write(dir / "job.yaml", job);
    write(dir / "p.ngc", program);
    return run_vcut("check " + (dir / "job.yaml").string() + " --json " + (dir / "check.json").string());
  }
  nlohmann::json json() {
    std::ifstream in(dir / "check.json");
    return nlohmann::json::parse(in);
  }
  fs::path dir;
  std::string job;
};

// Line 6 slots 8 mm deep: the shank's lower face (5 mm above the tip) is 3 mm below the
// top; line 9 plunges 22 mm: the holder's face (20 mm above the tip) is 2 mm below the top;
// line 14 cuts 1 mm deep after M5. The retracts (lines 7 and 10) go straight up the tool
// axis and are not flagged.
TEST_F(Check, ShankHolderAndStoppedSpindle) {
  const CommandResult r = check(
      "G21 G90\nT1 M6\nS1000 M3\nG0 X-10 Y20 Z5\nG1 Z-8 F500\nG1 X30\nG0 Z5\nG0 X45\nG1 Z-22\nG0 Z50\nM5\n"
      "G0 X-10 Y10\nG1 Z-1\nG1 X20\nG0 Z50\nM30\n");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no-go: 1 error(s), 3 warning(s)"), std::string::npos) << r.output;
  const auto j = json();
  EXPECT_EQ(j["verdict"], "no-go");
  ASSERT_EQ(j["events"].size(), 4u) << j.dump(1);
  auto expect = [&](std::size_t i, const char* severity, const char* kind, const char* line, double depth_mm) {
    EXPECT_EQ(j["events"][i]["severity"], severity);
    EXPECT_EQ(j["events"][i]["kind"], kind);
    EXPECT_EQ(j["events"][i]["line"], line);
    EXPECT_NEAR(j["events"][i]["depth_mm"].get<double>(), depth_mm, 1e-9) << kind;
  };
  expect(0, "warning", "shank_in_stock_box", "p.ngc:6", 3.0);
  expect(1, "warning", "shank_in_stock_box", "p.ngc:9", 8.0);  // the plunge: its 8 mm width is the shorter way out
  expect(2, "warning", "holder_in_stock_box", "p.ngc:9", 2.0);
  expect(3, "error", "spindle_stopped_feed", "p.ngc:14", 1.0);
  ASSERT_EQ(j["tools"].size(), 1u);
  EXPECT_NEAR(j["tools"][0]["holder_clearance_mm"].get<double>(), -2.0, 1e-9);
  EXPECT_EQ(j["tools"][0]["line"], "p.ngc:9");
}

// A clean program: 1 mm deep, the holder 19 mm above the top at the lowest.
TEST_F(Check, CleanProgramIsAGo) {
  const CommandResult r = check("G21 G90\nT1 M6\nS1000 M3\nG0 X-10 Y20 Z5\nG1 Z-1 F500\nG1 X70\nG0 Z5\nM30\n");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto j = json();
  EXPECT_EQ(j["verdict"], "go");
  EXPECT_TRUE(j["events"].empty()) << j.dump(1);
  EXPECT_NEAR(j["tools"][0]["holder_clearance_mm"].get<double>(), 19.0, 1e-9);
  // Cycle time: the feed moves alone take (6 + 80) mm / 500 mm/min = 10.32 s. The first
  // rapid starts from the machine at its zero, the tip 340 mm above the table (gauge point
  // 400, tool 60): 335 mm of Z at no more than Z's 500 mm/s, at least 0.67 s; at most that
  // plus a full jerk-limited ramp up and down (to 500 mm/s: 2 x 0.07 s of jerk, 0.073 s at
  // 3500 mm/s2, 0.213 s each way), 1.1 s. The 6 mm retract and the feed moves' four
  // starts and stops (0.026 s ramps at 8.33 mm/s) add at most 0.3 s and 0.1 s.
  EXPECT_GT(j["cycle_time_s"].get<double>(), 10.32 + 0.67);
  EXPECT_LT(j["cycle_time_s"].get<double>(), 10.32 + 1.1 + 0.3 + 0.1);
}

// Out of the machine's reach: A is limited to [-120, 30] deg on the AC trunnion.
TEST_F(Check, AxisLimitIsAnError) {
  job = std::string("job: check\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: p.ngc}\n") +
        "stock: {box: {min: [0, 0, -30], max: [60, 40, 0]}}\nreport: {out: out}\n";
  const CommandResult r = check("G21 G90\nT1 M6\nS1000 M3\nG0 X0 Y0 Z100 A0 C0\nG1 A60 F500\nG0 A0\nM30\n");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const auto j = json();
  bool found = false;
  for (const auto& e : j["events"])
    found = found || (e["kind"] == "unreachable" && e["line"] == "p.ngc:5" && e["severity"] == "error");
  EXPECT_TRUE(found) << j.dump(1);
}

// Events in program order of their first line, also in a file whose name has a dash (the
// pose engine's events carry their blocks; a "file:line" string cut at the first '-' sorted
// them to block 0): the shank at line 6 comes before the axis limit at line 8 (A60 beyond
// A's 30 deg) and line 9 (its start, at A60).
TEST_F(Check, EventsInProgramOrderInADashedFileName) {
  job = std::string("job: check\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: part-01.ngc}\n") +
        "stock: {box: {min: [0, 0, -30], max: [60, 40, 0]}}\nreport: {out: out}\n";
  write(dir / "job.yaml", job);
  write(dir / "part-01.ngc",
        "G21 G90\nT1 M6\nS1000 M3\nG0 X-10 Y20 Z5 A0 C0\nG1 Z-8 F500\nG1 X30\nG0 Z100\nG1 A60 F500\nG0 A0\nM30\n");
  const CommandResult r = run_vcut("check " + (dir / "job.yaml").string() + " --json " + (dir / "check.json").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const auto j = json();
  ASSERT_EQ(j["events"].size(), 3u) << j.dump(1);
  EXPECT_EQ(j["events"][0]["kind"], "shank_in_stock_box");
  EXPECT_EQ(j["events"][0]["line"], "part-01.ngc:6");
  EXPECT_EQ(j["events"][1]["kind"], "unreachable");
  EXPECT_EQ(j["events"][1]["line"], "part-01.ngc:8");
  EXPECT_EQ(j["events"][2]["line"], "part-01.ngc:9");
}

TEST_F(Check, BadJobIsAnInputError) {
  job += "bogus: 1\n";
  expect_error(check("G0 X0\n"), "job.yaml:");
}

}  // namespace
