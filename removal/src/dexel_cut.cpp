// DexelStock::cut: the moves binned by tile, each tile's rays cut by the moves over it in
// program order; probes (rapids, shanks, holders) measured against the material they meet.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "dexel_impl.h"
#include "initial_stock.h"
#include "move_batches.h"
#include "ray_sweep.h"
#include "surface_projection.h"

namespace vcut::removal {

namespace {

// A ray holding more intervals than this is searched by bisection for those in a window;
// fewer, by a scan (bisection on every ray cost W1's and W5's cut 4 %).
constexpr std::uint32_t kScanIntervals = 8;
// At most this many turning moves' pieces are cut row by row together (cut_pieces).
// (W5 whole: 16 cut 0.943x and the impeller 1.023x; 8 0.959x and 0.989x.)
constexpr int kGroupPieces = 8;

// The ray's material the kernel need look at for a window [win_lo, win_hi] along it: from
// the first interval that ends past the window's start to the last that starts before its
// end, [bottom, top] (false: none in the window). The intervals are disjoint and in order;
// a ray that many earlier cuts left in shreds is searched by bisection.
inline __attribute__((always_inline)) bool material_in_window(const DexelSegment* seg, std::uint32_t n, double win_lo,
                                                              double win_hi, double& bottom, double& top) {
  std::uint32_t j = 0, last = n - 1;
  if (n <= kScanIntervals) {
    while (j < n && !(seg[j].lo_mm < win_hi && seg[j].hi_mm > win_lo)) ++j;
    if (j == n) return false;
    while (last > j && !(seg[last].lo_mm < win_hi)) --last;
  } else {
    j = static_cast<std::uint32_t>(
        std::partition_point(seg, seg + n, [&](const DexelSegment& g) { return g.hi_mm <= win_lo; }) - seg);
    if (j == n || !(seg[j].lo_mm < win_hi)) return false;
    last = static_cast<std::uint32_t>(
        std::partition_point(seg + j, seg + n, [&](const DexelSegment& g) { return g.lo_mm < win_hi; }) - seg - 1);
  }
  bottom = seg[j].lo_mm;
  top = seg[last].hi_mm;
  return true;
}

// Whether a ray's one interval [lo, hi] meets section_window's window at u, without the
// window's square root (on W1's x rays it was 9 % of the tile loop's samples): [lo, hi]
// meets [s_lo - reach, s_hi + reach] when the larger of lo - s_hi and s_lo - hi is below
// reach, compared as squares. 1 or 0 as section_window and material_in_window answer; -1
// where the comparison lies within kSectionMargin_mm, for them to decide by their own
// rounding. The margin is far above the rounding of either form (1e-14 mm at 100 mm), so
// the answers are theirs. (Rays of more intervals, tested the same way interval by
// interval, made the tile loop 7 % slower: its branches cost more than the square root.)
constexpr double kSectionMargin_mm = 1e-7;
inline __attribute__((always_inline)) int section_meets(const detail::RaySweep::SectionRow& row, double u, double lo,
                                                        double hi) {
  const double reach2 = detail::RaySweep::section_reach2(row, u);
  if (reach2 < 0.0) return 0;
  const double gap = std::max(lo - row.s_hi, row.s_lo - hi);
  if (gap < 0.0) return 1;  // reach >= 0
  const double above = gap + kSectionMargin_mm, below = gap - kSectionMargin_mm;
  if (above * above < reach2) return 1;
  if (below > 0.0 && below * below > reach2) return 0;
  return -1;
}

// Longest overlap (mm) of [a, b] with the ray's material, and where along the ray.
double overlap(const SegmentList& ray, double a, double b, double& middle) {
  double best = 0.0;
  const DexelSegment* s = ray.data();
  for (std::uint32_t i = 0; i < ray.size(); ++i) {
    const double lo = std::max<double>(s[i].lo_mm, a), hi = std::min<double>(s[i].hi_mm, b);
    if (hi - lo > best) {
      best = hi - lo;
      middle = 0.5 * (lo + hi);
    }
  }
  return best;
}

// Coherence between consecutive moves. For a ball-end mill, any motion: its sweep is the parallelogram
// P = {c + u a + t D : u in [0, H], t in [0, 1]} (c the ball centre at the start, a the tool
// axis, H the core's length, D the motion) grown by the ball radius, so a point whose
// nearest point of P lies on P's edge t = 0 is inside the cutter at the move's start. When
// the cutting move before ended there with the same cutter and axis, that instance was cut
// already. The nearest point lies on that edge exactly when
//   h(q) = q.D - (D.a) clamp(q.a, 0, H) <= 0,  q = x - c
// (the edge's normal cone: q.D_perp <= 0 beside it, q.D <= 0 below its lower end,
// (q - H a).D <= 0 above its upper one). Likewise with c at the end and -D for the edge
// t = 1, which the next cutting move's start instance covers.
// For any cutter (a solid of revolution) moving square to its axis (D.a = 0), h = q.D: the
// cutter is symmetric under the reflection that turns D into -D, so the instants t at which
// a point lies inside it are an interval symmetric about t* = q.D / |D|^2; when t* <= 0 and
// the point is in the sweep at all, that interval holds t = 0.
// A flat or bull-nose end mill moving any other way (ramps, contouring): the cutter is its
// core C (the solid cylinder of radius Rc about that axis segment) grown by r, and
// f(t) = dist(x - t D, C) is convex in t, so where f does not fall at t = 0 the instance at
// t = 0 is the nearest: where
//   h_C = D.(x - p_C(x)) = (D.a) (m - clamp(m, 0, H)) + (D.rho) max(0, 1 - Rc / |rho|) <= 0,
// m = q.a, rho = q - m a, p_C the nearest point of C (the ball's h when Rc = 0). The factor
// is in [0, 1), so h_C <= max(h, (D.a) (m - clamp(m, 0, H))): h <= 0 where m stays within
// [0, H] when D.a < 0 (no point below the core's bottom while the tool goes down), and at
// most H when D.a > 0, is enough (`core`), and h's tests below serve with that bound on m.
struct Handover {
  Vector3d c = Vector3d::Zero(), d = Vector3d::Zero(), a = Vector3d::UnitZ();
  double height_mm = 0.0;
  bool on = false;
  double da = 0.0;    // D.a
  bool core = false;  // h_C's bound: m >= 0 (D.a < 0) or m <= H (D.a > 0) as well

