// One ray's intervals (removal/src/dexel_impl.h, private to the removal library) and the
// cut's removal along it (dexel::subtract), against a plain list of intervals with the
// difference taken interval by interval: the intervals, the moves named at their ends,
// the length removed, and the extent kept inline for the cut's first test of a ray.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "dexel_impl.h"

namespace vcut::removal::dexel {
namespace {

// The reference: [a, b] taken from every interval; what is left of one on either side stays
// when longer than kMinSegment_mm, its new end named after the move.
double reference_subtract(std::vector<DexelSegment>& ray, float a, float b, int move, int& dropped) {
  if (!(a < b)) return 0.0;
  std::vector<DexelSegment> out;
  double removed = 0.0;
  for (const DexelSegment& s : ray) {
    if (s.hi_mm <= a || s.lo_mm >= b) {
      out.push_back(s);
      continue;
    }
    removed += static_cast<double>(std::min(s.hi_mm, b)) - std::max(s.lo_mm, a);
    if (s.lo_mm < a) {
      if (static_cast<double>(a) - s.lo_mm > kMinSegment_mm) {
        out.push_back({s.lo_mm, a, s.lo_move, move});
      } else {
        removed += static_cast<double>(a) - s.lo_mm;
        ++dropped;
      }
    }
    if (s.hi_mm > b) {
      if (static_cast<double>(s.hi_mm) - b > kMinSegment_mm) {
        out.push_back({b, s.hi_mm, move, s.hi_move});
      } else {
        removed += static_cast<double>(s.hi_mm) - b;
        ++dropped;
      }
    }
  }
  ray = out;
  return removed;
}

void expect_same(const SegmentList& ray, const std::vector<DexelSegment>& expected, const char* where) {
  ASSERT_EQ(ray.size(), expected.size()) << where;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const DexelSegment& s = ray.data()[i];
    EXPECT_EQ(s.lo_mm, expected[i].lo_mm) << where << " interval " << i;
    EXPECT_EQ(s.hi_mm, expected[i].hi_mm) << where << " interval " << i;
    EXPECT_EQ(s.lo_move, expected[i].lo_move) << where << " interval " << i;
    EXPECT_EQ(s.hi_move, expected[i].hi_move) << where << " interval " << i;
  }
  if (!expected.empty()) {
    EXPECT_EQ(ray.first_lo_mm(), expected.front().lo_mm) << where;
    EXPECT_EQ(ray.last_hi_mm(), expected.back().hi_mm) << where;
  }
}

// Ends on a grid of 1/64 mm (exact in float, so both sides compute the same lengths), with
// the slivers a grazing cut leaves (under and over kMinSegment_mm) mixed in. Rays that grow
// do so in an arena (as the cut's do) or, for half the trials' first lists, on the heap.
TEST(SegmentList, SubtractIsTheDifferenceIntervalByIntervalAndKeepsTheExtentInline) {
  std::mt19937 rng(20261130);
  std::uniform_int_distribution<int> grid(0, 64 * 40), count(1, 5), cuts(1, 40), sliver(0, 4);
  std::vector<DexelSegment> scratch;
  SegmentArena arena;
  int heap_rays = 0, arena_rays = 0, grown_by_cuts = 0, emptied = 0, dropped = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    // A ray of disjoint intervals, in order.
    std::vector<int> ends;
    const int n = count(rng);
    while (static_cast<int>(ends.size()) < 2 * n) ends.push_back(grid(rng));
    std::sort(ends.begin(), ends.end());
    ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
    std::vector<DexelSegment> expected;
    for (std::size_t i = 0; i + 1 < ends.size(); i += 2)
      expected.push_back({ends[i] / 64.0f, ends[i + 1] / 64.0f, -1, -1});
    SegmentList ray;
    ray.assign(expected.data(), static_cast<std::uint32_t>(expected.size()), trial % 2 == 0 ? nullptr : &arena);
    expect_same(ray, expected, "assigned");
    const int steps = cuts(rng);
    for (int step = 0; step < steps && !expected.empty(); ++step) {
      float a = grid(rng) / 64.0f, b = grid(rng) / 64.0f;
      if (a > b) std::swap(a, b);
      // Now and then a cut that leaves a sliver of a few float steps at an interval's end:
      // under kMinSegment_mm (dropped) near 1 mm, over it (kept) near 40 mm.
      if (sliver(rng) == 0) {
        const DexelSegment& s = expected[static_cast<std::size_t>(grid(rng)) % expected.size()];
        const int steps_off = 1 << sliver(rng);  // 1 to 16
        if (sliver(rng) % 2 == 0) {
          a = s.lo_mm;
          for (int k = 0; k < steps_off; ++k) a = std::nextafter(a, 1e9f);
          b = std::max(b, a + 1.0f / 64.0f);
        } else {
          b = s.hi_mm;
          for (int k = 0; k < steps_off; ++k) b = std::nextafter(b, -1e9f);
          a = std::min(a, b - 1.0f / 64.0f);
        }
      }
      const int move = trial * 100 + step;
      const double want = reference_subtract(expected, a, b, move, dropped);
      const double got = subtract(ray, a, b, move, scratch, arena);
      EXPECT_DOUBLE_EQ(got, want) << "trial " << trial << " step " << step;
      expect_same(ray, expected, "after a cut");
      if (HasFailure()) return;
    }
    heap_rays += ray.heap_bytes() > 0;
    arena_rays += ray.borrowed();
    // Made inline or on the heap, it took room from the arena only when a cut split it.
    grown_by_cuts += trial % 2 == 0 && ray.borrowed();
    emptied += ray.size() == 0;
    // Moved (the stock's rays are made in place, but a moved list keeps its intervals too).
    SegmentList moved(std::move(ray));
    expect_same(moved, expected, "moved");
    EXPECT_EQ(ray.size(), 0u);
  }
  // The draws reach both storages, empty rays and dropped slivers.
  EXPECT_GT(heap_rays, 300);
  EXPECT_GT(arena_rays, 300);
  EXPECT_GT(grown_by_cuts, 100);
  EXPECT_GT(emptied, 100);
  EXPECT_GT(dropped, 20);
}

