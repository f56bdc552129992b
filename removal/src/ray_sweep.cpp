#include "ray_sweep.h"

#include "lanes.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>
#include <vector>

namespace vcut::removal::detail {
namespace {

using Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();
// tilted_flat's (and its lanes') slack: points on a boundary of its (s, t) region count as
// inside (mm, and mm^2 for the ellipse's q).
constexpr double kFlatSlack_mm = 1e-12;
// Motion or edge lengths below this (mm) count as zero.
constexpr double kTiny_mm = 1e-12;

// Minimum of a convex function on [a, b] by golden-section search; returns the argument.
template <class F>
double golden_argmin(F&& f, double a, double b, double tolerance) {
  constexpr double kInvPhi = 0.6180339887498949;
  double c = b - kInvPhi * (b - a), e = a + kInvPhi * (b - a);
  double fc = f(c), fe = f(e);
  while (b - a > tolerance) {
    if (fc <= fe) {
      b = e;
      e = c;
      fe = fc;
      c = b - kInvPhi * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = e;
      fc = fe;
      e = a + kInvPhi * (b - a);
      fe = f(e);
    }
  }
  // The ends too: a convex function may be smallest at a bound of the interval.
  double best = 0.5 * (a + b), f_best = f(best);
  for (double t : {a, b}) {
    const double ft = f(t);
    if (ft < f_best) {
      best = t;
      f_best = ft;
    }
  }
  return best;
}

// A root of f in [a, b] where f(a) and f(b) differ in sign (f(a) > 0 >= f(b) or the reverse):
// the point nearest to the side where f > 0 that is still <= 0, to `tolerance`.
template <class F>
double bisect(F&& f, double outside, double inside, double tolerance) {
  while (std::abs(inside - outside) > tolerance) {
    const double mid = 0.5 * (outside + inside);
    (f(mid) > 0.0 ? outside : inside) = mid;
  }
  return inside;
}

// The root march's next point from s (f > 0 there, `slope` its slope along +s where known,
// else NaN), walking along dir, given `safe`: the farthest of its own steps (the sphere step
// and, after the first point, the secant step). Newton's step where it goes farther: f is
// convex, so its tangent lies below it and the tangent's zero too comes at or before the root
// (a bull-nose's march from the bracket's end: 3.7 distances a root by sphere and secant
// steps, the first sphere step short where the ray meets the surface obliquely). Then
// `fallback` is `safe`, where the march goes instead should f come out below -tolerance
// (rounding in the slope); else NaN.
double newton_or(double s, double f, double slope, double dir, double safe, double& fallback) {
  fallback = std::numeric_limits<double>::quiet_NaN();
  const double fall = -dir * slope;  // f's fall per mm along the walk
  if (!(fall > 0.0)) return safe;
  const double newton = s + dir * (f / fall);
  if (!((newton - safe) * dir > 0.0)) return safe;
  fallback = safe;
  return newton;
}

// The first root of a convex, 1-Lipschitz f met walking from `from` toward `toward`, where
// f(from) > 0; f(s, slope) gives f and its slope along +s (NaN where not known). Each step
// takes the farthest of the sphere step (f is 1-Lipschitz: no root nearer than f), the secant
// step (f is convex: beyond two points before the root f lies above their secant, so the
// secant's zero comes at or before the root) and Newton's (newton_or): it never passes the
// root and converges superlinearly. False when f stops decreasing first (the line misses)
// or the walk leaves the range; `converged` false when it ran out of steps. march_lanes takes
// the same steps four rays at a time.
template <class F>
bool march_to_root(F&& f, double from, double toward, double tolerance, double& root, bool& converged) {
  const double dir = toward > from ? 1.0 : -1.0;
  double slope;
  double s0 = from, f0 = f(s0, slope);
  converged = true;
  if (f0 <= tolerance) {
    root = from;
    return true;
  }
  double fallback;
  double s1 = newton_or(s0, f0, slope, dir, s0 + dir * f0, fallback);
  for (int step = 0; step < 100; ++step) {
    if ((s1 - toward) * dir > 0.0) return false;
    const double f1 = f(s1, slope);
    if (f1 < -tolerance && fallback == fallback) {  // Newton's step passed the root
      s1 = fallback;
      fallback = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    if (f1 <= tolerance) {
      root = s1;
      return true;
    }
    if (f1 >= f0) return false;
    const double secant = s1 + (s1 - s0) * f1 / (f0 - f1);
    const double sphere = s1 + dir * f1;
    s0 = s1;
    f0 = f1;
    s1 = newton_or(s0, f0, slope, dir, dir > 0.0 ? std::max(secant, sphere) : std::min(secant, sphere), fallback);
  }
  converged = false;
  return false;
}

// The point at s on the ray of family `axis` through (u, w) (the other two coordinates, in
// increasing axis order).
Vector3d ray_point(int axis, double u, double w, double s) {
  // Built whole (a store by index read back by a vector load stalls).
  return axis == 0 ? Vector3d(s, u, w) : axis == 1 ? Vector3d(u, s, w) : Vector3d(u, w, s);
}

void widen(double& lo, double& hi, double a, double b) {
  lo = std::min(lo, a);
  hi = std::max(hi, b);
}

}  // namespace

bool line_cylinder(int axis, const Vector3d& o, const Vector3d& p, const Vector3d& d, double r, double& lo,
                   double& hi) {
  const double dd = d.squaredNorm();
  if (dd <= kTiny_mm * kTiny_mm) return false;
  Vector3d m = o - p;
  m[axis] = -p[axis];
  const double md = m.dot(d), nd = d[axis], mn = m[axis];
  const double a = dd - nd * nd;
  const double c = dd * (m.squaredNorm() - r * r) - md * md;
  double s0 = -kInf, s1 = kInf;
  if (a <= 1e-14 * dd) {
    if (c > 0.0) return false;  // parallel to the cylinder and outside it
  } else {
    const double b = dd * mn - nd * md;
    const double disc = b * b - a * c;
    if (disc < 0.0) return false;
    const double root = std::sqrt(disc);
    s0 = (-b - root) / a;
    s1 = (-b + root) / a;
  }
  // Between the two end planes: the projection parameter (md + s*nd)/dd in [0, 1].
  if (nd != 0.0) {
    double e0 = -md / nd, e1 = (dd - md) / nd;
    if (e0 > e1) std::swap(e0, e1);
    s0 = std::max(s0, e0);
    s1 = std::min(s1, e1);
  } else if (md < 0.0 || md > dd) {
    return false;
  }
  if (s0 > s1) return false;
  lo = s0;
  hi = s1;
  return true;
}

namespace {

// Restricts [s0, s1] to where v0 + s*slope lies in [lo, hi].
bool clip(double v0, double slope, double lo, double hi, double& s0, double& s1) {
  if (slope == 0.0) return v0 >= lo && v0 <= hi;
  double e0 = (lo - v0) / slope, e1 = (hi - v0) / slope;
  if (e0 > e1) std::swap(e0, e1);
  s0 = std::max(s0, e0);
  s1 = std::min(s1, e1);
  return s0 <= s1;
}

// clip with 1 / slope given (slope != 0): no division per ray.
bool clip_inv(double v0, double inv_slope, double lo, double hi, double& s0, double& s1) {
  double e0 = (lo - v0) * inv_slope, e1 = (hi - v0) * inv_slope;
  if (e0 > e1) std::swap(e0, e1);
  s0 = std::max(s0, e0);
  s1 = std::min(s1, e1);
  return s0 <= s1;
}

double sign(double x) { return x < 0.0 ? -1.0 : 1.0; }

// The real roots of a x^2 + 2 b x + c (into roots; how many returned), given 1 / a. A
// discriminant a hair below zero from rounding counts as zero (a ray through a cone's apex
// line: the double root is the answer there).
int quadratic_roots(double a, double b, double c, double roots[2], double inv_a) {
  if (a == 0.0) {
    if (b == 0.0) return 0;
    roots[0] = -c / (2.0 * b);
    return 1;
  }
  double disc = b * b - a * c;
  if (disc < 0.0) {
    if (disc < -1e-12 * std::max(b * b, std::abs(a * c))) return 0;
    disc = 0.0;
  }
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  if (q == 0.0) {  // b = 0 and a c = 0: the double root 0
    roots[0] = 0.0;
    return 1;
  }
  roots[0] = q * inv_a;
  roots[1] = c / q;
  return 2;
}

// ss s^2 + 2 st s t + tt t^2 + 2 s s + 2 t t + c over the (s, t) plane.
struct Conic {
  double ss, st, tt, s, t, c;
  double at(double x, double y) const { return (ss * x + 2.0 * (st * y + s)) * x + (tt * y + 2.0 * t) * y + c; }
  // Along the line (x, y) + l (dx, dy): a l^2 + 2 b l + c, given a = lead(dx, dy) and 1 / a.
  static double lead(double ss, double st, double tt, double dx, double dy) {
    return (ss * dx + 2.0 * st * dy) * dx + tt * dy * dy;
  }
  int on_line(double x, double y, double dx, double dy, double a, double inv_a, double roots[2]) const {
    const double qb = ss * x * dx + st * (x * dy + y * dx) + tt * y * dy + s * dx + t * dy;
    return quadratic_roots(a, qb, at(x, y), roots, inv_a);
  }
};

}  // namespace

// The tilted window box's margin (mm), far above rounding and far below anything a ray
// resolves: the window is only a filter, the kernel decides.
constexpr double kTiltMargin_mm = 1e-6;

RaySweep::RaySweep(const Cutter& cutter, const Move& move, const Eigen::AlignedBox3d* material_box)
    : p0_(move.start_mm),
      delta_(move.end_mm - move.start_mm),
      core_(core_of(cutter)),
      cutter_(cutter),
      sweep_(cutter, move) {
  bounds_ = sweep_.bounds();
  radius_mm_ = cutter.type == CutterType::VBit ? section_radius(cutter, cutter.flute_length_mm)
                                               : core_.core_radius_mm + core_.rounding_mm;
  height_mm_ = core_.z_high_mm + core_.rounding_mm;
  const Vector3d a = move.axis.normalized();
  tool_axis_ = a;
  slab_low_mm_ = move.slab_low_mm;
  slab_high_mm_ = move.slab_high_mm;
  // Unless VCUT_SCALAR_KERNELS is set (read per move, so that a test can cut both ways and
  // compare).
  lanes_ = kHaveAvx2 && std::getenv("VCUT_SCALAR_KERNELS") == nullptr;
  core_mid_ = p0_ + 0.5 * delta_;
  half_move_mm_ = 0.5 * delta_.norm();
  vertical_axis_ = std::abs(a.x()) <= kTiny_mm && std::abs(a.y()) <= kTiny_mm && a.z() > 0.0;
  flat_bottom_ = cutter.type != CutterType::VBit && core_.rounding_mm == 0.0;
  if (core_.core_radius_mm == 0.0 && cutter.type != CutterType::VBit) {
    method_ = Method::Ball;
    prepare_capsule(core_.rounding_mm);
    if (!vertical_axis_) prepare_tilt_box(material_box);
  } else if (vertical_axis_) {
    method_ = Method::Upright;
    // An upright bull-nose moving up or down: its horizontal rays take the general method's
    // march where the section changes along the move (upright_horizontal).
    upright_march_ = cutter.type != CutterType::VBit && core_.rounding_mm > 0.0 && std::abs(delta_.z()) > kTiny_mm;
    if (upright_march_) prepare_march();
  } else {
    method_ = Method::General;
    prepare_march();
    if (flat_bottom_)
      for (int axis = 0; axis < 3; ++axis) prepare_flat_family(axis);
    prepare_tilt_box(material_box);
  }
  // A V-bit's closed form (cone_interval): every ray of a tilted one, and an upright one's
  // horizontal rays where its section changes along the move (ramps).
  if (cutter.type == CutterType::VBit) {
    cone_ = true;
    cone_k_ = std::tan(0.5 * cutter.tip_angle_deg * M_PI / 180.0);
    cone_top_mm_ = std::min(cutter.flute_length_mm, cutter.radius_mm() / cone_k_);
    cone_r_mm_ = cone_top_mm_ * cone_k_;
    for (int axis = 0; axis < 3; ++axis) prepare_cone_family(axis);
  }
}

void RaySweep::prepare_march() {
  band_ = cutter_.type != CutterType::VBit && core_.rounding_mm > 0.0 && core_.core_radius_mm > 0.0;
  // band_'s heights: clear of the corner and the top rounding above every instance's tip by
  // far more than rounding moves the bracket's end.
  constexpr double kClear_mm = 1e-6;
  const double hd = delta_.dot(tool_axis_);
  band_h_lo_mm_ = core_.z_low_mm + kClear_mm + std::max(0.0, hd);
  band_h_hi_mm_ = core_.z_high_mm - kClear_mm + std::min(0.0, hd);
  lowest_h_mm_ = std::min(0.0, hd);
  lowest_tip_ = hd >= 0.0 ? p0_ : Vector3d(p0_ + delta_);
  // The root march's bracket: every instance lies within R of the core's axis segment (a
  // V-bit within R of its axis over [0, H]), so the sweep lies in that segment's sweep
  // grown by R, a ball sweep with the closed form. A hair wider, so that rounding never
  // puts the sweep's boundary outside it (the flat end mill's and the bull-nose's sides
  // lie on it), and no wider: a bull-nose's ends in its band are taken from it (band_).
  constexpr double kBracketMargin_mm = 1e-9;
  prepare_capsule(core_.core_radius_mm + core_.rounding_mm + kBracketMargin_mm);
}

// The ball sweep: the core's axis segment from z_low to z_high (a) swept along the move (b),
// grown by capsule_r.
void RaySweep::prepare_capsule(double capsule_r) {
  capsule_r_ = capsule_r;
  const Vector3d& a = tool_axis_;
  c0_ = p0_ + core_.z_low_mm * a;
  edge_a_ = (core_.z_high_mm - core_.z_low_mm) * a;
  edge_b_ = delta_;
  const double la = edge_a_.norm(), lb = edge_b_.norm();
  const Vector3d cross = edge_a_.cross(edge_b_);
  if (la <= 1e-9 && lb <= 1e-9) {
    segments_ = 0;
  } else if (la <= 1e-9 || lb <= 1e-9 || cross.norm() <= 1e-12 * la * lb) {
    // The parallelogram is a segment: its two extreme corners along the common direction.
    const Vector3d dir = (la > lb ? edge_a_ : edge_b_).normalized();
    Vector3d lo_point = c0_, hi_point = c0_;
    for (const Vector3d& p : {Vector3d(c0_ + edge_a_), Vector3d(c0_ + edge_b_), Vector3d(c0_ + edge_a_ + edge_b_)}) {
      if (p.dot(dir) < lo_point.dot(dir)) lo_point = p;
      if (p.dot(dir) > hi_point.dot(dir)) hi_point = p;
    }
    segments_ = 1;
    c0_ = lo_point;
    edge_a_ = hi_point - lo_point;
  } else {
    segments_ = 2;
    normal_ = cross.normalized();
    const Vector3d bn = edge_b_.cross(normal_), na = normal_.cross(edge_a_);
    dual_a_ = bn / edge_a_.dot(bn);
    dual_b_ = na / edge_b_.dot(na);
  }
  for (int axis = 0; axis < 3; ++axis) prepare_ball_family(axis);
}

void RaySweep::prepare_tilt_box(const Eigen::AlignedBox3d* material_box) {
  // Every instance lies in the cylinder of radius R around [0, H] along the axis a from the
  // tip; the tip moves by delta. Directions: a; n1, the motion's part square to a; n2 = a x n1
  // (no motion along it). Along a the sweep spans [min(0, delta.a), H + max(0, delta.a)],
  // along n1 [-R, R + |delta_perp|], along n2 [-R, R]. The part that stays out of the
  // material's box never meets material: H stops where it begins (W5: the tool stands 25 mm
  // out of a 12 mm block, and two thirds of the rays the whole box passed held none in it).
  // A move with a slab of heights (Move::slab_low_mm, slab_high_mm: a turning cutter's part)
  // spans only that slab's sweep along a.
  const Vector3d& a = tool_axis_;
  const double da = delta_.dot(a);
  const Vector3d perp = delta_ - da * a;
  const double along = perp.norm();
  const Vector3d n1 = along > kTiny_mm ? Vector3d(perp / along) : Vector3d(a.unitOrthogonal());
  const Vector3d n2 = a.cross(n1).normalized();
  const double R = radius_mm_;
  const double H = material_box == nullptr
                       ? height_mm_
                       : std::min(height_mm_, highest_point_in_box_mm(R, p0_, p0_ + delta_, a, a, *material_box));
  tilt_dirs_[0] = a;
  tilt_dirs_[1] = n1;
  tilt_dirs_[2] = n2;
  const double low = std::max(0.0, slab_low_mm_), high = std::max(low, std::min(H, slab_high_mm_));
  const double lo[3] = {low + std::min(0.0, da), -R, -R};
  const double hi[3] = {high + std::max(0.0, da), R + along, R};
  for (int c = 0; c < 8; ++c) {
    tilt_corner_[c] = p0_;
    for (int k = 0; k < 3; ++k)
      tilt_corner_[c] += ((c >> k & 1) ? hi[k] + kTiltMargin_mm : lo[k] - kTiltMargin_mm) * tilt_dirs_[k];
  }
  fill_tilt_boxes(p0_, tilt_dirs_, lo, hi, tilt_box_);
}

void RaySweep::fill_tilt_boxes(const Vector3d& origin, const Vector3d* dirs, const double* lo, const double* hi,
                               TiltBox* boxes) {
  for (int axis = 0; axis < 3; ++axis) {
    TiltBox& b = boxes[axis];
    const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
    for (int k = 0; k < 3; ++k) {
      // Taken along the ray (slope > 0), so that its lower bound gives the entry.
      const double sign = dirs[k][axis] < 0.0 ? -1.0 : 1.0;
      const Vector3d d = sign * dirs[k];
      b.base[k] = -d.dot(origin);
      b.du[k] = d[a1];
      b.dw[k] = d[a2];
      b.lo[k] = (sign > 0.0 ? lo[k] : -hi[k]) - kTiltMargin_mm;
      b.hi[k] = (sign > 0.0 ? hi[k] : -lo[k]) + kTiltMargin_mm;
      b.flat[k] = std::abs(d[axis]) <= 1e-12;
      b.inv_slope[k] = b.flat[k] ? 0.0 : 1.0 / d[axis];
    }
  }
}

RaySweep::GroupWindow::GroupWindow(const RaySweep* const* sweeps, int n) {
  const RaySweep& first = *sweeps[0];
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = kInf;
    hi[k] = -kInf;
  }
  for (int i = 0; i < n; ++i)
    for (const Vector3d& corner : sweeps[i]->tilt_corner_)
      for (int k = 0; k < 3; ++k) {
        const double x = first.tilt_dirs_[k].dot(corner - first.p0_);
        lo[k] = std::min(lo[k], x);
        hi[k] = std::max(hi[k], x);
      }
  fill_tilt_boxes(first.p0_, first.tilt_dirs_, lo, hi, box_);
}

RaySweep::GroupReach::GroupReach(const RaySweep* const* sweeps, int n) {
  const RaySweep& ref = *sweeps[n / 2];
  mid_ = ref.core_mid_;
  axis_ = ref.tool_axis_;
  // Along the reference axis, as far as every sweep's segment reaches (the parts of a long
  // cutter lie one above the other).
  z_low_mm_ = ref.core_.z_low_mm;
  z_high_mm_ = ref.core_.z_high_mm;
  for (int i = 0; i < n; ++i) {
    const RaySweep& s = *sweeps[i];
    for (const double z : {s.core_.z_low_mm, s.core_.z_high_mm}) {
      const double h = (s.core_mid_ + z * s.tool_axis_ - mid_).dot(axis_);
      z_low_mm_ = std::min(z_low_mm_, h);
      z_high_mm_ = std::max(z_high_mm_, h);
    }
  }
  auto distance = [&](const Vector3d& x) {
    const Vector3d p = x - mid_;
    const double h = std::clamp(p.dot(axis_), z_low_mm_, z_high_mm_);
    return (p - h * axis_).norm();
  };
  reach_mm_ = 0.0;
  for (int i = 0; i < n; ++i) {
    const RaySweep& s = *sweeps[i];
    const double d = std::max(distance(s.core_mid_ + s.core_.z_low_mm * s.tool_axis_),
                              distance(s.core_mid_ + s.core_.z_high_mm * s.tool_axis_));
    reach_mm_ = std::max(reach_mm_, s.capsule_r_ + s.half_move_mm_ + d);
  }
  reach_mm_ += 1e-9;  // rounding
}

// material_clear's test, with the group's segment and reach.
bool RaySweep::GroupReach::clear(int axis, double u, double w, double bottom, double top) const {
  if (!(std::isfinite(bottom) && std::isfinite(top))) return false;
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const double half = 0.5 * (top - bottom);
  const double pu = u - mid_[a1], pw = w - mid_[a2], ps = bottom + half - mid_[axis];
  const double qa = pu * axis_[a1] + pw * axis_[a2] + ps * axis_[axis];
  const double h = std::clamp(qa, z_low_mm_, z_high_mm_);
  const double reach = reach_mm_ + half;
  return pu * pu + pw * pw + ps * ps - h * (2.0 * qa - h) > reach * reach;
}

#if defined(__x86_64__)
namespace {
// GroupReach::clear four rays at a time (n a multiple of four; its operations in the same
// order, std::clamp as written: the low end where qa < lo, else the high one where hi < qa),
// the rays not clear to `index`.
__attribute__((target("avx2"))) int reach_not_clear_avx2(const Eigen::Vector3d& mid, const Eigen::Vector3d& axis_dir,
                                                         double z_low, double z_high, double reach_mm, int axis,
                                                         double w, int n, const double* u, const double* bottom,
                                                         const double* top, int* index) {
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const double pw = w - mid[a2];
  const v4d mid_u = all(mid[a1]), mid_s = all(mid[axis]), pw2 = all(pw * pw), low = all(z_low), high = all(z_high);
  const v4d au = all(axis_dir[a1]), aw = all(pw * axis_dir[a2]), as = all(axis_dir[axis]);
  const v4d largest = all(std::numeric_limits<double>::max());
  int kept = 0, j = 0;
  for (; j < n; j += 4) {
    const v4d U = vload(u + j), B = vload(bottom + j), T = vload(top + j);
    const v4i finite = (vabs(B) <= largest) & (vabs(T) <= largest);
    const v4d half = all(0.5) * (T - B);
    const v4d pu = U - mid_u, ps = (B + half) - mid_s;
    const v4d qa = (pu * au + aw) + ps * as;
    const v4d h = select(qa < low, low, select(high < qa, high, qa));
    const v4d reach = all(reach_mm) + half;
    const v4i clear = finite & (((pu * pu + pw2) + ps * ps) - h * (all(2.0) * qa - h) > reach * reach);
    for (int q = 0; q < 4; ++q)
      if (clear[q] == 0) index[kept++] = j + q;
  }
  return kept;
}
}  // namespace
#endif

int RaySweep::GroupReach::not_clear(int axis, double w, int n, const double* u, const double* bottom, const double* top,
                                    int* index, bool lanes) const {
  int kept = 0, j = 0;
#if defined(__x86_64__)
  if (lanes && kHaveAvx2) {
    j = n / 4 * 4;
    kept = reach_not_clear_avx2(mid_, axis_, z_low_mm_, z_high_mm_, reach_mm_, axis, w, j, u, bottom, top, index);
  }
#endif
  for (; j < n; ++j)
    if (!clear(axis, u[j], w, bottom[j], top[j])) index[kept++] = j;
  return kept;
}

void RaySweep::prepare_flat_family(int axis) {
  FlatFamily& f = flat_[axis];
  const Vector3d& a = tool_axis_;
  f.he = a[axis];
  f.hd = delta_.dot(a);
  Vector3d e = Vector3d::Zero();
  e[axis] = 1.0;
  const Vector3d E = e - f.he * a, D = delta_ - f.hd * a;
  f.EE = E.dot(E);
  f.ED = E.dot(D);
  f.DD = D.dot(D);
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  auto in_family_order = [&](const Vector3d& from, double* to) {
    to[0] = from[a1];
    to[1] = from[a2];
    to[2] = from[axis];
  };
  in_family_order(a, f.a);
  in_family_order(p0_, f.p);
  in_family_order(E, f.E);
  in_family_order(D, f.D);
  const double det = f.EE * f.DD - f.ED * f.ED;
  const bool ellipse = !(f.EE < 1e-12 || f.DD < 1e-12 || det <= 1e-9 * f.EE * f.DD);
  if (!ellipse) {
    // E and D along one direction u (the longer one's), the other's part square to it ignored
    // where that moves no point of the ray's instances by more than 1e-7 mm (along the ray,
    // measured from the point level with the tip, they lie within the cutter's length plus
    // diameter plus the move's length).
    const bool e_longer = f.EE >= f.DD;
    const double longest = std::sqrt(std::max(f.EE, f.DD));
    if (longest > 0.0) f.u = (e_longer ? E : D) / longest;
    f.e1 = E.dot(f.u);
    f.d1 = D.dot(f.u);
    const double off_e = (E - f.e1 * f.u).norm(), off_d = (D - f.d1 * f.u).norm();
    const double span_mm = height_mm_ + 2.0 * radius_mm_ + delta_.norm();
    f.kind = off_e * span_mm <= 1e-7 && off_d <= 1e-7 ? FlatFamily::Kind::Strips : FlatFamily::Kind::March;
    return;
  }
  f.kind = FlatFamily::Kind::Ellipse;
  f.inv_DD = 1.0 / f.DD;
  f.A = det / f.DD;
  f.inv_2A = 0.5 / f.A;
  f.inv_2EE = 0.5 / f.EE;
  // The h lines he s - hd t = c - hw, walked as (s, t) = k (he, -hd) + lambda (hd, he).
  const double nn = f.he * f.he + f.hd * f.hd;
  f.h_lines = nn > 1e-24;
  f.inv_nn = f.h_lines ? 1.0 / nn : 0.0;
  f.qa_h = f.EE * f.hd * f.hd - 2.0 * f.ED * f.hd * f.he + f.DD * f.he * f.he;
  f.inv_2qa_h = f.qa_h > 0.0 ? 0.5 / f.qa_h : 0.0;
  f.corners = std::abs(f.he) > 1e-12;
  f.inv_he = f.corners ? 1.0 / f.he : 0.0;
}

void RaySweep::prepare_ball_family(int axis) {
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const double r = capsule_r_;
  BallFamily& f = ball_[axis];
  // Fixed room, no allocation: a RaySweep is built per move.
  std::array<Vector3d, 4> centres = {c0_, c0_, c0_, c0_};
  std::array<std::pair<Vector3d, Vector3d>, 4> edges;
  spheres_ = 1;
  edges_ = 0;
  if (segments_ == 1) {
    centres[1] = c0_ + edge_a_;
    edges[0] = {c0_, edge_a_};
    spheres_ = 2;
    edges_ = 1;
  } else if (segments_ == 2) {
    // Order matters to intervals_within: centres c0, c1, top0, top1; edges along the move first.
    centres = {c0_, c0_ + edge_b_, c0_ + edge_a_, c0_ + edge_a_ + edge_b_};
    edges = {{{c0_, edge_b_}, {c0_ + edge_a_, edge_b_}, {c0_, edge_a_}, {c0_ + edge_b_, edge_a_}}};
    spheres_ = 4;
    edges_ = 4;
  }
  for (int i = 0; i < spheres_; ++i) {
    f.sphere[i][0] = centres[static_cast<std::size_t>(i)][a1];
    f.sphere[i][1] = centres[static_cast<std::size_t>(i)][a2];
    f.sphere[i][2] = centres[static_cast<std::size_t>(i)][axis];
  }
  for (int i = 0; i < edges_; ++i) {
    const auto& [p, d] = edges[static_cast<std::size_t>(i)];
    Edge& e = f.edge[i];
    e.p1 = p[a1];
    e.p2 = p[a2];
    e.pk2 = p[axis] * p[axis] - r * r;
    e.d1 = d[a1];
    e.d2 = d[a2];
    e.dk = d[axis];
    e.e0 = -p[axis] * d[axis];
    e.dd = d.squaredNorm();
    e.bk = -e.dd * p[axis];
    e.a = e.dd - e.dk * e.dk;
    e.parallel = e.a <= 1e-14 * e.dd;
    e.inv_a = e.parallel ? 0.0 : 1.0 / e.a;
    e.inv_dk = e.dk != 0.0 ? 1.0 / e.dk : 0.0;
  }
  f.slab_band = false;
  if (segments_ == 2 && vertical_axis_ && axis != 2) {
    // The centres' path in the horizontal plane: from (c0_u, c0_s) along (d_u, d_s), with s
    // the coordinate along the ray; its band |n . (q - c0)| <= r, 0 <= t <= 1.
    const double du = edge_b_[a1], ds = edge_b_[axis], len2 = du * du + ds * ds;
    if (len2 > kTiny_mm * kTiny_mm) {
      const double len = std::sqrt(len2);
      const double nu = -ds / len, ns = du / len;
      f.slab_band = true;
      f.band_n_base = -nu * c0_[a1] - ns * c0_[axis];
      f.band_n_u = nu;
      f.band_n_s = ns;
      f.band_t_base = (-du * c0_[a1] - ds * c0_[axis]) / len2;
      f.band_t_u = du / len2;
      f.band_t_s = ds / len2;
    }
  }
  if (segments_ == 2) {
    const Vector3d* g[3] = {&normal_, &dual_a_, &dual_b_};
    for (int j = 0; j < 3; ++j) {
      f.slab.base[j] = -g[j]->dot(c0_);
      f.slab.c1[j] = (*g[j])[a1];
      f.slab.c2[j] = (*g[j])[a2];
      f.slab.flat[j] = (*g[j])[axis] == 0.0;
      f.slab.inv_slope[j] = f.slab.flat[j] ? 0.0 : 1.0 / (*g[j])[axis];
    }
  }
}

inline bool RaySweep::ball_cylinder(int axis, int i, double u, double w, double& a, double& b, bool& lo_side,
                                    bool& hi_side) const {
  const BallFamily& f = ball_[axis];
  const Edge& e = f.edge[i];
  const double x = u - e.p1, y = w - e.p2;
  const double md = x * e.d1 + y * e.d2 + e.e0;
  const double c = e.dd * (x * x + y * y + e.pk2) - md * md;
  double s0 = -kInf, s1 = kInf;
  lo_side = hi_side = false;
  if (e.parallel) {
    if (c > 0.0) return false;
  } else {
    const double half_b = e.bk - e.dk * md;
    const double disc = half_b * half_b - e.a * c;
    if (disc < 0.0) return false;
    const double root = std::sqrt(disc);
    s0 = (-half_b - root) * e.inv_a;
    s1 = (-half_b + root) * e.inv_a;
  }
  if (e.dk != 0.0) {
    double t0 = -md * e.inv_dk, t1 = (e.dd - md) * e.inv_dk;
    if (t0 > t1) std::swap(t0, t1);
    lo_side = s0 > t0;
    hi_side = s1 < t1;
    s0 = std::max(s0, t0);
    s1 = std::min(s1, t1);
  } else if (md < 0.0 || md > e.dd) {
    return false;
  } else {
    lo_side = hi_side = !e.parallel;
  }
  if (s0 > s1) return false;
  a = s0;
  b = s1;
  return true;
}

// Any ball sweep: the hull of the corner spheres, the edge cylinders and the slab.
inline bool RaySweep::ball_general(int axis, double u, double w, double& lo, double& hi) const {
  const BallFamily& f = ball_[axis];
  const double r = capsule_r_, r2 = r * r;
  lo = kInf;
  hi = -kInf;
  double a, b;
  for (int i = 0; i < spheres_; ++i) {
    const double x = u - f.sphere[i][0], y = w - f.sphere[i][1];
    const double h2 = r2 - x * x - y * y;
    if (h2 < 0.0) continue;
    const double h = std::sqrt(h2);
    widen(lo, hi, f.sphere[i][2] - h, f.sphere[i][2] + h);
  }
  bool lo_side, hi_side;
  for (int i = 0; i < edges_; ++i)
    if (ball_cylinder(axis, i, u, w, a, b, lo_side, hi_side)) widen(lo, hi, a, b);
  if (segments_ == 2) {
    // The slab of thickness 2r over the parallelogram's inside.
    const Slab& sl = f.slab;
    double s0 = -kInf, s1 = kInf;
    const double bounds[3][2] = {{-r, r}, {0.0, 1.0}, {0.0, 1.0}};
    for (int j = 0; j < 3; ++j) {
      const double v0 = sl.base[j] + sl.c1[j] * u + sl.c2[j] * w;
      if (sl.flat[j]) {
        if (v0 < bounds[j][0] || v0 > bounds[j][1]) return lo <= hi;
        continue;
      }
      double e0 = (bounds[j][0] - v0) * sl.inv_slope[j], e1 = (bounds[j][1] - v0) * sl.inv_slope[j];
      if (e0 > e1) std::swap(e0, e1);
      s0 = std::max(s0, e0);
      s1 = std::min(s1, e1);
    }
    if (s0 <= s1) widen(lo, hi, s0, s1);
  }
  return lo <= hi;
}

void RaySweep::row_range(int axis, double w, double section, double& u_lo, double& u_hi) const {
  const int a1 = axis == 0 ? 1 : 0;
  u_lo = bounds().min()[a1];
  u_hi = bounds().max()[a1];
  if (!vertical_axis_) {
    // The row's plane at w cuts the window box (tilted_window's) in a convex polygon whose
    // corners lie on the box's edges: its extent in u holds every ray that meets the box.
    const int a2 = axis == 2 ? 1 : 2;
    // The box's 12 edges, corner c to corner c | 1 << k for each bit k not set in c.
    static constexpr int kEdges[12][2] = {{0, 1}, {0, 2}, {0, 4}, {1, 3}, {1, 5}, {2, 3},
                                          {2, 6}, {3, 7}, {4, 5}, {4, 6}, {5, 7}, {6, 7}};
    double lo = kInf, hi = -kInf;
    for (const auto& edge : kEdges) {
      const Vector3d &p = tilt_corner_[edge[0]], &q = tilt_corner_[edge[1]];
      const double pw = p[a2], qw = q[a2];
      if (w < std::min(pw, qw) || w > std::max(pw, qw)) continue;
      if (pw == qw) {
        widen(lo, hi, std::min(p[a1], q[a1]), std::max(p[a1], q[a1]));
      } else {
        const double x = p[a1] + (w - pw) / (qw - pw) * (q[a1] - p[a1]);
        widen(lo, hi, x, x);
      }
    }
    u_lo = std::max(u_lo, lo);
    u_hi = std::min(u_hi, hi);
    return;
  }
  const Eigen::Vector3d p1 = p0_ + delta_;
  if (axis == 2) {
    // Rays along z in the row y = w: where the row meets the stadium of radius R around the
    // tip's path in the xy plane (the two end discs and the band between them).
    const double radius = radius_mm_;
    double lo = kInf, hi = -kInf;
    for (const Vector3d* c : {&p0_, &p1}) {
      const double h2 = radius * radius - (w - c->y()) * (w - c->y());
      if (h2 >= 0.0) widen(lo, hi, c->x() - std::sqrt(h2), c->x() + std::sqrt(h2));
    }
    const double dx = delta_.x(), dy = delta_.y(), len = std::sqrt(dx * dx + dy * dy);
    if (len > kTiny_mm) {
      // Band: |n . (q - p0)| <= R and 0 <= (q - p0) . d <= |d|^2, q = (x, w), linear in x.
      const double nx = -dy / len, ny = dx / len;
      double s0 = -kInf, s1 = kInf;
      if (clip(ny * (w - p0_.y()) - nx * p0_.x(), nx, -radius, radius, s0, s1) &&
          clip(dy * (w - p0_.y()) - dx * p0_.x(), dx, 0.0, len * len, s0, s1))
        widen(lo, hi, s0, s1);
    }
    u_lo = std::max(u_lo, lo);
    u_hi = std::min(u_hi, hi);
    return;
  }
  // Rays along x or y in the row at height z = w: the cutter's widest section over the
  // heights above the tip the row takes during the move, around the tip's path.
  if (section < 0.0) {
    u_lo = 1.0;
    u_hi = 0.0;
    return;
  }
  u_lo = std::max(u_lo, std::min(p0_[a1], p1[a1]) - section);
  u_hi = std::min(u_hi, std::max(p0_[a1], p1[a1]) + section);
}

double RaySweep::row_section(int axis, double w) const {
  if (!vertical_axis_ || axis == 2) return kInf;
  const double z1 = p0_.z() + delta_.z();
  const double h_lo = w - std::max(p0_.z(), z1), h_hi = w - std::min(p0_.z(), z1);
  if (h_hi < 0.0 || h_lo > height_mm_) return -1.0;
  // The section grows up to `full` above the tip, then stays or shrinks: its largest value
  // over [h_lo, h_hi] is at the point of that range nearest to `full`.
  const double full =
      cutter_.type == CutterType::VBit ? std::min(height_mm_, underside_height(cutter_, radius_mm_)) : core_.z_low_mm;
  const double h = std::clamp(std::clamp(full, h_lo, h_hi), 0.0, height_mm_);
  return cutter_.type == CutterType::VBit ? section_radius(cutter_, h)
                                          : core_section_radius(core_, cutter_.flute_length_mm, h);
}

double RaySweep::row_floor(int axis, double w) const {
  if (axis != 2 || !vertical_axis_) return -kInf;
  // The tip never goes below its lower end; at horizontal distance rho from the tip's
  // path the underside lies underside(rho) higher, rho at least the row's distance from the
  // path's y range.
  const double y0 = std::min(p0_.y(), p0_.y() + delta_.y()), y1 = std::max(p0_.y(), p0_.y() + delta_.y());
  const double rho = w < y0 ? y0 - w : (w > y1 ? w - y1 : 0.0);
  if (rho > radius_mm_) return kInf;
  return std::min(p0_.z(), p0_.z() + delta_.z()) + underside_height(cutter_, rho);
}

bool RaySweep::interval_within(int axis, double u, double w, double bottom, double top, double& lo, double& hi) const {
  bool hit;
  intervals_within(axis, w, 1, &u, &bottom, &top, &lo, &hi, &hit);
  return hit;
}

// The ball method (see the header). An upright ball's sweep is cut by a row of rays in one
// of three ways, picked once per row:
//  - horizontal rays below both ball centres meet only the centres' swept capsule (the
//    parallelogram's nearest points are on its lower edge), above both top centres only
//    the top capsule;
//  - horizontal rays between the centres' heights and the top centres' heights meet the
//    disc of radius r swept along the centres' path in their plane;
//  - vertical rays enter through the centres' capsule and leave through the top one (the
//    rest lies between the two in z).
// A capsule is its edge's cylinder and two end spheres: an end of the cylinder's interval on
// its side (not on an end plane) is on the capsule's boundary, so the spheres are needed only
// for an end that is not. Anything else goes through ball_general.
__attribute__((flatten)) void RaySweep::intervals_within(int axis, double w, int count, const double* u,
                                                         const double* bottom, const double* top, double* lo,
                                                         double* hi, bool* hit) const {
  if (method_ == Method::General) {
    // The tilted flat end mill's closed form where it decides, else the root march over the
    // material only (a march started inside the sweep stops at once; one that never meets it
    // within the material ends the ray's test).
    if (!flat_bottom_ && !cone_ && segments_ == 2 && lanes_) {
      // general() with the bracket's intervals four rays at a time (bracket_avx2).
      const Eigen::AlignedBox3d& box = bounds_;
      const int a2 = axis == 2 ? 1 : 2;
      if (!(w >= box.min()[a2] && w <= box.max()[a2])) {  // the row misses the sweep's box
        std::fill(hit, hit + count, false);
        return;
      }
      int todo[kLanesBlock];
      double capsule_lo[kLanesBlock], capsule_hi[kLanesBlock];
      bool capsule_hit[kLanesBlock];
      for (int first = 0; first < count; first += kLanesBlock) {
        const int n =
            not_clear_avx2(axis, w, first, std::min(count, first + kLanesBlock), u, bottom, top, true, hit, todo);
        bracket_avx2(axis, w, n, todo, u + first, capsule_lo, capsule_hi, capsule_hit);
        bracketed_lanes(axis, w, first, n, todo, u, bottom, top, capsule_lo, capsule_hi, capsule_hit, lo, hi, hit);
      }
      return;
    }
    if (flat_bottom_ && lanes_ && flat_[axis].kind == FlatFamily::Kind::Ellipse) {
      tilted_flat_avx2(axis, w, count, u, lo, hi, hit);
      return;
    }
    if (cone_ && lanes_) {
      // general(): the box, material_clear (not_clear_avx2, as for the ball and bull-nose
      // above), then the cone's closed form on the rays left.
      const int a2 = axis == 2 ? 1 : 2;
      if (!(w >= bounds_.min()[a2] && w <= bounds_.max()[a2])) {
        std::fill(hit, hit + count, false);
        return;
      }
      int todo[kLanesBlock];
      for (int first = 0; first < count; first += kLanesBlock) {
        const int n =
            not_clear_avx2(axis, w, first, std::min(count, first + kLanesBlock), u, bottom, top, true, hit, todo);
        cone_intervals_avx2(axis, w, n, todo, u + first, lo + first, hi + first, hit + first);
      }
      return;
    }
    for (int k = 0; k < count; ++k) {
      bool decided = false;
      if (flat_bottom_) hit[k] = tilted_flat(axis, u[k], w, lo[k], hi[k], decided);
      if (!decided) hit[k] = general(axis, ray_point(axis, u[k], w, 0.0), bottom[k], top[k], lo[k], hi[k]);
    }
    return;
  }
  if (method_ == Method::Upright) {
    if (axis == 2 && lanes_ && !flat_bottom_ && !cone_ &&
        delta_.x() * delta_.x() + delta_.y() * delta_.y() > kTiny_mm * kTiny_mm) {
      upright_vertical_avx2(w, count, u, top, lo, hi, hit);
      return;
    }
    if (axis != 2 && lanes_ &&
        (upright_horizontal_avx2(axis, w, count, u, lo, hi, hit) ||
         upright_ramps_avx2(axis, w, count, u, bottom, top, lo, hi, hit)))
      return;
    for (int k = 0; k < count; ++k)
      hit[k] = axis == 2 ? upright_vertical(u[k], w, top[k], lo[k], hi[k])
                         : upright_horizontal(axis, u[k], w, bottom[k], top[k], lo[k], hi[k]);
    return;
  }
  const BallFamily& f = ball_[axis];
  const double r = capsule_r_, r2 = r * r;
  // Sphere i widens [l, h] (entry and exit as asked) where the ray meets it.
  auto sphere = [&](int i, double uk, double& l, double& h, bool entry, bool exit) {
    const double x = uk - f.sphere[i][0], y = w - f.sphere[i][1];
    const double h2 = r2 - x * x - y * y;
    if (h2 < 0.0) return;
    const double root = std::sqrt(h2);
    if (entry) l = std::min(l, f.sphere[i][2] - root);
    if (exit) h = std::max(h, f.sphere[i][2] + root);
  };
  const bool upright_ball = vertical_axis_ && segments_ == 2;
  if (upright_ball && axis != 2) {
    const double c_lo = std::min(f.sphere[0][1], f.sphere[1][1]), c_hi = std::max(f.sphere[0][1], f.sphere[1][1]);
    const double t_lo = std::min(f.sphere[2][1], f.sphere[3][1]), t_hi = std::max(f.sphere[2][1], f.sphere[3][1]);
    if (w < c_lo || w > t_hi) {
      const int first = w < c_lo ? 0 : 2;
      if (lanes_) {
        capsule_avx2(axis, w, first, count, u, lo, hi, hit);
        return;
      }
      for (int k = 0; k < count; ++k) {
        double l = kInf, h = -kInf, a, b;
        bool lo_side, hi_side;
        if (ball_cylinder(axis, first / 2, u[k], w, a, b, lo_side, hi_side)) {
          widen(l, h, a, b);
          if (lo_side && hi_side) {
            hit[k] = true;
            lo[k] = l;
            hi[k] = h;
            continue;
          }
        }
        sphere(first, u[k], l, h, true, true);
        sphere(first + 1, u[k], l, h, true, true);
        hit[k] = l <= h;
        lo[k] = l;
        hi[k] = h;
      }
      return;
    }
    if (w >= c_hi && w <= t_lo) {
      const double x0 = f.sphere[0][0], s0c = f.sphere[0][2], x1 = f.sphere[1][0], s1c = f.sphere[1][2];
      const bool band = f.slab_band;
      const double n_base = f.band_n_base, n_u = f.band_n_u, n_s = f.band_n_s;
      const double t_base = f.band_t_base, t_u = f.band_t_u, t_s = f.band_t_s;
      const double inv_n_s = n_s != 0.0 ? 1.0 / n_s : 0.0, inv_t_s = t_s != 0.0 ? 1.0 / t_s : 0.0;
      // Rays square to the path in their plane (W1's y rays): n0 is the row's, so the band's
      // slice [b0, b1] is too, and where it holds both discs' widest slices (sqrt is monotonic,
      // so no disc slice is wider than sqrt(r2)) it is the whole answer wherever t0 is in range.
      double b0 = -kInf, b1 = kInf;
      const bool band_holds_discs =
          band && n_u == 0.0 && n_s != 0.0 && t_s == 0.0 && clip_inv(n_base, inv_n_s, -r, r, b0, b1) &&
          b0 <= std::min(s0c, s1c) - std::sqrt(r2) && b1 >= std::max(s0c, s1c) + std::sqrt(r2);
      if (lanes_ && !band_holds_discs) {
        band_avx2(axis, inv_n_s, inv_t_s, count, u, lo, hi, hit);
        return;
      }
      for (int k = 0; k < count; ++k) {
        if (band_holds_discs) {
          const double t0 = t_base + t_u * u[k];
          if (t0 >= 0.0 && t0 <= 1.0) {
            hit[k] = true;
            lo[k] = b0;
            hi[k] = b1;
            continue;
          }
        }
        double l = kInf, h = -kInf;
        const double xa = u[k] - x0, ha = r2 - xa * xa;
        if (ha >= 0.0) widen(l, h, s0c - std::sqrt(ha), s0c + std::sqrt(ha));
        const double xb = u[k] - x1, hb = r2 - xb * xb;
        if (hb >= 0.0) widen(l, h, s1c - std::sqrt(hb), s1c + std::sqrt(hb));
        if (band) {
          double e0 = -kInf, e1 = kInf;
          const double n0 = n_base + n_u * u[k], t0 = t_base + t_u * u[k];
          const bool in_n = n_s == 0.0 ? n0 >= -r && n0 <= r : clip_inv(n0, inv_n_s, -r, r, e0, e1);
          if (in_n && (t_s == 0.0 ? t0 >= 0.0 && t0 <= 1.0 : clip_inv(t0, inv_t_s, 0.0, 1.0, e0, e1)))
            widen(l, h, e0, e1);
        }
        hit[k] = l <= h;
        lo[k] = l;
        hi[k] = h;
      }
      return;
    }
  }
  if (upright_ball && axis == 2) {
    // The exit is never below the lower top centre: with no material above that, it is not
    // needed.
    const double floor_of_exit = std::min(f.sphere[2][2], f.sphere[3][2]);
    if (lanes_) {
      vertical_avx2(w, floor_of_exit, count, u, top, lo, hi, hit);
      return;
    }
    for (int k = 0; k < count; ++k) {
      double l = kInf, h = -kInf, a, b;
      bool lo_side, hi_side;
      if (ball_cylinder(axis, 0, u[k], w, a, b, lo_side, hi_side)) l = a;
      if (l == kInf || !lo_side) {
        sphere(0, u[k], l, h, true, false);
        sphere(1, u[k], l, h, true, false);
      }
      lo[k] = l;
      if (l == kInf) {
        hit[k] = false;
        continue;
      }
      if (top[k] <= floor_of_exit) {
        hit[k] = true;
        hi[k] = floor_of_exit;
        continue;
      }
      if (ball_cylinder(axis, 1, u[k], w, a, b, lo_side, hi_side)) h = b;
      if (h == -kInf || !hi_side) {
        sphere(2, u[k], l, h, false, true);
        sphere(3, u[k], l, h, false, true);
      }
      hit[k] = h >= l;
      hi[k] = h;
    }
    return;
  }
  if (segments_ == 2 && lanes_) {
    // material_clear first, as below, then ball_general four rays at a time.
    int todo[kLanesBlock];
    for (int first = 0; first < count; first += kLanesBlock) {
      const int n =
          not_clear_avx2(axis, w, first, std::min(count, first + kLanesBlock), u, bottom, top, false, hit, todo);
      bracket_avx2(axis, w, n, todo, u + first, lo + first, hi + first, hit + first);
    }
    return;
  }
  for (int k = 0; k < count; ++k)
    hit[k] = !material_clear(axis, u[k], w, bottom[k], top[k]) && ball_general(axis, u[k], w, lo[k], hi[k]);
}

#if defined(__x86_64__)
// The AVX2 kernels' parts (lanes.h's four lanes).
namespace {
// ball_cylinder for four rays at u = U of the row at w: ok (it meets them), [s0, s1], and
// whether each end lies on the cylinder's side (meaningful where ok).
template <class Edge>
VCUT_AVX2 void cylinder_lanes(const Edge& e, v4d U, double w, v4i& ok, v4d& s0, v4d& s1, v4i& lo_side, v4i& hi_side) {
  const v4d zero = all(0.0);
  const double y = w - e.p2;
  const v4d x = U - all(e.p1);
  const v4d md = (x * all(e.d1) + all(y * e.d2)) + all(e.e0);
  const v4d c = all(e.dd) * ((x * x + all(y * y)) + all(e.pk2)) - md * md;
  if (e.parallel) {
    ok = !(c > zero);
    s0 = all(-std::numeric_limits<double>::infinity());
    s1 = all(std::numeric_limits<double>::infinity());
  } else {
    const v4d half_b = all(e.bk) - all(e.dk) * md;
    const v4d disc = half_b * half_b - all(e.a) * c;
    ok = !(disc < zero);
    const v4d root = vsqrt(select(ok, disc, zero));
    s0 = (-half_b - root) * all(e.inv_a);
    s1 = (-half_b + root) * all(e.inv_a);
  }
  if (e.dk != 0.0) {
    const v4d t0 = -md * all(e.inv_dk), t1 = (all(e.dd) - md) * all(e.inv_dk);
    const v4i swap = t0 > t1;
    const v4d tl = select(swap, t1, t0), th = select(swap, t0, t1);
    lo_side = s0 > tl;
    hi_side = s1 < th;
    s0 = vmax(s0, tl);
    s1 = vmin(s1, th);
  } else {
    ok = ok & !((md < zero) | (md > all(e.dd)));
    lo_side = hi_side = e.parallel ? v4i{} : ~v4i{};
  }
  ok = ok & !(s0 > s1);
}
// The sphere of radius^2 r2 about `centre` (u, w, along the ray) on four rays: ok where it
// meets them, and the half chord.
VCUT_AVX2 void sphere_lanes(const double* centre, v4d U, double w, double r2, v4i& ok, v4d& root) {
  const double y = w - centre[1];
  const v4d x = U - all(centre[0]);
  const v4d h2 = (all(r2) - x * x) - all(y * y);
  ok = h2 >= all(0.0);
  root = vsqrt(select(ok, h2, all(0.0)));
}
// The entry (kEntry) or exit of four vertical rays through the capsule of an upright ball's
// edge (0: the centres', 1: the top centres'): its cylinder's, unless the rays miss the
// cylinder or leave it through an end plane, then widened by the edge's end spheres.
template <bool kEntry, class Family>
VCUT_AVX2 v4d capsule_end(const Family& f, int edge, v4d U, double w, double r2) {
  const v4d none = all(kEntry ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity());
  v4i ok, lo_side, hi_side;
  v4d s0, s1;
  cylinder_lanes(f.edge[edge], U, w, ok, s0, s1, lo_side, hi_side);
  v4d end = select(ok, kEntry ? s0 : s1, none);
  const v4i spheres = (end == none) | !(ok & (kEntry ? lo_side : hi_side));
  for (int i = 2 * edge; i < 2 * edge + 2; ++i) {
    v4i meets;
    v4d root;
    sphere_lanes(f.sphere[i], U, w, r2, meets, root);
    end = select(spheres & meets,
                 kEntry ? vmin(end, all(f.sphere[i][2]) - root) : vmax(end, all(f.sphere[i][2]) + root), end);
  }
  return end;
}
// Four rays' values: a[k0 + j] (through `index` where given), past the n-th the last again.
VCUT_AVX2 v4d lanes_of(const double* a, const int* index, int k0, int n) {
  double x[4];
  for (int j = 0; j < 4; ++j) {
    const int k = std::min(k0 + j, n - 1);
    x[j] = a[index != nullptr ? index[k] : k];
  }
  return v4d{x[0], x[1], x[2], x[3]};
}
// The four rays' results, those up to the n-th, at the same places.
VCUT_AVX2 void store_lanes(v4i hits, v4d l, v4d h, const int* index, int k0, int n, bool* hit, double* lo, double* hi) {
  for (int j = 0; j < 4 && k0 + j < n; ++j) {
    const int k = index != nullptr ? index[k0 + j] : k0 + j;
    hit[k] = hits[j] != 0;
    lo[k] = l[j];
    hi[k] = h[j];
  }
}
// clip_inv on four lanes: [e0, e1] narrowed to where v0 + s / inv stays in [a, b].
VCUT_AVX2 v4i clip_lanes(v4d v0, double inv, double a, double b, v4d& e0, v4d& e1) {
  const v4d c0 = (all(a) - v0) * all(inv), c1 = (all(b) - v0) * all(inv);
  const v4i swap = c0 > c1;
  e0 = vmax(e0, select(swap, c1, c0));
  e1 = vmin(e1, select(swap, c0, c1));
  return e0 <= e1;
}
}  // namespace

// ball_general (two segments: four spheres, four edges and the slab) for the rays todo[0 ..
// n - 1] of a row (at u[todo[j]]; lo, hi and hit at the same index), four at a time in AVX2,
// where the processor has it. Without a branch per ray: every part's interval is worked out
// and an empty one left out by a mask, with the same operations in the same order as the
// scalar code (no fused multiply-add), so the same bits. The scalar code skips the parts a
// ray misses; four lanes take all of them and still come out ahead: W5's rows of the tilted
// ball cut 3.16 -> 2.44 s, of the bull-nose (whose march this brackets) 7.8-8.2 -> 6.3 s.
__attribute__((target("avx2"))) void RaySweep::bracket_avx2(int axis, double w, int n, const int* todo, const double* u,
                                                            double* lo, double* hi, bool* hit) const {
  const BallFamily& f = ball_[axis];
  const double r = capsule_r_, r2 = r * r;
  const v4d inf = all(kInf), minus_inf = all(-kInf);
  const double bounds[3][2] = {{-r, r}, {0.0, 1.0}, {0.0, 1.0}};
  // The parts the row misses (a tilted tool's top spheres and edge stand off most rows: W5's
  // first 16 rows, 69 % of the rays): a sphere where sphere_lanes' h2 is negative for every
  // u (h2 <= r2 - y y in floating point too), an edge where the row lies a hair (1e-4 mm,
  // far above the rounding of cylinder_lanes' terms) further than r from it.
  bool sphere_meets[4], edge_meets[4];
  for (int i = 0; i < 4; ++i) {
    const double y = w - f.sphere[i][1];
    sphere_meets[i] = !(r2 - y * y < 0.0);
    const Edge& e = f.edge[i];
    constexpr double kMargin_mm = 1e-4;
    edge_meets[i] =
        w >= std::min(e.p2, e.p2 + e.d2) - r - kMargin_mm && w <= std::max(e.p2, e.p2 + e.d2) + r + kMargin_mm;
  }
  for (int k0 = 0; k0 < n; k0 += 4) {
    const v4d U = lanes_of(u, todo, k0, n);
    v4d l = inf, h = minus_inf;
    for (int i = 0; i < 4; ++i) {
      if (!sphere_meets[i]) continue;
      v4i ok;
      v4d root;
      sphere_lanes(f.sphere[i], U, w, r2, ok, root);
      const v4d c = all(f.sphere[i][2]);
      l = vmin(l, select(ok, c - root, inf));
      h = vmax(h, select(ok, c + root, minus_inf));
    }
    for (int i = 0; i < 4; ++i) {
      if (!edge_meets[i]) continue;
      v4i ok, lo_side, hi_side;
      v4d s0, s1;
      cylinder_lanes(f.edge[i], U, w, ok, s0, s1, lo_side, hi_side);
      l = vmin(l, select(ok, s0, inf));
      h = vmax(h, select(ok, s1, minus_inf));
    }
    {
      // The slab of thickness 2r over the parallelogram's inside.
      const Slab& sl = f.slab;
      v4d s0 = minus_inf, s1 = inf;
      v4i inside = ~v4i{};
      for (int j = 0; j < 3; ++j) {
        const v4d v0 = (all(sl.base[j]) + all(sl.c1[j]) * U) + all(sl.c2[j] * w);
        if (sl.flat[j]) {
          inside = inside & !((v0 < all(bounds[j][0])) | (v0 > all(bounds[j][1])));
          continue;
        }
        const v4d e0 = (all(bounds[j][0]) - v0) * all(sl.inv_slope[j]);
        const v4d e1 = (all(bounds[j][1]) - v0) * all(sl.inv_slope[j]);
        const v4i swap = e0 > e1;
        s0 = vmax(s0, select(swap, e1, e0));
        s1 = vmin(s1, select(swap, e0, e1));
      }
      const v4i ok = inside & (s0 <= s1);
      l = vmin(l, select(ok, s0, inf));
      h = vmax(h, select(ok, s1, minus_inf));
    }
    store_lanes(l <= h, l, h, todo, k0, n, hit, lo, hi);
  }
}

// material_clear (and with `in_box`, general()'s test of the ray against the sweep's box
// across the rays, the row being within it) four rays at a time, the same operations, and the
// rays kept written without a branch: a loop branching on each ray's test went wrong about
// as often as not (W5).
__attribute__((target("avx2"))) int RaySweep::not_clear_avx2(int axis, double w, int first, int end, const double* u,
                                                             const double* bottom, const double* top, bool in_box,
                                                             bool* hit, int* todo) const {
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const double pw = w - core_mid_[a2], pw_a = pw * tool_axis_[a2], pw2 = pw * pw;
  const double reach_base = capsule_r_ + half_move_mm_;
  const v4d zl = all(core_.z_low_mm), zh = all(core_.z_high_mm), inf = all(kInf), zero = all(0.0);
  const v4d u_lo = all(in_box ? bounds_.min()[a1] : -kInf), u_hi = all(in_box ? bounds_.max()[a1] : kInf);
  int n = 0;
  for (int k0 = first; k0 < end; k0 += 4) {
    const v4d U = lanes_of(u, nullptr, k0, end), B = lanes_of(bottom, nullptr, k0, end),
              T = lanes_of(top, nullptr, k0, end);
    const v4d half = all(0.5) * (T - B);
    const v4d pu = U - all(core_mid_[a1]), ps = (B + half) - all(core_mid_[axis]);
    const v4d qa = (pu * all(tool_axis_[a1]) + all(pw_a)) + ps * all(tool_axis_[axis]);
    const v4d hq = select(qa < zl, zl, select(zh < qa, zh, qa));
    const v4d reach = all(reach_base) + half;
    const v4i finite = (select(B < zero, -B, B) < inf) & (select(T < zero, -T, T) < inf);
    const v4i clear = finite & (((pu * pu + all(pw2)) + ps * ps) - hq * (all(2.0) * qa - hq) > reach * reach);
    const v4i keep = ~clear & ~((U < u_lo) | (U > u_hi));
    for (int j = 0; j < 4 && k0 + j < end; ++j) {
      hit[k0 + j] = false;
      todo[n] = k0 + j - first;
      n += keep[j] != 0;
    }
  }
  return n;
}

// The upright ball's rows (intervals_within's three ways), four rays at a time in AVX2 with
// the same operations as the scalar loops there, so the same bits: each ray's parts all
// worked out, the scalar loop's choices between them made by masks. Horizontal rays below
// both centres (first 0) or above both top centres (first 2): the capsule of that edge.
__attribute__((target("avx2"))) void RaySweep::capsule_avx2(int axis, double w, int first, int count, const double* u,
                                                            double* lo, double* hi, bool* hit) const {
  const BallFamily& f = ball_[axis];
  const double r = capsule_r_, r2 = r * r;
  const v4d inf = all(kInf), minus_inf = all(-kInf);
  for (int k0 = 0; k0 < count; k0 += 4) {
    const v4d U = lanes_of(u, nullptr, k0, count);
    v4i ok, lo_side, hi_side;
    v4d s0, s1;
    cylinder_lanes(f.edge[first / 2], U, w, ok, s0, s1, lo_side, hi_side);
    const v4d cyl_l = select(ok, vmin(inf, s0), inf), cyl_h = select(ok, vmax(minus_inf, s1), minus_inf);
    // On the cylinder's side at both ends: the capsule's boundary, the spheres not asked.
    const v4i done = ok & lo_side & hi_side;
    v4d l = cyl_l, h = cyl_h;
    for (int i = first; i <= first + 1; ++i) {
      v4i meets;
      v4d root;
      sphere_lanes(f.sphere[i], U, w, r2, meets, root);
      const v4d c = all(f.sphere[i][2]);
      l = select(meets, vmin(l, c - root), l);
      h = select(meets, vmax(h, c + root), h);
    }
    l = select(done, cyl_l, l);
    h = select(done, cyl_h, h);
    store_lanes(done | (l <= h), l, h, nullptr, k0, count, hit, lo, hi);
  }
}

// Horizontal rays between the centres' and the top centres' heights: the two discs and the
// band swept between them (not where the band alone answers: the scalar loop's quick case).
__attribute__((target("avx2"))) void RaySweep::band_avx2(int axis, double inv_n_s, double inv_t_s, int count,
                                                         const double* u, double* lo, double* hi, bool* hit) const {
  const BallFamily& f = ball_[axis];
  const double r = capsule_r_, r2 = r * r;
  const v4d inf = all(kInf), minus_inf = all(-kInf), zero = all(0.0);
  const double x0 = f.sphere[0][0], s0c = f.sphere[0][2], x1 = f.sphere[1][0], s1c = f.sphere[1][2];
  const bool band = f.slab_band;
  const double n_base = f.band_n_base, n_u = f.band_n_u, n_s = f.band_n_s;
  const double t_base = f.band_t_base, t_u = f.band_t_u, t_s = f.band_t_s;
  for (int k0 = 0; k0 < count; k0 += 4) {
    const v4d U = lanes_of(u, nullptr, k0, count);
    v4d l = inf, h = minus_inf;
    const double centres[2][2] = {{x0, s0c}, {x1, s1c}};
    for (const auto& centre : centres) {
      const v4d x = U - all(centre[0]), h2 = all(r2) - x * x;
      const v4i meets = h2 >= zero;
      const v4d root = vsqrt(select(meets, h2, zero));
      l = select(meets, vmin(l, all(centre[1]) - root), l);
      h = select(meets, vmax(h, all(centre[1]) + root), h);
    }
    if (band) {
      v4d e0 = minus_inf, e1 = inf;
      const v4d n0 = all(n_base) + all(n_u) * U, t0 = all(t_base) + all(t_u) * U;
      v4i in = n_s == 0.0 ? (n0 >= all(-r)) & (n0 <= all(r)) : clip_lanes(n0, inv_n_s, -r, r, e0, e1);
      in = in & (t_s == 0.0 ? (t0 >= zero) & (t0 <= all(1.0)) : clip_lanes(t0, inv_t_s, 0.0, 1.0, e0, e1));
      l = select(in, vmin(l, e0), l);
      h = select(in, vmax(h, e1), h);
    }
    store_lanes(l <= h, l, h, nullptr, k0, count, hit, lo, hi);
  }
}

// tilted_flat's ellipse, four rays at a time: the lines a lane's extremes break are walked in
// every lane and their crossings and corners taken only where tilted_flat takes them (the
// same lines, the same operations in the same order, no fused multiply-add), so the same bits.
// On the impeller's flat parts (the ball's flutes above it) 2 of 3 rays walk both lines t = 0
// and t = 1, all but 0.2 % some of the four lines: branches the scalar code mispredicted.
__attribute__((target("avx2"))) void RaySweep::tilted_flat_avx2(int axis, double w, int count, const double* u,
                                                                double* lo, double* hi, bool* hit) const {
  const FlatFamily& f = flat_[axis];
  const double he = f.he, hd = f.hd, EE = f.EE, ED = f.ED, DD = f.DD;
  const double R = radius_mm_, H = height_mm_;
  constexpr double kSlack = kFlatSlack_mm;
  const v4d zero = all(0.0), one = all(1.0);
  const v4i no = zero != zero;
  const double xw = w - f.p[1], xk = -f.p[2];
  for (int k0 = 0; k0 < count; k0 += 4) {
    const v4d xu = lanes_of(u, nullptr, k0, count) - all(f.p[0]);
    const v4d hw = xu * all(f.a[0]) + all(xw * f.a[1]) + all(xk * f.a[2]);
    const v4d Wu = xu - hw * all(f.a[0]), Ww = all(xw) - hw * all(f.a[1]), Wk = all(xk) - hw * all(f.a[2]);
    const v4d WE = Wu * all(f.E[0]) + Ww * all(f.E[1]) + Wk * all(f.E[2]);
    const v4d WD = Wu * all(f.D[0]) + Ww * all(f.D[1]) + Wk * all(f.D[2]);
    const v4d WW = Wu * Wu + Ww * Ww + Wk * Wk - all(R * R);
    auto q = [&](v4d s, v4d t) __attribute__((target("avx2"), always_inline)) {
      return all(EE) * s * s - all(2.0 * ED) * s * t + all(DD) * t * t + all(2.0) * WE * s - all(2.0) * WD * t + WW;
    };
    auto broken = [&](v4d s, v4d t) __attribute__((target("avx2"), always_inline)) {
      const v4d h = hw + all(he) * s - all(hd) * t;
      return ((t < all(-kSlack)) & 1) | ((t > all(1.0 + kSlack)) & 2) | ((h < all(-kSlack)) & 4) |
             ((h > all(H + kSlack)) & 8);
    };
    v4d s_lo = all(kInf), s_hi = all(-kInf);
    auto take = [&](v4i mask, v4d s) __attribute__((target("avx2"), always_inline)) {
      s_lo = select(mask, vmin(s_lo, s), s_lo);
      s_hi = select(mask, vmax(s_hi, s), s_hi);
    };
    // 1. The ellipse's extremes in s.
    const v4d B = all(2.0) * (WE - WD * all(ED) * all(f.inv_DD)), C = WW - WD * WD * all(f.inv_DD);
    const v4d disc = B * B - all(4.0 * f.A) * C;
    v4i alive = !(disc < zero);
    const v4d root = vsqrt(select(alive, disc, zero));
    v4i lines = no;
    for (const v4d s : {(-B - root) * all(f.inv_2A), (-B + root) * all(f.inv_2A)}) {
      const v4d t = (all(ED) * s + WD) * all(f.inv_DD);
      const v4i breaks = broken(s, t);
      take(alive & (breaks == 0), s);
      lines = lines | (alive & breaks);
    }
    if (!f.h_lines) alive = alive & !((hw < zero) | (hw > all(H)));
    lines = lines & alive;
    // 2. Where each such line crosses the ellipse, inside the others.
    auto cross = [&](v4i walked, v4d ps, v4d pt, double ds, double dt, double qa, v4d qb, double inv_2qa)
        __attribute__((target("avx2"), always_inline)) {
      if (!any_lane(walked)) return;
      const v4d qc = q(ps, pt);
      const v4d d = qb * qb - all(4.0 * qa) * qc;
      const v4i meets = walked & !(d < zero);
      const v4d r = vsqrt(select(meets, d, zero));
      for (const v4d lambda : {(-qb - r) * all(inv_2qa), (-qb + r) * all(inv_2qa)}) {
        const v4d s = ps + lambda * all(ds), t = pt + lambda * all(dt);
        take(meets & (broken(s, t) == 0), s);
      }
    };
    cross((lines & 1) != 0, zero, zero, 1.0, 0.0, EE, all(2.0) * WE, f.inv_2EE);             // t = 0
    cross((lines & 2) != 0, zero, one, 1.0, 0.0, EE, all(2.0) * (WE - all(ED)), f.inv_2EE);  // t = 1
    if (f.h_lines && f.qa_h > 0.0) {
      for (int i = 0; i < 2; ++i) {
        const v4i walked = (lines & (4 << i)) != 0;
        if (!any_lane(walked)) continue;
        const v4d k = (all(i == 0 ? 0.0 : H) - hw) * all(f.inv_nn);
        const v4d ps = all(he) * k, pt = all(-hd) * k;
        const v4d qb = all(2.0) * (all(EE) * ps * all(hd) - all(ED) * (ps * all(he) + pt * all(hd)) +
                                   all(DD) * pt * all(he) + WE * all(hd) - WD * all(he));
        cross(walked, ps, pt, hd, he, f.qa_h, qb, f.inv_2qa_h);
      }
    }
    // 3. The corners where a walked line meets a line of the other kind, inside the ellipse.
    if (f.corners) {
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
          const v4i walked = (lines & ((1 << i) | (4 << j))) != 0;
          if (!any_lane(walked)) continue;
          const double t = i == 0 ? 0.0 : 1.0;
          const v4d s = (all(j == 0 ? 0.0 : H) - hw + all(hd * t)) * all(f.inv_he);
          take(walked & (q(s, all(t)) <= all(kSlack * (1.0 + R * R))), s);
        }
    }
    store_lanes(alive & (s_lo <= s_hi), s_lo, s_hi, nullptr, k0, count, hit, lo, hi);
  }
}

