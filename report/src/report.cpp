#include "vcut/report/report.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "vcut/io/atomic_file.h"
#include "vcut/io/csv.h"

namespace vcut::report {

using pipeline::axis_feed_of;
using pipeline::feed_interpretation_name;
using pipeline::PoseEvent;
using pipeline::PoseRun;
using pipeline::RegionRecord;
using pipeline::SimulationResult;
namespace {

using nlohmann::ordered_json;

ordered_json vec(const Eigen::Vector3d& v) {
  // Rounded to 0.1 um: positions are no better than that and the file stays readable.
  auto r = [](double x) { return std::round(x * 1e4) / 1e4; };
  return ordered_json::array({r(v.x()), r(v.y()), r(v.z())});
}

double um(double mm) { return std::round(mm * 1e6) / 1e6; }

ordered_json axes_json(const kinematics::Machine& machine, const kinematics::AxisValues& q) {
  ordered_json axes = ordered_json::object();  // mm, deg
  for (const auto& [letter, value] : pipeline::axis_readout(machine, q)) axes[std::string(1, letter)] = um(value);
  return axes;
}

ordered_json region(const RegionRecord& r, const kinematics::Program& program) {
  ordered_json j;
  j["depth_mm"] = um(r.depth_mm);
  j["area_mm2"] = um(r.area_mm2);
  j["centroid"] = vec(r.centroid_mm);
  j["deepest"] = vec(r.deepest_mm);
  j["lines"] = program.where(r.spans);
  j["tool"] = r.tools.empty() ? ordered_json(nullptr) : ordered_json(r.tools.front());
  j["tools"] = r.tools;
  j["initial_stock"] = r.initial_stock;
  return j;
}

}  // namespace

void write_report_json(const std::string& path, const std::string& out_dir, const io::Job& job,
                       const pipeline::SimulationResult& r) {
  ordered_json j;
  j["schema_version"] = kReportSchemaVersion;
  j["job"] = r.job_name;
  ordered_json s;
  s["moves"] = r.moves;
  s["cutting_moves"] = r.cutting_moves;
  s["blocks"] = r.blocks;
  s["poses"] = r.poses;
  s["initial_volume_mm3"] = um(r.initial_volume_mm3);
  s["final_volume_mm3"] = um(r.final_volume_mm3);
  s["removed_volume_mm3"] = um(r.removed_volume_mm3);
  s["compared"] = r.compared;
  s["max_gouge_mm"] = um(r.max_gouge_mm);
  s["max_excess_mm"] = um(r.max_excess_mm);
  s["gouge_regions"] = r.gouges.size();
  s["excess_regions"] = r.excess.size();
  s["collisions"] = r.collisions.size();
  if (r.machine_checked) {
    const auto hits = std::count_if(r.machine.contacts.begin(), r.machine.contacts.end(),
                                    [](const pipeline::MachineContact& c) { return c.hit; });
    s["machine_collisions"] = hits;
    s["machine_near_misses"] = static_cast<long>(r.machine.contacts.size()) - hits;
  }
  s["machined_vertices"] = r.machined_vertices;
  s["machined_triangles"] = r.machined_triangles;
  s["wall_time_s"] = std::round(r.wall_time_s * 1e3) / 1e3;
  s["peak_memory_mb"] = std::round(r.peak_memory_mb * 10) / 10;
  s["stock_memory_mb"] = std::round(r.stock_memory_mb * 10) / 10;
  s["estimated_memory_mb"] = std::round(r.estimated_memory_mb * 10) / 10;
  ordered_json stages = ordered_json::object();
  for (const auto& [name, seconds] : r.stage_seconds) stages[name] = std::round(seconds * 1e3) / 1e3;
  s["stage_seconds"] = stages;
  j["summary"] = s;
  j["gouges"] = ordered_json::array();
  const kinematics::Program& program = r.pose_run.program;
  for (const auto& g : r.gouges) j["gouges"].push_back(region(g, program));
  j["excess"] = ordered_json::array();
  for (const auto& e : r.excess) j["excess"].push_back(region(e, program));
  j["collisions"] = ordered_json::array();
  for (const auto& c : r.collisions)
    j["collisions"].push_back({{"kind", pipeline::collision_kind(c.probe)},
                               {"part", pipeline::collision_part(c.probe)},
                               {"line", program.where(c.lines)},
                               {"deepest_line", program.where(c.deepest_line)},
                               {"tool", c.tool},
                               {"depth_mm", um(c.depth_mm)},
                               {"where", vec(c.where_mm)},
                               {"moves", c.moves}});
  if (r.machine_checked) {
    // The machine's bodies, the fixtures and the tool's parts against each other (machine_check.h).
    ordered_json m;
    m["bodies"] = r.machine.bodies;
    m["pairs"] = r.machine.pairs;
    m["queries"] = r.machine.queries;
    m["contacts"] = ordered_json::array();
    for (const pipeline::MachineContact& c : r.machine.contacts)
      m["contacts"].push_back({{"kind", c.hit ? "machine_collision" : "machine_near_miss"},
                               {"bodies", {c.a, c.b}},
                               {"line", program.where(c.lines)},
                               {"depth_mm", um(c.depth_mm)},
                               {"clearance_mm", um(c.clearance_mm)},
                               {"between_poses", c.between_poses},
                               {"axes", axes_json(*r.pose_run.machine, c.axes)},
                               {"where", vec(c.where_mm)}});
    j["machine"] = m;
  }
  ordered_json h;
  h["unit"] = "mm";
  h["edges_mm"] = ordered_json::array();
  for (double e : r.histogram_edges_mm)
    h["edges_mm"].push_back(std::isinf(e) ? ordered_json(e < 0 ? "-inf" : "inf") : ordered_json(um(e)));
  h["vertex_counts"] = r.histogram_counts;
  h["area_mm2"] = ordered_json::array();
  for (double a : r.histogram_area_mm2) h["area_mm2"].push_back(um(a));
  j["histogram"] = h;
  if (r.endpoints.done) {
    // Which points the summary's gouge and excess figures were measured at.
    ordered_json e;
    e["measured_at"] =
        "dexel endpoints: every point where a ray of the tri-dexel stock enters or leaves material, exact distance to "
        "the design's triangles";
    e["points"] = r.endpoints.points;
    e["max_gouge_mm"] = um(r.endpoints.max_gouge_mm);
    e["deepest"] = vec(r.endpoints.deepest_mm);
    e["deepest_line"] = program.where(r.endpoints.deepest_line);
    e["max_excess_mm"] = um(r.endpoints.max_excess_mm);
    e["gouge_points"] = r.endpoints.gouge_points;
    e["excess_points"] = r.endpoints.excess_points;
    j["endpoint_check"] = e;
  }
  if (r.engines.done) {
    ordered_json e;
    e["compared"] =
        "tri-dexel and OpenVDB machined surfaces, every vertex of each against the other's triangles; "
        "vertices within two cells of a sharp edge (a face turned more than 20 deg from the vertex's mean normal) "
        "apart, as edge_*: "
        "each mesher cuts such an edge's corner anywhere within a cell or two";
    e["max_mm"] = um(r.engines.max_mm);
    e["rms_mm"] = um(r.engines.rms_mm);
    e["p99_mm"] = um(r.engines.p99_mm);
    e["max_at"] = vec(r.engines.max_where_mm);
    e["vertices"] = r.engines.vertices;
    e["vertices_beyond_quarter_resolution"] = r.engines.beyond_quarter;
    e["edge_vertices"] = r.engines.edge_vertices;
    e["edge_max_mm"] = um(r.engines.edge_max_mm);
    e["vdb_cut_s"] = std::round(r.engines.vdb_cut_s * 1e3) / 1e3;
    e["vdb_mesh_s"] = std::round(r.engines.vdb_mesh_s * 1e3) / 1e3;
    j["engine_check"] = e;
  }
  {
    // The pose engine (issue #5): time, densification, machine reach, servo and errors.
    const PoseRun& p = r.pose_run;
    ordered_json e;
    e["cycle_time_s"] = std::round(p.feed.cycle_time_s * 1e3) / 1e3;
    e["poses"] = p.poses;
    e["q"] = {{"min", p.q_min}, {"max", p.q_max}, {"mean", std::round(p.q_mean * 1e3) / 1e3}};
    e["rotating_moves"] = r.rotating_moves;
    e["max_nonlinear_error_mm"] = um(p.max_nonlinear_error_mm);
    if (p.max_nonlinear_line) e["max_nonlinear_line"] = program.where(p.max_nonlinear_line);
    e["cut_with"] = p.actual.empty()                  ? "nominal poses"
                    : (job.servo && job.apply_errors) ? "actual poses (servo lag and machine errors)"
                    : job.servo                       ? "actual poses (servo lag)"
                                                      : "actual poses (machine errors)";
    e["feed_interpretation"] = feed_interpretation_name(axis_feed_of(job, p.reader));
    if (job.servo) {
      // The servo runs every interpolation period; the cut follows its path thinned to a bound.
      e["servo"] = {{"period_s", job.servo->period_s},
                    {"periods", p.periods},
                    {"cut_path_poses", p.actual_path.size()},
                    {"cut_path_tolerance_mm", um(p.actual_path_tolerance_mm)}};
    }
    if (!p.actual.empty()) {
      e["max_contour_error_um"] = std::round(p.max_contour_error_um * 1e3) / 1e3;
      e["max_contour_line"] = program.where(p.max_contour_line);
      e["rms_contour_error_um"] = std::round(p.rms_contour_error_um * 1e3) / 1e3;
    }
    e["events"] = ordered_json::array();
    for (const PoseEvent& ev : p.events)
      e["events"].push_back(
          {{"kind", pipeline::to_string(ev.kind)}, {"line", program.where(ev.lines)}, {"detail", ev.detail}});
    if (r.nominal.done) {
      e["nominal_vs_actual"] = {
          {"compared", "the part cut with the actual poses against the part cut with the nominal ones"},
          {"max_mm", um(r.nominal.max_mm)},
          {"rms_mm", um(r.nominal.rms_mm)},
          {"p99_mm", um(r.nominal.p99_mm)},
          {"max_at", vec(r.nominal.max_where_mm)},
          {"max_line", program.where(r.nominal.max_line)},
          {"vertices", r.nominal.vertices}};
    }
    j["pose_engine"] = e;
  }
  j["warnings"] = r.warnings;
  // A program simulated without a job file: the machine, stock, tools and resolution assumed.
  if (!job.assumptions.empty()) j["assumptions"] = job.assumptions;
  ordered_json settings;
  settings["job_file"] = job.file;
  settings["machine"] = job.machine;
  settings["engine"] = io::engine_name(job.engine);
  settings["resolution_mm"] = r.resolution_mm;
  settings["threads"] = r.threads;
  settings["gouge_tolerance_mm"] = job.gouge_tolerance_mm;
  settings["excess_tolerance_mm"] = job.excess_tolerance_mm;
  settings["collision_tolerance_mm"] = job.collision_tolerance_mm;
  settings["chord_tolerance_mm"] = pipeline::chord_tolerance_mm(job, r.resolution_mm);
  settings["turn_tolerance_mm"] = pipeline::turn_tolerance_mm(job, r.resolution_mm);
  settings["out"] = out_dir;
  j["settings"] = settings;
  ordered_json inputs = ordered_json::array();
  for (const auto& [file, hash] : r.input_hashes) inputs.push_back({{"file", file}, {"sha256", hash}});
  j["inputs"] = inputs;
  j["outputs"] = r.outputs;
  io::write_text_atomically(path, j.dump(2) + "\n");
}

// One row per collision: the tool's parts in the stock (the cut's collisions), then the
// machine's (collisions and near misses between bodies).
void write_collisions_csv(const std::string& path, const pipeline::SimulationResult& r) {
  std::ostringstream out;
  out << "kind,body,other,depth_mm,clearance_mm,where_x,where_y,where_z,between_poses,lines\n";
  const kinematics::Program& program = r.pose_run.program;
  for (const auto& c : r.collisions)
    out << pipeline::collision_kind(c.probe) << ','
        << io::csv_field(std::string("T") + std::to_string(c.tool) + " " + pipeline::collision_part(c.probe))
        << ",the stock," << um(c.depth_mm) << ",," << c.where_mm.x() << ',' << c.where_mm.y() << ',' << c.where_mm.z()
        << ",false," << io::csv_field(program.where(c.lines)) << '\n';
  for (const pipeline::MachineContact& c : r.machine.contacts)
    out << (c.hit ? "machine_collision" : "machine_near_miss") << ',' << io::csv_field(c.a) << ',' << io::csv_field(c.b)
        << ',' << um(c.depth_mm) << ',' << um(c.clearance_mm) << ',' << c.where_mm.x() << ',' << c.where_mm.y() << ','
        << c.where_mm.z() << ',' << (c.between_poses ? "true" : "false") << ',' << io::csv_field(program.where(c.lines))
        << '\n';
  io::write_text_atomically(path, out.str());
}

void write_gouges_csv(const std::string& path, const pipeline::SimulationResult& r) {
  std::ostringstream out;
  out << "kind,rank,depth_mm,area_mm2,centroid_x,centroid_y,centroid_z,deepest_x,deepest_y,deepest_z,tool,lines\n";
  auto rows = [&](const char* kind, const std::vector<RegionRecord>& regions) {
    int rank = 0;
    for (const auto& g : regions) {
      std::string lines;
      for (const std::string& l : r.pose_run.program.where(g.spans)) lines += (lines.empty() ? "" : " ") + l;
      if (g.initial_stock) lines += std::string(lines.empty() ? "" : " ") + "(initial stock)";
      out << kind << ',' << ++rank << ',' << um(g.depth_mm) << ',' << um(g.area_mm2) << ',' << g.centroid_mm.x() << ','
          << g.centroid_mm.y() << ',' << g.centroid_mm.z() << ',' << g.deepest_mm.x() << ',' << g.deepest_mm.y() << ','
          << g.deepest_mm.z() << ',' << (g.tools.empty() ? std::string() : "T" + std::to_string(g.tools.front())) << ','
          << io::csv_field(lines) << '\n';
    }
  };
  rows("gouge", r.gouges);
  rows("excess", r.excess);
  io::write_text_atomically(path, out.str());
}

}  // namespace vcut::report
