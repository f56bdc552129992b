#include "vcut/report/check_report.h"

#include <nlohmann/json.hpp>

#include <cmath>

#include "vcut/io/atomic_file.h"
#include "vcut/pipeline/machine_check.h"

namespace vcut::report {

void write_check_json(const std::string& path, const io::Job& job, const pipeline::CheckResult& r) {
  using nlohmann::ordered_json;
  auto vec = [](const Eigen::Vector3d& v) { return ordered_json::array({v.x(), v.y(), v.z()}); };
  ordered_json j;
  j["schema"] = "vcut-check/1";
  j["job"] = job.name;
  j["machine"] = job.machine;
  j["verdict"] = r.errors == 0 ? "go" : "no-go";
  j["errors"] = r.errors;
  j["warnings"] = r.warnings;
  j["blocks"] = r.run.program.blocks.size();
  j["poses"] = r.run.poses;
  j["cycle_time_s"] = r.run.feed.cycle_time_s;
  j["stock_box"] = {{"min", vec(r.stock_box.min())}, {"max", vec(r.stock_box.max())}};
  j["events"] = ordered_json::array();
  for (const pipeline::CheckEvent& e : r.events) {
    ordered_json x{{"severity", pipeline::to_string(e.severity)},
                   {"kind", pipeline::to_string(e.kind)},
                   {"line", r.run.program.where(e.lines)},
                   {"detail", e.detail}};
    x["depth_mm"] = e.has_where ? ordered_json(e.depth_mm) : ordered_json(nullptr);
    x["where"] = e.has_where ? vec(e.where_mm) : ordered_json(nullptr);
    if (!e.bodies.empty()) {
      x["bodies"] = e.bodies;
      x["clearance_mm"] = e.clearance_mm;
      x["between_poses"] = e.between_poses;
      ordered_json axes = ordered_json::object();
      for (const auto& [letter, value] : pipeline::axis_readout(*r.run.machine, e.axes))
        axes[std::string(1, letter)] = value;
      x["axes"] = axes;  // mm, deg
    }
    j["events"].push_back(x);
  }
  j["tools"] = ordered_json::array();
  for (const pipeline::ToolClearance& t : r.tools)
    j["tools"].push_back(
        {{"tool", t.tool},
         {"holder", t.has_holder},
         {"holder_clearance_mm", t.over_stock ? ordered_json(t.holder_clearance_mm) : ordered_json(nullptr)},
         {"line", r.run.program.where(t.holder_line)}});
  if (r.machine_checked)
    j["machine_check"] = {{"bodies", r.bodies},
                          {"pairs", r.body_pairs},
                          {"queries", r.body_queries},
                          {"notes", r.notes},
                          {"seconds", r.machine_seconds}};
  j["wall_time_s"] = r.wall_time_s;
  io::write_text_atomically(path, j.dump(1) + "\n");
}

}  // namespace vcut::report
