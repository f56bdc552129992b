// `vcut study densification` through the real binary (issue 7). The job turns the table of
// table-table-ac a full turn (G1 C360) with the tool's axis 14 mm from the C axis, so the
// tool cuts a ring groove 3 mm deep. Densified by phi, the tip runs on chords of the 14 mm circle
// (axis programs interpolate the axes; the study cuts straight moves between poses), so the
// groove's inner wall (the outer one lies beyond the 15 mm stock) sits closer to the axis than
// the true circle by the chord's sagitta 14 (1 - cos(phi / 2)) mm at each chord's middle:
// 0.03410 mm at 8 deg, 0.00853 at 4, 0.00213 at 2, 0.00013 at the 0.5 deg reference. A setting's distance from the
// reference lies between its sagitta less the reference's and its sagitta (where the chords' middles fall on the
// reference's), widened by the meshing tolerance below.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "run_vcut.h"

namespace {
namespace fs = std::filesystem;
using vcut::cli::test::CommandResult;
using vcut::cli::test::expect_error;
using vcut::cli::test::fresh_test_dir;
using vcut::cli::test::run_vcut;
using vcut::cli::test::write;

constexpr double kPathRadiusMm = 14.0;
double sagitta_mm(double phi_deg) { return kPathRadiusMm * (1.0 - std::cos(phi_deg / 2.0 * M_PI / 180.0)); }

class Study : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fresh_test_dir("vcut_study_");
    write(dir / "tools.yaml",
          "tools:\n  1: {type: flat, diameter: 6, flute_length: 20, shank_diameter: 6, length: 30}\n");
    program = "G21 G90 G94\nT1 M6\nS10000 M3\nG0 X20 Y0 Z5 A0 C0\nG1 Z-3 F500\nG1 X14\nG1 C360 F2000\nG0 Z5\nM30\n";
    job =
        "job: turn\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: turn.ngc}\n"
        "stock: {cylinder: {center: [0, 0, -6], radius: 15, height: 6}}\n"
        "engine: {kind: dexel, resolution: 0.1, threads: 2}\nreport: {out: out, gouge_tolerance: 0.01}\n";
  }
  void TearDown() override { fs::remove_all(dir); }
  CommandResult study(const std::string& args) {
    write(dir / "job.yaml", job);
    write(dir / "turn.ngc", program);
    return run_vcut("study densification " + (dir / "job.yaml").string() + " " + args);
  }
  nlohmann::json json() {
    std::ifstream in(dir / "out" / "study.json");
    return nlohmann::json::parse(in);
  }
  bool no_output() { return !fs::exists(dir / "out") || fs::is_empty(dir / "out"); }
  fs::path dir;
  std::string program, job;
};

// Meshing: the dexel surface is exact on its rays and faceted between them; over 0.1 mm on
// the wall's 11 mm radius the facets stray 0.1^2 / (8 * 11) = 1.1e-4 mm. Allow 1 um. (Sharp edges, where
// meshing alone moves vertices by up to v/2, are left out of max_mm by the study.)
constexpr double kMeshSlackMm = 0.001;

TEST_F(Study, ChordSagittaOfATurningTableAndTheRecommendation) {
  const CommandResult r = study("--angles 8,4,2 --reference-angle 0.5 --accuracy 0.005");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("recommended: angle 2 deg"), std::string::npos) << r.output;
  const nlohmann::json j = json();
  EXPECT_EQ(j["varied"], "angle");
  EXPECT_EQ(j["reference"]["setting"], "angle 0.5 deg");
  ASSERT_EQ(j["settings"].size(), 3u);
  const double angles[] = {8.0, 4.0, 2.0};
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(angles[i]);
    const nlohmann::json& row = j["settings"][i];
    EXPECT_EQ(row["angle_deg"].get<double>(), angles[i]);
    const double high = sagitta_mm(angles[i]), low = high - sagitta_mm(0.5);
    EXPECT_GT(row["max_mm"].get<double>(), low - kMeshSlackMm) << row.dump();
    EXPECT_LT(row["max_mm"].get<double>(), high + kMeshSlackMm) << row.dump();
    EXPECT_LT(row["rms_mm"].get<double>(), row["max_mm"].get<double>());
    EXPECT_EQ(row["meets_accuracy"].get<bool>(), high <= 0.005);
  }
  // The C block is split into ceil(360 / phi) poses; every other block is the same.
  EXPECT_EQ(j["settings"][1]["poses"].get<int>() - j["settings"][0]["poses"].get<int>(), 90 - 45);
  EXPECT_EQ(j["settings"][2]["poses"].get<int>() - j["settings"][1]["poses"].get<int>(), 180 - 90);
  EXPECT_EQ(j["reference"]["poses"].get<int>() - j["settings"][2]["poses"].get<int>(), 720 - 180);
  EXPECT_EQ(j["recommended"], "angle 2 deg");

  std::ifstream csv_in(dir / "out" / "study.csv");
  std::stringstream csv_text;
  csv_text << csv_in.rdbuf();
  const std::string csv = csv_text.str();
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 3 + 1) << csv;  // header, settings, reference
  EXPECT_EQ(csv.rfind("setting,step_mm,angle_deg,tolerance_mm,poses,", 0), 0u) << csv;
  std::ifstream svg_in(dir / "out" / "study.svg");
  std::stringstream svg;
  svg << svg_in.rdbuf();
  EXPECT_NE(svg.str().find("<svg"), std::string::npos);
  EXPECT_NE(svg.str().find("</svg>"), std::string::npos);
  std::ifstream png(dir / "out" / "study.png", std::ios::binary);
  char signature[8] = {};
  png.read(signature, 8);
  EXPECT_EQ(std::string(signature + 1, 3), "PNG");
}