// upright_horizontal's closed form, the row's part once and four rays at a time (the same
// operations in the same order, so the same bits): on W1's raster with a flat end mill the
// root (half) was a fifth of the kernels' time, and two divisions a ray more.
__attribute__((target("avx2"))) bool RaySweep::upright_horizontal_avx2(int axis, double w, int count, const double* u,
                                                                       double* lo, double* hi, bool* hit) const {
  const HorizontalRow row = horizontal_row(axis, w);
  if (!row.meets) {
    std::fill(hit, hit + count, false);
    return true;
  }
  if (!row.same_section) return false;
  const double c0 = row.c0, dc = row.dc, dw = row.dw, ta = row.ta, tb = row.tb, radius = row.radius;
  const double u_axis = p0_[axis == 0 ? 1 : 0];
  const bool along = std::abs(dw) <= kTiny_mm;  // the offset from the axis stays the same
  const double off = along ? 0.0 : std::abs(dc) * radius / std::sqrt(dc * dc + dw * dw) * sign(dc) * sign(dw);
  const v4d zero = all(0.0), r2 = all(radius * radius);
  for (int k0 = 0; k0 < count; k0 += 4) {
    const v4d w0 = all(u_axis) - lanes_of(u, nullptr, k0, count);
    v4d t0 = all(ta), t1 = all(tb), t_lo, t_hi;
    v4i in;
    if (along) {
      in = !(vabs(w0) > all(radius));
      t_lo = dc >= 0.0 ? t0 : t1;
      t_hi = dc >= 0.0 ? t1 : t0;
    } else {
      const v4d e0 = (all(-radius) - w0) / all(dw), e1 = (all(radius) - w0) / all(dw);
      const v4i swap = e0 > e1;
      const v4d first = select(swap, e1, e0), second = select(swap, e0, e1);
      t0 = vmax(t0, first);
      t1 = vmin(t1, second);
      in = t0 <= t1;
      const v4d a = (all(-off) - w0) / all(dw), b = (all(off) - w0) / all(dw);
      t_lo = select(a < t0, t0, select(t1 < a, t1, a));
      t_hi = select(b < t0, t0, select(t1 < b, t1, b));
    }
    auto half = [&](v4d t) __attribute__((target("avx2"), always_inline)) {
      const v4d o = w0 + t * all(dw);
      return vsqrt(vmax(zero, r2 - o * o));
    };
    store_lanes(in, all(c0) + t_lo * all(dc) - half(t_lo), all(c0) + t_hi * all(dc) + half(t_hi), nullptr, k0, count,
                hit, lo, hi);
  }
  return true;
}

