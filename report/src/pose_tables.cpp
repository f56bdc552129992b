#include "vcut/report/pose_tables.h"

#include <fmt/format.h>
#include <cmath>
#include <string>
#include <vector>

#include "vcut/io/atomic_file.h"
#include "vcut/io/input_error.h"
#include "vcut/kinematics/forward_kinematics.h"

namespace vcut::report {
namespace {

std::string num(double v, int digits = 10) { return fmt::format("{:.{}g}", v + 0.0, digits); }

}  // namespace

pipeline::PoseRun run_pose_engine_with_periods(const io::Job& job, const std::string& periods_path) {
  if (!job.servo)
    throw InputError(job.file, 0, 0,
                     "--every-period: the job has no 'servo:' (the interpolation periods are the servo's)");
  pipeline::JobProgram input = pipeline::read_job_program(job);
  const kinematics::Machine machine(job.machine_spec);
  std::vector<std::string> lines;  // the NC line of each block
  lines.reserve(input.program.blocks.size());
  for (const auto& b : input.program.blocks) lines.push_back(input.program.where(b.source));
  pipeline::PoseRun run;
  io::write_stream_atomically(periods_path, [&](std::ostream& out) {
    std::string header = "t,block,source";
    for (const char* side : {"commanded_", "actual_"})
      for (int a = 0; a < machine.axis_count(); ++a) header += std::string(",") + side + machine.axis(a).letter;
    header +=
        ",commanded_x,commanded_y,commanded_z,actual_x,actual_y,actual_z,actual_i,actual_j,actual_k,contour_error_um\n";
    out << header;
    std::string row;
    const pipeline::PeriodVisitor visit = [&](const kinematics::PeriodSample& p) {
      row = num(p.t_s) + "," + std::to_string(p.block) + "," +
            (p.block >= 0 && static_cast<size_t>(p.block) < lines.size() ? lines[static_cast<size_t>(p.block)] : "");
      for (const kinematics::AxisValues* q : {&p.commanded, &p.actual})
        for (int a = 0; a < machine.axis_count(); ++a)
          row += "," + num(machine.axis(a).kind == kinematics::AxisKind::Rotary ? (*q)[a] * 180.0 / M_PI : (*q)[a]);
      for (int k = 0; k < 3; ++k) row += "," + num(p.commanded_pose.tip_mm[k]);
      for (int k = 0; k < 3; ++k) row += "," + num(p.actual_pose.tip_mm[k]);
      for (int k = 0; k < 3; ++k) row += "," + num(p.actual_pose.axis[k]);
      row += "," + num(p.contour_error_mm * 1000.0) + "\n";
      out << row;
    };
    run = pipeline::run_pose_engine(job, std::move(input), job.resolution_mm, &visit);
  });
  return run;
}

void write_poses_csv(const std::string& path, const io::Job& job, const pipeline::PoseRun& run) {
  const kinematics::Machine machine(job.machine_spec);
  const bool actual = !run.actual.empty();
  std::string text = "block,source,t,x,y,z,i,j,k";
  for (int a = 0; a < machine.axis_count(); ++a) text += std::string(",") + machine.axis(a).letter;
  text += ",feed";
  if (actual) text += ",actual_x,actual_y,actual_z,actual_i,actual_j,actual_k,contour_error_um";
  text += "\n";
  const auto& samples = run.densified.samples;
  for (size_t i = 0; i < samples.size(); ++i) {
    const auto& s = samples[i];
    const std::string source =
        s.block >= 0 ? run.program.where(run.program.blocks[static_cast<size_t>(s.block)].source) : "";
    text += std::to_string(s.block) + "," + source + "," + num(run.feed.t_s[i]);
    for (int k = 0; k < 3; ++k) text += "," + num(s.pose.tip_mm[k]);
    for (int k = 0; k < 3; ++k) text += "," + num(s.pose.axis[k]);
    for (int a = 0; a < machine.axis_count(); ++a) {
      const double v = s.axes.size() > a ? s.axes[a] : 0.0;
      text += "," + num(machine.axis(a).kind == kinematics::AxisKind::Rotary ? v * 180.0 / M_PI : v);
    }
    text += "," + num(run.feed.speed_mm_per_s[i] * 60.0);
    if (actual) {
      for (int k = 0; k < 3; ++k) text += "," + num(run.actual[i].tip_mm[k]);
      for (int k = 0; k < 3; ++k) text += "," + num(run.actual[i].axis[k]);
      text += "," + num(run.contour_error_um[i]);
    }
    text += "\n";
  }
  io::write_text_atomically(path, text);
}

void write_blocks_csv(const std::string& path, const io::Job& job, const pipeline::PoseRun& run) {
  (void)job;
  const bool actual = !run.actual.empty();
  const auto& blocks = run.densified.blocks;
  std::string text =
      "block,source,kind,q,time_s,nonlinear_error_mm,nonlinear_x,nonlinear_y,nonlinear_z,singular,unreachable";
  if (actual) text += ",contour_max_um,contour_rms_um,contour_max_x,contour_max_y,contour_max_z";
  text += "\n";
  auto quoted = [](const std::string& t) {
    std::string q = "\"";
    for (char c : t) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  static const char* kKinds[] = {"rapid", "linear", "arc"};
  for (size_t b = 0; b < blocks.size(); ++b) {
    const auto& block = run.program.blocks[b];
    const auto& r = blocks[b];
    text += std::to_string(b) + "," + run.program.where(block.source) + "," + kKinds[static_cast<int>(block.kind)] +
            "," + std::to_string(r.q) + "," + num(b < run.feed.block_time_s.size() ? run.feed.block_time_s[b] : 0.0) +
            "," + num(r.nonlinear_error_mm);
    for (int k = 0; k < 3; ++k) text += "," + num(r.nonlinear_at_mm[k]);
    text += std::string(",") + (r.singular ? "1" : "0") + "," + quoted(r.unreachable);
    if (actual) {
      const pipeline::PoseRun::BlockContour c =
          b < run.block_contour.size() ? run.block_contour[b] : pipeline::PoseRun::BlockContour{};
      text += "," + num(c.max_um) + "," + num(c.rms_um);
      for (int k = 0; k < 3; ++k) text += "," + num(c.at_mm[k]);
    }
    text += "\n";
  }
  io::write_text_atomically(path, text);
}

}  // namespace vcut::report
