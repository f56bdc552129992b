#include "vcut/pipeline/check.h"

#include <fmt/format.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "vcut/io/mesh_io.h"
#include "vcut/pipeline/machine_check.h"
#include "vcut/removal/move.h"
#include "vcut/removal/stock.h"
#include "vcut/removal/sweep.h"

namespace vcut::pipeline {

const char* to_string(Severity severity) {
  switch (severity) {
    case Severity::Error:
      return "error";
    case Severity::Warning:
      return "warning";
    case Severity::Note:
      return "note";
  }
  return "note";
}

const char* to_string(CheckKind kind) {
  switch (kind) {
    case CheckKind::Unreachable:
      return to_string(PoseEventKind::Unreachable);
    case CheckKind::Singular:
      return to_string(PoseEventKind::Singular);
    case CheckKind::AxisLimitedSpeed:
      return to_string(PoseEventKind::AxisLimitedSpeed);
    case CheckKind::DensifyError:
      return to_string(PoseEventKind::DensifyError);
    case CheckKind::NoTool:
      return "no_tool";
    case CheckKind::RapidInStockBox:
      return "rapid_in_stock_box";
    case CheckKind::SpindleStoppedFeed:
      return "spindle_stopped_feed";
    case CheckKind::ShankInStockBox:
      return "shank_in_stock_box";
    case CheckKind::HolderInStockBox:
      return "holder_in_stock_box";
    case CheckKind::MachineCollision:
      return "machine_collision";
    case CheckKind::MachineNearMiss:
      return "machine_near_miss";
    case CheckKind::BodyInStock:
      return "body_in_stock";
  }
  return "unreachable";
}

CheckKind check_kind(PoseEventKind kind) {
  switch (kind) {
    case PoseEventKind::Unreachable:
      return CheckKind::Unreachable;
    case PoseEventKind::Singular:
      return CheckKind::Singular;
    case PoseEventKind::AxisLimitedSpeed:
      return CheckKind::AxisLimitedSpeed;
    case PoseEventKind::DensifyError:
      return CheckKind::DensifyError;
  }
  return CheckKind::Unreachable;
}

namespace {

Eigen::AlignedBox3d stock_bounds(const io::Job& job) {
  switch (job.stock.kind) {
    case io::StockSpec::Kind::Box:
      return removal::bounds_of(job.stock.box);
    case io::StockSpec::Kind::Cylinder:
      return removal::bounds_of(job.stock.cylinder);
    case io::StockSpec::Kind::Mesh:
      break;
  }
  removal::TriangleMesh mesh = io::read_mesh(job.stock.mesh_file);
  return removal::bounds_of(removal::StockShape(std::move(mesh)));
}

// How far one box reaches into the other: the smallest of the three overlaps (the way out
// that is shortest); <= 0 when they do not overlap.
double penetration_mm(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b) {
  double depth = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k)
    depth = std::min(depth, std::min(a.max()[k], b.max()[k]) - std::max(a.min()[k], b.min()[k]));
  return depth;
}

// Events of one kind on consecutive blocks merge into one, with the line range.
class EventLog {
 public:
  explicit EventLog(const kinematics::Program& program) : program_(program) {}

