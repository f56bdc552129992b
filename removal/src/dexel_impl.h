// The tri-dexel stock's inside, shared by its three parts: ray storage (dexel_stock.cpp), the
// cut (dexel_cut.cpp) and the mesher (dexel_mesher.cpp). Private to the removal library.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include <sys/mman.h>

#include "vcut/removal/compare.h"
#include "vcut/removal/dexel_stock.h"
#include "surface_projection.h"

namespace vcut::removal {
namespace dexel {

using Eigen::Vector3d;
constexpr int kNoMove = -1;
// A tile of one family: kTileU rays along u by kTileW rows. A move's work per tile (its
// rays' range, its neighbours' hand-over bounds) and per row (range, section) is done once
// per tile it covers: long rows, so that a tool's rows fall in one or two tiles (W1, a 6 mm
// ball at 0.05 mm: cut 7.3 -> 6.4 s with 256 x 8 against 64 x 4; W1 on 40 mm, 1 thread,
// 1.109 -> 1.017 s with 512 x 16 against 256 x 8). 8 rows, not 16: a batch waits for its
// heaviest tile, and on 16 threads that bounded W5's cut at 12.3x one thread's (the tiles'
// times, scheduled; 14.3x with 8 rows, one thread's time the same within 2 %).
constexpr int kTileU = 512, kTileW = 8;
static_assert(kTileU % 64 == 0, "a tile row's occupied rays are whole 64-bit words");
constexpr std::size_t kBatchMoves = 4096;    // moves binned and cut together
constexpr std::size_t kBinChunkMoves = 128;  // the fewest moves binned as one chunk
// The move record is pruned when it has grown by this many moves and doubled since the last time.
constexpr std::size_t kPruneMoves = 65536;
// Material thinner than this along a ray (mm) is dropped: a sliver a grazing cut leaves.
constexpr float kMinSegment_mm = 1e-6f;

// Room for rays' intervals during the cut, a tile's rays from their tile's arena: lists of
// neighbouring rays lie together (the mesher reads a cell's rays side by side; one heap
// allocation per list scattered them) and the cut calls the allocator once a chunk, not
// once a list (D32: 1.4 % of the run's samples were in _int_malloc under its subtract).
// Blocks hold a power of two intervals; one a list outgrows comes back to its size's free
// list (a word in the block links it) and serves the next list of that size, still in
// cache. Chunks double from 64 intervals (1 KB), so a tile with few heap lists takes little.
class SegmentArena {
 public:
  // Room for at least n intervals: its size (a power of two) in `size`.
  DexelSegment* take(std::uint32_t n, std::uint32_t& size) {
    const int k = n <= 2 ? 1 : 32 - __builtin_clz(n - 1);
    size = std::uint32_t{1} << k;
    if (void* free = free_[static_cast<std::size_t>(k)]) {
      std::memcpy(&free_[static_cast<std::size_t>(k)], free, sizeof(void*));
      return static_cast<DexelSegment*>(free);
    }
    if (size > left_) grow(size);
    DexelSegment* const out = next_;
    next_ += size;
    left_ -= size;
    return out;
  }
  // A block take() gave out, of that size, given back.
  void give_back(DexelSegment* block, std::uint32_t size) {
    const std::size_t k = static_cast<std::size_t>(__builtin_ctz(size));
    std::memcpy(static_cast<void*>(block), &free_[k], sizeof(void*));
    free_[k] = block;
  }
  std::size_t bytes() const { return bytes_; }

