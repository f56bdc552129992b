// libFuzzer entry point for the G-code reader: any bytes are a program; the only exception
// allowed out of the reader is vcut::InputError, and what it did read must be well formed.
#include <vcut/io/gcode_reader.h>
#include <vcut/io/input_error.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

namespace {

// A broken invariant is a crash, so that the fuzzer keeps the input; the line says which.
void require_at(bool ok, int line) {
  if (ok) return;
  std::fprintf(stderr, "gcode_fuzz: broken invariant at gcode_fuzz.cpp:%d\n", line);
  std::abort();
}
#define require(ok) require_at((ok), __LINE__)

void check(const vcut::kinematics::Program& program, double comp_radius_mm) {
  using vcut::kinematics::MotionKind;
  // Coordinates are bounded by 1e6 mm; a pending axis may hold a value from the offsets.
  constexpr double kBound = 1e6 + 1e-6;
  for (const auto& b : program.blocks) {
    require(b.source.file >= 0 && static_cast<size_t>(b.source.file) < program.files.size() && b.source.line >= 1);
    require(b.start_mm.allFinite() && b.end_mm.allFinite() && b.center_mm.allFinite());
    require(b.start_mm.cwiseAbs().maxCoeff() <= kBound && b.end_mm.cwiseAbs().maxCoeff() <= kBound);
    for (size_t e = 0; e < 3; ++e)  // U V W
      require(std::abs(b.start_extra.value_mm[e]) <= kBound && std::abs(b.end_extra.value_mm[e]) <= kBound);
    require(b.feed_mm_per_min >= 0.0 && b.feed_mm_per_min <= 1e9);
    if (b.kind == MotionKind::Rapid) require(b.feed_mm_per_min == 0.0);
    if (b.kind != MotionKind::Rapid) require(b.feed_mm_per_min > 0.0);
    if (b.kind != MotionKind::Arc) {
      // Blocks that neither move nor turn are dropped.
      require(b.start_mm != b.end_mm || b.start_rotary.angle_rad != b.end_rotary.angle_rad ||
              b.start_axis != b.end_axis || b.start_extra.value_mm != b.end_extra.value_mm);
      require(std::abs(b.start_axis.norm() - 1.0) < 1e-12 && std::abs(b.end_axis.norm() - 1.0) < 1e-12);
      continue;
    }
    require(b.turns >= 1);
    require(std::abs(b.normal.norm() - 1.0) <= 1e-12);  // along an axis, or turned by G68.2
    const Eigen::Vector3d n = b.normal;
    // The centre lies in the start's plane; start and end are (nearly) equally far from it.
    require(std::abs(n.dot(b.center_mm - b.start_mm)) <= 1e-9);
    Eigen::Vector3d u = b.start_mm - b.center_mm, v = b.end_mm - b.center_mm;
    u -= n * n.dot(u);
    v -= n * n.dot(v);
    const double r1 = u.norm(), r2 = v.norm();
    require(r1 > 0.0 && r2 > 0.0);
    // The default tolerance: LinuxCNC 2.9's, at its widest in G20 (2 * 0.001 * sqrt(2) in,
    // or 0.1 % of the radius up to 100 times that).
    const double absolute_mm = 2.0 * 0.001 * std::sqrt(2.0) * 25.4;
    const double allowed = std::max(absolute_mm, std::min(100.0 * absolute_mm, 1e-3 * std::max(r1, r2)));
    // Cutter compensation's tangent rule (a corner under 0.05 rad) starts an arc up to 0.05
    // times the tool radius off its offset circle.
    require(std::abs(r1 - r2) <= allowed + 0.05 * comp_radius_mm + 1e-6);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  vcut::io::GcodeOptions options;
  options.max_lines = 10000;  // a loop that never ends stops here, not at the default 1e8
  options.tcp_m_codes = {{428, true}, {429, false}};
  // The first byte also picks the options, so that both the strict and the warning paths and
  // a non-zero offset are fuzzed.
  if (size > 0) {
    options.unsupported_as_warning = (data[0] & 1) != 0;
    if ((data[0] & 2) != 0) {
      options.work_offsets_mm["G54"] = Eigen::Vector3d(100.0, -250.5, 40.0);
      options.work_offsets_mm["G55"] = Eigen::Vector3d(-999999.0, 0.0, 999999.0);
    }
    // Bits 2-3: the flavour (Fanuc runs custom macro B); bit 4: a start position, G28/G30
    // references and tool lengths (as a job has them).
    const int flavor = (data[0] >> 2) & 3;
    options.flavor = flavor == 1   ? vcut::io::GcodeOptions::Flavor::LinuxCnc
                     : flavor == 2 ? vcut::io::GcodeOptions::Flavor::Fanuc
                                   : vcut::io::GcodeOptions::Flavor::Generic;
    if ((data[0] & 16) != 0) {
      options.start_mm = Eigen::Vector3d(0.0, 0.0, 400.0);
      options.reference_mm = {Eigen::Vector3d(0.0, 0.0, 400.0), Eigen::Vector3d(-100.0, 50.0, 300.0)};
      options.tool_length_mm = {{1, 90.0}, {2, 120.5}};
    }
  }
  // G53.1 / G53.6: a table-table A C machine with both axes through the origin (tool axis on
  // the part (sin A sin C, sin A cos C, cos A); the table turns the part by Rx(A) Rz(C)), A
  // within [-120, 30] deg.
  options.orient = [](int, const Eigen::Vector3d&, const Eigen::Vector3d& axis, const vcut::kinematics::RotaryWords&,
                      int tilt_sign, vcut::kinematics::RotaryWords& to) {
    const double a = (tilt_sign > 0 ? 1.0 : -1.0) * std::acos(std::clamp(axis.z(), -1.0, 1.0));
    if (a < -120.0 * M_PI / 180.0) return std::string("axis A would need more than -120 deg");
    to = {};
    to.angle_rad = {a, 0.0, std::atan2(-axis.x(), -axis.y())};
    to.given = {true, false, true};
    return std::string();
  };
  options.tip_after_turn = [](int, const Eigen::Vector3d& tip, const vcut::kinematics::RotaryWords& from,
                              const vcut::kinematics::RotaryWords& to) {
    auto table = [](const vcut::kinematics::RotaryWords& r) {
      return Eigen::Matrix3d(Eigen::AngleAxisd(r.angle_rad[0], Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(r.angle_rad[2], Eigen::Vector3d::UnitZ()));
    };
    return Eigen::Vector3d(table(to).transpose() * (table(from) * tip));
  };
  // Cutter compensation radii (G41 D1, D2, D3; D0 or none: the tool in the spindle).
  options.tool_radius_mm = {{0, 0.0}, {1, 5.0}, {2, 0.5}, {3, 12.7}};
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  vcut::kinematics::Program program;
  vcut::io::GcodeState state;
  try {
    vcut::io::read_gcode(in, "fuzz.ngc", options, program, state);
  } catch (const vcut::InputError&) {
    // Expected for bad input; the blocks read before the error must still be well formed.
  }
  check(program, state.comp.max_radius_mm);
  return 0;
}