  void add(Severity severity, CheckKind kind, int block, const std::string& detail, double depth_mm,
           const Eigen::Vector3d& where_mm) {
    const kinematics::SourceRef& src = program_.blocks[static_cast<std::size_t>(block)].source;
    auto it = open_.find(kind);
    if (it != open_.end()) {
      Open& o = it->second;
      CheckEvent& e = events_[o.index];
      if (block <= o.last_block + 1) {
        if (block != o.last_block && src.file == e.lines.first.file && src.line > e.lines.first.line)
          e.lines.last = src;
        o.last_block = block;
        if (depth_mm > e.depth_mm) {
          e.depth_mm = depth_mm;
          e.where_mm = where_mm;
          e.detail = detail;
        }
        return;
      }
    }
    open_[kind] = Open{events_.size(), block, block};
    CheckEvent e;
    e.severity = severity;
    e.kind = kind;
    e.lines = {src, src};
    e.detail = detail;
    e.depth_mm = depth_mm;
    e.where_mm = where_mm;
    e.has_where = true;
    events_.push_back(e);
    first_block_.push_back(block);
  }
  void add_lines(Severity severity, CheckKind kind, const kinematics::SourceRange& lines, const std::string& detail,
                 int block) {
    CheckEvent e;
    e.severity = severity;
    e.kind = kind;
    e.lines = lines;
    e.detail = detail;
    events_.push_back(e);
    first_block_.push_back(block);
  }
  // A contact of the machine check: a hit is an error, a near miss a warning, the tool side
  // in the stock's initial shape a warning (the program may have cut that material away).
  void add_contact(const MachineContact& c, const kinematics::Machine& machine) {
    CheckEvent e;
    const bool stock = c.b_kind == BodyKind::Stock;
    e.kind = stock ? CheckKind::BodyInStock : c.hit ? CheckKind::MachineCollision : CheckKind::MachineNearMiss;
    e.severity = !stock && c.hit ? Severity::Error : Severity::Warning;
    if (stock && !c.hit) e.kind = CheckKind::MachineNearMiss;
    e.lines = c.lines;
    e.bodies = {c.a, c.b};
    e.depth_mm = c.depth_mm;
    e.clearance_mm = c.clearance_mm;
    e.where_mm = c.where_mm;
    e.has_where = true;
    e.axes = c.axes;
    e.between_poses = c.between_poses;
    const std::string at = axis_text(machine, c.axes);
    const std::string when = c.between_poses ? " between two poses, at " : " at ";
    if (c.hit)
      e.detail = c.a + (stock ? " enters " : " hits ") + c.b + fmt::format(" ({:.3f} mm deep)", c.depth_mm) + when +
                 at + (stock ? " (a collision unless that material is gone)" : "");
    else
      e.detail = c.a + fmt::format(" passes {:.3f} mm from ", c.clearance_mm) + c.b + when + at;
    events_.push_back(e);
    first_block_.push_back(c.first_block);
  }
  // In program order (stable: the order of detection within a block).
  std::vector<CheckEvent> take() {
    std::vector<std::size_t> order(events_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return first_block_[a] < first_block_[b]; });
    std::vector<CheckEvent> out;
    for (std::size_t i : order) out.push_back(events_[i]);
    return out;
  }

 private:
  struct Open {
    std::size_t index;
    int first_block, last_block;
  };
  const kinematics::Program& program_;
  std::vector<CheckEvent> events_;
  std::vector<int> first_block_;
  std::map<CheckKind, Open> open_;
};

std::string mm(double x) { return fmt::format("{:.3f} mm", x); }

}  // namespace