 private:
  static constexpr std::size_t kFirstChunk = 64, kLargestChunk = std::size_t{1} << 16;
  void grow(std::size_t n) {
    const std::size_t size = std::max(n, chunk_);
    chunk_ = std::min(2 * chunk_, kLargestChunk);
    chunks_.push_back(std::unique_ptr<DexelSegment[]>(new DexelSegment[size]));
    next_ = chunks_.back().get();
    left_ = size;
    bytes_ += size * sizeof(DexelSegment);
  }
  std::vector<std::unique_ptr<DexelSegment[]>> chunks_;
  std::array<void*, 32> free_{};  // by log2 of the size
  DexelSegment* next_ = nullptr;
  std::size_t left_ = 0, chunk_ = kFirstChunk, bytes_ = 0;
};

// The intervals of one ray: one inline, more on the heap (24 bytes per ray). On the heap,
// the first interval's start and the last one's end stay inline too, where the inline
// interval keeps its own, so that the cut's first test of a ray (is all of its material
// beside the move?) never follows the pointer (W1: 244 M of its 620 M looks end there).
class SegmentList {
 public:
  SegmentList() : one_{0.0f, 0.0f, kNoMove, kNoMove} {}
  ~SegmentList() {
    if (owns_heap()) delete[] heap_.many;
  }
  SegmentList(const SegmentList&) = delete;
  SegmentList& operator=(const SegmentList&) = delete;
  SegmentList(SegmentList&& other) noexcept : size_(other.size_), capacity_(other.capacity_) {
    if (capacity_ > 1)
      heap_ = other.heap_;
    else
      one_ = other.one_;
    other.size_ = 0;
    other.capacity_ = 1;
  }
  SegmentList& operator=(SegmentList&&) = delete;

  std::uint32_t size() const { return size_; }
  const DexelSegment* data() const { return capacity_ > 1 ? heap_.many : &one_; }
  // Writes through this end with extent_changed().
  DexelSegment* data() { return capacity_ > 1 ? heap_.many : &one_; }
  // Whether its list lies in an arena.
  bool borrowed() const { return (capacity_ & kBorrowed) != 0; }
  // The bytes of its own heap list (one in an arena is the arena's).
  std::size_t heap_bytes() const { return owns_heap() ? capacity_ * sizeof(DexelSegment) : 0; }
  // The material's extent along the ray, with size() > 0: the first interval's start and
  // the last one's end (the two floats both members of the union begin with).
  float first_lo_mm() const { return one_.lo_mm; }
  float last_hi_mm() const { return one_.hi_mm; }

  // With `arena`, room for more intervals comes from it.
  void assign(const DexelSegment* s, std::uint32_t n, SegmentArena* arena = nullptr) {
    const std::uint32_t room = capacity_ & ~kBorrowed;
    if (n > room) {
      std::uint32_t capacity = std::max(n, 2 * room);
      if (capacity > kBorrowed / 2) throw std::length_error("a dexel ray holds more intervals than it can count");
      DexelSegment* const fresh = arena != nullptr ? arena->take(capacity, capacity) : new DexelSegment[capacity];
      // The old list is copied from below before its block can serve another.
      std::copy(s, s + n, fresh);
      if (owns_heap())
        delete[] heap_.many;
      else if (borrowed() && arena != nullptr)
        arena->give_back(heap_.many, room);  // (without one it stays where it was, unused)
      heap_.many = fresh;
      capacity_ = capacity | (arena != nullptr ? kBorrowed : 0u);
      size_ = n;
      extent_changed();
      return;
    }
    if (n > 0) std::memmove(data(), s, n * sizeof(DexelSegment));
    size_ = n;
    extent_changed();
  }
  // No intervals (the room stays).
  void clear() { size_ = 0; }
  // Keeps the first n intervals (n <= size()).
  void truncate(std::uint32_t n) {
    size_ = n;
    extent_changed();
  }
  // After intervals were written through data(): the extent kept inline follows them.
  void extent_changed() {
    if (capacity_ > 1 && size_ > 0) {
      heap_.first_lo_mm = heap_.many[0].lo_mm;
      heap_.last_hi_mm = heap_.many[size_ - 1].hi_mm;
    }
  }

