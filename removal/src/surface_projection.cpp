#include "surface_projection.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "vcut/removal/compare.h"
#include "vcut/removal/sweep.h"
#include "initial_stock.h"

namespace vcut::removal::detail {
namespace {
// Mesh vertices are moved onto the exact surface to within this (mm).
constexpr double kProjectionTolerance_mm = 1e-7;
}  // namespace

std::function<double(const Eigen::Vector3d&)> initial_distance(const StockShape& shape,
                                                               std::shared_ptr<const DesignDistance>& mesh_distance) {
  if (const auto* box = std::get_if<BoxShape>(&shape))
    return [b = *box](const Eigen::Vector3d& x) { return box_distance(b, x); };
  if (const auto* cyl = std::get_if<CylinderShape>(&shape))
    return [c = *cyl](const Eigen::Vector3d& x) { return cylinder_distance(c, x); };
  mesh_distance = std::make_shared<const DesignDistance>(std::get<TriangleMesh>(shape));
  return [d = mesh_distance](const Eigen::Vector3d& x) { return d->signed_distance(x); };
}

int remember_cutters(const std::vector<Cutter>& from, std::vector<Cutter>& cutters) {
  const int cutter_base = static_cast<int>(cutters.size());
  cutters.insert(cutters.end(), from.begin(), from.end());
  return cutter_base;
}

void MoveRecord::append(const Move* first, std::size_t count, int cutter_base) {
  const std::size_t at = moves_.size();
  moves_.insert(moves_.end(), first, first + count);
  ids_.resize(at + count);
  for (std::size_t i = at; i < at + count; ++i) {
    moves_[i].cutter += cutter_base;
    ids_[i] = next_id_++;
  }
}

const Move& MoveRecord::at(int id) const {
  const auto it = std::lower_bound(ids_.begin(), ids_.end(), id);
  assert(it != ids_.end() && *it == id);
  return moves_[static_cast<std::size_t>(it - ids_.begin())];
}

void MoveRecord::keep_only(const std::vector<bool>& named) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < ids_.size(); ++i) {
    const auto id = static_cast<std::size_t>(ids_[i]);
    if (id >= named.size() || !named[id]) continue;
    ids_[kept] = ids_[i];
    moves_[kept] = moves_[i];
    ++kept;
  }
  ids_.resize(kept);
  moves_.resize(kept);
  ids_.shrink_to_fit();
  moves_.shrink_to_fit();
}

SurfaceMesh mesh_from_polygons(const std::vector<openvdb::Vec3s>& points, const std::vector<openvdb::Vec3I>& triangles,
                               const std::vector<openvdb::Vec4I>& quads) {
  SurfaceMesh mesh;
  mesh.mesh.vertices_mm.reserve(points.size());
  for (const auto& p : points) mesh.mesh.vertices_mm.emplace_back(p.x(), p.y(), p.z());
  mesh.mesh.triangles.reserve(triangles.size() + 2 * quads.size());
  for (const auto& t : triangles)
    mesh.mesh.triangles.emplace_back(static_cast<int>(t[0]), static_cast<int>(t[2]), static_cast<int>(t[1]));
  for (const auto& q : quads) {
    mesh.mesh.triangles.emplace_back(static_cast<int>(q[0]), static_cast<int>(q[2]), static_cast<int>(q[1]));
    mesh.mesh.triangles.emplace_back(static_cast<int>(q[0]), static_cast<int>(q[3]), static_cast<int>(q[2]));
  }
  return mesh;
}

void project_onto_machined_surface(const MoveRecord& moves, const std::vector<Cutter>& cutters,
                                   const std::function<double(const Eigen::Vector3d&)>& initial,
                                   const NearbyMoves& nearby, double max_travel_mm, SurfaceMesh& mesh) {
  const std::size_t count = mesh.mesh.vertices_mm.size();
  mesh.vertex_move.assign(count, -1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256), [&](const auto& range) {
    // The vertex's sweeps in the order of its candidates, from a cache kept across vertices.
    SweepCache made(moves, cutters);
    std::vector<std::size_t> sweeps;
    std::vector<int> ids;
    for (std::size_t v = range.begin(); v != range.end(); ++v) {
      nearby(v, ids);
      made.make_room(ids.size());
      sweeps.clear();
      for (int id : ids) sweeps.push_back(made.index_of(id));
      // The surface that leads (an index into sweeps, -1: the initial stock) and by how much
      // it leads the next one, at the last point the field was taken.
      int lead = -1;
      double gap = 0.0;
      auto field = [&](const Eigen::Vector3d& x) {
        double f = initial(x), second = -std::numeric_limits<double>::infinity();
        lead = -1;
        for (std::size_t k = 0; k < sweeps.size(); ++k) {
          // Only the two largest count: a sweep at least -second away may stop its search
          // there (a flat end mill's raster: dozens of candidates a vertex, each a search).
          const double cut = -made[sweeps[k]].distance(x, -second);
          if (cut > f) {
            second = f;
            f = cut;
            lead = static_cast<int>(k);
          } else {
            second = std::max(second, cut);
          }
        }
        gap = f - second;
        return f;
      };
      const Eigen::Vector3d start = mesh.mesh.vertices_mm[v];
      Eigen::Vector3d x = start;
      constexpr double kStep_mm = 1e-5;  // central differences: error O(h^2) on smooth parts
      // Every surface's distance is 1-Lipschitz (to its evaluation's error, far below this):
      // a surface leading the others by more than two steps and this leads them at every
      // point of the differences, where the field is then its value, the same number.
      constexpr double kLeadSlack_mm = 1e-6;
      bool settled = false;  // the field was last taken at x, within the tolerance
      for (int iteration = 0; iteration < 16; ++iteration) {
        const double f = field(x);
        if (std::abs(f) < kProjectionTolerance_mm) {
          settled = true;
          break;
        }
        const bool alone = gap > 2.0 * kStep_mm + kLeadSlack_mm;
        const int leader = lead;
        // A ball, flat or bull-nose end mill's sweep leading alone, x outside its core's sweep:
        // its nearest surface point (a ball's in closed form, a cylinder core's from one
        // search over the move), where Newton's steps took six more distances each, each a
        // search for a flat or a bull-nose.
        Eigen::Vector3d on;
        if (alone && leader >= 0 && made[sweeps[static_cast<std::size_t>(leader)]].surface_point(x, on)) {
          x = on;
          continue;
        }
        auto probe = [&](const Eigen::Vector3d& y) {
          if (!alone) return field(y);
          return leader < 0 ? initial(y) : -made[sweeps[static_cast<std::size_t>(leader)]].distance(y);
        };
        Eigen::Vector3d g;
        for (int a = 0; a < 3; ++a) {
          Eigen::Vector3d h = Eigen::Vector3d::Zero();
          h[a] = kStep_mm;
          g[a] = (probe(x + h) - probe(x - h)) / (2 * kStep_mm);
        }
        if (g.squaredNorm() < 0.25) break;  // on a kink: keep the point
        x -= f * g / g.squaredNorm();
      }
      if ((x - start).norm() > max_travel_mm || !x.allFinite()) {
        x = start;
        settled = false;
      }
      if (!settled) field(x);
      mesh.mesh.vertices_mm[v] = x;
      mesh.vertex_move[v] = lead < 0 ? -1 : ids[static_cast<std::size_t>(lead)];
    }
  });
}

}  // namespace vcut::removal::detail