// Vertical rays: the entry through the centres' capsule, the exit (where material reaches
// above floor_of_exit) through the top one.
__attribute__((target("avx2"))) void RaySweep::vertical_avx2(double w, double floor_of_exit, int count, const double* u,
                                                             const double* top, double* lo, double* hi,
                                                             bool* hit) const {
  const BallFamily& f = ball_[2];
  const double r = capsule_r_, r2 = r * r;
  for (int k0 = 0; k0 < count; k0 += 4) {
    const v4d U = lanes_of(u, nullptr, k0, count), T = lanes_of(top, nullptr, k0, count);
    const v4d l = capsule_end<true>(f, 0, U, w, r2);
    const v4i met = l != all(kInf), low = T <= all(floor_of_exit);
    v4d h = all(floor_of_exit);
    v4i hits = met & low;
    const v4i exit = met & !low;
    if (any_lane(exit)) {
      const v4d e = capsule_end<false>(f, 1, U, w, r2);
      h = select(exit, e, h);
      hits = hits | (exit & (e >= l));
    }
    store_lanes(hits, l, h, nullptr, k0, count, hit, lo, hi);
  }
}

// The same operations as upright_vertical's, lane by lane (no fused multiply-add), so the
// same bits: the disc the move's axis passes through the ray within, the ends' distances to
// the axis, and the least of t dz + underside(t) where the core holds the ray throughout (flat),
// where the move is level (at the closest approach) or where an end's slope settles it; the
// top where the material stays below the sweep's lowest top. The rays that need the search
// between the ends (and not the top) are gathered and searched four at a time, each lane
// taking the scalar search's steps until its own test ends it (on W1B, a bull-nose raster of
// ramps, the scalar searches were a fifth of the run: each step a chain of two square roots
// and three divisions). Rays that need the top take upright_vertical itself.
__attribute__((target("avx2"))) void RaySweep::upright_vertical_avx2(double w, int count, const double* u,
                                                                     const double* top, double* lo, double* hi,
                                                                     bool* hit) const {
  const double radius = radius_mm_, rc = core_.core_radius_mm, r = core_.rounding_mm;
  const double qy = w - p0_.y();
  const double dx = delta_.x(), dy = delta_.y(), dz = delta_.z();
  const double dd = dx * dx + dy * dy;
  const bool level = std::abs(dz) <= kTiny_mm;
  const double top_floor = p0_.z() + std::min(0.0, dz) + height_mm_ - core_.rounding_mm;
  const v4d zero = all(0.0), one = all(1.0), inf = all(kInf);
  auto distance_at = [&](v4d qx, v4d t) __attribute__((target("avx2"), always_inline)) {
    const v4d x = qx - t * all(dx), y = all(qy) - t * all(dy);
    return vsqrt(x * x + y * y);
  };
  auto underside_at = [&](v4d rho) __attribute__((target("avx2"), always_inline)) {
    const v4d off = vmin(all(radius), rho) - all(rc);
    const v4d under = all(r) - vsqrt(vmax(zero, all(r * r) - off * off));
    return select(off <= zero, zero, under);
  };
  // slope_at: slope + U'(rho) rho'(t), and in `second` its derivative (dropped by the compiler
  // where unused).
  auto slope_at = [&](v4d qd, v4d t, v4d rho, v4d & second) __attribute__((target("avx2"), always_inline)) {
    const v4d drho = select(rho > zero, (t * all(dd) - qd) / rho, zero);
    const v4d d2rho = select(rho > zero, (all(dd) - drho * drho) / rho, zero);
    const v4d e = rho - all(rc);
    const v4d s2 = all(r * r) - e * e;
    const v4d root = vsqrt(select(s2 > zero, s2, one));
    const v4d side = select(drho < zero, -inf, select(drho > zero, inf, all(dz)));
    second =
        select(e <= zero, zero, select(s2 <= zero, inf, all(r * r) / (s2 * root) * drho * drho + e / root * d2rho));
    return select(e <= zero, all(dz), select(s2 <= zero, side, all(dz) + e / root * drho));
  };
  // Where the ray crosses the disc the move's axis passes through: [ta, tb] (met), and qx, qd.
  auto crossing = [&](v4d U, v4d & qx, v4d & qd, v4d & ta, v4d & tb) __attribute__((target("avx2"), always_inline)) {
    qx = U - all(p0_.x());
    qd = qx * all(dx) + all(qy * dy);
    const v4d qq = qx * qx + all(qy * qy);
    const v4d disc = qd * qd - all(dd) * (qq - all(radius * radius));
    const v4i met_disc = !(disc < zero);
    const v4d root = vsqrt(select(met_disc, disc, zero));
    ta = vmax(zero, (qd - root) / all(dd));
    tb = vmin(one, (qd + root) / all(dd));
    return met_disc & !(ta > tb);
  };
  // lowest(dz)'s safeguarded Newton steps, lane by lane (slope_at's second derivative too),
  // for the rays pending[0 .. n): the least is settled by neither end, so the search runs.
  const double t_tolerance = kRaySearchTolerance_mm / std::max(1.0, std::sqrt(dd + dz * dz));
  auto search = [&](const int* pending, int n) __attribute__((target("avx2"), always_inline)) {
    for (int g = 0; g < n; g += 4) {
      v4d qx, qd, lo_t, hi_t;
      crossing(lanes_of(u, pending, g, n), qx, qd, lo_t, hi_t);
      const v4d c = qd / all(dd);
      v4d t = select(c < lo_t, lo_t, select(hi_t < c, hi_t, c));  // std::clamp
      v4i active = ~v4i{};
      for (int iteration = 0; iteration < 100; ++iteration) {
        active &= hi_t - lo_t > all(t_tolerance);
        if (!any_lane(active)) break;
        v4d second;
        const v4d d1 = slope_at(qd, t, distance_at(qx, t), second);
        const v4i below = d1 < zero;
        const v4i above = d1 > zero;
        lo_t = select(active & below, t, lo_t);
        hi_t = select(active & above, t, hi_t);
        active &= below | above;  // a zero slope: t is the least
        active &= !(vabs(d1) * (hi_t - lo_t) <= all(kGeneralSweepTolerance_mm));
        const v4d middle = all(0.5) * (lo_t + hi_t);
        v4d next = select((second > zero) & (vabs(second) <= all(std::numeric_limits<double>::max())), t - d1 / second,
                          middle);
        next = select((next > lo_t) & (next < hi_t), next, middle);
        const v4i converged = vabs(next - t) <= all(t_tolerance);
        t = select(active, next, t);
        active &= !converged;
      }
      const v4d l = all(p0_.z()) + (t * all(dz) + underside_at(distance_at(qx, t)));
      for (int j = 0; j < 4 && g + j < n; ++j) {
        const int k = pending[g + j];
        hit[k] = true;
        lo[k] = l[j];
        hi[k] = top_floor;
      }
    }
  };
  int pending[kLanesBlock];
  int n_pending = 0;
  for (int k0 = 0; k0 < count; k0 += 4) {
    const v4d T = lanes_of(top, nullptr, k0, count);
    v4d qx, qd, ta, tb;
    const v4i met = crossing(lanes_of(u, nullptr, k0, count), qx, qd, ta, tb);
    const v4d rho_a = distance_at(qx, ta), rho_b = distance_at(qx, tb);
    const v4i over_core = vmax(rho_a, rho_b) <= all(rc);
    // lowest(dz, over_core), where it needs no search (settled).
    v4d value;
    v4i settled;
    const v4d flat_value = dz >= 0.0 ? ta * all(dz) : tb * all(dz);
    if (level) {
      const v4d c = qd / all(dd);
      const v4d closest = select(c < ta, ta, select(tb < c, tb, c));
      value = select(over_core, flat_value, underside_at(distance_at(qx, closest)));
      settled = ~v4i{};
    } else {
      v4d unused;
      const v4i at_a = slope_at(qd, ta, rho_a, unused) >= zero;
      const v4i at_b = slope_at(qd, tb, rho_b, unused) <= zero;
      value = select(at_a, ta * all(dz) + underside_at(rho_a), tb * all(dz) + underside_at(rho_b));
      value = select(over_core, flat_value, value);
      settled = over_core | at_a | at_b;
    }
    const v4i low = T <= all(top_floor);
    const v4d l = all(p0_.z()) + value;
    for (int j = 0; j < 4 && k0 + j < count; ++j) {
      const int k = k0 + j;
      if (!met[j]) {
        hit[k] = false;
      } else if (settled[j] && low[j]) {
        hit[k] = true;
        lo[k] = l[j];
        hi[k] = top_floor;
      } else if (low[j]) {
        pending[n_pending++] = k;
        if (n_pending == kLanesBlock) {
          search(pending, n_pending);
          n_pending = 0;
        }
      } else {
        hit[k] = upright_vertical(u[k], w, top[k], lo[k], hi[k]);
      }
    }
  }
  search(pending, n_pending);
}

