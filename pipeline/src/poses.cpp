#include "vcut/pipeline/poses.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>

#include "vcut/io/program_reader.h"
#include "vcut/io/input_error.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/servo.h"

namespace vcut::pipeline {
namespace fs = std::filesystem;

kinematics::FeedInterpretation axis_feed_of(const io::Job& job, const std::string& reader) {
  if (job.machine_spec.feed_interpretation) return *job.machine_spec.feed_interpretation;
  // By dialect: Fanuc and Haas combine mm and deg (Fanuc's feed for simultaneous linear and
  // rotary motion); LinuxCNC's interpreter and SINUMERIK without TRAORI put F on the linear
  // axes when they move; CL data are tool poses (F on the tip).
  if (job.dialect == "fanuc") return kinematics::FeedInterpretation::Combined;
  if (reader == "apt") return kinematics::FeedInterpretation::Tip;
  return kinematics::FeedInterpretation::LinuxCnc;
}

const char* feed_interpretation_name(kinematics::FeedInterpretation f) {
  switch (f) {
    case kinematics::FeedInterpretation::LinuxCnc: return "linuxcnc";
    case kinematics::FeedInterpretation::Combined: return "combined";
    case kinematics::FeedInterpretation::Tip: return "tip";
  }
  return "linuxcnc";
}

// Where a probe's tip, moving from `a` to `b`, first touches the stock as it is before the
// program (a fraction of the move; 0: it starts inside), or none. A box by its slabs; a
// cylinder by its axial slab and the quadratic of its side. A mesh stock: none (the reader
// warns that its probes trip at their end).
static std::optional<double> stock_contact(const io::StockSpec& stock, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  double lo = 0.0, hi = 1.0;
  // Clips [lo, hi] to the s where lower <= value0 + s * rate <= upper.
  auto clip = [&](double value0, double rate, double lower, double upper) {
    if (rate == 0.0) {
      if (value0 < lower || value0 > upper) hi = -1.0;
      return;
    }
    double s0 = (lower - value0) / rate, s1 = (upper - value0) / rate;
    if (s0 > s1) std::swap(s0, s1);
    lo = std::max(lo, s0);
    hi = std::min(hi, s1);
  };
  const Eigen::Vector3d d = b - a;
  if (stock.kind == io::StockSpec::Kind::Box) {
    for (int k = 0; k < 3; ++k) clip(a[k], d[k], stock.box.min_mm[k], stock.box.max_mm[k]);
  } else if (stock.kind == io::StockSpec::Kind::Cylinder) {
    const removal::CylinderShape& c = stock.cylinder;
    const Eigen::Vector3d u = c.axis.normalized();
    clip((a - c.base_center_mm).dot(u), d.dot(u), 0.0, c.height_mm);
    // Distance from the axis: |w + s e|^2 <= r^2, w and e the parts across it.
    const Eigen::Vector3d w = (a - c.base_center_mm) - (a - c.base_center_mm).dot(u) * u, e = d - d.dot(u) * u;
    const double qa = e.squaredNorm(), qb = 2.0 * w.dot(e), qc = w.squaredNorm() - c.radius_mm * c.radius_mm;
    if (qa == 0.0) {
      if (qc > 0.0) hi = -1.0;
    } else {
      const double disc = qb * qb - 4.0 * qa * qc;
      if (disc < 0.0) {
        hi = -1.0;
      } else {
        const double root = std::sqrt(disc);
        lo = std::max(lo, (-qb - root) / (2.0 * qa));
        hi = std::min(hi, (-qb + root) / (2.0 * qa));
      }
    }
  } else {
    return std::nullopt;
  }
  if (lo > hi) return std::nullopt;
  return lo;
}

JobProgram read_job_program(const io::Job& job) {
  // G-code and APT CL data (io::read_programs picks the reader from the job's dialect or from
  // each file). An APT program's CUTTER/ shapes fill in the T numbers the tool library lacks:
  // the library, written for the machine, wins where it has the number.
  io::ProgramOptions reading;
  reading.gcode.work_offsets_mm = job.offsets_mm;
  reading.gcode.unsupported_as_warning = job.unsupported_as_warning;
  reading.gcode.unknown_m_code_as_error = job.unknown_m_code_as_error;
  reading.gcode.block_delete = job.block_delete;
  if (job.arc_tolerance_mm) reading.gcode.arc_tolerance_mm = *job.arc_tolerance_mm;
  reading.gcode.subroutine_path = job.subroutine_path;
  reading.gcode.max_lines = job.max_lines;
  reading.gcode.tcp_m_codes = job.tcp_m_codes;
  reading.gcode.initial_tool = job.initial_tool;
  // The machine starts at its home and goes there on G28 (a tool-pose program's tip under the
  // spindle's gauge point; an axis program's axes at their home values).
  auto machine_start = [&](bool axis_program) {
    io::set_machine(reading.gcode, job.machine_spec, job.tools, axis_program);
    if (!job.start_mm) return;
    // The job's start names the tip; the reader's start is the gauge point above it.
    const auto length = reading.gcode.tool_length_mm.find(job.initial_tool);
    const double l = length == reading.gcode.tool_length_mm.end() ? 0.0 : length->second;
    for (const auto& [letter, value] : *job.start_mm) {
      const int a = letter - 'X';
      (*reading.gcode.start_mm)[a] = value + l * reading.gcode.spindle_axis[a];
    }
  };
  machine_start(false);
  if (job.stock.kind != io::StockSpec::Kind::Mesh) {
    reading.gcode.probe_contact = [stock = job.stock](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return stock_contact(stock, a, b);
    };
  }
  io::LoadedProgram loaded = io::read_programs(job.program_files, job.dialect, reading);
  if (loaded.dialect == "gcode" &&
      std::any_of(loaded.program.blocks.begin(), loaded.program.blocks.end(), [](const kinematics::Block& b) { return !b.tool_pose; })) {
    machine_start(true);
    loaded = io::read_programs(job.program_files, job.dialect, reading);
  }
  JobProgram out;
  out.program = std::move(loaded.program);
  for (auto& f : out.program.files) f = io::display_name(f, job.file);
  out.tools = job.tools;
  out.tools.insert(loaded.cutters.begin(), loaded.cutters.end());  // insert keeps existing numbers
  out.dialect = loaded.dialect;
  return out;
}

double chord_tolerance_mm(const io::Job& job, double resolution_mm) {
  return job.chord_tolerance_mm > 0.0 ? job.chord_tolerance_mm : resolution_mm / 20.0;
}

double default_densify_tolerance_mm(const io::Job& job, double resolution_mm) {
  double eps = resolution_mm / 10.0;
  if (job.gouge_tolerance_mm > 0.0) eps = std::min(eps, job.gouge_tolerance_mm / 2.0);
  return eps;
}

PoseRun run_pose_engine(const io::Job& job, const PeriodVisitor* every_period) {
  return run_pose_engine(job, read_job_program(job), job.resolution_mm, every_period);
}

namespace {

// The servo's actual path thinned for the cut: a period's pose is dropped while every
// dropped pose since the last one kept lies within the tolerance of the chord from that
// one to the newest (tip distance plus the flute length times the tool axis's turn from the
// chord's axis); a block change keeps the pose before it, so that each move has one block.
class PathThinner {
 public:
  PathThinner(std::vector<PoseRun::ActualPose>& out, double tolerance_mm, double reach_mm)
      : out_(out), tolerance_mm_(tolerance_mm), reach_mm_(reach_mm) {}

