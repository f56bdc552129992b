// Places mesh vertices on the exact machined surface, shared by the stock engines.
// Internal to vcut::removal.
#pragma once

#include <Eigen/Core>

#include <functional>
#include <vector>

#include "vcut/removal/move.h"
#include "vcut/removal/stock.h"

namespace vcut::removal::detail {

// Moves every vertex onto the exact machined surface F(x) = max(initial(x), -s_m(x)) = 0
// by Newton steps, where the moves m are `nearby[v]` (those that shaped the stock around
// vertex v, indices into `moves`); each vertex takes the id of the move whose sweep is its
// surface (-1: the initial stock). A vertex that would travel farther than max_travel_mm
// found no surface nearby and stays where it is.
void project_onto_machined_surface(const std::vector<Move>& moves, const std::vector<Cutter>& cutters,
                                   const std::function<double(const Eigen::Vector3d&)>& initial_distance,
                                   const std::vector<std::vector<int>>& nearby, double max_travel_mm,
                                   SurfaceMesh& mesh);

}  // namespace vcut::removal::detail
