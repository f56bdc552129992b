// `vcut program FILE` end to end (issue 4 item 5): the canonical motion list as JSON lines,
// on a small APT CL file and on a G-code file, and its one-line errors. Expected records are
// worked by hand from the programs below (comments next to each).
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "run_vcut.h"

namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;
using vcut::cli::test::CommandResult;
using vcut::cli::test::expect_error;
using vcut::cli::test::run_vcut;
using vcut::cli::test::write;

// JSON numbers are printed round-trippably; values below are exact or one normalisation away.
constexpr double kRoundOff = 1e-12;

void expect_array(const json& actual, const std::vector<double>& expected) {
  ASSERT_TRUE(actual.is_array()) << actual.dump();
  ASSERT_EQ(actual.size(), expected.size()) << actual.dump();
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(actual[i].get<double>(), expected[i], kRoundOff) << actual.dump();
  }
}

class ProgramCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() /
          ("vcut_program_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  // The JSON records of a successful run; other lines (warnings) go to `other`.
  std::vector<json> records(const std::string& args, std::vector<std::string>* other = nullptr) {
    const CommandResult r = run_vcut(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    std::vector<json> out;
    std::istringstream lines(r.output);
    std::string line;
    while (std::getline(lines, line)) {
      if (!line.empty() && line[0] == '{') {
        out.push_back(json::parse(line));
      } else if (other) {
        other->push_back(line);
      }
    }
    return out;
  }

  fs::path dir;
};

TEST_F(ProgramCli, AptFile) {
  const std::string file = (dir / "part.cls").string();
  write(file,
        "$$ a five-axis CL file\n"
        "PARTNO SAMPLE\n"
        "UNITS/MM\n"
        "LOADTL/2\n"
        "CUTTER/6,3\n"
        "MULTAX/ON\n"
        "FROM/0,0,20,0,0,1\n"
        "SPINDL/1000,CLW\n"
        "FEDRAT/500,MMPM\n"
        "RAPID\n"
        "GOTO/10,0,5\n"
        "GOTO/10,0,0,0,0.6,0.8\n"
        "CIRCLE/0,0,0,0,0,1,10\n"
        "GOTO/0,10,0\n"
        "FINI\n");
  std::vector<std::string> other;
  const std::vector<json> r = records("program " + file + " --machine table-table-ac", &other);
  ASSERT_EQ(r.size(), 3u);
  // Line 11: RAPID from the FROM/ point.
  EXPECT_EQ(r[0]["kind"], "rapid");
  expect_array(r[0]["start"], {0, 0, 20});
  expect_array(r[0]["end"], {10, 0, 5});
  EXPECT_EQ(r[0]["feed"].get<double>(), 0.0);
  EXPECT_EQ(r[0]["feed_mode"], "mm/min");
  EXPECT_EQ(r[0]["tool"], 2);
  EXPECT_EQ(r[0]["tcp"], true);
  expect_array(r[0]["start_axis"], {0, 0, 1});
  expect_array(r[0]["end_axis"], {0, 0, 1});
  EXPECT_EQ(r[0]["orientation_mode"], "vector");
  EXPECT_EQ(r[0]["source"], file + ":11");
  EXPECT_FALSE(r[0].contains("center"));
  EXPECT_FALSE(r[0].contains("rotary"));
  // Line 12: the tool tilts to (0, 0.6, 0.8) while feeding down.
  EXPECT_EQ(r[1]["kind"], "linear");
  EXPECT_EQ(r[1]["feed"].get<double>(), 500.0);
  expect_array(r[1]["end_axis"], {0, 0.6, 0.8});
  EXPECT_EQ(r[1]["source"], file + ":12");
  // Lines 13-14: a quarter circle about +Z from (10,0,0) to (0,10,0).
  EXPECT_EQ(r[2]["kind"], "arc");
  expect_array(r[2]["start"], {10, 0, 0});
  expect_array(r[2]["end"], {0, 10, 0});
  expect_array(r[2]["center"], {0, 0, 0});
  expect_array(r[2]["normal"], {0, 0, 1});
  EXPECT_EQ(r[2]["turns"], 1);
  expect_array(r[2]["start_axis"], {0, 0.6, 0.8});
  EXPECT_EQ(r[2]["source"], file + ":14");
  // PARTNO is not read: one warning on stderr naming its line.
  ASSERT_EQ(other.size(), 1u);
  EXPECT_EQ(other[0].rfind("vcut: warning: " + file + ":2:1: ", 0), 0u) << other[0];
}

TEST_F(ProgramCli, GcodeFile) {
  const std::string file = (dir / "part.ngc").string();
  write(file,
        "G21 G90 G17\n"
        "G0 X0 Y0 Z5\n"      // from 0, where rs274 starts: rapid (0,0,0) -> (0,0,5)
        "G1 Z0 F100\n"       // linear (0,0,5) -> (0,0,0)
        "G2 X10 Y0 I5 J0\n"  // clockwise half circle about (5,0): normal -Z
        "M2\n");
  std::vector<json> r = records("program " + file);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0]["kind"], "rapid");
  expect_array(r[0]["start"], {0, 0, 0});
  expect_array(r[0]["end"], {0, 0, 5});
  r.erase(r.begin());
  EXPECT_EQ(r[0]["kind"], "linear");
  expect_array(r[0]["start"], {0, 0, 5});
  expect_array(r[0]["end"], {0, 0, 0});
  EXPECT_EQ(r[0]["feed"].get<double>(), 100.0);
  EXPECT_EQ(r[0]["tool"], 0);
  EXPECT_EQ(r[0]["source"], file + ":3");
  EXPECT_EQ(r[1]["kind"], "arc");
  expect_array(r[1]["center"], {5, 0, 0});
  expect_array(r[1]["normal"], {0, 0, -1});
  EXPECT_EQ(r[1]["turns"], 1);
  EXPECT_EQ(r[1]["source"], file + ":4");
  // The same file named as APT is an APT error on its first line.
  expect_error(run_vcut("program " + file + " --dialect apt"), file + ":1:5: unexpected 'G' after G21");
}

TEST_F(ProgramCli, Errors) {
  const std::string bad = (dir / "bad.apt").string();
  write(bad, "FEDRAT/10\nGOTO/1,2\n");
  expect_error(run_vcut("program " + bad), bad + ":2:6: GOTO/ with 2 parameter(s)");
  const std::string good = (dir / "good.apt").string();
  write(good, "FROM/0,0,0\nFEDRAT/1\nGOTO/1,0,0\n");
  expect_error(run_vcut("program " + good + " --dialect heidenhain"), "unknown program dialect");
  expect_error(run_vcut("program " + good + " --machine " + (dir / "none.yaml").string()), "none.yaml");
  const std::string mpf = (dir / "five.mpf").string();
  write(mpf, "N10 TRAORI\nN20 ROTS X10\n");
  expect_error(run_vcut("program " + mpf), mpf + ":2:5: ROTS is not supported");
  expect_error(run_vcut("program " + (dir / "missing.nc").string()), "cannot open");
}

}  // namespace
