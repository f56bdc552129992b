#include "vcut/kinematics/machine.h"

#include <fmt/format.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vcut::kinematics {
namespace {

constexpr double kUnitTolerance = 1e-6;  // |v| this close to 1 is normalised with a warning
constexpr double kParallelSine = 1e-6;   // linear axes whose directions' sine is below this are parallel

std::string fixed(double v) { return fmt::format("{:.9g}", v); }

// Normalises `v` in place; returns a problem when it is zero or far from unit length.
void check_unit(Eigen::Vector3d& v, const std::string& key, std::vector<SpecProblem>& out) {
  const double n = v.norm();
  if (!std::isfinite(n) || n < 1e-12) {
    out.push_back({key, "a non-zero vector (got a zero vector)", false});
    return;
  }
  if (std::abs(n - 1.0) > kUnitTolerance) {
    out.push_back({key, "a unit vector (length " + fixed(n) + ")", false});
    return;
  }
  if (n != 1.0) {
    v /= n;
    if (std::abs(n - 1.0) > 1e-15) out.push_back({key, "normalised a vector of length " + fixed(n), true});
  }
}

bool is_axis_letter(char c) { return std::string("XYZABC").find(c) != std::string::npos; }

}  // namespace

double ErrorTable::at(double position) const {
  if (values.empty()) return 0.0;
  if (positions.empty() || values.size() == 1) return values.front();
  if (position <= positions.front()) return values.front();
  if (position >= positions.back()) return values.back();
  const auto hi =
      static_cast<size_t>(std::upper_bound(positions.begin(), positions.end(), position) - positions.begin());
  const size_t lo = hi - 1;
  const double s = (position - positions[lo]) / (positions[hi] - positions[lo]);
  return values[lo] + s * (values[hi] - values[lo]);
}

bool ComponentErrors::empty() const {
  for (int i = 0; i < 3; ++i)
    if (!translation_mm[i].empty() || !rotation_rad[i].empty()) return false;
  return true;
}

std::vector<SpecProblem> validate(MachineSpec& spec) {
  std::vector<SpecProblem> out;
  const std::string& topo = spec.topology;

  // Topology: W first, T last, each letter once, only W F T and axis letters.
  std::string seen;
  for (char c : topo) {
    if (!(c == 'W' || c == 'F' || c == 'T' || is_axis_letter(c)))
      out.push_back({"topology",
                     std::string("letters W, F, T and axis letters X Y Z A B C (unknown letter '") + c + "')", false});
    else if (seen.find(c) != std::string::npos)
      out.push_back({"topology", std::string("each letter once (duplicate letter '") + c + "')", false});
    seen += c;
  }
  if (topo.empty() || topo.front() != 'W') out.push_back({"topology", "a chain starting at the workpiece W", false});
  if (topo.empty() || topo.back() != 'T') out.push_back({"topology", "a chain ending at the tool T", false});
  if (!out.empty()) return out;

  // Axes against the topology.
  int linear = 0, rotary = 0;
  for (size_t i = 0; i < spec.axes.size(); ++i) {
    AxisSpec& a = spec.axes[i];
    const std::string key = std::string("axes.") + a.letter;
    for (size_t j = 0; j < i; ++j)
      if (spec.axes[j].letter == a.letter) out.push_back({key, "each axis once (duplicate axis)", false});
    if (topo.find(a.letter) == std::string::npos)
      out.push_back(
          {key, std::string("an axis named in the topology (") + a.letter + " is not in '" + topo + "')", false});
    check_unit(a.direction, key + (a.kind == AxisKind::Linear ? ".direction" : ".axis"), out);
    if (a.limits && !(a.limits->first < a.limits->second))
      out.push_back({key + ".limits", "limits [min, max] with min < max (inverted or empty limits)", false});
    (a.kind == AxisKind::Linear ? linear : rotary) += 1;
    if (a.kind == AxisKind::Linear && !a.location.offset_mm.isZero(0.0))
      out.push_back({key, "no offset location errors on a linear axis (only squareness tilts)", false});
  }
  for (char c : topo) {
    if (c == 'W' || c == 'F' || c == 'T') continue;
    const bool found =
        std::any_of(spec.axes.begin(), spec.axes.end(), [c](const AxisSpec& a) { return a.letter == c; });
    if (!found)
      out.push_back({"axes", std::string("an entry for every axis of the topology (missing axis ") + c + ")", false});
  }
  if (linear != 3) out.push_back({"axes", "three linear axes (got " + std::to_string(linear) + ")", false});
  if (rotary > 2)
    out.push_back(
        {"axes", "at most two rotary axes (got " + std::to_string(rotary) + "): more than two rotary axes", false});
  check_unit(spec.spindle_axis, "spindle.axis", out);
  for (const SpecProblem& p : out)
    if (!p.warning) return out;

  // Linear axes must span space: no two parallel, not all three in a plane.
  std::vector<const AxisSpec*> lin;
  for (const AxisSpec& a : spec.axes)
    if (a.kind == AxisKind::Linear) lin.push_back(&a);
  for (size_t i = 0; i < lin.size(); ++i)
    for (size_t j = i + 1; j < lin.size(); ++j)
      if (lin[i]->direction.cross(lin[j]->direction).norm() < kParallelSine)
        out.push_back({std::string("axes.") + lin[j]->letter + ".direction",
                       std::string("a direction not parallel to axis ") + lin[i]->letter + " (parallel linear axes)",
                       false});
  const bool errors_so_far = std::any_of(out.begin(), out.end(), [](const SpecProblem& p) { return !p.warning; });
  if (lin.size() == 3 && !errors_so_far &&
      std::abs(lin[0]->direction.cross(lin[1]->direction).dot(lin[2]->direction)) < kParallelSine)
    out.push_back({std::string("axes.") + lin[2]->letter + ".direction",
                   "three linear directions that span space (all three lie in one plane)", false});
  if (!(spec.singularity_angle_rad >= 0.0 && spec.singularity_angle_rad < 0.5))
    out.push_back({"singularity_deg", "an angle in [0, 28) deg", false});
  return out;
}

