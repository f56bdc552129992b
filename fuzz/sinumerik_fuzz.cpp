// libFuzzer entry point for the SINUMERIK 840D reader: any bytes are a part program; the only
// exception allowed out of the reader is vcut::InputError, and what it did read must be well
// formed.
#include <vcut/io/input_error.h>
#include <vcut/io/sinumerik_reader.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

namespace {

// A broken invariant is a crash, so that the fuzzer keeps the input.
void require(bool ok) {
  if (!ok) std::abort();
}

bool unit(const Eigen::Vector3d& v) { return v.allFinite() && std::abs(v.norm() - 1.0) <= 1e-12; }

void check(const vcut::kinematics::Program& program, const vcut::io::SinumerikOptions& options) {
  using vcut::kinematics::FeedMode;
  using vcut::kinematics::MotionKind;
  using vcut::kinematics::OrientationMode;
  constexpr double kBound = 1e6;  // every end point is checked against it; offsets are 0 here
  for (const auto& b : program.blocks) {
    require(b.source.file == 0 && b.source.line >= 1);
    require(b.tool >= 0 && b.tool <= 99999);
    require(b.start_mm.allFinite() && b.end_mm.allFinite() && b.center_mm.allFinite());
    require(b.start_mm.cwiseAbs().maxCoeff() <= kBound && b.end_mm.cwiseAbs().maxCoeff() <= kBound);
    require(unit(b.start_axis) && unit(b.end_axis));
    for (int k = 0; k < 3; ++k) {
      require(std::isfinite(b.start_rotary.angle_rad[k]) && std::isfinite(b.end_rotary.angle_rad[k]));
    }
    if (b.orientation == OrientationMode::Vector && b.tool_pose && !b.end_rotary.any()) {
      require(b.start_axis.dot(b.end_axis) > -1.0);  // never opposite
    }
    if (b.orientation == OrientationMode::ConeClockwise || b.orientation == OrientationMode::ConeCounterClockwise) {
      require(unit(b.cone_axis));
    }
    require(b.spindle_rpm >= 0.0 && b.spindle_rpm <= 1e6);
    if (b.kind == MotionKind::Rapid) require(b.feed_mm_per_min == 0.0);
    if (b.kind != MotionKind::Rapid) require(b.feed_mm_per_min > 0.0 && std::isfinite(b.feed_mm_per_min));
    if (b.feed_mode == FeedMode::UnitsPerMinute) require(b.feed_mm_per_min <= 1e6);
    require(b.blend_tolerance_mm < 0.0 || (b.blend_tolerance_mm <= 1e6 && !b.exact_stop) || b.exact_stop);
    if (b.kind != MotionKind::Arc) continue;
    require(b.turns == 1 && unit(b.normal));
    const Eigen::Vector3d n = b.normal;
    require(std::abs(n.dot(b.center_mm - b.start_mm)) <= 1e-6);
    Eigen::Vector3d u = b.start_mm - b.center_mm, v = b.end_mm - b.center_mm;
    u -= n * n.dot(u);
    v -= n * n.dot(v);
    const double r1 = u.norm(), r2 = v.norm();
    require(r1 > 0.0 && r2 > 0.0);
    // The reader's rule: the larger of the absolute tolerance and 0.1 % of the radius
    // ($MN_CIRCLE_ERROR_FACTOR); doubled for the rounding of the printed numbers.
    const double allowed = 2.0 * std::max(options.arc_tolerance_mm, 1e-3 * std::max(r1, r2));
    require(std::abs(r1 - r2) <= allowed + 1e-6);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  vcut::io::SinumerikOptions options;
  options.max_lines = 10000;  // a loop that never ends stops here, not at the default 1e8
  // The first byte also picks the arc tolerance and the warning mode, so that both are fuzzed.
  if (size > 0 && (data[0] & 1) != 0) options.arc_tolerance_mm = 0.5;
  if (size > 0 && (data[0] & 2) != 0) options.unsupported_as_warning = true;
  if (size > 0 && (data[0] & 4) != 0) {
    // A machine (CYCLE800, SUPA, G74/G75, D0): a table-table A C machine with both axes through
    // the origin (tool axis on the part (sin A sin C, sin A cos C, cos A); the table turns the
    // part by Rx(A) Rz(C)), A within [-120, 30] deg, homes and tool lengths as a job has them.
    auto table = [](const vcut::kinematics::RotaryWords& r) {
      return Eigen::Matrix3d(Eigen::AngleAxisd(r.angle_rad[0], Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(r.angle_rad[2], Eigen::Vector3d::UnitZ()));
    };
    options.orient = [](int, const Eigen::Vector3d&, const Eigen::Vector3d& axis, const vcut::kinematics::RotaryWords&,
                        int tilt_sign, vcut::kinematics::RotaryWords& to) {
      const double a = (tilt_sign > 0 ? 1.0 : -1.0) * std::acos(std::clamp(axis.z(), -1.0, 1.0));
      if (a < -120.0 * M_PI / 180.0 || a > 30.0 * M_PI / 180.0) return std::string("axis A out of [-120, 30] deg");
      to = {};
      to.angle_rad = {a, 0.0, std::atan2(-axis.x(), -axis.y())};
      to.given = {true, false, true};
      return std::string();
    };
    options.tip_after_turn = [table](int, const Eigen::Vector3d& tip, const vcut::kinematics::RotaryWords& from,
                                     const vcut::kinematics::RotaryWords& to) {
      return Eigen::Vector3d(table(to).transpose() * (table(from) * tip));
    };
    options.frame_rotation = [table](const vcut::kinematics::RotaryWords& r) {
      return Eigen::Matrix3d(table(r).transpose());
    };
    options.rotary_axes = "AC";
    options.reference_mm = {Eigen::Vector3d(0.0, 0.0, 400.0), Eigen::Vector3d(-100.0, 50.0, 300.0)};
    options.tool_length_mm = {{1, 90.0}, {2, 120.5}};
  }
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  vcut::kinematics::Program program;
  vcut::io::SinumerikState state;
  try {
    vcut::io::read_sinumerik(in, "fuzz.mpf", options, program, state);
  } catch (const vcut::InputError&) {
    // Expected for bad input; the blocks read before the error must still be well formed.
  }
  check(program, options);
  return 0;
}
