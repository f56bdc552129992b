#include "vcut/pipeline/study.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <sstream>

#include "vcut/io/input_error.h"
#include "vcut/pipeline/simulate.h"
#include "vcut/removal/stock.h"

namespace vcut::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

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
    throw InputError(std::string(option) + ": " + number(*reference) + " " + unit +
                     " is not finer than the finest setting (" + number(finest) + " " + unit +
                     "); the reference must be finer than every setting");
}

double finest_over_4(const std::vector<double>& values) {
  return *std::min_element(values.begin(), values.end()) / 4.0;
}

io::Job with_setting(io::Job job, const DensifySetting& s) {
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

}  // namespace

std::string describe(const DensifySetting& s) {
  if (s.tolerance_mm > 0.0) return "tolerance " + number(s.tolerance_mm) + " mm";
  std::string out;
  if (s.step_mm > 0.0) out = "step " + number(s.step_mm) + " mm";
  if (s.angle_deg > 0.0) out += (out.empty() ? "" : ", ") + std::string("angle ") + number(s.angle_deg) + " deg";
  return out.empty() ? "as in the job" : out;
}

StudyResult run_densification_study(const io::Job& job, const StudyOptions& options) {
  const auto t_start = Clock::now();
  StudyResult s;
  s.job_name = job.name;
  s.engine = job.engine == io::Engine::Both ? io::Engine::Dexel : job.engine;

  // The settings and the reference.
  const auto& steps = options.steps_mm;
  const auto& angles = options.angles_deg;
  const auto& tolerances = options.tolerances_mm;
  require_positive(steps, "--steps", "mm");
  require_positive(angles, "--angles", "deg");
  require_positive(tolerances, "--tolerances", "mm");
  if (steps.empty() && angles.empty() && tolerances.empty())
    throw InputError(
        "study densification: no settings: give --steps, --angles or --tolerances (comma-separated lists)");
  if (!tolerances.empty() && (!steps.empty() || !angles.empty()))
    throw InputError(
        "--tolerances cannot be combined with --steps or --angles: tolerance mode replaces the step and the angle");
  if (!steps.empty() && !angles.empty() && steps.size() != angles.size())
    throw InputError("--steps and --angles: expected the same number of values (they are paired by position), got " +
                     std::to_string(steps.size()) + " and " + std::to_string(angles.size()));
  auto reference_needs = [](const std::optional<double>& reference, const std::vector<double>& values,
                            const char* option, const char* list) {
    if (reference && values.empty())
      throw InputError(std::string(option) + " without " + list + ": the reference refines the settings " + list +
                       " lists");
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
    s.warnings.push_back(
        "accuracy " + number(s.accuracy_mm) + " mm is below what meshes at " + number(resolution_mm) +
        " mm resolve (about 1/100 of it): figures near it are meshing noise; choose a finer --resolution");

  if (!(resolution_mm > 0.0) || !std::isfinite(resolution_mm))
    throw InputError("--resolution: expected a positive number of mm");
  s.resolution_mm = resolution_mm;
  // The pieces a turning move is cut as lie within the turn tolerance of its rigid motion,
  // overcutting by up to it, and two settings split a move differently: at the job's
  // tolerance (v/10 by default) they would stand for the densification's own difference.
  // (A pure turn about the tool's tip at v = 0.2 mm: 0.0039 mm between 8 and 0.5 deg at
  // 0.02 mm, 0.00007 at 0.0005.) Not below v/1000: a tenth of what the meshes resolve.
  s.turn_tolerance_mm =
      std::min(turn_tolerance_mm(job, resolution_mm), std::max(s.accuracy_mm / 10.0, resolution_mm / 1000.0));
  const int threads = options.threads.value_or(job.threads);
  s.threads = threads > 0 ? threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(s.threads));
  io::Job base = job;
  if (base.engine == io::Engine::Both) base.engine = io::Engine::Dexel;  // the cross-check has nothing to add here
  const std::size_t runs = settings.size() + 1;
  auto progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    if (options.progress) options.progress(stage, done, total);
  };
  // One setting: poses, moves, cut and mesh (the stages of simulate that make the surface).
  auto run = [&](const DensifySetting& setting, std::size_t index, StudyRow& row) -> removal::SurfaceMesh {
    row.setting = setting;
    row.label = describe(setting);
    if (options.on_run) options.on_run(index, runs, row.label);
    const auto t0 = Clock::now();
    const io::Job j = with_setting(base, setting);
    const PoseRun poses = run_pose_engine(j, read_job_program(j), resolution_mm, nullptr, true);
    // What the machine cuts: the actual path with servo or errors.
    CutMoves cut(poses, !poses.actual_path.empty(), false, s.turn_tolerance_mm);
    const removal::StockShape shape = stock_shape(j);
    cut.set_stock_box(removal::bounds_of(shape));
    require_cuttable(j, cut, shape, resolution_mm, options.max_memory_mb);
    // Two settings' meshes are compared to resolution / 100: no flat merging (make_stock).
    const std::unique_ptr<removal::Stock> stock = make_stock(j, shape, resolution_mm, false);
    removal::CutOptions cut_options;
    cut_options.collision_tolerance_mm = j.collision_tolerance_mm;
    cut_options.progress = [&](std::size_t done, std::size_t total) { progress("cut", done, total); };
    stock->cut(cut, cut_options);
    progress("mesh", 0, 1);
    removal::SurfaceMesh surface = stock->surface();
    row.poses = poses.poses;
    row.moves = cut.count();
    row.wall_time_s = std::chrono::duration<double>(Clock::now() - t0).count();
    for (const auto& w : warnings_of(j, poses))
      if (std::find(s.warnings.begin(), s.warnings.end(), w) == s.warnings.end()) s.warnings.push_back(w);
    return surface;
  };

  // The settings first (the cheap runs: a job that cannot run at all fails fast), then the
  // reference; each setting's surface is kept until the reference is there to measure it.
  std::vector<std::optional<removal::SurfaceMesh>> surfaces(settings.size());
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
    throw InputError("study densification: no setting could be run; " + s.rows.front().label + ": " +
                     s.rows.front().error);
  removal::SurfaceMesh reference_surface;
  try {
    reference_surface = run(reference, settings.size(), s.reference);
  } catch (const InputError& e) {
    throw InputError("study densification: the reference (" + describe(reference) + ") could not be run: " + e.what());
  }
  // The reference's side of each measurement made once.
  const removal::PreparedSurface reference_side(reference_surface, removal::kSharpEdgeDeg);
  for (std::size_t i = 0; i < settings.size(); ++i) {
    StudyRow& row = s.rows[i];
    if (!surfaces[i]) continue;
    const removal::SurfaceDifference d = removal::surface_difference(*surfaces[i], reference_side, s.resolution_mm);
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
    if (r.poses < best.poses || (r.poses == best.poses && size(r.setting) > size(best.setting)))
      s.recommended = static_cast<int>(i);
  }
  s.wall_time_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  s.peak_memory_mb = peak_memory_mb();
  return s;
}

}  // namespace vcut::pipeline