// upright_ramp on a row's rays four at a time: ramp_span's T (its clips of the rows' heights
// worked out once a row) and the section at T's ends, then the searches of the extremes no end
// of T settles, gathered and run four at a time, each lane taking ramp_search's steps
// (ramp_section's operations in the same order) until its own test ends it. A ray whose
// search fails takes general(), as upright_horizontal does. (On W1B the ramps' searches were
// a fifth of the run, and T with its ends another fifth once the searches ran in lanes.)
__attribute__((target("avx2"))) bool RaySweep::upright_ramps_avx2(int axis, double w, int count, const double* u,
                                                                  const double* bottom, const double* top, double* lo,
                                                                  double* hi, bool* hit) const {
  const HorizontalRow row = horizontal_row(axis, w);
  if (!row.meets || row.same_section) return false;
  if (cone_) {  // a V-bit's ramp: upright_horizontal takes cone_interval itself
    cone_intervals_avx2(axis, w, count, nullptr, u, lo, hi, hit);
    return true;
  }
  if (!upright_march_ || row.dh == 0.0 || count > kLanesBlock) return false;
  const double c0 = row.c0, dc = row.dc, dw = row.dw, h0 = row.h0, dh = row.dh;
  const double u_axis = p0_[axis == 0 ? 1 : 0];
  const double Rc = core_.core_radius_mm, r = core_.rounding_mm, zl = core_.z_low_mm, zh = core_.z_high_mm;
  // The searches: the ray's w0, the extreme (s), T and the first best; then their outcome.
  double job_w0[2 * kLanesBlock], job_s[2 * kLanesBlock], job_t1[2 * kLanesBlock], job_t2[2 * kLanesBlock],
      job_best[2 * kLanesBlock], job_value[2 * kLanesBlock];
  bool job_found[2 * kLanesBlock];
  int n = 0;
  // Per ray: its extremes' values where settled, and the jobs of those that are not (-1: none).
  double entry[kLanesBlock], exit[kLanesBlock];
  int entry_job[kLanesBlock], exit_job[kLanesBlock];
  const v4d zero = all(0.0), inf = all(kInf);
  // ramp_section at t, four rays (w0) at a time: half, its slope and second derivative, and
  // where they are finite.
  auto section = [&](v4d w0, v4d t, v4d & half, v4d & d1, v4d & d2) __attribute__((target("avx2"), always_inline)) {
    const v4d h = all(h0) + t * all(dh), off = w0 + t * all(dw);
    const v4i below = h < all(zl), above = (!below) & (h > all(zh));
    const v4d e = select(below, all(zl) - h, select(above, h - all(zh), zero));
    const v4d e1 = select(below, all(-dh), select(above, all(dh), zero));
    const v4d sigma = vsqrt(vmax(zero, all(r * r) - e * e));
    const v4d rho = all(Rc) + sigma, q = rho * rho - off * off;
    half = vsqrt(vmax(zero, q));
    const v4d s1 = -e * e1 / sigma, s2 = -e1 * e1 * all(r) * all(r) / (sigma * sigma * sigma);
    const v4d q1 = all(2.0) * (rho * s1 - off * all(dw)), q2 = all(2.0) * (s1 * s1 + rho * s2 - all(dw * dw));
    d1 = q1 / (all(2.0) * half);
    d2 = q2 / (all(2.0) * half) - q1 * q1 / (all(4.0) * half * half * half);
    return (sigma > zero) & (half > zero);
  };
  // ramp_span's T and ends, four rays at a time. clip()'s bounds along the line's height are
  // the row's; add()'s and clip()'s max and min in the same order (exact either way).
  const double ta = row.ta, tb = row.tb;
  auto clip_height = [&](double y_lo, double y_hi, double& e0, double& e1) {
    e0 = (y_lo - h0) / dh;  // dh != 0: the section changes
    e1 = (y_hi - h0) / dh;
    if (e0 > e1) std::swap(e0, e1);
  };
  const double x_halves[2] = {Rc + r, Rc}, y_los[2] = {zl, zl - r}, y_his[2] = {zh, zh + r};
  double h_e0[2], h_e1[2];
  for (int i = 0; i < 2; ++i) clip_height(y_los[i], y_his[i], h_e0[i], h_e1[i]);
  const double A = dw * dw + dh * dh;
  const double h_lo = h0 + std::min(ta * dh, tb * dh), h_hi = h0 + std::max(ta * dh, tb * dh);
  const double off_min = std::min(ta * dw, tb * dw), off_max = std::max(ta * dw, tb * dw);
  for (int k0 = 0; k0 < count; k0 += 4) {
    const v4d w0 = all(u_axis) - lanes_of(u, nullptr, k0, count);
    v4d t1 = inf, t2 = -inf;
    auto add = [&](v4i in, v4d a, v4d b) __attribute__((target("avx2"), always_inline)) {
      a = vmax(a, all(ta));
      b = vmin(b, all(tb));
      const v4i keep = in & (a <= b);
      t1 = select(keep, vmin(t1, a), t1);
      t2 = select(keep, vmax(t2, b), t2);
    };
    for (int i = 0; i < 2; ++i) {  // the two rectangles
      v4d a = -inf, b = inf;
      v4i in;
      if (dw == 0.0) {
        in = (w0 >= all(-x_halves[i])) & (w0 <= all(x_halves[i]));
      } else {
        v4d e0 = (all(-x_halves[i]) - w0) / all(dw), e1 = (all(x_halves[i]) - w0) / all(dw);
        const v4i swap = e0 > e1;
        const v4d first = select(swap, e1, e0), second = select(swap, e0, e1);
        a = vmax(a, first);
        b = vmin(b, second);
        in = a <= b;
      }
      a = vmax(a, all(h_e0[i]));
      b = vmin(b, all(h_e1[i]));
      in &= a <= b;
      add(in, a, b);
    }
    const v4d off_lo = w0 + all(off_min), off_hi = w0 + all(off_max);
    for (const double cx : {-Rc, Rc})
      for (const double cy : {zl, zh}) {
        if (h_hi < cy - r || h_lo > cy + r) continue;
        const v4i near = (!(off_hi < all(cx - r))) & (!(off_lo > all(cx + r)));
        if (!any_lane(near)) continue;
        const v4d px = w0 - all(cx);
        const double py = h0 - cy;
        const v4d B = px * all(dw) + all(py * dh), C = px * px + all(py * py) - all(r * r);
        const v4d disc = B * B - all(A) * C;
        const v4i meets = near & !(disc < zero);
        const v4d root = vsqrt(select(meets, disc, zero));
        add(meets, (-B - root) / all(A), (-B + root) / all(A));
      }
    const v4i met = t1 <= t2;
    v4d half1, slope1, half2, slope2, unused;
    const v4i finite1 = section(w0, select(met, t1, zero), half1, slope1, unused);
    const v4i finite2 = section(w0, select(met, t2, zero), half2, slope2, unused);
    for (int j = 0; j < 4 && k0 + j < count; ++j) {
      const int k = k0 + j;
      entry_job[k] = exit_job[k] = -1;
      hit[k] = met[j] != 0;
      if (!hit[k]) continue;
      RampSpan span;
      span.t1 = t1[j];
      span.t2 = t2[j];
      span.half1 = half1[j];
      span.slope1 = slope1[j];
      span.half2 = half2[j];
      span.slope2 = slope2[j];
      span.finite1 = finite1[j] != 0;
      span.finite2 = finite2[j] != 0;
      const double w0k = w0[j];
      for (int side = 0; side < 2; ++side) {
        const double s = side == 0 ? 1.0 : -1.0;
        double& value = side == 0 ? entry[k] : exit[k];
        double best;
        if (ramp_settled(span, s, c0, dc, value, best)) continue;
        (side == 0 ? entry_job : exit_job)[k] = n;
        job_w0[n] = w0k;
        job_s[n] = s;
        job_t1[n] = span.t1;
        job_t2[n] = span.t2;
        job_best[n] = best;
        ++n;
      }
    }
  }
  for (int g = 0; g < n; g += 4) {
    const v4d w0 = lanes_of(job_w0, nullptr, g, n), s = lanes_of(job_s, nullptr, g, n);
    v4d a = lanes_of(job_t1, nullptr, g, n), b = lanes_of(job_t2, nullptr, g, n);
    v4d best = lanes_of(job_best, nullptr, g, n), value = zero;
    v4d t = all(0.5) * (a + b);
    v4i active = ~v4i{}, found = v4i{};
    for (int step = 0; step < 60 && any_lane(active); ++step) {
      v4d half, d1, d2;
      active &= section(w0, t, half, d1, d2);  // else the search fails
      // ramp_search's step.
      const v4d f = s * (all(c0) + t * all(dc)) - half;
      best = select(active, vmin(best, f), best);
      const v4d slope = s * all(dc) - d1, g2 = -d2;
      const v4i falls = slope < zero;
      a = select(active & falls, t, a);
      b = select(active & !falls, t, b);
      const v4i done = active & (vabs(slope) * (b - a) <= all(kGeneralSweepTolerance_mm));
      value = select(done, best, value);
      found |= done;
      active &= !done;
      v4d next = select(g2 > zero, t - slope / g2, a);
      next = select((next > a) & (next < b), next, all(0.5) * (a + b));
      t = select(active, next, t);
    }
    for (int j = 0; j < 4 && g + j < n; ++j) {
      job_found[g + j] = found[j] != 0;
      job_value[g + j] = value[j];
    }
  }
  for (int k = 0; k < count; ++k) {
    if (!hit[k]) continue;
    // upright_ramp's outcome: decided where both extremes were found (the entry's search
    // failing decides as the exit's would: general() either way).
    const bool entry_found = entry_job[k] < 0 || job_found[entry_job[k]];
    const bool exit_found = exit_job[k] < 0 || job_found[exit_job[k]];
    if (!entry_found || !exit_found) {
      hit[k] = general(axis, ray_point(axis, u[k], w, 0.0), bottom[k], top[k], lo[k], hi[k]);
      continue;
    }
    lo[k] = entry_job[k] < 0 ? entry[k] : job_value[entry_job[k]];
    hi[k] = -(exit_job[k] < 0 ? exit[k] : job_value[exit_job[k]]);
  }
  return true;
}