// A pure turn: with tool-centre-point control on (LinuxCNC's M428 on xyzac-trt) the tip
// stays put while A tilts the table 30 deg, so the tool turns about its tip on one great
// circle at an even rate, and every setting densifies the very same rigid motion (the
// distance from the reference is zero). What a setting measures is then the cut's own: the
// turning pieces, within the study's turn tolerance (accuracy / 10 = 0.0002 mm here, not
// the job's 0.02 = min(v / 10, gouge tolerance / 2)), which each setting splits differently,
// and the meshes of nearly one solid. So every setting is well within the accuracy.
TEST_F(Study, APureTurnIsTheSameAtEverySetting) {
  program = "G21 G90 G94\nT1 M6\nS10000 M3\nG0 X0 Y0 Z5 A0 C0\nM428\nG1 Z-4 F500\nG1 A30 F2000\nG1 Z5\nM429\nM30\n";
  job =
      "job: tilt\nmachine: xyzac-trt\ntools: tools.yaml\n"
      "program: {file: turn.ngc, tcp_m_codes: {M428: on, M429: off}}\n"
      "stock: {box: {min: [-15, -15, -10], max: [15, 15, 0]}}\n"
      "engine: {kind: dexel, resolution: 0.2, threads: 2}\nreport: {out: out, gouge_tolerance: 0.1}\n";
  const CommandResult r = study("--angles 8,4,2 --reference-angle 0.5 --accuracy 0.002");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("accuracy 0.002 mm, turning moves within 0.0002 mm"), std::string::npos) << r.output;
  const nlohmann::json j = json();
  EXPECT_DOUBLE_EQ(j["turn_tolerance_mm"].get<double>(), 0.0002);
  ASSERT_EQ(j["settings"].size(), 3u);
  for (const nlohmann::json& row : j["settings"]) {
    SCOPED_TRACE(row.dump());
    EXPECT_LT(row["max_mm"].get<double>(), 0.001);
    EXPECT_TRUE(row["meets_accuracy"].get<bool>());
  }
  EXPECT_EQ(j["recommended"], "angle 8 deg");
}

// No setting meets a 0.1 um accuracy: exit 1, the files complete, no recommendation. (At
// 0.5 mm: the figures do not matter here, and such an accuracy is also warned about.)
TEST_F(Study, NoSettingMeetsTheAccuracy) {
  const CommandResult r = study("--angles 8,4 --accuracy 0.0001 --resolution 0.5 -q");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no setting is within 0.0001 mm of the reference"), std::string::npos) << r.output;
  const nlohmann::json j = json();
  EXPECT_TRUE(j["recommended"].is_null());
  EXPECT_NE(r.output.find("warning: accuracy 0.0001 mm is below what meshes at 0.5 mm resolve"), std::string::npos)
      << r.output;
  EXPECT_EQ(j["reference"]["setting"], "angle 1 deg");  // the finest / 4
  // The turning moves' tolerance no finer than v / 1000 (a tenth of what the meshes
  // resolve), not the accuracy's tenth.
  EXPECT_DOUBLE_EQ(j["turn_tolerance_mm"].get<double>(), 0.0005);
  EXPECT_TRUE(fs::exists(dir / "out" / "study.png"));
}

TEST_F(Study, BadOptionsAreClearErrorsAndWriteNothing) {
  expect_error(study("--angles 8,0"), "--angles: 0 is not a positive number of deg");
  expect_error(study("--angles 8,2 --reference-angle 4"),
               "--reference-angle: 4 deg is not finer than the finest setting (2 deg)");
  expect_error(study("--angles 8 --tolerances 0.01"), "--tolerances cannot be combined with --steps or --angles");
  expect_error(study("--angles 8,4 --reference-step 0.1"), "--reference-step without --steps");
  expect_error(study("--steps 1,0.5 --angles 8"), "expected the same number of values");
  expect_error(study(""), "no settings: give --steps, --angles or --tolerances");
  expect_error(study("--angles 8 --accuracy -1"), "--accuracy: -1 is not a positive number of mm");
  EXPECT_TRUE(no_output());
  write(dir / "blocker", "a file where the folder should be");
  expect_error(study("--angles 8 --out " + (dir / "blocker" / "out").string()), "blocker");
}

// Every run fails the same way (the program calls a tool the library lacks): one error.
TEST_F(Study, NoSettingCanBeRun) {
  program.replace(program.find("T1 M6"), 5, "T7 M6");
  const CommandResult r = study("--angles 8,4");
  expect_error(r, "no setting could be run; angle 8 deg: ");
  EXPECT_NE(r.output.find("T7"), std::string::npos) << r.output;
  EXPECT_TRUE(!fs::exists(dir / "out" / "study.json"));
}

}  // namespace