// Blocks of a power of two intervals, at least those asked for; a block given back serves the
// next request of its size (and of no other), and chunks are taken only when none is free.
TEST(SegmentArena, GivesPowersOfTwoAndServesReturnedBlocksAgain) {
  SegmentArena arena;
  std::uint32_t size = 0;
  DexelSegment* const two = arena.take(2, size);
  EXPECT_EQ(size, 2u);
  DexelSegment* const four = arena.take(3, size);
  EXPECT_EQ(size, 4u);
  EXPECT_EQ(four, two + 2);  // from the same chunk, side by side
  DexelSegment* const eight = arena.take(5, size);
  EXPECT_EQ(size, 8u);
  EXPECT_EQ(arena.take(8, size), eight + 8);
  EXPECT_EQ(arena.take(1, size), eight + 16);  // one interval's room: still a block of two
  EXPECT_EQ(size, 2u);
  const std::size_t bytes = arena.bytes();
  EXPECT_EQ(bytes, 64 * sizeof(DexelSegment));  // the first chunk, 2 + 4 + 8 + 8 + 2 used
  arena.give_back(four, 4);
  arena.give_back(eight, 8);
  EXPECT_EQ(arena.take(4, size), four);
  EXPECT_EQ(arena.take(8, size), eight);
  EXPECT_NE(arena.take(4, size), four);  // given out again: not on the free list twice
  EXPECT_EQ(arena.bytes(), bytes);
  // A request larger than the chunk left: a new chunk (twice the first), not the free lists'.
  arena.give_back(two, 2);
  DexelSegment* const big = arena.take(100, size);
  EXPECT_EQ(size, 128u);
  EXPECT_NE(big, two);
  EXPECT_EQ(arena.bytes(), bytes + 128 * sizeof(DexelSegment));
  EXPECT_EQ(arena.take(2, size), two);
  // A list that outgrows its block gives it back.
  SegmentArena rays;
  const DexelSegment segs[3] = {{0.0f, 1.0f, 1, 2}, {2.0f, 3.0f, 3, 4}, {4.0f, 5.0f, 5, 6}};
  SegmentList ray;
  ray.assign(segs, 2, &rays);
  const DexelSegment* const first = ray.data();
  ray.assign(segs, 3, &rays);
  EXPECT_TRUE(ray.borrowed());
  EXPECT_EQ(ray.size(), 3u);
  EXPECT_EQ(ray.data()[2].hi_move, 6);
  EXPECT_EQ(rays.take(2, size), first);
}

}  // namespace
}  // namespace vcut::removal::dexel