 private:
  // In capacity_: the list lies in an arena (capacity_ > 1 still means "on the heap").
  static constexpr std::uint32_t kBorrowed = std::uint32_t{1} << 31;
  bool owns_heap() const { return capacity_ > 1 && (capacity_ & kBorrowed) == 0; }
  struct Heap {
    float first_lo_mm, last_hi_mm;  // a common initial sequence with DexelSegment's lo_mm, hi_mm
    DexelSegment* many;
  };
  static_assert(std::is_standard_layout<Heap>::value && std::is_standard_layout<DexelSegment>::value &&
                    offsetof(Heap, last_hi_mm) == offsetof(DexelSegment, hi_mm),
                "the extent is read through either member");
  union {
    DexelSegment one_;
    Heap heap_;
  };
  std::uint32_t size_ = 0, capacity_ = 1;
};
static_assert(sizeof(SegmentList) == 24, "one ray should stay 24 bytes");

// Removes [a, b] (made by `move`) from the ray (an interval left thinner than
// kMinSegment_mm goes too); returns the length removed (mm). `scratch`: room for a split;
// `arena`: where a ray that needs more room grows (its tile's).
// Always inline: the cut's hot loops call it once per ray they cut (with two callers GCC
// kept it out of line, and W1's cut took 6 % longer).
inline __attribute__((always_inline)) double subtract(SegmentList& ray, float a, float b, int move,
                                                      std::vector<DexelSegment>& scratch, SegmentArena& arena) {
  const std::uint32_t n = ray.size();
  if (n == 0 || !(a < b)) return 0.0;
  DexelSegment* s = ray.data();
  if (b <= s[0].lo_mm || a >= s[n - 1].hi_mm) return 0.0;
  if (n == 1 && !(s[0].lo_mm < a && s[0].hi_mm > b)) {
    // One interval, trimmed at one end or removed whole: in place.
    DexelSegment& seg = s[0];
    const double before = static_cast<double>(seg.hi_mm) - seg.lo_mm;
    if (seg.lo_mm < a) {
      seg.hi_mm = a;
      seg.hi_move = move;
    } else if (seg.hi_mm > b) {
      seg.lo_mm = b;
      seg.lo_move = move;
    } else {
      ray.clear();
      return before;
    }
    const double after = static_cast<double>(seg.hi_mm) - seg.lo_mm;
    if (after <= kMinSegment_mm) {
      ray.clear();
      return before;
    }
    ray.extent_changed();
    return before - after;
  }
  // Several intervals: those from i to j meet [a, b]; they give way to at most two pieces,
  // the part of i below a and the part of j above b (a sliver thinner than kMinSegment_mm
  // is dropped), and the intervals after j move up or down to follow them.
  std::uint32_t i = 0;
  while (s[i].hi_mm <= a) ++i;
  if (s[i].lo_mm >= b) return 0.0;
  std::uint32_t j = i;
  while (j + 1 < n && s[j + 1].lo_mm < b) ++j;
  double removed = 0.0;
  for (std::uint32_t k = i; k <= j; ++k)
    removed += static_cast<double>(std::min(s[k].hi_mm, b)) - std::max(s[k].lo_mm, a);
  DexelSegment pieces[2];
  std::uint32_t kept = 0;
  if (s[i].lo_mm < a) {
    if (a - s[i].lo_mm > kMinSegment_mm)
      pieces[kept++] = {s[i].lo_mm, a, s[i].lo_move, move};
    else
      removed += static_cast<double>(a) - s[i].lo_mm;
  }
  if (s[j].hi_mm > b) {
    if (s[j].hi_mm - b > kMinSegment_mm)
      pieces[kept++] = {b, s[j].hi_mm, move, s[j].hi_move};
    else
      removed += static_cast<double>(s[j].hi_mm) - b;
  }
  const std::uint32_t gone = j - i + 1, size = n - gone + kept;
  if (size > n) {
    // One interval split in two: through the scratch list, the ray may need more room.
    scratch.assign(s, s + i);
    scratch.insert(scratch.end(), pieces, pieces + kept);
    scratch.insert(scratch.end(), s + j + 1, s + n);
    ray.assign(scratch.data(), size, &arena);
    return removed;
  }
  // As many pieces as intervals gone (an interval trimmed at one end): those after stay put.
  if (kept != gone) std::memmove(s + i + kept, s + j + 1, (n - j - 1) * sizeof(DexelSegment));
  // One by one: std::copy of these 16 or 32 bytes was a call to memmove (2.4 % of W1's run).
  if (kept > 0) s[i] = pieces[0];
  if (kept > 1) s[i + 1] = pieces[1];
  ray.truncate(size);  // the extent follows
  return removed;
}

// Room for the rays: hundreds of MB, on transparent huge pages where Linux grants them, so
// that filling the stock faults per 2 MiB instead of per 4 KiB (W1's stock stage: 0.6 s,
// then 0.06-0.4 s on this noisy VM; the cut itself measured no different). Advice only.
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  static constexpr std::size_t kHuge = std::size_t{2} << 20;
  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < 4 * kHuge) return static_cast<T*>(::operator new(bytes));
    void* p = std::aligned_alloc(kHuge, (bytes + kHuge - 1) / kHuge * kHuge);
    if (p == nullptr) throw std::bad_alloc();
    ::madvise(p, (bytes + kHuge - 1) / kHuge * kHuge, MADV_HUGEPAGE);
    return static_cast<T*>(p);
  }
  // A vector's default construction of its elements is left to its owner, which makes them
  // in parallel (Impl::setup): the first touch of a page has the kernel zero it, and on one
  // thread W1's 173 MB of rays took up to 0.4 s of the stock stage on this VM.
  template <class U>
  void construct(U*) noexcept {}
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  void deallocate(T* p, std::size_t n) {
    if (n * sizeof(T) < 4 * kHuge)
      ::operator delete(p);
    else
      std::free(p);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const {
    return true;
  }
  template <class U>
  bool operator!=(const HugePageAllocator<U>&) const {
    return false;
  }
};

