// Places mesh vertices on the exact machined surface, shared by the stock engines.
// Internal to vcut::removal.
#pragma once

#include <Eigen/Core>
#include <openvdb/Types.h>

#include <functional>
#include <vector>

#include "vcut/removal/move.h"
#include "vcut/removal/stock.h"
#include "vcut/removal/sweep.h"

namespace vcut::removal::detail {

// An engine's record of every move cut so far, by id (the ids the stock stores; they count
// across cuts). A cut's cutters are appended first (remember_cutters returns the index of
// the first), then its moves a batch at a time (cutter indices shifted by that). Only moves
// the stock still names need their geometry, for the mesher's projection: a stock may drop
// the others (keep_only), and the record then grows with the machined surface, not with
// the program.
int remember_cutters(const std::vector<Cutter>& from, std::vector<Cutter>& cutters);
class MoveRecord {
 public:
  int next_id() const { return next_id_; }
  void append(const Move* first, std::size_t count, int cutter_base);
  // The move with this id, which must be kept.
  const Move& at(int id) const;
  // Keeps the moves whose ids are marked (named[id]) and drops the rest.
  void keep_only(const std::vector<bool>& named);
  std::size_t kept() const { return moves_.size(); }
  std::size_t memory_bytes() const { return ids_.capacity() * sizeof(int) + moves_.capacity() * sizeof(Move); }

 private:
  std::vector<int> ids_;  // ascending, of the moves kept
  std::vector<Move> moves_;
  int next_id_ = 0;
};

// The sweeps of the moves a run of neighbouring vertices or cells names, built once each:
// neighbours share their moves. Indices stay valid until the next make_room.
class SweepCache {
 public:
  SweepCache(const MoveRecord& moves, const std::vector<Cutter>& cutters) : moves_(moves), cutters_(cutters) {}
  // Before asking for `incoming` more: forgets all when they would pass the cache's size.
  void make_room(std::size_t incoming) {
    if (held_.size() + incoming > kSize) held_.clear();
  }
  // The index of move `id`'s sweep, built when not held.
  std::size_t index_of(int id) {
    for (std::size_t i = 0; i < held_.size(); ++i)
      if (held_[i].first == id) return i;
    const Move& move = moves_.at(id);
    held_.emplace_back(id, TranslationSweep(cutters_[static_cast<std::size_t>(move.cutter)], move));
    return held_.size() - 1;
  }
  const TranslationSweep& operator[](std::size_t i) const { return held_[i].second; }

 private:
  static constexpr std::size_t kSize = 64;
  const MoveRecord& moves_;
  const std::vector<Cutter>& cutters_;
  std::vector<std::pair<int, TranslationSweep>> held_;
};

// volumeToMesh's polygons as an outward, counter-clockwise triangle mesh (OpenVDB winds
// level-set polygons clockwise seen from outside; quads are split in two).
SurfaceMesh mesh_from_polygons(const std::vector<openvdb::Vec3s>& points, const std::vector<openvdb::Vec3I>& triangles,
                               const std::vector<openvdb::Vec4I>& quads);

// The moves that shaped the stock around vertex v (ids in the engine's MoveRecord, ascending
// and distinct), written into `ids` (cleared first). Called once per vertex, from several
// threads at once.
using NearbyMoves = std::function<void(std::size_t v, std::vector<int>& ids)>;

// Moves every vertex onto the exact machined surface F(x) = max(initial(x), -s_m(x)) = 0
// by Newton steps, where the moves m are the vertex's `nearby` ones; each vertex takes the
// id of the move whose sweep is its surface (-1: the initial stock). A vertex that would
// travel farther than max_travel_mm found no surface nearby and stays where it is. (The
// moves are gathered per vertex as it is projected: a list per vertex held for the whole
// mesh took 180 MB on a 2.8 M-vertex mesh.)
void project_onto_machined_surface(const MoveRecord& moves, const std::vector<Cutter>& cutters,
                                   const std::function<double(const Eigen::Vector3d&)>& initial_distance,
                                   const NearbyMoves& nearby, double max_travel_mm, SurfaceMesh& mesh);

}  // namespace vcut::removal::detail
