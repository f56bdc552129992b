#include "vcut/removal/sweep.h"

#include "distance.h"
#include "lanes.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vcut::removal {
namespace {

using detail::extrude;
using detail::interval_distance;

// Motion components below this (mm) are treated as zero; the distance error this causes
// is at most this much, since d is 1-Lipschitz in the sweep's end point.
constexpr double kDegenerateMotion_mm = 1e-9;

// Any rotation taking `axis` to +Z (the cutter is symmetric about its axis).
Eigen::Matrix3d rotation_to_z(const Eigen::Vector3d& axis) {
  return Eigen::Quaterniond::FromTwoVectors(axis.normalized(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

TranslationSweep::TranslationSweep(const Cutter& cutter, const Move& move)
    : core_(core_of(cutter)), cutter_(cutter), to_tool_(rotation_to_z(move.axis)), origin_(move.start_mm) {
  delta_tool_ = to_tool_ * (move.end_mm - move.start_mm);
  delta_length_ = delta_tool_.norm();
  const double across = delta_tool_.head<2>().norm();
  if (cutter.type == CutterType::VBit) {
    kind_ = Kind::General;  // the cone is not a core grown by a ball: search along the move
  } else if (std::abs(delta_tool_.z()) <= kDegenerateMotion_mm) {
    kind_ = Kind::Across;
    delta_tool_.z() = 0.0;
  } else if (across <= kDegenerateMotion_mm) {
    kind_ = Kind::Along;
    delta_tool_.head<2>().setZero();
  } else {
    kind_ = Kind::General;
  }
  // Bounds: the cutter's bounding cylinder box at both ends, in the workpiece frame.
  const double radius = core_.core_radius_mm + core_.rounding_mm;
  const Eigen::Matrix3d to_work = to_tool_.transpose();
  bounds_.setEmpty();
  for (const Eigen::Vector3d& tip : {move.start_mm, move.end_mm}) {
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d c((corner & 1) ? radius : -radius, (corner & 2) ? radius : -radius,
                              (corner & 4) ? core_.z_high_mm + core_.rounding_mm : 0.0);
      bounds_.extend(tip + to_work * c);
    }
  }
}

bool TranslationSweep::start_dominates(const Eigen::AlignedBox3d& box) const {
  if (!ball() || delta_length_ == 0.0) return false;
  // The box in the tool frame, bounded by the box around the rotated box.
  const Eigen::Vector3d center = to_tool_ * (box.center() - origin_);
  const Eigen::Vector3d half = to_tool_.cwiseAbs() * (0.5 * box.sizes());
  // max over the box of delta . (y - c(y)) = dx yx + dy yy + dz g(yz), g(z) = z - clamp(z, lo,
  // hi) nondecreasing: each term's maximum is at an end of its interval.
  const Eigen::Vector3d& d = delta_tool_;
  const double z = d.z() >= 0.0 ? center.z() + half.z() : center.z() - half.z();
  const double g = z - std::clamp(z, core_.z_low_mm, core_.z_high_mm);
  const double most =
      d.x() * center.x() + std::abs(d.x()) * half.x() + d.y() * center.y() + std::abs(d.y()) * half.y() + d.z() * g;
  return most <= 0.0;
}

bool TranslationSweep::start_dominates(const Eigen::Vector3d& x) const {
  if (!ball() || delta_length_ == 0.0) return false;
  const Eigen::Vector3d y = to_tool_ * (x - origin_);
  const double g = y.z() - std::clamp(y.z(), core_.z_low_mm, core_.z_high_mm);
  return delta_tool_.x() * y.x() + delta_tool_.y() * y.y() + delta_tool_.z() * g <= 0.0;
}

namespace {

// min over t in [0, 1] of a convex f given by eval(t, f, num, den), its slope num / den with
// den > 0 (f's derivative, or where f has a kink any slope between its one-sided ones; the
// division only where the value is needed: at an end that is the minimum its sign decides,
// and the sweep's march mostly ends there): f' goes from negative to
// positive once, so the minimum is found on a bracket [a, b] with f'(a) < 0 < f'(b) by secant
// steps on f' (bisection when a step would not shrink the bracket enough; the tangents'
// meeting point after a step that found f straight: below). The tangents at a
// and b meet below the minimum, which gives a lower bound: the search stops when the best
// value found is within kGeneralSweepTolerance_mm of it (the error bound), or when it is at
// least `far`. convex_minimum_between is that search from the two ends once neither is the
// minimum (f and f' at t = 0: fa, ga < 0; at t = 1: fb, gb > 0); convex_minimum looks at the
// ends first. `at`, where given: the t of the value returned (unless it is the bound `far`).
template <class Eval>
double convex_minimum_between(Eval&& eval, double delta_length, double far, double fa, double ga, double fb, double gb,
                              double* at = nullptr) {
  double a = 0.0, b = 1.0, num, den;
  double best = std::min(fa, fb);
  bool kink = false;
  if (at != nullptr) *at = fa <= fb ? 0.0 : 1.0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    // The tangents at a and b meet at t_x, below the convex f's minimum.
    const double tx = (fb - fa - gb * b + ga * a) / (ga - gb);
    const double lower = fa + ga * (tx - a);
    if (lower >= far || best - lower <= kGeneralSweepTolerance_mm ||
        (b - a) * delta_length <= kGeneralSweepTolerance_mm) {
      return lower >= far ? lower : best;
    }
    // After a step whose slope came out within a tenth of the slope at that side's end (f is
    // straight from that end to it, so f' jumps further in: a kink at the least, where the
    // core's distance turns from its side's to its end's), the tangents' meeting point itself:
    // between straight pieces they meet at the kink, and f there is the bound. Secant roots of
    // f' closed in on a kink by a tenth of the bracket a step (W1F's mesh: 18.9 steps a
    // search, 3.6 % of them 39 or more; 5.2 with this, W5's bull-nose 4.94 -> 4.89).
    const double width = b - a;
    double t;
    if (kink) {
      t = tx > a && tx < b ? tx : 0.5 * (a + b);
    } else {
      t = a - ga * (b - a) / (gb - ga);  // the secant root of f'
      if (!(t > a + 0.1 * width && t < b - 0.1 * width)) t = 0.5 * (a + b);
    }
    double ft;
    eval(t, ft, num, den);
    const double gt = num / den;
    if (ft < best) {
      best = ft;
      if (at != nullptr) *at = t;
    }
    if (gt == 0.0) return best;
    kink = gt < 0.0 ? std::abs(gt - ga) <= 0.1 * -ga : std::abs(gt - gb) <= 0.1 * gb;
    if (gt < 0.0) {
      a = t, fa = ft, ga = gt;
    } else {
      b = t, fb = ft, gb = gt;
    }
  }
  return best;
}

template <class Eval>
double convex_minimum(Eval&& eval, double delta_length, double far, double* at = nullptr) {
  // The end first: the march comes at the sweep mostly from ahead of the move (W5's bull-nose
  // rows: 79 % of these end at t = 1, 17 % at t = 0), and f convex takes its minimum at an end
  // whose slope points away from the other (both only where f is constant).
  double fa, fb, num, den;
  if (at != nullptr) *at = 1.0;
  eval(1.0, fb, num, den);
  if (num <= 0.0) return fb;
  const double gb = num / den;
  if (at != nullptr) *at = 0.0;
  eval(0.0, fa, num, den);
  if (num >= 0.0) return fa;
  return convex_minimum_between(eval, delta_length, far, fa, num / den, fb, gb, at);
}

// The core's middle height and half height (cylinder_eval's and its lanes').
double core_middle_mm(const CutterCore& core) { return 0.5 * (core.z_low_mm + core.z_high_mm); }
double core_half_mm(const CutterCore& core) { return 0.5 * (core.z_high_mm - core.z_low_mm); }

}  // namespace

// f(t) = d_K(y - t delta), K the core cylinder (radius Rc, z in [lo, hi]), is convex (rho and
// zeta each convex in t), with an analytic derivative (f = extrude(rho - Rc, zeta)).
inline void TranslationSweep::cylinder_eval(const Eigen::Vector3d& y, double t, const Eigen::Vector3d& e, double& f,
                                            double& num, double& den, double& along_num) const {
  const Eigen::Vector3d& d = delta_tool_;
  const double mid = core_middle_mm(core_), half = core_half_mm(core_);
  const Eigen::Vector3d p = y - t * d;
  // sqrt of the sum of squares, not hypot: no overflow at mm scale, and hypot was 42 % of
  // a tilted bull-nose's cut (perf, W5's first rows).
  const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());
  const double dr = rho - core_.core_radius_mm;
  const double q = p.z() - mid;
  const double dz = std::abs(q) - half;
  const double dz_slope = q > 0.0 ? -d.z() : q < 0.0 ? d.z() : 0.0;
  // dr's slope is -(p.d)_xy / rho (0 on the axis); along e, (p.e)_xy / rho, and dz's along e
  // is +-e.z.
  const double radial = rho > 0.0 ? -(p.x() * d.x() + p.y() * d.y()) : 0.0;
  const double radial_e = rho > 0.0 ? p.x() * e.x() + p.y() * e.y() : 0.0;
  const double dz_e = q > 0.0 ? e.z() : q < 0.0 ? -e.z() : 0.0;
  if (dr > 0.0 && dz > 0.0) {
    f = std::sqrt(dr * dr + dz * dz);
    num = dr * (radial / rho) + dz * dz_slope;
    along_num = dr * (radial_e / rho) + dz * dz_e;
    den = f;
  } else if (dr > 0.0 || (dz <= 0.0 && dr >= dz)) {
    f = dr;
    num = radial;
    along_num = radial_e;
    den = rho > 0.0 ? rho : 1.0;
  } else {
    f = dz;
    num = dz_slope;
    along_num = dz_e;
    den = 1.0;
  }
}

inline void TranslationSweep::cylinder_eval(const Eigen::Vector3d& y, double t, double& f, double& num,
                                            double& den) const {
  double unused;
  cylinder_eval(y, t, Eigen::Vector3d::Zero(), f, num, den, unused);
}

double TranslationSweep::cylinder_sweep_distance(const Eigen::Vector3d& y, double far) const {
  auto eval = [&](double t, double& f, double& num, double& den) { cylinder_eval(y, t, f, num, den); };
  return convex_minimum(eval, delta_length_, far);
}

// The V-bit (a convex solid of revolution): f(t) = d(y - t delta) is convex, its slope the
// profile's gradient (vbit_profile_distance) turned about the axis, against -delta. (A
// golden-section search took about 35 profile distances a point: 43 % of a tilted V-bit
// raster's run, in the mesher.)
double TranslationSweep::vbit_sweep_distance(const Eigen::Vector3d& y, double far) const {
  const Eigen::Vector3d& d = delta_tool_;
  auto eval = [&](double t, double& f, double& num, double& den) {
    const Eigen::Vector3d p = y - t * d;
    const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());
    double g_rho, g_z;
    f = vbit_profile_distance(cutter_, rho, p.z(), g_rho, g_z);
    // On the axis the distance is level across it (a solid of revolution).
    num = -((rho > 0.0 ? g_rho * (p.x() * d.x() + p.y() * d.y()) / rho : 0.0) + g_z * d.z());
    den = 1.0;
  };
  return convex_minimum(eval, delta_length_, far);
}