// The two lattice axes of a family, in increasing order.
constexpr std::array<std::array<int, 2>, 3> kOther = {{{1, 2}, {0, 2}, {0, 1}}};

struct Family {
  int axis = 0;
  int lo_u = 0, lo_w = 0;  // lattice index of the first ray along the two other axes
  int n_u = 0, n_w = 0;
  int tiles_u = 0, tiles_w = 0;
  int words_u = 0;  // occupied words per row
  std::vector<SegmentList, HugePageAllocator<SegmentList>> rays;
  std::vector<SegmentArena> arenas;  // per tile: where its rays grow during the cut
  // Which rays hold material: a bit per ray, 64-bit words along each row, so a cut walks
  // only the rays with material (each word lies within one tile: a tile writes only its own).
  std::vector<std::uint64_t> occupied;
  double length_mm = 0.0;  // material along all rays

  bool contains(int iu, int iw) const { return iu >= lo_u && iu < lo_u + n_u && iw >= lo_w && iw < lo_w + n_w; }
  const SegmentList& at(int iu, int iw) const {
    return rays[static_cast<std::size_t>(iw - lo_w) * static_cast<std::size_t>(n_u) +
                static_cast<std::size_t>(iu - lo_u)];
  }
  SegmentList& at(int iu, int iw) {
    return rays[static_cast<std::size_t>(iw - lo_w) * static_cast<std::size_t>(n_u) +
                static_cast<std::size_t>(iu - lo_u)];
  }
  int tiles() const { return tiles_u * tiles_w; }
  // Word `word` of the row at iw: rays lo_u + 64 word ... lo_u + 64 word + 63.
  std::uint64_t& occupied_word(int word, int iw) {
    return occupied[static_cast<std::size_t>(iw - lo_w) * static_cast<std::size_t>(words_u) +
                    static_cast<std::size_t>(word)];
  }
};

}  // namespace dexel

using namespace dexel;  // included by the stock's three source files only

struct DexelStock::Impl {
  double v = 0.1;  // ray spacing, mm
  std::array<Family, 3> families;
  Eigen::AlignedBox3d shape_bounds;
  std::function<double(const Eigen::Vector3d&)> initial_distance;
  std::shared_ptr<const DesignDistance> initial_mesh;
  detail::MoveRecord moves;  // the moves some ray endpoint names, by id
  std::size_t kept_after_pruning = 0;
  std::vector<Cutter> cutters;
  bool flat_merging = true;

  // World coordinate of lattice index i along any axis: rays sit mid-cell, so a box whose
  // faces lie on multiples of v is measured exactly.
  double position(int i) const { return (i + 0.5) * v; }
  double index_of(double x) const { return x / v - 0.5; }

