// Where an axis-parallel ray meets the volume swept by one move (ARCHITECTURE §8).
// Internal to vcut::removal (the tri-dexel stock's cutting kernel).
//
// The cutter is convex and a translation sweeps it into a convex set, so a line meets the
// sweep in one interval. Three methods, chosen per move:
//  - Ball end, any tool axis: the sweep is a parallelogram P (the axis segment of the
//    core swept along the move) grown by the ball radius r; a line meets P + B(r) in the
//    hull of its meetings with the four edge capsules and the slab over P: closed form.
//  - Flat, bull-nose or V-bit with the tool axis +Z (three-axis work): the slice of the
//    sweep by the plane of the ray and the motion, in (s, t) = (along the ray, along the
//    move), is convex; its extent in s is the minimum of a convex function of t: closed
//    form when the cutter's cross-section at the ray does not change along the move (or the
//    ray stays over a bull-nose's flat core), else a bracketing search to
//    kRaySearchTolerance_mm.
//  - Flat end mill, tilted: a point of the ray at s is inside the instance at t when its
//    distance from the tool axis is at most R (an ellipse in (s, t)) and its height along the
//    axis lies in [0, H] (two lines), with t in [0, 1] (two more): the convex region's extent
//    in s, from the ellipse's s-extremes, its meetings with the lines and the lines' corners.
//    Where the ellipse degenerates (the motion along the axis, the ray along it, or both
//    square to it along one direction), three strips: a polygon, extreme at its vertices.
//  - Anything else (tilted bull-nose or V-bit): the sweep's signed distance along the ray is
//    convex and 1-Lipschitz in s; its two zero crossings are found by a safe root march,
//    started at the ends of the ray's interval in an enclosing ball sweep (the core's axis
//    segment swept and grown by R: closed form), and not at all where it misses that.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

#include "vcut/removal/cutter.h"
#include "vcut/removal/move.h"
#include "vcut/removal/sweep.h"

namespace vcut::removal::detail {

// Bracketing searches stop when the bracket is this small (mm along the ray, or mm of
// motion along the move): endpoints are exact to about this, far below the 1 um target.
inline constexpr double kRaySearchTolerance_mm = 1e-9;

// The line o + s e_axis (o[axis] ignored) against the solid cylinder of radius r around the
// segment p -> p + d, between the planes through p and p + d normal to d: [lo, hi] of s.
bool line_cylinder(int axis, const Eigen::Vector3d& o, const Eigen::Vector3d& p, const Eigen::Vector3d& d, double r,
                   double& lo, double& hi);

// Hidden: used only inside vcut_removal, so its calls from the cut's loop go direct.
class __attribute__((visibility("hidden"))) RaySweep {
 public:
  // material_box (none: anywhere): where all material lies. A tilted tool's window box
  // (tilted_window, row_range) stops at the height above the tip beyond which no point of the
  // tool comes inside it during the move (highest_point_in_box_mm). Only a filter: the kernel
  // still takes the whole cutter.
  RaySweep(const Cutter& cutter, const Move& move, const Eigen::AlignedBox3d* material_box = nullptr);

  // The ray parallel to coordinate axis `axis` (0 x, 1 y, 2 z) through the point whose two
  // other coordinates, in increasing axis order, are (u, w). Returns false when it misses the
  // sweep, else the interval [lo, hi] of the axis coordinate inside it.
  bool interval(int axis, double u, double w, double& lo, double& hi) const;
  // The same where only the interval's part within [bottom, top] matters (the ray holds no
  // material outside it that the sweep can reach): lo may then be any value <= max(true lo,
  // bottom) and hi any value >= min(true hi, top), and a sweep that meets the ray only
  // outside [bottom, top] may count as missed.
  bool interval_within(int axis, double u, double w, double bottom, double top, double& lo, double& hi) const;
  // interval_within for `count` rays of one row at w, at u[k] with material in
  // [bottom[k], top[k]]: hit[k], lo[k], hi[k]. One call per row keeps the kernel's constants
  // in registers.
  void intervals_within(int axis, double w, int count, const double* u, const double* bottom, const double* top,
                        double* lo, double* hi, bool* hit) const;

