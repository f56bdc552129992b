#include "vcut/removal/endpoint_check.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <cstdint>
#include <utility>

#include "vcut/removal/morton.h"

namespace vcut::removal {

EndpointDeviation endpoint_deviation(const std::vector<DexelEndpoint>& points, const Eigen::Vector3d& origin_mm,
                                     double v, const DesignDistance& design, const CompareSettings& settings) {
  // order[i]: the i-th point in Morton order (a ray's two ends can lie a stock's length apart).
  std::vector<std::pair<std::uint64_t, std::size_t>> order(points.size());
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) {
    const Eigen::Vector3d c = ((points[i].x_mm - origin_mm) / v).array().max(0.0);
    order[i] = {morton_code(static_cast<std::uint64_t>(c.x()), static_cast<std::uint64_t>(c.y()),
                            static_cast<std::uint64_t>(c.z())),
                i};
  });
  // The pairs are distinct: one sorted order for any thread count.
  tbb::parallel_sort(order.begin(), order.end());
  std::vector<double> d(points.size());  // in the order of `points`
  hinted_queries(points.size(), [&](std::size_t i, DistanceHint& hint) {
    const std::size_t p = order[i].second;
    d[p] = design.signed_distance(points[p].x_mm, hint);
  });
  EndpointDeviation e;
  e.points = points.size();
  std::size_t deepest = points.size();
  for (const auto& [key, i] : order) {  // the first of equally deep points in Morton order
    if (-d[i] > e.max_gouge_mm) {
      e.max_gouge_mm = -d[i];
      deepest = i;
    }
    e.max_excess_mm = std::max(e.max_excess_mm, d[i]);
    e.gouge_points += -d[i] > settings.gouge_tolerance_mm;
    e.excess_points += d[i] > settings.excess_tolerance_mm;
  }
  if (deepest < points.size()) {
    e.deepest_mm = points[deepest].x_mm;
    e.deepest_move = points[deepest].move;
  }
  return e;
}

}  // namespace vcut::removal
