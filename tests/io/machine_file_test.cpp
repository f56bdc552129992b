// Tests of the machine-file reader (ARCHITECTURE §3, §6). Expected values are converted by
// hand from the file units (mm/min, deg, deg/min, deg/s^2, um, urad) and interpolated by
// hand where a table is read between its rows; each is worked out in a comment beside it.
// Error cases check the file, the line the mistake is on and a phrase that tells it.
#include <gtest/gtest.h>
#include <vcut/io/input_error.h>
#include <vcut/io/machine_file.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

namespace vcut::io {
namespace {
namespace fs = std::filesystem;

using kinematics::AxisKind;
using kinematics::AxisSpec;
using kinematics::MachineSpec;

constexpr double kPi = 3.14159265358979323846;
// Hand values are exact decimals or closed forms in pi evaluated in double: only the rounding
// of a unit conversion or two separates them from the reader's results.
constexpr double kTol = 1e-12;

// A directory of its own for each test's files.
fs::path test_dir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(::testing::TempDir()) / "vcut_machine_file" / info->name();
  fs::create_directories(dir);
  return dir;
}

std::string write(const std::string& text, const std::string& name = "machine.yaml") {
  const fs::path file = test_dir() / name;
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
  return file.string();
}

// The 1-based number of the first line of `text` that contains `marker`.
int line_of(const std::string& text, const std::string& marker) {
  const size_t at = text.find(marker);
  if (at == std::string::npos) {
    ADD_FAILURE() << "no '" << marker << "' in:\n" << text;
    return -1;
  }
  int line = 1;
  for (size_t i = 0; i < at; ++i) line += text[i] == '\n';
  return line;
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  if (at == std::string::npos) {
    ADD_FAILURE() << "no '" << from << "' in:\n" << text;
    return text;
  }
  return text.replace(at, from.size(), to);
}

const AxisSpec& axis(const MachineSpec& spec, char letter) {
  for (const AxisSpec& a : spec.axes)
    if (a.letter == letter) return a;
  ADD_FAILURE() << "no axis " << letter;
  static const AxisSpec none;
  return none;
}

// A valid table-table AC machine, the base every bad case changes in one place.
const std::string kBase = R"(machine: test-ac
topology: WCAFXYZT
axes:
  X: {kind: linear, direction: [1, 0, 0], limits: [-300, 300], max_velocity: 20000}
  Y: {kind: linear, direction: [0, 1, 0], limits: [-200, 200]}
  Z: {kind: linear, direction: [0, 0, 1], limits: [-400, 0]}
  A: {kind: rotary, axis: [1, 0, 0], center: [0, 20, 10], limits: [-120, 30], max_velocity: 5400}
  C: {kind: rotary, axis: [0, 0, 1], center: [0, 0, 0], limits: null}
)";

// Reads `text` as a machine file; fails the test unless that raises an InputError at the
// line holding `marker` whose message holds every fragment.
void expect_error(const std::string& text, const std::string& marker, std::initializer_list<const char*> fragments) {
  const std::string file = write(text);
  const int line = line_of(text, marker);
  try {
    read_machine_file(file);
    ADD_FAILURE() << "no InputError for:\n" << text;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(e.line(), line) << what;
    EXPECT_GT(e.column(), 0) << what;
    EXPECT_EQ(what.rfind(file + ":" + std::to_string(line) + ":", 0), 0u) << what;
    for (const char* f : fragments) EXPECT_NE(what.find(f), std::string::npos) << "'" << f << "' not in: " << what;
  }
}

#define EXPECT_MACHINE_ERROR(text, marker, ...) \
  do {                                          \
    SCOPED_TRACE(marker);                       \
    expect_error(text, marker, {__VA_ARGS__});  \
  } while (0)