  const Eigen::AlignedBox3d& bounds() const { return bounds_; }

  // A range [u_lo, u_hi] holding every ray of family `axis` in the row at w that can meet
  // the sweep (an upright tool's from its section about the tip's path, a tilted one's the
  // row's slice of tilted_window's box: no ray outside it has a window).
  void row_range(int axis, double w, double& u_lo, double& u_hi) const {
    row_range(axis, w, row_section(axis, w), u_lo, u_hi);
  }
  // The same given the row's row_section(axis, w), for a caller that needs it too.
  void row_range(int axis, double w, double section, double& u_lo, double& u_hi) const;
  // For z rays (axis 2): a height below which the sweep does not reach anywhere in the row
  // y = w (-inf when no such bound is known): rays with no material above it are clear.
  double row_floor(int axis, double w) const;
  // For x and y rays of an upright tool: the widest section of the cutter over the row at
  // height w (+inf when unknown, < 0 when the row misses the cutter's height), and from it
  // a window [lo, hi] along the ray at u holding the ray's meeting with the sweep (false:
  // the ray misses). The section is a disc of at most that radius about the tip's path.
  // The row's part (section_row: the path's extent across and along the rays, the section
  // squared) is worked out once a row; the ray's (section_window) then takes a square root.
  double row_section(int axis, double w) const;
  struct SectionRow {
    double u_lo, u_hi;  // the tip's path across the rays (mm)
    double s_lo, s_hi;  // and along them (mm)
    double section2;    // the section's radius squared (mm^2)
  };
  void section_row(int axis, double section, SectionRow& row) const {
    const int a1 = axis == 0 ? 1 : 0;
    const double p1u = p0_[a1] + delta_[a1], p1s = p0_[axis] + delta_[axis];
    row = {std::min(p0_[a1], p1u), std::max(p0_[a1], p1u), std::min(p0_[axis], p1s), std::max(p0_[axis], p1s),
           section * section};
  }
  // The window's reach squared at u (< 0: the ray misses): the window is [s_lo - reach,
  // s_hi + reach].
  static double section_reach2(const SectionRow& row, double u) {
    const double du = u < row.u_lo ? row.u_lo - u : (u > row.u_hi ? u - row.u_hi : 0.0);
    return row.section2 - du * du;
  }
  static bool section_window(const SectionRow& row, double u, double& lo, double& hi) {
    const double reach2 = section_reach2(row, u);
    if (reach2 < 0.0) return false;
    const double reach = std::sqrt(reach2);
    lo = row.s_lo - reach;
    hi = row.s_hi + reach;
    return true;
  }

  // For a tilted tool: a window [lo, hi] along the ray at u of a row
  // holding its meeting with the sweep (false: the ray misses), from a box around the sweep
  // aligned with the tool axis and the motion. A ray with no material in the window is
  // clear of the move, found with a few products instead of the closed form or the march.
  // The row's part (tilted_row, at w) is worked out once: along each of the box's directions
  // the window's ends are c + slope u.
  bool tilted() const { return !vertical_axis_; }
  struct TiltRow {
    double c_lo[3], c_hi[3], slope[3];
    double u_min, u_max;  // where the directions square to the rays keep the row in the box
  };
  void tilted_row(int axis, double w, TiltRow& row) const { box_row(tilt_box_[axis], w, row); }
  static bool tilted_window(const TiltRow& row, double u, double& lo, double& hi) {
    if (!(u >= row.u_min && u <= row.u_max)) return false;
    // Pairwise max and min (comparing as std::max({...}) and std::min({...}) would), as the
    // four-ray tilted_windows does.
    const double along0 = row.slope[0] * u, along1 = row.slope[1] * u, along2 = row.slope[2] * u;
    lo = std::max(std::max(row.c_lo[0] + along0, row.c_lo[1] + along1), row.c_lo[2] + along2);
    hi = std::min(std::min(row.c_hi[0] + along0, row.c_hi[1] + along1), row.c_hi[2] + along2);
    return lo <= hi;
  }
  // tilted_window for the rays u[0 .. n - 1] whose material lies in [bottom, top]: those whose
  // window meets it (neither bottom >= hi nor top <= lo), in order, as `index` into them with
  // their windows [lo, hi]; their count. Four rays at a time with `lanes` (the same bits).
  static int tilted_windows(const TiltRow& row, int n, const double* u, const double* bottom, const double* top,
                            int* index, double* lo, double* hi, bool lanes);
  // Whether the four-ray kernels are taken (the processor has AVX2, VCUT_SCALAR_KERNELS unset).
  bool lanes() const { return lanes_; }