double TranslationSweep::core_distance(const Eigen::Vector3d& y) const {
  if (cutter_.type == CutterType::VBit) return cutter_distance(cutter_, y);
  const double d_radial = std::sqrt(y.x() * y.x() + y.y() * y.y()) - core_.core_radius_mm;
  return extrude(d_radial, interval_distance(y.z(), core_.z_low_mm, core_.z_high_mm));
}

Eigen::Vector2d TranslationSweep::across_spine(const Eigen::Vector3d& y) const {
  const Eigen::Vector2d d = delta_tool_.head<2>();
  const double len2 = d.squaredNorm();
  return (len2 > 0.0 ? std::clamp(y.head<2>().dot(d) / len2, 0.0, 1.0) : 0.0) * d;
}

void TranslationSweep::along_span(double& lo_mm, double& hi_mm) const {
  lo_mm = core_.z_low_mm + std::min(0.0, delta_tool_.z());
  hi_mm = core_.z_high_mm + std::max(0.0, delta_tool_.z());
}

Eigen::Vector3d TranslationSweep::ball_core_point(const Eigen::Vector3d& y) const {
  const double lo = core_.z_low_mm, hi = core_.z_high_mm;
  switch (kind_) {
    case Kind::Across: {
      // The core segment moved square to itself: a rectangle, the motion's segment times [lo, hi].
      const Eigen::Vector2d spine = across_spine(y);
      return {spine.x(), spine.y(), std::clamp(y.z(), lo, hi)};
    }
    case Kind::Along: {
      double z_lo, z_hi;
      along_span(z_lo, z_hi);
      return {0.0, 0.0, std::clamp(y.z(), z_lo, z_hi)};
    }
    case Kind::General:
      break;
  }
  // The segment swept into a parallelogram P spanned by the axis and delta: y's foot on P's
  // plane where it falls inside P, else the nearest point of P's four edges.
  const Eigen::Vector3d o(0.0, 0.0, lo), up(0.0, 0.0, hi - lo);
  const Eigen::Vector3d q = y - o;
  const Eigen::Vector2d d_plane = delta_tool_.head<2>();
  const double t = q.head<2>().dot(d_plane) / d_plane.squaredNorm();
  const double s = q.z() - t * delta_tool_.z();
  if (t >= 0.0 && t <= 1.0 && s >= 0.0 && s <= up.z()) return o + t * delta_tool_ + Eigen::Vector3d(0.0, 0.0, s);
  Eigen::Vector3d best_point = o;
  double best = std::numeric_limits<double>::infinity();
  auto edge = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& d) {
    const double u = std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    const Eigen::Vector3d p = a + u * d;
    const double e = (q - p).squaredNorm();
    if (e < best) best = e, best_point = o + p;
  };
  edge(Eigen::Vector3d::Zero(), delta_tool_);
  edge(up, delta_tool_);
  if (up.z() > 0.0) {
    edge(Eigen::Vector3d::Zero(), up);
    edge(delta_tool_, up);
  }
  return best_point;
}