// cone_interval on the rays index[0 .. n) (all of the first n without an index) four at a
// time: every conic's roots in lanes (quadratic_roots' cases as masks, its copysign by the
// sign bit), each candidate taken where its lane's tests hold, the operations of the scalar
// code in the same order. (V5's cut was three quarters cone_interval, ray by ray.)
__attribute__((target("avx2"))) void RaySweep::cone_intervals_avx2(int axis, double w, int n, const int* index,
                                                                   const double* u, double* lo, double* hi,
                                                                   bool* hit) const {
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const ConeFamily& f = cone_family_[axis];
  const double r = cone_r_mm_, H = height_mm_, cone_top = cone_top_mm_;
  constexpr double kTol_mm = 1e-9, kTolT = 1e-12;
  const v4d zero = all(0.0), inf = all(kInf);
  const v4d sign_bit = all(-0.0);
  // quadratic_roots(a, b, c) with 1 / a: the roots, and the lanes with at least one and with two.
  auto roots_of = [&](double a, v4d b, v4d c, double inv_a, v4d& root0, v4d& root1, v4i& one, v4i& two)
      __attribute__((target("avx2"), always_inline)) {
    if (a == 0.0) {
      one = b != zero;
      root0 = -c / (all(2.0) * b);
      root1 = zero;
      two = v4i{};
      return;
    }
    v4d disc = b * b - all(a) * c;
    const v4i negative = disc < zero;
    const v4i none = negative & (disc < all(-1e-12) * vmax(b * b, vabs(all(a) * c)));
    disc = select(negative, zero, disc);
    const v4d root = vsqrt(disc);
    const v4d signed_root = (v4d)(((v4i)root & ~(v4i)sign_bit) | ((v4i)b & (v4i)sign_bit));  // std::copysign
    const v4d q = -(b + signed_root);
    const v4i q_zero = q == zero;
    root0 = select(q_zero, zero, q * all(inv_a));
    root1 = c / q;
    one = !none;
    two = (!none) & (!q_zero);
  };
  for (int k0 = 0; k0 < n; k0 += 4) {
    const v4d U = lanes_of(u, index, k0, n);
    // cone_interval.
    const v4d w0_1 = U - all(p0_[a1]);
    const double w0_2 = w - p0_[a2];
    const v4d A0 = w0_1 * all(f.a1) + all(w0_2 * f.a2);
    const double A1 = f.A1, A2 = f.A2;
    const v4d wd = w0_1 * all(f.d1) + all(w0_2 * f.d2), ww = w0_1 * w0_1 + all(w0_2 * w0_2);
    struct LaneConic {
      double ss, st, tt;
      v4d s, t, c;
    };
    auto conic = [&](int j) __attribute__((target("avx2"), always_inline)) {
      const double c = f.c[j];
      return LaneConic{f.ss[j],
                       f.st[j],
                       f.tt[j],
                       all(-c) * A0 * all(A1),
                       -wd + all(c) * A0 * all(A2),
                       ww - all(c) * A0 * A0 - all(f.kappa[j])};
    };
    const LaneConic cone = conic(0), cylinder = conic(1);
    auto at = [&](const LaneConic& q, v4d x, v4d y) __attribute__((target("avx2"), always_inline)) {
      return (all(q.ss) * x + all(2.0) * (all(q.st) * y + q.s)) * x + (all(q.tt) * y + all(2.0) * q.t) * y + q.c;
    };
    auto on_line = [&](const LaneConic& q, v4d x, v4d y, double dx, double dy, double a, double inv_a, v4d& root0,
                       v4d& root1, v4i& one, v4i& two) __attribute__((target("avx2"), always_inline)) {
      const v4d qb = all(q.ss) * x * all(dx) + all(q.st) * (x * all(dy) + y * all(dx)) + all(q.tt) * y * all(dy) +
                     q.s * all(dx) + q.t * all(dy);
      roots_of(a, qb, at(q, x, y), inv_a, root0, root1, one, two);
    };
    v4d s_lo = inf, s_hi = -inf;
    auto take = [&](v4i valid, v4d s, v4d t, double y_lo, double y_hi) __attribute__((target("avx2"), always_inline)) {
      valid &= (t >= all(-kTolT)) & (t <= all(1.0 + kTolT));
      const v4d y = A0 + all(A1) * s - all(A2) * t;
      valid &= (y >= all(y_lo - kTol_mm)) & (y <= all(y_hi + kTol_mm));
      s_lo = select(valid, vmin(s_lo, s), s_lo);
      s_hi = select(valid, vmax(s_hi, s), s_hi);
    };
    v4d root0, root1;
    v4i one, two;
    // Where each conic runs square to s (its derivative in t zero).
    for (int which = 0; which < 2; ++which) {
      const LaneConic& q = which == 0 ? cone : cylinder;
      if (q.tt == 0.0) continue;
      roots_of(f.lead[which], q.s * all(q.tt) - all(q.st) * q.t, q.c * all(q.tt) - q.t * q.t, f.inv_lead[which], root0,
               root1, one, two);
      const double y_lo = which == 0 ? 0.0 : cone_top, y_hi = which == 0 ? cone_top : H;
      take(one, root0, -(all(q.st) * root0 + q.t) * all(f.inv_tt[which]), y_lo, y_hi);
      take(two, root1, -(all(q.st) * root1 + q.t) * all(f.inv_tt[which]), y_lo, y_hi);
    }
    // Each conic against the first and last instance.
    for (const double t : {0.0, 1.0})
      for (int which = 0; which < 2; ++which) {
        on_line(which == 0 ? cone : cylinder, zero, all(t), 1.0, 0.0, f.ss[which], f.inv_ss[which], root0, root1, one,
                two);
        const double y_lo = which == 0 ? 0.0 : cone_top, y_hi = which == 0 ? cone_top : H;
        take(one, root0, all(t), y_lo, y_hi);
        take(two, root1, all(t), y_lo, y_hi);
      }
    // The cylinder against the top and where it meets the cone.
    if (A1 != 0.0 || A2 != 0.0) {
      for (int line = 0; line < (cone_top < H ? 2 : 1); ++line) {
        const double height = line == 0 ? H : cone_top;
        const v4d x = f.along_s ? (all(height) - A0) * all(f.inv_A1) : zero;
        const v4d y = f.along_s ? zero : (A0 - all(height)) * all(f.inv_A2);
        on_line(cylinder, x, y, A2, A1, f.line_lead, f.inv_line_lead, root0, root1, one, two);
        take(one, x + root0 * all(A2), y + root0 * all(A1), height, height);
        take(two, x + root1 * all(A2), y + root1 * all(A1), height, height);
      }
    }
    // The top's centre line at the first and last instance, where it lies in the top disc.
    const double cylinder_tol = 2.0 * r * kTol_mm;
    if (A1 != 0.0)
      for (const double t : {0.0, 1.0}) {
        const v4d s = (all(H) - A0 + all(A2 * t)) * all(f.inv_A1);
        take(at(cylinder, s, all(t)) <= all(cylinder_tol), s, all(t), H, H);
      }
    const v4i found = s_lo <= s_hi;
    const v4d entry_mm = s_lo + all(p0_[axis]), exit_mm = s_hi + all(p0_[axis]);
    for (int j = 0; j < 4 && k0 + j < n; ++j) {
      const int k = index != nullptr ? index[k0 + j] : k0 + j;
      hit[k] = found[j] != 0;
      if (!hit[k]) continue;
      lo[k] = entry_mm[j];
      hi[k] = exit_mm[j];
    }
  }
}