 private:
  // The box of tilted_window along one family's rays: the coordinate along direction k is
  // base + u du + w dw + s slope, within [lo, hi] (widened by a rounding margin).
  struct TiltBox {
    double base[3], du[3], dw[3], inv_slope[3], lo[3], hi[3];
    bool flat[3];
  };

 public:
  // material_clear for n tilted sweeps at once (a run of turning moves' pieces): one
  // reference segment, on the middle sweep's middle instance's axis as far as every sweep's
  // core segment reaches along it, and a reach that holds every sweep's bracket. A sweep's
  // bracket lies within its capsule radius plus half its move of its own middle core
  // segment, and every point of that segment within d of the reference segment, d the
  // farther of its two ends' distances (the distance to a convex set is convex along a line,
  // so largest at an end of a segment): so within the largest of r + half move + d. A ray's
  // material clear of it is clear of every sweep, and so is what the sweeps before leave of
  // it (they only take material away).
  class GroupReach {
   public:
    GroupReach(const RaySweep* const* sweeps, int n);
    bool clear(int axis, double u, double w, double bottom, double top) const;
    // The rays u[0 .. n - 1] of the row at w (material in [bottom, top]) that are not clear(),
    // in order, as `index` into them; their count. Four rays at a time with `lanes` (the same
    // bits).
    int not_clear(int axis, double w, int n, const double* u, const double* bottom, const double* top, int* index,
                  bool lanes) const;

   private:
    Eigen::Vector3d mid_, axis_;
    double z_low_mm_, z_high_mm_, reach_mm_;
  };
  // One window box around the window boxes of n tilted sweeps (a turning move's pieces):
  // the first's directions, its extents along them over every corner of every box (each box
  // is its corners' hull). Its rows and windows as tilted_row and tilted_window give them.
  class GroupWindow {
   public:
    GroupWindow(const RaySweep* const* sweeps, int n);
    void row(int axis, double w, TiltRow& row) const { box_row(box_[axis], w, row); }

   private:
    TiltBox box_[3];
  };

 private:
  // The three families' boxes for the box spanning [lo[k], hi[k]] along dirs[k] from origin.
  static void fill_tilt_boxes(const Eigen::Vector3d& origin, const Eigen::Vector3d* dirs, const double* lo,
                              const double* hi, TiltBox* boxes);
  static void box_row(const TiltBox& b, double w, TiltRow& row) {
    row.u_min = -std::numeric_limits<double>::infinity();
    row.u_max = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const double v0 = b.base[k] + w * b.dw[k];
      if (b.flat[k]) {
        row.c_lo[k] = -std::numeric_limits<double>::infinity();
        row.c_hi[k] = std::numeric_limits<double>::infinity();
        row.slope[k] = 0.0;
        if (b.du[k] == 0.0) {
          if (v0 < b.lo[k] || v0 > b.hi[k]) row.u_min = std::numeric_limits<double>::infinity();
          continue;
        }
        double e0 = (b.lo[k] - v0) / b.du[k], e1 = (b.hi[k] - v0) / b.du[k];
        if (e0 > e1) std::swap(e0, e1);
        row.u_min = std::max(row.u_min, e0);
        row.u_max = std::min(row.u_max, e1);
        continue;
      }
      // inv_slope > 0 (the box's direction taken along the ray): lo before hi.
      row.c_lo[k] = (b.lo[k] - v0) * b.inv_slope[k];
      row.c_hi[k] = (b.hi[k] - v0) * b.inv_slope[k];
      row.slope[k] = -b.du[k] * b.inv_slope[k];
    }
  }