  // The test along the rays of one family, its coordinates picked out once per move.
  struct OnAxis {
    double c1, c2, d1, d2, cd, dk, a1, a2, ca, ak, da, height_mm;
    bool core;
    // True when every point of the ray at (u, w) with axis coordinate in [s_lo, s_hi] has
    // h <= 0 (and with `core`, m on the side it must keep). h is linear in s between the two
    // heights where q.a is 0 or H.
    bool covers(double u, double w, double s_lo, double s_hi) const {
      const double k0 = (u - c1) * d1 + (w - c2) * d2 - cd;
      const double m0 = (u - c1) * a1 + (w - c2) * a2 - ca;
      if (core && !core_side(m0 + ak * s_lo, m0 + ak * s_hi)) return false;
      auto h = [&](double s) { return k0 + dk * s - da * std::clamp(m0 + ak * s, 0.0, height_mm); };
      if (h(s_lo) > 0.0 || h(s_hi) > 0.0) return false;
      if (ak != 0.0) {
        for (double level : {0.0, height_mm}) {
          const double s = (level - m0) / ak;
          if (s > s_lo && s < s_hi && h(s) > 0.0) return false;
        }
      }
      return true;
    }
    // `core`'s bound on m, given m at both ends of the span (m is linear along the ray).
    bool core_side(double m_a, double m_b) const {
      if (da < 0.0) return std::min(m_a, m_b) >= 0.0;
      if (da > 0.0) return std::max(m_a, m_b) <= height_mm;
      return true;
    }
    // Row by row: h along the row of rays at w is built from two forms linear in (u, s),
    // L1 = k0 + dk s and L2 = m0 + ak s, as h = L1 - da clamp(L2, 0, H), that is
    //   h = max(min(L1 - da L2, L1), L1 - da H)    (da >= 0)
    //   h = min(max(L1 + e L2, L1), L1 + e H)      (e = -da > 0).
    // A form p u + q + r s is at most (or at least) a bound for every s in [s_lo, s_hi] on a
    // half-line of u: checked at both ends. The spans below are such half-lines' meets (u in
    // mm; lo > hi: none), with h kept kRowMargin from 0 so that the ray-wise test, in its own
    // rounding, agrees.
    static constexpr double kRowMargin = 1e-7;  // mm^2, as h: far above the ray-wise test's rounding
    struct Form {
      double p, q, r;  // u-coefficient, constant, s-coefficient
    };
    void row_forms(double w, Form& l1, Form& l1_l2, Form& l1_h) const {
      l1 = {d1, -c1 * d1 + (w - c2) * d2 - cd, dk};
      const Form l2{a1, -c1 * a1 + (w - c2) * a2 - ca, ak};
      l1_l2 = {l1.p - da * l2.p, l1.q - da * l2.q, l1.r - da * l2.r};
      l1_h = {l1.p, l1.q - da * height_mm, l1.r};
    }
    // Narrows range to where f <= bound (at_most) or f >= bound for every s.
    static void narrow(double* range, const Form& f, bool at_most, double bound, double s_lo, double s_hi) {
      const double extreme = at_most ? std::max(f.r * s_lo, f.r * s_hi) : std::min(f.r * s_lo, f.r * s_hi);
      const double rhs = bound - f.q - extreme;  // p u against rhs
      if (f.p != 0.0) {
        const double at = rhs / f.p;
        if ((f.p > 0.0) == at_most)
          range[1] = std::min(range[1], at);
        else
          range[0] = std::max(range[0], at);
      } else if (at_most ? rhs < 0.0 : rhs > 0.0) {
        range[0] = std::numeric_limits<double>::infinity();
      }
    }
    // Up to two spans of u where covers(u, w, lo, hi) holds for every [lo, hi] within
    // [s_lo, s_hi] (h <= -margin for every s): for da >= 0 where L1 <= -m, or where L1 - da L2
    // <= -m and L1 - da H <= -m; for da < 0 where L1 + e L2 <= -m and L1 <= -m, or where
    // L1 + e H <= -m.
    void covered_spans(double w, double s_lo, double s_hi, double span[2][2]) const {
      Form l1, l1_l2, l1_h;
      row_forms(w, l1, l1_l2, l1_h);
      constexpr double kAll = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 2; ++i) span[i][0] = -kAll, span[i][1] = kAll;
      narrow(span[0], l1, true, -kRowMargin, s_lo, s_hi);
      if (da < 0.0) narrow(span[0], l1_l2, true, -kRowMargin, s_lo, s_hi);
      narrow(span[1], l1_h, true, -kRowMargin, s_lo, s_hi);
      if (da >= 0.0) narrow(span[1], l1_l2, true, -kRowMargin, s_lo, s_hi);
      if (core && da != 0.0) {  // and m kept kRowMargin (mm) inside its side
        const Form l2{a1, -c1 * a1 + (w - c2) * a2 - ca, ak};
        for (int i = 0; i < 2; ++i)
          narrow(span[i], l2, da > 0.0, da > 0.0 ? height_mm - kRowMargin : kRowMargin, s_lo, s_hi);
      }
    }
    // The other way: up to two spans of u where h >= margin at every s in [s_lo, s_hi], so
    // that covers() is false for any [lo, hi] there: for da >= 0 (h is at least L1 - da H and
    // at least min(L1 - da L2, L1)) where L1 - da H >= m, or where L1 - da L2 >= m and L1 >=
    // m; for da < 0 where L1 >= m (then L1 + e H >= m too), or where L1 + e L2 >= m and
    // L1 + e H >= m.
    void uncovered_spans(double w, double s_lo, double s_hi, double span[2][2]) const {
      Form l1, l1_l2, l1_h;
      row_forms(w, l1, l1_l2, l1_h);
      constexpr double kAll = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 2; ++i) span[i][0] = -kAll, span[i][1] = kAll;
      narrow(span[0], da >= 0.0 ? l1_h : l1, false, kRowMargin, s_lo, s_hi);
      narrow(span[1], l1_l2, false, kRowMargin, s_lo, s_hi);
      narrow(span[1], da >= 0.0 ? l1 : l1_h, false, kRowMargin, s_lo, s_hi);
    }
  };
  OnAxis on_axis(int axis) const {
    const auto [i1, i2] = kOther[static_cast<std::size_t>(axis)];
    return {c[i1],   c[i2], d[i1],     d[i2], c[axis] * d[axis], d[axis], a[i1], a[i2], c[axis] * a[axis],
            a[axis], da,    height_mm, core};
  }
};

// Row by row, for an upright tool (axis +Z): along a row of rays of family `axis` at w, h
// is linear in the rays' coordinate u plus a function of s alone, h = slope u + base(w) +
// g(s) (g piecewise linear with corners where s - c_z is 0 or H, and only for z rays). Its
// bounds over a span of s are worked out once per move and family.
struct RowHandover {
  bool on = false;
  double slope = 0.0, g_max = 0.0, g_min = 0.0;
  double base0 = 0.0, base_w = 0.0;                      // base(w) = base0 + base_w w - clamp term
  double clamp_c = 0.0, clamp_d = 0.0, height_mm = 0.0;  // x, y rays: d clamp(w - c, 0, H)
  // The rows that `core`'s bound on m lets h's test cover (none for z rays outside it);
  // base is +inf in the others: nothing covered there, all() and at() say so.
  double w_lo = -std::numeric_limits<double>::infinity(), w_hi = std::numeric_limits<double>::infinity();

  double base(double w) const {
    if (!(w >= w_lo && w <= w_hi)) return std::numeric_limits<double>::infinity();
    return base0 + base_w * w - clamp_d * std::clamp(w - clamp_c, 0.0, height_mm);
  }
  // Whether every ray of the row at w is covered (h <= 0 for every s), else through `at`
  // where the covered half-line {u : slope u + base + g <= 0} begins (g = g_max: covered
  // for sure; g = g_min: perhaps covered).
  bool all(double w, double g) const { return slope == 0.0 && base(w) + g <= 0.0; }
  bool none(double w, double g) const { return slope == 0.0 && base(w) + g > 0.0; }
  double at(double w, double g) const { return -(base(w) + g) / slope; }
};

// The row-wise form needs the tool axis along +z.
bool upright(const Handover& h) { return h.a.x() == 0.0 && h.a.y() == 0.0 && h.a.z() > 0.0; }

RowHandover row_handover(const Handover& h, int axis, double s_lo, double s_hi) {
  RowHandover out;
  if (!h.on || !upright(h) || !(s_lo <= s_hi)) return out;
  const auto [a1, a2] = kOther[static_cast<std::size_t>(axis)];
  out.on = true;
  out.slope = h.d[a1];
  out.base0 = -h.c[a1] * h.d[a1] - h.c[a2] * h.d[a2];
  out.base_w = h.d[a2];
  if (axis != 2) {  // w is z
    out.clamp_c = h.c.z();
    out.clamp_d = h.d.z();
    out.height_mm = h.height_mm;
  }
  auto g = [&](double s) {
    const double along = (s - h.c[axis]) * h.d[axis];
    return axis != 2 ? along : along - h.d.z() * std::clamp(s - h.c.z(), 0.0, h.height_mm);
  };
  out.g_max = std::max(g(s_lo), g(s_hi));
  out.g_min = std::min(g(s_lo), g(s_hi));
  if (axis == 2) {
    for (double s : {h.c.z(), h.c.z() + h.height_mm}) {
      if (s > s_lo && s < s_hi) {
        out.g_max = std::max(out.g_max, g(s));
        out.g_min = std::min(out.g_min, g(s));
      }
    }
  }
  if (h.core && h.da != 0.0) {  // m = z - c_z kept OnAxis::kRowMargin inside its side
    constexpr double kMargin = Handover::OnAxis::kRowMargin;
    const double z_lo = h.da < 0.0 ? h.c.z() + kMargin : -std::numeric_limits<double>::infinity();
    const double z_hi = h.da > 0.0 ? h.c.z() + h.height_mm - kMargin : std::numeric_limits<double>::infinity();
    if (axis != 2) {
      out.w_lo = z_lo;
      out.w_hi = z_hi;
    } else if (!(s_lo >= z_lo && s_hi <= z_hi)) {
      out.w_lo = std::numeric_limits<double>::infinity();  // no row
    }
  }
  return out;
}

