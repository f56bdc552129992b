// Feed planning over the densified poses (ARCHITECTURE §5, seed 000 §3.3).
//
// The path is the tip polyline through the samples; its parameter s is the tip arc length
// (mm), or for a block whose tip stands still while the tool turns, the rotary motion in
// degrees (LinuxCNC: with no X Y Z motion the feed applies to the rotary axes, deg/min).
//
// 1. Runs: the consecutive samples of one block. Each gets its limits: the programmed feed
//    (G94 F/60; G93 L/(60/F) as a first guess; rapids none), the centripetal bounds of an arc
//    (v^2/R <= a, v^3/R^2 <= j), and every machine axis through the ratio r_i = |dq_i|/ds of
//    each segment (velocity, acceleration and jerk, see axis_bounds()).
// 2. Spans: runs that continue one another with equal limits, no exact stop and a junction
//    that does not bind (collinear, or a corner whose blend speed exceeds the cruise: a
//    line or a gentle curve cut into many blocks) form one span; each span is one
//    jerk-limited S-curve (7 phases: jerk up, constant acceleration, jerk down, cruise and the
//    mirror) from its entry to its exit speed, with zero acceleration at both ends.
// 3. Junction speeds between spans: exact stop 0; a corner by the blend rule (corner_speed());
//    a look-ahead window (backward pass from an assumed stop at the window's end, forward
//    pass) keeps every junction reachable and stoppable, O(n) overall.
// 4. G93 blocks then get the cruise speed that makes them last 1/F min, where the limits allow.
// 5. Every sample's time is the inverse of the span's s(t) at the sample's arc length,
//    solved within the phase that holds it (cubic in t, safeguarded Newton to rounding).
#include "vcut/kinematics/feed_planner.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <utility>

namespace vcut::kinematics {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kRadToDeg = 180.0 / M_PI;
// A block whose tip moves less than this (1 nm) stands still: far below any densification
// step, far above the rounding of forward kinematics on a 3 m machine (~1e-12 mm).
constexpr double kStillTipMm = 1e-6;
constexpr double kStillRotationDeg = 1e-9;
// Directions closer than this continue one another: the corner rule would allow
// sqrt(a * tol * 8 / 1e-14), beyond any feed.
constexpr double kTangentRad = 1e-7;
// Limits equal to this relative difference let two runs share one S-curve.
constexpr double kSameLimit = 1e-12;
// A path speed below this (mm/s or deg/s) is raised to it, so that degenerate limits (a feed
// of 0, an axis with zero velocity) give long but finite times.
constexpr double kMinSpeed = 1e-9;

using Direction = Eigen::Matrix<double, 5, 1>;  // tip (3 components) or rotary axes (up to 5)

// ---------------------------------------------------------------- S-curve primitives
//
// A change of speed u -> w (dv = |w - u|) with zero acceleration at both ends, jerk j and
// acceleration a: when dv >= a^2/j, jerk phases of a/j reach a, a constant-acceleration phase
// covers the rest: T = dv/a + a/j; otherwise the acceleration peaks at sqrt(dv j) < a after
// sqrt(dv/j): T = 2 sqrt(dv/j). The acceleration profile is symmetric in time, so the speed is
// point-symmetric about the midpoint and the mean speed is (u + w)/2: distance (u + w)/2 T.

double change_time(double dv, double a, double j) {
  if (dv <= 0.0) return 0.0;
  if (dv >= a * a / j) return dv / a + a / j;
  return 2.0 * std::sqrt(dv / j);
}

double change_time_derivative(double dv, double a, double j) {
  if (dv >= a * a / j) return 1.0 / a;
  return dv > 0.0 ? 1.0 / std::sqrt(dv * j) : kInf;
}

double change_distance(double u, double w, double a, double j) {
  return 0.5 * (u + w) * change_time(std::abs(w - u), a, j);
}

// Root of an increasing f on [lo, hi] with f(lo) <= 0 <= f(hi); f returns (value, slope).
// Newton steps kept inside the bracket, bisection when one leaves it (rtsafe, Numerical
// Recipes §9.4): quadratic near the root, never worse than bisection.
template <class F>
double solve_increasing(const F& f, double lo, double hi, double x, double xtol) {
  for (int it = 0; it < 200; ++it) {
    const std::pair<double, double> fx = f(x);
    if (fx.first == 0.0) return x;
    if (fx.first < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    double next = x - fx.first / fx.second;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - x) <= xtol || hi - lo <= xtol;
    x = next;
    if (done) break;
  }
  return x;
}

// The highest speed w <= cap reachable from u within distance L (by the symmetry of the
// change, also the highest speed from which u is reached by braking within L).
double reach(double u, double L, double a, double j, double cap) {
  if (cap <= u) return cap;
  if (change_distance(u, cap, a, j) <= L) return cap;
  // Full acceleration (dv >= a^2/j): (2u + dv)(dv/a + a/j) = 2L, a quadratic in dv,
  // dv^2/a + b dv + c = 0; the root in the cancellation-free form -2c / (b + sqrt(b^2 - 4c/a)).
  const double b = 2.0 * u / a + a / j;
  const double c = 2.0 * u * a / j - 2.0 * L;
  double dv = -2.0 * c / (b + std::sqrt(b * b - 4.0 * c / a));
  if (!(dv >= a * a / j)) {
    // Acceleration not reached: (2u + x^2) x = L sqrt(j) with x = sqrt(dv), the cubic
    // x^3 + p x - Q = 0 (p = 2u >= 0): one real root, Cardano's x = w - p/(3w) with
    // w = cbrt(Q/2 + sqrt(Q^2/4 + p^3/27)), then Newton steps against its cancellation.
    const double p = 2.0 * u, q = L * std::sqrt(j);
    const double w = std::cbrt(0.5 * q + std::sqrt(0.25 * q * q + p * p * p / 27.0));
    double x = w > 0.0 ? w - p / (3.0 * w) : 0.0;
    for (int it = 0; it < 3; ++it) {
      const double d = 3.0 * x * x + p;
      if (d <= 0.0) break;
      x -= (x * x * x + p * x - q) / d;
    }
    dv = x * x;
  }
  return std::min(cap, u + std::max(0.0, dv));
}

struct Phase {
  double t0, s0, v0, a0, jerk, duration, length;
  double speed(double tau) const { return v0 + tau * (a0 + 0.5 * jerk * tau); }
  double distance(double tau) const { return tau * (v0 + tau * (0.5 * a0 + jerk * tau / 6.0)); }
};

// One span's S-curve: at most 7 phases of constant jerk.
struct Profile {
  std::array<Phase, 7> phase{};
  int count = 0;
  double duration = 0.0;
  double peak = 0.0;
  // running state while building
  double t = 0.0, s = 0.0, v = 0.0, a = 0.0;

