// The pose engine end to end through the real binary (issue 5): `vcut poses` (time stamps of
// the jerk-limited feed, servo lag and contour error), `vcut compensate` read back as a
// program whose actual poses land on the nominal ones, and five-axis `vcut simulate` on APT
// CL data. Expected values are closed forms worked in the comments, never the binary's output.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "csv_table.h"
#include "run_vcut.h"

namespace {
namespace fs = std::filesystem;
using vcut::cli::test::CommandResult;
using vcut::cli::test::Csv;
using vcut::cli::test::expect_error;
using vcut::cli::test::read_csv;
using vcut::cli::test::run_vcut;
using vcut::cli::test::write;

// poses.csv prints 10 significant digits: 1e-8 mm at 100 mm, 1e-9 s at 4 s.
constexpr double kPrintPrecision = 1e-4;  // mm, the round trip's bound (as rs274's tests)
constexpr double kTimePrecision = 1e-6;   // s: 10 digits, and the 5e-7 mm/min reversal speed
constexpr double kRelativeServo = 0.01;   // the 1 % for the circle shrink
constexpr double kDeg = M_PI / 180.0;

// A CSV file with a header row; cells by column name. poses.csv has no quoted fields.
// Binary STL: 80-byte header, uint32 triangle count, then 50-byte records (normal, three
// vertices as little-endian floats, uint16 attribute). Returns every vertex of every triangle.
std::vector<std::array<double, 3>> read_binary_stl_vertices(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::array<double, 3>> out;
  if (bytes.size() < 84) {
    ADD_FAILURE() << path << ": too short for a binary STL";
    return out;
  }
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + 80, 4);
  EXPECT_EQ(bytes.size(), 84u + 50u * count) << path << ": size does not match the triangle count";
  if (bytes.size() != 84u + 50u * count) return out;
  for (std::uint32_t t = 0; t < count; ++t) {
    float f[12];
    std::memcpy(f, bytes.data() + 84 + 50 * static_cast<size_t>(t), sizeof f);
    for (int k = 0; k < 3; ++k) out.push_back({f[3 + 3 * k], f[4 + 3 * k], f[5 + 3 * k]});
  }
  return out;
}

class PoseCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() /
          ("vcut_pose_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    write(dir / "tools.yaml",
          "tools:\n  1: {type: flat, diameter: 10, corner_radius: 0, flute_length: 15, "
          "shank_diameter: 10, length: 20, "
          "gauge_length: 100}\n");
  }
  void TearDown() override { fs::remove_all(dir); }

  // `vcut poses` on job text (written to NAME.yaml), CSV to NAME.csv.
  Csv poses(const std::string& name, const std::string& job) {
    write(dir / (name + ".yaml"), job);
    const CommandResult r =
        run_vcut("poses --quiet " + (dir / (name + ".yaml")).string() + " --out " + (dir / (name + ".csv")).string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return read_csv(dir / (name + ".csv"));
  }
  nlohmann::json simulate(const std::string& name, const std::string& job) {
    write(dir / (name + ".yaml"), job);
    const CommandResult r = run_vcut("simulate --quiet " + (dir / (name + ".yaml")).string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(dir / ("out_" + name) / "report.json");
    return in ? nlohmann::json::parse(in) : nlohmann::json();
  }

  fs::path dir;
};

// 1. A rest-to-rest G1 where every limit is reached. F = 1200 mm/min (v = 20 mm/s), path
// acceleration a = 100 mm/s^2, jerk j = 1000 mm/s^3, L = 50 mm.
// Derivation: speeding up 0 -> v with zero acceleration at both ends takes jerk ramps of a/j
// and a constant-acceleration phase (reached since v = 20 >= a^2/j = 10): T_acc = v/a + a/j
// (0.2 + 0.1 = 0.3 s). The acceleration profile is symmetric in time, so the mean speed is
// v/2 and the distance v T_acc / 2 = 3 mm; slowing down is the mirror. Cruise covers
// L - v T_acc = 44 mm (>= 0: cruise reached) in L/v - T_acc. Total
//   T = 2 T_acc + L/v - T_acc = L/v + v/a + a/j = 2.5 + 0.2 + 0.1 = 2.8 s.
// The G1 starts at rest: the G0 before it runs along +X and the G1 back along -X, a reversal
// (turn of pi) where the blend rule's corner radius, hence speed, is 0; G61 is not read.
TEST_F(PoseCli, ThreeAxisRestToRestBlockTime) {
  write(dir / "line.ngc", "G21 G90 G94\nT1 M6\nG0 X0 Y0 Z5\nG0 X60 Y0 Z5\nG1 X10 F1200\nM2\n");
  const Csv csv = poses("line",
                        "job: line\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: line.ngc}\n"
                        "stock: {box: {min: [0, 0, -20], max: [60, 40, 0]}}\n"
                        "feed: {acceleration: 100, jerk: 1000}\ndensify: {step: 1}\n");
  const double F = 1200.0, v = F / 60.0, a = 100.0, j = 1000.0, L = 50.0;
  ASSERT_GT(csv.rows.size(), 3u);
  const std::vector<std::string> columns = {"block", "source", "t", "x", "y", "z",   "i",
                                            "j",     "k",      "X", "Y", "Z", "feed"};
  EXPECT_EQ(csv.header, columns);  // no servo, no errors: no actual columns
  // A sample closes the motion from the previous one (densify.h), so the G1 starts at the last
  // G0 row (line 4) and ends at its own last row (line 5): its time is their t difference.
  double t_start = -1.0, t_end = -1.0, max_feed = 0.0;
  int g1_rows = 0;
  for (size_t r = 0; r < csv.rows.size(); ++r) {
    if (r > 0) {
      EXPECT_GT(csv.num(r, "t"), csv.num(r - 1, "t")) << "row " << r;
    }
    if (csv.text(r, "source") == "line.ngc:4") t_start = csv.num(r, "t");
    if (csv.text(r, "source") != "line.ngc:5") continue;
    ++g1_rows;
    t_end = csv.num(r, "t");
    EXPECT_LE(csv.num(r, "feed"), F * (1.0 + 1e-9)) << "row " << r;
    max_feed = std::max(max_feed, csv.num(r, "feed"));
  }
  EXPECT_EQ(g1_rows, 50);  // densify step 1 mm over 50 mm
  ASSERT_GE(t_start, 0.0);
  EXPECT_NEAR(t_end - t_start, L / v + v / a + a / j, kTimePrecision);
  EXPECT_NEAR(max_feed, F, 1e-6);  // cruise reached
  // The per-block file beside it: one row per block, the G1's time the same closed form.
  const Csv blocks = read_csv(dir / "line_blocks.csv");
  ASSERT_TRUE(blocks.has("time_s") && blocks.has("q") && blocks.has("source"));
  bool block_found = false;
  for (size_t r = 0; r < blocks.rows.size(); ++r) {
    if (blocks.text(r, "source") != "line.ngc:5") continue;
    block_found = true;
    EXPECT_EQ(blocks.text(r, "kind"), "linear");
    EXPECT_NEAR(blocks.num(r, "time_s"), L / v + v / a + a / j, kTimePrecision);
  }
  EXPECT_TRUE(block_found);
  // The acceleration phase ends v T_acc / 2 = 3 mm into the block (x = 57) at T_acc = 0.3 s.
  bool found = false;
  for (size_t r = 0; r < csv.rows.size(); ++r) {
    if (csv.text(r, "source") != "line.ngc:5" || std::abs(csv.num(r, "x") - 57.0) > 1e-9) continue;
    found = true;
    EXPECT_NEAR(csv.num(r, "t") - t_start, v / a + a / j, kTimePrecision);
    EXPECT_NEAR(csv.num(r, "feed"), F, 1e-6);
  }
  EXPECT_TRUE(found);
}

// 2. Servo lag: `servo: {kv: 20, omega_n: ideal}` is a first-order position loop x' = Kv (c - x)
// on every axis, sampled at 0.1 ms. F = 3000 mm/min, v = 50 mm/s.
// - Straight line: in cruise the lag e = c - x obeys e' = v - Kv e -> e = v/Kv = 2.5 mm
//   (the sampled loop gives the same: e[k+1] = e[k] (1 - Kv dT) + v dT has the fixed point
//   v/Kv), along the path: the actual tip stays on the line, contour error 0.
// - Circle of radius R = 10 at angular rate w = v/R = 5 /s: each axis is driven by a sinusoid,
//   so in steady state it follows with gain 1/sqrt(1 + (w/Kv)^2) and the same phase lag on
//   both axes: the actual tip runs on a circle of radius R/sqrt(1 + (w/Kv)^2), and the contour
//   error is R [1 - 1/sqrt(1 + (w/Kv)^2)] = 10 (1 - 1/sqrt(1.0625)) mm = 298.6 um. Sampling
//   at dT shifts it by O(Kv dT) = 0.2 %; the chords (0.1 um tolerance) by < 0.04 %: 1 %.
// An axis program (rotary words without TCP) starts where the machine stands: xyzac-trt's home
// has Z at 120 (the nose 120 mm over the table, its gauge point at the origin at all-zero axes)
// and the rotaries at 0. T1 M6 leaves the spindle there, so the tool's tip is its 100 mm gauge
// length below the nose: the start row has tip z = 20 and Z = 120, the machine not moved. (It
// once read the home's Z as the tip, so that Z had to be 220: out of its travel.)
TEST_F(PoseCli, AxisProgramStartsAtTheMachinesHome) {
  write(dir / "tilt.ngc", "G21 G90 G94\nT1 M6\nG0 X0 Y0 Z15 A0 C0\nG0 A-30\nM2\n");
  const Csv csv = poses("tilt",
                        "job: tilt\nmachine: xyzac-trt\ntools: tools.yaml\nprogram: {file: tilt.ngc}\n"
                        "stock: {box: {min: [-20, -20, -20], max: [20, 20, 0]}}\n");
  ASSERT_GT(csv.rows.size(), 2u);
  EXPECT_EQ(csv.text(0, "block"), "-1");
  EXPECT_NEAR(csv.num(0, "z"), 20.0, 1e-9);
  EXPECT_NEAR(csv.num(0, "Z"), 120.0, 1e-9);
  EXPECT_NEAR(csv.num(1, "Z"), 115.0, 1e-9);  // the first move: 5 mm down
}

TEST_F(PoseCli, ServoLagAlongLineAndCircleShrink) {
  // A 110 mm lead-in along -Y ends tangent to the clockwise circle about the origin, run three
  // times (P3): the lag's transient decays as exp(-Kv t), 4.5e-5 after 0.5 s.
  write(dir / "circle.ngc", "G21 G90 G94 G17\nT1 M6\nG0 X10 Y110 Z5\nG1 Y0 F3000\nG2 X10 Y0 I-10 J0 P3\nM2\n");
  const Csv csv = poses("circle",
                        "job: circle\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: circle.ngc, initial_tool: 1}\n"
                        "stock: {box: {min: [0, 0, -20], max: [60, 40, 0]}}\n"
                        "densify: {chord_tolerance: 0.0001, step: 0.5}\n"
                        "servo: {kv: 20, omega_n: ideal, period: 0.0001}\n"
                        "start: {X: 10, Y: 110, Z: 5}\n");  // T1's tip at rest on the lead-in's start
  const double F = 3000.0, v = F / 60.0, kv = 20.0, R = 10.0, w = v / R;
  const double shrink_um = 1000.0 * R * (1.0 - 1.0 / std::sqrt(1.0 + (w / kv) * (w / kv)));
  ASSERT_GT(csv.rows.size(), 100u);
  double line_start = -1.0, circle_start = -1.0;
  int line_rows = 0, circle_rows = 0;
  for (size_t r = 0; r < csv.rows.size(); ++r) {
    const std::string& source = csv.text(r, "source");
    const double t = csv.num(r, "t");
    if (source == "circle.ngc:4") {
      if (line_start < 0.0) line_start = csv.num(r - 1, "t");
      circle_start = t;  // the last line row is where the circle starts
      // Lag along the line: no contour error anywhere on it.
      EXPECT_LT(csv.num(r, "contour_error_um"), 1e-3) << "row " << r;
      EXPECT_NEAR(csv.num(r, "actual_x"), 10.0, 1e-9) << "row " << r;
      if (t - line_start < 1.0 || std::abs(csv.num(r, "feed") - F) > 1e-6) continue;  // cruise, settled
      ++line_rows;
      EXPECT_NEAR(csv.num(r, "actual_y") - csv.num(r, "y"), v / kv, 1e-6) << "row " << r;  // behind: moving -Y
    } else if (source == "circle.ngc:5") {
      if (t - circle_start < 0.5 || std::abs(csv.num(r, "feed") - F) > 1e-6) continue;  // steady, before slowing
      ++circle_rows;
      EXPECT_NEAR(csv.num(r, "contour_error_um"), shrink_um, kRelativeServo * shrink_um) << "row " << r;
      // Inside the commanded circle by that much.
      const double radius = std::hypot(csv.num(r, "actual_x"), csv.num(r, "actual_y"));
      EXPECT_NEAR(1000.0 * (R - radius), shrink_um, kRelativeServo * shrink_um) << "row " << r;
    }
  }
  EXPECT_GT(line_rows, 50);     // about 1.2 s of cruise at 0.5 mm steps
  EXPECT_GT(circle_rows, 300);  // about 3 turns of 126 steps
}

// 3. `vcut compensate` round trip on table-table-ac with geometric errors. The compensated
// axis program, run on the same machine with `errors: machine`, must put the actual tool tip
// on the nominal tip of the original program, row for row.
TEST_F(PoseCli, CompensateRoundTrip) {
  // The bundled machine plus an errors line: its own errors block is commented out.
  std::string machine = vcut::cli::test::bundled_machine_text("table-table-ac");
  ASSERT_FALSE(machine.empty());
  ASSERT_EQ(machine.find("\nerrors:"), std::string::npos) << "the bundled file's errors block is live";
  machine += "\nerrors: {E_X0C: 20, E_A0C: 80, E_XX: {table: [[-300, -10], [300, 15]]}, E_C0Y: 40}\n";
  write(dir / "machine.yaml", machine);
  write(dir / "square.ngc", "G21 G90 G94\nT1 M6\nG0 X50 Y20 Z5\nG1 Z-2 F600\nG1 X90\nG1 Y40\nG1 X50 Y20\nG0 Z5\nM2\n");
  const std::string common =
      "machine: machine.yaml\ntools: tools.yaml\nstock: {box: {min: [0, 0, -20], max: [100, 60, "
      "0]}}\nstart: {X: 50, Y: 20, Z: 5}\n";  // T1 (initial_tool) at rest at the first point
  const std::string nominal_job =
      "job: nominal\n" + common + "program: {file: square.ngc, initial_tool: 1}\ndensify: {step: 2}\n";
  const Csv nominal = poses("nominal", nominal_job);
  const Csv uncompensated =
      poses("uncompensated", "job: uncompensated\n" + common +
                                 "program: {file: square.ngc, initial_tool: 1}\ndensify: {step: 2}\nerrors: machine\n");

  // Without compensation the errors show (so the comparison below can fail): E_XX alone moves
  // the tip 2.5 + X/24 um along x, 4.6 to 6.3 um at X = 50..90, and E_A0C tilts the table
  // 80 urad about x, some 8 um at 100 mm from the A axis.
  ASSERT_EQ(uncompensated.rows.size(), nominal.rows.size());
  double max_error_mm = 0.0;
  for (size_t r = 0; r < uncompensated.rows.size(); ++r)
    for (const char* c : {"x", "y", "z"})
      max_error_mm =
          std::max(max_error_mm, std::abs(uncompensated.num(r, std::string("actual_") + c) - uncompensated.num(r, c)));
  EXPECT_GT(max_error_mm, 0.005);

  const CommandResult c =
      run_vcut("compensate " + (dir / "nominal.yaml").string() + " --out " + (dir / "comp.ngc").string());
  ASSERT_EQ(c.exit_code, 0) << c.output;  // every pose converged
  EXPECT_NE(c.output.find("residual after compensation"), std::string::npos) << c.output;
  std::ifstream comp_in(dir / "comp.ngc");
  const std::string comp((std::istreambuf_iterator<char>(comp_in)), std::istreambuf_iterator<char>());
  EXPECT_NE(comp.find("(square.ngc:5)"), std::string::npos) << comp;  // comments name the source line
  EXPECT_FALSE(std::regex_search(comp, std::regex("[0-9][eE][-+]?[0-9]"))) << "rs274 numbers have no exponent:\n"
                                                                           << comp;

  const Csv actual =
      poses("compensated", "job: compensated\n" + common + "program: {file: comp.ngc}\nerrors: machine\n");
  // Row alignment: comp.ngc has one line per row of the nominal run, its start row included
  // (the "(start)" line), and each line is one block that densifies into one sample (axis
  // blocks, no step or angle limit). The read-back run adds its own start row before them:
  // the program's position before its first line. So actual row r + 1 <-> nominal row r.
  ASSERT_EQ(actual.rows.size(), nominal.rows.size() + 1);
  // Every line, the start included, is run with the tool its pose was computed for: the
  // machine axes stay within 0.1 mm, 0.01 deg of the nominal run's (compensation moves them
  // by tens of um); a line read with no tool would sit the gauge length (100 mm) off in Z.
  for (size_t r = 0; r < nominal.rows.size(); ++r) {
    for (const char* k : {"X", "Y", "Z"})
      EXPECT_NEAR(actual.num(r + 1, k), nominal.num(r, k), 0.1) << "nominal row " << r << ", " << k;
    for (const char* k : {"A", "C"})
      EXPECT_NEAR(actual.num(r + 1, k), nominal.num(r, k), 0.01) << "nominal row " << r << ", " << k;
  }
  int compared = 0;
  for (size_t r = 0; r < nominal.rows.size(); ++r) {
    const bool feed_row = nominal.text(r, "source") != "" && nominal.text(r, "source") != "square.ngc:3" &&
                          nominal.text(r, "source") != "square.ngc:8";  // G1 lines 4-7
    if (!feed_row) continue;
    ++compared;
    for (const char* k : {"x", "y", "z"})
      EXPECT_NEAR(actual.num(r + 1, std::string("actual_") + k), nominal.num(r, k), kPrintPrecision)
          << "nominal row " << r << " (" << nominal.text(r, "source") << "), " << k;
    for (const char* k : {"i", "j", "k"})
      EXPECT_NEAR(actual.num(r + 1, std::string("actual_") + k), nominal.num(r, k), kPrintPrecision)
          << "nominal row " << r << ", " << k;
  }
  EXPECT_EQ(compared, 4 + 20 + 10 + 23);  // ceil(L / 2 mm) for L = 7, 40, 20, 44.7 mm
}

// The same for an APT program: the compensated CL data are the poses a tool-centre-point
// controller turns into the compensated commands; read back on the machine with errors,
// they land on the nominal poses. The FROM/ line is the read-back run's start row, so here
// the rows align one to one.
TEST_F(PoseCli, CompensateAptRoundTrip) {
  std::string machine = vcut::cli::test::bundled_machine_text("table-table-ac");
  machine += "\nerrors: {E_X0C: 20, E_A0C: 80, E_C0Y: 40}\n";
  write(dir / "machine.yaml", machine);
  write(dir / "tilt.apt",
        "UNITS/MM\nMULTAX/ON\nCUTTER/10\nLOADTL/1\nFROM/50,20,5,0.1,0,0.9949874\nFEDRAT/600,MMPM\n"
        "GOTO/50,20,-2,0.1,0,0.9949874\nGOTO/90,20,-2,0.2,0,0.9797959\nGOTO/90,40,-2,0.2,0.1,0.9746794\nFINI\n");
  // The tool starts tilted, away from the pole of C: near the pole the two branches tie on
  // least motion, and the compensated commands' small A offset could tip the read-back's
  // choice to the other branch (whose errors differ) - a real controller's ambiguity too.
  const std::string common =
      "machine: machine.yaml\ntools: tools.yaml\nstock: {box: {min: [0, 0, -20], max: [100, 60, 0]}}\n";
  const Csv nominal = poses("apt_nominal", "job: n\n" + common + "program: {file: tilt.apt}\ndensify: {step: 5}\n");
  const CommandResult c =
      run_vcut("compensate " + (dir / "apt_nominal.yaml").string() + " --out " + (dir / "comp.apt").string());
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const Csv actual =
      poses("apt_back", "job: b\n" + common + "program: {file: comp.apt, dialect: apt}\nerrors: machine\n");
  ASSERT_EQ(actual.rows.size(), nominal.rows.size());
  double worst = 0.0;
  for (size_t r = 0; r < nominal.rows.size(); ++r)
    for (const char* k : {"x", "y", "z", "i", "j", "k"})
      worst = std::max(worst, std::abs(actual.num(r, std::string("actual_") + k) - nominal.num(r, k)));
  EXPECT_LT(worst, kPrintPrecision);
  // Without compensation the same poses miss by tens of um (the test can fail).
  const Csv raw =
      poses("apt_raw", "job: r\n" + common + "program: {file: tilt.apt}\ndensify: {step: 5}\nerrors: machine\n");
  double raw_worst = 0.0;
  for (size_t r = 0; r < raw.rows.size(); ++r)
    for (const char* k : {"x", "y", "z"})
      raw_worst = std::max(raw_worst, std::abs(raw.num(r, std::string("actual_") + k) - raw.num(r, k)));
  EXPECT_GT(raw_worst, 0.005);
}

TEST_F(PoseCli, CompensateNeedsErrors) {
  write(dir / "square.ngc", "G21 G90 G94\nT1 M6\nG0 X50 Y20 Z5\nG1 Z-2 F600\nM2\n");
  write(dir / "job.yaml",
        "job: none\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: square.ngc}\n"
        "stock: {box: {min: [0, 0, -20], max: [100, 60, 0]}}\n");
  expect_error(run_vcut("compensate " + (dir / "job.yaml").string() + " --out " + (dir / "c.ngc").string()), "errors");
  EXPECT_FALSE(fs::exists(dir / "c.ngc"));
}

// 4. Five-axis simulate, APT CL data on table-table-ac. A 10 mm flat end mill with its axis
// u = (sin 20, 0, cos 20) (tilted 20 deg about y) runs with its tip on the line x = 15, z = -10
// from y = -35 to 35, through a 18 x 40 x 20 box (x 0..18, y -20..20, z -20..0).
// Translating along y (perpendicular to u) the cylinder sweeps a prism over its projection on
// the xz plane: with w = (cos 20, 0, -sin 20), the strip -5 <= (p - tip).w <= 5 above the end
// face (p - tip).u >= 0. The machined wall is the plane (p - tip).w = -5; the strip's far side
// (+5) lies beyond x = 18 for z > -11.7, so no sliver is left. Removed cross-section: the
// quadrilateral corner C0 = tip - 5w = (10.3015, -8.2899), floor at x = 18 (tip + (3/cos20) w)
// = (18, -11.0919), (18, 0), wall top C0 + (8.2899/cos20) u = (13.3188, 0): 62.099 mm2 by the
// shoelace formula, times 40 mm.
TEST_F(PoseCli, FiveAxisFlankPlane) {
  const double s20 = std::sin(20 * kDeg), c20 = std::cos(20 * kDeg);
  char axis[64];
  std::snprintf(axis, sizeof axis, "%.10f,0,%.10f", s20, c20);
  const std::string a = axis;
  write(dir / "flank.apt",
        "$$ flank cut, axis tilted 20 deg about y\nUNITS/MM\nCUTTER/10\nLOADTL/1\nMULTAX/ON\n"
        "FROM/15,-35,30," +
            a + "\nFEDRAT/600,MMPM\nGOTO/15,-35,-10," + a + "\nGOTO/15,35,-10," + a + "\nGOTO/15,35,30," + a +
            "\nFINI\n");
  const double v = 0.2;
  const nlohmann::json j = simulate("flank",
                                    "job: flank\nmachine: table-table-ac\ntools: tools.yaml\n"
                                    "program: {file: flank.apt, dialect: apt}\n"
                                    "stock: {box: {min: [0, -20, -20], max: [18, 20, 0]}}\n"
                                    "engine: {kind: dexel, resolution: 0.2, threads: 2}\nreport: {out: out_flank}\n");
  ASSERT_TRUE(j.contains("pose_engine")) << j.dump();
  EXPECT_EQ(j["pose_engine"]["poses"], 4);  // FROM/ and three GOTO/s, one sample each
  EXPECT_EQ(j["pose_engine"]["rotating_moves"], 0);
  for (const auto& e : j["pose_engine"]["events"]) EXPECT_NE(e["kind"], "unreachable") << e.dump();
  // Shoelace of the cross-section above, in closed form.
  const double x0 = 15 - 5 * c20, z0 = -10 + 5 * s20;  // C0
  const double x_top = x0 + (-z0 / c20) * s20;         // wall at z = 0
  const double z_floor = -10 - (3.0 / c20) * s20;      // floor at x = 18
  const double px[4] = {x0, 18, 18, x_top}, pz[4] = {z0, z_floor, 0, 0};
  double twice_area = 0.0;
  for (int k = 0; k < 4; ++k) twice_area += px[k] * pz[(k + 1) % 4] - px[(k + 1) % 4] * pz[k];
  const double removed = 0.5 * std::abs(twice_area) * 40.0;  // 2483.94 mm3
  EXPECT_NEAR(j["summary"]["removed_volume_mm3"].get<double>(), removed, 0.005 * removed);

  // Mesh vertices on the wall: x > 5 (not the x = 0 face), -7.5 <= z <= -0.5 (0.5 mm from the
  // top face, 0.8 mm along the wall from the floor's crease), |y| <= 19.5 (not the end
  // faces). In that window the wall is the only surface, so every vertex is on it. The dexel
  // endpoints are exact along their rays (1 um), but the mesh vertices are not endpoints: the
  // mesher places one per surface cell (or per merged flat block) from the crossings on its
  // edges, and rounds creases off by up to v/2 (docs/PERFORMANCE.md); v/2 is thus the bound every mesh vertex of the
  // machined surface must meet (on a plane, away from creases, it is far closer).
  const auto vertices = read_binary_stl_vertices(dir / "out_flank" / "machined.stl");
  int on_wall = 0;
  double worst = 0.0;
  for (const auto& p : vertices) {
    if (p[0] <= 5.0 || p[2] < -7.5 || p[2] > -0.5 || std::abs(p[1]) > 19.5) continue;
    ++on_wall;
    const double r = (p[0] - 15.0) * c20 - (p[2] + 10.0) * s20;  // (p - tip).w
    worst = std::max(worst, std::abs(r + 5.0));
  }
  // About 7.4 x 39 mm2 of flat wall: the mesher merges it into blocks of at most 16 cells
  // (3.2 mm squares at 0.2 mm), so at least 28 vertices.
  EXPECT_GT(on_wall, 28);
  EXPECT_LE(worst, v / 2.0);
}

// The axis tilting from (0,0,1) to (sin 30, 0, cos 30) along the same path: five-axis moves
// cut as translation pieces within v/10 of the rigid motion, by both engines; the two
// machined surfaces must agree as two meshings of one solid do (v/4, the engines' own check
// threshold) plus the pieces' bound v/10.
// A 3+2 program as Fanuc/Haas posts write it, on the AC trunnion: G68.2 over the part's -Y
// face (origin at its centre, J90: the feature Z is the face's outward normal), G53.1 (A to
// -90), two plunges 5 deep 12 mm apart, G69, G91 G28 Z0 (out along the tool), G0 A0 C0 (the
// table back, the linear axes held), and a plunge 4 deep in the top face. The 10 mm flat end
// mill removes three cylinders: pi 5^2 (5 + 5 + 4) = 350 pi mm3.
TEST_F(PoseCli, ThreePlusTwoTiltedPlaneHoles) {
  write(dir / "holes.nc",
        "%\nO0001\nG21 G90 G17 G40 G49 G80\nT1 M6\nS8000 M3\nG0 X0 Y0\nG43 H1 Z50.\n"
        "G68.2 X0 Y-20. Z-15. I0 J90. K0\nG53.1\nG0 X0 Y0 Z10.\nG1 Z-5. F200\nG0 Z10.\nX12.\nG1 Z-5.\nG0 Z10.\n"
        "G69\nG91 G28 Z0\nG90 G0 A0 C0\nG0 X0 Y0 Z10.\nG1 Z-4. F200\nG0 Z50.\nM30\n%\n");
  const nlohmann::json j =
      simulate("holes",
               "job: holes\nmachine: table-table-ac\ntools: tools.yaml\nprogram: {file: holes.nc}\n"
               "stock: {box: {min: [-25, -20, -30], max: [25, 20, 0]}}\n"
               "engine: {kind: dexel, resolution: 0.1, threads: 2}\nreport: {out: out_holes}\n");
  const double removed = 350.0 * M_PI;  // 1099.56 mm3
  EXPECT_NEAR(j["summary"]["removed_volume_mm3"].get<double>(), removed, 0.005 * removed);
}

// A probe finds the stock's top (box z -10..0) from Z10 down to Z-25; G10 L20 makes that Z0
// and the 10 mm end mill cuts 2 below it: a plunge and a 10 mm slot, pi 5^2 2 + 10 10 2 =
// 357.08 mm3. A probe that ran to its end would put Z0 at -25 and cut nothing.
TEST_F(PoseCli, ProbeTouchesTheStock) {
  write(dir / "probe.ngc",
        "G21 G90 G17\nT1 M6\nG0 X10 Y10 Z10\nG38.2 Z-25 F100\nG10 L20 P1 Z0\nG0 Z5\nG1 Z-2 F200\nX20\nG0 Z20\nM30\n");
  const nlohmann::json j = simulate("probe",
                                    "job: probe\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: probe.ngc}\n"
                                    "stock: {box: {min: [0, 0, -10], max: [40, 40, 0]}}\n"
                                    "engine: {kind: dexel, resolution: 0.1, threads: 2}\nreport: {out: out_probe}\n");
  const double removed = M_PI * 25.0 * 2.0 + 10.0 * 10.0 * 2.0;
  EXPECT_NEAR(j["summary"]["removed_volume_mm3"].get<double>(), removed, 0.005 * removed);
}

// The tilting cut's removed volume by a second method: the stock's cells (centres, spacing h)
// that some instant of the programmed rigid motion puts inside the flat end mill (D10, flutes
// 15 mm): the tip straight from (15, -35, -10) to (15, 35, -10), the axis turning on its great
// circle from +Z to (0.5, 0, 0.866); a point at y meets the tool only while the tip's y is
// within 5 mm of it (the axis has no y part), sampled every 1/8 mm of tip travel.
double tilting_cut_volume_mm3(double h) {
  const Eigen::Vector3d a0(0, 0, 1), a1(0.5, 0, std::sqrt(0.75));
  const Eigen::Vector3d turn_axis = a0.cross(a1).normalized();
  const double angle = std::acos(a0.dot(a1));
  std::size_t inside_cells = 0;
  for (double x = 9.5 + 0.5 * h; x < 18; x += h)  // the tool reaches x >= 15 - 5
    for (double y = -20 + 0.5 * h; y < 20; y += h)
      for (double z = -13 + 0.5 * h; z < 0; z += h) {  // its rim dips to -10 - 5 sin 30
        const double t0 = std::max(0.0, (y - 5 + 35) / 70), t1 = std::min(1.0, (y + 5 + 35) / 70);
        const int n = static_cast<int>(std::ceil((t1 - t0) * 70 * 8));
        bool inside = false;
        for (int s = 0; s <= n && !inside; ++s) {
          const double t = t0 + (t1 - t0) * s / n;
          const Eigen::Vector3d d = Eigen::Vector3d(x, y, z) - Eigen::Vector3d(15, -35 + 70 * t, -10);
          const Eigen::Vector3d u = Eigen::AngleAxisd(angle * t, turn_axis) * a0;
          const double along = d.dot(u);
          inside = along >= 0 && along <= 15 && (d - along * u).squaredNorm() <= 25;
        }
        inside_cells += inside;
      }
  return static_cast<double>(inside_cells) * h * h * h;
}

TEST_F(PoseCli, FiveAxisTiltingEnginesAgree) {
  const double reference_mm3 = tilting_cut_volume_mm3(0.25);
  write(dir / "tilt.apt",
        "$$ the axis tilts 0 -> 30 deg about y along the cut\nUNITS/MM\nCUTTER/10\nLOADTL/1\n"
        "MULTAX/ON\nFROM/15,-35,30,0,0,1\nFEDRAT/600,MMPM\nGOTO/15,-35,-10,0,0,1\n"
        "GOTO/15,35,-10,0.5,0,0.8660254038\nGOTO/15,35,30,0.5,0,0.8660254038\nFINI\n");
  const double v = 0.2;
  for (const std::string engine : {"dexel", "vdb", "both"}) {
    SCOPED_TRACE(engine);
    const nlohmann::json j = simulate("tilt_" + engine,
                                      "job: tilt\nmachine: table-table-ac\ntools: tools.yaml\n"
                                      "program: {file: tilt.apt, dialect: apt}\n"
                                      "stock: {box: {min: [0, -20, -20], max: [18, 20, 0]}}\n"
                                      "engine: {kind: " +
                                          engine +
                                          ", resolution: 0.2, threads: 2}\ndensify: {angle: 2}\n"
                                          "report: {out: out_tilt_" +
                                          engine + "}\n");
    ASSERT_TRUE(j.contains("pose_engine")) << j.dump();
    // FROM/, the plunge, 30 deg in steps of at most 2 deg (q = 15), the retract.
    EXPECT_EQ(j["pose_engine"]["poses"], 1 + 1 + 15 + 1);
    EXPECT_EQ(j["pose_engine"]["rotating_moves"], 15);
    for (const auto& e : j["pose_engine"]["events"]) EXPECT_NE(e["kind"], "unreachable") << e.dump();
    // The engines cut translation pieces within v / 10 = 0.02 mm of the rigid motion; over the
    // cut's boundary (walls 2 x 40 x ~11, floor 40 x 8, ends: under 1,300 mm2) that moves the
    // volume by at most 1,300 x 0.02 = 26 mm3. The reference's own grid error is below 0.3
    // mm3 (2673.4 at h = 0.25, 2673.1 at h = 0.1 and 0.2).
    EXPECT_NEAR(j["summary"]["removed_volume_mm3"].get<double>(), reference_mm3, 26.0);
    if (engine == "both") {
      ASSERT_TRUE(j.contains("engine_check")) << j.dump();
      EXPECT_LT(j["engine_check"]["p99_mm"].get<double>(), v / 4 + v / 10) << j["engine_check"].dump();
    }
  }
}

// 5. Bad pose-engine keys: exit 2, one line naming the key.
TEST_F(PoseCli, BadPoseKeys) {
  write(dir / "line.ngc", "G21 G90 G94\nT1 M6\nG0 X0 Y0 Z5\nG1 X10 F1200\nM2\n");
  const std::string base =
      "job: bad\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: line.ngc}\n"
      "stock: {box: {min: [0, 0, -20], max: [60, 40, 0]}}\n";
  const std::pair<std::string, std::string> cases[] = {{"errors: maybe\n", "errors"},
                                                       {"servo: {kv: -1}\n", "servo.kv"},
                                                       {"servo: {kv: 0}\n", "servo.kv"},
                                                       {"servo: {period: 0}\n", "servo.period"},
                                                       {"servo: {period: 5}\n", "servo.period"},
                                                       {"servo: {omega_n: 0}\n", "servo.omega_n"},
                                                       {"servo: {zeta: -0.1}\n", "servo.zeta"},
                                                       {"servo: {axes: {A: {kv: 18}}}\n", "servo.axes.A"},
                                                       {"servo: {axes: {X: {period: 1}}}\n", "servo.axes.X.period"},
                                                       {"servo: {axes: {Y: {omega_n: -5}}}\n", "servo.axes.Y.omega_n"},
                                                       // Sampled loops that diverge (Kv dT = 2.5; Kv 1000/s around
                                                       // seed 004's velocity loop at 5 ms), a period of hours' work.
                                                       {"servo: {kv: 500, omega_n: ideal}\n", "servo.kv"},
                                                       {"servo: {axes: {X: {kv: 1000}}}\n", "servo.axes.X.kv"},
                                                       {"servo: {period: 1e-9}\n", "servo.period"},
                                                       {"densify: {angle: 0}\n", "densify.angle"}};
  for (const auto& [line, key] : cases) {
    SCOPED_TRACE(line);
    write(dir / "bad.yaml", base + line);
    expect_error(run_vcut("poses " + (dir / "bad.yaml").string() + " --out " + (dir / "bad.csv").string()), key);
    EXPECT_FALSE(fs::exists(dir / "bad.csv"));
  }
}

}  // namespace
