// libFuzzer entry point for the APT CL-data reader: any bytes are a CL file; the only exception
// allowed out of the reader is vcut::InputError, and what it did read must be well formed.
#include <vcut/io/apt_reader.h>
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
  std::fprintf(stderr, "apt_fuzz: broken invariant at apt_fuzz.cpp:%d\n", line);
  std::abort();
}
#define require(ok) require_at((ok), __LINE__)

bool unit(const Eigen::Vector3d& v) { return v.allFinite() && std::abs(v.norm() - 1.0) <= 1e-12; }

void check(const vcut::io::AptProgram& out, const vcut::io::AptOptions& options, double comp_radius_mm) {
  using vcut::kinematics::MotionKind;
  // Coordinates are bounded by 1e6 mm (a GODLTA/ adds at most that to a bounded point, and
  // its end is checked too).
  constexpr double kBound = 1e6;
  // Cutter compensation takes a corner under 0.05 rad as tangent (rs274's rule) and starts the
  // arc where the straight's offset ends: at most the tool radius times 0.05 from the arc's
  // offset start, so its radius may differ from the end's by that much more.
  const double comp_allowed_mm = 0.05 * comp_radius_mm;
  for (const auto& b : out.program.blocks) {
    require(b.source.file == 0 && b.source.line >= 1);
    require(b.tool_pose && b.tool >= 1 && b.tool <= 99999);
    require(b.start_mm.allFinite() && b.end_mm.allFinite() && b.center_mm.allFinite());
    require(b.start_mm.cwiseAbs().maxCoeff() <= kBound && b.end_mm.cwiseAbs().maxCoeff() <= kBound);
    require(unit(b.start_axis) && unit(b.end_axis));
    require(b.start_axis.dot(b.end_axis) > -1.0);  // never opposite
    require(b.feed_mm_per_min >= 0.0 && b.feed_mm_per_min <= 1e6);
    require(b.spindle_rpm >= 0.0 && b.spindle_rpm <= 1e6);
    if (b.kind == MotionKind::Rapid) require(b.feed_mm_per_min == 0.0);
    if (b.kind != MotionKind::Rapid) require(b.feed_mm_per_min > 0.0);
    if (b.kind != MotionKind::Arc) {
      require(b.start_mm != b.end_mm || b.start_axis != b.end_axis);  // still moves are dropped
      continue;
    }
    require(b.turns >= 1 && b.turns <= 1000 && unit(b.normal));  // CIRCLE/ ... TIMES,n
    const Eigen::Vector3d n = b.normal;
    // The centre lies in the start's plane; start and end are (nearly) equally far from it.
    require(std::abs(n.dot(b.center_mm - b.start_mm)) <= 1e-6);
    Eigen::Vector3d u = b.start_mm - b.center_mm, v = b.end_mm - b.center_mm;
    u -= n * n.dot(u);
    v -= n * n.dot(v);
    const double r1 = u.norm(), r2 = v.norm();
    require(r1 > 0.0 && r2 > 0.0);
    const double allowed = 2.0 * std::max(options.arc_tolerance_mm, 1e-6 * std::max(r1, r2));
    require(std::abs(r1 - r2) <= allowed + comp_allowed_mm + 1e-6);
  }
  for (const auto& [number, c] : out.cutters) {
    require(number >= 1 && number <= 99999);
    require(c.diameter_mm > 0.0 && std::isfinite(c.diameter_mm));
    require(c.corner_radius_mm >= 0.0 && c.corner_radius_mm <= 0.5 * c.diameter_mm);
    require(c.flute_length_mm > 0.0 && c.flute_length_mm >= c.corner_radius_mm);
    if (c.type == vcut::removal::CutterType::VBit) {
      require(c.tip_angle_deg > 0.0 && c.tip_angle_deg < 180.0);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  vcut::io::AptOptions options;
  // The first byte also picks the arc tolerance, so that strict and loose arcs are both fuzzed.
  if (size > 0 && (data[0] & 1) != 0) options.arc_tolerance_mm = 0.5;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  vcut::io::AptProgram out;
  vcut::io::AptState state;
  try {
    vcut::io::read_apt(in, "fuzz.apt", options, out, state);
  } catch (const vcut::InputError&) {
    // Expected for bad input; the blocks read before the error must still be well formed.
  }
  check(out, options, state.comp.max_radius_mm);
  return 0;
}