  void append(double jerk, double T) {
    if (!(T > 0.0)) return;
    Phase& ph = phase[static_cast<size_t>(count++)];
    ph = {t, s, v, a, jerk, T, 0.0};
    ph.length = ph.distance(T);
    t += T;
    s += ph.length;
    v = ph.speed(T);
    a += jerk * T;
  }

  void append_change(double u, double w, double amax, double j) {
    const double dv = std::abs(w - u), sign = w > u ? 1.0 : -1.0;
    v = u;
    a = 0.0;
    if (dv > 0.0) {
      if (!std::isfinite(j)) {  // no jerk limit: a trapezoid's constant-acceleration phase
        a = sign * amax;
        append(0.0, dv / amax);
      } else if (dv >= amax * amax / j) {
        append(sign * j, amax / j);
        a = sign * amax;  // exact, against the rounding of j * (amax / j)
        append(0.0, dv / amax - amax / j);
        append(-sign * j, amax / j);
      } else {
        append(sign * j, std::sqrt(dv / j));
        append(-sign * j, std::sqrt(dv / j));
      }
    }
    v = w;
    a = 0.0;
  }
};

// The S-curve over distance L from v_in to v_out cruising at most at v_cruise. The caller
// guarantees that v_in and v_out are connected within L (the look-ahead does).
Profile make_profile(double L, double v_in, double v_out, double v_cruise, double a, double j) {
  Profile p;
  const double lo = std::max(v_in, v_out);
  const auto distance = [&](double vp) { return change_distance(v_in, vp, a, j) + change_distance(vp, v_out, a, j); };
  double vp = std::max(lo, v_cruise);
  if (!std::isfinite(vp) || distance(vp) > L) {
    // Cruise not reached: the peak solves distance(vp) = L, increasing in vp. A peak above
    // lo + sqrt(2 a L) would need more than L for its speed change alone (dv^2/(2a) > L).
    const double hi = std::min(vp, lo + std::sqrt(2.0 * a * L));
    if (distance(lo) >= L) {
      vp = lo;
    } else if (distance(hi) <= L) {
      vp = hi;
    } else {
      const auto f = [&](double x) {
        const double d1 = x - v_in, d2 = x - v_out;
        const double slope = 0.5 * (change_time(d1, a, j) + change_time(d2, a, j)) +
                             0.5 * (v_in + x) * change_time_derivative(d1, a, j) +
                             0.5 * (x + v_out) * change_time_derivative(d2, a, j);
        return std::make_pair(distance(x) - L, slope);
      };
      vp = solve_increasing(f, lo, hi, hi, 4.0 * kEps * hi);
    }
  }
  const double cruise = std::max(0.0, L - distance(vp));
  p.peak = vp;
  p.append_change(v_in, vp, a, j);
  if (cruise > 0.0 && vp > 0.0) p.append(0.0, cruise / vp);
  p.append_change(vp, v_out, a, j);
  p.duration = p.t;
  return p;
}

// Time into a phase at which it has covered ds: s(tau) is a cubic, increasing (speed >= 0).
double time_in_phase(const Phase& ph, double ds) {
  if (ds <= 0.0) return 0.0;
  if (ds >= ph.length) return ph.duration;
  if (ph.jerk == 0.0 && ph.a0 == 0.0) return std::min(ph.duration, ds / ph.v0);
  const auto f = [&](double tau) { return std::make_pair(ph.distance(tau) - ds, ph.speed(tau)); };
  return solve_increasing(f, 0.0, ph.duration, ph.duration * ds / ph.length, 4.0 * kEps * ph.duration);
}

// ---------------------------------------------------------------- corners
//
// The corner rule. At a corner where the path turns by theta, the controller blends with an
// arc tangent to both segments. Its centre lies on the bisector at R / cos(theta/2) from the
// corner, so the arc passes the corner at R (1/cos(theta/2) - 1); the blend tolerance tol
// (G64 P) bounds that: R = tol cos(theta/2) / (1 - cos(theta/2)). (With the interior angle
// alpha = pi - theta this is the familiar R = tol sin(alpha/2) / (1 - sin(alpha/2)), grbl's
// junction deviation.) The arc's tangent points lie R tan(theta/2) from the corner and must
// fit in half of each adjacent segment. Driving the arc at the path acceleration, v^2/R <= a:
//   v_corner = sqrt(a R).
// The time is still counted along the programmed polyline (the blend is a speed rule only);
// the jump of the centripetal acceleration at the arc's ends is not jerk-limited.
double corner_speed(double theta, double tol_mm, double a, double shorter_segment) {
  if (theta <= kTangentRad) return kInf;
  if (tol_mm <= 0.0) return 0.0;
  const double c = std::cos(0.5 * theta);
  const double one_minus_c = 2.0 * std::pow(std::sin(0.25 * theta), 2);  // 1 - cos(theta/2)
  double radius = tol_mm * c / one_minus_c;
  const double t = std::tan(0.5 * theta);
  if (t > 0.0 && std::isfinite(t)) radius = std::min(radius, 0.5 * shorter_segment / t);
  return std::sqrt(a * std::max(0.0, radius));
}

// Angle between two directions (0 for a zero vector's lack of one: pi). Kahan's
// 2 atan2(|u - v|, |u + v|) keeps small angles exact.
double angle_between(const Direction& u, const Direction& v) {
  if (u.squaredNorm() == 0.0 || v.squaredNorm() == 0.0) return M_PI;
  return 2.0 * std::atan2((u - v).norm(), (u + v).norm());
}

// ---------------------------------------------------------------- runs and spans

enum class Unit { None, Tip, Rotation };

struct Run {
  int block = -1;
  size_t first = 0, last = 0;  // sample indices of its segments' ends
  Unit unit = Unit::None;
  double length = 0.0;
  double v = 0.0, a = 0.0, j = 0.0;  // cruise, path acceleration and jerk
  double v_cap = kInf;               // arcs and axes: what G93 may not exceed
  double v_axis = kInf;              // the axes alone
  double v_prog = kInf;              // programmed feed (G93: L / T)
  bool rapid = false;
  double g93_time_s = 0.0;  // > 0: inverse time block of this duration
  bool axis_limited = false;
  bool exact_stop = false;
  double tolerance_mm = 0.0;
  Direction dir_in = Direction::Zero(), dir_out = Direction::Zero();
  double seg_in = 0.0, seg_out = 0.0;  // lengths of its first and last moving segments
};

struct Span {
  size_t first_run = 0, last_run = 0;
  size_t moving_run = 0;  // the run that set its limits (not a still block before it)
  Unit unit = Unit::None;
  double length = 0.0;
  double v = 0.0, a = 0.0, j = 0.0;
  double v_cap = kInf;
  double g93_time_s = 0.0;
  bool end_stop = false;
  double tolerance_mm = 0.0;  // of its last block: the corner at its end
  Direction dir_in = Direction::Zero(), dir_out = Direction::Zero();
  double seg_in = 0.0, seg_out = 0.0;
};

bool same_limit(double x, double y) {
  if (x == y) return true;
  return std::abs(x - y) <= kSameLimit * std::max(std::abs(x), std::abs(y));
}

// Axis limits through the kinematics. Along a segment the axes move linearly with s, so
// dq_i/dt = r_i v with r_i = |dq_i| / ds exactly; we also take d2q_i/dt2 = r_i a and
// d3q_i/dt3 = r_i j, which neglects the terms of the curvature of q(s) (d2q/ds2 v^2 and its
// kin: the change of r_i from one segment to the next). Exact for straight moves of linear
// axes; elsewhere an approximation that the densification step controls.
struct AxisBounds {
  double v = kInf, a = kInf, j = kInf;
};

void axis_bounds(const Machine& machine, const AxisValues& q0, const AxisValues& q1, double ds, AxisBounds& out) {
  if (!(ds > 0.0)) return;
  const int n = std::min(machine.axis_count(), static_cast<int>(std::min(q0.size(), q1.size())));
  for (int k = 0; k < n; ++k) {
    const double dq = std::abs(q1[k] - q0[k]);
    if (dq == 0.0) continue;
    const double ratio = dq / ds;
    const AxisSpec& axis = machine.axis(k);
    if (axis.max_velocity_per_s > 0.0) out.v = std::min(out.v, axis.max_velocity_per_s / ratio);
    if (axis.max_acceleration_per_s2 > 0.0) out.a = std::min(out.a, axis.max_acceleration_per_s2 / ratio);
    if (axis.max_jerk_per_s3 > 0.0) out.j = std::min(out.j, axis.max_jerk_per_s3 / ratio);
  }
}

// The rotary motion of a segment in degrees: the rotary axes' displacement (norm over the
// axes, LinuxCNC's ABC length) when the machine axes are known, else the tool axis's turn.
double rotation_deg(const std::vector<PoseSample>& samples, const std::vector<PoseSample>* axes, const Machine* machine,
                    size_t i, Direction* direction) {
  if (axes && machine) {
    Direction d = Direction::Zero();
    const AxisValues& q0 = (*axes)[i - 1].axes;
    const AxisValues& q1 = (*axes)[i].axes;
    for (int k = 0; k < std::min(machine->axis_count(), 5); ++k)
      if (machine->axis(k).kind == AxisKind::Rotary && k < q0.size() && k < q1.size())
        d[k] = (q1[k] - q0[k]) * kRadToDeg;
    const double n = d.norm();
    if (n > 0.0) {
      if (direction) *direction = d / n;
      return n;
    }
  }
  const Eigen::Vector3d& u0 = samples[i - 1].pose.axis;
  const Eigen::Vector3d& u1 = samples[i].pose.axis;
  const Eigen::Vector3d cross = u0.cross(u1);
  const double angle = std::atan2(cross.norm(), u0.dot(u1)) * kRadToDeg;
  if (direction) {
    *direction = Direction::Zero();
    if (cross.norm() > 0.0) direction->head<3>() = cross.normalized();
  }
  return angle;
}

// Unit tangent of an arc block at its start or end (the derivative of arc_point in s).
Direction arc_tangent(const Block& b, bool at_end) {
  const Eigen::Vector3d n = b.normal.normalized();
  const Eigen::Vector3d p = at_end ? b.end_mm : b.start_mm;
  Eigen::Vector3d radial = p - b.center_mm;
  radial -= radial.dot(n) * n;
  const double angle = arc_angle_rad(b);
  const double rise_per_rad = angle > 0.0 ? (b.end_mm - b.start_mm).dot(n) / angle : 0.0;
  const Eigen::Vector3d t = n.cross(radial) + rise_per_rad * n;
  Direction d = Direction::Zero();
  if (t.norm() > 0.0) d.head<3>() = t.normalized();
  return d;
}

// Radius of curvature of an arc block (a helix of radius r rising c per radian curves with
// radius (r^2 + c^2) / r); 0 when it has none.
double arc_curvature_radius(const Block& b) {
  const Eigen::Vector3d n = b.normal.normalized();
  Eigen::Vector3d radial = b.start_mm - b.center_mm;
  radial -= radial.dot(n) * n;
  const double r = radial.norm();
  if (r <= 0.0) return 0.0;
  const double angle = arc_angle_rad(b);
  const double c = angle > 0.0 ? (b.end_mm - b.start_mm).dot(n) / angle : 0.0;
  return (r * r + c * c) / r;
}

// An axis block's tip speed per unit of F: the tip's length over the length F applies to
// (FeedSettings::axis_feed); 1 for tool-pose blocks, for rotation-only runs (F in deg/min
// already) and for the Tip reading.
double axis_feed_scale(const Block& b, const std::vector<PoseSample>* axes, const Machine* machine,
                       const FeedSettings& settings, size_t first, size_t last, const Run& run) {
  if (b.tool_pose || run.unit != Unit::Tip || settings.axis_feed == FeedInterpretation::Tip || !axes || !machine)
    return 1.0;
  // The programmed X Y Z path: the line, or the arc (helix) of the words.
  const double xyz = b.kind == MotionKind::Arc ? arc_length_mm(b) : (b.end_mm - b.start_mm).norm();
  // The rotary axes' motion (deg) over the block.
  const AxisValues& q0 = (*axes)[first - 1].axes;
  const AxisValues& q1 = (*axes)[last].axes;
  double rotary2 = 0.0;
  for (int k = 0; k < machine->axis_count() && k < q0.size() && k < q1.size(); ++k)
    if (machine->axis(k).kind == AxisKind::Rotary) rotary2 += std::pow((q1[k] - q0[k]) * kRadToDeg, 2);
  const double programmed = settings.axis_feed == FeedInterpretation::Combined ? std::sqrt(xyz * xyz + rotary2)
                            : xyz > kStillTipMm                                ? xyz
                                                                               : std::sqrt(rotary2);
  return programmed > 0.0 ? run.length / programmed : 1.0;
}

Run make_run(const Program& program, const std::vector<PoseSample>& samples, const std::vector<PoseSample>* axes,
             const Machine* machine, const FeedSettings& settings, int block, size_t first, size_t last,
             std::vector<double>& seg_len) {
  Run run;
  run.block = block;
  run.first = first;
  run.last = last;
  const Block& b = program.blocks[static_cast<size_t>(block)];
  double tip = 0.0, rotation = 0.0;
  for (size_t i = first; i <= last; ++i) tip += (samples[i].pose.tip_mm - samples[i - 1].pose.tip_mm).norm();
  if (tip <= kStillTipMm)
    for (size_t i = first; i <= last; ++i) rotation += rotation_deg(samples, axes, machine, i, nullptr);
  run.unit = tip > kStillTipMm ? Unit::Tip : (rotation > kStillRotationDeg ? Unit::Rotation : Unit::None);

  AxisBounds bounds;
  bool have_in = false;
  for (size_t i = first; i <= last; ++i) {
    Direction d = Direction::Zero();
    double ds = 0.0;
    if (run.unit == Unit::Tip) {
      const Eigen::Vector3d step = samples[i].pose.tip_mm - samples[i - 1].pose.tip_mm;
      ds = step.norm();
      if (ds > 0.0) d.head<3>() = step / ds;
    } else if (run.unit == Unit::Rotation) {
      ds = rotation_deg(samples, axes, machine, i, &d);
    }
    seg_len[i] = ds;
    run.length += ds;
    if (ds > 0.0) {
      if (!have_in) {
        run.dir_in = d;
        run.seg_in = ds;
        have_in = true;
      }
      run.dir_out = d;
      run.seg_out = ds;
      if (axes && machine) axis_bounds(*machine, (*axes)[i - 1].axes, (*axes)[i].axes, ds, bounds);
    }
  }
  const bool arc = b.kind == MotionKind::Arc && b.tool_pose && run.unit == Unit::Tip;
  if (arc) {  // the chords' directions miss the tangents by half a chord angle
    run.dir_in = arc_tangent(b, false);
    run.dir_out = arc_tangent(b, true);
  }

  run.a = std::min(settings.path_acceleration_mm_per_s2, bounds.a);
  run.j = std::min(settings.path_jerk_mm_per_s3, bounds.j);
  run.rapid = b.kind == MotionKind::Rapid;
  run.v_axis = bounds.v;
  run.v_cap = bounds.v;
  if (arc) {
    const double radius = arc_curvature_radius(b);
    if (radius > 0.0) run.v_cap = std::min({run.v_cap, std::sqrt(run.a * radius), std::cbrt(run.j * radius * radius)});
  }
  const double f = b.feed_mm_per_min;
  if (!run.rapid && f > 0.0) {
    if (b.feed_mode == FeedMode::InverseTime) {
      run.g93_time_s = 60.0 / f;
      run.v_prog = run.length / run.g93_time_s;
    } else {
      run.v_prog = f / 60.0 * axis_feed_scale(b, axes, machine, settings, first, last, run);
    }
  }
  // Rapids (and a feed move without a feed) run at the axes' speed, or the settings' rapid.
  if (!std::isfinite(run.v_prog) && !std::isfinite(run.v_axis)) run.v_prog = settings.rapid_mm_per_min / 60.0;
  run.v = std::max(kMinSpeed, std::min(run.v_prog, run.v_cap));
  // The axes set the speed where they bind before the feed and the arc's own bounds. G93
  // blocks are decided once their cruise speed is known (plan_feed step 4).
  run.axis_limited =
      !run.rapid && run.g93_time_s == 0.0 && f > 0.0 && run.v_axis < run.v_prog && run.v_axis <= run.v_cap;
  run.exact_stop = b.exact_stop;
  run.tolerance_mm = b.blend_tolerance_mm >= 0.0 ? b.blend_tolerance_mm : settings.default_blend_tolerance_mm;
  return run;
}

Span span_of(const Run& r, size_t index) {
  Span s;
  s.first_run = s.last_run = s.moving_run = index;
  s.unit = r.unit;
  s.length = r.length;
  s.v = r.v;
  s.a = r.a;
  s.j = r.j;
  s.v_cap = r.v_cap;
  s.g93_time_s = r.g93_time_s;
  s.end_stop = r.exact_stop;
  s.tolerance_mm = r.tolerance_mm;
  s.dir_in = r.dir_in;
  s.dir_out = r.dir_out;
  s.seg_in = r.seg_in;
  s.seg_out = r.seg_out;
  return s;
}

// Whether run r continues span s as one S-curve: no stop between them, the same limits,
// and a junction that does not bind: tangent, or (tip paths) a corner whose blend speed is
// at least the cruise speed, so that the S-curve passes it at whatever speed it has there.
// Curves cut into short blocks (CAM output) then accelerate across their blocks instead of
// with zero acceleration at every junction.
bool continues(const Span& s, const Run& r) {
  if (s.end_stop || s.unit != r.unit || s.g93_time_s != 0.0 || r.g93_time_s != 0.0) return false;
  if (!same_limit(s.v, r.v) || !same_limit(s.a, r.a) || !same_limit(s.j, r.j)) return false;
  const double theta = angle_between(s.dir_out, r.dir_in);
  if (theta <= kTangentRad) return true;
  return s.unit == Unit::Tip &&
         corner_speed(theta, s.tolerance_mm, std::min(s.a, r.a), std::min(s.seg_out, r.seg_in)) >= std::max(s.v, r.v);
}

// Adds run k (in program order) to the spans: a new span, or the last one extended.
template <class Spans>
void add_to_spans(Spans& spans, const Run& r, size_t k) {
  if (spans.empty()) {
    spans.push_back(span_of(r, k));
    return;
  }
  Span& s = spans.back();
  if (r.unit == Unit::None) {  // a block that does not move: part of whatever it sits in
    s.last_run = k;
    s.end_stop = s.end_stop || r.exact_stop;
  } else if (s.unit == Unit::None) {  // only still blocks so far: the moving one takes over
    const size_t first = s.first_run;
    s = span_of(r, k);
    s.first_run = first;
  } else if (continues(s, r)) {
    s.last_run = k;
    s.length += r.length;
    s.end_stop = r.exact_stop;
    s.tolerance_mm = r.tolerance_mm;
    s.dir_out = r.dir_out;
    s.seg_out = r.seg_out;
  } else {
    spans.push_back(span_of(r, k));
  }
}

// What the later steps need of a run once its span has taken the rest (a whole Run is ~200
// bytes a block; this is 40).
struct RunTiming {
  int block = -1;
  size_t first = 0, last = 0;
  double v_axis = kInf, v_cap = kInf;
  bool axis_limited = false;
};

// Speed allowed at the junction between spans p and n.
double junction_limit(const Span& p, const Span& n) {
  if (p.end_stop || p.unit != n.unit || p.unit == Unit::None) return 0.0;
  const double v = std::min(p.v, n.v);
  const double theta = angle_between(p.dir_out, n.dir_in);
  // Rotations only continue without a stop when they turn on about the same axes.
  if (p.unit == Unit::Rotation) return theta <= kTangentRad ? v : 0.0;
  return std::min(v, corner_speed(theta, p.tolerance_mm, std::min(p.a, n.a), std::min(p.seg_out, n.seg_in)));
}

// Step 4 for one span between junction speeds v_in and v_out: a G93 span gets the cruise
// speed that makes it last 1/F min. The duration falls as the cruise speed rises (until the
// peak saturates); bisection on [L/T, the cap]. Returns whether the moving run (its axis
// bounds given) is then axis-limited, where that changes: when the time cannot be met and the
// span goes as fast as the limits allow.
std::optional<bool> solve_inverse_time(Span& s, double v_in, double v_out, double v_axis, double v_cap) {
  if (s.g93_time_s <= 0.0) return std::nullopt;
  const auto duration = [&](double v) { return make_profile(s.length, v_in, v_out, v, s.a, s.j).duration; };
  double hi = std::min(s.v_cap, std::max(v_in, v_out) + std::sqrt(2.0 * s.a * s.length));
  hi = std::max(hi, s.v);
  if (duration(hi) >= s.g93_time_s) {
    s.v = hi;  // not achievable: as fast as the limits allow
    return std::isfinite(v_axis) && v_axis <= v_cap && hi >= v_axis;
  }
  double lo = s.v;
  for (int it = 0; it < 200 && hi - lo > 4.0 * kEps * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (duration(mid) > s.g93_time_s ? lo : hi) = mid;
  }
  s.v = hi;
  return std::nullopt;
}

// Step 5 along one span: the time into its profile and the speed there at each arc length, in
// ascending order (the phase found last is where the search goes on).
class SpanClock {
 public:
  SpanClock(const Span& s, double v_in, double v_out)
      : profile_(make_profile(s.length, v_in, v_out, s.v, s.a, s.j)), length_(s.length), v_out_(v_out) {}
  // At `arc` (mm or deg from the span's start): {t, v}.
  std::pair<double, double> at(double arc) {
    const Profile& p = profile_;
    // The span's end is known exactly; solving for it would not be: near a stop s(t) is
    // flat (j t^3/6), so the rounding of the arc length (1e-15 mm) would move it ~1e-6 s.
    if (!(p.count > 0 && arc < length_)) return {p.duration, v_out_};
    while (phase_ + 1 < p.count &&
           arc > p.phase[static_cast<size_t>(phase_)].s0 + p.phase[static_cast<size_t>(phase_)].length)
      ++phase_;
    const Phase& phase = p.phase[static_cast<size_t>(phase_)];
    const double tau = time_in_phase(phase, arc - phase.s0);
    return {phase.t0 + tau, std::max(0.0, phase.speed(tau))};
  }
  const Profile& profile() const { return profile_; }

