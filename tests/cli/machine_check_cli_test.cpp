// `vcut check` with the machine's bodies (issue #25), through the real binary, on the bundled
// example examples/machine-collision: table-table-ac (its models from
// scripts/make-machine-models), a clamp on the table, a flat D10 tool 120 mm out of the nose
// in a D40 holder. Expected figures are worked from the models' sizes in that script:
// - the rotary table's top at z = -40 (C at 0: the workpiece frame is the machine frame);
// - the spindle housing, radius 60, from the spindle nose up; the nose 120 mm above the tip;
// - the clamp x 60..100, y -20..20, z -40..40 on the table (workpiece frame).
#include <gtest/gtest.h>

#include <cmath>
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

const fs::path kExample = fs::path(VCUT_SOURCE_DIR) / "examples" / "machine-collision";

class MachineCheck : public ::testing::Test {
 protected:
  void SetUp() override { dir = fresh_test_dir("vcut_machine_check_"); }
  void TearDown() override { fs::remove_all(dir); }
  CommandResult check(const fs::path& job) {
    return run_vcut("check " + job.string() + " --json " + (dir / "check.json").string());
  }
  nlohmann::json json() {
    std::ifstream in(dir / "check.json");
    return nlohmann::json::parse(in);
  }
  // The example's job with its own program, and `extra` keys.
  fs::path job_with(const std::string& program, const std::string& extra = "") {
    write(dir / "p.ngc", program);
    write(dir / "job.yaml", "job: t\nmachine: table-table-ac\ntools: " + (kExample / "tools.yaml").string() +
                                "\nprogram: {file: p.ngc}\nfixtures: [{file: " + (kExample / "clamp.stl").string() +
                                "}]\nstock: {box: {min: [-40, -40, -30], max: [40, 40, 0]}}\n"
                                "report: {machine_clearance: 2}\n" +
                                extra);
    return dir / "job.yaml";
  }
  std::vector<nlohmann::json> machine_events(const nlohmann::json& j) {
    std::vector<nlohmann::json> out;
    for (const auto& e : j["events"])
      if (e["kind"].get<std::string>().rfind("machine_", 0) == 0 || e["kind"] == "body_in_stock") out.push_back(e);
    return out;
  }
  fs::path dir;
};

// crash.ngc line 12 puts the tip at z = -170 beside the table (Y -215: the holder, radius 20,
// stays 5 mm off the cradle's -190 face): the nose at -50, the housing's underside 10 mm below
// the table's top. Line 16 turns C 0 -> 180 with poses every 60 deg (densify angle 60). At
// C = 60 the clamp's nearest edge lies 20 mm from the cutter's axis at (0, 80) (the edge from
// (12.68, 61.96) to (32.68, 96.60)), 15 mm from its side, and at C = 120 likewise by symmetry:
// both poses are clean; the clamp passes through the cutter around C = 90 (the clamp's middle
// at 80 mm from the C axis), between the poses. Line 21 brings the tip down to z = -159 at the
// same place as line 12: the housing's underside 1 mm above the table's top, within the job's
// 2 mm clearance (a near miss, a warning).
TEST_F(MachineCheck, BundledCrashIsFoundWithItsLinesAndBodies) {
  const CommandResult r = check(kExample / "job.yaml");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const std::vector<nlohmann::json> events = machine_events(json());
  ASSERT_EQ(events.size(), 3u) << json().dump(1);
  const nlohmann::json& head = events[0];
  EXPECT_EQ(head["kind"], "machine_collision");
  EXPECT_EQ(head["severity"], "error");
  EXPECT_EQ(head["line"], "crash.ngc:12");
  EXPECT_EQ(head["bodies"], nlohmann::json::array({"spindle housing (Z)", "rotary table (C)"}));
  EXPECT_NEAR(head["depth_mm"].get<double>(), 10.0, 0.01);
  EXPECT_NEAR(head["where"][2].get<double>(), -40.0, 0.01);  // on the table's top
  EXPECT_FALSE(head["between_poses"].get<bool>());
  EXPECT_NEAR(head["axes"]["Z"].get<double>(), -170.0 + 120.0 - 500.0, 1e-6);  // nose at -50, 500 at Z = 0

  const nlohmann::json& clamp = events[1];
  EXPECT_EQ(clamp["kind"], "machine_collision");
  EXPECT_EQ(clamp["line"], "crash.ngc:16");
  EXPECT_EQ(clamp["bodies"], nlohmann::json::array({"T1 cutter", "fixture clamp"}));
  EXPECT_TRUE(clamp["between_poses"].get<bool>());
  const double c_deg = clamp["axes"]["C"].get<double>();
  EXPECT_GT(c_deg, 60.0);
  EXPECT_LT(c_deg, 120.0);

  const nlohmann::json& near = events[2];
  EXPECT_EQ(near["kind"], "machine_near_miss");
  EXPECT_EQ(near["severity"], "warning");
  EXPECT_EQ(near["line"], "crash.ngc:21");
  EXPECT_EQ(near["bodies"], nlohmann::json::array({"spindle housing (Z)", "rotary table (C)"}));
  EXPECT_NEAR(near["clearance_mm"].get<double>(), 1.0, 0.01);
  EXPECT_NE(r.output.find("error   machine_collision at crash.ngc:12: spindle housing (Z) hits rotary table (C)"),
            std::string::npos)
      << r.output;
}