TEST(MachineFile, ReadsEveryFieldInInternalUnits) {
  // Axes listed in chain order (C A X Y Z); the spec keeps them as X Y Z A B C.
  const std::string text = R"(machine: table-table-ac
topology: WCAFXYZT
axes:
  C: {kind: rotary, axis: [0, 0, 1], center: [0, 0, 0], limits: null, max_velocity: 7200}
  A: {kind: rotary, axis: [1, 0, 0], center: [0, 20, 10], limits: [-120, 30], max_velocity: 5400, max_acceleration: 360, max_jerk: 3600}
  X: {kind: linear, direction: [1, 0, 0], limits: [-300, 300], max_velocity: 20000, max_acceleration: 2000, max_jerk: 50000}
  Y:
    kind: linear
    direction: [0, 1, 0]
    limits: [-200, 200]
  Z: {kind: linear, direction: [0, 0, 1], limits: [-400, 0]}
spindle: {gauge_point: [0, 0, 150], axis: [0, 0, 1]}
workpiece: {origin: [5, -10, 20]}
singularity_deg: 0.5
models:
  A: [{file: models/a.stl, origin: [1, 2, 3]}]
  T: [{file: tool.stl}]
errors:
  E_XX: 5
  E_YX: {table: [[-300, 0], [0, 2.5], [300, 4]]}
  E_BX: 20
  E_C0Y: 30
  E_X0C: 10
  E_A0C: 100
  E_Y0A: -7
  E_CC: {table: [[0, 0], [360, 12]]}
)";
  const std::string file = write(text);
  write("solid a\nendsolid a\n", "models/a.stl");
  write("solid t\nendsolid t\n", "tool.stl");
  std::vector<std::string> warnings;
  const MachineSpec spec = read_machine_file(file, &warnings);
  EXPECT_TRUE(warnings.empty()) << warnings.front();

  EXPECT_EQ(spec.name, "table-table-ac");
  EXPECT_EQ(spec.topology, "WCAFXYZT");
  ASSERT_EQ(spec.axes.size(), 5u);
  std::string letters;
  for (const AxisSpec& a : spec.axes) letters += a.letter;
  EXPECT_EQ(letters, "XYZAC");

  const AxisSpec& x = axis(spec, 'X');
  EXPECT_EQ(x.kind, AxisKind::Linear);
  EXPECT_TRUE(x.direction.isApprox(Eigen::Vector3d::UnitX()));
  ASSERT_TRUE(x.limits.has_value());
  EXPECT_DOUBLE_EQ(x.limits->first, -300.0);
  EXPECT_DOUBLE_EQ(x.limits->second, 300.0);
  EXPECT_NEAR(x.max_velocity_per_s, 1000.0 / 3.0, kTol);  // 20000 mm/min / 60 = 333.33 mm/s
  EXPECT_DOUBLE_EQ(x.max_acceleration_per_s2, 2000.0);    // already per second
  EXPECT_DOUBLE_EQ(x.max_jerk_per_s3, 50000.0);

  const AxisSpec& y = axis(spec, 'Y');  // written as a block map
  EXPECT_TRUE(y.direction.isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_DOUBLE_EQ(y.limits->first, -200.0);
  EXPECT_EQ(y.max_velocity_per_s, 0.0);  // not given
  EXPECT_EQ(y.max_acceleration_per_s2, 0.0);

  const AxisSpec& a = axis(spec, 'A');
  EXPECT_EQ(a.kind, AxisKind::Rotary);
  EXPECT_TRUE(a.direction.isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(a.center_mm.isApprox(Eigen::Vector3d(0, 20, 10)));
  ASSERT_TRUE(a.limits.has_value());
  EXPECT_NEAR(a.limits->first, -2.0 * kPi / 3.0, kTol);     // -120 deg
  EXPECT_NEAR(a.limits->second, kPi / 6.0, kTol);           // 30 deg
  EXPECT_NEAR(a.max_velocity_per_s, kPi / 2.0, kTol);       // 5400 deg/min = 90 deg/s = 1.5708 rad/s
  EXPECT_NEAR(a.max_acceleration_per_s2, 2.0 * kPi, kTol);  // 360 deg/s^2
  EXPECT_NEAR(a.max_jerk_per_s3, 20.0 * kPi, 1e-11);        // 3600 deg/s^3

  const AxisSpec& c = axis(spec, 'C');
  EXPECT_EQ(c.kind, AxisKind::Rotary);
  EXPECT_FALSE(c.limits.has_value());                        // null: continuous
  EXPECT_NEAR(c.max_velocity_per_s, 2.0 * kPi / 3.0, kTol);  // 7200 deg/min = 120 deg/s

  EXPECT_TRUE(spec.gauge_point_mm.isApprox(Eigen::Vector3d(0, 0, 150)));
  EXPECT_TRUE(spec.spindle_axis.isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(spec.workpiece_origin_mm.isApprox(Eigen::Vector3d(5, -10, 20)));
  EXPECT_NEAR(spec.singularity_angle_rad, kPi / 360.0, kTol);  // 0.5 deg

  // Model files relative to the machine file, made absolute.
  ASSERT_EQ(spec.models.size(), 2u);
  ASSERT_EQ(spec.models.at('A').size(), 1u);
  const fs::path dir = test_dir();
  EXPECT_EQ(spec.models.at('A')[0].file, (dir / "models" / "a.stl").string());
  EXPECT_TRUE(fs::path(spec.models.at('A')[0].file).is_absolute());
  EXPECT_TRUE(spec.models.at('A')[0].origin_mm.isApprox(Eigen::Vector3d(1, 2, 3)));
  ASSERT_EQ(spec.models.at('T').size(), 1u);
  EXPECT_EQ(spec.models.at('T')[0].file, (dir / "tool.stl").string());
  EXPECT_TRUE(spec.models.at('T')[0].origin_mm.isZero(0.0));

  // E_XX: 5 um constant = 0.005 mm along x.
  const auto& exx = x.errors.translation_mm[0];
  EXPECT_TRUE(exx.positions.empty());
  ASSERT_EQ(exx.values.size(), 1u);
  EXPECT_NEAR(exx.values[0], 0.005, kTol);
  EXPECT_NEAR(exx.at(123.0), 0.005, kTol);
  // E_YX: table in mm and um; between rows by hand: at 150 mm halfway from 2.5 to 4 um =
  // 3.25 um; at -150 mm halfway from 0 to 2.5 um = 1.25 um; beyond the end held at 4 um.
  const auto& eyx = x.errors.translation_mm[1];
  ASSERT_EQ(eyx.positions.size(), 3u);
  EXPECT_DOUBLE_EQ(eyx.positions[0], -300.0);
  EXPECT_DOUBLE_EQ(eyx.positions[2], 300.0);
  EXPECT_NEAR(eyx.values[1], 0.0025, kTol);
  EXPECT_NEAR(eyx.at(150.0), 0.00325, kTol);
  EXPECT_NEAR(eyx.at(-150.0), 0.00125, kTol);
  EXPECT_NEAR(eyx.at(1000.0), 0.004, kTol);
  EXPECT_TRUE(x.errors.translation_mm[2].empty());
  // E_BX: 20 urad about y.
  EXPECT_NEAR(x.errors.rotation_rad[1].at(0.0), 2e-5, kTol);
  EXPECT_TRUE(x.errors.rotation_rad[0].empty());
  EXPECT_TRUE(x.location.empty());
  // E_C0Y: squareness of Y, 30 urad about z.
  EXPECT_TRUE(y.location.tilt_rad.isApprox(Eigen::Vector3d(0, 0, 3e-5)));
  EXPECT_TRUE(y.location.offset_mm.isZero(0.0));
  EXPECT_TRUE(y.errors.empty());
  // E_X0C: 10 um = 0.01 mm along x; E_A0C: 100 urad = 1e-4 rad about x.
  EXPECT_TRUE(c.location.offset_mm.isApprox(Eigen::Vector3d(0.01, 0, 0)));
  EXPECT_TRUE(c.location.tilt_rad.isApprox(Eigen::Vector3d(1e-4, 0, 0)));
  // E_Y0A: -7 um = -0.007 mm along y.
  EXPECT_TRUE(a.location.offset_mm.isApprox(Eigen::Vector3d(0, -0.007, 0)));
  EXPECT_TRUE(a.location.tilt_rad.isZero(0.0));
  EXPECT_TRUE(a.errors.empty());
  // E_CC: positions in deg -> rad (360 deg = 2 pi); at 90 deg a quarter of 12 urad = 3 urad.
  const auto& ecc = c.errors.rotation_rad[2];
  ASSERT_EQ(ecc.positions.size(), 2u);
  EXPECT_NEAR(ecc.positions[1], 2.0 * kPi, kTol);
  EXPECT_NEAR(ecc.values[1], 1.2e-5, kTol);
  EXPECT_NEAR(ecc.at(kPi / 2.0), 3e-6, kTol);
  EXPECT_TRUE(axis(spec, 'Z').errors.empty());
  EXPECT_TRUE(axis(spec, 'Z').location.empty());

  // The spec is a usable machine, its axes in X Y Z A B C order.
  const kinematics::Machine machine(spec);
  EXPECT_EQ(machine.axis_letters(), "XYZAC");
  EXPECT_TRUE(machine.has_errors());
}

TEST(MachineFile, OptionalSectionsTakeTheirDefaults) {
  const std::string text = replace(kBase, "limits: [-120, 30], ", "");
  const MachineSpec spec = read_machine_file(write(text));
  EXPECT_TRUE(spec.gauge_point_mm.isZero(0.0));
  EXPECT_TRUE(spec.spindle_axis.isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(spec.workpiece_origin_mm.isZero(0.0));
  EXPECT_NEAR(spec.singularity_angle_rad, 0.1 * kPi / 180.0, kTol);
  EXPECT_TRUE(spec.models.empty());
  for (const AxisSpec& a : spec.axes) {
    EXPECT_TRUE(a.errors.empty()) << a.letter;
    EXPECT_TRUE(a.location.empty()) << a.letter;
  }
  EXPECT_FALSE(axis(spec, 'A').limits.has_value());  // absent: continuous
  EXPECT_TRUE(axis(spec, 'Z').limits.has_value());
}

// --- mistakes found by kinematics::validate, placed at the key it names ---

TEST(MachineFileError, SecondYamlDocument) {
  // YAML::Load would read the first document and drop the rest without a word.
  EXPECT_MACHINE_ERROR(kBase + std::string("---\nmachine: other\n"), "machine: other", "one YAML document");
}

TEST(MachineFileError, UnknownLetterInTopology) {
  EXPECT_MACHINE_ERROR(replace(kBase, "WCAFXYZT", "WCAFXYZQT"), "topology:", "'topology'", "unknown", "Q");
}

TEST(MachineFileError, DuplicateLetterInTopology) {
  EXPECT_MACHINE_ERROR(replace(kBase, "WCAFXYZT", "WCAFXYZXT"), "topology:", "'topology'", "duplicate");
}

TEST(MachineFileError, TopologyAxisMissingFromAxes) {
  const std::string text =
      replace(kBase, "  C: {kind: rotary, axis: [0, 0, 1], center: [0, 0, 0], limits: null}\n", "");
  EXPECT_MACHINE_ERROR(text, "axes:", "'axes'", "missing axis C");
}

TEST(MachineFileError, AxisMissingFromTopology) {
  EXPECT_MACHINE_ERROR(replace(kBase, "WCAFXYZT", "WAFXYZT"), "  C:", "'axes.C'", "topology");
}

TEST(MachineFileError, ZeroVector) {
  EXPECT_MACHINE_ERROR(replace(kBase, "direction: [1, 0, 0]", "direction: [0, 0, 0]"), "  X:", "'axes.X.direction'",
                       "zero");
}

TEST(MachineFileError, VectorFarFromUnitLength) {
  EXPECT_MACHINE_ERROR(replace(kBase, "axis: [1, 0, 0]", "axis: [1, 1, 0]"), "  A:", "'axes.A.axis'", "unit");
}

TEST(MachineFileError, VectorNearUnitLengthIsNormalisedWithAWarning) {
  const std::string text = replace(kBase, "direction: [0, 1, 0]", "direction: [0, 1.0000005, 0]");
  const std::string file = write(text);
  std::vector<std::string> warnings;
  const MachineSpec spec = read_machine_file(file, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind(file + ":" + std::to_string(line_of(text, "  Y:")) + ":", 0), 0u) << warnings[0];
  EXPECT_NE(warnings[0].find("axes.Y.direction"), std::string::npos) << warnings[0];
  EXPECT_NEAR(axis(spec, 'Y').direction.norm(), 1.0, 1e-15);
  EXPECT_NEAR(axis(spec, 'Y').direction.y(), 1.0, 1e-15);
  EXPECT_NO_THROW(read_machine_file(file));  // warnings are optional to collect
}

TEST(MachineFileError, ParallelLinearAxes) {
  EXPECT_MACHINE_ERROR(replace(kBase, "direction: [0, 1, 0]", "direction: [-1, 0, 0]"), "  Y:", "'axes.Y.direction'",
                       "parallel");
}

TEST(MachineFileError, ThreeRotaryAxes) {
  std::string text = replace(kBase, "WCAFXYZT", "WCBAFXYZT");
  text += "  B: {kind: rotary, axis: [0, 1, 0], center: [0, 0, 0]}\n";
  EXPECT_MACHINE_ERROR(text, "axes:", "'axes'", "more than two rotary");
}

TEST(MachineFileError, InvertedLimits) {
  EXPECT_MACHINE_ERROR(replace(kBase, "[-300, 300]", "[300, -300]"), "  X:", "'axes.X.limits'", "min < max");
}

// --- mistakes the reader finds itself ---

TEST(MachineFileError, UnknownErrorName) {
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_XX: 5\n  E_QX: 5\n", "E_QX", "'errors.E_QX'", "unknown error name");
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_XX: 5\n  EXX2: 5\n", "EXX2", "'errors.EXX2'", "unknown error name");
}

TEST(MachineFileError, SquarenessOffsetOnLinearAxis) {
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_C0Y: 5\n  E_X0Y: 5\n", "E_X0Y", "'errors.E_X0Y'", "squareness",
                       "offsets have no meaning for a linear axis");
}

TEST(MachineFileError, ErrorOfAnAxisTheMachineLacks) {
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_XB: 5\n", "E_XB", "'errors.E_XB'", "no axis B");
}

TEST(MachineFileError, TableNotAscending) {
  const std::string text = kBase + R"(errors:
  E_YX:
    table:
      - [0, 0]
      - [100, 1]
      - [50, 2]
)";
  EXPECT_MACHINE_ERROR(text, "- [50, 2]", "'errors.E_YX.table'", "ascending");
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_YX: {table: [[0, 0]]}\n", "E_YX", "at least two rows");
}

TEST(MachineFileError, LocationErrorIsAConstant) {
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_X0C: {table: [[0, 0], [360, 1]]}\n", "E_X0C", "'errors.E_X0C'",
                       "constant");
}