namespace {
// RaySweep::tilted_windows four rays at a time (n a multiple of four): tilted_window's
// products, sums and pairwise max / min in the same order, the tests negated as written (so a
// NaN goes as it would).
__attribute__((target("avx2"))) int tilted_windows_avx2(const RaySweep::TiltRow& row, int n, const double* u,
                                                        const double* bottom, const double* top, int* index, double* lo,
                                                        double* hi) {
  const v4d u_min = all(row.u_min), u_max = all(row.u_max);
  const v4d s0 = all(row.slope[0]), s1 = all(row.slope[1]), s2 = all(row.slope[2]);
  const v4d lo0 = all(row.c_lo[0]), lo1 = all(row.c_lo[1]), lo2 = all(row.c_lo[2]);
  const v4d hi0 = all(row.c_hi[0]), hi1 = all(row.c_hi[1]), hi2 = all(row.c_hi[2]);
  int kept = 0, j = 0;
  for (; j < n; j += 4) {
    const v4d U = vload(u + j), B = vload(bottom + j), T = vload(top + j);
    const v4d along0 = s0 * U, along1 = s1 * U, along2 = s2 * U;
    const v4d l = vmax(vmax(lo0 + along0, lo1 + along1), lo2 + along2);
    const v4d h = vmin(vmin(hi0 + along0, hi1 + along1), hi2 + along2);
    const v4i meets = (U >= u_min) & (U <= u_max) & (l <= h) & ~(B >= h) & ~(T <= l);
    if (!any_lane(meets)) continue;
    for (int q = 0; q < 4; ++q)
      if (meets[q] != 0) {
        index[kept] = j + q;
        lo[kept] = l[q];
        hi[kept] = h[q];
        ++kept;
      }
  }
  return kept;
}
}  // namespace

#else
// Never called (lanes_ is false off x86-64): defined for the linker.
int RaySweep::not_clear_avx2(int, double, int, int, const double*, const double*, const double*, bool, bool*,
                             int*) const {
  return 0;
}
void RaySweep::bracket_avx2(int, double, int, const int*, const double*, double*, double*, bool*) const {}
void RaySweep::capsule_avx2(int, double, int, int, const double*, double*, double*, bool*) const {}
void RaySweep::band_avx2(int, double, double, int, const double*, double*, double*, bool*) const {}
void RaySweep::vertical_avx2(double, double, int, const double*, const double*, double*, double*, bool*) const {}
void RaySweep::tilted_flat_avx2(int, double, int, const double*, double*, double*, bool*) const {}
bool RaySweep::upright_horizontal_avx2(int, double, int, const double*, double*, double*, bool*) const { return false; }
bool RaySweep::upright_ramps_avx2(int, double, int, const double*, const double*, const double*, double*, double*,
                                  bool*) const {
  return false;
}
void RaySweep::cone_intervals_avx2(int, double, int, const int*, const double*, double*, double*, bool*) const {}
void RaySweep::upright_vertical_avx2(double, int, const double*, const double*, double*, double*, bool*) const {}
#endif

int RaySweep::tilted_windows(const TiltRow& row, int n, const double* u, const double* bottom, const double* top,
                             int* index, double* lo, double* hi, bool lanes) {
  int kept = 0, j = 0;
#if defined(__x86_64__)
  if (lanes && kHaveAvx2) {
    j = n / 4 * 4;
    kept = tilted_windows_avx2(row, j, u, bottom, top, index, lo, hi);
  }
#endif
  for (; j < n; ++j)
    if (tilted_window(row, u[j], lo[kept], hi[kept]) && !(bottom[j] >= hi[kept]) && !(top[j] <= lo[kept]))
      index[kept++] = j;
  return kept;
}

bool RaySweep::interval(int axis, double u, double w, double& lo, double& hi) const {
  switch (method_) {
    case Method::Ball:
    case Method::General:
      return interval_within(axis, u, w, -kInf, kInf, lo, hi);
    case Method::Upright:
      return axis == 2 ? upright_vertical(u, w, kInf, lo, hi) : upright_horizontal(axis, u, w, -kInf, kInf, lo, hi);
  }
  return false;
}

bool RaySweep::upright_vertical(double u, double w, double top, double& lo, double& hi) const {
  const double radius = radius_mm_;
  const double qx = u - p0_.x(), qy = w - p0_.y();
  const double dx = delta_.x(), dy = delta_.y(), dz = delta_.z();
  const double dd = dx * dx + dy * dy, qd = qx * dx + qy * dy, qq = qx * qx + qy * qy;
  // The part of the move during which the line passes through the cutter's disc.
  double ta = 0.0, tb = 1.0;
  if (dd <= kTiny_mm * kTiny_mm) {
    if (qq > radius * radius) return false;
  } else {
    const double disc = qd * qd - dd * (qq - radius * radius);
    if (disc < 0.0) return false;
    const double root = std::sqrt(disc);
    ta = std::max(0.0, (qd - root) / dd);
    tb = std::min(1.0, (qd + root) / dd);
    if (ta > tb) return false;
  }
  // Height of the cutter's underside above its tip at the line, at move parameter t; the
  // top mirrors it (rounded top of the core model), except a V-bit's, which is flat.
  // (The root of the sum of squares, not hypot: no overflow at mm scale, and hypot was 11 % of
  // a bull-nose ramp's cut.)
  auto distance_at = [&](double t) {
    const double x = qx - t * dx, y = qy - t * dy;
    return std::sqrt(x * x + y * y);
  };
  // underside_height's own arithmetic for a flat, ball or bull-nose (the core's radius and
  // rounding kept here), its call for a V-bit.
  const bool vbit = cutter_.type == CutterType::VBit;
  auto underside_at = [&](double rho) {
    if (vbit) return underside_height(cutter_, std::min(radius, rho));
    const double off = std::min(radius, rho) - core_.core_radius_mm;
    return off <= 0.0 ? 0.0
                      : core_.rounding_mm - std::sqrt(std::max(0.0, core_.rounding_mm * core_.rounding_mm - off * off));
  };
  auto underside = [&](double t) { return underside_at(distance_at(t)); };
  const bool flat_top = cutter_.type == CutterType::VBit || flat_bottom_;
  const double t_tolerance = kRaySearchTolerance_mm / std::max(1.0, std::sqrt(dd + dz * dz));
  // min over [ta, tb] of t*slope + height(t): convex (the underside is a convex function
  // of the distance to the axis, itself convex in t).
  // Its derivative g'(t) = slope + U'(rho) rho'(t), and g'' in `second` (U the underside
  // as a function of the distance rho to the axis; infinite where the side is vertical).
  const double rc = core_.core_radius_mm, r = core_.rounding_mm;
  const double cone = cutter_.type == CutterType::VBit ? 1.0 / cone_k_ : 0.0;  // cone_k_: the tangent, once
  auto slope_at = [&](double slope, double t, double rho, double& second) {
    const double drho = rho > 0.0 ? (t * dd - qd) / rho : 0.0;
    const double d2rho = rho > 0.0 ? (dd - drho * drho) / rho : 0.0;
    if (cutter_.type == CutterType::VBit) {
      second = cone * d2rho;
      return slope + cone * drho;
    }
    const double e = rho - rc;
    if (e <= 0.0) {
      second = 0.0;
      return slope;
    }
    const double s2 = r * r - e * e;
    if (s2 <= 0.0) {
      second = kInf;
      return drho < 0.0 ? -kInf : (drho > 0.0 ? kInf : slope);
    }
    const double root = std::sqrt(s2);
    second = r * r / (s2 * root) * drho * drho + e / root * d2rho;
    return slope + e / root * drho;
  };
  // The ends' distances to the axis, worked out once for both searches (a flat end mill's
  // underside is flat: none needed).
  const double rho_a = flat_bottom_ ? 0.0 : distance_at(ta), rho_b = flat_bottom_ ? 0.0 : distance_at(tb);
  // min over [ta, tb] of g(t) = t*slope + underside(t): g is convex, so its derivative
  // rises through zero once; safeguarded Newton steps on it from the closest approach,
  // halving the bracket where a step would leave it.
  auto lowest = [&](double slope, bool flat) {
    if (flat) return slope >= 0.0 ? ta * slope : tb * slope;
    if (std::abs(slope) <= kTiny_mm) return underside(dd > 0.0 ? std::clamp(qd / dd, ta, tb) : ta);
    const auto g = [&](double t) { return t * slope + underside(t); };
    double second;
    if (slope_at(slope, ta, rho_a, second) >= 0.0) return ta * slope + underside_at(rho_a);
    if (slope_at(slope, tb, rho_b, second) <= 0.0) return tb * slope + underside_at(rho_b);
    double lo_t = ta, hi_t = tb;
    double t = dd > 0.0 ? std::clamp(qd / dd, ta, tb) : 0.5 * (ta + tb);
    for (int iteration = 0; iteration < 100 && hi_t - lo_t > t_tolerance; ++iteration) {
      const double d1 = slope_at(slope, t, distance_at(t), second);
      if (d1 < 0.0)
        lo_t = t;
      else if (d1 > 0.0)
        hi_t = t;
      else
        break;
      // g is convex and t an end of the bracket, which holds the least: g(t) exceeds it by
      // at most |g'(t)| times the bracket's width.
      if (std::abs(d1) * (hi_t - lo_t) <= kGeneralSweepTolerance_mm) break;
      double next = second > 0.0 && std::isfinite(second) ? t - d1 / second : 0.5 * (lo_t + hi_t);
      if (!(next > lo_t && next < hi_t)) next = 0.5 * (lo_t + hi_t);
      const bool converged = std::abs(next - t) <= t_tolerance;
      t = next;
      if (converged) break;
    }
    return g(t);
  };
  // Where the line stays over the flat core of a bull-nose's underside for the whole move
  // (the distance to the axis is convex in t: largest at the ends), the underside is flat.
  // (A flat end mill's underside is flat anyway: no distances to work out.)
  const bool over_core = !vbit && !flat_bottom_ && std::max(rho_a, rho_b) <= core_.core_radius_mm;
  lo = p0_.z() + lowest(dz, flat_bottom_ || over_core);
  // The top lies at least H - r (H with a flat top) above the lowest tip: material below
  // that needs no search for it (a value between the material's top and the sweep's will do).
  const double top_floor = p0_.z() + std::min(0.0, dz) + height_mm_ - (flat_top ? 0.0 : core_.rounding_mm);
  hi = top <= top_floor ? top_floor : p0_.z() + height_mm_ - lowest(-dz, flat_top || over_core);
  return true;
}

RaySweep::HorizontalRow RaySweep::horizontal_row(int axis, double w) const {
  HorizontalRow row;
  const int across = axis == 0 ? 1 : 0;  // the other horizontal axis, where u lies
  row.c0 = p0_[axis];
  row.dc = delta_[axis];
  row.dw = delta_[across];
  row.h0 = w - p0_.z();  // the line's height above the tip
  row.dh = -delta_.z();
  if (std::abs(row.dh) <= kTiny_mm) {
    if (row.h0 < 0.0 || row.h0 > height_mm_) return row;
  } else if (!clip(row.h0, row.dh, 0.0, height_mm_, row.ta, row.tb)) {
    return row;
  }
  row.meets = true;
  // Heights above the tip where the section is the full radius.
  const double full_lo = cutter_.type == CutterType::VBit ? underside_height(cutter_, radius_mm_) : core_.z_low_mm;
  const double full_hi = cutter_.type == CutterType::VBit ? height_mm_ : core_.z_high_mm;
  const double h_a = row.h0 + row.ta * row.dh, h_b = row.h0 + row.tb * row.dh;
  const bool full_section = std::min(h_a, h_b) >= full_lo && std::max(h_a, h_b) <= full_hi;
  row.same_section = flat_bottom_ || full_section || std::abs(row.dh) <= kTiny_mm;
  if (row.same_section)
    row.radius = section_radius(cutter_, std::clamp(row.h0 + 0.5 * (row.ta + row.tb) * row.dh, 0.0, height_mm_));
  return row;
}