struct MoveHandover {
  Handover from_start;         // on: the cutting move before ended at this move's start
  Handover to_end;             // on: the cutting move after starts at this move's end
  Eigen::AlignedBox3d bounds;  // the sweep's box, as the cut loop sees it
  std::size_t next = 0;        // with to_end: the next cutting move
};

// For every move of the list: which of its neighbours cover part of its sweep. The
// neighbours are the cutting moves before and after it: rapids and the shank and holder
// probes between them remove nothing.
// Into `out`, whose storage a cut keeps from batch to batch.
void handovers(const MoveList& list, std::vector<MoveHandover>& out) {
  const std::size_t count = list.moves.size();
  out.resize(count);
  auto square = [&](const Move& m) {
    const Vector3d d = m.end_mm - m.start_mm;
    return std::abs(d.dot(m.axis)) <= 1e-12 * d.norm() * m.axis.norm();
  };
  // Any cutter square to its axis; ball, flat and bull-nose end mills any way (`core` for the
  // flat and the bull-nose then).
  auto by_core = [&](const Move& m) {
    const Cutter& c = list.cutters.at(static_cast<std::size_t>(m.cutter));
    return c.type != CutterType::VBit && core_of(c).core_radius_mm > 0.0 && !square(m);
  };
  auto eligible = [&](const Move& m) {
    if (m.rapid) return false;
    return list.cutters.at(static_cast<std::size_t>(m.cutter)).type != CutterType::VBit || square(m);
  };
  std::vector<std::size_t> next_cut(count + 1, count);
  for (std::size_t i = count; i-- > 0;) next_cut[i] = list.moves[i].rapid ? next_cut[i + 1] : i;
  std::vector<std::size_t> last_cut(count + 1, count);  // last_cut[i]: the last cutting move before i
  for (std::size_t i = 0; i < count; ++i) last_cut[i + 1] = list.moves[i].rapid ? last_cut[i] : i;
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
    const Move& m = list.moves[i];
    out[i] = MoveHandover{};
    if (!eligible(m)) return;
    const CutterCore core = core_of(list.cutters.at(static_cast<std::size_t>(m.cutter)));
    const Vector3d a = m.axis.normalized();
    const Vector3d c0 = m.start_mm + core.z_low_mm * a, c1 = m.end_mm + core.z_low_mm * a;
    const double height = core.z_high_mm - core.z_low_mm;
    auto joins = [&](const Move& first, const Move& second) {
      return eligible(first) && eligible(second) && first.cutter == second.cutter && first.axis == second.axis &&
             first.end_mm == second.start_mm;
    };
    const std::size_t before = last_cut[i], after = next_cut[i + 1];
    const Vector3d d = m.end_mm - m.start_mm;
    const bool cylinder = by_core(m);
    out[i].from_start = {c0, d, a, height, before < count && joins(list.moves[before], m), d.dot(a), cylinder};
    out[i].to_end = {c1, -d, a, height, after < count && joins(m, list.moves[after]), -d.dot(a), cylinder};
    out[i].next = after;
    out[i].bounds = TranslationSweep(list.cutters[static_cast<std::size_t>(m.cutter)], m).bounds();
  });
}

// A tilted tool's neighbours, for the tests along the rays of one family (the cut's
// ray-wise hand-over, and row by row row_skips).
struct RayNeighbours {
  bool start_on = false, end_on = false;
  Handover::OnAxis start, end, back;  // back: the next move's from_start
  double lo, hi, next_lo, next_hi;    // the move's and the next one's box along the rays
};

// The ray-wise tests' sure answers over a whole row (at w_mm, rays k0..k1 of a family whose
// first ray is lattice index lo_u, spacing v), as up to six ranges of ray indices to skip,
// a hair inside: the rays the move before surely cut (its end instance is this move's
// start), and those the end instance surely holds where the next move's start test surely
// does not hold (the next move cuts them and will not pass them over). Out of line: the
// cut's loop around it runs faster without it inside.
__attribute__((noinline)) int row_skips(const RayNeighbours& r, double w_mm, int k0, int k1, int lo_u, double v,
                                        int (*skip)[2]) {
  int n = 0;
  auto skip_span = [&](double u_lo, double u_hi) {
    constexpr double kInside = 1e-6;  // of a spacing
    if (!(u_lo <= u_hi)) return;
    const double lo = std::max(u_lo / v - 0.5 + kInside, static_cast<double>(k0 + lo_u));
    const double hi = std::min(u_hi / v - 0.5 - kInside, static_cast<double>(k1 + lo_u));
    if (!(lo <= hi)) return;
    skip[n][0] = static_cast<int>(std::ceil(lo)) - lo_u;
    skip[n][1] = static_cast<int>(std::floor(hi)) - lo_u;
    ++n;
  };
  if (r.start_on) {
    double span[2][2];
    r.start.covered_spans(w_mm, r.lo, r.hi, span);
    for (const auto& sp : span) skip_span(sp[0], sp[1]);
  }
  if (r.end_on) {
    double ends[2][2], backs[2][2];
    r.end.covered_spans(w_mm, r.lo, r.hi, ends);
    r.back.uncovered_spans(w_mm, r.next_lo, r.next_hi, backs);
    for (const auto& e : ends)
      for (const auto& b : backs) skip_span(std::max(e[0], b[0]), std::min(e[1], b[1]));
  }
  return n;
}

// The bits of word `word` outside the n ray index ranges skip[i][0]..skip[i][1].
__attribute__((noinline)) std::uint64_t skip_mask(const int (*skip)[2], int n, int word) {
  std::uint64_t keep = ~std::uint64_t{0};
  for (int i = 0; i < n; ++i) {
    const int lo = std::max(skip[i][0], 64 * word), hi = std::min(skip[i][1], 64 * word + 63);
    if (lo <= hi) keep &= ~((~std::uint64_t{0} << (lo % 64)) & (~std::uint64_t{0} >> (63 - hi % 64)));
  }
  return keep;
}

// Rounding allowance (mm) between a probe's window and the interval the kernel finds in
// it: far above the kernel's rounding, far below any depth that counts.
constexpr double kProbeMargin_mm = 1e-6;

struct Probe {
  int move;  // index in the batch
  int axis;
  double overlap_mm;
  Vector3d where_mm;
};

// A row's rays to cut (at most a tile's width): their offsets in the row, positions and
// material tops, and the intervals found.
struct RowRays {
  int k[kTileU];
  double u[kTileU], bottom[kTileU], top[kTileU], lo[kTileU], hi[kTileU];
  bool hit[kTileU];
};

struct TileResult {
  double removed_mm = 0.0;  // length along the family's rays
  std::vector<Probe> probes;
};

// A shank or holder probe whose axis is a lattice axis: that axis's rays alone find any
// material in its way thicker than the spacing, and its depth along them; the other two
// families would test thousands of rays per move for nothing more. -1: all three.
int probe_family(const Move& move) {
  if (!move.rapid || (move.probe != ProbeKind::Shank && move.probe != ProbeKind::Holder)) return -1;
  for (int a = 0; a < 3; ++a)
    if (std::abs(move.axis[a]) > 1.0 - 1e-12) return a;
  return -1;
}

}  // namespace