TEST(MachineFileError, DuplicateErrorName) {
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_XX: 5\n  E_XX: 6\n", "E_XX: 6", "'errors.E_XX'", "duplicate");
}

TEST(MachineFileError, ErrorValueNotANumber) {
  EXPECT_MACHINE_ERROR(kBase + "errors:\n  E_XX: five\n", "E_XX", "'errors.E_XX'", "a number");
}

TEST(MachineFileError, MissingModelFile) {
  EXPECT_MACHINE_ERROR(kBase + "models:\n  A: [{file: models/missing.stl}]\n", "missing.stl", "'models.A.file'",
                       "missing.stl");
}

TEST(MachineFileError, ModelOnANodeTheMachineLacks) {
  write("solid b\nendsolid b\n", "b.stl");
  EXPECT_MACHINE_ERROR(kBase + "models:\n  B: [{file: b.stl}]\n", "  B:", "'models.B'", "node of this machine");
}

TEST(MachineFileError, InvalidYaml) {
  EXPECT_MACHINE_ERROR(replace(kBase, "limits: [-200, 200]}", "limits: [-200, 200]]}"), "  Y:", "invalid YAML");
}

TEST(MachineFileError, UnknownKey) {
  EXPECT_MACHINE_ERROR(replace(kBase, "max_velocity: 20000", "max_velocty: 20000"), "  X:", "'axes.X.max_velocty'",
                       "unknown key");
  EXPECT_MACHINE_ERROR(kBase + "spindel: {axis: [0, 0, 1]}\n", "spindel", "'spindel'", "unknown key");
}

