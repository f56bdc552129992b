#include "vcut/report/study_report.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "vcut/io/atomic_file.h"
#include "vcut/io/csv.h"
#include "vcut/report/plot.h"

namespace vcut::report {
namespace {

using pipeline::DensifySetting;
using pipeline::StudyResult;
using pipeline::StudyRow;

std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(6) << x;
  return s.str();
}

// Log scales need positive values: a surface identical to the reference is drawn at the
// axis minimum (plot.h), and labelled "= ref".
std::string point_label(const StudyRow& r, const std::string& varied) {
  if (varied == "step") return number(r.setting.step_mm) + " mm";
  if (varied == "angle") return number(r.setting.angle_deg) + " deg";
  if (varied == "tolerance") return number(r.setting.tolerance_mm) + " mm";
  return number(r.setting.step_mm) + " mm/" + number(r.setting.angle_deg) + " deg";
}

Plot study_plot(const StudyResult& s) {
  Plot plot;
  plot.title = "Densification study: " + s.job_name + " (" + s.varied + ")";
  const Rgb max_colour{214, 39, 40}, rms_colour{31, 119, 180};
  PlotPanel density, time;
  density.title = "accuracy against density";
  density.x_label = "poses";
  density.y_label = "distance from the reference cut (mm)";
  density.log_x = density.log_y = true;
  time.title = "accuracy against time";
  time.x_label = "wall time: poses, cut and mesh (s)";
  time.y_label = density.y_label;
  time.log_y = true;
  double t_min = 0.0, t_max = 0.0;
  for (PlotPanel* panel : {&density, &time}) {
    PlotSeries max_series{"max", max_colour, {}, true, true, {}}, rms_series{"RMS", rms_colour, {}, true, true, {}};
    std::vector<const StudyRow*> rows;
    for (const StudyRow& r : s.rows)
      if (r.error.empty()) rows.push_back(&r);
    // Joined in the order of density, so the lines read left to right.
    std::stable_sort(rows.begin(), rows.end(), [&](const StudyRow* a, const StudyRow* b) {
      return panel == &density ? a->poses < b->poses : a->wall_time_s < b->wall_time_s;
    });
    for (const StudyRow* r : rows) {
      const double x = panel == &density ? static_cast<double>(r->poses) : r->wall_time_s;
      max_series.points.push_back({x, r->max_mm});
      max_series.labels.push_back(point_label(*r, s.varied) + (r->max_mm == 0.0 ? " (= ref)" : ""));
      rms_series.points.push_back({x, r->rms_mm});
      if (panel == &time) {
        t_min = t_min == 0.0 ? r->wall_time_s : std::min(t_min, r->wall_time_s);
        t_max = std::max(t_max, r->wall_time_s);
      }
    }
    // Time is measured, not set: the points scatter, so they are not joined.
    max_series.line = rms_series.line = panel == &density;
    panel->series = {max_series, rms_series};
    panel->marks.push_back({true, s.accuracy_mm, "accuracy " + number(s.accuracy_mm) + " mm", {200, 40, 40}});
    if (s.recommended >= 0) {
      const StudyRow& r = s.rows[static_cast<std::size_t>(s.recommended)];
      const double x = panel == &density ? static_cast<double>(r.poses) : r.wall_time_s;
      panel->highlights.push_back({{x, r.max_mm}, "recommended", {0, 150, 60}});
    }
  }
  time.log_x = t_min > 0.0 && t_max > 10.0 * t_min;
  plot.panels = {density, time};
  std::ostringstream foot;
  foot << "reference: " << s.reference.label << " (" << s.reference.poses << " poses, " << std::fixed
       << std::setprecision(2) << s.reference.wall_time_s << " s); " << io::engine_name(s.engine) << " engine at "
       << number(s.resolution_mm) << " mm, " << s.threads << " threads";
  plot.footnote = foot.str();
  return plot;
}

nlohmann::ordered_json row_json(const StudyRow& r) {
  nlohmann::ordered_json j;
  j["setting"] = r.label;
  const auto set_or_null = [](double x) {
    return x > 0.0 ? nlohmann::ordered_json(x) : nlohmann::ordered_json(nullptr);
  };
  j["step_mm"] = set_or_null(r.setting.step_mm);
  j["angle_deg"] = set_or_null(r.setting.angle_deg);
  j["tolerance_mm"] = set_or_null(r.setting.tolerance_mm);
  if (!r.error.empty()) {
    j["error"] = r.error;
    return j;
  }
  j["poses"] = r.poses;
  j["moves"] = r.moves;
  j["max_mm"] = r.max_mm;
  j["rms_mm"] = r.rms_mm;
  j["p99_mm"] = r.p99_mm;
  j["max_at_mm"] = {r.max_where_mm.x(), r.max_where_mm.y(), r.max_where_mm.z()};
  j["edge_max_mm"] = r.edge_max_mm;
  j["edge_vertices"] = r.edge_vertices;
  j["wall_time_s"] = r.wall_time_s;
  j["meets_accuracy"] = r.meets;
  return j;
}

}  // namespace