// One function, long: the batch's state (tiles, hand-overs, sweeps, the window) is shared
// by the lambdas of the hot loop that BM_CutMovesDexel measures; split into functions it
// would pass a dozen references a call.
CutResult DexelStock::cut(MoveSource& source, const CutOptions& options) {
  Impl& m = *impl_;
  CutResult result;
  const std::size_t total = source.size_hint();
  const std::vector<Cutter>& cutters = source.cutters();
  // Rays' endpoints hold move ids that count across calls: remember every move.
  const int id_base = m.moves.next_id();
  const int cutter_base = detail::remember_cutters(cutters, m.cutters);
  // Per rapid: the longest overlap with material seen along each family.
  std::map<int, std::array<Probe, 3>> probes;
  std::array<double, 3> removed_mm = {0.0, 0.0, 0.0};
  std::array<int, 4> tile_base = {0, 0, 0, 0};
  for (int a = 0; a < 3; ++a)
    tile_base[static_cast<std::size_t>(a + 1)] =
        tile_base[static_cast<std::size_t>(a)] + m.families[static_cast<std::size_t>(a)].tiles();
  const int tiles = tile_base[3];
  std::vector<int> start(static_cast<std::size_t>(tiles) + 1);
  std::vector<int> entries;
  std::vector<int> runs;              // per entry: cut_pieces' runs (see below)
  std::vector<unsigned char> in_run;  // per move of the batch: whether it can join a run
  std::vector<std::int64_t> rays_of(static_cast<std::size_t>(tiles));  // per tile: its moves' rays, summed
  // A move's rays in each family (none: u0 > u1).
  struct RayBox {
    int u0 = 1, u1 = 0, w0 = 1, w1 = 0;
  };
  std::vector<std::array<RayBox, 3>> ray_boxes;
  // The binning's per tile and chunk of the batch's moves: how many of the chunk's moves
  // cover the tile (then where the first of them goes), and their rays.
  std::vector<int> chunk_count;
  std::vector<std::int64_t> chunk_rays;
  std::vector<std::optional<detail::RaySweep>> sweeps;  // kept: a batch's 4,096 sweeps are 20 MB
  std::vector<TileResult> results(static_cast<std::size_t>(tiles));
  tbb::enumerable_thread_specific<std::vector<DexelSegment>> scratch;
  // The moves around a batch that its hand-over tests look at: the last cutting move before
  // it and those after it up to the next cutting move (the batch is window.moves[off..]).
  MoveList window;
  window.cutters = cutters;
  std::vector<MoveHandover> handover;  // of the window's moves
  std::optional<Move> last_cutting;    // before the batch
  detail::MoveBatches batches(source);
  // The same for a whole row of an upright tool at once: narrows [u_lo, u_hi] to the rays
  // that neither neighbour takes (false: none), from bounds that hold for any material
  // along the rays within the move's box, so that no ray skipped here would be kept by the
  // test below. The next move's cover is bounded from the other side (its g_min): a ray it
  // might take is never left to it.
  struct RowNeighbours {
    RowHandover start, end, back;  // back: the next move's from_start
  };
  // Material never leaves the initial stock's box: the bounds over a move's box along the
  // rays need only hold within it (W1's z rays: g's top, a tool's length above the
  // tip, lies far above the stock).
  auto row_neighbours = [&](const MoveHandover& h, int axis) {
    RowNeighbours out;
    const double stock_lo = m.shape_bounds.min()[axis], stock_hi = m.shape_bounds.max()[axis];
    const double s_lo = std::max(h.bounds.min()[axis], stock_lo), s_hi = std::min(h.bounds.max()[axis], stock_hi);
    out.start = row_handover(h.from_start, axis, s_lo, s_hi);
    out.end = row_handover(h.to_end, axis, s_lo, s_hi);
    if (out.end.on) {
      const MoveHandover& next = handover[h.next];
      out.back = row_handover(next.from_start, axis, std::max(next.bounds.min()[axis], stock_lo),
                              std::min(next.bounds.max()[axis], stock_hi));
      if (!out.back.on) out.end.on = false;
    }
    return out;
  };
  auto kept_by_neighbours = [](const RowNeighbours& r, double w, double& u_lo, double& u_hi) {
    constexpr double kMargin_mm = 1e-9;  // keeps a ray on the boundary
    if (r.start.on) {
      const RowHandover& s = r.start;
      if (s.all(w, s.g_max)) return false;
      if (s.slope > 0.0) u_lo = std::max(u_lo, s.at(w, s.g_max) - kMargin_mm);
      if (s.slope < 0.0) u_hi = std::min(u_hi, s.at(w, s.g_max) + kMargin_mm);
    }
    if (!r.end.on) return u_lo <= u_hi;
    // Skipped: u in T = {end covers for sure} outside N = {back perhaps covers}, when that
    // is a half-line at one end of the row (or the whole row).
    const RowHandover &e = r.end, &b = r.back;
    if (b.all(w, b.g_min)) return u_lo <= u_hi;
    const bool n_empty = b.none(w, b.g_min);
    if (e.slope < 0.0 && (n_empty || b.slope > 0.0)) {  // T = u >= t, N = u <= n
      const double t = e.at(w, e.g_max);
      u_hi = std::min(u_hi, (n_empty ? t : std::max(t, b.at(w, b.g_min))) + kMargin_mm);
    } else if (e.slope > 0.0 && (n_empty || b.slope < 0.0)) {  // T = u <= t, N = u >= n
      const double t = e.at(w, e.g_max);
      u_lo = std::max(u_lo, (n_empty ? t : std::min(t, b.at(w, b.g_min))) - kMargin_mm);
    } else if (e.all(w, e.g_max)) {  // skipped: u outside N
      if (n_empty) return false;
      if (b.slope > 0.0)
        u_hi = std::min(u_hi, b.at(w, b.g_min) + kMargin_mm);
      else
        u_lo = std::max(u_lo, b.at(w, b.g_min) - kMargin_mm);
    }
    return u_lo <= u_hi;
  };
  // Skip the ray for move i when its neighbours cut all of it that move i would: the one
  // before when its end instance holds the ray's part of the sweep (it was cut first), the
  // one after when its start instance does, unless that one hands the ray back (it is cut
  // after this move, so one of the two must cut it). Each test spans the ray's material
  // within that move's box, as the move's own test does.
  auto ray_neighbours = [&](const MoveHandover& h, int axis) {
    RayNeighbours out;
    out.start_on = h.from_start.on;
    out.end_on = h.to_end.on;
    out.lo = h.bounds.min()[axis];
    out.hi = h.bounds.max()[axis];
    if (out.start_on) out.start = h.from_start.on_axis(axis);
    if (out.end_on) {
      const MoveHandover& next = handover[h.next];
      out.end = h.to_end.on_axis(axis);
      out.back = next.from_start.on_axis(axis);
      out.next_lo = next.bounds.min()[axis];
      out.next_hi = next.bounds.max()[axis];
    }
    return out;
  };
  // The span [lo, hi] of the ray's material within [box_lo, box_hi] (false: none there):
  // from the first interval ending above box_lo to the last one starting below box_hi, so
  // that material elsewhere along the ray does not widen it.
  auto material_within = [](const DexelSegment* s, std::uint32_t n, double box_lo, double box_hi, double& lo,
                            double& hi) {
    std::uint32_t i = 0, j = n - 1;
    while (i < j && s[i].hi_mm <= box_lo) ++i;
    while (j > i && s[j].lo_mm >= box_hi) --j;
    lo = std::max<double>(s[i].lo_mm, box_lo);
    hi = std::min<double>(s[j].hi_mm, box_hi);
    return lo <= hi;
  };
  auto handed_over = [&](const RayNeighbours& r, double u, double w, const DexelSegment* ray, std::uint32_t n) {
    if (!r.start_on && !r.end_on) return false;
    double lo, hi;
    if (!material_within(ray, n, r.lo, r.hi, lo, hi)) return true;  // nothing for this move to cut
    if (r.start_on && r.start.covers(u, w, lo, hi)) return true;
    if (!r.end_on || !r.end.covers(u, w, lo, hi)) return false;
    // Material the end instance covers lies in the next move's box: none there is only a
    // degenerate case, and the ray is then cut here.
    if (!material_within(ray, n, r.next_lo, r.next_hi, lo, hi)) return false;
    return !r.back.covers(u, w, lo, hi);
  };

  for (std::size_t first = 0;;) {
    const std::size_t count = std::min(kBatchMoves, batches.fill(kBatchMoves));
    if (count == 0) break;
    // Look ahead to the first cutting move after the batch (or the end).
    std::size_t ahead = count;
    for (;; ++ahead) {
      if (ahead == batches.held().size() && batches.fill(ahead + kBatchMoves) == ahead) break;
      if (!batches.held()[ahead].rapid) break;
    }
    const std::size_t last = first + count;
    window.moves.clear();
    if (last_cutting) window.moves.push_back(*last_cutting);
    const std::size_t off = window.moves.size();
    window.moves.insert(
        window.moves.end(), batches.held().begin(),
        batches.held().begin() + static_cast<std::ptrdiff_t>(std::min(ahead + 1, batches.held().size())));
    handovers(window, handover);
    const Move* const batch = window.moves.data() + off;
    sweeps.clear();
    sweeps.resize(count);
    in_run.assign(count, 0);
    std::atomic<bool> any_runs{false};
    ray_boxes.assign(count, {});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        // Material never leaves the initial stock's box: a tilted tool's part that stays out
        // of it need not be looked for along the rays, and a sweep clear of it (a holder
        // probe high above the part) meets no ray's material.
        const detail::RaySweep& sweep =
            sweeps[i].emplace(cutters.at(static_cast<std::size_t>(batch[i].cutter)), batch[i], &m.shape_bounds);
        // Turning moves' pieces (cutting, tilted, with no hand-over; so is any other such move)
        // are cut a run at a time (cut_pieces).
        const MoveHandover& h = handover[off + i];
        if (!batch[i].rapid && sweep.tilted() && !h.from_start.on && !h.to_end.on) {
          in_run[i] = 1;
          any_runs.store(true, std::memory_order_relaxed);
        }
        if (!sweep.bounds().intersects(m.shape_bounds)) continue;
        const int only = probe_family(batch[i]);
        for (int a = 0; a < 3; ++a) {
          RayBox& r = ray_boxes[i][static_cast<std::size_t>(a)];
          if ((only >= 0 && a != only) ||
              !m.ray_range(m.families[static_cast<std::size_t>(a)], sweep.bounds(), r.u0, r.u1, r.w0, r.w1))
            r = RayBox{};
        }
      }
    });
    // Bin the batch's moves to the tiles of rays their sweep's box covers (counting sort:
    // within a tile the moves stay in program order). The moves in chunks side by side, as
    // many as there are threads: any chunking gives the same lists (a chunk's moves of a tile
    // follow the chunks' before it), so the thread count changes nothing but the time.
    auto for_each_tile = [&](std::size_t i, auto&& visit) {
      for (int a = 0; a < 3; ++a) {
        const Family& f = m.families[static_cast<std::size_t>(a)];
        const RayBox& r = ray_boxes[i][static_cast<std::size_t>(a)];
        if (r.u0 > r.u1) continue;
        for (int tw = (r.w0 - f.lo_w) / kTileW; tw <= (r.w1 - f.lo_w) / kTileW; ++tw)
          for (int tu = (r.u0 - f.lo_u) / kTileU; tu <= (r.u1 - f.lo_u) / kTileU; ++tu) {
            const int tile_u0 = f.lo_u + tu * kTileU, tile_w0 = f.lo_w + tw * kTileW;
            const std::int64_t rays = std::int64_t{std::min(r.u1, tile_u0 + kTileU - 1) - std::max(r.u0, tile_u0) + 1} *
                                      (std::min(r.w1, tile_w0 + kTileW - 1) - std::max(r.w0, tile_w0) + 1);
            visit(tile_base[static_cast<std::size_t>(a)] + tw * f.tiles_u + tu, rays);
          }
      }
    };
    const std::size_t chunks = std::clamp<std::size_t>(
        count / kBinChunkMoves, 1, static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
    const std::size_t chunk_moves = (count + chunks - 1) / chunks;
    // Chunk-major: a chunk's slots lie apart from the others'.
    auto slot = [&](std::size_t c, int t) { return c * static_cast<std::size_t>(tiles) + static_cast<std::size_t>(t); };
    auto for_each_in_chunk = [&](std::size_t c, auto&& visit) {
      for (std::size_t i = c * chunk_moves; i < std::min(count, (c + 1) * chunk_moves); ++i)
        for_each_tile(i, [&](int t, std::int64_t rays) { visit(i, t, rays); });
    };
    chunk_count.assign(static_cast<std::size_t>(tiles) * chunks, 0);
    chunk_rays.assign(static_cast<std::size_t>(tiles) * chunks, 0);
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
      for_each_in_chunk(c, [&](std::size_t, int t, std::int64_t rays) {
        ++chunk_count[slot(c, t)];
        chunk_rays[slot(c, t)] += rays;
      });
    });
    start[0] = 0;
    for (int t = 0; t < tiles; ++t) {
      int at = start[static_cast<std::size_t>(t)];
      std::int64_t rays = 0;
      for (std::size_t c = 0; c < chunks; ++c) {
        const int n = chunk_count[slot(c, t)];
        chunk_count[slot(c, t)] = at;  // each chunk's count becomes its first slot
        at += n;
        rays += chunk_rays[slot(c, t)];
      }
      start[static_cast<std::size_t>(t) + 1] = at;
      rays_of[static_cast<std::size_t>(t)] = rays;
    }
    entries.resize(static_cast<std::size_t>(start[static_cast<std::size_t>(tiles)]));
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
      for_each_in_chunk(c, [&](std::size_t i, int t, std::int64_t) {
        entries[static_cast<std::size_t>(chunk_count[slot(c, t)]++)] = static_cast<int>(i);
      });
    });
    // The busy tiles, those the most rays' worth of moves cover first, handed out one at a
    // time: a few heavy tiles (where the tool dwells) then start early instead of last.
    // Tiles share no ray, so the order changes nothing but the time.
    std::vector<int> busy;
    for (int t = 0; t < tiles; ++t)
      if (start[static_cast<std::size_t>(t) + 1] > start[static_cast<std::size_t>(t)]) busy.push_back(t);
    std::vector<int> heaviest_first = busy;
    std::stable_sort(heaviest_first.begin(), heaviest_first.end(), [&](int x, int y) {
      return rays_of[static_cast<std::size_t>(x)] > rays_of[static_cast<std::size_t>(y)];
    });
    // Beside the tiles, one thread's work that would otherwise stand alone on the run's path
    // (W1 on 16 threads: 0.04 of the cut's 0.95 s): the move record (for the mesher) grows by
    // the batch, and the next batch's moves are pulled from the source. Neither touches what
    // the tiles read (the batch is the window's copy).
    tbb::task_group beside;
    beside.run([&] {
      m.moves.append(batch, count, cutter_base);
      batches.fill(count + 2 * kBatchMoves);  // the next batch and its look-ahead
    });
    // A run of turning moves' pieces (consecutive cutting entries, tilted, with no hand-over:
    // a move's pieces and the next move's) over one tile, row by row; returns the length
    // removed. Where the pieces cover much the same rays of a row (W5: 3.2 pieces a program
    // move 0.4 mm long, a tool 6-8 mm wide), the rays with material in a window box around
    // all of them are found once, and each piece then looks only at those: a ray clear of
    // the run costs one look, not one a piece. Where they lie apart, each piece takes its
    // own rays. Either way every ray meets the pieces in program order, each seeing what the
    // ones before left, as one piece after another over the whole tile would: the same cut.
    auto cut_pieces = [&](const int* list, int n, int a, int tile_u0, int tile_w0, std::vector<DexelSegment>& buffer,
                          SegmentArena& arena) __attribute__((noinline)) {
      double removed = 0.0;
      // windows: the candidates GroupReach leaves, then a piece's that meet its window
      RowRays rows, candidates, windows;
      Family& f = m.families[static_cast<std::size_t>(a)];
      const int lo_u = f.lo_u;  // a local: the rays' stores could otherwise alias it
      struct Piece {
        const detail::RaySweep* sweep;
        int id, u0, u1, w0, w1;
        double box_lo, box_hi;
      };
      Piece pieces[kGroupPieces];
      std::optional<detail::RaySweep::GroupWindow> window;  // made where a row first needs it
      std::optional<detail::RaySweep::GroupReach> reach;    // with it
      int w_lo = tile_w0 + kTileW, w_hi = tile_w0 - 1;
      for (int p = 0; p < n; ++p) {
        const int i = list[p];
        const detail::RaySweep& sweep = *sweeps[static_cast<std::size_t>(i)];
        const RayBox& box = ray_boxes[static_cast<std::size_t>(i)][static_cast<std::size_t>(a)];
        pieces[p] = {&sweep,
                     id_base + static_cast<int>(first) + i,
                     std::max(box.u0, tile_u0),
                     std::min(box.u1, tile_u0 + kTileU - 1),
                     std::max(box.w0, tile_w0),
                     std::min(box.w1, tile_w0 + kTileW - 1),
                     sweep.bounds().min()[a],
                     sweep.bounds().max()[a]};
        w_lo = std::min(w_lo, pieces[p].w0);
        w_hi = std::max(w_hi, pieces[p].w1);
      }
      const double v = m.v;
      for (int iw = w_lo; iw <= w_hi; ++iw) {
        const double w_mm = m.position(iw);
        struct Span {
          int k0, k1;  // the piece's rays in the row, from lo_u (k0 > k1: none)
          detail::RaySweep::TiltRow tilt;
        };
        Span spans[kGroupPieces];
        int k_lo = std::numeric_limits<int>::max(), k_hi = -1, span_sum = 0;
        double box_lo = std::numeric_limits<double>::infinity(), box_hi = -box_lo;
        for (int p = 0; p < n; ++p) {
          const Piece& piece = pieces[p];
          Span& span = spans[p];
          span.k0 = 1;
          span.k1 = 0;
          if (iw < piece.w0 || iw > piece.w1) continue;
          const double section = piece.sweep->row_section(a, w_mm);
          if (section < 0.0) continue;
          double row_lo, row_hi;
          piece.sweep->row_range(a, w_mm, section, row_lo, row_hi);
          span.k0 = std::max(piece.u0, static_cast<int>(std::ceil(m.index_of(row_lo)))) - lo_u;
          span.k1 = std::min(piece.u1, static_cast<int>(std::floor(m.index_of(row_hi)))) - lo_u;
          if (span.k0 > span.k1) continue;
          piece.sweep->tilted_row(a, w_mm, span.tilt);
          span_sum += span.k1 - span.k0 + 1;
          k_lo = std::min(k_lo, span.k0);
          k_hi = std::max(k_hi, span.k1);
          box_lo = std::min(box_lo, piece.box_lo);
          box_hi = std::max(box_hi, piece.box_hi);
        }
        if (k_lo > k_hi) continue;
        SegmentList* const row = &f.at(lo_u, iw);
        // The ray k (at u_mm) into `out` when it holds material within the window [win_lo,
        // win_hi] of its row: its material there, clamped to the window (the sweep lies in it).
        auto take_in_window = [&](const SegmentList& ray, int k, double u_mm, double win_lo, double win_hi,
                                  RowRays& out, int& count) {
          double bottom, top;
          if (!material_in_window(ray.data(), ray.size(), win_lo, win_hi, bottom, top)) return;
          out.k[count] = k;
          out.u[count] = u_mm;
          out.bottom[count] = std::max(bottom, win_lo);
          out.top[count] = std::min(top, win_hi);
          ++count;
        };
        // The ray k into `out` when it holds material within [lo, hi] and the window at its
        // row (tilt).
        auto take = [&](int k, double lo, double hi, const detail::RaySweep::TiltRow& tilt, RowRays& out, int& count) {
          const SegmentList& ray = row[k];
          const std::uint32_t size = ray.size();
          if (size == 0 || ray.first_lo_mm() >= hi || ray.last_hi_mm() <= lo) return;
          const double u_mm = (lo_u + k + 0.5) * v;  // m.position
          double win_lo, win_hi;
          if (detail::RaySweep::tilted_window(tilt, u_mm, win_lo, win_hi))
            take_in_window(ray, k, u_mm, win_lo, win_hi, out, count);
        };
        // The row's rays k0..k1 that take() keeps.
        auto gather = [&](int k0, int k1, double lo, double hi, const detail::RaySweep::TiltRow& tilt, RowRays& out) {
          int count = 0;
          for (int word = k0 / 64; word <= k1 / 64; ++word) {
            std::uint64_t walk = f.occupied_word(word, iw);
            if (word == k0 / 64) walk &= ~std::uint64_t{0} << (k0 % 64);
            if (word == k1 / 64) walk &= ~std::uint64_t{0} >> (63 - k1 % 64);
            for (; walk != 0; walk &= walk - 1) take(64 * word + __builtin_ctzll(walk), lo, hi, tilt, out, count);
          }
          return count;
        };
        // Piece p's intervals on the rays in `rows`, cut.
        auto cut = [&](const Piece& piece, int count) {
          piece.sweep->intervals_within(a, w_mm, count, rows.u, rows.bottom, rows.top, rows.lo, rows.hi, rows.hit);
          double sum = removed;  // in a local through the row, in the same order (as in the tile loop)
          for (int c = 0; c < count; ++c) {
            if (!rows.hit[c]) continue;
            const int k = rows.k[c];
            SegmentList& ray = row[k];
            sum +=
                subtract(ray, static_cast<float>(rows.lo[c]), static_cast<float>(rows.hi[c]), piece.id, buffer, arena);
            if (ray.size() == 0) f.occupied_word(k / 64, iw) &= ~(std::uint64_t{1} << (k % 64));
          }
          removed = sum;
        };
        // Pieces mostly apart along the row (the impeller's, the S-piece's): each its own rays.
        if (span_sum < 2 * (k_hi - k_lo + 1)) {
          for (int p = 0; p < n; ++p)
            if (spans[p].k0 <= spans[p].k1)
              cut(pieces[p], gather(spans[p].k0, spans[p].k1, pieces[p].box_lo, pieces[p].box_hi, spans[p].tilt, rows));
          continue;
        }
        // Over much the same rays (W5's): those with material within the window around all
        // the pieces first, then each piece's among them.
        if (!window) {
          const detail::RaySweep* group[kGroupPieces] = {};
          for (int p = 0; p < n; ++p) group[p] = pieces[p].sweep;
          window.emplace(group, n);
          reach.emplace(group, n);
        }
        detail::RaySweep::TiltRow group_row;
        window->row(a, w_mm, group_row);
        // Those whose material lies clear of every piece's bracket (GroupReach) go no further:
        // shreds beside the tool, which each piece would otherwise look at and pass over.
        const int gathered = gather(k_lo, k_hi, box_lo, box_hi, group_row, candidates);
        const int reached = reach->not_clear(a, w_mm, gathered, candidates.u, candidates.bottom, candidates.top,
                                             windows.k, pieces[0].sweep->lanes());
        int held = 0;
        for (int j = 0; j < reached; ++j) {
          const int c = windows.k[j];
          candidates.k[held] = candidates.k[c];
          candidates.u[held] = candidates.u[c];
          candidates.bottom[held] = candidates.bottom[c];
          candidates.top[held] = candidates.top[c];
          ++held;
        }
        for (int p = 0; p < n; ++p) {
          const Span& span = spans[p];
          if (span.k0 > span.k1) continue;
          int count = 0;
          // A candidate's material in the run's window when it was gathered holds all it has
          // in the piece's window now (the pieces before only took some away): where the two
          // windows' spans do not meet, the ray is passed over unread.
          const int c0 = static_cast<int>(std::lower_bound(candidates.k, candidates.k + held, span.k0) - candidates.k);
          const int c1 =
              static_cast<int>(std::upper_bound(candidates.k + c0, candidates.k + held, span.k1) - candidates.k);
          const int met = detail::RaySweep::tilted_windows(span.tilt, c1 - c0, candidates.u + c0,
                                                           candidates.bottom + c0, candidates.top + c0, windows.k,
                                                           windows.lo, windows.hi, pieces[p].sweep->lanes());
          for (int j = 0; j < met; ++j) {
            const int c = c0 + windows.k[j];
            const int k = candidates.k[c];
            const SegmentList& ray = row[k];
            if (ray.size() == 0 || ray.first_lo_mm() >= pieces[p].box_hi || ray.last_hi_mm() <= pieces[p].box_lo)
              continue;
            take_in_window(ray, k, candidates.u[c], windows.lo[j], windows.hi[j], rows, count);
          }
          cut(pieces[p], count);
        }
      }
      return removed;
    };
    // Each tile's runs of pieces: runs[e] is the run's length at its first entry, 0 at the
    // others, 1 for an entry cut on its own.
    runs.assign(entries.size(), 1);
    if (any_runs.load())
      tbb::parallel_for(std::size_t{0}, busy.size(), [&](std::size_t b) {
        const int t = busy[b];
        const int end = start[static_cast<std::size_t>(t) + 1];
        for (int e = start[static_cast<std::size_t>(t)]; e < end;) {
          int g = e + 1;
          if (in_run[static_cast<std::size_t>(entries[static_cast<std::size_t>(e)])])
            while (g < end && g - e < kGroupPieces &&
                   in_run[static_cast<std::size_t>(entries[static_cast<std::size_t>(g)])])
              ++g;
          if (g > e + 1) {
            runs[static_cast<std::size_t>(e)] = g - e;
            for (int k = e + 1; k < g; ++k) runs[static_cast<std::size_t>(k)] = 0;
          }
          e = g;
        }
      });
    std::atomic<std::size_t> next_busy{0};
    const std::size_t workers =
        std::min(busy.size(), static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
    tbb::parallel_for(std::size_t{0}, workers, [&](std::size_t) {
      auto& buffer = scratch.local();
      for (std::size_t b; (b = next_busy.fetch_add(1, std::memory_order_relaxed)) < busy.size();) {
        const int t = heaviest_first[b];
        const int a = t >= tile_base[2] ? 2 : (t >= tile_base[1] ? 1 : 0);
        Family& f = m.families[static_cast<std::size_t>(a)];
        const int lo_u = f.lo_u;  // a local: the rays' stores could otherwise alias it
        const int local = t - tile_base[static_cast<std::size_t>(a)];
        const int tu = local % f.tiles_u, tw = local / f.tiles_u;
        const int tile_u0 = f.lo_u + tu * kTileU, tile_w0 = f.lo_w + tw * kTileW;
        TileResult& r = results[static_cast<std::size_t>(t)];
        SegmentArena& arena = f.arenas[static_cast<std::size_t>(local)];
        r.probes.clear();
        double removed = 0.0;  // summed here, stored once: neighbouring tiles' results share cache lines
        RowRays rows;
        for (int e = start[static_cast<std::size_t>(t)]; e < start[static_cast<std::size_t>(t) + 1]; ++e) {
          const int i = entries[static_cast<std::size_t>(e)];
          // A run's first entry cuts the whole run; its other entries are done then.
          if (const int run = runs[static_cast<std::size_t>(e)]; __builtin_expect(run != 1, 0)) {
            if (run > 1)
              removed += cut_pieces(&entries[static_cast<std::size_t>(e)], run, a, tile_u0, tile_w0, buffer, arena);
            continue;
          }
          const detail::RaySweep& sweep = *sweeps[static_cast<std::size_t>(i)];
          const Move& move = batch[i];
          const bool rapid = move.rapid;
          const int id = id_base + static_cast<int>(first) + i;
          const RayBox& box = ray_boxes[static_cast<std::size_t>(i)][static_cast<std::size_t>(a)];  // as binned
          const int u0 = std::max(box.u0, tile_u0), u1 = std::min(box.u1, tile_u0 + kTileU - 1);
          const int w0 = std::max(box.w0, tile_w0), w1 = std::min(box.w1, tile_w0 + kTileW - 1);
          const double box_lo = sweep.bounds().min()[a], box_hi = sweep.bounds().max()[a];
          // The section window pays for itself on rays that run along the motion (a move
          // along x sweeps its disc along the x rays: most of the box is clear of it); across
          // the motion it is about the box again (W1's y rays: 2 % rejected).
          const Vector3d motion = move.end_mm - move.start_mm;
          const bool use_window = std::abs(motion[a]) * 2.0 >= motion.norm();
          // Tilted tools: the box window on every ray (on the S-piece at 0.1 mm it passed
          // over half the rays the kernel took, none of which the move would have cut).
          const bool tilted = sweep.tilted();
          Probe probe{i, a, 0.0, Vector3d::Zero()};
          const MoveHandover& hand = handover[off + static_cast<std::size_t>(i)];
          const RowNeighbours neighbours = row_neighbours(hand, a);
          // The ray-wise test only for a tilted tool, on the rays its rows' sure answers
          // (row_skips) leave: for an upright tool, after the row-wise bounds it cost more than
          // the cuts it saved (W1 on 40 mm, 1 thread: cut 1.294 -> 1.223 s without it; on 20 mm
          // 4.13 -> 3.80 G instructions).
          RayNeighbours ray_cover;
          if (!upright(hand.from_start)) ray_cover = ray_neighbours(hand, a);
          const bool ray_wise = ray_cover.start_on || ray_cover.end_on;
          const double v = m.v;
          // The tile's rows first (at most kTileW, independent of each other, so their chains
          // of divisions overlap), then their rays.
          struct RowSpan {
            int first_u, last_u;
            double section;
          };
          RowSpan spans[kTileW];
          for (int iw = w0; iw <= w1; ++iw) {
            RowSpan& span = spans[iw - w0];
            span = {1, 0, -1.0};
            const double w_mm = m.position(iw);
            span.section = sweep.row_section(a, w_mm);
            if (span.section < 0.0) continue;  // the row passes above or below the cutter throughout
            double row_lo, row_hi;
            sweep.row_range(a, w_mm, span.section, row_lo, row_hi);
            if (!kept_by_neighbours(neighbours, w_mm, row_lo, row_hi)) continue;
            span.first_u = std::max(u0, static_cast<int>(std::ceil(m.index_of(row_lo))));
            span.last_u = std::min(u1, static_cast<int>(std::floor(m.index_of(row_hi))));
          }
          for (int iw = w0; iw <= w1; ++iw) {
            const int first_u = spans[iw - w0].first_u, last_u = spans[iw - w0].last_u;
            if (first_u > last_u) continue;
            const double w_mm = m.position(iw), section = spans[iw - w0].section;
            // A ray whose material ends below this is clear: the box, and for z rays of a
            // cutting move the sweep's floor over the row.
            const double clear_below = a == 2 && !rapid ? std::max(box_lo, sweep.row_floor(a, w_mm)) : box_lo;
            const int k0 = first_u - lo_u, k1 = last_u - lo_u;
            SegmentList* const row = &f.at(lo_u, iw);
            const bool windowed = use_window && section < std::numeric_limits<double>::infinity();
            detail::RaySweep::TiltRow tilt_row{};
            detail::RaySweep::SectionRow section_row{};
            if (tilted)
              sweep.tilted_row(a, w_mm, tilt_row);
            else if (windowed)
              sweep.section_row(a, section, section_row);
            // A tilted tool's rays the move before cut for sure (its end instance is this
            // move's start): the ray-wise start test's spans over the whole box along the
            // rays, as ray indices (k_skip[i][0] > k_skip[i][1]: none), a hair inside.
            // Likewise the rays the end instance holds for sure (the next move cuts them) where
            // the next move's start test surely does not hold (it will not pass them over).
            int k_skip[6][2];
            const int skips = ray_wise ? row_skips(ray_cover, w_mm, k0, k1, lo_u, m.v, k_skip) : 0;
            // The row's rays that pass the tests below, then their intervals in one call.
            int count = 0;
            for (int word = k0 / 64; word <= k1 / 64; ++word) {
              std::uint64_t walk = f.occupied_word(word, iw);
              if (word == k0 / 64) walk &= ~std::uint64_t{0} << (k0 % 64);
              if (word == k1 / 64) walk &= ~std::uint64_t{0} >> (63 - k1 % 64);
              if (skips > 0) walk &= skip_mask(k_skip, skips, word);
              for (; walk != 0; walk &= walk - 1) {
                const int bit = __builtin_ctzll(walk);
                const int k = 64 * word + bit;
                SegmentList& ray = row[k];
                const std::uint32_t n = ray.size();
                if (n == 0) continue;
                const double top = ray.last_hi_mm();
                // Rays already clear of the sweep's box cost a look only.
                if (ray.first_lo_mm() >= box_hi || top <= clear_below) continue;
                const DexelSegment* const seg = ray.data();
                const double u_mm = (lo_u + k + 0.5) * v;  // m.position
                // A cutting move's section window on a ray of one interval: whether they meet is
                // all that is asked (the kernel then takes the whole interval, as below).
                if (windowed && !tilted && !rapid && n == 1) {
                  const int meets = section_meets(section_row, u_mm, seg[0].lo_mm, seg[0].hi_mm);
                  if (meets == 0) continue;
                  if (meets == 1) {
                    rows.k[count] = k;
                    rows.u[count] = u_mm;
                    rows.bottom[count] = seg[0].lo_mm;
                    rows.top[count] = top;
                    ++count;
                    continue;
                  }
                }
                double win_lo = box_lo, win_hi = box_hi;
                // A tighter window along the ray: the section disc about the tip's path, or
                // for a tilted tool the box about the sweep along its axis and motion.
                if ((windowed || tilted) &&
                    (tilted ? !detail::RaySweep::tilted_window(tilt_row, u_mm, win_lo, win_hi)
                            : !detail::RaySweep::section_window(section_row, u_mm, win_lo, win_hi)))
                  continue;
                // The ray's material the kernel need look at: all of it, or for a cutting move
                // with a window, from the first interval in the window to the last.
                double bottom = seg[0].lo_mm, material_top = top;
                if (rapid) {
                  // A probe keeps the longest overlap it finds: a ray with no material in the
                  // window, or less than that overlap by the margin, cannot replace it.
                  double middle;
                  const double longest = overlap(ray, win_lo, win_hi, middle);
                  if (longest <= 0.0 || (probe.overlap_mm > 0.0 && longest + kProbeMargin_mm <= probe.overlap_mm))
                    continue;
                } else if (windowed || tilted) {
                  if (!material_in_window(seg, n, win_lo, win_hi, bottom, material_top)) continue;
                  // The sweep lies in a tilted tool's window: the kernel need look no further
                  // (the root march then starts at the tool's tip plane, not below it).
                  if (tilted) {
                    bottom = std::max(bottom, win_lo);
                    material_top = std::min(material_top, win_hi);
                  }
                }
                rows.k[count] = k;
                rows.u[count] = u_mm;
                rows.bottom[count] = bottom;
                rows.top[count] = material_top;
                ++count;
              }
            }
            if (ray_wise) {
              int kept = 0;
              for (int c = 0; c < count; ++c) {
                const SegmentList& ray = row[rows.k[c]];
                if (handed_over(ray_cover, rows.u[c], w_mm, ray.data(), ray.size())) continue;
                rows.k[kept] = rows.k[c];
                rows.u[kept] = rows.u[c];
                rows.bottom[kept] = rows.bottom[c];
                rows.top[kept] = rows.top[c];
                ++kept;
              }
              count = kept;
            }
            sweep.intervals_within(a, w_mm, count, rows.u, rows.bottom, rows.top, rows.lo, rows.hi, rows.hit);
            if (rapid) {
              for (int c = 0; c < count; ++c) {
                if (!rows.hit[c]) continue;
                double middle = 0.0;
                const double depth = overlap(row[rows.k[c]], rows.lo[c], rows.hi[c], middle);
                if (depth > probe.overlap_mm) {
                  probe.overlap_mm = depth;
                  probe.where_mm = m.point(a, lo_u + rows.k[c], iw, middle);
                }
              }
              continue;
            }
            // The sum in a local through the row, in the same order: as `removed` it lived on
            // the stack, a store and a load on every cut ray's chain.
            double sum = removed;
            for (int c = 0; c < count; ++c) {
              if (!rows.hit[c]) continue;
              const int k = rows.k[c];
              SegmentList& ray = row[k];
              sum += subtract(ray, static_cast<float>(rows.lo[c]), static_cast<float>(rows.hi[c]), id, buffer, arena);
              if (ray.size() == 0) f.occupied_word(k / 64, iw) &= ~(std::uint64_t{1} << (k % 64));
            }
            removed = sum;
          }
          if (probe.overlap_mm > 0.0) r.probes.push_back(probe);
        }
        r.removed_mm = removed;
      }
    });
    beside.wait();
    // Gather in tile order: the same sums and the same collisions for any thread count.
    for (int t : busy) {
      const int a = t >= tile_base[2] ? 2 : (t >= tile_base[1] ? 1 : 0);
      const TileResult& r = results[static_cast<std::size_t>(t)];
      removed_mm[static_cast<std::size_t>(a)] += r.removed_mm;
      for (const Probe& p : r.probes) {
        auto& slot = probes[static_cast<int>(first) + p.move][static_cast<std::size_t>(a)];
        if (p.overlap_mm > slot.overlap_mm) {
          slot = p;
          slot.move = static_cast<int>(first) + p.move;
        }
      }
    }
    for (std::size_t i = 0; i < count; ++i)
      if (!batch[i].rapid) last_cutting = batch[i];
    batches.drop(count);
    first = last;
    // Moves no endpoint names any more leave the record (the mesher projects onto the moves
    // the endpoints name): it then grows with the machined surface, not with the program.
    if (m.moves.kept() >= 2 * m.kept_after_pruning + kPruneMoves) {
      // Value-initialised: all clear. Threads only ever set a flag, so relaxed stores do.
      std::vector<std::atomic<unsigned char>> flags(static_cast<std::size_t>(m.moves.next_id()));
      for (const Family& f : m.families)
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f.rays.size(), 4096), [&](const auto& range) {
          for (std::size_t r = range.begin(); r != range.end(); ++r)
            for (std::uint32_t k = 0; k < f.rays[r].size(); ++k) {
              const DexelSegment& seg = f.rays[r].data()[k];
              if (seg.lo_move != kNoMove)
                flags[static_cast<std::size_t>(seg.lo_move)].store(1, std::memory_order_relaxed);
              if (seg.hi_move != kNoMove)
                flags[static_cast<std::size_t>(seg.hi_move)].store(1, std::memory_order_relaxed);
            }
        });
      std::vector<bool> named(flags.size());
      for (std::size_t i = 0; i < flags.size(); ++i) named[i] = flags[i].load(std::memory_order_relaxed) != 0;
      m.moves.keep_only(named);
      m.kept_after_pruning = m.moves.kept();
    }
    if (options.progress) options.progress(last, std::max(total, last));
  }
  double removed = 0.0;
  for (int a = 0; a < 3; ++a) {
    m.families[static_cast<std::size_t>(a)].length_mm -= removed_mm[static_cast<std::size_t>(a)];
    removed += removed_mm[static_cast<std::size_t>(a)];
  }
  result.removed_volume_mm3 = removed * m.v * m.v / 3.0;
  // A rapid's depth in material: the shortest of the longest overlaps the three families
  // saw (a family that saw none is below its resolution there and does not count).
  for (const auto& [move, by_axis] : probes) {
    const Probe* best = nullptr;
    for (const Probe& p : by_axis)
      if (p.overlap_mm > 0.0 && (best == nullptr || p.overlap_mm < best->overlap_mm)) best = &p;
    if (best != nullptr && best->overlap_mm > options.collision_tolerance_mm)
      result.collisions.push_back({move, best->overlap_mm, best->where_mm});
  }
  return result;
}

}  // namespace vcut::removal