TEST(MachineFileError, MissingRequiredKey) {
  EXPECT_MACHINE_ERROR(replace(kBase, "topology: WCAFXYZT\n", ""), "machine:", "'topology'", "missing key");
  EXPECT_MACHINE_ERROR(replace(kBase, "kind: linear, direction: [1, 0, 0]", "kind: linear"),
                       "  X:", "'axes.X.direction'", "missing key");
}

TEST(MachineFileError, DuplicateAxis) {
  EXPECT_MACHINE_ERROR(kBase + "  X: {kind: linear, direction: [1, 0, 0]}\n", "direction: [1, 0, 0]}\n", "'axes.X'",
                       "duplicate");
}

TEST(MachineFileError, AxisKind) {
  EXPECT_MACHINE_ERROR(replace(kBase, "kind: linear, direction: [0, 0, 1]", "kind: prismatic, direction: [0, 0, 1]"),
                       "  Z:", "'axes.Z.kind'", "linear or rotary");
}

TEST(MachineFileError, LinearAxisWithRotaryKeys) {
  EXPECT_MACHINE_ERROR(replace(kBase, "kind: linear, direction: [1, 0, 0]", "kind: linear, axis: [1, 0, 0]"),
                       "  X:", "'axes.X.axis'", "'direction' for a linear axis");
  EXPECT_MACHINE_ERROR(replace(kBase, "kind: rotary, axis: [1, 0, 0]", "kind: rotary, direction: [1, 0, 0]"),
                       "  A:", "'axes.A.direction'", "'axis' and 'center' for a rotary axis");
}

