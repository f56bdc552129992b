#include "vcut/pipeline/compensate.h"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "vcut/io/input_error.h"
#include "vcut/kinematics/compensation.h"
#include "vcut/kinematics/forward_kinematics.h"

namespace vcut::pipeline {
namespace {

// A G-code number: fixed point, as rs274 reads it (no exponent: a tiny compensated angle like
// 2.7e-12 in %g form is a syntax error), 9 decimals (1e-9 mm, 1e-9 deg), trailing zeros cut.
std::string gcode_num(double v) {
  std::string s = fmt::format("{:.9f}", v);
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

}  // namespace

CompensatedProgram compensate_program(const io::Job& job, const PoseRun& run) {
  const kinematics::Machine machine(job.machine_spec);
  if (!machine.has_errors())
    throw InputError(job.machine_file, 0, 0, "geometric errors to compensate (the machine file has no 'errors')");
  CompensatedProgram out;
  CompensationReport& report = out.report;
  std::string& text = out.text;
  const auto& samples = run.densified.samples;
  const auto& program = run.program;
  const bool apt = run.reader == io::ProgramReader::Apt;
  text =
      apt ? "$$ vcut compensate: " + job.name + " on " + machine.name() +
                ", one GOTO per densified pose\nUNITS/MM\nMULTAX/ON\n"
          : "(vcut compensate: " + job.name + " on " + machine.name() + ", one line per densified pose)\nG21 G90 G94\n";
  int tool = -1;
  double feed = -1.0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const auto& s = samples[i];
    const std::optional<kinematics::Block> of_sample =
        s.block >= 0 ? std::optional<kinematics::Block>(program.blocks[static_cast<size_t>(s.block)]) : std::nullopt;
    const kinematics::Block* block = of_sample ? &*of_sample : nullptr;
    const double length = run.tool_length_mm[i];
    const kinematics::CompensationResult c = kinematics::compensate(machine, s.pose, length, s.axes);
    ++report.poses;
    const double before =
        kinematics::pose_error(s.pose, kinematics::forward(machine, s.axes, length, kinematics::Geometry::Actual))
            .tip_um.norm();
    const std::string line = block ? program.where(block->source) : "start";
    if (before > report.max_error_before_um) {
      report.max_error_before_um = before;
      report.max_error_line = block ? std::optional<kinematics::SourceRef>(block->source) : std::nullopt;
    }
    report.max_residual_tip_um = std::max(report.max_residual_tip_um, c.residual_tip_um);
    report.max_residual_axis_urad = std::max(report.max_residual_axis_urad, c.residual_axis_urad);
    if (!c.converged) {
      ++report.not_converged;
      if (report.first_failure.empty()) report.first_failure = line + ": " + c.note;
    }
    // The start pose was computed with the first block's tool (run.tool_length_mm), so its
    // tool change comes before the start line: read back, the line then has the same length.
    const std::optional<kinematics::Block> first =
        program.blocks.empty() ? std::nullopt : std::optional<kinematics::Block>(program.blocks.front());
    const kinematics::Block* holder = block ? block : first ? &*first : nullptr;
    if (holder && holder->tool != tool && holder->tool > 0 && apt) {
      tool = holder->tool;
      text += "LOADTL/" + std::to_string(tool) + "\n";
    }
    if (apt) {
      // The pose a tool-centre-point controller turns into the compensated commands.
      const kinematics::ToolPose p = kinematics::forward(machine, c.q, length);
      const bool rapid = !block || block->kind == kinematics::MotionKind::Rapid;
      if (!block) {
        text += "FROM/";
      } else {
        if (!rapid && block->feed_mm_per_min != feed) {
          feed = block->feed_mm_per_min;
          text += "FEDRAT/" + gcode_num(feed) + ",MMPM\n";
        }
        text += rapid ? "RAPID\nGOTO/" : "GOTO/";
      }
      text += gcode_num(p.tip_mm.x()) + "," + gcode_num(p.tip_mm.y()) + "," + gcode_num(p.tip_mm.z()) + "," +
              gcode_num(p.axis.x()) + "," + gcode_num(p.axis.y()) + "," + gcode_num(p.axis.z()) + " $$ " + line + "\n";
      continue;
    }
    if (holder && holder->tool != tool && holder->tool > 0) {
      tool = holder->tool;
      text += "T" + std::to_string(tool) + " M6\n";
      if (holder->spindle_rpm > 0)
        text += "S" + gcode_num(holder->spindle_rpm) +
                (holder->spindle == kinematics::SpindleState::CounterClockwise ? " M4\n" : " M3\n");
    }
    // X Y Z of an axis program: the tip at all-zero rotary axes for these linear axes.
    kinematics::AxisValues linear = c.q;
    for (int k = 0; k < machine.rotary_count(); ++k) linear[machine.rotary_axis(k)] = 0.0;
    const Eigen::Vector3d xyz = kinematics::forward(machine, linear, length).tip_mm;
    const bool rapid = !block || block->kind == kinematics::MotionKind::Rapid;
    std::string g = rapid ? "G0" : "G1";
    g += " X" + gcode_num(xyz.x()) + " Y" + gcode_num(xyz.y()) + " Z" + gcode_num(xyz.z());
    for (int k = 0; k < machine.rotary_count(); ++k) {
      const int a = machine.rotary_axis(k);
      g += std::string(" ") + machine.axis(a).letter + gcode_num(c.q[a] * 180.0 / M_PI);
    }
    if (!rapid && block->feed_mm_per_min != feed) {
      feed = block->feed_mm_per_min;
      g += " F" + gcode_num(feed);
    }
    text += g + " (" + line + ")\n";
  }
  text += apt ? "FINI\n" : "M2\n";
  return out;
}

}  // namespace vcut::pipeline