CheckResult run_check(const io::Job& job) {
  const auto t0 = std::chrono::steady_clock::now();
  CheckResult result;
  result.run = run_pose_engine(job);
  const PoseRun& run = result.run;
  const kinematics::Program& program = run.program;
  result.stock_box = stock_bounds(job);
  const Eigen::AlignedBox3d& box = result.stock_box;
  const double tolerance_mm = job.collision_tolerance_mm;
  EventLog log(program);
  // With the machine check, a stock that is not a box meets the shank and holder there, by its
  // shape; a box stock's box test is exact.
  const bool machine_bodies = has_machine_bodies(job, run);
  const bool by_shape = machine_bodies && job.stock.kind != io::StockSpec::Kind::Box;

  // The pose engine's findings, by their first block.
  for (const PoseEvent& e : run.events) {
    const int block = std::max(e.first_block, 0);
    const Severity s = e.kind == PoseEventKind::Unreachable                                         ? Severity::Error
                       : e.kind == PoseEventKind::Singular || e.kind == PoseEventKind::DensifyError ? Severity::Warning
                                                                                                    : Severity::Note;
    log.add_lines(s, check_kind(e.kind), e.lines, e.detail, block);
  }

  // The tools' cutting parts, shanks and holders against the stock's box, move by move.
  removal::MoveList parts;
  std::map<int, int> cutter_of_tool;
  for (const auto& [number, cutter] : run.tools) {
    cutter_of_tool[number] = static_cast<int>(parts.cutters.size());
    parts.cutters.push_back(cutter);
  }
  const std::vector<removal::ToolBody> bodies = removal::add_tool_bodies(parts);
  std::map<int, ToolClearance> clearance;
  const auto& samples = run.densified.samples;
  std::vector<removal::Move> probes;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const int block = samples[i].block;
    if (block < 0) continue;
    const kinematics::Block& b = program.blocks[static_cast<std::size_t>(block)];
    const bool rapid = b.kind == kinematics::MotionKind::Rapid;
    if (b.tool == 0) {
      if (!rapid)
        log.add(Severity::Error, CheckKind::NoTool, block, "a feed move with no tool in the spindle", 0.0,
                samples[i].pose.tip_mm);
      continue;
    }
    const int c = cutter_of_tool.at(b.tool);
    removal::Move m;
    m.start_mm = samples[i - 1].pose.tip_mm;
    m.end_mm = samples[i].pose.tip_mm;
    m.cutter = c;
    m.block = block;
    // A retract straight up the tool axis meets nothing the move before it did not: skip.
    const Eigen::Vector3d step = m.end_mm - m.start_mm;
    const Eigen::Vector3d axis_now = samples[i].pose.axis.normalized();
    if (samples[i - 1].pose.axis.isApprox(samples[i].pose.axis, 1e-12) && step.dot(axis_now) > 0.0 &&
        step.cross(axis_now).norm() <= 1e-9 * step.norm())
      continue;
    // A turning move: both end orientations (the box of the pieces between lies within).
    for (const Eigen::Vector3d& axis : {samples[i - 1].pose.axis, samples[i].pose.axis}) {
      m.axis = axis.normalized();
      const Eigen::AlignedBox3d cut = removal::TranslationSweep(parts.cutters[static_cast<std::size_t>(c)], m).bounds();
      const double depth = penetration_mm(cut, box);
      if (depth > tolerance_mm) {
        if (rapid)
          log.add(Severity::Warning, CheckKind::RapidInStockBox, block,
                  "a rapid with the cutting part " + mm(depth) +
                      " inside the stock's box (a collision unless that material is gone)",
                  depth, m.end_mm);
        else if (b.spindle == kinematics::SpindleState::Off)
          log.add(Severity::Error, CheckKind::SpindleStoppedFeed, block,
                  "a feed move into the stock's box (" + mm(depth) + ") with the spindle stopped", depth, m.end_mm);
      }
      probes.clear();
      removal::append_body_probes(probes, m, bodies[static_cast<std::size_t>(c)]);
      for (const removal::Move& p : probes) {
        const Eigen::AlignedBox3d part =
            removal::TranslationSweep(parts.cutters[static_cast<std::size_t>(p.cutter)], p).bounds();
        const bool holder = p.probe == removal::ProbeKind::Holder;
        if (holder) {
          ToolClearance& t = clearance[b.tool];
          t.tool = b.tool;
          t.has_holder = true;
          const bool over = part.min().x() < box.max().x() && part.max().x() > box.min().x() &&
                            part.min().y() < box.max().y() && part.max().y() > box.min().y();
          const double gap = part.min().z() - box.max().z();
          if (over && (!t.over_stock || gap < t.holder_clearance_mm)) {
            t.holder_clearance_mm = gap;
            t.holder_line = b.source;
          }
          t.over_stock = t.over_stock || over;
        }
        const double d = penetration_mm(part, box);
        if (d > tolerance_mm && !by_shape)
          log.add(Severity::Warning, holder ? CheckKind::HolderInStockBox : CheckKind::ShankInStockBox, block,
                  std::string(holder ? "the holder" : "the shank") + " of T" + std::to_string(b.tool) + " " + mm(d) +
                      " inside the stock's box (a collision unless that material is gone)",
                  d, p.end_mm);
      }
    }
  }
  for (const auto& b : program.blocks)
    if (b.tool != 0 && !clearance.count(b.tool)) clearance[b.tool].tool = b.tool;  // no holder given
  for (const auto& [tool, t] : clearance) result.tools.push_back(t);
  if (machine_bodies) {
    const auto m0 = std::chrono::steady_clock::now();
    MachineCheckOptions options;
    options.clearance_mm = job.machine_clearance_mm;
    options.stock = true;
    options.stock_parts = by_shape;
    const MachineCheck m = check_machine(job, run, options);
    result.machine_checked = true;
    result.bodies = m.bodies;
    result.body_pairs = m.pairs;
    result.body_queries = m.queries;
    result.notes = m.warnings;
    for (const MachineContact& c : m.contacts) log.add_contact(c, *run.machine);
    result.machine_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - m0).count();
  }
  result.events = log.take();
  for (const CheckEvent& e : result.events) {
    result.errors += e.severity == Severity::Error;
    result.warnings += e.severity == Severity::Warning;
  }
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace vcut::pipeline