  void add(const PoseRun::ActualPose& p) {
    if (out_.empty()) {
      out_.push_back(p);
      return;
    }
    if (!pending_.empty() && (p.block != pending_.back().block || pending_.size() >= kMaxPending || !fits(p))) {
      out_.push_back(pending_.back());
      pending_.clear();
    }
    pending_.push_back(p);
  }
  void finish() {
    if (!pending_.empty()) out_.push_back(pending_.back());
    pending_.clear();
  }

 private:
  // Bounds the work per period; a long straight cruise keeps a pose every this many periods.
  static constexpr std::size_t kMaxPending = 16;

  bool fits(const PoseRun::ActualPose& p) const {
    const kinematics::ToolPose& a = out_.back().pose;
    const Eigen::Vector3d d = p.pose.tip_mm - a.tip_mm;
    const double len2 = d.squaredNorm();
    for (const auto& q : pending_) {
      const double t = len2 > 0.0 ? std::clamp((q.pose.tip_mm - a.tip_mm).dot(d) / len2, 0.0, 1.0) : 0.0;
      const double tip = (q.pose.tip_mm - (a.tip_mm + t * d)).norm();
      if (tip > tolerance_mm_) return false;
      if (q.pose.axis == a.axis && p.pose.axis == a.axis) continue;  // the tool does not turn
      // The turn off the chord's axis: its chord on the unit sphere (the angle to third order).
      const Eigen::Vector3d axis = (a.axis + t * (p.pose.axis - a.axis)).normalized();
      if (tip + reach_mm_ * (axis - q.pose.axis).norm() > tolerance_mm_) return false;
    }
    return true;
  }

