// libFuzzer entry point for the machine-file reader: any bytes are a YAML machine file (the
// reader takes a path, so they go to a temporary file first). The only exception allowed
// out of the reader is vcut::InputError; a machine it accepts must build, and forward
// kinematics at zero axes followed by inverse kinematics of that pose must run without any
// exception and agree with each other.
#include <unistd.h>
#include <vcut/io/input_error.h>
#include <vcut/io/machine_file.h>
#include <vcut/kinematics/forward_kinematics.h>
#include <vcut/kinematics/inverse_kinematics.h>
#include <vcut/kinematics/machine.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace kin = vcut::kinematics;

// A broken invariant is a crash, so that the fuzzer keeps the input.
void require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "machine_file_fuzz: broken invariant: %s\n", what);
  std::abort();
}

// VCUT_FUZZ_VERBOSE=1 prints what each input gave (to write and check corpus seeds).
bool verbose() {
  static const bool on = std::getenv("VCUT_FUZZ_VERBOSE") != nullptr;
  return on;
}

const std::string& temp_path() {
  static const std::string path = (std::filesystem::temp_directory_path() /
                                   ("vcut_machine_fuzz_" + std::to_string(static_cast<long>(::getpid())) + ".yaml"))
                                      .string();
  return path;
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Some 2 pi winding of zero lies inside [lo + margin, hi - margin].
bool zero_winding_inside(double lo, double hi, double margin) {
  const double k = std::ceil((lo + margin) / (2.0 * M_PI));
  return k * 2.0 * M_PI <= hi - margin;
}

void check_spec(const kin::MachineSpec& spec) {
  require(spec.axes.size() >= 3 && spec.axes.size() <= 5, "three to five axes");
  for (const kin::AxisSpec& a : spec.axes) {
    require(a.direction.allFinite() && std::abs(a.direction.norm() - 1.0) <= 1e-12, "axis direction is a unit vector");
    require(a.center_mm.allFinite(), "finite axis center");
    if (a.limits) require(a.limits->first < a.limits->second, "limits min < max");
    require(std::isfinite(a.max_velocity_per_s) && a.max_velocity_per_s >= 0.0, "velocity >= 0");
    require(std::isfinite(a.max_acceleration_per_s2) && a.max_acceleration_per_s2 >= 0.0, "acceleration >= 0");
    require(std::isfinite(a.max_jerk_per_s3) && a.max_jerk_per_s3 >= 0.0, "jerk >= 0");
    for (int i = 0; i < 3; ++i)
      for (const kin::ErrorTable* t :
           {&a.errors.translation_mm[static_cast<size_t>(i)], &a.errors.rotation_rad[static_cast<size_t>(i)]}) {
        require(t->positions.empty() ? t->values.size() <= 1
                                     : t->positions.size() == t->values.size() && t->positions.size() >= 2,
                "error table shape");
        require(std::is_sorted(t->positions.begin(), t->positions.end()) &&
                    std::adjacent_find(t->positions.begin(), t->positions.end()) == t->positions.end(),
                "error table positions strictly ascending");
        for (double v : t->values) require(std::isfinite(v), "finite error value");
        for (double p : t->positions) require(std::isfinite(p), "finite error position");
      }
    require(a.location.offset_mm.allFinite() && a.location.tilt_rad.allFinite(), "finite location errors");
  }
  require(spec.gauge_point_mm.allFinite() && spec.workpiece_origin_mm.allFinite(), "finite gauge point and origin");
  require(std::abs(spec.spindle_axis.norm() - 1.0) <= 1e-12, "unit spindle axis");
  require(spec.singularity_angle_rad >= 0.0 && spec.singularity_angle_rad < 0.5, "singularity angle in range");
}

// Forward kinematics at zero, inverse kinematics of that pose, forward of every solution.
void check_kinematics(const kin::Machine& machine, double tool_length_mm) {
  const kin::MachineSpec& spec = machine.spec();
  const kin::AxisValues zero = machine.zero();
  const kin::ToolPose pose = kin::forward(machine, zero, tool_length_mm);
  require(pose.tip_mm.allFinite() && pose.axis.allFinite(), "finite pose at zero");
  require(std::abs(pose.axis.norm() - 1.0) <= 1e-9, "unit tool axis at zero");
  // The other geometry and the node poses must run too (errors are bounded by the reader).
  const kin::ToolPose actual = kin::forward(machine, zero, tool_length_mm, kin::Geometry::Actual);
  require(actual.tip_mm.allFinite() && actual.axis.allFinite(), "finite actual pose at zero");
  for (const kin::NodePose& n : kin::node_poses(machine, zero))
    require(n.pose.matrix().allFinite(), "finite node pose");

  // Rounding grows with the coordinates in the file (up to 1e9 mm) and with how close the
  // linear directions are to a plane (the reader lets det go down to 1e-6).
  double scale = 1.0 + std::abs(tool_length_mm);
  scale = std::max(scale, spec.gauge_point_mm.cwiseAbs().maxCoeff());
  scale = std::max(scale, spec.workpiece_origin_mm.cwiseAbs().maxCoeff());
  for (const kin::AxisSpec& a : spec.axes) scale = std::max(scale, a.center_mm.cwiseAbs().maxCoeff());
  const double tip_tolerance = 1e-5 * scale;

  const kin::IkResult ik = kin::inverse(machine, pose, tool_length_mm);
  // The pose came from q = 0: its orientation is reachable, so there is at least one candidate.
  require(!ik.solutions.empty(), "inverse of a reachable pose has solutions");
  require(ik.chosen >= -1 && ik.chosen < static_cast<int>(ik.solutions.size()), "chosen index");
  for (const kin::IkSolution& s : ik.solutions) {
    require(s.q.size() == machine.axis_count(), "solution size");
    if (!s.within_limits) continue;
    require(s.q.allFinite(), "finite solution");
    const kin::ToolPose back = kin::forward(machine, s.q, tool_length_mm);
    require(back.tip_mm.allFinite() && back.axis.allFinite(), "finite pose of a solution");
    require(angle_between(back.axis, pose.axis) <= 1e-6, "solution reaches the tool axis");
    require((back.tip_mm - pose.tip_mm).norm() <= tip_tolerance, "solution reaches the tip");
  }
  // q = 0 itself is a solution: when it lies well inside every limit, one is chosen.
  bool zero_inside = true;
  for (const kin::AxisSpec& a : spec.axes) {
    if (!a.limits) continue;
    const double margin = a.kind == kin::AxisKind::Linear ? 1e-3 * scale : 1e-6;
    const double lo = a.limits->first, hi = a.limits->second;
    zero_inside = zero_inside && (a.kind == kin::AxisKind::Linear ? lo + margin <= 0.0 && 0.0 <= hi - margin
                                                                  : zero_winding_inside(lo, hi, margin));
  }
  if (zero_inside) require(ik.ok(), "inverse of the zero pose within limits is found");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = temp_path();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    require(static_cast<bool>(out), "writing the temporary file");
  }
  std::vector<std::string> warnings;
  kin::MachineSpec spec;
  try {
    spec = vcut::io::read_machine_file(path, &warnings);
  } catch (const vcut::InputError& e) {
    // Expected for bad input; it names this file and a position in it.
    if (verbose()) std::fprintf(stderr, "InputError: %s\n", e.what());
    require(e.file() == path, "the error names the file");
    require(e.line() >= 1 && e.column() >= 1, "the error names a line and column");
    require(std::string(e.what()).size() > path.size() + 2, "the error says what was expected");
    std::remove(path.c_str());
    return 0;
  }
  std::remove(path.c_str());
  for (const std::string& w : warnings) require(w.rfind(path + ":", 0) == 0, "warning names the file");
  check_spec(spec);
  // A spec the reader accepted has passed validate(): Machine must not throw.
  const kin::Machine machine(spec);
  require(machine.axis_count() == static_cast<int>(spec.axes.size()), "axis count");
  check_kinematics(machine, 0.0);
  check_kinematics(machine, 75.0);
  if (verbose())
    std::fprintf(stderr, "read machine '%s' (%s, %zu warning(s)): FK/IK checked\n", spec.name.c_str(),
                 machine.axis_letters().c_str(), warnings.size());
  return 0;
}