 private:
  Profile profile_;
  double length_, v_out_;
  int phase_ = 0;
};

}  // namespace

FeedPlan plan_feed(const Program& program, const std::vector<PoseSample>& samples, const Machine* machine,
                   const FeedSettings& settings) {
  // The samples' machine axis values count where the machine is known.
  const std::vector<PoseSample>* const axes = machine != nullptr ? &samples : nullptr;
  FeedPlan plan;
  const size_t n = samples.size();
  plan.t_s.assign(n, 0.0);
  plan.speed_mm_per_s.assign(n, 0.0);
  plan.block_time_s.assign(program.blocks.size(), 0.0);
  if (n < 2) return plan;

  // 1. Runs of consecutive samples of one block, and 2. spans, one S-curve each, built as
  //    the runs are made.
  std::vector<double> seg_len(n, 0.0);
  std::vector<RunTiming> runs;
  std::vector<Span> spans;
  bool skipped = false;  // samples naming no block of the program (a caller's error)
  for (size_t i = 1; i < n;) {
    const int block = samples[i].block;
    size_t last = i;
    while (last + 1 < n && samples[last + 1].block == block) ++last;
    assert(block >= 0 && static_cast<size_t>(block) < program.blocks.size());
    if (block >= 0 && static_cast<size_t>(block) < program.blocks.size()) {
      const Run r = make_run(program, samples, axes, machine, settings, block, i, last, seg_len);
      add_to_spans(spans, r, runs.size());
      runs.push_back({r.block, r.first, r.last, r.v_axis, r.v_cap, r.axis_limited});
    } else {
      skipped = true;
    }
    i = last + 1;
  }
  if (runs.empty()) return plan;
  const size_t K = spans.size();

  // 3. Junction speeds: limits, then the look-ahead. The window covers W spans (each at
  //    least one block) and is advanced W at a time: the backward pass of a window starts
  //    2W spans ahead from an assumed stop (or at the program end with its end speed), so
  //    every junction sees between W and 2W spans ahead and the work is O(K). A farther
  //    horizon only relaxes the assumed stop, so speeds chosen in one window stay reachable
  //    and stoppable under the next.
  std::vector<double> limit(K + 1, 0.0);
  limit[0] = std::min(settings.start_speed_mm_per_s, spans.front().v);
  limit[K] = std::min(settings.end_speed_mm_per_s, spans.back().v);
  for (size_t k = 1; k < K; ++k) limit[k] = junction_limit(spans[k - 1], spans[k]);
  for (size_t k = 0; k <= K; ++k) limit[k] = std::max(0.0, limit[k]);

  const size_t W = static_cast<size_t>(std::max(1, settings.lookahead_blocks));
  std::vector<double> backward(K + 1, 0.0), speed(K + 1, 0.0);
  speed[0] = limit[0];
  for (size_t c = 0; c < K; c += W) {
    const size_t e = std::min(K, c + 2 * W);
    backward[e] = e == K ? limit[K] : 0.0;
    for (size_t k = e; k-- > c;) {
      const Span& s = spans[k];
      backward[k] = reach(backward[k + 1], s.length, s.a, s.j, limit[k]);
    }
    speed[c] = std::min(speed[c], backward[c]);
    const size_t f = std::min(K, c + W);
    for (size_t k = c; k < f; ++k) {
      const Span& s = spans[k];
      speed[k + 1] = reach(speed[k], s.length, s.a, s.j, backward[k + 1]);
    }
  }

  // 4. G93 (solve_inverse_time).
  for (size_t k = 0; k < K; ++k) {
    Span& s = spans[k];
    RunTiming& r = runs[s.moving_run];
    if (const auto limited = solve_inverse_time(s, speed[k], speed[k + 1], r.v_axis, r.v_cap))
      r.axis_limited = *limited;
  }

  // 5. Time stamps: the inverse of each span's s(t) at its samples' arc lengths.
  double t_span = 0.0, s_span = 0.0;
  if (settings.timing) {
    plan.path_s.assign(n, 0.0);
    plan.spans.reserve(K);
  }
  plan.speed_mm_per_s[0] = spans.front().unit == Unit::Tip ? speed[0] : 0.0;
  for (size_t k = 0; k < K; ++k) {
    const Span& s = spans[k];
    SpanClock clock(s, speed[k], speed[k + 1]);
    const Profile& p = clock.profile();
    const size_t first = runs[s.first_run].first, last = runs[s.last_run].last;
    double arc = 0.0;
    for (size_t i = first; i <= last; ++i) {
      arc += seg_len[i];
      const auto [t, v] = clock.at(arc);
      plan.t_s[i] = t_span + t;
      plan.speed_mm_per_s[i] = s.unit == Unit::Tip ? v : 0.0;
      if (settings.timing) plan.path_s[i] = s_span + arc;
    }
    const double t0_s = t_span, s0 = s_span;
    t_span += p.duration;
    s_span += arc;
    if (!settings.timing) continue;
    SpanTiming timing;
    timing.first_sample = first;
    timing.last_sample = last;
    timing.t0_s = t0_s;
    timing.duration_s = p.duration;
    for (int q = 0; q < p.count; ++q) {
      const Phase& ph = p.phase[static_cast<size_t>(q)];
      timing.phases.push_back({t0_s + ph.t0, s0 + ph.s0, ph.v0, ph.a0, ph.jerk, ph.duration});
    }
    plan.spans.push_back(std::move(timing));
  }
  if (skipped)  // they take no time
    for (size_t i = 1; i < n; ++i)
      if (samples[i].block < 0 || static_cast<size_t>(samples[i].block) >= program.blocks.size())
        plan.t_s[i] = plan.t_s[i - 1];

  for (const RunTiming& r : runs) {
    plan.block_time_s[static_cast<size_t>(r.block)] += plan.t_s[r.last] - plan.t_s[r.first - 1];
    if (r.axis_limited)
      for (size_t i = r.first; i <= r.last; ++i) plan.axis_limited_samples.push_back(static_cast<int>(i));
  }
  plan.cycle_time_s = plan.t_s.back();
  return plan;
}

