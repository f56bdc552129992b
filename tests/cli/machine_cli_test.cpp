// `vcut machine`, `vcut fk` and `vcut ik` end to end (issue 3 item 7), run as a machine
// builder runs them: the words of `machine`, the JSON of fk and ik, CSV batches, exit codes
// and one-line errors. Expected poses are worked by hand in the comments from the bundled
// machine files' geometry (examples/machines/*.yaml); ik is also checked by running fk on
// each of its solutions, a second path through the program.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
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

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadPerDeg = kPi / 180.0;
const double kSqrt2 = std::sqrt(2.0);
// JSON numbers are printed round-trippable; what is left is the double round-off of a chain
// of a few rotations of coordinates up to ~600 mm (~1e-13 mm) and deg <-> rad conversions.
constexpr double kRoundOffMm = 1e-9;
constexpr double kRoundOffDeg = 1e-9;
constexpr double kRoundOffUnit = 1e-12;  // unit axis components
constexpr double kRoundOffUm = 1e-6;     // error vectors, um
// CSV cells are printed with 10 significant digits: 600 mm to 6e-8 mm, a unit component to 1e-10.
constexpr double kCsvPrecisionMm = 1e-6;
constexpr double kCsvPrecisionUnit = 1e-9;
// Compensation must reach 0.01 um (issue 3 item 6).
constexpr double kCompensationResidualUm = 0.01;
// fk --errors at the compensated axes reproduces the nominal tip: the residual bound plus
// the 17-digit JSON round trip of the commands.
constexpr double kCompensatedTipMm = 1e-5;