  enum class Method { Ball, Upright, General };
  // What a tile's walk and the kernels read of a move's sweep first, together at the front:
  // every tile a move covers reads them, mostly from memory (a batch's 4,096 sweeps are 20
  // MB), and spread over the object's 5 KB they took W1's cut 2-5 % longer (ABBA: 0.95-0.974x
  // at 2 threads, 0.976x at one, together). The large per-family constants come last.
  Method method_;
  int segments_ = 0;  // 0: sphere, 1: one capsule c0 -> c0 + edge_a, 2: parallelogram
  int spheres_ = 0, edges_ = 0;
  bool vertical_axis_ = false;
  bool flat_bottom_ = false;  // flat end mill: underside at the tip, section constant
  bool cone_ = false;
  bool lanes_ = false;  // the processor has AVX2, and the four-ray kernel is wanted
  double radius_mm_;    // R
  double height_mm_;    // H = z_high + r, the top of the cutting part
  double capsule_r_ = 0.0;
  Eigen::AlignedBox3d bounds_;  // sweep_'s
  Eigen::Vector3d p0_, delta_;
  CutterCore core_;
  Eigen::Vector3d tool_axis_ = Eigen::Vector3d::UnitZ();
  // Ball: the parallelogram c0 + a*A + b*B, a, b in [0, 1].
  Eigen::Vector3d c0_, edge_a_, edge_b_;
  Eigen::Vector3d normal_, dual_a_, dual_b_;       // slab normal and dual basis (no slab if zero)
  double slab_low_mm_ = 0.0, slab_high_mm_ = 0.0;  // the move's (Move::slab_low_mm): the tilted window's heights
  Eigen::Vector3d tilt_dirs_[3];                   // the window box's directions: a, n1, n2 (GroupWindow's)
  Cutter cutter_;
  TranslationSweep sweep_;
  void prepare_tilt_box(const Eigen::AlignedBox3d* material_box);
  // With the ray's material [bottom, top] (as interval_within's; infinite: the whole line).
  bool upright_vertical(double u, double w, double top, double& lo, double& hi) const;
  bool upright_horizontal(int axis, double u, double w, double bottom, double top, double& lo, double& hi) const;
  // An upright bull-nose's horizontal line where its section changes along the move (a ramp
  // through the corner's heights): instance t's section at the line's height h(t) = h0 + t dh
  // above its tip is a disc of radius rho(h) centred c(t) = c0 + t dc along the line and off(t)
  // = w0 + t dw across it, over t in [ta, tb]. False with `decided`: the line misses the sweep;
  // `decided` false: the search ran out of steps (the caller takes the march).
  bool upright_ramp(double c0, double dc, double w0, double dw, double h0, double dh, double ta, double tb, double& lo,
                    double& hi, bool& decided) const;
  // upright_ramp's parts: T = [t1, t2] and the section at its ends (false: T is empty); the
  // section at t (false: its slope infinite); an extreme an end of T settles; the search for
  // one it does not.
  struct RampSpan {
    double t1, t2, half1, slope1 = 0.0, half2, slope2 = 0.0;
    bool finite1, finite2;
  };
  bool ramp_span(double w0, double dw, double h0, double dh, double ta, double tb, RampSpan& span) const;
  bool ramp_section(double t, double w0, double dw, double h0, double dh, double& half, double& d1, double& d2) const;
  static bool ramp_settled(const RampSpan& span, double s, double c0, double dc, double& value, double& best);
  bool ramp_search(const RampSpan& span, double s, double c0, double dc, double w0, double dw, double h0, double dh,
                   double best, double& value) const;
  // upright_horizontal's rays of a row where an upright bull-nose's or V-bit's section changes
  // along the move (upright_ramp, cone_interval), four at a time: false (nothing written) for
  // other rows.
  bool upright_ramps_avx2(int axis, double w, int count, const double* u, const double* bottom, const double* top,
                          double* lo, double* hi, bool* hit) const;
  // The root march over [bottom, top] of the ray (see interval_within).
  bool general(int axis, const Eigen::Vector3d& o, double bottom, double top, double& lo, double& hi) const;
  // The rest of general() given the bracket's interval [capsule_lo, capsule_hi] on the ray.
  bool bracketed(int axis, const Eigen::Vector3d& o, double bottom, double top, double capsule_lo, double capsule_hi,
                 double& lo, double& hi) const;
  // bracketed()'s start: the march's range [sa, sb] and the ends known without it. True where
  // that decides the ray (hit; lo and hi where it is hit), false where it takes the march.
  struct Bracket {
    double sa, sb, known_lo, known_hi;
    bool exact_lo, exact_hi;
  };
  bool bracket_ends(int axis, const Eigen::Vector3d& o, double bottom, double top, double capsule_lo, double capsule_hi,
                    Bracket& b, bool& hit, double& lo, double& hi) const;
  // bracketed()'s march to the sweep's first zero for n rays of the row at w, from `from`
  // toward `toward` along the ray at u (root, found and converged as march_to_root gives
  // them): the same steps ray by ray, four rays' distances taken together
  // (TranslationSweep::distances).
  struct MarchJob {
    double u, from, toward;
  };
  void march_lanes(int axis, double w, int n, const MarchJob* jobs, double* root, bool* found, bool* converged) const;
  // bracketed() for the rays todo[0 .. n - 1] of a row whose bracket hit (capsule_hit), the
  // marches four rays at a time; the same results.
  void bracketed_lanes(int axis, double w, int first, int n, const int* todo, const double* u, const double* bottom,
                       const double* top, const double* capsule_lo, const double* capsule_hi, const bool* capsule_hit,
                       double* lo, double* hi, bool* hit) const;
  // Bull-nose (band_): between the heights z_low = r and z_high above its tip the cutter is a
  // cylinder of radius R, and so is the bracket's capsule (the core's axis segment grown by
  // R). A point at a height strictly inside (z_low, z_high) above every instance's tip
  // (band_h_lo_mm_ < h < band_h_hi_mm_, h above the first tip) is nearest each instance's core
  // segment at an inner point, so it lies in the capsule sweep exactly when it lies in the
  // sweep: an end of the ray's capsule interval there is on the sweep's boundary and is the
  // sweep's own entry or exit (the sweep lies inside the capsule sweep), to the capsule's
  // 1e-9 mm margin. Likewise the sweep lies above the plane at height lowest_h_mm_ (above the
  // first tip) through the lowest instance's tip (lowest_tip_), and holds of that plane the
  // instance's flat bottom (the disc of the core's radius about the tip): a ray crossing the
  // plane there enters the sweep (leaves it, running down the tool axis).
  bool band_ = false;
  double band_h_lo_mm_ = 0.0, band_h_hi_mm_ = 0.0, lowest_h_mm_ = 0.0;
  Eigen::Vector3d lowest_tip_ = Eigen::Vector3d::Zero();
  // The ray's material [bottom, top] (finite), a ball about its middle, lies farther than
  // the capsule's radius plus half the move from the middle instance's core segment (every
  // instance's lies within half the move of it): clear of the capsule sweep, which holds the
  // sweep, for a few products instead of the capsule's closed form. Such rays are mostly
  // shreds the earlier pieces of a turning move left beside the tool (W5's bull-nose rows:
  // 0.03-2 mm long, 0.05-1.5 mm from the sweep, half the rays the window passes).
  bool material_clear(int axis, double u, double w, double bottom, double top) const;
  Eigen::Vector3d core_mid_ = Eigen::Vector3d::Zero();  // the middle instance's tip
  double half_move_mm_ = 0.0;
  // V-bit, tool axis not vertical: closed form. The tool is convex (a cone from the tip up to
  // radius R, a cylinder of radius R above it to the flute length H), and so is its sweep
  // along the move: a ray meets it in one interval, the extent in s of the convex region Q of
  // (s, t), t in [0, 1] the time along the move, where the ray's point at s lies in the
  // instance at t. Q is bounded by lines (t = 0, t = 1, the heights 0 and H above the tip)
  // and two conics (the cone's and the cylinder's surfaces), so its extremes in s are among
  // a fixed set of points: where a conic runs square to s, and where two boundaries meet.
  bool cone_interval(int axis, double u, double w, double& lo, double& hi) const;
  // cone_interval on a row's rays index[0 .. n) (the first n without an index), four at a time.
  void cone_intervals_avx2(int axis, double w, int n, const int* index, const double* u, double* lo, double* hi,
                           bool* hit) const;
  // The general method's march (band_ and the bracket's capsule), for a tilted tool or an
  // upright bull-nose moving up or down (upright_march_: its horizontal rays).
  void prepare_march();
  bool upright_march_ = false;
  // Its constants for the rays of one family: the tool axis's and the motion's coordinates
  // across the rays (a1, a2, d1, d2); y = A0 + A1 s - A2 t; per conic (0 the cone, 1 the
  // cylinder) its y^2 factor c and constant kappa, its coefficients in s and t that do not
  // depend on the ray, the leading coefficient of its extremes' quadratic (lead) and the
  // inverses; the cylinder's leading coefficient along the lines y = height (along_s: they
  // are written from s = (height - A0) / A1, else from t).
  struct ConeFamily {
    double a1, a2, d1, d2, A1, A2, inv_A1, inv_A2;
    double c[2], kappa[2], ss[2], st[2], tt[2], lead[2], inv_lead[2], inv_tt[2], inv_ss[2];
    double line_lead, inv_line_lead;
    bool along_s;
  };
  void prepare_cone_family(int axis);
  double cone_k_ = 0.0;       // radius per height of the cone
  double cone_top_mm_ = 0.0;  // the height at which the cone reaches cone_r_mm_ (<= H)
  double cone_r_mm_ = 0.0;    // the tool's widest radius (R, or the cone's at H when shorter)
  // Flat end mill, any tool axis: closed form; `decided` false in the degenerate cases
  // (motion along the tool axis, a ray along it) that general() then takes.
  bool tilted_flat(int axis, double u, double w, double& lo, double& hi, bool& decided) const;
  // tilted_flat's constants for the rays of one family, worked out once per move: the
  // ray's point o + s e in the tool frame has height h = hw + he s - hd t along the axis and
  // offset W + s E - t D from it (E, D, he, hd the same for every ray of the family).
  struct FlatFamily {
    // Ellipse: the closed form. Strips: degenerate, E and D parallel (or zero) to within 1e-7
    // mm over the move: the offset from the axis is W + (s e1 - t d1) u, and the instances'
    // points on the ray lie in three strips of the (s, t) plane (flat_strip). March: general().
    enum class Kind { Ellipse, Strips, March } kind = Kind::March;
    Eigen::Vector3d u = Eigen::Vector3d::Zero();  // Strips: zero when E and D both are
    double e1 = 0.0, d1 = 0.0;
    // Coordinates in the family's order (u, w, along the ray): the tool axis, the start
    // point, E and D.
    double a[3], p[3], E[3], D[3];
    double he, hd, EE, ED, DD, inv_DD, A, inv_2A, inv_2EE, inv_nn, qa_h, inv_2qa_h, inv_he;
    bool h_lines, corners;
  };
  void prepare_flat_family(int axis);
  bool flat_strip(int axis, double u, double w, double& lo, double& hi) const;

