#include "vcut/kinematics/pose_chain.h"

#include <algorithm>
#include <cmath>

namespace vcut::kinematics {
namespace {

// The servo's actual path thinned for the cut: a period's pose is dropped while every
// dropped pose since the last one kept lies within the tolerance of the chord from that
// one to the newest (tip distance plus the flute length times the tool axis's turn from the
// chord's axis); a block change keeps the pose before it, so that each move has one block.
class PathThinner {
 public:
  PathThinner(std::vector<PoseChain::ActualPose>& out, double tolerance_mm, double reach_mm)
      : out_(out), tolerance_mm_(tolerance_mm), reach_mm_(reach_mm) {}

  void add(const PoseChain::ActualPose& p) {
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

  bool fits(const PoseChain::ActualPose& p) const {
    const ToolPose& a = out_.back().pose;
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

  std::vector<PoseChain::ActualPose>& out_;
  std::vector<PoseChain::ActualPose> pending_;
  double tolerance_mm_, reach_mm_;
};

}  // namespace

PoseChain run_pose_chain(const Program& program, const Machine& machine, const std::map<int, double>& tool_length_mm,
                         const PoseChainSettings& settings, const PeriodVisitor* every_period) {
  PoseChain run;
  DensifyMachine dm;
  dm.machine = &machine;
  dm.tool_length_mm = tool_length_mm;
  run.densified = densify(program, settings.densify, dm);
  const auto& samples = run.densified.samples;

  // Time.
  FeedSettings feed = settings.feed;
  feed.timing = settings.servo.has_value();  // the periods between the samples
  run.feed = plan_feed(program, samples, &machine, feed);

  run.tool_length_mm.resize(samples.size(), 0.0);
  for (size_t i = 0; i < samples.size(); ++i) {
    const int block = std::max(0, samples[i].block);
    const auto it = program.blocks.empty() ? tool_length_mm.end()
                                           : tool_length_mm.find(program.blocks[static_cast<size_t>(block)].tool);
    run.tool_length_mm[i] = it == tool_length_mm.end() ? 0.0 : it->second;
  }

  // Actual poses: servo lag on the axes (every interpolation period), then the machine's
  // geometric errors.
  const Geometry geometry = settings.geometry;
  // Per block only where there are actual poses.
  const bool actual = (settings.servo && samples.size() > 1) || (geometry == Geometry::Actual && !samples.empty());
  if (actual) run.block_contour.assign(program.blocks.size(), {});
  std::vector<double> block_sum2(actual ? program.blocks.size() : 0, 0.0);
  size_t feed_count = 0;
  double sum2 = 0.0;
  // One contour error (mm) of a period (servo) or sample (errors only) into the figures; a
  // peak between instants (`counted` false) raises the maxima only, not the RMS.
  const auto account = [&](int block, double error_mm, const Eigen::Vector3d& at, bool counted) {
    if (block < 0 || static_cast<size_t>(block) >= program.blocks.size()) return;
    const double um = error_mm * 1000.0;
    PoseChain::BlockContour& c = run.block_contour[static_cast<size_t>(block)];
    if (um >= c.max_um) c.max_um = um, c.at_mm = at;
    const bool feed = program.blocks[static_cast<size_t>(block)].kind != MotionKind::Rapid;
    if (counted) {
      ++c.count;
      block_sum2[static_cast<size_t>(block)] += um * um;
      if (feed) ++feed_count, sum2 += um * um;
    }
    // The summary covers feed moves: rapids cut corners by design.
    if (feed && um > run.max_contour_error_um) {
      run.max_contour_error_um = um;
      run.max_contour_block = block;
    }
  };
  if (settings.servo && samples.size() > 1) {
    if (settings.before_servo) settings.before_servo(run.feed);
    InterpolatorInput in;
    in.program = &program;
    in.samples = &samples;
    in.blocks = &run.densified.blocks;
    in.feed = &run.feed;
    in.machine = &machine;
    in.tool_length_mm = &run.tool_length_mm;
    in.servo = *settings.servo;
    in.geometry = geometry;
    in.ik = dm.ik;
    in.commanded_pose = every_period != nullptr;
    run.actual.resize(samples.size());
    run.contour_error_um.resize(samples.size(), 0.0);
    run.actual_path_tolerance_mm = settings.actual_path_tolerance_mm;
    PathThinner thinner(run.actual_path, run.actual_path_tolerance_mm, settings.densify.cutter_length_mm);
    run.periods = for_each_period(in, [&](const PeriodSample& p) {
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
  } else if (geometry == Geometry::Actual && !samples.empty()) {
    // Geometric errors alone are static: the actual pose of each sample, the move between
    // two of them as rigid as the nominal one.
    const CommandedPath path(program, samples, run.densified.blocks, &machine, &run.tool_length_mm);
    run.actual.reserve(samples.size());
    run.contour_error_um.resize(samples.size(), 0.0);
    size_t from = 1;
    for (size_t i = 0; i < samples.size(); ++i) {
      run.actual.push_back(forward(machine, samples[i].axes, run.tool_length_mm[i], geometry));
      run.actual_path.push_back({run.actual.back(), samples[i].block});
      if (samples.size() < 2) continue;
      const auto [lo, hi] = path.window(from, std::max<size_t>(1, i));
      const double e = path.distance(run.actual[i].tip_mm, lo, hi, &from);
      run.contour_error_um[i] = e * 1000.0;
      if (i > 0) account(samples[i].block, e, run.actual[i].tip_mm, true);
    }
  }
  for (size_t b = 0; b < run.block_contour.size(); ++b)
    if (run.block_contour[b].count)
      run.block_contour[b].rms_um = std::sqrt(block_sum2[b] / static_cast<double>(run.block_contour[b].count));
  run.rms_contour_error_um = feed_count == 0 ? 0.0 : std::sqrt(sum2 / static_cast<double>(feed_count));
  return run;
}

}  // namespace vcut::kinematics