TEST(MachineFileError, LimitsShape) {
  EXPECT_MACHINE_ERROR(replace(kBase, "[-300, 300]", "[-300, 0, 300]"), "  X:", "'axes.X.limits'", "two numbers");
  EXPECT_MACHINE_ERROR(replace(kBase, "[-300, 300]", "300"), "  X:", "'axes.X.limits'", "two numbers");
}

TEST(MachineFileError, NonPositiveDynamics) {
  EXPECT_MACHINE_ERROR(replace(kBase, "max_velocity: 5400", "max_velocity: -5400"), "  A:", "'axes.A.max_velocity'",
                       "positive");
}

TEST(MachineFileError, UnknownAxisLetter) {
  EXPECT_MACHINE_ERROR(kBase + "  U: {kind: linear, direction: [1, 0, 0]}\n", "  U:", "'axes.U'", "axis letter");
}

// --- bundled machines ---

TEST(MachineFile, ResolvesOnlyBareNamesOfBundledMachines) {
  EXPECT_EQ(resolve_machine("no-such-machine"), "no-such-machine");
  EXPECT_EQ(resolve_machine("dir/3axis"), "dir/3axis");
  EXPECT_EQ(resolve_machine("3axis.yaml"), "3axis.yaml");
  EXPECT_EQ(resolve_machine(""), "");
}

TEST(MachineFile, BundledMachinesRead) {
  int found = 0;
  for (const char* name :
       {"3axis", "table-table-ac", "table-table-bc", "head-table-bc", "head-head-ac", "gantry-wyxzcat"}) {
    const fs::path expected = fs::path(VCUT_SOURCE_DIR) / "examples" / "machines" / (std::string(name) + ".yaml");
    if (!fs::exists(expected)) continue;
    ++found;
    const std::string path = resolve_machine(name);
    ASSERT_NE(path, name);
    EXPECT_TRUE(fs::equivalent(path, expected)) << path;
    std::vector<std::string> warnings;
    try {
      const MachineSpec spec = read_machine_file(path, &warnings);
      EXPECT_EQ(spec.name, name);
      EXPECT_NO_THROW(kinematics::Machine{spec}) << name;
    } catch (const InputError& e) {
      ADD_FAILURE() << e.what();
    }
    EXPECT_TRUE(warnings.empty()) << warnings.front();
  }
  if (found == 0) GTEST_SKIP() << "no bundled machine files yet";
}

}  // namespace
}  // namespace vcut::io