  // The ball method's pieces with everything that does not depend on the ray worked out per
  // ray family (no divisions left per ray).
  struct Edge {  // the cylinder of radius r around p -> p + d
    // With m = o - p = (u - p1, w - p2, -p_k): m.d = x d1 + y d2 + e0, |m|^2 - r^2 =
    // x^2 + y^2 + pk2, and the quadratic's half-b = bk - dk (m.d).
    double p1, p2, pk2, d1, d2, e0, bk, dd, dk, a, inv_a, inv_dk;
    bool parallel;
  };
  struct Slab {  // normal, dual_a, dual_b along the ray: value = base + c1 u + c2 w + slope s
    double base[3], c1[3], c2[3], inv_slope[3];
    bool flat[3];
  };
  struct BallFamily {
    double sphere[4][3];  // (u, w, along the ray) of each corner sphere
    Edge edge[4];
    Slab slab;
    // Upright ball, horizontal rays between the centres' and the top centres' heights.
    bool slab_band = false;
    double band_n_base = 0, band_n_u = 0, band_n_s = 0, band_t_base = 0, band_t_u = 0, band_t_s = 0;
  };
  void prepare_ball_family(int axis);
  bool ball_general(int axis, double u, double w, double& lo, double& hi) const;
  // ball_general for the rays todo[0 .. n - 1] of a row (u, lo, hi, hit by that index),
  // where the processor runs AVX2; at most kLanesBlock rays a call.
  static constexpr int kLanesBlock = 512;
  void bracket_avx2(int axis, double w, int n, const int* todo, const double* u, double* lo, double* hi,
                    bool* hit) const;
  // The rays first .. end - 1 whose material is not clear of the bracket (material_clear) and
  // with `in_box` within the sweep's box across the rays, by their index from first, into
  // todo (how many: returned); hit false for all of them.
  int not_clear_avx2(int axis, double w, int first, int end, const double* u, const double* bottom, const double* top,
                     bool in_box, bool* hit, int* todo) const;
  // The upright ball's rows the same way (intervals_within's capsule, band and vertical rows).
  void capsule_avx2(int axis, double w, int first, int count, const double* u, double* lo, double* hi, bool* hit) const;
  void band_avx2(int axis, double inv_n_s, double inv_t_s, int count, const double* u, double* lo, double* hi,
                 bool* hit) const;
  void vertical_avx2(double w, double floor_of_exit, int count, const double* u, const double* top, double* lo,
                     double* hi, bool* hit) const;
  // An upright tool's horizontal row at height w (family axis): the line's coordinates along
  // itself (c0 + t dc), across (u's axis: its offset from the axis is p0 - u + t dw) and its
  // height above the tip (h0 + t dh); the instants [ta, tb] the row lies within the cutter's
  // height (meets: some), and where the section stays the same along the move its radius.
  struct HorizontalRow {
    double c0, dc, dw, h0, dh, ta = 0.0, tb = 1.0, radius = 0.0;
    bool meets = false, same_section = false;
  };
  HorizontalRow horizontal_row(int axis, double w) const;
  // upright_horizontal's rays of a row where the section stays the same along the move (its
  // closed form), four at a time: false (nothing written) where it changes, for
  // upright_horizontal ray by ray.
  bool upright_horizontal_avx2(int axis, double w, int count, const double* u, double* lo, double* hi, bool* hit) const;
  // tilted_flat's closed form (Kind::Ellipse) on a row's rays, four at a time.
  void tilted_flat_avx2(int axis, double w, int count, const double* u, double* lo, double* hi, bool* hit) const;
  // An upright bull-nose's vertical rays (moving across them: dd > 0) as upright_vertical
  // takes them, four at a time where an end of the move settles both ends of the interval;
  // a ray that needs a search goes to upright_vertical.
  void upright_vertical_avx2(double w, int count, const double* u, const double* top, double* lo, double* hi,
                             bool* hit) const;
  // `lo_side`/`hi_side`: that end of the interval lies on the cylinder's side, not on an end
  // plane, so on the boundary of the capsule around the edge: its end spheres cannot move it.
  bool ball_cylinder(int axis, int edge, double u, double w, double& lo, double& hi, bool& lo_side,
                     bool& hi_side) const;

  // The ball sweep (c0_, edge_a_, edge_b_, ball_) of radius capsule_r: the ball method's
  // sweep, or the general method's bracket around the sweep.
  void prepare_capsule(double capsule_r);

  BallFamily ball_[3];
  FlatFamily flat_[3];
  ConeFamily cone_family_[3];
  TiltBox tilt_box_[3];
  Eigen::Vector3d tilt_corner_[8];  // the window box's corners (corner c: bit k set, the high side along k)
};

}  // namespace vcut::removal::detail