// simulate cuts the face pass (lines 6-7) and reports the same two collisions and the near
// miss, in the terminal, report.json and collisions.csv.
TEST_F(MachineCheck, SimulateReportsThemInTheReportAndCollisionsCsv) {
  const CommandResult r =
      run_vcut("simulate " + (kExample / "job.yaml").string() + " --resolution 0.5 --out " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(
      r.output.find("machine collision: spindle housing (Z) hits rotary table (C), 10.000 mm deep, at crash.ngc:12"),
      std::string::npos)
      << r.output;
  std::ifstream in(dir / "out" / "report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["summary"]["machine_collisions"], 2);
  EXPECT_EQ(j["summary"]["machine_near_misses"], 1);
  ASSERT_EQ(j["machine"]["contacts"].size(), 3u);
  EXPECT_EQ(j["machine"]["contacts"][1]["line"], "crash.ngc:16");
  EXPECT_TRUE(j["machine"]["contacts"][1]["between_poses"].get<bool>());
  std::ifstream csv_in(dir / "out" / "collisions.csv");
  std::string header, row1, row2, row3, extra;
  std::getline(csv_in, header);
  std::getline(csv_in, row1);
  std::getline(csv_in, row2);
  std::getline(csv_in, row3);
  EXPECT_FALSE(std::getline(csv_in, extra));
  EXPECT_EQ(header, "kind,body,other,depth_mm,clearance_mm,where_x,where_y,where_z,between_poses,lines");
  EXPECT_EQ(row1.rfind("machine_collision,spindle housing (Z),rotary table (C),", 0), 0u) << row1;
  EXPECT_NE(row1.find(",false,crash.ngc:12"), std::string::npos) << row1;
  EXPECT_EQ(row2.rfind("machine_collision,T1 cutter,fixture clamp,", 0), 0u) << row2;
  EXPECT_NE(row2.find(",true,crash.ngc:16"), std::string::npos) << row2;
  EXPECT_EQ(row3.rfind("machine_near_miss,spindle housing (Z),rotary table (C),", 0), 0u) << row3;
  EXPECT_NE(row3.find(",false,crash.ngc:21"), std::string::npos) << row3;
}

// The same findings, to the byte, with 1 thread and with 3 (the pairs and the poses are
// checked in parallel): the fast-tilt program has runs of both kinds, at poses and between.
TEST_F(MachineCheck, SameFindingsForOneAndThreeThreads) {
  std::string reports[2];
  int k = 0;
  for (const char* threads : {"1", "3"}) {
    job_with(
        "G21 G90 G94\nT1 M6\nS8000 M3\nG0 X-50 Y0 Z10 A0 C0\nG1 Z-2 F1000\nG1 X50\nG0 Z100\n"
        "G0 X0 Y-95\nG0 Z30\nG0 A-90\nG0 Z100\nG0 X0 Y-215 A0\nG1 Z-158.5 F2000\nG0 Z100\nM30\n",
        "densify: {angle: 90}\n");
    const CommandResult r = run_vcut("simulate " + (dir / "job.yaml").string() + " --quiet --resolution 1 --threads " +
                                     threads + " --out " + (dir / "out").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(dir / "out" / "report.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    reports[k++] = j["machine"].dump();
    EXPECT_GE(j["machine"]["contacts"].size(), 3u) << j["machine"].dump(1);
  }
  EXPECT_EQ(reports[0], reports[1]);
}

TEST_F(MachineCheck, CleanVariantReportsNone) {
  const CommandResult r = check(kExample / "job-clean.yaml");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(machine_events(json()).empty()) << json().dump(1);
  EXPECT_EQ(json()["machine_check"]["bodies"].size(), 11u);  // 6 models, the clamp, the stock, cutter, shank, holder
}

// The housing's underside 1.5 mm above the table's top (tip at -158.5: nose at -38.5): a near
// miss within the 2 mm clearance, a warning; at 2.5 mm above, nothing.
TEST_F(MachineCheck, NearMissWithinTheClearance) {
  const std::string start = "G21 G90 G94\nT1 M6\nS8000 M3\nG0 X0 Y-215 Z100 A0 C0\nG0 Z-100\n";
  CommandResult r = check(job_with(start + "G1 Z-158.5 F2000\nG0 Z100\nM30\n"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::vector<nlohmann::json> events = machine_events(json());
  ASSERT_EQ(events.size(), 1u) << json().dump(1);
  EXPECT_EQ(events[0]["kind"], "machine_near_miss");
  EXPECT_EQ(events[0]["severity"], "warning");
  EXPECT_EQ(events[0]["line"], "p.ngc:6");
  EXPECT_NEAR(events[0]["clearance_mm"].get<double>(), 1.5, 1e-6);
  r = check(job_with(start + "G1 Z-157.5 F2000\nG0 Z100\nM30\n"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(machine_events(json()).empty()) << json().dump(1);
}

// A rapid that tilts A from 0 to -90 (right hand about +x through y -20, z -100) with the
// tool waiting at tip z 30 over y -95. In A's frame (dy, dz) = (y + 20, z + 100) the table is
// dy -150..190, dz 20..60 and the cutter's point (-75, 130); turned back by 45 deg that point
// is (-144.9, 38.9), inside the table: the table's -y end swings up through the cutter around
// A = -45. With densify angle 90 the only poses are A = 0 (the table 70 mm below the tip) and
// A = -90 (the table a wall at y 0..40; the cradle, dy -170..170, dz -60..18, at y -80..-2
// and z up to 70: 10 mm from the cutter's side and from the holder's underside at z 80):
// clean at both.
TEST_F(MachineCheck, AFastTiltBetweenTwoCleanPosesIsFound) {
  const CommandResult r =
      check(job_with("G21 G90 G94\nT1 M6\nS8000 M3\nG0 X0 Y-95 Z100 A0 C0\nG0 Z30\nG0 A-90\nG0 Z100\nM30\n",
                     "densify: {angle: 90}\n"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const std::vector<nlohmann::json> events = machine_events(json());
  ASSERT_FALSE(events.empty()) << json().dump(1);
  bool found = false;
  for (const auto& e : events)
    if (e["line"] == "p.ngc:6" && e["kind"] == "machine_collision" && e["bodies"][1] == "rotary table (C)") {
      found = true;
      EXPECT_TRUE(e["between_poses"].get<bool>()) << e.dump();
      const double a_deg = e["axes"]["A"].get<double>();
      EXPECT_LT(a_deg, 0.0);
      EXPECT_GT(a_deg, -90.0);
    }
  EXPECT_TRUE(found) << json().dump(1);
}

// The same fast tilt after 253 short clean moves: a pair's samples are checked in chunks of
// 256 side by side, and here the tilt is sample 256 (the start is sample 0, then one a move:
// lines 4 to 258 are samples 1 to 255),
// the first of the second chunk. The interval from sample 255 into it is where the clamp
// passes through the cutter: the chunk must open at the sample before it, as the one before
// would have left it (a chunk that starts afresh finds nothing here).
TEST_F(MachineCheck, AFastTiltAtTheStartOfAChunkOfSamplesIsFound) {
  std::string program = "G21 G90 G94\nT1 M6\nS8000 M3\nG0 X0 Y-95 Z100 A0 C0\nG0 Z30\n";
  for (int line = 6; line < 259; ++line) program += line % 2 == 0 ? "G0 Z31\n" : "G0 Z30\n";
  program += "G0 A-90\nG0 Z100\nM30\n";  // the tilt on line 259
  const CommandResult r = check(job_with(program, "densify: {angle: 90}\n"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(json()["poses"], 258) << json().dump(1);  // the start, then lines 4 to 260
  bool found = false;
  for (const auto& e : machine_events(json())) {
    EXPECT_EQ(e["line"], "p.ngc:259") << e.dump();
    found = found || (e["kind"] == "machine_collision" && e["between_poses"].get<bool>());
  }
  EXPECT_TRUE(found) << json().dump(1);
}

// The bundled machines' own bodies stay clear of each other (and of a tool retracted 50 mm
// below the top of Z's travel, 100 mm out of the nose; on LinuxCNC's desktop xyzac-trt 5 mm
// below, 30 mm out) while the rotary axes run to the ends of their travels: the models make no false
// alarm by themselves.
TEST_F(MachineCheck, BundledMachinesAreClearOverTheirTravels) {
  struct Case {
    const char* machine;
    double gauge_mm;  // the tool out of the nose
    double top_mm;    // the tip: the nose's height at Z's top, less the tool, less 50 mm
    const char* start;
    const char* moves;
  };
  const Case cases[] = {
      {"table-table-ac", 100, 350, " A0 C0", "G0 A-120\nG0 C180\nG0 A30\nG0 C-90\n"},
      {"table-table-bc", 100, 300, " B0 C0", "G0 B-110\nG0 C180\nG0 B110\nG0 C-90\n"},
      {"xyzac-trt", 30, 85, " A0 C0", "G0 A-100\nG0 C180\nG0 A50\nG0 C-90\n"},
      {"head-table-bc", 100, 250, " B0 C0", "G0 B-110\nG0 C180\nG0 B110\nG0 C-90\n"},
      {"head-head-ac", 100, 450, " A0 C0", "G0 A-105\nG0 C180\nG0 A105\nG0 C-180\n"},
      {"gantry-wyxzcat", 100, 2250, " A0 C0", "G0 A-110\nG0 C180\nG0 A110\nG0 C-180\n"},
      {"3axis", 100, 250, "", "G0 X300 Y200\nG0 X-300 Y-200\n"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.machine);
    write(dir / "tools.yaml",
          "tools:\n  1: {type: flat, diameter: 10, flute_length: 10, length: " + std::to_string(c.gauge_mm / 2) +
              ", gauge_length: " + std::to_string(c.gauge_mm) + ", holder_diameter: 40}\n");
    write(dir / "p.ngc",
          "G21 G90 G94\nT1 M6\nG0 X0 Y0 Z" + std::to_string(c.top_mm) + c.start + "\n" + c.moves + "M30\n");
    write(dir / "job.yaml",
          std::string("job: t\nmachine: ") + c.machine +
              "\ntools: tools.yaml\nprogram: {file: p.ngc}\n"
              "stock: {box: {min: [-40, -40, -30], max: [40, 40, 0]}}\nreport: {machine_clearance: 2}\n");
    const CommandResult r = check(dir / "job.yaml");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(machine_events(json()).empty()) << json().dump(1);
    EXPECT_GE(json()["machine_check"]["bodies"].size(), 6u);
  }
}

// On a head-head machine the workpiece stands on the bed: a fixture standing on the table
// (the clamp moved down 20 mm: its underside on the table's top at z -60) never moves against
// it and is no collision; the spindle housing coming down onto the clamp is.
TEST_F(MachineCheck, AFixtureOnTheBedOfAHeadHeadMachine) {
  write(dir / "p.ngc", "G21 G90 G94\nT1 M6\nG0 X80 Y0 Z200 A0 C0\nG0 Z100\nM30\n");
  write(dir / "job.yaml", "job: t\nmachine: head-head-ac\ntools: " + (kExample / "tools.yaml").string() +
                              "\nprogram: {file: p.ngc}\nfixtures: [{file: " + (kExample / "clamp.stl").string() +
                              ", transform: {translate: [0, 0, -20]}}]\n"
                              "stock: {box: {min: [-40, -40, -30], max: [40, 40, 0]}}\n");
  CommandResult r = check(dir / "job.yaml");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(machine_events(json()).empty()) << json().dump(1);
  // Tip at z -10 over the clamp's middle (x 80): the cutter 30 mm into its top at z 20.
  write(dir / "p.ngc", "G21 G90 G94\nT1 M6\nG0 X80 Y0 Z200 A0 C0\nG1 Z-10 F1000\nM30\n");
  r = check(dir / "job.yaml");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const std::vector<nlohmann::json> events = machine_events(json());
  ASSERT_FALSE(events.empty()) << json().dump(1);
  EXPECT_EQ(events[0]["line"], "p.ngc:4");
  EXPECT_EQ(events[0]["bodies"][1], "fixture clamp");
}

// A cylinder stock (radius 30 about z, z -30..0): a holder (radius 20) whose underside comes to
// z -5 at x = y = 45 lies in the cylinder's box but 63.6 - 20 - 30 = 13.6 mm from the
// cylinder: the box test would flag it, the shape does not. With the tool's axis at x 40 (the holder
// 10 mm into the cylinder's side, 5 mm below its top) it is in the stock.
TEST_F(MachineCheck, HolderAgainstACylinderStocksShape) {
  write(dir / "tools.yaml",
        "tools:\n  1: {type: flat, diameter: 10, flute_length: 10, length: 20, gauge_length: 100, "
        "holder_diameter: 40}\n");
  const std::string job_text =
      "job: t\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: p.ngc}\n"
      "stock: {cylinder: {center: [0, 0, -30], radius: 30, height: 30}}\n";
  write(dir / "job.yaml", job_text);
  write(dir / "p.ngc", "G21 G90 G94\nT1 M6\nS1000 M3\nG0 X45 Y45 Z50\nG0 Z-25\nG0 Z50\nM30\n");
  CommandResult r = check(dir / "job.yaml");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json j = json();
  for (const auto& e : j["events"]) {
    EXPECT_NE(e["kind"], "holder_in_stock_box") << e.dump();
    EXPECT_NE(e["kind"], "body_in_stock") << e.dump();
  }
  write(dir / "p.ngc", "G21 G90 G94\nT1 M6\nS1000 M3\nG0 X40 Y0 Z50\nG0 Z-25\nG0 Z50\nM30\n");
  r = check(dir / "job.yaml");
  j = json();
  bool holder = false;
  for (const auto& e : j["events"])
    if (e["kind"] == "body_in_stock" && e["bodies"][0] == "T1 holder") {
      holder = true;
      EXPECT_EQ(e["line"], "p.ngc:5") << e.dump();
    }
  EXPECT_TRUE(holder) << j.dump(1);
}

// A holder model from the tool library (holder_mesh: its origin the spindle nose, hanging
// below): a block 100 x 100 mm, 60 mm deep. With the nose 120 mm above the tip at -25 the
// block's underside is at z 35, its side at x 20 + 50 = 70: 5 mm into the clamp's top (z 40)
// over x 60..70. The tool itself (radius 5 at x 20) stays clear of the clamp.
TEST_F(MachineCheck, AHolderModelFromTheToolLibrary) {
  std::string stl = "solid holder\n";
  const double lo[3] = {-50, -50, -60}, hi[3] = {50, 50, 0};
  auto v = [&](int i) {
    return std::to_string(i & 1 ? hi[0] : lo[0]) + " " + std::to_string(i & 2 ? hi[1] : lo[1]) + " " +
           std::to_string(i & 4 ? hi[2] : lo[2]);
  };
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : faces)
    stl += "facet normal 0 0 0\nouter loop\nvertex " + v(f[0]) + "\nvertex " + v(f[1]) + "\nvertex " + v(f[2]) +
           "\nendloop\nendfacet\n";
  write(dir / "holder.stl", stl + "endsolid holder\n");
  write(dir / "tools.yaml",
        "tools:\n  1: {type: flat, diameter: 10, flute_length: 20, length: 40, gauge_length: 120, "
        "holder_mesh: holder.stl}\n");
  write(dir / "p.ngc", "G21 G90 G94\nT1 M6\nS1000 M3\nG0 X20 Y0 Z50 A0 C0\nG1 Z-25 F500\nG0 Z50\nM30\n");
  write(dir / "job.yaml",
        "job: t\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: p.ngc}\n"
        "fixtures: [{file: " +
            (kExample / "clamp.stl").string() + "}]\nstock: {box: {min: [-40, -40, -30], max: [40, 40, 0]}}\n");
  const CommandResult r = check(dir / "job.yaml");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const std::vector<nlohmann::json> events = machine_events(json());
  ASSERT_EQ(events.size(), 1u) << json().dump(1);
  EXPECT_EQ(events[0]["bodies"], nlohmann::json::array({"T1 holder", "fixture clamp"}));
  EXPECT_EQ(events[0]["line"], "p.ngc:5");
  EXPECT_NEAR(events[0]["depth_mm"].get<double>(), 5.0, 0.01);
  // A holder model that is not there: the tool library's error.
  write(dir / "tools.yaml", "tools:\n  1: {type: flat, diameter: 10, flute_length: 20, holder_mesh: none.stl}\n");
  expect_error(check(dir / "job.yaml"), "'tools.1.holder_mesh': expected an existing mesh file");
}

TEST_F(MachineCheck, BadModelsAndFixtures) {
  // A machine model that is one triangle, not a solid.
  write(dir / "flat.stl",
        "solid f\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
        "endsolid f\n");
  std::string machine = vcut::cli::test::bundled_machine_text("3axis");
  const std::size_t at = machine.find("  Z: [{file:");
  ASSERT_NE(at, std::string::npos);
  machine.insert(at + 6, "{file: " + (dir / "flat.stl").string() + ", name: plate}, ");
  write(dir / "m.yaml", machine);
  write(dir / "p.ngc", "G21 G90\nT1 M6\nG0 X0 Y0 Z10\nM30\n");
  write(dir / "j.yaml", "job: t\nmachine: m.yaml\ntools: " + (kExample / "tools.yaml").string() +
                            "\nprogram: {file: p.ngc}\nstock: {box: {min: [0, 0, -10], max: [10, 10, 0]}}\n");
  expect_error(run_vcut("check " + (dir / "j.yaml").string()), "flat.stl: machine model on Z: not a closed mesh");
  // A fixture file that does not exist.
  write(dir / "job.yaml", "job: t\nmachine: table-table-ac\ntools: " + (kExample / "tools.yaml").string() +
                              "\nprogram: {file: p.ngc}\nfixtures: [{file: vice.stl}]\n"
                              "stock: {box: {min: [-40, -40, -30], max: [40, 40, 0]}}\n");
  expect_error(run_vcut("check " + (dir / "job.yaml").string()), "'fixtures[0].file': expected an existing mesh file");
  // A clamp inside the stock at the start: a warning naming both.
  write(dir / "p.ngc", "G21 G90\nT1 M6\nG0 X0 Y0 Z100\nM30\n");
  write(dir / "job.yaml", "job: t\nmachine: table-table-ac\ntools: " + (kExample / "tools.yaml").string() +
                              "\nprogram: {file: p.ngc}\nfixtures: [{file: " + (kExample / "clamp.stl").string() +
                              "}]\nstock: {box: {min: [-40, -40, -30], max: [80, 40, 0]}}\n");
  const CommandResult r = check(dir / "job.yaml");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: fixture clamp intersects the stock at the start"), std::string::npos) << r.output;
}

}  // namespace
