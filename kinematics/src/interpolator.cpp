#include "vcut/kinematics/interpolator.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "segment.h"

namespace vcut::kinematics {
namespace {

// The lag runs along the path, so the nearest move is searched from the last one found,
// kBackSlack moves back (should that one have been a near miss), to kAheadSlack beyond the
// move being commanded (the loops overshoot a stop by a few per cent of their lag, not by
// whole moves).
constexpr std::size_t kBackSlack = 4;
constexpr std::size_t kAheadSlack = 2;
constexpr int kGoldenIterations = 48;  // the piece's parameter to 0.618^48 ~ 1e-10
// The peak between two instants exceeds the larger instant by the path's curvature over half
// a period: a few per cent at seed 004's 40 m/min. Instants below this share of the largest
// error of their block so far, or below the floor (0.1 um: rounding noise along a straight
// cruise peaks every other period), cannot set a maximum and are not refined.
constexpr double kPeakShare = 0.9;
constexpr double kPeakFloorMm = 1e-4;

// Distance from p to an arc (helix) block near its parameter s_guess: the angle of p about
// the arc's axis, taken in the turn nearest the guess; exact for a planar arc, for a helix
// the point of the helix at p's angle (off the true nearest by the pitch's second order).
double arc_distance(const Block& b, const Eigen::Vector3d& p, double s_guess) {
  const Eigen::Vector3d n = b.normal.normalized();
  Eigen::Vector3d u = b.start_mm - b.center_mm;
  u -= u.dot(n) * n;
  Eigen::Vector3d w = p - b.center_mm;
  w -= w.dot(n) * n;
  const double total = arc_angle_rad(b);
  if (u.norm() == 0.0 || w.norm() == 0.0 || !(total > 0.0)) return (p - arc_point(b, s_guess)).norm();
  double phi = std::atan2(n.dot(u.cross(w)), u.dot(w));  // (-pi, pi] about n from the start
  const double guess = s_guess * total;
  phi += 2.0 * M_PI * std::round((guess - phi) / (2.0 * M_PI));
  const double s = std::clamp(phi / total, 0.0, 1.0);
  return (p - arc_point(b, s)).norm();
}

}  // namespace

CommandedPath::CommandedPath(const Program& program, const std::vector<PoseSample>& samples,
                             const std::vector<BlockReport>& blocks, const Machine* machine,
                             const std::vector<double>* tool_length_mm)
    : program_(program), samples_(samples), machine_(machine), tool_length_mm_(tool_length_mm) {
  // densify places a block's q samples at s = k / q.
  param_.assign(samples.size(), 0.0);
  int index = 0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const int b = samples[i].block;
    index = b == samples[i - 1].block ? index + 1 : 1;
    const int q =
        b >= 0 && static_cast<std::size_t>(b) < blocks.size() ? std::max(1, blocks[static_cast<std::size_t>(b)].q) : 1;
    param_[i] = static_cast<double>(index) / q;
  }
}

std::pair<std::size_t, std::size_t> CommandedPath::window(std::size_t nearest_last, std::size_t commanded) const {
  const std::size_t hi = std::min(samples_.size() - 1, commanded + kAheadSlack);
  return {std::min(hi, nearest_last > kBackSlack ? nearest_last - kBackSlack : 1), hi};
}

double CommandedPath::distance(const Eigen::Vector3d& p, std::size_t lo, std::size_t hi, std::size_t* nearest) const {
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_k = lo;
  for (std::size_t k = lo; k <= hi; ++k) {
    const double d = detail::segment_nearest(p, samples_[k - 1].pose.tip_mm, samples_[k].pose.tip_mm).second;
    if (d < best) best = d, best_k = k;
  }
  if (nearest) *nearest = best_k;
  return refine(p, best_k, best);
}