bool TranslationSweep::ball_core_nearest(const Eigen::Vector3d& x, Eigen::Vector3d& q, double& radius_mm) const {
  if (!ball()) return false;
  q = origin_ + to_tool_.transpose() * ball_core_point(to_tool_ * (x - origin_));
  radius_mm = core_.rounding_mm;
  return true;
}

bool TranslationSweep::surface_point(const Eigen::Vector3d& x, Eigen::Vector3d& out) const {
  Eigen::Vector3d q;
  double r;
  if (ball_core_nearest(x, q, r)) {
    const double from_core = (x - q).norm();
    if (!(from_core > 0.0)) return false;
    out = q + (r / from_core) * (x - q);
    return true;
  }
  if (cutter_.type == CutterType::VBit || kind_ != Kind::General) return false;
  // The instance t nearest y (f(t) = d_K(y - t delta) at its least, K the core cylinder),
  // K's point k nearest p = y - t delta (the radial part cut to Rc, the height to [lo, hi])
  // and the normal n toward p, then k + r n moved by t delta. Not inside the core's sweep:
  // there the deepest instance's boundary often lies inside another, and Newton's steps on
  // the distance came back sooner (W1's raster with a flat end mill: 3.7 such steps a vertex).
  const Eigen::Vector3d y = tool_frame(x);
  double t;
  const double f =
      convex_minimum([&](double at, double& value, double& num, double& den) { cylinder_eval(y, at, value, num, den); },
                     delta_length_, std::numeric_limits<double>::infinity(), &t);
  if (!(f > 0.0)) return false;
  const Eigen::Vector3d p = y - t * delta_tool_;
  const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());
  const double radial = rho > core_.core_radius_mm ? core_.core_radius_mm / rho : 1.0;
  const Eigen::Vector3d k(p.x() * radial, p.y() * radial, std::clamp(p.z(), core_.z_low_mm, core_.z_high_mm));
  const Eigen::Vector3d n = (p - k) / f;
  out = origin_ + to_tool_.transpose() * (k + core_.rounding_mm * n + t * delta_tool_);
  return true;
}

