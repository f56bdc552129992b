#include "vcut/io/study.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "vcut/io/atomic_file.h"
#include "vcut/io/csv.h"
#include "vcut/io/input_error.h"
#include "vcut/io/plot.h"
#include "vcut/io/simulate.h"

namespace vcut::io {
namespace {

using Clock = std::chrono::steady_clock;

// Vertices within 2 v of sharp edges are left out of the figures (surface_difference): an
// edge is where an incident face turns more than this from the vertex's mean normal. A
// 90 deg edge turns 45; the corners a coarse densification leaves between chords turn half
// the step.

std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(6) << x;
  return s.str();
}

void require_positive(const std::vector<double>& values, const char* option, const char* unit) {
  for (double x : values)
    if (!(x > 0.0) || !std::isfinite(x))
      throw InputError(std::string(option) + ": " + number(x) + " is not a positive number of " + unit);
}

void require_finer(const std::optional<double>& reference, const std::vector<double>& values, const char* option,
                   const char* unit) {
  if (!reference || values.empty()) return;
  const double finest = *std::min_element(values.begin(), values.end());
  if (!(*reference > 0.0) || !std::isfinite(*reference))
    throw InputError(std::string(option) + ": " + number(*reference) + " is not a positive number of " + unit);
  if (*reference >= finest)
    throw InputError(std::string(option) + ": " + number(*reference) + " " + unit + " is not finer than the finest setting (" +
                     number(finest) + " " + unit + "); the reference must be finer than every setting");
}

double finest_over_4(const std::vector<double>& values) { return *std::min_element(values.begin(), values.end()) / 4.0; }

Job with_setting(Job job, const DensifySetting& s) {
  job.densify_given = true;
  if (s.tolerance_mm > 0.0) {
    job.densify_tolerance_mm = s.tolerance_mm;
  } else {
    job.densify_tolerance_mm = 0.0;
    if (s.step_mm > 0.0) job.step_mm = s.step_mm;
    if (s.angle_deg > 0.0) job.angle_step_deg = s.angle_deg;
  }
  return job;
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
  foot << "reference: " << s.reference.label << " (" << s.reference.poses << " poses, " << std::fixed << std::setprecision(2)
       << s.reference.wall_time_s << " s); " << s.engine << " engine at " << number(s.resolution_mm) << " mm, " << s.threads
       << " threads";
  plot.footnote = foot.str();
  return plot;
}

nlohmann::ordered_json row_json(const StudyRow& r) {
  nlohmann::ordered_json j;
  j["setting"] = r.label;
  const auto set_or_null = [](double x) { return x > 0.0 ? nlohmann::ordered_json(x) : nlohmann::ordered_json(nullptr); };
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

void write_study_files(const std::string& folder, const StudyResult& s, const Job& job, std::vector<std::string>& outputs) {
  // study.csv: one row per setting, then the reference.
  std::ostringstream csv;
  csv << "setting,step_mm,angle_deg,tolerance_mm,poses,moves,max_mm,rms_mm,p99_mm,edge_max_mm,wall_time_s,meets_accuracy,reference,"
         "error\n";
  auto csv_row = [&](const StudyRow& r, bool reference) {
    auto opt = [](double x) { return x > 0.0 ? number(x) : std::string(); };
    csv << csv_field(r.label) << ',' << opt(r.setting.step_mm) << ',' << opt(r.setting.angle_deg) << ','
        << opt(r.setting.tolerance_mm) << ',';
    if (r.error.empty()) {
      csv << r.poses << ',' << r.moves << ',' << number(r.max_mm) << ',' << number(r.rms_mm) << ',' << number(r.p99_mm) << ','
          << number(r.edge_max_mm) << ',' << number(r.wall_time_s) << ',' << (reference ? "" : r.meets ? "yes" : "no");
    } else {
      csv << ",,,,,,,";
    }
    csv << ',' << (reference ? "yes" : "no") << ',' << csv_field(r.error) << '\n';
  };
  for (const StudyRow& r : s.rows) csv_row(r, false);
  csv_row(s.reference, true);

  nlohmann::ordered_json j;
  j["schema_version"] = "1.0";
  j["study"] = "densification";
  j["job"] = s.job_name;
  j["job_file"] = job.file;
  j["machine"] = job.machine;
  j["engine"] = s.engine;
  j["resolution_mm"] = s.resolution_mm;
  j["threads"] = s.threads;
  j["varied"] = s.varied;
  j["accuracy_mm"] = s.accuracy_mm;
  // What the settings leave as the job has it (0 = not set).
  j["job_densify"] = {{"step_mm", job.step_mm}, {"angle_deg", job.angle_step_deg}, {"tolerance_mm", job.densify_tolerance_mm}};
  j["metric"] =
      "distance of each setting's machined surface from the reference's: every vertex of each against the other's triangles, "
      "vertices within 2 voxels of a sharp edge (a face turned more than 20 deg from the vertex's mean normal) apart: meshing "
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
  write_text_atomically(base + ".csv", csv.str());
  write_plot(base + ".svg", base + ".png", study_plot(s));
  write_text_atomically(base + ".json", j.dump(2) + "\n");
  outputs = {base + ".csv", base + ".json", base + ".svg", base + ".png"};
}

}  // namespace

std::string describe(const DensifySetting& s) {
  if (s.tolerance_mm > 0.0) return "tolerance " + number(s.tolerance_mm) + " mm";
  std::string out;
  if (s.step_mm > 0.0) out = "step " + number(s.step_mm) + " mm";
  if (s.angle_deg > 0.0) out += (out.empty() ? "" : ", ") + std::string("angle ") + number(s.angle_deg) + " deg";
  return out.empty() ? "as in the job" : out;
}

StudyResult run_densification_study(const Job& job, const StudyOptions& options) {
  const auto t_start = Clock::now();
  StudyResult s;
  s.job_name = job.name;
  s.engine = job.engine == "both" ? "dexel" : job.engine;
  s.out_dir = options.out_dir.value_or(job.out_dir);

  // The settings and the reference.
  const auto& steps = options.steps_mm;
  const auto& angles = options.angles_deg;
  const auto& tolerances = options.tolerances_mm;
  require_positive(steps, "--steps", "mm");
  require_positive(angles, "--angles", "deg");
  require_positive(tolerances, "--tolerances", "mm");
  if (steps.empty() && angles.empty() && tolerances.empty())
    throw InputError("study densification: no settings: give --steps, --angles or --tolerances (comma-separated lists)");
  if (!tolerances.empty() && (!steps.empty() || !angles.empty()))
    throw InputError("--tolerances cannot be combined with --steps or --angles: tolerance mode replaces the step and the angle");
  if (!steps.empty() && !angles.empty() && steps.size() != angles.size())
    throw InputError("--steps and --angles: expected the same number of values (they are paired by position), got " +
                     std::to_string(steps.size()) + " and " + std::to_string(angles.size()));
  auto reference_needs = [](const std::optional<double>& reference, const std::vector<double>& values, const char* option,
                            const char* list) {
    if (reference && values.empty())
      throw InputError(std::string(option) + " without " + list + ": the reference refines the settings " + list + " lists");
  };
  reference_needs(options.reference_step_mm, steps, "--reference-step", "--steps");
  reference_needs(options.reference_angle_deg, angles, "--reference-angle", "--angles");
  reference_needs(options.reference_tolerance_mm, tolerances, "--reference-tolerance", "--tolerances");
  require_finer(options.reference_step_mm, steps, "--reference-step", "mm");
  require_finer(options.reference_angle_deg, angles, "--reference-angle", "deg");
  require_finer(options.reference_tolerance_mm, tolerances, "--reference-tolerance", "mm");
  std::vector<DensifySetting> settings;
  DensifySetting reference;
  if (!tolerances.empty()) {
    s.varied = "tolerance";
    for (double e : tolerances) settings.push_back({0.0, 0.0, e});
    reference.tolerance_mm = options.reference_tolerance_mm.value_or(finest_over_4(tolerances));
  } else {
    s.varied = steps.empty() ? "angle" : angles.empty() ? "step" : "step+angle";
    for (std::size_t i = 0; i < std::max(steps.size(), angles.size()); ++i)
      settings.push_back({steps.empty() ? 0.0 : steps[i], angles.empty() ? 0.0 : angles[i], 0.0});
    if (!steps.empty()) reference.step_mm = options.reference_step_mm.value_or(finest_over_4(steps));
    if (!angles.empty()) reference.angle_deg = options.reference_angle_deg.value_or(finest_over_4(angles));
    if (job.densify_tolerance_mm > 0.0)
      s.warnings.push_back("the job's densify.tolerance is off in this study: it varies the " + s.varied +
                           ", which tolerance mode would replace");
  }
  s.accuracy_mm = options.accuracy_mm.value_or(job.gouge_tolerance_mm);
  if (!(s.accuracy_mm > 0.0) || !std::isfinite(s.accuracy_mm))
    throw InputError("--accuracy: " + number(s.accuracy_mm) + " is not a positive number of mm");

  const double resolution_mm = options.resolution_mm.value_or(job.resolution_mm);
  if (s.accuracy_mm < resolution_mm / 100.0)
    s.warnings.push_back("accuracy " + number(s.accuracy_mm) + " mm is below what meshes at " + number(resolution_mm) +
                         " mm resolve (about 1/100 of it): figures near it are meshing noise; choose a finer --resolution");

  // Fail on an unwritable output folder before the runs, not after.
  ensure_writable_folder(s.out_dir);

  SimulateOptions run_options;
  run_options.resolution_mm = options.resolution_mm;
  run_options.threads = options.threads;
  run_options.max_memory_mb = options.max_memory_mb;
  run_options.outputs = false;
  run_options.progress = options.progress;
  Job base = job;
  if (base.engine == "both") base.engine = "dexel";  // the cross-check has nothing to add here
  const std::size_t runs = settings.size() + 1;
  auto run = [&](const DensifySetting& setting, std::size_t index, StudyRow& row) -> std::shared_ptr<const removal::SurfaceMesh> {
    row.setting = setting;
    row.label = describe(setting);
    if (options.on_run) options.on_run(index, runs, row.label);
    const SimulationResult r = simulate(with_setting(base, setting), run_options);
    row.poses = r.poses;
    row.moves = r.moves;
    row.wall_time_s = r.wall_time_s;
    s.resolution_mm = r.resolution_mm;
    s.threads = r.threads;
    for (const auto& w : r.warnings)
      if (std::find(s.warnings.begin(), s.warnings.end(), w) == s.warnings.end()) s.warnings.push_back(w);
    return r.surface;
  };

  // The settings first (the cheap runs: a job that cannot run at all fails fast), then the
  // reference; each setting's surface is kept until the reference is there to measure it.
  std::vector<std::shared_ptr<const removal::SurfaceMesh>> surfaces(settings.size());
  s.rows.resize(settings.size());
  for (std::size_t i = 0; i < settings.size(); ++i) {
    try {
      surfaces[i] = run(settings[i], i, s.rows[i]);
    } catch (const InputError& e) {
      s.rows[i].error = e.what();
    }
  }
  const auto failed = std::count_if(s.rows.begin(), s.rows.end(), [](const StudyRow& r) { return !r.error.empty(); });
  if (static_cast<std::size_t>(failed) == s.rows.size())
    throw InputError("study densification: no setting could be run; " + s.rows.front().label + ": " + s.rows.front().error);
  std::shared_ptr<const removal::SurfaceMesh> reference_surface;
  try {
    reference_surface = run(reference, settings.size(), s.reference);
  } catch (const InputError& e) {
    throw InputError("study densification: the reference (" + describe(reference) + ") could not be run: " + e.what());
  }
  for (std::size_t i = 0; i < settings.size(); ++i) {
    StudyRow& row = s.rows[i];
    if (!surfaces[i]) continue;
    const SurfaceDifference d = surface_difference(*surfaces[i], *reference_surface, s.resolution_mm, kSharpEdgeDeg);
    row.max_mm = d.max_mm;
    row.rms_mm = d.rms_mm;
    row.p99_mm = d.p99_mm;
    row.max_where_mm = d.max_where_mm;
    row.edge_max_mm = d.edge_max_mm;
    row.edge_vertices = d.edge_vertices;
    row.meets = row.max_mm <= s.accuracy_mm;
    surfaces[i].reset();
  }
  // The coarsest setting that meets the accuracy: fewest poses, then the larger setting.
  for (std::size_t i = 0; i < s.rows.size(); ++i) {
    const StudyRow& r = s.rows[i];
    if (!r.error.empty() || !r.meets) continue;
    if (s.recommended < 0) {
      s.recommended = static_cast<int>(i);
      continue;
    }
    const StudyRow& best = s.rows[static_cast<std::size_t>(s.recommended)];
    const auto size = [](const DensifySetting& d) { return d.step_mm + d.angle_deg + d.tolerance_mm; };
    if (r.poses < best.poses || (r.poses == best.poses && size(r.setting) > size(best.setting))) s.recommended = static_cast<int>(i);
  }
  s.wall_time_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  s.peak_memory_mb = peak_memory_mb();
  write_study_files(s.out_dir, s, base, s.outputs);
  return s;
}

}  // namespace vcut::io