double CommandedPath::refine(const Eigen::Vector3d& p, std::size_t k, double polyline) const {
  const int block = samples_[k].block;
  if (block < 0 || static_cast<std::size_t>(block) >= program_.blocks.size()) return polyline;
  const Block& b = program_.blocks[static_cast<std::size_t>(block)];
  const PoseSample& from = samples_[k - 1];
  const PoseSample& to = samples_[k];
  if (b.tool_pose) {
    if (b.kind != MotionKind::Arc) return polyline;  // the tips lie on the line
    const double s0 = from.block == block ? param_[k - 1] : 0.0, s1 = param_[k];
    const double t = detail::segment_nearest(p, from.pose.tip_mm, to.pose.tip_mm).first;
    return arc_distance(b, p, s0 + t * (s1 - s0));
  }
  // An axis block: the axes run linearly, the tip on the machine's curve between the two
  // samples; its distance from p is unimodal over so short a piece (golden section).
  if (!machine_ || from.axes.size() != machine_->axis_count() || to.axes.size() != from.axes.size()) return polyline;
  const double length = tool_length_mm_ && k < tool_length_mm_->size() ? (*tool_length_mm_)[k] : 0.0;
  const auto d = [&](double t) {
    return (forward(*machine_, from.axes + t * (to.axes - from.axes), length).tip_mm - p).norm();
  };
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double lo = 0.0, hi = 1.0;
  double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo), d1 = d(m1), d2 = d(m2);
  for (int it = 0; it < kGoldenIterations; ++it) {
    if (d1 > d2) {
      lo = m1, m1 = m2, d1 = d2, m2 = lo + g * (hi - lo), d2 = d(m2);
    } else {
      hi = m2, m2 = m1, d2 = d1, m1 = hi - g * (hi - lo), d1 = d(m1);
    }
  }
  return std::min({d1, d2, d(0.0), d(1.0)});
}