namespace {

// TranslationSweep::cylinder_eval's constants.
struct CylinderConstants {
  double dx, dy, dz, mid, half, core_radius;
  double ex, ey, ez;  // the direction the slope is taken along (tool frame)
};

#if defined(__x86_64__)
using detail::all;
using detail::select;
using detail::v4d;
using detail::v4i;
using detail::vsqrt;

// cylinder_eval at t for four points (their tool-frame coordinates in lanes): its operations
// in the same order, each case's values worked out in every lane and the lane's case picked.
VCUT_AVX2 void cylinder_eval_lanes(const CylinderConstants& c, v4d yx, v4d yy, v4d yz, double t, v4d& f, v4d& num,
                                   v4d& den, v4d& along_num) {
  const v4d zero = all(0.0), px = yx - all(t * c.dx), py = yy - all(t * c.dy), pz = yz - all(t * c.dz);
  const v4d rho = vsqrt(px * px + py * py);
  const v4d dr = rho - all(c.core_radius);
  const v4d q = pz - all(c.mid);
  const v4d dz = select(q < zero, -q, q) - all(c.half);
  const v4d dz_slope = select(q > zero, all(-c.dz), select(q < zero, all(c.dz), zero));
  const v4i on_axis = !(rho > zero);
  const v4d radial = select(on_axis, zero, -(px * all(c.dx) + py * all(c.dy)));
  const v4d radial_e = select(on_axis, zero, px * all(c.ex) + py * all(c.ey));
  const v4d dz_e = select(q > zero, all(c.ez), select(q < zero, all(-c.ez), zero));
  const v4i corner = (dr > zero) & (dz > zero);
  const v4i side = (dr > zero) | ((dz <= zero) & (dr >= dz));
  const v4d corner_f = vsqrt(dr * dr + dz * dz);
  const v4d corner_num = dr * (radial / select(on_axis, all(1.0), rho)) + dz * dz_slope;
  const v4d corner_along = dr * (radial_e / select(on_axis, all(1.0), rho)) + dz * dz_e;
  f = select(corner, corner_f, select(side, dr, dz));
  num = select(corner, corner_num, select(side, radial, dz_slope));
  along_num = select(corner, corner_along, select(side, radial_e, dz_e));
  den = select(corner, corner_f, select(side, select(on_axis, all(1.0), rho), all(1.0)));
}

// f, num, den and the slope's numerator along e at t = 1 for the points y[0 .. m - 1], and at
// t = 0 too where the end t = 1 leaves one open (num > 0): `open`.
__attribute__((target("avx2"))) bool end_values_lanes(const CylinderConstants& c, const Eigen::Vector3d* y, int m,
                                                      double* fb, double* nb, double* db, double* eb, double* fa,
                                                      double* na, double* da, double* ea) {
  double yx[4], yy[4], yz[4];
  for (int j = 0; j < 4; ++j) {
    const Eigen::Vector3d& p = y[std::min(j, m - 1)];
    yx[j] = p.x(), yy[j] = p.y(), yz[j] = p.z();
  }
  const v4d x{yx[0], yx[1], yx[2], yx[3]}, yv{yy[0], yy[1], yy[2], yy[3]}, z{yz[0], yz[1], yz[2], yz[3]};
  v4d f, num, den, along;
  cylinder_eval_lanes(c, x, yv, z, 1.0, f, num, den, along);
  bool open = false;
  for (int j = 0; j < m; ++j) {
    fb[j] = f[j], nb[j] = num[j], db[j] = den[j], eb[j] = along[j];
    open |= !(nb[j] <= 0.0);
  }
  if (!open) return false;
  cylinder_eval_lanes(c, x, yv, z, 0.0, f, num, den, along);
  for (int j = 0; j < m; ++j) fa[j] = f[j], na[j] = num[j], da[j] = den[j], ea[j] = along[j];
  return true;
}
#else
// Never called (kHaveAvx2 is false off x86-64).
bool end_values_lanes(const CylinderConstants&, const Eigen::Vector3d*, int, double*, double*, double*, double*,
                      double*, double*, double*, double*) {
  return false;
}
#endif

}  // namespace