Machine::Machine(MachineSpec spec) : spec_(std::move(spec)) {
  for (const SpecProblem& p : validate(spec_))
    if (!p.warning) throw std::invalid_argument("machine '" + spec_.name + "': " + p.key + ": " + p.message);
  // Axis values are always in the order X Y Z A B C, whatever the file's order.
  const std::string order = "XYZABC";
  std::stable_sort(spec_.axes.begin(), spec_.axes.end(),
                   [&](const AxisSpec& a, const AxisSpec& b) { return order.find(a.letter) < order.find(b.letter); });
  const std::string& topo = spec_.topology;
  const size_t f = topo.find('F');
  const size_t frame_at = f == std::string::npos ? 1 : f;  // without F the frame sits right after W
  // Workpiece side: letters 1 .. frame_at-1 read from W inward; the chain from F outward reverses them.
  for (size_t i = frame_at; i-- > 1;) workpiece_chain_.push_back(axis_index(topo[i]));
  const size_t tool_from = f == std::string::npos ? 1 : f + 1;
  for (size_t i = tool_from; i + 1 < topo.size(); ++i) tool_chain_.push_back(axis_index(topo[i]));
  // Orientation equation u_w = R_W^T R_T u_0: workpiece rotaries from W inward (inverse, s = -1),
  // then tool rotaries from F outward (s = +1).
  for (auto it = workpiece_chain_.rbegin(); it != workpiece_chain_.rend(); ++it)
    if (axis(*it).kind == AxisKind::Rotary) rotary_.push_back({*it, -1.0});
  for (int i : tool_chain_)
    if (axis(i).kind == AxisKind::Rotary) rotary_.push_back({i, 1.0});
  for (const AxisSpec& a : spec_.axes) has_errors_ = has_errors_ || !a.errors.empty() || !a.location.empty();
}

int Machine::axis_index(char letter) const {
  for (int i = 0; i < axis_count(); ++i)
    if (axis(i).letter == letter) return i;
  return -1;
}

std::string Machine::axis_letters() const {
  std::string s;
  for (const AxisSpec& a : spec_.axes) s += a.letter;
  return s;
}

}  // namespace vcut::kinematics