std::size_t for_each_period(const InterpolatorInput& in, const std::function<void(const PeriodSample&)>& visit) {
  const std::vector<PoseSample>& samples = *in.samples;
  const FeedPlan& plan = *in.feed;
  const Program& program = *in.program;
  const std::size_t n = samples.size();
  if (n < 2 || !in.machine) return 0;
  const Machine& machine = *in.machine;
  const double dt = in.servo.period_s;
  const CommandedPath path(program, samples, *in.blocks, in.machine, in.tool_length_mm);
  PathCursor cursor(plan);
  ServoLoop loop(in.servo, samples[0].axes);
  const auto length_at = [&](std::size_t i) {
    return in.tool_length_mm && i < in.tool_length_mm->size() ? (*in.tool_length_mm)[i] : 0.0;
  };

  std::size_t from = 1;  // the nearest move found last
  PeriodSample out;
  // Fills `out` for the actual axes given: pose, contour error, the move's block.
  const auto finish = [&](std::size_t segment, std::size_t length_sample) {
    const int block = samples[segment].block;
    out.segment = segment;
    out.block = block;
    out.feed = block >= 0 && program.blocks[static_cast<std::size_t>(block)].kind != MotionKind::Rapid;
    const double length = length_at(length_sample);
    out.actual_pose = forward(machine, out.actual, length, in.geometry);
    if (in.commanded_pose) out.commanded_pose = forward(machine, out.commanded, length);
    const auto [lo, hi] = path.window(from, segment);
    out.contour_error_mm = path.distance(out.actual_pose.tip_mm, lo, hi, &out.nearest_segment);
    from = out.nearest_segment;
    visit(out);
  };
  double e_before = 0.0, e_mid = 0.0;  // contour error at the two instants before the last
  std::size_t near_before = 1;         // the nearest move at the first of them
  int peak_block = -2;                 // the commanded block of the instants seen last
  double block_max = 0.0;              // their largest error
  PeriodSample mid;                    // the period sample at the middle instant
  const auto peak = [&](double t_mid) {
    // The error over [t_mid - dT, t_mid + dT] from the two periods' Hermite interpolants.
    // The nearest moves lie between the one nearest at t_mid - dT and the last commanded.
    const double length = length_at(mid.segment);
    const auto [lo, hi] = path.window(near_before, out.segment);
    PeriodSample p = mid;
    const auto error = [&](double x) {  // x in [-1, 1] periods from t_mid
      p.actual = x <= 0.0 ? loop.within_period_before_last(1.0 + x) : loop.within_last_period(x);
      p.actual_pose = forward(machine, p.actual, length, in.geometry);
      return path.distance(p.actual_pose.tip_mm, lo, hi, nullptr);
    };
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    double a = -1.0, b = 1.0, x1 = b - g * (b - a), x2 = a + g * (b - a), e1 = error(x1), e2 = error(x2);
    for (int it = 0; it < kGoldenIterations / 2; ++it) {
      if (e1 < e2) {
        a = x1, x1 = x2, e1 = e2, x2 = a + g * (b - a), e2 = error(x2);
      } else {
        b = x2, x2 = x1, e2 = e1, x1 = b - g * (b - a), e1 = error(x1);
      }
    }
    const double x = e1 >= e2 ? x1 : x2;
    const double e = error(x);
    if (!(e > e_mid)) return;
    p.t_s = t_mid + x * dt;
    p.stamp = -1;
    p.peak = true;
    p.contour_error_mm = e;
    visit(p);
  };
  // The interpolator's command at t. Axis blocks, and tool-pose moves whose rotary axes
  // stand still, run their axes linearly between the densified samples (exact: the axes of
  // an axis block are linear in its parameter; with the rotary axes fixed the linear ones
  // are linear in the tip). A tool-pose move that turns the tool is what a TCP controller
  // interpolates in the part: the tip on the chord, the tool axis on the great circle
  // between the samples (ORIVECT's own path; a cone's within the densification's bound), its
  // axes from the inverse kinematics every period (the branch nearest the last command);
  // under ORIAXES or rotary words the rotary axes run linearly and the linear ones follow
  // the tip.
  AxisValues last_command = samples[0].axes;
  const auto command_at = [&](double t, std::size_t* segment) {
    const PathPosition at = cursor.at(t);
    *segment = at.segment;
    const PoseSample& a = samples[at.segment - 1];
    const PoseSample& b = samples[at.segment];
    const double f = at.fraction;
    AxisValues q = a.axes + f * (b.axes - a.axes);
    const int block = b.block;
    if (f <= 0.0 || f >= 1.0 || block < 0 || !program.blocks[static_cast<std::size_t>(block)].tool_pose)
      return last_command = q;
    bool turns = false;
    for (int k = 0; k < machine.rotary_count(); ++k)
      turns = turns || a.axes[machine.rotary_axis(k)] != b.axes[machine.rotary_axis(k)];
    if (!turns) return last_command = q;
    const Block& blk = program.blocks[static_cast<std::size_t>(block)];
    const double length = length_at(at.segment);
    const Eigen::Vector3d tip = a.pose.tip_mm + f * (b.pose.tip_mm - a.pose.tip_mm);
    if (blk.end_rotary.any() || blk.orientation == OrientationMode::Axes) {
      solve_linear_axes(machine, q, tip, length);
      return last_command = q;
    }
    const IkResult r =
        inverse(machine, ToolPose{tip, great_circle(a.pose.axis, b.pose.axis, f)}, length, &last_command, in.ik);
    return last_command = r.ok() ? r.q() : q;
  };

  // t = 0: at rest on the start.
  std::size_t segment = 1;
  AxisValues command = command_at(0.0, &segment);
  out.t_s = 0.0;
  out.stamp = -1;
  out.commanded = command;
  out.actual = loop.position();
  finish(segment, segment);
  std::size_t next_stamp = 0, periods = 1;
  const double end_s = plan.cycle_time_s;
  const AxisValues& last = samples.back().axes;
  e_mid = out.contour_error_mm;
  mid = out;
  for (long long k = 0;; ++k) {
    const double t_k = static_cast<double>(k) * dt, t_next = static_cast<double>(k + 1) * dt;
    loop.step(command);
    // The densified samples' own instants inside this period.
    while (next_stamp < n && plan.t_s[next_stamp] < t_next) {
      const std::size_t i = next_stamp++;
      out.t_s = plan.t_s[i];
      out.stamp = static_cast<long long>(i);
      out.commanded = samples[i].axes;
      out.actual = loop.within_last_period(std::clamp((plan.t_s[i] - t_k) / dt, 0.0, 1.0));
      finish(std::max<std::size_t>(1, i), i);
    }
    command = command_at(t_next, &segment);
    out.t_s = t_next;
    out.stamp = -1;
    out.commanded = command;
    out.actual = loop.position();
    finish(segment, segment);
    ++periods;
    // The instant t_k a local maximum of the error: its peak lies within a period of it.
    if (mid.block != peak_block) peak_block = mid.block, block_max = 0.0;
    block_max = std::max(block_max, e_mid);
    if (k >= 1 && e_mid > e_before && e_mid > out.contour_error_mm && e_mid > kPeakFloorMm &&
        e_mid >= kPeakShare * block_max)
      peak(t_k);
    e_before = e_mid;
    near_before = mid.nearest_segment;
    e_mid = out.contour_error_mm;
    mid = out;
    if (t_next >= end_s && next_stamp >= n) {
      const bool settled = (loop.position() - last).cwiseAbs().maxCoeff() <= in.settle_tolerance &&
                           loop.max_speed() <= in.settle_tolerance;
      if (settled || t_next >= end_s + in.settle_max_s) break;
    }
  }
  return periods;
}

}  // namespace vcut::kinematics