// plan_feed's steps over the program as it is densified, twice: one densifier (ahead) makes
// the runs and spans and lets the look-ahead windows close; a second (behind) densifies the
// blocks of each span again once its junction speeds are final and times their samples.
// What is held is the spans between the two, at most about 3 W, whatever the program's
// length. The arithmetic is plan_feed's, in the same order: the same bytes.
double stream_feed(const Program& program, const DensifySettings& densify_settings, const DensifyMachine& dm,
                   const FeedSettings& settings, const FeedStreamVisitor& visit) {
  if (program.blocks.empty()) return 0.0;
  const Machine* const machine = dm.machine;
  Densifier ahead(program, densify_settings, dm), behind(program, densify_settings, dm);
  const size_t W = static_cast<size_t>(std::max(1, settings.lookahead_blocks));

  // Spans k = base, base + 1, ... with the limit (limit[k]) and speed (speed[k]) at their
  // start; for the span whose run set its limits, that run's axis bounds (G93, step 4).
  struct MovingRun {
    double v_axis = kInf, v_cap = kInf;
  };
  std::deque<Span> spans;
  std::deque<MovingRun> moving;
  std::deque<double> limit, speed;
  size_t base = 0;         // the first span still held
  size_t limits = 0;       // limit[0 .. limits - 1] are known
  size_t next_window = 0;  // the next look-ahead window's first span
  size_t K = 0;            // the number of spans, once the program has ended
  bool ended = false;
  const auto at = [&](std::deque<double>& d, size_t k) -> double& {
    const size_t i = k - base;
    if (i >= d.size()) d.resize(i + 1, 0.0);
    return d[i];
  };
  const auto span = [&](size_t k) -> Span& { return spans[k - base]; };
  const auto created = [&] { return base + spans.size(); };

  std::vector<PoseSample> window;
  std::vector<double> seg_len, backward;
  const auto densify_block = [&](Densifier& d, BlockReport& report) {
    window.clear();
    window.push_back(d.last());
    d.next_block(window, report);
    seg_len.assign(window.size(), 0.0);
    const int block = static_cast<int>(d.next_index() - 1);
    return make_run(program, window, machine != nullptr ? &window : nullptr, machine, settings, block, 1,
                    window.size() - 1, seg_len);
  };

  // 3. Junction limits of the spans that are complete (a later span exists, or the end).
  const auto close_limits = [&] {
    const size_t complete = ended ? K : created() - 1;  // spans 0 .. complete - 1 are final
    while (limits < (ended ? K + 1 : complete)) {
      const size_t k = limits;
      double l;
      if (k == 0)
        l = std::min(settings.start_speed_mm_per_s, span(0).v);
      else if (k == K && ended)
        l = std::min(settings.end_speed_mm_per_s, span(K - 1).v);
      else
        l = junction_limit(span(k - 1), span(k));
      at(limit, k) = std::max(0.0, l);
      if (k == 0) at(speed, 0) = at(limit, 0);
      ++limits;
    }
  };
  // The look-ahead windows whose 2 W spans ahead are complete (or the end).
  const auto close_windows = [&] {
    while (ended ? next_window < K : created() >= next_window + 2 * W + 1) {
      const size_t c = next_window, e = ended ? std::min(K, c + 2 * W) : c + 2 * W;
      backward.assign(e - c + 1, 0.0);
      backward[e - c] = ended && e == K ? at(limit, K) : 0.0;
      for (size_t k = e; k-- > c;) {
        const Span& s = span(k);
        backward[k - c] = reach(backward[k + 1 - c], s.length, s.a, s.j, at(limit, k));
      }
      at(speed, c) = std::min(at(speed, c), backward[0]);
      const size_t f = ended ? std::min(K, c + W) : c + W;
      for (size_t k = c; k < f; ++k) {
        const Span& s = span(k);
        at(speed, k + 1) = reach(at(speed, k), s.length, s.a, s.j, backward[k + 1 - c]);
      }
      next_window = c + W;
    }
  };

  // 4. and 5. The spans whose speeds are final: G93, then their samples' times.
  double t_span = 0.0, t_last = 0.0;
  size_t sample_index = 0;
  const auto emit = [&] {
    while (base < created() && (base + 1 < next_window || (ended && next_window >= K))) {
      const size_t k = base;
      Span& s = span(k);
      const double v_in = at(speed, k), v_out = at(speed, k + 1);
      const MovingRun& m = moving.front();
      const std::optional<bool> limited_by_g93 = solve_inverse_time(s, v_in, v_out, m.v_axis, m.v_cap);
      if (k == 0) visit.sample(sample_index++, behind.start(), 0.0, s.unit == Unit::Tip ? v_in : 0.0);
      SpanClock clock(s, v_in, v_out);
      double arc = 0.0;
      for (size_t b = s.first_run; b <= s.last_run; ++b) {
        assert(behind.next_index() == b);  // spans cover the blocks in order
        BlockReport report;
        const Run r = densify_block(behind, report);
        const double t_before = t_last;
        for (size_t i = 1; i < window.size(); ++i) {
          arc += seg_len[i];
          const auto [t, v] = clock.at(arc);
          t_last = t_span + t;
          visit.sample(sample_index++, window[i], t_last, s.unit == Unit::Tip ? v : 0.0);
        }
        const bool limited = b == s.moving_run && limited_by_g93 ? *limited_by_g93 : r.axis_limited;
        visit.block(b, report, t_last - t_before, limited);
      }
      t_span += clock.profile().duration;
      spans.pop_front();
      moving.pop_front();
      limit.pop_front();
      speed.pop_front();
      ++base;
    }
  };

  // 1. and 2. Runs and spans as the ahead densifier makes them.
  while (!ahead.done()) {
    BlockReport report;
    const size_t before = created();
    const Run r = densify_block(ahead, report);
    const size_t k = ahead.next_index() - 1;
    add_to_spans(spans, r, k);
    if (created() > before) moving.emplace_back();
    if (spans.back().moving_run == k) moving.back() = {r.v_axis, r.v_cap};
    close_limits();
    close_windows();
    emit();
  }
  ended = true;
  K = created();
  close_limits();
  close_windows();
  emit();
  return t_last;
}