void TranslationSweep::distances(const Eigen::Vector3d* x, int n, double* out, bool lanes) const {
  distances(x, n, out, lanes, -1, nullptr);
}

void TranslationSweep::distances(const Eigen::Vector3d* x, int n, double* out, bool lanes, int axis,
                                 double* slope) const {
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  if (kind_ != Kind::General || ball() || cutter_.type == CutterType::VBit) {
    for (int j = 0; j < n; ++j) {
      out[j] = distance(x[j]);
      if (slope != nullptr) slope[j] = unknown;
    }
    return;
  }
  // convex_minimum for up to four points at a time: the end t = 1, then t = 0, each loop's
  // iterations independent of each other (or in AVX2 lanes); a point neither end settles
  // goes on alone.
  const double r = core_.rounding_mm, far = std::numeric_limits<double>::infinity();
  lanes = lanes && detail::kHaveAvx2;
  const Eigen::Vector3d e = axis >= 0 ? Eigen::Vector3d(to_tool_.col(axis)) : Eigen::Vector3d::Zero();
  const CylinderConstants constants{delta_tool_.x(),
                                    delta_tool_.y(),
                                    delta_tool_.z(),
                                    core_middle_mm(core_),
                                    core_half_mm(core_),
                                    core_.core_radius_mm,
                                    e.x(),
                                    e.y(),
                                    e.z()};
  for (int first = 0; first < n; first += 4) {
    const int m = std::min(4, n - first);
    Eigen::Vector3d y[4];
    double fb[4], nb[4], db[4], eb[4], fa[4], na[4], da[4], ea[4];
    for (int j = 0; j < m; ++j) y[j] = tool_frame(x[first + j]);
    bool open = false;
    if (lanes) {
      open = end_values_lanes(constants, y, m, fb, nb, db, eb, fa, na, da, ea);
    } else {
      for (int j = 0; j < m; ++j) cylinder_eval(y[j], 1.0, e, fb[j], nb[j], db[j], eb[j]);
      for (int j = 0; j < m; ++j) open |= !(nb[j] <= 0.0);
      if (open)
        for (int j = 0; j < m; ++j) cylinder_eval(y[j], 0.0, e, fa[j], na[j], da[j], ea[j]);
    }
    for (int j = 0; j < m; ++j) {
      double along = unknown;  // the slope where an end is the least and the point outside the core's sweep
      if (nb[j] <= 0.0) {
        out[first + j] = fb[j] - r;
        if (fb[j] > 0.0) along = eb[j] / db[j];
      } else if (na[j] >= 0.0) {
        out[first + j] = fa[j] - r;
        if (fa[j] > 0.0) along = ea[j] / da[j];
      } else {
        auto eval = [&](double t, double& f, double& num, double& den) { cylinder_eval(y[j], t, f, num, den); };
        out[first + j] =
            convex_minimum_between(eval, delta_length_, far, fa[j], na[j] / da[j], fb[j], nb[j] / db[j]) - r;
      }
      if (slope != nullptr) slope[first + j] = along;
    }
  }
}

double TranslationSweep::distance(const Eigen::Vector3d& x, double far_mm) const {
  const Eigen::Vector3d y = tool_frame(x);
  switch (kind_) {
    case Kind::Across: {
      // Core + segment = stadium (disk swept along a segment in the plane) x [z_low, z_high].
      const double d_plane = (y.head<2>() - across_spine(y)).norm() - core_.core_radius_mm;
      return extrude(d_plane, interval_distance(y.z(), core_.z_low_mm, core_.z_high_mm)) - core_.rounding_mm;
    }
    case Kind::Along: {
      // Core + segment = a longer cylinder.
      double lo, hi;
      along_span(lo, hi);
      return extrude(y.head<2>().norm() - core_.core_radius_mm, interval_distance(y.z(), lo, hi)) - core_.rounding_mm;
    }
    case Kind::General: {
      if (ball()) return (y - ball_core_point(y)).norm() - core_.rounding_mm;
      if (cutter_.type != CutterType::VBit)
        return cylinder_sweep_distance(y, far_mm + core_.rounding_mm) - core_.rounding_mm;
      return vbit_sweep_distance(y, far_mm);
    }
  }
  return 0.0;
}

}  // namespace vcut::removal
