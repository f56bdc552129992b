// A MoveSource read in batches of exactly the engines' size, whatever the source hands over
// at a time, with room to look ahead. Internal to vcut::removal.
#pragma once

#include <cstddef>
#include <vector>

#include "vcut/removal/move.h"

namespace vcut::removal::detail {

class MoveBatches {
 public:
  explicit MoveBatches(MoveSource& source) : source_(source) {}

  // Pulls until at least `n` moves wait (fewer when the source runs out); returns how many do.
  std::size_t fill(std::size_t n) {
    while (more_ && held_.size() < n) more_ = source_.next(held_, n - held_.size());
    return held_.size();
  }
  // The moves pulled and not yet dropped, in program order.
  const std::vector<Move>& held() const { return held_; }
  // The first n held moves are done.
  void drop(std::size_t n) { held_.erase(held_.begin(), held_.begin() + static_cast<std::ptrdiff_t>(n)); }

 private:
  MoveSource& source_;
  std::vector<Move> held_;
  bool more_ = true;
};

}  // namespace vcut::removal::detail