bool RaySweep::upright_horizontal(int axis, double u, double w, double bottom, double top, double& lo,
                                  double& hi) const {
  const HorizontalRow row = horizontal_row(axis, w);
  if (!row.meets) return false;
  const double c0 = row.c0, dc = row.dc, w0 = p0_[axis == 0 ? 1 : 0] - u, dw = row.dw, h0 = row.h0, dh = row.dh;
  double ta = row.ta, tb = row.tb;
  if (row.same_section) {
    // The section does not change along the move: a disc swept along a segment in the
    // plane of the line, whose extent along the line has a closed form.
    const double radius = row.radius;
    if (std::abs(dw) <= kTiny_mm) {
      if (std::abs(w0) > radius) return false;
    } else if (!clip(w0, dw, -radius, radius, ta, tb)) {
      return false;
    }
    auto half = [&](double t) {
      const double off = w0 + t * dw;
      return std::sqrt(std::max(0.0, radius * radius - off * off));
    };
    double t_lo, t_hi;
    if (std::abs(dw) <= kTiny_mm) {
      t_lo = dc >= 0.0 ? ta : tb;
      t_hi = dc >= 0.0 ? tb : ta;
    } else {
      // Stationary points of c(t) -/+ half(t): the offset where the disc's edge runs
      // parallel to the line.
      // (The root of the sum of squares, not hypot, as above: hypot was 2 % of the S-piece's cut.)
      const double off = std::abs(dc) * radius / std::sqrt(dc * dc + dw * dw) * sign(dc) * sign(dw);
      t_lo = std::clamp((-off - w0) / dw, ta, tb);
      t_hi = std::clamp((off - w0) / dw, ta, tb);
    }
    lo = c0 + t_lo * dc - half(t_lo);
    hi = c0 + t_hi * dc + half(t_hi);
    return true;
  }
  // A V-bit or a bull-nose moving up or down: the section changes along the move. The cone's
  // closed form; the bull-nose's march (a flat end mill's section never changes, a ball is
  // the ball method's), prepared for it (upright_march_).
  if (cone_) return cone_interval(axis, u, w, lo, hi);
  assert(upright_march_);
  bool decided = false;
  const bool hit = upright_ramp(c0, dc, w0, dw, h0, dh, ta, tb, lo, hi, decided);
  return decided ? hit : general(axis, ray_point(axis, u, w, 0.0), bottom, top, lo, hi);
}

// The instances that meet the line are those whose section there reaches it: (off(t), h(t))
// in the tool's axial section, the core's rectangle [-Rc, Rc] x [zl, zh] grown by r, which is
// two slabs' cross and four corner discs; each meets the line's path (off, h) over an interval
// of t in closed form, and they over T, the hull. Instance t meets the line over c(t) -/+
// half(t), half = sqrt(rho^2 - off^2). The sweep is convex, so over T the entry c - half is
// convex in t and the exit c + half concave (the set of (s, t) with the line's point s in
// instance t is convex, and these are its lower and upper edges): each extreme is an end of T
// whose slope points away from the other, else found by Newton's steps on the slope within a
// bracket (bisection where a step would leave it), to within kGeneralSweepTolerance_mm of the
// value by the tangent's bound. W1's raster with a D6 r1 bull-nose ramps in every move: the
// march took two root searches a ray, each of about four distances, each a search along the
// move.
bool RaySweep::ramp_span(double w0, double dw, double h0, double dh, double ta, double tb, RampSpan& span) const {
  const double Rc = core_.core_radius_mm, r = core_.rounding_mm, zl = core_.z_low_mm, zh = core_.z_high_mm;
  double t1 = kInf, t2 = -kInf;
  auto add = [&](double a, double b) {
    a = std::max(a, ta);
    b = std::min(b, tb);
    if (a <= b) {
      t1 = std::min(t1, a);
      t2 = std::max(t2, b);
    }
  };
  auto rectangle = [&](double x_half, double y_lo, double y_hi) {
    double a = -kInf, b = kInf;
    if (clip(w0, dw, -x_half, x_half, a, b) && clip(h0, dh, y_lo, y_hi, a, b)) add(a, b);
  };
  rectangle(Rc + r, zl, zh);
  rectangle(Rc, zl - r, zh + r);
  const double A = dw * dw + dh * dh;  // > 0: the line's height changes (dh != 0)
  // The corner discs the path's box over [ta, tb] meets (the top ones mostly not).
  const double h_lo = h0 + std::min(ta * dh, tb * dh), h_hi = h0 + std::max(ta * dh, tb * dh);
  const double off_lo = w0 + std::min(ta * dw, tb * dw), off_hi = w0 + std::max(ta * dw, tb * dw);
  for (const double cx : {-Rc, Rc})
    for (const double cy : {zl, zh}) {
      if (h_hi < cy - r || h_lo > cy + r || off_hi < cx - r || off_lo > cx + r) continue;
      const double px = w0 - cx, py = h0 - cy;
      const double B = px * dw + py * dh, C = px * px + py * py - r * r;
      const double disc = B * B - A * C;
      if (disc < 0.0) continue;
      const double root = std::sqrt(disc);
      add((-B - root) / A, (-B + root) / A);
    }
  if (!(t1 <= t2)) return false;
  span.t1 = t1;
  span.t2 = t2;
  // T's ends, for both extremes.
  double unused;  // the second derivative, not needed at the ends
  span.finite1 = ramp_section(t1, w0, dw, h0, dh, span.half1, span.slope1, unused);
  span.finite2 = ramp_section(t2, w0, dw, h0, dh, span.half2, span.slope2, unused);
  return true;
}

// At t: half, its slope and its second derivative (false where the slope is infinite: the
// line touching the section, or the corner's vertical tangent at the tip's or the top's
// height, both only at T's ends, where the slope points into T).
bool RaySweep::ramp_section(double t, double w0, double dw, double h0, double dh, double& half, double& d1,
                            double& d2) const {
  const double Rc = core_.core_radius_mm, r = core_.rounding_mm, zl = core_.z_low_mm, zh = core_.z_high_mm;
  const double h = h0 + t * dh, off = w0 + t * dw;
  double e = 0.0, e1 = 0.0;  // the height's distance from the core's [zl, zh], and its slope
  if (h < zl) {
    e = zl - h;
    e1 = -dh;
  } else if (h > zh) {
    e = h - zh;
    e1 = dh;
  }
  const double sigma = std::sqrt(std::max(0.0, r * r - e * e));
  const double rho = Rc + sigma, q = rho * rho - off * off;
  half = std::sqrt(std::max(0.0, q));
  if (!(sigma > 0.0) || !(half > 0.0)) return false;
  const double s1 = -e * e1 / sigma, s2 = -e1 * e1 * r * r / (sigma * sigma * sigma);
  const double q1 = 2.0 * (rho * s1 - off * dw), q2 = 2.0 * (s1 * s1 + rho * s2 - dw * dw);
  d1 = q1 / (2.0 * half);
  d2 = q2 / (2.0 * half) - q1 * q1 / (4.0 * half * half * half);
  return true;
}

// The least of F(t) = s c(t) - half(t) over T (s = 1: the entry; s = -1: minus the exit)
// where an end of T settles it (true, in value); else false, with the search's first best.
bool RaySweep::ramp_settled(const RampSpan& span, double s, double c0, double dc, double& value, double& best) {
  const double f1 = s * (c0 + span.t1 * dc) - span.half1;
  if (span.t2 - span.t1 <= 0.0 || (span.finite1 && s * dc - span.slope1 >= 0.0)) {
    value = f1;
    return true;
  }
  const double f2 = s * (c0 + span.t2 * dc) - span.half2;
  if (span.finite2 && s * dc - span.slope2 <= 0.0) {
    value = f2;
    return true;
  }
  best = std::min(f1, f2);
  return false;
}

// The least of F over T where no end settles it: Newton's steps on the slope in the bracket
// (false: the section's slope infinite inside T, rounding at its ends, or out of steps).
bool RaySweep::ramp_search(const RampSpan& span, double s, double c0, double dc, double w0, double dw, double h0,
                           double dh, double best, double& value) const {
  double half, d1, d2;
  double a = span.t1, b = span.t2, t = 0.5 * (span.t1 + span.t2);
  for (int step = 0; step < 60; ++step) {
    double g2 = 0.0, g = 0.0;
    if (ramp_section(t, w0, dw, h0, dh, half, d1, d2)) {
      const double f = s * (c0 + t * dc) - half;
      best = std::min(best, f);
      g = s * dc - d1;
      g2 = -d2;
      if (g < 0.0)
        a = t;
      else
        b = t;
      if (std::abs(g) * (b - a) <= kGeneralSweepTolerance_mm) {
        value = best;
        return true;
      }
    } else {
      return false;  // inside T the slope is finite: rounding at its ends
    }
    double next = g2 > 0.0 ? t - g / g2 : a;
    if (!(next > a && next < b)) next = 0.5 * (a + b);
    t = next;
  }
  return false;
}

bool RaySweep::upright_ramp(double c0, double dc, double w0, double dw, double h0, double dh, double ta, double tb,
                            double& lo, double& hi, bool& decided) const {
  decided = true;
  RampSpan span;
  if (!ramp_span(w0, dw, h0, dh, ta, tb, span)) return false;
  auto least = [&](double s, double& value) {
    double best;
    return ramp_settled(span, s, c0, dc, value, best) || ramp_search(span, s, c0, dc, w0, dw, h0, dh, best, value);
  };
  double entry, exit;
  if (!least(1.0, entry) || !least(-1.0, exit)) {
    decided = false;
    return false;
  }
  lo = entry;
  hi = -exit;
  return true;
}

bool RaySweep::flat_strip(int axis, double u, double w, double& lo, double& hi) const {
  const FlatFamily& f = flat_[axis];
  const Vector3d& a = tool_axis_;
  const double R = radius_mm_, H = height_mm_;
  // Measured from the ray's point level with the tip (s = s0 + sigma): E's part square to u,
  // left out, then moves the points by at most its length times |sigma| < the span.
  const double s0 = p0_[axis];
  const Vector3d x = ray_point(axis, u, w, s0) - p0_;
  const double hw = x.dot(a);
  const Vector3d W = x - hw * a;
  const double Wu = W.dot(f.u), reach2 = R * R - (W.squaredNorm() - Wu * Wu);
  if (reach2 < 0.0) return false;
  const double reach = std::sqrt(reach2);
  // Each strip: value = c + cs s + ct t within [lo, hi].
  struct Strip {
    double c, cs, ct, lo, hi;
  };
  const Strip strips[3] = {{Wu, f.e1, -f.d1, -reach, reach}, {0.0, 0.0, 1.0, 0.0, 1.0}, {hw, f.he, -f.hd, 0.0, H}};
  constexpr double kSlack = 1e-9;  // mm, or per unit of t: a vertex on a boundary is inside
  bool active[3];
  for (int i = 0; i < 3; ++i) {
    const Strip& k = strips[i];
    active[i] = std::abs(k.cs) + std::abs(k.ct) > 1e-12;
    if (!active[i] && (k.c < k.lo - kSlack || k.c > k.hi + kSlack)) return false;
  }
  auto inside = [&](double s, double t) {
    for (const Strip& k : strips) {
      const double v = k.c + k.cs * s + k.ct * t;
      if (v < k.lo - kSlack || v > k.hi + kSlack) return false;
    }
    return true;
  };
  // The polygon's extremes in s are among its vertices: two strips' boundary lines meeting.
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      if (!active[i] || !active[j]) continue;
      const Strip &p = strips[i], &q = strips[j];
      const double det = p.cs * q.ct - p.ct * q.cs;
      if (std::abs(det) <= 1e-12 * (std::abs(p.cs) + std::abs(p.ct)) * (std::abs(q.cs) + std::abs(q.ct))) continue;
      for (const double bp : {p.lo, p.hi})
        for (const double bq : {q.lo, q.hi}) {
          const double rp = bp - p.c, rq = bq - q.c;
          const double s = (rp * q.ct - p.ct * rq) / det, t = (p.cs * rq - rp * q.cs) / det;
          if (!inside(s, t)) continue;
          lo = std::min(lo, s0 + s);
          hi = std::max(hi, s0 + s);
        }
    }
  return lo <= hi;
}

bool RaySweep::tilted_flat(int axis, double u, double w, double& lo, double& hi, bool& decided) const {
  // The point o + s e - p(t), p(t) = p0 + t delta, in the tool frame: height along the axis
  // h = hw + he s - hd t, offset from the axis W + s E - t D (all normal to the axis).
  const FlatFamily& f = flat_[axis];
  decided = f.kind != FlatFamily::Kind::March;
  if (f.kind != FlatFamily::Kind::Ellipse) return decided && flat_strip(axis, u, w, lo, hi);
  // o - p0 and W in the family's coordinates (u, w, along the ray).
  const double xu = u - f.p[0], xw = w - f.p[1], xk = -f.p[2];
  const double hw = xu * f.a[0] + xw * f.a[1] + xk * f.a[2];
  const double Wu = xu - hw * f.a[0], Ww = xw - hw * f.a[1], Wk = xk - hw * f.a[2];
  const double he = f.he, hd = f.hd, EE = f.EE, ED = f.ED, DD = f.DD;
  const double R = radius_mm_, H = height_mm_;
  // q(s, t) = |W + s E - t D|^2 - R^2 <= 0: an ellipse.
  const double WE = Wu * f.E[0] + Ww * f.E[1] + Wk * f.E[2], WD = Wu * f.D[0] + Ww * f.D[1] + Wk * f.D[2];
  const double WW = Wu * Wu + Ww * Ww + Wk * Wk - R * R;
  auto q = [&](double s, double t) {
    return EE * s * s - 2.0 * ED * s * t + DD * t * t + 2.0 * WE * s - 2.0 * WD * t + WW;
  };
  constexpr double kSlack = kFlatSlack_mm;
  // Which of the four lines' constraints (t >= 0, t <= 1, h >= 0, h <= H) a point breaks.
  auto broken = [&](double s, double t) {
    const double h = hw + he * s - hd * t;
    return (t < -kSlack ? 1 : 0) | (t > 1.0 + kSlack ? 2 : 0) | (h < -kSlack ? 4 : 0) | (h > H + kSlack ? 8 : 0);
  };
  double s_lo = std::numeric_limits<double>::infinity(), s_hi = -s_lo;
  auto take = [&](double s) {
    s_lo = std::min(s_lo, s);
    s_hi = std::max(s_hi, s);
  };
  // 1. The ellipse's extremes in s (where dq/dt = 0: t = (ED s + WD) / DD). Where one keeps
  // all four constraints it is the region's extreme on that side. Where it breaks some, the
  // region's extreme lies on one of those lines (the segment from it to the ellipse's
  // extreme would otherwise lead, inside the region, to a better point), so only the lines
  // an extreme breaks are walked below; every point taken lies in the region.
  int lines = 0;
  {
    const double B = 2.0 * (WE - WD * ED * f.inv_DD), C = WW - WD * WD * f.inv_DD;
    const double disc = B * B - 4.0 * f.A * C;
    if (disc < 0.0) return false;  // the ellipse is empty: the line never comes within R of the axis
    const double root = std::sqrt(disc);
    for (double s : {(-B - root) * f.inv_2A, (-B + root) * f.inv_2A}) {
      const double t = (ED * s + WD) * f.inv_DD;
      const int breaks = broken(s, t);
      if (breaks == 0)
        take(s);
      else
        lines |= breaks;
    }
  }
  if (!f.h_lines && (hw < 0.0 || hw > H)) return false;  // the height never changes: never within [0, H]
  if (lines == 0) {
    lo = s_lo;
    hi = s_hi;
    return true;
  }
  // 2. Where each such line crosses the ellipse, inside the others: along a line
  // (s, t) = (ps, pt) + lambda (ds, dt), q is qa lambda^2 + qb lambda + qc.
  auto cross = [&](double ps, double pt, double ds, double dt, double qa, double qb, double inv_2qa) {
    const double qc = q(ps, pt);
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc < 0.0) return;
    const double root = std::sqrt(disc);
    for (double lambda : {(-qb - root) * inv_2qa, (-qb + root) * inv_2qa}) {
      const double s = ps + lambda * ds, t = pt + lambda * dt;
      if (broken(s, t) == 0) take(s);
    }
  };
  if (lines & 1) cross(0.0, 0.0, 1.0, 0.0, EE, 2.0 * WE, f.inv_2EE);         // t = 0
  if (lines & 2) cross(0.0, 1.0, 1.0, 0.0, EE, 2.0 * (WE - ED), f.inv_2EE);  // t = 1
  if (f.h_lines && f.qa_h > 0.0) {
    for (int i = 0; i < 2; ++i) {
      if (!(lines & (4 << i))) continue;
      const double k = ((i == 0 ? 0.0 : H) - hw) * f.inv_nn;
      const double ps = he * k, pt = -hd * k;
      const double qb = 2.0 * (EE * ps * hd - ED * (ps * he + pt * hd) + DD * pt * he + WE * hd - WD * he);
      cross(ps, pt, hd, he, f.qa_h, qb, f.inv_2qa_h);
    }
  }
  // 3. The corners where a walked line meets a line of the other kind, inside the ellipse.
  if (f.corners) {
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) {
        if (!(lines & ((1 << i) | (4 << j)))) continue;
        const double t = i == 0 ? 0.0 : 1.0, s = ((j == 0 ? 0.0 : H) - hw + hd * t) * f.inv_he;
        if (q(s, t) <= kSlack * (1.0 + R * R)) take(s);
      }
  }
  if (!(s_lo <= s_hi)) return false;
  lo = s_lo;
  hi = s_hi;
  return true;
}

void RaySweep::prepare_cone_family(int axis) {
  ConeFamily& f = cone_family_[axis];
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const Vector3d& a = tool_axis_;
  f.a1 = a[a1];
  f.a2 = a[a2];
  f.d1 = delta_[a1];
  f.d2 = delta_[a2];
  f.A1 = a[axis];
  f.A2 = delta_.dot(a);
  const double d_e = delta_[axis], dd = delta_.squaredNorm(), k = cone_k_;
  f.along_s = std::abs(f.A1) >= std::abs(f.A2);
  f.inv_A1 = 1.0 / f.A1;
  f.inv_A2 = 1.0 / f.A2;
  for (int j = 0; j < 2; ++j) {
    const double c = j == 0 ? 1.0 + k * k : 1.0;
    f.c[j] = c;
    f.kappa[j] = j == 0 ? 0.0 : cone_r_mm_ * cone_r_mm_;
    f.ss[j] = 1.0 - c * f.A1 * f.A1;
    f.st[j] = -d_e + c * f.A1 * f.A2;
    f.tt[j] = dd - c * f.A2 * f.A2;
    f.lead[j] = f.ss[j] * f.tt[j] - f.st[j] * f.st[j];
    f.inv_lead[j] = 1.0 / f.lead[j];
    f.inv_tt[j] = 1.0 / f.tt[j];
    f.inv_ss[j] = 1.0 / f.ss[j];
  }
  f.line_lead = Conic::lead(f.ss[1], f.st[1], f.tt[1], f.A2, f.A1);
  f.inv_line_lead = 1.0 / f.line_lead;
}

