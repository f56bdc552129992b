#include "vcut/pipeline/poses.h"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>

#include "vcut/io/program_reader.h"
#include "vcut/io/input_error.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/servo.h"

namespace vcut::pipeline {
namespace fs = std::filesystem;

kinematics::FeedInterpretation axis_feed_of(const io::Job& job, io::ProgramReader reader) {
  if (job.machine_spec.feed_interpretation) return *job.machine_spec.feed_interpretation;
  // By dialect: Fanuc and Haas combine mm and deg (Fanuc's feed for simultaneous linear and
  // rotary motion); LinuxCNC's interpreter and SINUMERIK without TRAORI put F on the linear
  // axes when they move; CL data are tool poses (F on the tip).
  if (job.dialect == io::Dialect::Fanuc) return kinematics::FeedInterpretation::Combined;
  if (reader == io::ProgramReader::Apt) return kinematics::FeedInterpretation::Tip;
  return kinematics::FeedInterpretation::LinuxCnc;
}

const char* feed_interpretation_name(kinematics::FeedInterpretation f) {
  switch (f) {
    case kinematics::FeedInterpretation::LinuxCnc:
      return "linuxcnc";
    case kinematics::FeedInterpretation::Combined:
      return "combined";
    case kinematics::FeedInterpretation::Tip:
      return "tip";
  }
  return "linuxcnc";
}

// Where a probe's tip, moving from `a` to `b`, first touches the stock as it is before the
// program (a fraction of the move; 0: it starts inside), or none. A box by its slabs; a
// cylinder by its axial slab and the quadratic of its side. A mesh stock: none (the reader
// warns that its probes trip at their end).
static std::optional<double> stock_contact(const io::StockSpec& stock, const Eigen::Vector3d& a,
                                           const Eigen::Vector3d& b) {
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
  reading.apt.cutcom_on_centre = job.apt_cutcom_on_centre;
  reading.gcode.subroutine_path = job.subroutine_path;
  reading.gcode.max_lines = job.max_lines;
  reading.gcode.tcp_m_codes = job.tcp_m_codes;
  reading.gcode.initial_tool = job.initial_tool;
  reading.gcode.extra_axes.clear();  // a job's machines have no U V W: their words are errors naming the line
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
  if (loaded.reader == io::ProgramReader::Gcode &&
      std::any_of(loaded.program.blocks.begin(), loaded.program.blocks.end(),
                  [](const kinematics::Block& b) { return !b.tool_pose; })) {
    machine_start(true);
    loaded = io::read_programs(job.program_files, job.dialect, reading);
  }
  JobProgram out;
  out.program = std::move(loaded.program);
  for (auto& f : out.program.files) f = io::display_name(f, job.file);
  out.tools = job.tools;
  out.tools.insert(loaded.cutters.begin(), loaded.cutters.end());  // insert keeps existing numbers
  out.reader = loaded.reader;
  return out;
}

const char* to_string(PoseEventKind kind) {
  switch (kind) {
    case PoseEventKind::Unreachable:
      return "unreachable";
    case PoseEventKind::Singular:
      return "singular";
    case PoseEventKind::AxisLimitedSpeed:
      return "axis_limited_speed";
    case PoseEventKind::DensifyError:
      return "densify_error";
  }
  return "unreachable";
}

double chord_tolerance_mm(const io::Job& job, double resolution_mm) {
  return job.chord_tolerance_mm > 0.0 ? job.chord_tolerance_mm : resolution_mm / 20.0;
}

// The pieces' union reaches past the rigid sweep by up to the tolerance, so by default it is
// the densification's: the part within half the gouge tolerance of the machine's.
double turn_tolerance_mm(const io::Job& job, double resolution_mm) {
  return job.turn_tolerance_mm > 0.0 ? job.turn_tolerance_mm : default_densify_tolerance_mm(job, resolution_mm);
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

// The findings of the blocks, visited in program order (densify's reports, then the blocks
// an axis limit slowed): per-block events in block order, then the singular runs, then the
// axis-limited blocks, as report.json lists them; q statistics and the largest nonlinear error.
class Findings {
 public:
  Findings(const io::Job& job, PoseRun& run) : job_(job), run_(run), program_(run.program) {}

  void block(std::size_t i, const kinematics::BlockReport& r) {
    // The block's line, decoded only where a finding names it (most blocks have none).
    const auto line = [&] { return program_.blocks[i].source; };
    q_sum_ += r.q;
    run_.q_min = i == 0 ? r.q : std::min(run_.q_min, r.q);
    run_.q_max = std::max(run_.q_max, r.q);
    ++blocks_;
    if (r.nonlinear_error_mm > run_.max_nonlinear_error_mm) {
      run_.max_nonlinear_error_mm = r.nonlinear_error_mm;
      run_.max_nonlinear_line = line();
    }
    const int block = static_cast<int>(i);
    if (!r.unreachable.empty())
      run_.events.push_back({PoseEventKind::Unreachable, {line(), line()}, r.unreachable, block, block});
    // The user's step or angle leaves the moves off the machine's path by more than a gouge.
    if (job_.densify_given && r.chord_error_mm > job_.gouge_tolerance_mm) {
      const std::string detail = fmt::format(
          "the densified moves leave the tool tip {:.3f} mm off the machine's path (chord error; the gouge "
          "tolerance is {:g} mm): densify finer, or leave `densify:` out to densify to the tolerance",
          r.chord_error_mm, job_.gouge_tolerance_mm);
      run_.events.push_back({PoseEventKind::DensifyError, {line(), line()}, detail, block, block});
      // The terminal gets the first few; every block stays in the events (report, page).
      if (++densify_warnings_ <= kDensifyWarnings) run_.warnings.push_back(program_.where(line()) + ": " + detail);
    }
    // Singular poses, one event per run of consecutive blocks (a three-axis program on a
    // five-axis machine sits on the pole throughout: one event, not thousands).
    if (r.singular) {
      if (singular_first_ < 0) singular_first_ = block, singular_miss_ = 0.0;
      singular_miss_ = std::max(singular_miss_, r.singular_miss_rad);
    } else {
      close_singular(block - 1);
    }
  }
  // A block whose speed a machine axis limit set (each once).
  void axis_limited(int block) {
    if (block < 0 || block == last_limited_) return;
    last_limited_ = block;
    limited_.push_back({PoseEventKind::AxisLimitedSpeed, program_.range_of_blocks(block, block),
                        "a machine axis limit, not the programmed feed, set the speed", block, block});
  }
  void finish() {
    close_singular(static_cast<int>(blocks_) - 1);
    if (densify_warnings_ > kDensifyWarnings)
      run_.warnings.push_back(
          std::to_string(densify_warnings_ - kDensifyWarnings) +
          " more block(s) densified beyond the gouge tolerance (events densify_error in report.json)");
    run_.events.insert(run_.events.end(), singular_.begin(), singular_.end());
    run_.events.insert(run_.events.end(), limited_.begin(), limited_.end());
    run_.q_mean = blocks_ == 0 ? 0.0 : q_sum_ / static_cast<double>(blocks_);
  }

 private:
  static constexpr int kDensifyWarnings = 10;
  void close_singular(int last) {
    if (singular_first_ < 0) return;
    const int i = singular_first_;
    singular_first_ = -1;
    const std::string detail = fmt::format(
        "{} block(s) with the tool axis in the singular cone: the free rotary angle was kept "
        "(largest tool-axis miss {:.3g} urad)",
        last - i + 1, singular_miss_ * 1e6);
    singular_.push_back({PoseEventKind::Singular, program_.range_of_blocks(i, last), detail, i, last});
  }

  const io::Job& job_;
  PoseRun& run_;
  const kinematics::Program& program_;
  double q_sum_ = 0.0;
  std::size_t blocks_ = 0;
  int densify_warnings_ = 0;
  int singular_first_ = -1, last_limited_ = -1;
  double singular_miss_ = 0.0;
  std::vector<PoseEvent> singular_, limited_;
};

constexpr std::size_t kTimelinePoints = 4000;
// The first sample of the timeline's point p of `points` over n samples.
std::size_t timeline_sample(std::size_t p, std::size_t n, std::size_t points) { return p * n / points; }

// The job's feed settings, F read in axis blocks as its program's reader and machine say.
kinematics::FeedSettings feed_settings_of(const io::Job& job, io::ProgramReader reader) {
  kinematics::FeedSettings feed = job.feed;
  feed.axis_feed = axis_feed_of(job, reader);
  return feed;
}

// A streamed run's two passes over the program, neither holding the samples: one counts the
// poses (the timeline's points depend on their number), the other times them and gathers the
// findings.
void streamed_passes(const io::Job& job, PoseRun& run) {
  const kinematics::Program& program = run.program;
  const kinematics::DensifySettings& settings = run.densify_settings;
  Findings findings(job, run);
  kinematics::Densifier count(program, settings, run.densify_machine, !run.poses_need_axes);
  std::vector<kinematics::PoseSample> block_samples;
  run.poses = program.blocks.empty() ? 0 : 1;
  while (!count.done()) {
    kinematics::BlockReport report;
    block_samples.clear();
    count.next_block(block_samples, report);
    run.poses += block_samples.size();
  }
  const std::size_t n = run.poses, points = std::min(n, kTimelinePoints);
  std::size_t point = 0;
  kinematics::FeedStreamVisitor visit;
  visit.sample = [&](std::size_t i, const kinematics::PoseSample&, double t_s, double speed_mm_per_s) {
    if (n < 2 || point >= points || i != timeline_sample(point, n, points)) return;
    run.timeline.t_s.push_back(t_s);
    run.timeline.speed_mm_per_s.push_back(speed_mm_per_s);
    run.timeline.sample.push_back(i);
    ++point;
  };
  visit.block = [&](std::size_t b, const kinematics::BlockReport& report, double, bool axis_limited) {
    findings.block(b, report);
    if (axis_limited) findings.axis_limited(static_cast<int>(b));
  };
  kinematics::FeedSettings feed = feed_settings_of(job, run.reader);
  feed.timing = false;
  run.feed.cycle_time_s = kinematics::stream_feed(program, settings, run.densify_machine, feed, visit);
  findings.finish();
}

}  // namespace

void finish_pose_run(const io::Job& job, PoseRun& run) {
  if (!run.passes_pending) return;
  streamed_passes(job, run);
  run.passes_pending = false;
}

PoseRun run_pose_engine(const io::Job& job, JobProgram input, double resolution_mm, const PeriodVisitor* every_period,
                        bool stream, bool stream_passes_later) {
  PoseRun run;
  run.program = std::move(input.program);
  run.tools = std::move(input.tools);
  run.reader = input.reader;
  const kinematics::Program& program = run.program;
  run.machine = std::make_shared<const kinematics::Machine>(job.machine_spec);
  const kinematics::Machine& machine = *run.machine;

  // Tools: their gauge lengths for the kinematics, and the largest cutting part for the
  // tolerance mode (a conservative bound for every tool).
  std::map<int, double> tool_length_mm;  // gauge lengths by T number
  kinematics::DensifySettings settings;
  for (const auto& b : program.blocks) {
    if (b.tool == 0 || tool_length_mm.count(b.tool)) continue;
    const auto it = run.tools.find(b.tool);
    if (it == run.tools.end())
      throw InputError(
          program.where(b.source) + ": tool T" + std::to_string(b.tool) + " is not in the tool library" +
          (job.tools_file.empty() ? std::string(" of the job") : " " + io::display_name(job.tools_file, job.file)));
    tool_length_mm[b.tool] = it->second.gauge_length_mm;
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
  kinematics::PoseChainSettings chain;
  chain.densify = settings;
  chain.feed = feed_settings_of(job, run.reader);
  chain.servo = job.servo;
  chain.geometry = job.apply_errors ? kinematics::Geometry::Actual : kinematics::Geometry::Ideal;
  chain.actual_path_tolerance_mm = default_densify_tolerance_mm(job, resolution_mm);
  run.densify_settings = settings;
  run.densify_machine.machine = &machine;
  run.densify_machine.tool_length_mm = tool_length_mm;
  Findings findings(job, run);

  if (stream && !job.servo && !job.apply_errors && every_period == nullptr) {
    run.streamed = true;
    run.poses_need_axes = std::any_of(program.blocks.begin(), program.blocks.end(),
                                      [](const kinematics::Block& b) { return kinematics::uses_start_axes(b); });
    if (stream_passes_later)
      run.passes_pending = true;
    else
      streamed_passes(job, run);
    return run;
  }

  chain.before_servo = [&](const kinematics::FeedPlan& feed) {
    // A period far below any controller's (a unit slip) would run for hours: refused.
    constexpr double kMaxPeriods = 1e8;  // about 40 s of this loop
    const double span_s = feed.cycle_time_s + kinematics::InterpolatorInput{}.settle_max_s;
    const double periods = span_s / job.servo->period_s;
    if (periods <= kMaxPeriods) return;
    const std::string what = fmt::format(
        "'servo.period': {:g} s makes {:.3g} interpolation periods of the program's {:.1f} s; expected a period "
        "of at least {:.3g} s",
        job.servo->period_s, periods, feed.cycle_time_s, span_s / kMaxPeriods);
    throw InputError(job.file, 0, 0, what);
  };
  static_cast<kinematics::PoseChain&>(run) =
      kinematics::run_pose_chain(program, machine, tool_length_mm, chain, every_period);
  if (run.max_contour_block >= 0)
    run.max_contour_line = program.blocks[static_cast<size_t>(run.max_contour_block)].source;
  const auto& samples = run.densified.samples;
  run.poses = samples.size();

  for (size_t i = 0; i < run.densified.blocks.size(); ++i) findings.block(i, run.densified.blocks[i]);
  for (int s : run.feed.axis_limited_samples) findings.axis_limited(samples[static_cast<size_t>(s)].block);
  findings.finish();

  // The timeline: each point the largest contour error of its stretch, so peaks survive.
  const auto& t = run.feed.t_s;
  if (t.size() > 1 && run.feed.speed_mm_per_s.size() == t.size()) {
    const std::size_t n = t.size(), points = std::min(n, kTimelinePoints);
    const bool contour = run.contour_error_um.size() == n;
    for (std::size_t p = 0; p < points; ++p) {
      const std::size_t a = timeline_sample(p, n, points), b = std::max(a + 1, timeline_sample(p + 1, n, points));
      std::size_t pick = a;
      if (contour)
        for (std::size_t i = a; i < b; ++i)
          if (run.contour_error_um[i] > run.contour_error_um[pick]) pick = i;
      run.timeline.t_s.push_back(t[pick]);
      run.timeline.sample.push_back(pick);
      run.timeline.speed_mm_per_s.push_back(run.feed.speed_mm_per_s[pick]);
      if (contour) run.timeline.contour_error_um.push_back(run.contour_error_um[pick]);
    }
  }
  return run;
}

}  // namespace vcut::pipeline
