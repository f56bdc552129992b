#include "program_command.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "vcut/io/input_error.h"
#include "vcut/io/machine_file.h"
#include "vcut/io/program_reader.h"
#include "vcut/io/tool_library.h"

namespace vcut::cli {
namespace {

using json = nlohmann::ordered_json;
using namespace vcut::kinematics;

constexpr double kDegPerRad = 180.0 / M_PI;

double clean(double v) { return v + 0.0; }  // no -0 in the output
json array(const Eigen::Vector3d& v) { return json::array({clean(v.x()), clean(v.y()), clean(v.z())}); }

// The given ones of three axis values by letter, times `scale` (rotary words: deg; U V W: mm).
json given_values(const std::array<double, 3>& values, const std::array<bool, 3>& given, const char* letters,
                  double scale) {
  json j = json::object();
  for (size_t k = 0; k < 3; ++k)
    if (given[k]) j[std::string(1, letters[k])] = clean(values[k] * scale);
  return j;
}
json rotary(const RotaryWords& words) { return given_values(words.angle_rad, words.given, "ABC", kDegPerRad); }
json extra(const ExtraAxes& axes) { return given_values(axes.value_mm, axes.given, "UVW", 1.0); }

const char* kind_name(MotionKind kind) {
  switch (kind) {
    case MotionKind::Rapid:
      return "rapid";
    case MotionKind::Linear:
      return "linear";
    case MotionKind::Arc:
      return "arc";
  }
  return "?";
}

const char* orientation_name(OrientationMode mode) {
  switch (mode) {
    case OrientationMode::Axes:
      return "axes";
    case OrientationMode::Vector:
      return "vector";
    case OrientationMode::ConeClockwise:
      return "cone-cw";
    case OrientationMode::ConeCounterClockwise:
      return "cone-ccw";
  }
  return "?";
}

json record(const Program& program, const Block& b) {
  json j;
  j["kind"] = kind_name(b.kind);
  j["start"] = array(b.start_mm);
  j["end"] = array(b.end_mm);
  if (b.start_rotary.any()) j["start_rotary"] = rotary(b.start_rotary);
  if (b.end_rotary.any()) j["rotary"] = rotary(b.end_rotary);
  if (b.start_extra.any()) j["start_extra"] = extra(b.start_extra);  // U V W, mm
  if (b.end_extra.any()) j["extra"] = extra(b.end_extra);
  if (b.kind == MotionKind::Arc) {
    j["center"] = array(b.center_mm);
    j["normal"] = array(b.normal);
    j["turns"] = b.turns;
  }
  j["feed"] = clean(b.feed_mm_per_min);
  j["feed_mode"] = b.feed_mode == FeedMode::InverseTime ? "inverse-time" : "mm/min";
  j["tool"] = b.tool;
  j["tcp"] = b.tool_pose;
  if (!(b.tool_pose && b.end_rotary.any())) {
    // A TCP block with rotary words (G43.4) has its tool axis from the machine, not the program.
    j["start_axis"] = array(b.start_axis);
    j["end_axis"] = array(b.end_axis);
  }
  j["orientation_mode"] = orientation_name(b.orientation);
  if (b.orientation == OrientationMode::ConeClockwise || b.orientation == OrientationMode::ConeCounterClockwise) {
    j["cone_axis"] = array(b.cone_axis);
  }
  j["source"] = program.where(b.source);
  return j;
}

}  // namespace

void add_program_command(CLI::App& app, ProgramCommand& c) {
  c.program =
      app.add_subcommand("program", "Print a program's canonical motion list as JSON lines, one record per motion");
  c.program->add_option("file", c.file, "NC program: G-code or APT CL data")->required();
  c.program->add_option("--dialect", c.dialect,
                        "auto (default: from the extension, then the content), gcode, linuxcnc, "
                        "fanuc, apt or sinumerik");
  c.program->add_option("--machine", c.machine, "Machine file (YAML) or bundled machine name");
  c.program->add_option("--subroutine-path", c.subroutine_path,
                        "G-code: a folder searched for <name>.ngc when o<name> is called but not defined "
                        "(after the program's own folder; repeatable)");
  c.program->add_option("--max-lines", c.max_lines, "G-code: lines read before a loop is taken to be endless")
      ->check(CLI::PositiveNumber);
  c.program->add_option("--tools", c.tools,
                        "Tool library (YAML): the radii cutter compensation G41/G42 D uses and, with --machine, "
                        "the gauge lengths that put each tool's tip under the spindle");
  c.program->add_option("--tcp-on", c.tcp_on, "G-code: an M code number that switches TCP on, like G43.4 (repeatable)")
      ->check(CLI::Range(10, 999));
  c.program->add_option("--tcp-off", c.tcp_off, "G-code: an M code number that switches TCP off (repeatable)")
      ->check(CLI::Range(10, 999));
}

bool run_program_command(const ProgramCommand& c) {
  if (!c.program || !*c.program) return false;
  io::ProgramOptions options;
  const io::ToolLibrary tools = c.tools.empty() ? io::ToolLibrary{} : io::read_tool_library(c.tools);
  // Without a machine the program starts at 0 with G28/G30 references at 0, as LinuxCNC's rs274
  // runs it; with one, at the machine's home.
  options.gcode.start_mm = Eigen::Vector3d::Zero();
  for (const auto& [number, cutter] : tools) options.gcode.tool_radius_mm[number] = cutter.radius_mm();
  std::optional<kinematics::MachineSpec> spec;
  if (!c.machine.empty()) {
    std::vector<std::string> warnings;
    spec = io::read_machine_file(io::resolve_machine(c.machine), &warnings);
    for (const auto& w : warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
    io::set_machine(options.gcode, *spec, tools);
  }
  options.gcode.subroutine_path = c.subroutine_path;
  options.gcode.max_lines = c.max_lines;
  for (int m : c.tcp_on) options.gcode.tcp_m_codes[m] = true;
  for (int m : c.tcp_off) options.gcode.tcp_m_codes[m] = false;
  const io::Dialect dialect = io::parse_dialect(c.dialect);
  io::LoadedProgram loaded = io::read_program(c.file, dialect, options);
  // An axis program (rotary words without TCP) starts at the home's axis values, as a job's.
  if (spec && loaded.reader == io::ProgramReader::Gcode &&
      std::any_of(loaded.program.blocks.begin(), loaded.program.blocks.end(),
                  [](const Block& b) { return !b.tool_pose; })) {
    io::set_machine(options.gcode, *spec, tools, true);
    loaded = io::read_program(c.file, dialect, options);
  }
  for (const auto& w : loaded.program.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  std::string line;
  for (const Block& b : loaded.program.blocks) {
    line = record(loaded.program, b).dump();
    line += '\n';
    std::fwrite(line.data(), 1, line.size(), stdout);
  }
  std::fflush(stdout);
  return true;
}

}  // namespace vcut::cli