std::string g17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Tool axis in the workpiece for table-table-ac, worked from its file: the table turns A
// about +x, then C about +z on the cradle, so a workpiece vector w sits in the frame as
// Rx(a) Rz(c) w; the spindle axis is +z, hence u_w = Rz(-c) Rx(-a) z = (sin a sin c, sin a cos c,
// cos a).
std::vector<double> ac_axis(double a_deg, double c_deg) {
  const double a = a_deg * kRadPerDeg, c = c_deg * kRadPerDeg;
  return {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
}

// The linear axes of table-table-ac putting the tip on workpiece point p at (a, c): the
// workpiece point sits in the frame at q = c0 + Rx(a) (Rz(c) p - c0), c0 = (0, -20, -100) the
// A centre (the C centre is the origin); the tool side is X Y Z translations of the spindle
// nose (0, 0, 500), tip = nose - L z. So X = q.x, Y = q.y, Z = q.z - 500 + L.
std::vector<double> ac_linear(const std::vector<double>& p, double a_deg, double c_deg, double length_mm) {
  const double a = a_deg * kRadPerDeg, c = c_deg * kRadPerDeg;
  const double x = std::cos(c) * p[0] - std::sin(c) * p[1], y = std::sin(c) * p[0] + std::cos(c) * p[1], z = p[2];
  const double ry = y + 20.0, rz = z + 100.0;  // minus c0
  return {x, -20.0 + std::cos(a) * ry - std::sin(a) * rz,
          -100.0 + std::sin(a) * ry + std::cos(a) * rz - 500.0 + length_mm};
}

// The difference of two angles in deg, folded into (-180, 180].
double angle_diff_deg(double a, double b) {
  double d = std::fmod(a - b, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d <= -180.0) d += 360.0;
  return d;
}

// A small CSV reader for the program's output (quoted fields allowed: the status cell may
// contain commas).
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const {
    for (size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return static_cast<int>(i);
    return -1;
  }
  const std::string& cell(size_t row, const std::string& name) const {
    const int c = column(name);
    if (c < 0) throw std::runtime_error("no column " + name);
    return rows.at(row).at(static_cast<size_t>(c));
  }
  double number(size_t row, const std::string& name) const { return std::stod(cell(row, name)); }
};

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

Csv read_csv(const fs::path& path) {
  Csv t;
  std::ifstream in(path);
  std::string line;
  bool first = true;
  while (std::getline(in, line)) {
    if (first)
      t.header = split_csv_line(line);
    else
      t.rows.push_back(split_csv_line(line));
    first = false;
  }
  return t;
}

class MachineCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir =
        fs::temp_directory_path() /
        ("vcut_machine_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  // Runs a command that must succeed and print JSON.
  json run_json(const std::string& args) {
    const CommandResult r = run_vcut(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    try {
      return json::parse(r.output);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not JSON (" << e.what() << "): " << r.output;
      return json::object();
    }
  }

  // table-table-ac with a lone E_X0C of 10 um: the bundled file, whose commented errors
  // block is its last lines, plus one errors key at the top level.
  std::string error_machine() {
    const fs::path file = dir / "ac-x0c.yaml";
    const std::string text = vcut::cli::test::bundled_machine_text("table-table-ac");
    EXPECT_FALSE(text.empty());
    write(file, text + "\nerrors: {E_X0C: 10}\n");
    return file.string();
  }

  // The folder holds exactly these names (no temporary left by an atomic write).
  void expect_folder(const std::set<std::string>& names) {
    std::set<std::string> found;
    for (const auto& e : fs::directory_iterator(dir)) found.insert(e.path().filename().string());
    EXPECT_EQ(found, names);
  }

  fs::path dir;
};

class FkCli : public MachineCli {};
class IkCli : public MachineCli {};
class MachineCliErrors : public MachineCli {};

void expect_vec(const json& v, const std::vector<double>& expected, double tolerance, const std::string& what) {
  ASSERT_TRUE(v.is_array() && v.size() == 3) << what << ": " << v;
  for (size_t k = 0; k < 3; ++k) EXPECT_NEAR(v[k].get<double>(), expected[k], tolerance) << what << "[" << k << "]";
}

std::string axes_arg(const json& q) {
  std::string s;
  for (const char* letter : {"X", "Y", "Z", "A", "C"})
    s += (s.empty() ? "" : ",") + std::string(letter) + "=" + g17(q[letter].get<double>());
  return s;
}

// ------------------------------------------------------------------------------------ machine

TEST_F(MachineCli, TableTableAcInWords) {
  const CommandResult r = run_vcut("machine table-table-ac");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // From the file: topology WCAFXYZT, W on C on A on the frame; X Y Z outward to the tool.
  EXPECT_NE(r.output.find("workpiece chain: frame -> A -> C"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("tool chain: frame -> X -> Y -> Z"), std::string::npos) << r.output;
  std::istringstream lines(r.output);
  std::string line, a_line, c_line, x_line;
  while (std::getline(lines, line)) {
    if (line.rfind("  A: ", 0) == 0) a_line = line;
    if (line.rfind("  C: ", 0) == 0) c_line = line;
    if (line.rfind("  X: ", 0) == 0) x_line = line;
  }
  EXPECT_NE(a_line.find("limits -120 .. 30 deg"), std::string::npos) << a_line;  // limits: [-120, 30]
  EXPECT_NE(c_line.find("continuous"), std::string::npos) << c_line;             // limits: null
  EXPECT_EQ(c_line.find("limits"), std::string::npos) << c_line;
  EXPECT_NE(x_line.find("limits -300 .. 300 mm"), std::string::npos) << x_line;
  EXPECT_NE(r.output.find("geometric errors: none"), std::string::npos) << r.output;
}

TEST_F(MachineCli, NamesTheGeometricErrors) {
  const CommandResult r = run_vcut("machine " + error_machine());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("E_X0C: 10 um"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("geometric errors: none"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\n\n"), std::string::npos) << "a blank line in: " << r.output;
}

// ----------------------------------------------------------------------------------------- fk

TEST_F(FkCli, GantryASwingsTheToolAboutTheALine) {
  // gantry-wyxzcat, A = 90, L = 100: spindle nose (0, 0, 2400), tip at zero (0, 0, 2300);
  // A turns about the x-parallel line through (0, -75, 2800): tip - centre = (0, 75, -500),
  // Rx(90) (0, y, z) = (0, -z, y) = (0, 500, 75), + centre = (0, 425, 2875). The workpiece
  // sits on the frame (W next to F), so that is the tip in the workpiece. The axis
  // Rx(90) (0, 0, 1) = (0, -1, 0) (the file's (sin A sin C, -sin A cos C, cos A)).
  const json j = run_json("fk gantry-wyxzcat --axes A=90 --tool-length 100");
  expect_vec(j["tip"], {0.0, 425.0, 2875.0}, kRoundOffMm, "tip");
  expect_vec(j["axis"], {0.0, -1.0, 0.0}, kRoundOffUnit, "axis");
  EXPECT_EQ(j["status"], "ok");
  EXPECT_EQ(j["axes"]["A"].get<double>(), 90.0);
  EXPECT_EQ(j["tool_length_mm"].get<double>(), 100.0);
}

TEST_F(FkCli, LocationErrorOfCMovesTheTipByHand) {
  // E_X0C = 10 um displaces the C table by d = (10, 0, 0) um in its parent's frame at every
  // angle (ARCHITECTURE §6; tests/kinematics ErrorLocation); at A = 0 that is the frame. The
  // tool tip t stays put in the frame, so in the workpiece it is Rz(-c) (t - d): it moves by
  // -Rz(-c) d. C = 0: (-10, 0, 0); C = 90: -(0, -10, 0) = (0, 10, 0); C = 180: (10, 0, 0) um.
  // The axis is untouched (a pure translation).
  const std::string machine = error_machine();
  const std::vector<std::pair<int, std::vector<double>>> cases = {
      {0, {-10.0, 0.0, 0.0}}, {90, {0.0, 10.0, 0.0}}, {180, {10.0, 0.0, 0.0}}};
  for (const auto& [c_deg, tip_um] : cases) {
    SCOPED_TRACE("C = " + std::to_string(c_deg));
    const json j = run_json("fk " + machine + " --errors --axes C=" + std::to_string(c_deg));
    expect_vec(j["error"]["tip_um"], tip_um, kRoundOffUm, "error.tip_um");
    EXPECT_NEAR(j["error"]["tip_um_norm"].get<double>(), 10.0, kRoundOffUm);
    EXPECT_NEAR(j["error"]["axis_tilt_urad"].get<double>(), 0.0, kRoundOffUm);
    // Nominal tip at C = c: Rz(-c) (0, 0, 500) = (0, 0, 500); actual = nominal + error.
    expect_vec(j["tip"], {0.0, 0.0, 500.0}, kRoundOffMm, "tip");
    expect_vec(j["actual"]["tip"], {tip_um[0] / 1000.0, tip_um[1] / 1000.0, 500.0}, kRoundOffMm, "actual.tip");
  }
}

TEST_F(FkCli, CsvBatchAddsThePoseColumns) {
  // table-table-ac, L = 0, tip in the frame t = (X, Y, 500 + Z); in the workpiece
  // p = Rz(-c) (c0 + Rx(-a) (t - c0)), c0 = (0, -20, -100); axis (sin a sin c, sin a cos c, cos a).
  // Row 1, A = 40 (beyond the +30 limit): t - c0 = (0, 20, 600), Rx(-40) gives
  //   (0, 20 cos40 + 600 sin40, -20 sin40 + 600 cos40); axis (0, sin40, cos40).
  // Row 2, C = 90, X = 10, Y = 20, Z = -100: t = (10, 20, 400), Rz(-90) (x, y, z) = (y, -x, z)
  //   = (20, -10, 400); axis (0, 0, 1).
  // Row 3, A = -90, Z = -500: t = (0, 0, 0), t - c0 = (0, 20, 100), Rx(90) (0, y, z) = (0, -z, y)
  //   = (0, -100, 20), + c0 = (0, -120, -80); axis (0, -1, 0).
  // The columns in a shuffled order: they are matched by name.
  write(dir / "in.csv", "A,C,X,Y,Z\n40,0,0,0,0\n0,90,10,20,-100\n-90,0,0,0,-500\n");
  const CommandResult r =
      run_vcut("fk table-table-ac --csv " + (dir / "in.csv").string() + " --out " + (dir / "out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Csv t = read_csv(dir / "out.csv");
  const std::vector<std::string> header = {"A",     "C",     "X",      "Y",      "Z",      "tip_x",
                                           "tip_y", "tip_z", "axis_i", "axis_j", "axis_k", "status"};
  EXPECT_EQ(t.header, header);
  ASSERT_EQ(t.rows.size(), 3u);
  const double s40 = std::sin(40 * kRadPerDeg), c40 = std::cos(40 * kRadPerDeg);
  const std::vector<std::vector<double>> tips = {
      {0.0, -20.0 + 20 * c40 + 600 * s40, -100.0 - 20 * s40 + 600 * c40}, {20.0, -10.0, 400.0}, {0.0, -120.0, -80.0}};
  const std::vector<std::vector<double>> axes = {{0.0, s40, c40}, {0.0, 0.0, 1.0}, {0.0, -1.0, 0.0}};
  const std::vector<std::vector<std::string>> inputs = {
      {"40", "0", "0", "0", "0"}, {"0", "90", "10", "20", "-100"}, {"-90", "0", "0", "0", "-500"}};
  for (size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE("row " + std::to_string(i + 1));
    ASSERT_EQ(t.rows[i].size(), header.size());
    for (size_t k = 0; k < 5; ++k) EXPECT_EQ(t.rows[i][k], inputs[i][k]);  // input columns kept, in order
    const char* tip_cols[] = {"tip_x", "tip_y", "tip_z"};
    const char* axis_cols[] = {"axis_i", "axis_j", "axis_k"};
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_NEAR(t.number(i, tip_cols[k]), tips[i][k], kCsvPrecisionMm) << tip_cols[k];
      EXPECT_NEAR(t.number(i, axis_cols[k]), axes[i][k], kCsvPrecisionUnit) << axis_cols[k];
    }
  }
  EXPECT_NE(t.cell(0, "status").find("beyond limits"), std::string::npos) << t.cell(0, "status");
  EXPECT_NE(t.cell(0, "status").find("axis A"), std::string::npos) << t.cell(0, "status");
  EXPECT_EQ(t.cell(1, "status"), "ok");
  EXPECT_EQ(t.cell(2, "status"), "ok");
  expect_folder({"in.csv", "out.csv"});
}

// ----------------------------------------------------------------------------------------- ik

// The pose used below on table-table-ac: tip p = (10, 0, 0), axis (1/2, 1/2, 1/sqrt2), L = 50.
// From u_w = (sin a sin c, sin a cos c, cos a): cos a = 1/sqrt2, a = +-45. a = +45 gives
// sin c = cos c = 1/sqrt2, c = 45, but A's limits are [-120, 30]; a = -45 gives
// sin c = cos c = -1/sqrt2, c = -135 (mod 360): the chosen branch.
// Linear axes (ac_linear): Rz(-135) p = (-5 sqrt2, -5 sqrt2, 0); minus c0: (-5 sqrt2, 20 - 5 sqrt2,
// 100); Rx(-45) (0, y, z) = (0, (y + z)/sqrt2, (z - y)/sqrt2) = (.., 60 sqrt2 - 5, 40 sqrt2 + 5);
// plus c0: q = (-5 sqrt2, 60 sqrt2 - 25, 40 sqrt2 - 95); X = -5 sqrt2, Y = 60 sqrt2 - 25, Z = q.z -
// 500 + 50 = 40 sqrt2 - 545.
const std::string kPoseArgs = "--tip 10,0,0 --axis 0.5,0.5,0.70710678118654752 --tool-length 50";

TEST_F(IkCli, TableTableAcPoseByHandAndEverySolutionThroughFk) {
  const json j = run_json("ik table-table-ac " + kPoseArgs);
  EXPECT_EQ(j["status"], "ok");
  const json& q = j["chosen"];
  ASSERT_TRUE(q.is_object()) << j;
  EXPECT_NEAR(q["A"].get<double>(), -45.0, kRoundOffDeg);
  EXPECT_NEAR(angle_diff_deg(q["C"].get<double>(), -135.0), 0.0, kRoundOffDeg);
  EXPECT_NEAR(q["X"].get<double>(), -5 * kSqrt2, kRoundOffMm);
  EXPECT_NEAR(q["Y"].get<double>(), 60 * kSqrt2 - 25, kRoundOffMm);
  EXPECT_NEAR(q["Z"].get<double>(), 40 * kSqrt2 - 545, kRoundOffMm);
  // The same from the closed-form helper (checks the helper against the numbers above).
  const std::vector<double> lin = ac_linear({10, 0, 0}, -45, -135, 50);
  EXPECT_NEAR(lin[0], -5 * kSqrt2, 1e-12);
  EXPECT_NEAR(lin[1], 60 * kSqrt2 - 25, 1e-12);
  EXPECT_NEAR(lin[2], 40 * kSqrt2 - 545, 1e-12);

  // Both branches listed; the a = +45 one flagged beyond A's limits.
  ASSERT_GE(j["solutions"].size(), 2u);
  bool saw_plus_branch = false;
  for (const json& s : j["solutions"]) {
    if (std::abs(s["A"].get<double>() - 45.0) < 1e-6) {
      saw_plus_branch = true;
      EXPECT_FALSE(s["within_limits"].get<bool>());
      EXPECT_NEAR(angle_diff_deg(s["C"].get<double>(), 45.0), 0.0, kRoundOffDeg);
    }
    // Every solution, run forward, gives back the pose.
    SCOPED_TRACE(s.dump());
    const json f = run_json("fk table-table-ac --tool-length 50 --axes " + axes_arg(s));
    expect_vec(f["tip"], {10.0, 0.0, 0.0}, kRoundOffMm, "fk tip");
    expect_vec(f["axis"], {0.5, 0.5, 1.0 / kSqrt2}, kRoundOffUnit, "fk axis");
  }
  EXPECT_TRUE(saw_plus_branch) << j["solutions"];
}

TEST_F(IkCli, PreviousPicksTheNearestWindingOfC) {
  // C is continuous: -135 and 225 are the same table angle; from a previous C = 200 the
  // least motion is 225 (25 deg against 335).
  const json j = run_json("ik table-table-ac " + kPoseArgs + " --previous C=200");
  EXPECT_EQ(j["status"], "ok");
  EXPECT_NEAR(j["chosen"]["C"].get<double>(), 225.0, kRoundOffDeg);
  EXPECT_NEAR(j["chosen"]["A"].get<double>(), -45.0, kRoundOffDeg);
}

TEST_F(IkCli, AxisBeyondTheCradleIsUnreachable) {
  // An axis 130 deg from +z: cos a = cos 130, a = +-130, both outside A's [-120, 30].
  const double t = 130 * kRadPerDeg;
  const CommandResult r =
      run_vcut("ik table-table-ac --tip 0,0,0 --axis " + g17(std::sin(t)) + ",0," + g17(std::cos(t)));
  EXPECT_EQ(r.exit_code, 0) << r.output;  // a result, not an input error
  const json j = json::parse(r.output);
  EXPECT_EQ(j["status"], "unreachable");
  EXPECT_NE(j["reason"].get<std::string>().find("axis A limits"), std::string::npos) << j["reason"];
  EXPECT_TRUE(j["chosen"].is_null());
}

TEST_F(IkCli, ThreeAxisCannotTilt) {
  const CommandResult r = run_vcut("ik 3axis --tip 0,0,0 --axis 0,1,1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const json j = json::parse(r.output);
  EXPECT_EQ(j["status"], "unreachable");
  EXPECT_NE(j["reason"].get<std::string>().find("orientation out of reach"), std::string::npos) << j["reason"];
}

TEST_F(IkCli, CompensatesALocationError) {
  // E_X0C = 10 um: C's table displaced by d = (0.010, 0, 0) mm in A's frame; A turns about x,
  // which leaves d alone, so the workpiece sits d further along frame x at every A and C.
  // At the nominal solution (A = -45, C = -135) the tip therefore misses by
  // -Rz(-c) d = -Rz(135) (10, 0, 0) = (5 sqrt2, -5 sqrt2, 0) um, and the commands that put it
  // back move the tool by d too: X + 0.010, the rest unchanged.
  const std::string machine = error_machine();
  const json j = run_json("ik " + machine + " " + kPoseArgs + " --errors");
  EXPECT_EQ(j["status"], "ok");
  expect_vec(j["actual"]["error_tip_um"], {5 * kSqrt2, -5 * kSqrt2, 0.0}, kRoundOffUm, "actual.error_tip_um");
  const json& c = j["compensated"];
  EXPECT_TRUE(c["converged"].get<bool>()) << c;
  EXPECT_LE(c["residual_tip_um"].get<double>(), kCompensationResidualUm);
  const json& nominal = j["chosen"];
  EXPECT_NEAR(c["axes"]["X"].get<double>(), nominal["X"].get<double>() + 0.010, kRoundOffMm);
  for (const char* letter : {"Y", "Z", "A", "C"})
    EXPECT_NEAR(c["axes"][letter].get<double>(), nominal[letter].get<double>(), kRoundOffMm) << letter;
  // The compensated commands, run forward with the errors, give back the nominal pose.
  const json f = run_json("fk " + machine + " --errors --tool-length 50 --axes " + axes_arg(c["axes"]));
  expect_vec(f["actual"]["tip"], {10.0, 0.0, 0.0}, kCompensatedTipMm, "fk actual tip");
  expect_vec(f["actual"]["axis"], {0.5, 0.5, 1.0 / kSqrt2}, 1e-9, "fk actual axis");
}

// A path on table-table-ac with A = -45 and C stepping -135, -90, -45 at tip (10, 0, 0),
// L = 0, with an unreachable row (axis 130 deg from z) between the second and the third.
std::string path_csv() {
  std::string text = "tip_x,tip_y,tip_z,axis_i,axis_j,axis_k\n";
  auto row = [&](const std::vector<double>& u) {
    text += "10,0,0," + g17(u[0]) + "," + g17(u[1]) + "," + g17(u[2]) + "\n";
  };
  row(ac_axis(-45, -135));
  row(ac_axis(-45, -90));
  const double t = 130 * kRadPerDeg;
  row({std::sin(t), 0.0, std::cos(t)});
  row(ac_axis(-45, -45));
  return text;
}

TEST_F(IkCli, CsvPathOneRowPerPose) {
  write(dir / "path.csv", path_csv());
  const CommandResult r =
      run_vcut("ik table-table-ac --csv " + (dir / "path.csv").string() + " --out " + (dir / "axes.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Csv t = read_csv(dir / "axes.csv");
  const std::vector<std::string> header = {"tip_x", "tip_y", "tip_z", "axis_i", "axis_j", "axis_k",
                                           "X",     "Y",     "Z",     "A",      "C",      "status"};
  EXPECT_EQ(t.header, header);
  ASSERT_EQ(t.rows.size(), 4u);
  // Rows 1, 2, 4: A = -45 and C as stepped; each row starts from the previous solution, so C
  // moves by +45 and never winds (row 4 follows row 2: the unreachable row 3 changes nothing).
  const std::vector<std::pair<size_t, double>> reachable = {{0, -135.0}, {1, -90.0}, {3, -45.0}};
  for (const auto& [i, c_deg] : reachable) {
    SCOPED_TRACE("row " + std::to_string(i + 1));
    EXPECT_EQ(t.cell(i, "status"), "ok");
    EXPECT_NEAR(t.number(i, "A"), -45.0, kCsvPrecisionMm);
    EXPECT_NEAR(angle_diff_deg(t.number(i, "C"), c_deg), 0.0, kCsvPrecisionMm);
    const std::vector<double> lin = ac_linear({10, 0, 0}, -45, c_deg, 0.0);
    EXPECT_NEAR(t.number(i, "X"), lin[0], kCsvPrecisionMm);
    EXPECT_NEAR(t.number(i, "Y"), lin[1], kCsvPrecisionMm);
    EXPECT_NEAR(t.number(i, "Z"), lin[2], kCsvPrecisionMm);
  }
  EXPECT_NEAR(t.number(1, "C") - t.number(0, "C"), 45.0, kCsvPrecisionMm);
  EXPECT_NEAR(t.number(3, "C") - t.number(1, "C"), 45.0, kCsvPrecisionMm);
  EXPECT_EQ(t.cell(2, "status").rfind("unreachable", 0), 0u) << t.cell(2, "status");
  EXPECT_NE(t.cell(2, "status").find("axis A limits"), std::string::npos) << t.cell(2, "status");
  for (const char* letter : {"X", "Y", "Z", "A", "C"}) EXPECT_EQ(t.cell(2, letter), "") << letter;
  EXPECT_EQ(t.cell(2, "tip_x"), "10");  // the input kept on every row
  expect_folder({"path.csv", "axes.csv"});
}

TEST_F(IkCli, CsvWithErrorsAddsCompensatedColumns) {
  // As in CompensatesALocationError: on every reachable row comp_X = X + 0.010, the rest equal.
  const std::string machine = error_machine();
  write(dir / "path.csv", path_csv());
  const CommandResult r = run_vcut("ik " + machine + " --errors --csv " + (dir / "path.csv").string() + " --out " +
                                   (dir / "axes.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Csv t = read_csv(dir / "axes.csv");
  for (const char* c : {"X", "C", "status", "actual_x", "actual_k", "error_um", "tilt_urad", "comp_X", "comp_Y",
                        "comp_Z", "comp_A", "comp_C", "residual_um", "residual_urad"})
    EXPECT_GE(t.column(c), 0) << c;
  ASSERT_EQ(t.rows.size(), 4u);
  for (size_t i : {0u, 1u, 3u}) {
    SCOPED_TRACE("row " + std::to_string(i + 1));
    EXPECT_EQ(t.cell(i, "status"), "ok");
    EXPECT_NEAR(t.number(i, "error_um"), 10.0, 1e-6);  // |Rz(-c) d| = 10 um at every C
    EXPECT_NEAR(t.number(i, "comp_X"), t.number(i, "X") + 0.010, kCsvPrecisionMm);
    for (const char* letter : {"Y", "Z", "A", "C"})
      EXPECT_NEAR(t.number(i, std::string("comp_") + letter), t.number(i, letter), kCsvPrecisionMm) << letter;
    EXPECT_LE(t.number(i, "residual_um"), kCompensationResidualUm);
  }
  EXPECT_EQ(t.cell(2, "comp_X"), "");
  expect_folder({"ac-x0c.yaml", "path.csv", "axes.csv"});
}

// -------------------------------------------------------------------------------- bad input

TEST_F(MachineCliErrors, MissingMachineFile) {
  expect_error(run_vcut("fk " + (dir / "nope.yaml").string() + " --axes X=1"), "nope.yaml");
  expect_error(run_vcut("machine " + (dir / "nope.yaml").string()), "nope.yaml");
}

TEST_F(MachineCliErrors, YamlErrorNamesTheLine) {
  // The stray ']' is on line 4.
  write(dir / "bad.yaml", "machine: x\ntopology: WFXYZT\naxes:\n  X: {kind: linear, direction: [1, 0, 0]]}\n");
  expect_error(run_vcut("fk " + (dir / "bad.yaml").string() + " --axes X=1"), "bad.yaml:4:");
}

TEST_F(MachineCliErrors, UnknownAxisLetter) {
  const CommandResult r = run_vcut("fk table-table-ac --axes X=1,Q=1");
  expect_error(r, "--axes");
  EXPECT_NE(r.output.find("Q=1"), std::string::npos) << r.output;
}

TEST_F(MachineCliErrors, AxisValueNotANumber) {
  const CommandResult r = run_vcut("fk table-table-ac --axes A=abc");
  expect_error(r, "--axes");
  EXPECT_NE(r.output.find("abc"), std::string::npos) << r.output;
}

TEST_F(MachineCliErrors, TipWithTwoNumbers) {
  const CommandResult r = run_vcut("ik table-table-ac --tip 1,2 --axis 0,0,1");
  expect_error(r, "--tip");
  EXPECT_NE(r.output.find("three numbers"), std::string::npos) << r.output;
}

TEST_F(MachineCliErrors, CsvWithoutOut) {
  write(dir / "in.csv", "X,Y,Z,A,C\n0,0,0,0,0\n");
  expect_error(run_vcut("fk table-table-ac --csv " + (dir / "in.csv").string()), "--out");
  expect_folder({"in.csv"});
}

TEST_F(MachineCliErrors, CsvCellNotANumberNamesFileLineColumn) {
  // Line 3, "1,2,zz,4,5": the bad cell starts at column 5.
  write(dir / "in.csv", "X,Y,Z,A,C\n1,2,3,4,5\n1,2,zz,4,5\n");
  const CommandResult r =
      run_vcut("fk table-table-ac --csv " + (dir / "in.csv").string() + " --out " + (dir / "out.csv").string());
  expect_error(r, "in.csv:3:5");
  EXPECT_NE(r.output.find("zz"), std::string::npos) << r.output;
  expect_folder({"in.csv"});
}

TEST_F(MachineCliErrors, CsvMissingAColumn) {
  write(dir / "in.csv", "X,Y,Z,A\n1,2,3,4\n");
  const CommandResult r =
      run_vcut("fk table-table-ac --csv " + (dir / "in.csv").string() + " --out " + (dir / "out.csv").string());
  expect_error(r, "in.csv:1");
  EXPECT_NE(r.output.find("'C'"), std::string::npos) << r.output;
  expect_folder({"in.csv"});

  write(dir / "path.csv", "tip_x,tip_y,tip_z,axis_i,axis_j\n0,0,0,0,0\n");
  const CommandResult ik =
      run_vcut("ik table-table-ac --csv " + (dir / "path.csv").string() + " --out " + (dir / "out.csv").string());
  expect_error(ik, "path.csv:1");
  EXPECT_NE(ik.output.find("'axis_k'"), std::string::npos) << ik.output;
  expect_folder({"in.csv", "path.csv"});
}

TEST_F(MachineCliErrors, IkBatchFailingMidwayLeavesNoOutput) {
  // Row 2 (line 3) is fine as a number but a zero tool axis.
  write(dir / "path.csv", "tip_x,tip_y,tip_z,axis_i,axis_j,axis_k\n0,0,0,0,0,1\n0,0,0,0,0,0\n");
  expect_error(
      run_vcut("ik table-table-ac --csv " + (dir / "path.csv").string() + " --out " + (dir / "out.csv").string()),
      "path.csv:3");
  expect_folder({"path.csv"});
}

TEST_F(MachineCliErrors, PreferANonRotaryAxis) {
  const CommandResult r = run_vcut("ik table-table-ac --tip 0,0,0 --axis 0,0,1 --prefer X+");
  expect_error(r, "--prefer");
  EXPECT_NE(r.output.find("X+"), std::string::npos) << r.output;
}

}  // namespace
