#include "vcut/kinematics/densify.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "vcut/kinematics/forward_kinematics.h"
#include "segment.h"

namespace vcut::kinematics {
namespace {
constexpr double kTwoPi = 2.0 * M_PI;
constexpr int kMaxMovesPerBlock = 1 << 20;  // tolerance search cap
}  // namespace

int arc_chord_count(double radius_mm, double angle_rad, double tolerance_mm) {
  if (radius_mm <= tolerance_mm) return std::max(1, static_cast<int>(std::ceil(angle_rad / (M_PI / 2))));
  const double max_angle = 2.0 * std::acos(1.0 - tolerance_mm / radius_mm);
  return std::max(1, static_cast<int>(std::ceil(angle_rad / max_angle - 1e-12)));
}

double arc_angle_rad(const Block& b) {
  const Eigen::Vector3d n = b.normal.normalized();
  Eigen::Vector3d u = b.start_mm - b.center_mm;
  Eigen::Vector3d w = b.end_mm - b.center_mm;
  u -= u.dot(n) * n;
  w -= w.dot(n) * n;
  double angle = std::atan2(u.cross(w).dot(n), u.dot(w));  // (-pi, pi]
  if (angle <= 1e-12) angle += kTwoPi;                     // (0, 2 pi]: start == end is a full turn
  return angle + kTwoPi * std::max(0, b.turns - 1);
}

double arc_radius_mm(const Block& b) {
  const Eigen::Vector3d n = b.normal.normalized();
  return (b.start_mm - b.center_mm - (b.start_mm - b.center_mm).dot(n) * n).norm();
}

double arc_length_mm(const Block& b) {
  return std::hypot(arc_radius_mm(b) * arc_angle_rad(b), (b.end_mm - b.start_mm).dot(b.normal.normalized()));
}

Eigen::Vector3d arc_point(const Block& b, double s) {
  const Eigen::Vector3d n = b.normal.normalized();
  const Eigen::Vector3d u = b.start_mm - b.center_mm;  // in the start plane
  const double rise = (b.end_mm - b.start_mm).dot(n);
  const double r_start = u.norm();
  const Eigen::Vector3d w_end = (b.end_mm - b.center_mm) - ((b.end_mm - b.center_mm).dot(n)) * n;
  const double r_end = w_end.norm();
  const double angle = arc_angle_rad(b) * s;
  // Radius blends linearly when the end radius differs within the reader's tolerance,
  // so the arc ends exactly on the programmed point.
  const double radius = r_start + (r_end - r_start) * s;
  const Eigen::Vector3d dir = Eigen::AngleAxisd(angle, n) * (r_start > 0 ? Eigen::Vector3d(u / r_start) : u);
  return b.center_mm + radius * dir + s * rise * n;
}

Eigen::Vector3d great_circle(const Eigen::Vector3d& u0, const Eigen::Vector3d& u1, double s) {
  const Eigen::Vector3d cross = u0.cross(u1);
  const double sin_angle = cross.norm(), cos_angle = u0.dot(u1);
  const double angle = std::atan2(sin_angle, cos_angle);
  if (angle < 1e-15) return u0;
  Eigen::Vector3d k;
  if (sin_angle > 1e-12) {
    k = cross / sin_angle;
  } else {  // opposite: any perpendicular, the same one every time
    const Eigen::Vector3d helper = std::abs(u0.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    k = u0.cross(helper).normalized();
  }
  return Eigen::AngleAxisd(s * angle, k) * u0;
}

namespace {

// The angle a cone block turns its tool axis about Block::cone_axis: from start to end in the
// block's sense, in (0, 2 pi] (a full turn when they coincide).
double cone_turn_rad(const Block& b) {
  const Eigen::Vector3d k = b.cone_axis.normalized();
  Eigen::Vector3d a = b.start_axis - b.start_axis.dot(k) * k, c = b.end_axis - b.end_axis.dot(k) * k;
  double angle = std::atan2(k.dot(a.cross(c)), a.dot(c));  // counterclockwise about k, (-pi, pi]
  if (b.orientation == OrientationMode::ConeClockwise) angle = -angle;
  if (angle <= 1e-12) angle += kTwoPi;
  return b.orientation == OrientationMode::ConeClockwise ? -angle : angle;
}

Eigen::Vector3d tip_at(const Block& b, double s) {
  return b.kind == MotionKind::Arc ? arc_point(b, s) : Eigen::Vector3d(b.start_mm + s * (b.end_mm - b.start_mm));
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// A block's controller path: the pose (and, where the axes are what is interpolated, the
// machine axes) at fraction s.
class BlockPath {
 public:
  BlockPath(const Block& b, const DensifyMachine& dm, const AxisValues* start_axes, BlockReport& report)
      : b_(b), machine_(dm.machine) {
    const auto length = dm.tool_length_mm.find(b.tool);
    tool_length_mm_ = length == dm.tool_length_mm.end() ? 0.0 : length->second;
    if (!b.tool_pose) {
      // Axis program: every axis linear. X Y Z are the linear axes zeroed so that at
      // all-zero rotary axes the tip is at the programmed point (the operator's setup).
      if (!machine_) {
        report.note = "axis program without a machine: taken as tool poses";
        return;
      }
      mode_ = Mode::AxesLinear;
      q0_ = axis_values(b.start_mm, b.start_rotary, report);
      q1_ = axis_values(b.end_mm, b.end_rotary, report);
    } else if (b.end_rotary.any()) {
      // TCP with rotary words (G43.4, direct A/B/C under TRAORI): the rotary axes go
      // linearly from the start's values to the end's, the tip along its path.
      if (!machine_ || machine_->rotary_count() == 0) {
        report.note = "rotary words under TCP without a five-axis machine: the tool axis stays as it was";
        return;
      }
      mode_ = Mode::RotaryLinear;
      q0_ = tcp_axis_values(b.start_mm, b.start_rotary, start_axes, report);
      q1_ = tcp_axis_values(b.end_mm, b.end_rotary, start_axes, report);
    } else if (b.orientation == OrientationMode::Axes && (b.start_axis - b.end_axis).norm() > 0.0) {
      if (!machine_ || !start_axes || machine_->rotary_count() == 0) {
        report.note = "ORIAXES without a five-axis machine: interpolated as ORIVECT";
        return;
      }
      // ORIAXES under TCP: the rotary axes go linearly from the start's to the end's
      // solution (the one nearest the start), the tip along its path.
      const IkResult end = inverse(*machine_, {b.end_mm, b.end_axis}, tool_length_mm_, start_axes, dm.ik);
      if (!end.ok()) {
        report.unreachable = end.reason;
        return;
      }
      mode_ = Mode::RotaryLinear;
      q0_ = *start_axes;
      q1_ = end.q();
    }
  }

  bool axes_known() const { return mode_ != Mode::Pose; }

  AxisValues axes(double s) const {
    AxisValues q = q0_ + s * (q1_ - q0_);
    if (mode_ == Mode::AxesLinear && b_.kind == MotionKind::Arc) {
      AxisValues lin = q;
      for (int k = 0; k < machine_->rotary_count(); ++k) lin[machine_->rotary_axis(k)] = 0.0;
      solve_linear_axes(*machine_, lin, arc_point(b_, s), tool_length_mm_);
      for (int i = 0; i < machine_->axis_count(); ++i)
        if (machine_->axis(i).kind == AxisKind::Linear) q[i] = lin[i];
    }
    if (mode_ == Mode::RotaryLinear) solve_linear_axes(*machine_, q, tip_at(b_, s), tool_length_mm_);
    return q;
  }

  ToolPose pose(double s) const {
    if (mode_ == Mode::AxesLinear) return forward(*machine_, axes(s), tool_length_mm_);
    ToolPose p;
    p.tip_mm = tip_at(b_, s);
    if (mode_ == Mode::RotaryLinear) {
      p.axis = forward(*machine_, q0_ + s * (q1_ - q0_), tool_length_mm_).axis;
    } else if (b_.orientation == OrientationMode::ConeClockwise ||
               b_.orientation == OrientationMode::ConeCounterClockwise) {
      p.axis = Eigen::AngleAxisd(s * cone_turn_rad(b_), b_.cone_axis.normalized()) * b_.start_axis;
    } else {
      p.axis = great_circle(b_.start_axis, b_.end_axis, s);
    }
    return p;
  }

  double tool_length_mm() const { return tool_length_mm_; }

  // A tool pose's straight move that does not turn the tool: the controller's path is the
  // chord itself.
  bool straight_translation() const {
    return mode_ == Mode::Pose && b_.kind != MotionKind::Arc && b_.orientation != OrientationMode::ConeClockwise &&
           b_.orientation != OrientationMode::ConeCounterClockwise && b_.start_axis == b_.end_axis;
  }

  // Tip path length and orientation change for q = max(ceil(L / lambda), ceil(theta / phi)).
  double length_mm() const {
    if (mode_ == Mode::AxesLinear) {
      double l = 0.0;
      Eigen::Vector3d prev = pose(0.0).tip_mm;
      for (int i = 1; i <= 64; ++i) {
        const Eigen::Vector3d p = pose(i / 64.0).tip_mm;
        l += (p - prev).norm();
        prev = p;
      }
      return l;
    }
    return b_.kind == MotionKind::Arc ? arc_length_mm(b_) : (b_.end_mm - b_.start_mm).norm();
  }

  double turn_rad() const {
    if (mode_ != Mode::Pose) {
      double t = 0.0;
      for (int k = 0; k < machine_->rotary_count(); ++k)
        t = std::max(t, std::abs(q1_[machine_->rotary_axis(k)] - q0_[machine_->rotary_axis(k)]));
      return t;
    }
    if (b_.orientation == OrientationMode::ConeClockwise || b_.orientation == OrientationMode::ConeCounterClockwise) {
      const Eigen::Vector3d k = b_.cone_axis.normalized();
      return std::abs(cone_turn_rad(b_)) * (b_.start_axis - b_.start_axis.dot(k) * k).norm();  // arc on the sphere
    }
    return angle_between(b_.start_axis, b_.end_axis);
  }

  // Axis programs: the largest distance of the tip path from the chord, and where.
  void nonlinear_error(BlockReport& report) const {
    if (mode_ != Mode::AxesLinear) return;
    const Eigen::Vector3d a = pose(0.0).tip_mm, c = pose(1.0).tip_mm;
    auto distance = [&](double s) { return detail::segment_nearest(pose(s).tip_mm, a, c).second; };
    constexpr int kScan = 64;
    int best = 0;
    double best_d = 0.0;
    for (int i = 0; i <= kScan; ++i) {
      const double di = distance(static_cast<double>(i) / kScan);
      if (di > best_d) best_d = di, best = i;
    }
    // Golden-section refinement around the best scan point.
    double lo = std::max(0.0, (best - 1.0) / kScan), hi = std::min(1.0, (best + 1.0) / kScan);
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    for (int it = 0; it < 60; ++it) {
      const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
      if (distance(m1) > distance(m2))
        hi = m2;
      else
        lo = m1;
    }
    const double s = 0.5 * (lo + hi);
    if (distance(s) > best_d)
      best_d = distance(s);
    else if (best_d > 0.0)
      lo = hi = static_cast<double>(best) / kScan;
    report.nonlinear_error_mm = best_d;
    report.nonlinear_at_mm = pose(0.5 * (lo + hi)).tip_mm;
  }

 private:
  enum class Mode { Pose, AxesLinear, RotaryLinear };

  // The rotary axes the words give, by letter, into q.
  void set_rotary(const RotaryWords& words, AxisValues& q, BlockReport& report) const {
    for (int k = 0; k < 3; ++k) {
      if (!words.given[static_cast<size_t>(k)]) continue;
      const char letter = static_cast<char>('A' + k);
      const int i = machine_->axis_index(letter);
      if (i < 0) {
        // A machine without this axis holds it at 0 (a program's "A0" on a three-axis mill).
        if (words.angle_rad[static_cast<size_t>(k)] != 0.0 && report.unreachable.empty())
          report.unreachable = std::string("the machine has no axis ") + letter;
        continue;
      }
      q[i] = words.angle_rad[static_cast<size_t>(k)];
    }
  }

  AxisValues axis_values(const Eigen::Vector3d& xyz, const RotaryWords& words, BlockReport& report) const {
    AxisValues q = machine_->zero();
    if (!solve_linear_axes(*machine_, q, xyz, tool_length_mm_) && report.unreachable.empty())
      report.unreachable = "the machine's linear axes cannot be solved";
    set_rotary(words, q, report);
    if (report.unreachable.empty()) report.unreachable = limit_violation(*machine_, q);
    return q;
  }

  // Axis values putting the tip at `tip` with the rotary axes at the words' values (those not
  // given stay where they were, else at zero).
  AxisValues tcp_axis_values(const Eigen::Vector3d& tip, const RotaryWords& words, const AxisValues* previous,
                             BlockReport& report) const {
    AxisValues q = previous ? *previous : machine_->zero();
    set_rotary(words, q, report);
    if (!solve_linear_axes(*machine_, q, tip, tool_length_mm_) && report.unreachable.empty())
      report.unreachable = "the machine's linear axes cannot be solved";
    if (report.unreachable.empty()) report.unreachable = limit_violation(*machine_, q);
    return q;
  }

  const Block& b_;
  const Machine* machine_ = nullptr;
  double tool_length_mm_ = 0.0;
  Mode mode_ = Mode::Pose;
  AxisValues q0_, q1_;
};

// The largest distance, over the cutting part, between the controller's pose and the move
// through the densified poses k and k + 1 (tip straight, axis on the great circle) at s.
double move_deviation(const BlockPath& path, const ToolPose& a, const ToolPose& b, double s0, double s1,
                      const DensifySettings& settings) {
  double worst = 0.0;
  for (double t : {0.25, 0.5, 0.75}) {
    const ToolPose truth = path.pose(s0 + t * (s1 - s0));
    const Eigen::Vector3d tip = a.tip_mm + t * (b.tip_mm - a.tip_mm);
    const Eigen::Vector3d axis = great_circle(a.axis, b.axis, t);
    const Eigen::Vector3d d = truth.tip_mm - tip, e = truth.axis - axis;
    // Points on the axis deviate by d + h e, largest at h = 0 or h = cutter length; points
    // off the axis add at most radius x the angle between the axes.
    const double along = std::max(d.norm(), (d + settings.cutter_length_mm * e).norm());
    worst = std::max(worst, along + settings.cutter_radius_mm * angle_between(truth.axis, axis));
  }
  return worst;
}

double deviation_for(const BlockPath& path, int q, const DensifySettings& settings) {
  double worst = 0.0;
  ToolPose prev = path.pose(0.0);
  for (int k = 1; k <= q; ++k) {
    const ToolPose next = path.pose(static_cast<double>(k) / q);
    worst = std::max(
        worst, move_deviation(path, prev, next, static_cast<double>(k - 1) / q, static_cast<double>(k) / q, settings));
    prev = next;
  }
  return worst;
}

int arc_moves(const Block& b, double chord_tolerance_mm) {
  return arc_chord_count(arc_radius_mm(b), arc_angle_rad(b), chord_tolerance_mm);
}

int moves_for(const Block& b, const BlockPath& path, const DensifySettings& settings) {
  if (settings.tolerance_mm > 0.0) {
    // One move: the search below would find the chord's deviation at rounding level (1e-13 mm
    // at 1 m from the origin), inside any tolerance above 1e-9 mm. The shortcut matters where
    // a streamed run densifies a raster's blocks several times.
    if (path.straight_translation() && settings.tolerance_mm > 1e-9) return 1;
    const int least = settings.arcs_by_chord && b.kind == MotionKind::Arc && settings.chord_tolerance_mm > 0.0
                          ? std::min(arc_moves(b, settings.chord_tolerance_mm), kMaxMovesPerBlock)
                          : 1;
    if (deviation_for(path, least, settings) <= settings.tolerance_mm) return least;
    int lo = least, hi = std::min(kMaxMovesPerBlock, 2 * least);  // lo fails
    while (hi < kMaxMovesPerBlock && deviation_for(path, hi, settings) > settings.tolerance_mm) {
      lo = hi;
      hi = std::min(kMaxMovesPerBlock, 2 * hi);
    }
    // lo fails; hi meets the tolerance (or is the cap)
    while (hi - lo > 1) {
      const int mid = lo + (hi - lo) / 2;
      (deviation_for(path, mid, settings) <= settings.tolerance_mm ? hi : lo) = mid;
    }
    return hi;
  }
  const double turn = path.turn_rad();
  if (b.kind == MotionKind::Rapid && turn == 0.0 && !path.axes_known()) return 1;
  int q = 1;
  if (b.kind == MotionKind::Arc) q = arc_moves(b, settings.chord_tolerance_mm);
  if (settings.step_mm > 0.0 && (b.kind != MotionKind::Rapid || path.axes_known()))
    q = std::max(q, static_cast<int>(std::ceil(path.length_mm() / settings.step_mm - 1e-12)));
  if (settings.angle_step_rad > 0.0)
    q = std::max(q, static_cast<int>(std::ceil(turn / settings.angle_step_rad - 1e-12)));
  return std::clamp(q, 1, kMaxMovesPerBlock);
}

// The largest distance of the controller's tip path from the chords of the block's q moves
// (at a quarter, half and three quarters of each: the middle for a circle's chord), where the
// tip path can bend: arcs, axis blocks, rotary-linear blocks. Lines of tool-pose blocks keep
// the tip on the chord.
void chord_error(const Block& b, const BlockPath& path, BlockReport& report) {
  if (b.tool_pose && b.kind != MotionKind::Arc) return;
  Eigen::Vector3d prev = path.pose(0.0).tip_mm;
  for (int k = 1; k <= report.q; ++k) {
    const double s0 = static_cast<double>(k - 1) / report.q, s1 = static_cast<double>(k) / report.q;
    const Eigen::Vector3d next = path.pose(s1).tip_mm;
    for (double t : {0.25, 0.5, 0.75}) {
      const Eigen::Vector3d p = path.pose(s0 + t * (s1 - s0)).tip_mm;
      const double e = detail::segment_nearest(p, prev, next).second;
      if (e > report.chord_error_mm) report.chord_error_mm = e, report.chord_error_at_mm = p;
    }
    prev = next;
  }
}

}  // namespace

ToolPose block_pose(const Block& block, double s) {
  BlockReport unused;
  return BlockPath(block, DensifyMachine{}, nullptr, unused).pose(s);
}

bool uses_start_axes(const Block& b) {
  // BlockPath's second and third cases (the first, an axis program, has its own axes).
  return b.tool_pose &&
         (b.end_rotary.any() || (b.orientation == OrientationMode::Axes && (b.start_axis - b.end_axis).norm() > 0.0));
}

Densifier::Densifier(const Program& program, const DensifySettings& settings, const DensifyMachine& machine,
                     bool poses_only)
    : program_(program), settings_(settings), dm_(machine), poses_only_(poses_only) {
  if (program.blocks.empty()) return;
  // The program's start: the first block's start pose, with its axis values.
  BlockReport start_report;
  const Machine* m = dm_.machine;
  const Block first = program.blocks.front();  // BlockPath keeps a reference
  BlockPath path(first, dm_, nullptr, start_report);
  start_.pose = path.pose(0.0);
  if (m) {
    if (path.axes_known()) {
      start_.axes = path.axes(0.0);
    } else if (!poses_only_) {
      const IkResult r = inverse(*m, start_.pose, path.tool_length_mm(), nullptr, dm_.ik);
      start_.axes = r.ok() ? r.q() : m->zero();
      start_.singular = r.status == IkStatus::Singular;
      if (!r.ok()) start_unreachable_ = r.reason;
    }
  }
  last_ = start_;
}

void Densifier::rewind() {
  next_ = 0;
  last_ = start_;
}

void Densifier::next_block(std::vector<PoseSample>& out, BlockReport& report) {
  const std::size_t i = next_++;
  const Block& b = program_.blocks[i];
  const Machine* machine = dm_.machine;
  report = BlockReport{};
  if (i == 0) report.unreachable = start_unreachable_;
  const AxisValues* start_axes = machine ? &last_.axes : nullptr;
  const BlockPath path(b, dm_, start_axes, report);
  path.nonlinear_error(report);
  report.q = moves_for(b, path, settings_);
  if (settings_.tolerance_mm <= 0.0) chord_error(b, path, report);
  for (int k = 1; k <= report.q; ++k) {
    const double s = static_cast<double>(k) / report.q;
    PoseSample sample;
    sample.block = static_cast<int>(i);
    // The end of the block is exactly the programmed pose.
    sample.pose = (k == report.q && b.tool_pose && !b.end_rotary.any()) ? ToolPose{b.end_mm, b.end_axis} : path.pose(s);
    if (machine) {
      if (path.axes_known()) {
        sample.axes = path.axes(s);
      } else if (!poses_only_) {
        const IkResult r = inverse(*machine, sample.pose, path.tool_length_mm(), &last_.axes, dm_.ik);
        if (r.ok()) {
          sample.axes = r.q();
          sample.singular = r.status == IkStatus::Singular;
          report.singular = report.singular || sample.singular;
          report.singular_miss_rad = std::max(report.singular_miss_rad, r.orientation_error_rad);
        } else {
          sample.axes = last_.axes;
          if (report.unreachable.empty()) report.unreachable = r.reason;
        }
      }
    }
    last_ = sample;
    out.push_back(std::move(sample));
  }
}

Densified densify(const Program& program, const DensifySettings& settings, const DensifyMachine& dm) {
  Densified out;
  if (program.blocks.empty()) return out;
  out.samples.reserve(program.blocks.size() + 1);
  out.blocks.resize(program.blocks.size());
  Densifier densifier(program, settings, dm);
  out.samples.push_back(densifier.start());
  for (std::size_t i = 0; i < program.blocks.size(); ++i) densifier.next_block(out.samples, out.blocks[i]);
  return out;
}

std::vector<PoseSample> densify(const Program& program, const DensifySettings& settings) {
  return densify(program, settings, DensifyMachine{}).samples;
}

}  // namespace vcut::kinematics