void write_study(const std::string& folder, pipeline::StudyResult& s, const io::Job& job) {
  std::vector<std::string>& outputs = s.outputs;
  // study.csv: one row per setting, then the reference.
  std::ostringstream csv;
  csv << "setting,step_mm,angle_deg,tolerance_mm,poses,moves,max_mm,rms_mm,p99_mm,edge_max_mm,wall_time_s,meets_"
         "accuracy,reference,"
         "error\n";
  auto csv_row = [&](const StudyRow& r, bool reference) {
    auto opt = [](double x) { return x > 0.0 ? number(x) : std::string(); };
    csv << io::csv_field(r.label) << ',' << opt(r.setting.step_mm) << ',' << opt(r.setting.angle_deg) << ','
        << opt(r.setting.tolerance_mm) << ',';
    if (r.error.empty()) {
      csv << r.poses << ',' << r.moves << ',' << number(r.max_mm) << ',' << number(r.rms_mm) << ',' << number(r.p99_mm)
          << ',' << number(r.edge_max_mm) << ',' << number(r.wall_time_s) << ','
          << (reference ? ""
              : r.meets ? "yes"
                        : "no");
    } else {
      csv << ",,,,,,,";
    }
    csv << ',' << (reference ? "yes" : "no") << ',' << io::csv_field(r.error) << '\n';
  };
  for (const StudyRow& r : s.rows) csv_row(r, false);
  csv_row(s.reference, true);

  nlohmann::ordered_json j;
  j["schema_version"] = "1.0";
  j["study"] = "densification";
  j["job"] = s.job_name;
  j["job_file"] = job.file;
  j["machine"] = job.machine;
  j["engine"] = io::engine_name(s.engine);
  j["resolution_mm"] = s.resolution_mm;
  j["threads"] = s.threads;
  j["varied"] = s.varied;
  j["accuracy_mm"] = s.accuracy_mm;
  j["turn_tolerance_mm"] = s.turn_tolerance_mm;
  // What the settings leave as the job has it (0 = not set).
  j["job_densify"] = {
      {"step_mm", job.step_mm}, {"angle_deg", job.angle_step_deg}, {"tolerance_mm", job.densify_tolerance_mm}};
  j["metric"] =
      "distance of each setting's machined surface from the reference's: every vertex of each against the other's "
      "triangles, "
      "vertices within 2 voxels of a sharp edge (a face turned more than 20 deg from the vertex's mean normal) apart: "
      "meshing "
      "cuts such an edge's corner anywhere within a cell or two, so their largest distance is edge_max_mm, not max_mm; "
      "what is left resolves about resolution / 100";
  j["reference"] = row_json(s.reference);
  j["settings"] = nlohmann::ordered_json::array();
  for (const StudyRow& r : s.rows) j["settings"].push_back(row_json(r));
  j["recommended"] = s.recommended >= 0 ? nlohmann::ordered_json(s.rows[static_cast<std::size_t>(s.recommended)].label)
                                        : nlohmann::ordered_json(nullptr);
  j["warnings"] = s.warnings;
  j["wall_time_s"] = s.wall_time_s;
  j["peak_memory_mb"] = s.peak_memory_mb;
  j["outputs"] = {"study.csv", "study.json", "study.svg", "study.png"};

  const std::string base = folder + "/study";
  io::write_text_atomically(base + ".csv", csv.str());
  write_plot(base + ".svg", base + ".png", study_plot(s));
  io::write_text_atomically(base + ".json", j.dump(2) + "\n");
  outputs = {base + ".csv", base + ".json", base + ".svg", base + ".png"};
}

}  // namespace vcut::report
