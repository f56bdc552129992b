#include "vcut/removal/endpoint_check.h"

#include <tbb/parallel_for.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

namespace vcut::removal {

namespace {

// Rounding allowed between a point's bound (its distance to its hint's triangle) and the
// distance the full query finds: the two agree to the bit where the query takes the same
// triangle, and a point far from the design goes through CGAL's tree.
constexpr double kBoundSlack_mm = 1e-9;

void raise(std::atomic<double>& figure, double value) {
  double now = figure.load(std::memory_order_relaxed);
  while (value > now && !figure.compare_exchange_weak(now, value, std::memory_order_relaxed)) {
  }
}

}  // namespace

EndpointDeviation endpoint_deviation(const DexelStock& stock, const DesignDistance& design,
                                     const CompareSettings& settings) {
  // A point whose bound lies within both tolerances counts neither as a gouge nor as excess:
  // it matters only if it could be the deepest gouge or the thickest excess. Such points are
  // set aside (most of a finished surface: the S-piece's 9.3 M endpoints cost 1.2 CPU-s of
  // full queries) and measured after all rows only where their bound reaches the largest
  // figures the others gave; the rest cannot change any figure. The same figures, to the bit,
  // as measuring every point.
  const double within_mm = std::min(settings.gouge_tolerance_mm, settings.excess_tolerance_mm);
  struct Aside {
    std::uint32_t index;  // in the row
    float bound_mm;       // rounded up
  };
  // One row's figures; the deepest gouge point by its place in the row.
  struct Row {
    std::size_t points = 0, gouge_points = 0, excess_points = 0;
    double max_gouge_mm = 0.0, max_excess_mm = 0.0;
    DexelEndpoint deepest{Eigen::Vector3d::Zero(), -1, 0};
    std::size_t deepest_index = 0;
    std::vector<Aside> aside;
  };
  std::vector<Row> rows(stock.endpoint_rows());
  // The largest figures measured so far in any row: below the final ones, so a point whose
  // bound lies under both can be dropped at once (which ones depends on the threads' timing;
  // which are measured at the end does not: those whose bound reaches the final figures).
  std::atomic<double> gouge_so_far{0.0}, excess_so_far{0.0};
  auto measure = [&](Row& out, const DexelEndpoint& p, std::size_t index, DistanceHint& hint) {
    const double d = design.signed_distance(p.x_mm, hint);
    if (-d > out.max_gouge_mm || (-d > 0.0 && -d == out.max_gouge_mm && index < out.deepest_index)) {
      out.max_gouge_mm = -d;
      out.deepest = p;
      out.deepest_index = index;
    }
    out.max_excess_mm = std::max(out.max_excess_mm, d);
    return d;
  };
  tbb::enumerable_thread_specific<std::vector<DexelEndpoint>> scratch;
  tbb::parallel_for(std::size_t{0}, rows.size(), [&](std::size_t r) {
    std::vector<DexelEndpoint>& points = scratch.local();
    stock.row_endpoints(r, points);
    // Hints: up to kHints points' nearest triangles at different places along the rays, each
    // query taking the one nearest along them (a ray's intervals end near where its
    // neighbour's do). Reset per row: the same queries for any thread count.
    constexpr int kHints = 8;
    const double near_mm = 4.0 * stock.spacing_mm();  // a point this near replaces its hint
    DistanceHint hints[kHints];
    double along[kHints];
    int used = 0, next = 0;
    Row& out = rows[r];
    out.points = points.size();
    double gouge_floor = gouge_so_far.load(std::memory_order_relaxed),
           excess_floor = excess_so_far.load(std::memory_order_relaxed);
    for (std::size_t k = 0; k < points.size(); ++k) {
      const DexelEndpoint& p = points[k];
      const double s = p.x_mm[p.axis];
      int pick = -1;
      for (int h = 0; h < used; ++h)
        if (pick < 0 || std::abs(along[h] - s) < std::abs(along[pick] - s)) pick = h;
      DistanceHint hint = pick >= 0 ? hints[pick] : DistanceHint{};
      if (pick >= 0) {
        const double bound = design.distance_bound(p.x_mm, hint, within_mm - kBoundSlack_mm) + kBoundSlack_mm;
        if (bound <= within_mm) {
          hints[pick] = hint;  // perhaps a triangle beside the one it had: the next points start there
          const double keep_from =
              std::min(std::max(out.max_gouge_mm, gouge_floor), std::max(out.max_excess_mm, excess_floor));
          if (bound >= keep_from) {
            float rounded = static_cast<float>(bound);
            if (rounded < bound) rounded = std::nextafter(rounded, std::numeric_limits<float>::infinity());
            out.aside.push_back({static_cast<std::uint32_t>(k), rounded});
          }
          continue;
        }
      }
      const double d = measure(out, p, k, hint);
      if (pick >= 0 && std::abs(along[pick] - s) <= near_mm) {
        along[pick] = s;
        hints[pick] = hint;
      } else {
        hints[next] = hint;
        along[next] = s;
        next = (next + 1) % kHints;
        used = std::min(used + 1, kHints);
      }
      out.gouge_points += -d > settings.gouge_tolerance_mm;
      out.excess_points += d > settings.excess_tolerance_mm;
    }
    raise(gouge_so_far, out.max_gouge_mm);
    raise(excess_so_far, out.max_excess_mm);
    const double keep_from = std::min(out.max_gouge_mm, out.max_excess_mm);
    out.aside.erase(
        std::remove_if(out.aside.begin(), out.aside.end(), [&](const Aside& a) { return a.bound_mm < keep_from; }),
        out.aside.end());
  });
  // The points set aside that could reach the final figures (a gouge as deep as the deepest,
  // the first in order of which is kept; excess as thick), measured; none counts beyond a
  // tolerance.
  double max_gouge_mm = 0.0, max_excess_mm = 0.0;
  for (const Row& row : rows) {
    max_gouge_mm = std::max(max_gouge_mm, row.max_gouge_mm);
    max_excess_mm = std::max(max_excess_mm, row.max_excess_mm);
  }
  const double keep_from = std::min(max_gouge_mm, max_excess_mm);
  tbb::parallel_for(std::size_t{0}, rows.size(), [&](std::size_t r) {
    Row& row = rows[r];
    if (std::none_of(row.aside.begin(), row.aside.end(), [&](const Aside& a) { return a.bound_mm >= keep_from; })) {
      row.aside = {};
      return;
    }
    std::vector<DexelEndpoint>& points = scratch.local();
    stock.row_endpoints(r, points);
    DistanceHint hint;
    for (const Aside& a : row.aside)
      if (a.bound_mm >= keep_from) measure(row, points[a.index], a.index, hint);
    row.aside = {};
  });
  EndpointDeviation e;
  for (const Row& row : rows) {  // in row order: the first of equally deep points
    e.points += row.points;
    e.gouge_points += row.gouge_points;
    e.excess_points += row.excess_points;
    e.max_excess_mm = std::max(e.max_excess_mm, row.max_excess_mm);
    if (row.max_gouge_mm > e.max_gouge_mm) {
      e.max_gouge_mm = row.max_gouge_mm;
      e.deepest_mm = row.deepest.x_mm;
      e.deepest_move = row.deepest.move;
    }
  }
  return e;
}

}  // namespace vcut::removal