  void setup(const Eigen::AlignedBox3d& box) {
    std::array<int, 3> lo, count;
    for (int a = 0; a < 3; ++a) {
      lo[a] = static_cast<int>(std::floor(index_of(box.min()[a]))) - 1;
      const int hi = static_cast<int>(std::ceil(index_of(box.max()[a]))) + 1;
      count[a] = hi - lo[a] + 1;
    }
    for (int axis = 0; axis < 3; ++axis) {
      Family& f = families[static_cast<std::size_t>(axis)];
      const auto [a1, a2] = kOther[static_cast<std::size_t>(axis)];
      f.axis = axis;
      f.lo_u = lo[static_cast<std::size_t>(a1)];
      f.lo_w = lo[static_cast<std::size_t>(a2)];
      f.n_u = count[static_cast<std::size_t>(a1)];
      f.n_w = count[static_cast<std::size_t>(a2)];
      f.tiles_u = (f.n_u + kTileU - 1) / kTileU;
      f.tiles_w = (f.n_w + kTileW - 1) / kTileW;
      f.words_u = (f.n_u + 63) / 64;
      f.arenas = std::vector<SegmentArena>(static_cast<std::size_t>(f.tiles()));
      f.rays = std::vector<SegmentList, HugePageAllocator<SegmentList>>(static_cast<std::size_t>(f.n_u) *
                                                                        static_cast<std::size_t>(f.n_w));
      SegmentList* const rays = f.rays.data();
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f.rays.size(), std::size_t{1} << 16),
                        [rays](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i != range.end(); ++i) ::new (rays + i) SegmentList();
                        });
    }
  }

  // Fills every ray with its intervals inside an analytic stock.
  template <class Interval>
  void fill(Interval&& interval) {
    for (Family& f : families) {
      tbb::parallel_for(0, f.n_w, [&](int row) {
        const int iw = f.lo_w + row;
        for (int iu = f.lo_u; iu < f.lo_u + f.n_u; ++iu) {
          double a, b;
          if (interval(f.axis, position(iu), position(iw), a, b) && b - a > kMinSegment_mm) {
            const DexelSegment seg{static_cast<float>(a), static_cast<float>(b), kNoMove, kNoMove};
            f.at(iu, iw).assign(&seg, 1);
          }
        }
      });
    }
  }

  void fill_mesh(const TriangleMesh& mesh);
  void find_occupied() {
    for (Family& f : families) {
      f.occupied.assign(static_cast<std::size_t>(f.n_w) * static_cast<std::size_t>(f.words_u), 0);
      tbb::parallel_for(f.lo_w, f.lo_w + f.n_w, [&](int iw) {  // each row its own words
        for (int k = 0; k < f.n_u; ++k)
          if (f.at(f.lo_u + k, iw).size() > 0) f.occupied_word(k / 64, iw) |= std::uint64_t{1} << (k % 64);
      });
    }
  }

  // Each row's sum in parallel, the rows' added in order: the same total for any thread count.
  void sum_lengths() {
    for (Family& f : families) {
      std::vector<double> rows(static_cast<std::size_t>(f.n_w), 0.0);
      tbb::parallel_for(0, f.n_w, [&](int row) {
        double total = 0.0;
        for (int iu = f.lo_u; iu < f.lo_u + f.n_u; ++iu) {
          const SegmentList& ray = f.at(iu, f.lo_w + row);
          for (std::uint32_t i = 0; i < ray.size(); ++i)
            total += static_cast<double>(ray.data()[i].hi_mm) - ray.data()[i].lo_mm;
        }
        rows[static_cast<std::size_t>(row)] = total;
      });
      double total = 0.0;
      for (double r : rows) total += r;
      f.length_mm = total;
    }
  }

  Vector3d point(int axis, int iu, int iw, double s) const {
    Vector3d x;
    x[axis] = s;
    x[kOther[static_cast<std::size_t>(axis)][0]] = position(iu);
    x[kOther[static_cast<std::size_t>(axis)][1]] = position(iw);
    return x;
  }

  // Lattice index range [first, last] of rays of family f within [lo, hi] on its axis a1/a2.
  bool ray_range(const Family& f, const Eigen::AlignedBox3d& box, int& u0, int& u1, int& w0, int& w1) const {
    const auto [a1, a2] = kOther[static_cast<std::size_t>(f.axis)];
    u0 = std::max(f.lo_u, static_cast<int>(std::ceil(index_of(box.min()[a1]))));
    u1 = std::min(f.lo_u + f.n_u - 1, static_cast<int>(std::floor(index_of(box.max()[a1]))));
    w0 = std::max(f.lo_w, static_cast<int>(std::ceil(index_of(box.min()[a2]))));
    w1 = std::min(f.lo_w + f.n_w - 1, static_cast<int>(std::floor(index_of(box.max()[a2]))));
    return u0 <= u1 && w0 <= w1;
  }
};

}  // namespace vcut::removal