  std::vector<PoseRun::ActualPose>& out_;
  std::vector<PoseRun::ActualPose> pending_;
  double tolerance_mm_, reach_mm_;
};

}  // namespace

PoseRun run_pose_engine(const io::Job& job, JobProgram input, double resolution_mm, const PeriodVisitor* every_period) {
  PoseRun run;
  run.program = std::move(input.program);
  run.tools = std::move(input.tools);
  run.dialect = input.dialect;
  const kinematics::Program& program = run.program;
  const kinematics::Machine machine(job.machine_spec);

  // Tools: their gauge lengths for the kinematics, and the largest cutting part for the
  // tolerance mode (a conservative bound for every tool).
  kinematics::DensifyMachine dm;
  dm.machine = &machine;
  kinematics::DensifySettings settings;
  for (const auto& b : program.blocks) {
    if (b.tool == 0 || dm.tool_length_mm.count(b.tool)) continue;
    const auto it = run.tools.find(b.tool);
    if (it == run.tools.end())
      throw InputError(program.where(b.source) + ": tool T" + std::to_string(b.tool) + " is not in the tool library " +
                       io::display_name(job.tools_file, job.file));
    dm.tool_length_mm[b.tool] = it->second.gauge_length_mm;
    settings.cutter_length_mm = std::max(settings.cutter_length_mm, it->second.flute_length_mm);
    settings.cutter_radius_mm = std::max(settings.cutter_radius_mm, it->second.radius_mm());
  }
  settings.chord_tolerance_mm = chord_tolerance_mm(job, resolution_mm);
  settings.step_mm = job.step_mm;
  settings.angle_step_rad = job.angle_step_deg * M_PI / 180.0;
  settings.tolerance_mm = job.densify_tolerance_mm;
  // No `densify:`: every block within the tolerance of the machine's path (a straight
  // translation stays one move), arcs still by their chord tolerance where it is finer.
  const bool by_default = !job.densify_given;
  if (by_default) {
    settings.tolerance_mm = default_densify_tolerance_mm(job, resolution_mm);
    settings.arcs_by_chord = true;
  }
  run.densified = kinematics::densify(program, settings, dm);
  const auto& samples = run.densified.samples;

  // Time.
  std::vector<kinematics::AxisValues> axes;
  axes.reserve(samples.size());
  for (const auto& s : samples) axes.push_back(s.axes);
  kinematics::FeedSettings feed = job.feed;
  feed.axis_feed = axis_feed_of(job, run.dialect);
  run.feed = kinematics::plan_feed(program, samples, &axes, &machine, feed);

  run.tool_length_mm.resize(samples.size(), 0.0);
  for (size_t i = 0; i < samples.size(); ++i) {
    const int block = std::max(0, samples[i].block);
    const auto it = program.blocks.empty() ? dm.tool_length_mm.end() : dm.tool_length_mm.find(program.blocks[static_cast<size_t>(block)].tool);
    run.tool_length_mm[i] = it == dm.tool_length_mm.end() ? 0.0 : it->second;
  }

  // Actual poses: servo lag on the axes (every interpolation period), then the machine's
  // geometric errors.
  const auto geometry = job.apply_errors ? kinematics::Geometry::Actual : kinematics::Geometry::Ideal;
  run.block_contour.assign(program.blocks.size(), {});
  std::vector<double> block_sum2(program.blocks.size(), 0.0);
  size_t feed_count = 0;
  double sum2 = 0.0;
  // One contour error (mm) of a period (servo) or sample (errors only) into the figures; a
  // peak between instants (`counted` false) raises the maxima only, not the RMS.
  const auto account = [&](int block, double error_mm, const Eigen::Vector3d& at, bool counted) {
    if (block < 0 || static_cast<size_t>(block) >= program.blocks.size()) return;
    const double um = error_mm * 1000.0;
    PoseRun::BlockContour& c = run.block_contour[static_cast<size_t>(block)];
    if (um >= c.max_um) c.max_um = um, c.at_mm = at;
    const bool feed = program.blocks[static_cast<size_t>(block)].kind != kinematics::MotionKind::Rapid;
    if (counted) {
      ++c.count;
      block_sum2[static_cast<size_t>(block)] += um * um;
      if (feed) ++feed_count, sum2 += um * um;
    }
    // The summary covers feed moves: rapids cut corners by design.
    if (feed && um > run.max_contour_error_um) {
      run.max_contour_error_um = um;
      run.max_contour_line = program.where(program.blocks[static_cast<size_t>(block)].source);
    }
  };
  if (job.servo && samples.size() > 1) {
    // A period far below any controller's (a unit slip) would run for hours: refused.
    constexpr double kMaxPeriods = 1e8;  // about 40 s of this loop
    kinematics::InterpolatorInput in;
    const double span_s = run.feed.cycle_time_s + in.settle_max_s;
    const double periods = span_s / job.servo->period_s;
    if (periods > kMaxPeriods) {
      char what[240];
      std::snprintf(what, sizeof what,
                    "'servo.period': %g s makes %.3g interpolation periods of the program's %.1f s; expected a period "
                    "of at least %.3g s",
                    job.servo->period_s, periods, run.feed.cycle_time_s, span_s / kMaxPeriods);
      throw InputError(job.file, 0, 0, what);
    }
    in.program = &program;
    in.samples = &samples;
    in.blocks = &run.densified.blocks;
    in.feed = &run.feed;
    in.machine = &machine;
    in.tool_length_mm = &run.tool_length_mm;
    in.servo = *job.servo;
    in.geometry = geometry;
    in.ik = dm.ik;
    in.commanded_pose = every_period != nullptr;
    run.actual.resize(samples.size());
    run.contour_error_um.resize(samples.size(), 0.0);
    run.actual_path_tolerance_mm = default_densify_tolerance_mm(job, resolution_mm);
    PathThinner thinner(run.actual_path, run.actual_path_tolerance_mm, settings.cutter_length_mm);
    run.periods = kinematics::for_each_period(in, [&](const kinematics::PeriodSample& p) {
      if (p.stamp >= 0) {
        run.actual[static_cast<size_t>(p.stamp)] = p.actual_pose;
        run.contour_error_um[static_cast<size_t>(p.stamp)] = p.contour_error_mm * 1000.0;
        return;
      }
      // The block where the tool is: of the path's move nearest the actual tip, not the one
      // being commanded (the lag still finishes a cut while the interpolator starts the
      // retract; that is no rapid into the stock).
      const int block = samples[p.nearest_segment].block;
      account(block, p.contour_error_mm, p.actual_pose.tip_mm, !p.peak);
      if (p.peak) return;
      thinner.add({p.actual_pose, block});
      if (every_period) (*every_period)(p);
    });
    thinner.finish();
  } else if (job.apply_errors && !samples.empty()) {
    // Geometric errors alone are static: the actual pose of each sample, the move between
    // two of them as rigid as the nominal one.
    const kinematics::CommandedPath path(program, samples, run.densified.blocks, &machine, &run.tool_length_mm);
    run.actual.reserve(samples.size());
    run.contour_error_um.resize(samples.size(), 0.0);
    size_t from = 1;
    for (size_t i = 0; i < samples.size(); ++i) {
      run.actual.push_back(kinematics::forward(machine, samples[i].axes, run.tool_length_mm[i], geometry));
      run.actual_path.push_back({run.actual.back(), samples[i].block});
      if (samples.size() < 2) continue;
      const auto [lo, hi] = path.window(from, std::max<size_t>(1, i));
      const double e = path.distance(run.actual[i].tip_mm, lo, hi, &from);
      run.contour_error_um[i] = e * 1000.0;
      if (i > 0) account(samples[i].block, e, run.actual[i].tip_mm, true);
    }
  }
  for (size_t b = 0; b < run.block_contour.size(); ++b)
    if (run.block_contour[b].count) run.block_contour[b].rms_um = std::sqrt(block_sum2[b] / static_cast<double>(run.block_contour[b].count));
  run.rms_contour_error_um = feed_count == 0 ? 0.0 : std::sqrt(sum2 / static_cast<double>(feed_count));

  // Per-block findings and q statistics.
  constexpr int kDensifyWarnings = 10;
  int densify_warnings = 0;
  const auto& blocks = run.densified.blocks;
  double q_sum = 0.0;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const auto& r = blocks[i];
    const std::string line = program.where(program.blocks[i].source);
    q_sum += r.q;
    run.q_min = i == 0 ? r.q : std::min(run.q_min, r.q);
    run.q_max = std::max(run.q_max, r.q);
    if (r.nonlinear_error_mm > run.max_nonlinear_error_mm) {
      run.max_nonlinear_error_mm = r.nonlinear_error_mm;
      run.max_nonlinear_line = line;
    }
    const int block = static_cast<int>(i);
    if (!r.unreachable.empty()) run.events.push_back({"unreachable", line, r.unreachable, block, block});
    // The user's step or angle leaves the moves off the machine's path by more than a gouge.
    if (job.densify_given && r.chord_error_mm > job.gouge_tolerance_mm) {
      char detail[240];
      std::snprintf(detail, sizeof detail,
                    "the densified moves leave the tool tip %.3f mm off the machine's path (chord error; the gouge "
                    "tolerance is %g mm): densify finer, or leave `densify:` out to densify to the tolerance",
                    r.chord_error_mm, job.gouge_tolerance_mm);
      run.events.push_back({"densify_error", line, detail, block, block});
      // The terminal gets the first few; every block stays in the events (report, page).
      if (++densify_warnings <= kDensifyWarnings) run.warnings.push_back(line + ": " + detail);
    }
  }
  if (densify_warnings > kDensifyWarnings)
    run.warnings.push_back(std::to_string(densify_warnings - kDensifyWarnings) +
                           " more block(s) densified beyond the gouge tolerance (events densify_error in report.json)");
  // Singular poses, one event per run of consecutive blocks (a three-axis program on a
  // five-axis machine sits on the pole throughout: one event, not thousands).
  for (size_t i = 0; i < blocks.size();) {
    if (!blocks[i].singular) {
      ++i;
      continue;
    }
    size_t j = i;
    double miss = 0.0;
    while (j < blocks.size() && blocks[j].singular) miss = std::max(miss, blocks[j++].singular_miss_rad);
    const kinematics::SourceRef a = program.blocks[i].source, b = program.blocks[j - 1].source;
    std::string where = program.where(a);
    if (b.file == a.file && b.line != a.line) where += "-" + std::to_string(b.line);
    else if (b.file != a.file) where += " to " + program.where(b);
    char detail[160];
    std::snprintf(detail, sizeof detail,
                  "%zu block(s) with the tool axis in the singular cone: the free rotary angle was kept "
                  "(largest tool-axis miss %.3g urad)", j - i, miss * 1e6);
    run.events.push_back({"singular", where, detail, static_cast<int>(i), static_cast<int>(j - 1)});
    i = j;
  }
  run.q_mean = blocks.empty() ? 0.0 : q_sum / static_cast<double>(blocks.size());
  int last_block = -1;
  for (int s : run.feed.axis_limited_samples) {
    const int block = samples[static_cast<size_t>(s)].block;
    if (block < 0 || block == last_block) continue;
    last_block = block;
    run.events.push_back({"axis_limited_speed", program.where(program.blocks[static_cast<size_t>(block)].source),
                          "a machine axis limit, not the programmed feed, set the speed", block, block});
  }
  return run;
}

}  // namespace vcut::pipeline
