#include "vcut/removal/endpoint_check.h"

#include <tbb/parallel_for.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>

namespace vcut::removal {

EndpointDeviation endpoint_deviation(const DexelStock& stock, const DesignDistance& design,
                                     const CompareSettings& settings) {
  // One row's figures; the deepest gouge point by its place in the row.
  struct Row {
    std::size_t points = 0, gouge_points = 0, excess_points = 0;
    double max_gouge_mm = 0.0, max_excess_mm = 0.0;
    DexelEndpoint deepest{Eigen::Vector3d::Zero(), -1, 0};
  };
  std::vector<Row> rows(stock.endpoint_rows());
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
    for (const DexelEndpoint& p : points) {
      const double s = p.x_mm[p.axis];
      int pick = -1;
      for (int h = 0; h < used; ++h)
        if (pick < 0 || std::abs(along[h] - s) < std::abs(along[pick] - s)) pick = h;
      DistanceHint hint = pick >= 0 ? hints[pick] : DistanceHint{};
      const double d = design.signed_distance(p.x_mm, hint);
      if (pick >= 0 && std::abs(along[pick] - s) <= near_mm) {
        along[pick] = s;
        hints[pick] = hint;
      } else {
        hints[next] = hint;
        along[next] = s;
        next = (next + 1) % kHints;
        used = std::min(used + 1, kHints);
      }
      if (-d > out.max_gouge_mm) {
        out.max_gouge_mm = -d;
        out.deepest = p;
      }
      out.max_excess_mm = std::max(out.max_excess_mm, d);
      out.gouge_points += -d > settings.gouge_tolerance_mm;
      out.excess_points += d > settings.excess_tolerance_mm;
    }
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