bool RaySweep::cone_interval(int axis, double u, double w, double& lo, double& hi) const {
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const ConeFamily& f = cone_family_[axis];
  // The ray's point at s less the first tip, with s' = s - p0[axis]: w0 + s' e, w0[axis] = 0
  // (coordinates near the move, whatever the ray's position along its axis).
  const double w0_1 = u - p0_[a1], w0_2 = w - p0_[a2];
  // Height above the instance's tip at (s', t): y = A0 + A1 s' - A2 t; its square distance
  // from the instance's tip, |w0 + s' e - t delta|^2, less y^2 is the square radius.
  const double A0 = w0_1 * f.a1 + w0_2 * f.a2, A1 = f.A1, A2 = f.A2;
  const double wd = w0_1 * f.d1 + w0_2 * f.d2, ww = w0_1 * w0_1 + w0_2 * w0_2;
  // |.|^2 - c y^2 - kappa: the cone (c = 1 + k^2, kappa = 0: radius^2 <= k^2 y^2) and the
  // cylinder (c = 1, kappa = R^2).
  auto conic = [&](int j) {
    const double c = f.c[j];
    return Conic{f.ss[j], f.st[j], f.tt[j], -c * A0 * A1, -wd + c * A0 * A2, ww - c * A0 * A0 - f.kappa[j]};
  };
  const double r = cone_r_mm_, H = height_mm_;
  const Conic cone = conic(0), cylinder = conic(1);
  // A point on one of the surfaces counts where the tool has that surface: the cone from the
  // tip's height to the cone's top, the cylinder from there to H (on the cone, radius^2 =
  // k^2 y^2, which is below R^2 there and above it higher up; on the cylinder the other way
  // round), at a time within the move: a range test each, to within rounding (1e-9 mm).
  constexpr double kTol_mm = 1e-9, kTolT = 1e-12;
  const double top = cone_top_mm_;
  double s_lo = kInf, s_hi = -kInf;
  auto take = [&](double s, double t, double y_lo, double y_hi) {
    if (!(t >= -kTolT && t <= 1.0 + kTolT)) return;
    const double y = A0 + A1 * s - A2 * t;
    if (!(y >= y_lo - kTol_mm && y <= y_hi + kTol_mm)) return;
    s_lo = std::min(s_lo, s);
    s_hi = std::max(s_hi, s);
  };
  double roots[2];
  // Where each conic runs square to s (its derivative in t zero).
  for (int which = 0; which < 2; ++which) {
    const Conic& q = which == 0 ? cone : cylinder;
    if (q.tt == 0.0) continue;
    const int n =
        quadratic_roots(f.lead[which], q.s * q.tt - q.st * q.t, q.c * q.tt - q.t * q.t, roots, f.inv_lead[which]);
    for (int i = 0; i < n; ++i)
      take(roots[i], -(q.st * roots[i] + q.t) * f.inv_tt[which], which == 0 ? 0.0 : top, which == 0 ? top : H);
  }
  // Each conic against the first and last instance.
  for (const double t : {0.0, 1.0})
    for (int which = 0; which < 2; ++which) {
      const int n = (which == 0 ? cone : cylinder).on_line(0.0, t, 1.0, 0.0, f.ss[which], f.inv_ss[which], roots);
      for (int i = 0; i < n; ++i) take(roots[i], t, which == 0 ? 0.0 : top, which == 0 ? top : H);
    }
  // The cylinder against the top (y = H) and where it meets the cone (y = cone top; the top
  // again when the cone is cut off there). (The cone meets the tip's height y = 0 only at the
  // apex, the cylinder there outside the cone.) The line y = height: through (x, y), along
  // (A2, A1).
  if (A1 != 0.0 || A2 != 0.0) {
    for (int line = 0; line < (top < H ? 2 : 1); ++line) {
      const double height = line == 0 ? H : top;
      const double x = f.along_s ? (height - A0) * f.inv_A1 : 0.0, y = f.along_s ? 0.0 : (A0 - height) * f.inv_A2;
      const int n = cylinder.on_line(x, y, A2, A1, f.line_lead, f.inv_line_lead, roots);
      for (int i = 0; i < n; ++i) take(x + roots[i] * A2, y + roots[i] * A1, height, height);
    }
  }
  // The top's centre line at the first and last instance, where it lies in the top disc.
  const double cylinder_tol = 2.0 * r * kTol_mm;
  if (A1 != 0.0)
    for (const double t : {0.0, 1.0}) {
      const double s = (H - A0 + A2 * t) * f.inv_A1;
      if (cylinder.at(s, t) <= cylinder_tol) take(s, t, H, H);
    }
  if (!(s_lo <= s_hi)) return false;
  lo = s_lo + p0_[axis];
  hi = s_hi + p0_[axis];
  return true;
}

bool RaySweep::material_clear(int axis, double u, double w, double bottom, double top) const {
  if (!(std::isfinite(bottom) && std::isfinite(top))) return false;
  // In scalars: see ray_point.
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  const double half = 0.5 * (top - bottom);
  const double pu = u - core_mid_[a1], pw = w - core_mid_[a2], ps = bottom + half - core_mid_[axis];
  const double qa = pu * tool_axis_[a1] + pw * tool_axis_[a2] + ps * tool_axis_[axis];
  const double h = std::clamp(qa, core_.z_low_mm, core_.z_high_mm);
  const double reach = capsule_r_ + half_move_mm_ + half;
  return pu * pu + pw * pw + ps * ps - h * (2.0 * qa - h) > reach * reach;
}

bool RaySweep::general(int axis, const Vector3d& o, double bottom, double top, double& lo, double& hi) const {
  const Eigen::AlignedBox3d& box = bounds_;
  for (int a = 0; a < 3; ++a)
    if (a != axis && (o[a] < box.min()[a] || o[a] > box.max()[a])) return false;
  // Material clear of the bracket (material_clear). In scalars throughout: o's coordinate
  // along the ray is written by index, and a vector built from it stalls on the store.
  if (material_clear(axis, o[axis == 0 ? 1 : 0], o[axis == 2 ? 1 : 2], bottom, top)) return false;
  // A V-bit's sweep in closed form (the bracket below in front of it, even four rays at a
  // time, cost more than the misses it saved: V5's cut 3.33 -> 3.01 s without it).
  if (cone_) return cone_interval(axis, o[axis == 0 ? 1 : 0], o[axis == 2 ? 1 : 2], lo, hi);
  // The enclosing ball sweep's interval: none, no meeting; else the march starts at its ends.
  double capsule_lo, capsule_hi;
  if (!ball_general(axis, o[axis == 0 ? 1 : 0], o[axis == 2 ? 1 : 2], capsule_lo, capsule_hi)) return false;
  return bracketed(axis, o, bottom, top, capsule_lo, capsule_hi, lo, hi);
}

bool RaySweep::bracket_ends(int axis, const Vector3d& o, double bottom, double top, double capsule_lo,
                            double capsule_hi, Bracket& b, bool& hit, double& lo, double& hi) const {
  const Eigen::AlignedBox3d& box = bounds_;
  const double ak = tool_axis_[axis];
  b.sa = std::max(std::max(box.min()[axis], capsule_lo), bottom) - 1e-6;
  b.sb = std::min(std::min(box.max()[axis], capsule_hi), top) + 1e-6;
  if (!(b.sa <= b.sb)) {
    hit = false;
    return true;
  }
  // A bull-nose's ends where they are known without the march: the bracket's end in the band
  // (band_), or the point where the ray crosses the sweep's lowest plane inside the lowest
  // instance's flat bottom.
  bool& exact_lo = b.exact_lo;
  bool& exact_hi = b.exact_hi;
  double& known_lo = b.known_lo;
  double& known_hi = b.known_hi;
  exact_lo = exact_hi = false;
  known_lo = capsule_lo;
  known_hi = capsule_hi;
  if (band_) {
    // Heights along the axis above the first tip: h(s) = oa + s ak.
    const double oa = (o[0] - p0_[0]) * tool_axis_[0] + (o[1] - p0_[1]) * tool_axis_[1] +
                      (o[2] - p0_[2]) * tool_axis_[2] - o[axis] * ak;
    auto in_band = [&](double s) {
      const double h = oa + s * ak;
      return h > band_h_lo_mm_ && h < band_h_hi_mm_;
    };
    exact_lo = in_band(capsule_lo);
    exact_hi = in_band(capsule_hi);
    if (!(exact_lo && exact_hi) && ak != 0.0) {
      // Where the ray crosses the lowest plane (h = min(0, delta.a)), its offset from the
      // lowest tip is square to the axis.
      const double s_plane = (lowest_h_mm_ - oa) / ak;
      const double dx = o[0] - lowest_tip_[0], dy = o[1] - lowest_tip_[1], dz = o[2] - lowest_tip_[2];
      const double radial2 = dx * dx + dy * dy + dz * dz + s_plane * (2.0 * (o[axis] - lowest_tip_[axis]) + s_plane);
      if (radial2 <= core_.core_radius_mm * core_.core_radius_mm) {
        if (ak > 0.0 && !exact_lo) {
          exact_lo = true;
          known_lo = s_plane;
        } else if (ak < 0.0 && !exact_hi) {
          exact_hi = true;
          known_hi = s_plane;
        }
      }
    }
  }
  if ((exact_lo && known_lo > top) || (exact_hi && known_hi < bottom)) {  // all material beside it
    hit = false;
    return true;
  }
  if (exact_lo && exact_hi) {
    lo = known_lo;
    hi = known_hi;
    hit = true;
    return true;
  }
  return false;
}

void RaySweep::march_lanes(int axis, double w, int n, const MarchJob* jobs, double* root, bool* found,
                           bool* converged) const {
  // Four marches at a time, each in its slot until it ends, then the next job in that slot:
  // march_to_root's steps.
  struct Slot {
    int job = -1, step = 0;
    bool started = false;
    double s0 = 0, f0 = 0, s1 = 0, dir = 0, fallback = 0;
  };
  Slot slot[4];
  int next = 0;
  auto end = [&](Slot& sl, bool is_found, bool is_converged, double at) {
    found[sl.job] = is_found;
    converged[sl.job] = is_converged;
    if (is_found) root[sl.job] = at;
    sl.job = -1;
  };
  for (;;) {
    Vector3d points[4];
    int which[4], m = 0;
    for (int i = 0; i < 4; ++i) {
      Slot& sl = slot[i];
      if (sl.job < 0 && next < n) {
        const MarchJob& job = jobs[next];
        sl = Slot{next++, 0, false, job.from, 0.0, 0.0, job.toward > job.from ? 1.0 : -1.0, 0.0};
      }
      if (sl.job < 0) continue;
      points[m] = ray_point(axis, jobs[sl.job].u, w, sl.started ? sl.s1 : sl.s0);
      which[m++] = i;
    }
    if (m == 0) return;
    double f[4], slope[4];
    sweep_.distances(points, m, f, lanes_, axis, slope);
    for (int j = 0; j < m; ++j) {
      Slot& sl = slot[which[j]];
      const double toward = jobs[sl.job].toward, dir = sl.dir;
      if (!sl.started) {
        // march_to_root's start: f at `from`, then the first step.
        sl.started = true;
        sl.f0 = f[j];
        if (sl.f0 <= kGeneralSweepTolerance_mm) {
          end(sl, true, true, sl.s0);
          continue;
        }
        sl.s1 = newton_or(sl.s0, sl.f0, slope[j], dir, sl.s0 + dir * sl.f0, sl.fallback);
      } else {
        const double f1 = f[j];
        if (f1 < -kGeneralSweepTolerance_mm && sl.fallback == sl.fallback) {  // Newton's step passed the root
          sl.s1 = sl.fallback;
          sl.fallback = std::numeric_limits<double>::quiet_NaN();
        } else {
          if (f1 <= kGeneralSweepTolerance_mm) {
            end(sl, true, true, sl.s1);
            continue;
          }
          if (f1 >= sl.f0) {
            end(sl, false, true, 0.0);
            continue;
          }
          const double secant = sl.s1 + (sl.s1 - sl.s0) * f1 / (sl.f0 - f1);
          const double sphere = sl.s1 + dir * f1;
          sl.s0 = sl.s1;
          sl.f0 = f1;
          sl.s1 = newton_or(sl.s0, sl.f0, slope[j], dir,
                            dir > 0.0 ? std::max(secant, sphere) : std::min(secant, sphere), sl.fallback);
        }
        if (++sl.step == 100) {
          end(sl, false, false, 0.0);
          continue;
        }
      }
      if ((sl.s1 - toward) * dir > 0.0) end(sl, false, true, 0.0);
    }
  }
}

void RaySweep::bracketed_lanes(int axis, double w, int first, int n, const int* todo, const double* u,
                               const double* bottom, const double* top, const double* capsule_lo,
                               const double* capsule_hi, const bool* capsule_hit, double* lo, double* hi,
                               bool* hit) const {
  // The rays the ends leave open, and their marches from below, then from above.
  int open[kLanesBlock], n_open = 0;
  Bracket bracket[kLanesBlock];
  MarchJob jobs[kLanesBlock];
  int job_of[kLanesBlock];
  double root[kLanesBlock];
  bool found[kLanesBlock], converged[kLanesBlock];
  bool lo_found[kLanesBlock], lo_converged[kLanesBlock];
  for (int j = 0; j < n; ++j) {
    const int c = todo[j], k = first + c;
    if (!capsule_hit[c]) continue;
    bool decided_hit;
    Bracket& b = bracket[n_open];
    if (bracket_ends(axis, ray_point(axis, u[k], w, 0.0), bottom[k], top[k], capsule_lo[c], capsule_hi[c], b,
                     decided_hit, lo[k], hi[k])) {
      hit[k] = decided_hit;
      continue;
    }
    open[n_open++] = j;
  }
  int n_jobs = 0;
  for (int i = 0; i < n_open; ++i) {
    const int k = first + todo[open[i]];
    job_of[i] = -1;
    if (bracket[i].exact_lo) continue;
    job_of[i] = n_jobs;
    jobs[n_jobs++] = MarchJob{u[k], bracket[i].sa, bracket[i].sb};
  }
  if (n_jobs > 0) march_lanes(axis, w, n_jobs, jobs, root, found, converged);
  n_jobs = 0;
  for (int i = 0; i < n_open; ++i) {
    const int k = first + todo[open[i]];
    const Bracket& b = bracket[i];
    if (b.exact_lo) {
      lo[k] = b.known_lo;
      lo_found[i] = lo_converged[i] = true;
    } else {
      const int job = job_of[i];
      lo_found[i] = found[job];
      lo_converged[i] = converged[job];
      if (found[job]) lo[k] = root[job];
    }
    job_of[i] = -1;
    if (!lo_found[i] || b.exact_hi) continue;
    job_of[i] = n_jobs;
    jobs[n_jobs++] = MarchJob{u[k], b.sb, b.sa};
  }
  if (n_jobs > 0) march_lanes(axis, w, n_jobs, jobs, root, found, converged);
  // bracketed()'s decisions; a march out of steps takes bracketed() whole.
  for (int i = 0; i < n_open; ++i) {
    const int c = todo[open[i]], k = first + c;
    const Bracket& b = bracket[i];
    if (lo_found[i]) {
      if (b.exact_hi) {
        hi[k] = b.known_hi;
        hit[k] = true;
        continue;
      }
      const int job = job_of[i];
      if (found[job]) hi[k] = root[job];
      if (found[job] && hi[k] >= lo[k]) {
        hit[k] = true;
        continue;
      }
      if (converged[job]) {
        hit[k] = false;
        continue;
      }
    } else if (lo_converged[i]) {
      hit[k] = false;
      continue;
    }
    hit[k] =
        bracketed(axis, ray_point(axis, u[k], w, 0.0), bottom[k], top[k], capsule_lo[c], capsule_hi[c], lo[k], hi[k]);
  }
}

bool RaySweep::bracketed(int axis, const Vector3d& o, double bottom, double top, double capsule_lo, double capsule_hi,
                         double& lo, double& hi) const {
  Bracket b;
  bool hit;
  if (bracket_ends(axis, o, bottom, top, capsule_lo, capsule_hi, b, hit, lo, hi)) return hit;
  const bool exact_lo = b.exact_lo, exact_hi = b.exact_hi;
  const double sa = b.sa, sb = b.sb, known_lo = b.known_lo, known_hi = b.known_hi;
  // The point built whole from scalars (no store by index under a vector load: see above).
  const double o0 = o[0], o1 = o[1], o2 = o[2];
  auto f = [&](double s) {
    return sweep_.distance(Vector3d(axis == 0 ? s : o0, axis == 1 ? s : o1, axis == 2 ? s : o2));
  };
  // With its slope along the ray where known: march_lanes' values, to the bit.
  auto f_slope = [&](double s, double& slope) {
    const Vector3d x(axis == 0 ? s : o0, axis == 1 ? s : o1, axis == 2 ? s : o2);
    double value;
    sweep_.distances(&x, 1, &value, lanes_, axis, &slope);
    return value;
  };
  // The sweep's signed distance is convex and 1-Lipschitz along the line: march to its first
  // zero from each end (exact to the distance's own tolerance, kGeneralSweepTolerance_mm).
  bool converged_lo = false, converged_hi = false;
  if (exact_lo ? (lo = known_lo, true) : march_to_root(f_slope, sa, sb, kGeneralSweepTolerance_mm, lo, converged_lo)) {
    if (exact_hi) {
      hi = known_hi;
      return true;
    }
    if (march_to_root(f_slope, sb, sa, kGeneralSweepTolerance_mm, hi, converged_hi) && hi >= lo) return true;
    if (converged_hi) return false;
  } else if (converged_lo) {
    return false;
  }
  // Out of steps (not seen in practice): bracket the minimum, then the two zero crossings.
  const double s_min = golden_argmin(f, sa, sb, kRaySearchTolerance_mm);
  if (f(s_min) > 0.0) return false;
  lo = f(sa) > 0.0 ? bisect(f, sa, s_min, kRaySearchTolerance_mm) : sa;
  hi = f(sb) > 0.0 ? bisect(f, sb, s_min, kRaySearchTolerance_mm) : sb;
  return true;
}

}  // namespace vcut::removal::detail