PathPosition PathCursor::at(double t_s) {
  const FeedPlan& p = plan_;
  const std::size_t n = p.t_s.size();
  if (n < 2 || p.spans.empty()) return {1, 0.0};
  if (span_ >= p.spans.size() || t_s < last_t_s_) span_ = phase_ = 0, segment_ = 1;
  last_t_s_ = t_s;
  while (span_ + 1 < p.spans.size() && t_s >= p.spans[span_ + 1].t0_s) ++span_, phase_ = 0;
  const SpanTiming& span = p.spans[span_];
  if (segment_ < span.first_sample) segment_ = span.first_sample;
  // The path parameter at t_s: within the phase that holds it (the span's end exactly).
  double s;
  if (span.phases.empty() || t_s >= span.t0_s + span.duration_s) {
    s = p.path_s[span.last_sample];
  } else {
    while (phase_ + 1 < span.phases.size() && t_s >= span.phases[phase_ + 1].t0_s) ++phase_;
    const JerkPhase& ph = span.phases[phase_];
    s = ph.at(std::clamp(t_s - ph.t0_s, 0.0, ph.duration_s));
  }
  // The move holding s: the first whose end lies at or beyond it.
  while (segment_ < span.last_sample && p.path_s[segment_] < s) ++segment_;
  const double s0 = p.path_s[segment_ - 1], s1 = p.path_s[segment_];
  const double f = s1 > s0 ? std::clamp((s - s0) / (s1 - s0), 0.0, 1.0) : 1.0;
  return {segment_, f};
}

}  // namespace vcut::kinematics
