#include "vcut/removal/dexel_stock.h"

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>

#include <sys/mman.h>

#include "vcut/removal/compare.h"
#include "vcut/removal/morton.h"
#include "initial_stock.h"
#include "ray_sweep.h"
#include "surface_projection.h"

namespace vcut::removal {
namespace {

using Eigen::Vector3d;
constexpr int kNoMove = -1;
// A tile of one family: kTileU rays along u by kTileW rows. A move's work per tile (its
// rays' range, its neighbours' hand-over bounds) and per row (range, section) is done once
// per tile it covers: long rows, so that a tool's rows fall in one or two tiles (W1, a 6 mm
// ball at 0.05 mm: cut 7.3 -> 6.4 s with 256 x 8 against 64 x 4; W1 on 40 mm, 1 thread,
// 1.109 -> 1.017 s with 512 x 16 against 256 x 8).
constexpr int kTileU = 512, kTileW = 16;
static_assert(kTileU % 64 == 0, "a tile row's occupied rays are whole 64-bit words");
constexpr std::size_t kBatchMoves = 4096;  // moves binned and cut together
// Material thinner than this along a ray (mm) is dropped: a sliver a grazing cut leaves.
constexpr float kMinSegment_mm = 1e-6f;

// The intervals of one ray: one inline, more on the heap (24 bytes per ray).
class SegmentList {
 public:
  SegmentList() : one_{0.0f, 0.0f, kNoMove, kNoMove} {}
  ~SegmentList() {
    if (capacity_ > 1) delete[] many_;
  }
  SegmentList(const SegmentList&) = delete;
  SegmentList& operator=(const SegmentList&) = delete;
  SegmentList(SegmentList&& other) noexcept : size_(other.size_), capacity_(other.capacity_) {
    if (capacity_ > 1)
      many_ = other.many_;
    else
      one_ = other.one_;
    other.size_ = 0;
    other.capacity_ = 1;
  }
  SegmentList& operator=(SegmentList&&) = delete;

  std::uint32_t size() const { return size_; }
  const DexelSegment* data() const { return capacity_ > 1 ? many_ : &one_; }
  DexelSegment* data() { return capacity_ > 1 ? many_ : &one_; }
  std::size_t heap_bytes() const { return capacity_ > 1 ? capacity_ * sizeof(DexelSegment) : 0; }

  void assign(const DexelSegment* s, std::uint32_t n) {
    if (n > capacity_) {
      const std::uint32_t capacity = std::max(n, 2 * capacity_);
      auto* fresh = new DexelSegment[capacity];
      if (capacity_ > 1) delete[] many_;
      many_ = fresh;
      capacity_ = capacity;
    }
    if (n > 0) std::memmove(data(), s, n * sizeof(DexelSegment));
    size_ = n;
  }
  // Keeps the first n intervals (n <= size()).
  void truncate(std::uint32_t n) { size_ = n; }

 private:
  union {
    DexelSegment one_;
    DexelSegment* many_;
  };
  std::uint32_t size_ = 0, capacity_ = 1;
};
static_assert(sizeof(SegmentList) == 24, "one ray should stay 24 bytes");

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

// Removes [a, b] (made by `move`) from the ray; returns the length removed (mm).
double subtract(SegmentList& ray, float a, float b, int move, std::vector<DexelSegment>& scratch) {
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
      ray.assign(nullptr, 0);
      return before;
    }
    const double after = static_cast<double>(seg.hi_mm) - seg.lo_mm;
    if (after <= kMinSegment_mm) {
      ray.assign(nullptr, 0);
      return before;
    }
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
    ray.assign(scratch.data(), size);
    return removed;
  }
  std::memmove(s + i + kept, s + j + 1, (n - j - 1) * sizeof(DexelSegment));
  std::copy(pieces, pieces + kept, s + i);
  ray.truncate(size);
  return removed;
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
struct Handover {
  Vector3d c = Vector3d::Zero(), d = Vector3d::Zero(), a = Vector3d::UnitZ();
  double height_mm = 0.0;
  bool on = false;
  double da = 0.0;  // D.a

  // The test along the rays of one family, its coordinates picked out once per move.
  struct OnAxis {
    double c1, c2, d1, d2, cd, dk, a1, a2, ca, ak, da, height_mm;
    // True when every point of the ray at (u, w) with axis coordinate in [s_lo, s_hi] has
    // h <= 0. h is linear in s between the two heights where q.a is 0 or H.
    bool covers(double u, double w, double s_lo, double s_hi) const {
      const double k0 = (u - c1) * d1 + (w - c2) * d2 - cd;
      const double m0 = (u - c1) * a1 + (w - c2) * a2 - ca;
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
  };
  OnAxis on_axis(int axis) const {
    const auto [i1, i2] = kOther[static_cast<std::size_t>(axis)];
    return {c[i1],   c[i2], d[i1],    d[i2], c[axis] * d[axis], d[axis], a[i1], a[i2], c[axis] * a[axis],
            a[axis], da,    height_mm};
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

  double base(double w) const { return base0 + base_w * w - clamp_d * std::clamp(w - clamp_c, 0.0, height_mm); }
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
std::vector<MoveHandover> handovers(const MoveList& list) {
  const std::size_t count = list.moves.size();
  std::vector<MoveHandover> out(count);
  auto eligible = [&](const Move& m) {
    if (m.rapid) return false;
    const Cutter& c = list.cutters.at(static_cast<std::size_t>(m.cutter));
    if (c.type != CutterType::VBit && core_of(c).core_radius_mm == 0.0) return true;  // ball end
    const Vector3d d = m.end_mm - m.start_mm;
    return std::abs(d.dot(m.axis)) <= 1e-12 * d.norm() * m.axis.norm();  // square to the axis
  };
  std::vector<std::size_t> next_cut(count + 1, count);
  for (std::size_t i = count; i-- > 0;) next_cut[i] = list.moves[i].rapid ? next_cut[i + 1] : i;
  std::vector<std::size_t> last_cut(count + 1, count);  // last_cut[i]: the last cutting move before i
  for (std::size_t i = 0; i < count; ++i) last_cut[i + 1] = list.moves[i].rapid ? last_cut[i] : i;
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
    const Move& m = list.moves[i];
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
    out[i].from_start = {c0, d, a, height, before < count && joins(list.moves[before], m), d.dot(a)};
    out[i].to_end = {c1, -d, a, height, after < count && joins(m, list.moves[after]), -d.dot(a)};
    out[i].next = after;
    out[i].bounds = TranslationSweep(list.cutters[static_cast<std::size_t>(m.cutter)], m).bounds();
  });
  return out;
}

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
  double u[kTileU], top[kTileU], lo[kTileU], hi[kTileU];
  bool hit[kTileU];
};

struct TileResult {
  double removed_mm = 0.0;  // length along the family's rays
  std::vector<Probe> probes;
};

}  // namespace

struct DexelStock::Impl {
  double v = 0.1;  // ray spacing, mm
  std::array<Family, 3> families;
  Eigen::AlignedBox3d shape_bounds;
  std::function<double(const Eigen::Vector3d&)> initial_distance;
  std::shared_ptr<const DesignDistance> initial_mesh;
  std::vector<Move> moves;
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
      f.rays = std::vector<SegmentList, HugePageAllocator<SegmentList>>(static_cast<std::size_t>(f.n_u) *
                                                                        static_cast<std::size_t>(f.n_w));
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
      for (int iw = f.lo_w; iw < f.lo_w + f.n_w; ++iw)
        for (int k = 0; k < f.n_u; ++k)
          if (f.at(f.lo_u + k, iw).size() > 0) f.occupied_word(k / 64, iw) |= std::uint64_t{1} << (k % 64);
    }
  }

  void sum_lengths() {
    for (Family& f : families) {
      double total = 0.0;
      for (const SegmentList& ray : f.rays)
        for (std::uint32_t i = 0; i < ray.size(); ++i)
          total += static_cast<double>(ray.data()[i].hi_mm) - ray.data()[i].lo_mm;
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

void DexelStock::Impl::fill_mesh(const TriangleMesh& mesh) {
  for (Family& f : families) {
    const int k = f.axis;
    const auto [a1, a2] = kOther[static_cast<std::size_t>(k)];
    // Triangles by the rows of rays their projection covers.
    std::vector<std::vector<int>> rows(static_cast<std::size_t>(f.n_w));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int c = 0; c < 3; ++c) {
        const double w = mesh.vertices_mm[static_cast<std::size_t>(mesh.triangles[t][c])][a2];
        lo = std::min(lo, w);
        hi = std::max(hi, w);
      }
      const int r0 = std::max(f.lo_w, static_cast<int>(std::ceil(index_of(lo))));
      const int r1 = std::min(f.lo_w + f.n_w - 1, static_cast<int>(std::floor(index_of(hi))));
      for (int r = r0; r <= r1; ++r) rows[static_cast<std::size_t>(r - f.lo_w)].push_back(static_cast<int>(t));
    }
    tbb::parallel_for(0, f.n_w, [&](int row) {
      const int iw = f.lo_w + row;
      const double w = position(iw);
      std::vector<std::vector<std::pair<double, int>>> hits(static_cast<std::size_t>(f.n_u));
      for (int t : rows[static_cast<std::size_t>(row)]) {
        Vector3d p[3];
        for (int c = 0; c < 3; ++c)
          p[c] = mesh.vertices_mm[static_cast<std::size_t>(mesh.triangles[static_cast<std::size_t>(t)][c])];
        auto cross2 = [&](const Vector3d& a, const Vector3d& b, double pu, double pw) {
          return (b[a1] - a[a1]) * (pw - a[a2]) - (b[a2] - a[a2]) * (pu - a[a1]);
        };
        double area = cross2(p[0], p[1], p[2][a1], p[2][a2]);
        if (area == 0.0) continue;  // edge-on
        // The triangle's outward normal along the ray: leaving material where it is positive.
        const double normal_k = k == 1 ? -area : area;
        const int direction = normal_k > 0.0 ? -1 : 1;  // -1 leaves, +1 enters material
        if (area < 0.0) {
          std::swap(p[1], p[2]);
          area = -area;
        }
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const auto& q : p) {
          lo = std::min(lo, q[a1]);
          hi = std::max(hi, q[a1]);
        }
        const int u0 = std::max(f.lo_u, static_cast<int>(std::ceil(index_of(lo))));
        const int u1 = std::min(f.lo_u + f.n_u - 1, static_cast<int>(std::floor(index_of(hi))));
        for (int iu = u0; iu <= u1; ++iu) {
          const double u = position(iu);
          double e[3];
          bool in = true;
          for (int c = 0; c < 3 && in; ++c) {
            const Vector3d& a = p[(c + 1) % 3];
            const Vector3d& b = p[(c + 2) % 3];
            e[c] = cross2(a, b, u, w);
            if (e[c] < 0.0) in = false;
            // On an edge: it belongs to exactly one of the two triangles sharing it (the
            // edge's direction decides), so a ray through it counts once.
            if (e[c] == 0.0) {
              const double du = b[a1] - a[a1], dw = b[a2] - a[a2];
              if (!(dw < 0.0 || (dw == 0.0 && du < 0.0))) in = false;
            }
          }
          if (!in) continue;
          const double s = (e[0] * p[0][k] + e[1] * p[1][k] + e[2] * p[2][k]) / area;
          hits[static_cast<std::size_t>(iu - f.lo_u)].emplace_back(s, direction);
        }
      }
      std::vector<DexelSegment> segments;
      for (int iu = f.lo_u; iu < f.lo_u + f.n_u; ++iu) {
        auto& list = hits[static_cast<std::size_t>(iu - f.lo_u)];
        if (list.empty()) continue;
        std::sort(list.begin(), list.end());
        segments.clear();
        int winding = 0;
        double start = 0.0;
        for (const auto& [s, d] : list) {
          const int before = winding;
          winding += d;
          if (before <= 0 && winding > 0) start = s;
          if (before > 0 && winding <= 0 && s - start > kMinSegment_mm)
            segments.push_back({static_cast<float>(start), static_cast<float>(s), kNoMove, kNoMove});
        }
        f.at(iu, iw).assign(segments.data(), static_cast<std::uint32_t>(segments.size()));
      }
    });
  }
}

std::size_t estimate_dexel_memory_bytes(const StockShape& shape, double spacing_mm) {
  const Eigen::AlignedBox3d box = bounds_of(shape);
  const Vector3d n = (box.sizes() / spacing_mm).array() + 4.0;
  const double rays = n.x() * n.y() + n.y() * n.z() + n.x() * n.z();
  // Rays, plus the meshing and the outputs at the end, per surface cell: about 40 bytes on
  // W1 (peak 735 MB, rays 197 MB, 13.5 million surface cells); 48 to be safe.
  const double surface_cells = surface_area_mm2(shape) / (spacing_mm * spacing_mm);
  return static_cast<std::size_t>(rays * sizeof(SegmentList) + surface_cells * 48.0);
}

namespace {

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

DexelStock::DexelStock(const StockShape& shape, double spacing_mm) : impl_(std::make_unique<Impl>()) {
  if (!(spacing_mm > 0.0)) throw std::invalid_argument("ray spacing must be positive");
  Impl& m = *impl_;
  m.v = spacing_mm;
  m.shape_bounds = bounds_of(shape);
  m.setup(m.shape_bounds);
  if (const auto* box = std::get_if<BoxShape>(&shape)) {
    m.fill([b = *box](int axis, double u, double w, double& lo, double& hi) {
      const auto [a1, a2] = kOther[static_cast<std::size_t>(axis)];
      if (u < b.min_mm[a1] || u > b.max_mm[a1] || w < b.min_mm[a2] || w > b.max_mm[a2]) return false;
      lo = b.min_mm[axis];
      hi = b.max_mm[axis];
      return true;
    });
  } else if (const auto* cyl = std::get_if<CylinderShape>(&shape)) {
    m.fill([c = *cyl](int axis, double u, double w, double& lo, double& hi) {
      Vector3d o;
      o[axis] = 0.0;
      o[kOther[static_cast<std::size_t>(axis)][0]] = u;
      o[kOther[static_cast<std::size_t>(axis)][1]] = w;
      return detail::line_cylinder(axis, o, c.base_center_mm, c.axis.normalized() * c.height_mm, c.radius_mm, lo, hi);
    });
  } else {
    const auto& mesh = std::get<TriangleMesh>(shape);
    if (!is_closed(mesh)) throw std::invalid_argument("a mesh stock must be closed");
    m.fill_mesh(mesh);
  }
  m.initial_distance = detail::initial_distance(shape, m.initial_mesh);
  m.sum_lengths();
  m.find_occupied();
}

DexelStock::~DexelStock() = default;

double DexelStock::spacing_mm() const { return impl_->v; }

void DexelStock::set_flat_merging(bool on) { impl_->flat_merging = on; }

CutResult DexelStock::cut(const MoveList& list, const CutOptions& options) {
  Impl& m = *impl_;
  CutResult result;
  const std::size_t total = list.moves.size();
  // Rays' endpoints hold move ids that count across calls: remember every move.
  const int id_base = detail::remember_moves(list, m.moves, m.cutters);
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
  std::vector<TileResult> results(static_cast<std::size_t>(tiles));
  tbb::enumerable_thread_specific<std::vector<DexelSegment>> scratch;
  const std::vector<MoveHandover> handover = handovers(list);
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
  struct RayNeighbours {
    bool start_on = false, end_on = false;
    Handover::OnAxis start, end, back;  // back: the next move's from_start
    double lo, hi, next_lo, next_hi;    // the move's and the next one's box along the rays
  };
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

  for (std::size_t first = 0; first < total; first += kBatchMoves) {
    const std::size_t last = std::min(total, first + kBatchMoves);
    std::vector<std::optional<detail::RaySweep>> sweeps(last - first);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, 256), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i)
        sweeps[i - first].emplace(list.cutters.at(static_cast<std::size_t>(list.moves[i].cutter)), list.moves[i]);
    });
    // Bin the batch's moves to the tiles of rays their sweep's box covers (counting sort:
    // within a tile the moves stay in program order).
    std::fill(start.begin(), start.end(), 0);
    auto for_each_tile = [&](std::size_t i, auto&& visit) {
      // Material never leaves the initial stock's box: a sweep clear of it (a holder probe
      // high above the part) meets no ray's material.
      if (!sweeps[i - first]->bounds().intersects(m.shape_bounds)) return;
      const int only = probe_family(list.moves[i]);
      for (int a = 0; a < 3; ++a) {
        if (only >= 0 && a != only) continue;
        const Family& f = m.families[static_cast<std::size_t>(a)];
        int u0, u1, w0, w1;
        if (!m.ray_range(f, sweeps[i - first]->bounds(), u0, u1, w0, w1)) continue;
        for (int tw = (w0 - f.lo_w) / kTileW; tw <= (w1 - f.lo_w) / kTileW; ++tw)
          for (int tu = (u0 - f.lo_u) / kTileU; tu <= (u1 - f.lo_u) / kTileU; ++tu)
            visit(tile_base[static_cast<std::size_t>(a)] + tw * f.tiles_u + tu);
      }
    };
    for (std::size_t i = first; i < last; ++i)
      for_each_tile(i, [&](int t) { ++start[static_cast<std::size_t>(t) + 1]; });
    for (int t = 0; t < tiles; ++t) start[static_cast<std::size_t>(t) + 1] += start[static_cast<std::size_t>(t)];
    entries.resize(static_cast<std::size_t>(start[static_cast<std::size_t>(tiles)]));
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (std::size_t i = first; i < last; ++i)
        for_each_tile(i, [&](int t) {
          entries[static_cast<std::size_t>(fill[static_cast<std::size_t>(t)]++)] = static_cast<int>(i - first);
        });
    }
    std::vector<int> busy;
    for (int t = 0; t < tiles; ++t)
      if (start[static_cast<std::size_t>(t) + 1] > start[static_cast<std::size_t>(t)]) busy.push_back(t);

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, busy.size(), 1), [&](const auto& range) {
      auto& buffer = scratch.local();
      for (std::size_t b = range.begin(); b != range.end(); ++b) {
        const int t = busy[b];
        const int a = t >= tile_base[2] ? 2 : (t >= tile_base[1] ? 1 : 0);
        Family& f = m.families[static_cast<std::size_t>(a)];
        const int local = t - tile_base[static_cast<std::size_t>(a)];
        const int tu = local % f.tiles_u, tw = local / f.tiles_u;
        const int tile_u0 = f.lo_u + tu * kTileU, tile_w0 = f.lo_w + tw * kTileW;
        TileResult& r = results[static_cast<std::size_t>(t)];
        r.probes.clear();
        double removed = 0.0;  // summed here, stored once: neighbouring tiles' results share cache lines
        RowRays rows;
        for (int e = start[static_cast<std::size_t>(t)]; e < start[static_cast<std::size_t>(t) + 1]; ++e) {
          const int i = entries[static_cast<std::size_t>(e)];
          const detail::RaySweep& sweep = *sweeps[static_cast<std::size_t>(i)];
          const Move& move = list.moves[first + static_cast<std::size_t>(i)];
          const int id = id_base + static_cast<int>(first) + i;
          int u0, u1, w0, w1;
          m.ray_range(f, sweep.bounds(), u0, u1, w0, w1);
          u0 = std::max(u0, tile_u0);
          u1 = std::min(u1, tile_u0 + kTileU - 1);
          w0 = std::max(w0, tile_w0);
          w1 = std::min(w1, tile_w0 + kTileW - 1);
          const double box_lo = sweep.bounds().min()[a], box_hi = sweep.bounds().max()[a];
          // The section window pays for itself on rays that run along the motion (a move
          // along x sweeps its disc along the x rays: most of the box is clear of it); across
          // the motion it is about the box again (W1's y rays: 2 % rejected).
          const Vector3d motion = move.end_mm - move.start_mm;
          const bool use_window = std::abs(motion[a]) * 2.0 >= motion.norm();
          Probe probe{i, a, 0.0, Vector3d::Zero()};
          const MoveHandover& hand = handover[first + static_cast<std::size_t>(i)];
          const RowNeighbours neighbours = row_neighbours(hand, a);
          // The ray-wise test only for a tilted tool, where the row-wise one cannot run: after
          // the row-wise bounds it cost more than the cuts it saved (W1 on 40 mm, 1 thread:
          // cut 1.294 -> 1.223 s without it; on 20 mm 4.13 -> 3.80 G instructions).
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
            const double clear_below = a == 2 && !move.rapid ? std::max(box_lo, sweep.row_floor(a, w_mm)) : box_lo;
            const int k0 = first_u - f.lo_u, k1 = last_u - f.lo_u;
            SegmentList* const row = &f.at(f.lo_u, iw);
            const bool windowed = use_window && section < std::numeric_limits<double>::infinity();
            // The row's rays that pass the tests below, then their intervals in one call.
            int count = 0;
            for (int word = k0 / 64; word <= k1 / 64; ++word) {
              std::uint64_t walk = f.occupied_word(word, iw);
              if (word == k0 / 64) walk &= ~std::uint64_t{0} << (k0 % 64);
              if (word == k1 / 64) walk &= ~std::uint64_t{0} >> (63 - k1 % 64);
              for (; walk != 0; walk &= walk - 1) {
                const int bit = __builtin_ctzll(walk);
                const int k = 64 * word + bit;
                SegmentList& ray = row[k];
                const std::uint32_t n = ray.size();
                if (n == 0) continue;
                const DexelSegment* const seg = ray.data();
                const double top = seg[n - 1].hi_mm;
                // Rays already clear of the sweep's box cost a look only.
                if (seg[0].lo_mm >= box_hi || top <= clear_below) continue;
                const double u_mm = (f.lo_u + k + 0.5) * v;  // m.position
                if (windowed) {
                  // A tighter window along the ray: the section disc about the tip's path.
                  double win_lo, win_hi;
                  if (!sweep.ray_window(a, u_mm, section, win_lo, win_hi)) continue;
                  std::uint32_t j = 0;
                  while (j < n && !(seg[j].lo_mm < win_hi && seg[j].hi_mm > win_lo)) ++j;
                  if (j == n) continue;
                }
                rows.k[count] = k;
                rows.u[count] = u_mm;
                rows.top[count] = top;
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
                rows.top[kept] = rows.top[c];
                ++kept;
              }
              count = kept;
            }
            sweep.intervals_below(a, w_mm, count, rows.u, rows.top, rows.lo, rows.hi, rows.hit);
            for (int c = 0; c < count; ++c) {
              if (!rows.hit[c]) continue;
              const int k = rows.k[c];
              SegmentList& ray = row[k];
              const double lo = rows.lo[c], hi = rows.hi[c];
              if (move.rapid) {
                double middle = 0.0;
                const double depth = overlap(ray, lo, hi, middle);
                if (depth > probe.overlap_mm) {
                  probe.overlap_mm = depth;
                  probe.where_mm = m.point(a, f.lo_u + k, iw, middle);
                }
              } else {
                removed += subtract(ray, static_cast<float>(lo), static_cast<float>(hi), id, buffer);
                if (ray.size() == 0) f.occupied_word(k / 64, iw) &= ~(std::uint64_t{1} << (k % 64));
              }
            }
          }
          if (probe.overlap_mm > 0.0) r.probes.push_back(probe);
        }
        r.removed_mm = removed;
      }
    });
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
    if (options.progress) options.progress(last, total);
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

namespace {

// ---- The surface by dual contouring on the rays' lattice ----
//
// Nodes are the lattice points; a node's inside/outside comes from the z ray through it
// (one family decides, so neighbouring cells always agree). A cell (the cube between eight
// nodes) whose nodes differ holds the surface: one vertex, the mean of the crossings on
// its edges where the signs change (each the endpoint of the ray along that edge, exact);
// every edge where the sign changes gives a quad joining the four cells around it. Where
// the surface is flat, cells are merged: the lattice is cut into bricks of 16^3 cells, and
// within a brick an octree block of 2, 4, 8 or 16 cells a side whose cells' points lie
// within kFlatTolerance of one plane shares a single vertex; a quad whose corners now
// coincide becomes a triangle or disappears. Merging only renames vertices, so the mesh
// stays closed across merged and unmerged cells and across bricks. Bricks are meshed in
// parallel and joined in lattice order: the same mesh for any thread count.
constexpr int kBrick = 16;
constexpr int kBrickCells = kBrick * kBrick * kBrick;
constexpr int kBrickLevels = 4;  // 16 = 2^4
// A merged block's points lie within this fraction of the spacing of its plane.
constexpr double kFlatTolerance = 0.05;
// Crossings this close (mm) to one axis plane lie on it (float endpoints of one face agree).
constexpr double kExactPlane_mm = 1e-6;

// Sets bits first..last (inclusive) of a bit array.
void set_bits(std::uint64_t* words, int first, int last) {
  const int w0 = first >> 6, w1 = last >> 6;
  const std::uint64_t head = ~std::uint64_t{0} << (first & 63);
  const std::uint64_t tail = ~std::uint64_t{0} >> (63 - (last & 63));
  if (w0 == w1) {
    words[w0] |= head & tail;
    return;
  }
  words[w0] |= head;
  for (int w = w0 + 1; w < w1; ++w) words[w] = ~std::uint64_t{0};
  words[w1] |= tail;
}

// A cell's Morton code within its brick (bit 3b + a: bit b of its index along axis a),
// and back, through tables (both sit in the mesher's innermost loops).
constexpr std::array<int, kBrick> kMortonSpread = [] {
  std::array<int, kBrick> t{};
  for (int i = 0; i < kBrick; ++i)
    t[static_cast<std::size_t>(i)] = static_cast<int>(morton_spread(static_cast<std::uint64_t>(i)));
  return t;
}();
int morton(int x, int y, int z) {
  return kMortonSpread[static_cast<std::size_t>(x)] | kMortonSpread[static_cast<std::size_t>(y)] << 1 |
         kMortonSpread[static_cast<std::size_t>(z)] << 2;
}
struct MortonCell {
  std::uint8_t index[3];
};
const std::array<MortonCell, kBrickCells> kMortonCells = [] {
  std::array<MortonCell, kBrickCells> t{};
  for (int code = 0; code < kBrickCells; ++code)
    for (int b = 0; b < kBrickLevels; ++b)
      for (int a = 0; a < 3; ++a)
        t[static_cast<std::size_t>(code)].index[a] =
            static_cast<std::uint8_t>(t[static_cast<std::size_t>(code)].index[a] | ((code >> (3 * b + a)) & 1) << b);
  return t;
}();
std::array<int, 3> unmorton(int code) {
  const MortonCell& c = kMortonCells[static_cast<std::size_t>(code)];
  return {c.index[0], c.index[1], c.index[2]};
}

// Node signs of one brick: bit t of column (x, y) is node (x0 + x, y0 + y, z0 + t).
struct BrickSigns {
  std::array<std::uint32_t, (kBrick + 1) * (kBrick + 1)> column{};
  std::uint32_t at(int x, int y) const { return column[static_cast<std::size_t>(y * (kBrick + 1) + x)]; }
  bool inside(int x, int y, int z) const { return (at(x, y) >> z) & 1u; }
};

struct BrickMesh {
  std::array<int, 3> origin;          // lattice index of the brick's first node
  std::vector<std::uint16_t> cells;   // active cells, Morton codes ascending
  std::vector<std::uint32_t> vertex;  // per active cell: index into points
  std::vector<Vector3d> points;
  std::uint32_t first_vertex = 0;  // global index of points[0]
};

class Contour {
 public:
  explicit Contour(const DexelStock::Impl& m) : m_(m) {
    // Node index range per axis: the y rays span x as u, the x rays y and z.
    lo_ = {m.families[1].lo_u, m.families[0].lo_u, m.families[0].lo_w};
    count_ = {m.families[1].n_u, m.families[0].n_u, m.families[0].n_w};
    for (int a = 0; a < 3; ++a)
      bricks_[static_cast<std::size_t>(a)] = (count_[static_cast<std::size_t>(a)] - 1 + kBrick - 1) / kBrick;
  }

  SurfaceMesh run() {
    const int columns = bricks_[0] * bricks_[1];
    std::vector<std::vector<BrickMesh>> by_column(static_cast<std::size_t>(columns));
    // Node signs a brick column at a time: each node column's inside nodes as bits over the
    // whole height, from which each brick takes its 17.
    const std::size_t words = column_words();
    tbb::enumerable_thread_specific<std::vector<std::uint64_t>> column_bits;
    tbb::parallel_for(tbb::blocked_range<int>(0, columns, 1), [&](const tbb::blocked_range<int>& range) {
      std::vector<std::uint64_t>& bits = column_bits.local();
      std::vector<std::uint64_t> in_any(words), in_all(words);
      for (int c = range.begin(); c != range.end(); ++c) {
        const auto [x0, y0] = column_origin(c);
        node_bits(c, bits);
        // Nodes inside in any and in all of the brick column's node columns: a brick whose
        // nodes are all out, or all in, holds no surface (most of a stock's bricks).
        std::fill(in_any.begin(), in_any.end(), 0);
        std::fill(in_all.begin(), in_all.end(), ~std::uint64_t{0});
        for (std::size_t col = 0; col < kNodeColumns; ++col) {
          const std::uint64_t* row = bits.data() + col * words;
          for (std::size_t w = 0; w < words; ++w) {
            in_any[w] |= row[w];
            in_all[w] &= row[w];
          }
        }
        for (int bk = 0; bk < bricks_[2]; ++bk) {
          const int shift = bk * kBrick;
          if (levels(in_any.data(), shift) == 0 || levels(in_all.data(), shift) == kFullColumn) continue;
          BrickSigns sg;
          brick_signs(bits, shift, sg);
          BrickMesh b;
          b.origin = {x0, y0, lo_[2] + shift};
          if (plane(b, sg) || vertices(b, sg)) by_column[static_cast<std::size_t>(c)].push_back(std::move(b));
        }
      }
    });
    // Bricks in lattice order, numbered; vertices numbered brick after brick.
    column_first_.assign(static_cast<std::size_t>(columns) + 1, 0);
    for (int c = 0; c < columns; ++c) {
      column_first_[static_cast<std::size_t>(c) + 1] =
          column_first_[static_cast<std::size_t>(c)] + by_column[static_cast<std::size_t>(c)].size();
      for (BrickMesh& b : by_column[static_cast<std::size_t>(c)]) bricks_list_.push_back(std::move(b));
    }
    by_column.clear();
    std::uint32_t next = 0;
    for (BrickMesh& b : bricks_list_) {
      b.first_vertex = next;
      next += static_cast<std::uint32_t>(b.points.size());
    }
    std::vector<std::vector<Triangle>> faces(bricks_list_.size());
    // Each thread's table of a brick's cells by position, -1 where no cell is, as every
    // brick leaves it.
    tbb::enumerable_thread_specific<CellTable> tables([] {
      CellTable t;
      t.fill(-1);
      return t;
    });
    // A brick column at a time again, its node bits found once for all its bricks.
    tbb::parallel_for(tbb::blocked_range<int>(0, columns, 1), [&](const tbb::blocked_range<int>& range) {
      CellTable& table = tables.local();
      std::vector<std::uint64_t>& bits = column_bits.local();
      for (int c = range.begin(); c != range.end(); ++c) {
        const std::size_t first = column_first_[static_cast<std::size_t>(c)],
                          last = column_first_[static_cast<std::size_t>(c) + 1];
        if (first == last) continue;
        node_bits(c, bits);
        for (std::size_t i = first; i < last; ++i) {
          BrickSigns sg;
          brick_signs(bits, bricks_list_[i].origin[2] - lo_[2], sg);
          quads(bricks_list_[i], sg, table, faces[i]);
        }
      }
    });
    SurfaceMesh mesh;
    mesh.mesh.vertices_mm.reserve(next);
    for (const BrickMesh& b : bricks_list_)
      mesh.mesh.vertices_mm.insert(mesh.mesh.vertices_mm.end(), b.points.begin(), b.points.end());
    std::size_t triangles = 0;
    for (const auto& f : faces) triangles += f.size();
    mesh.mesh.triangles.reserve(triangles);
    for (const auto& f : faces) mesh.mesh.triangles.insert(mesh.mesh.triangles.end(), f.begin(), f.end());
    return mesh;
  }

 private:
  using Triangle = Eigen::Vector3i;
  using CellTable = std::array<int, kBrickCells>;  // a brick's vertex per cell, -1: none

  // The runs [k0, k1] of inside nodes (within [k_lo, k_hi]) on the z ray through (i, j):
  // nodes k with lo <= position(k) <= hi for one of its intervals (a node on an endpoint
  // is inside).
  template <class Visit>
  void column_nodes(int i, int j, int k_lo, int k_hi, Visit&& visit) const {
    const Family& z = m_.families[2];
    if (!z.contains(i, j)) return;
    const SegmentList& ray = z.at(i, j);
    for (std::uint32_t s = 0; s < ray.size(); ++s) {
      const float lo = ray.data()[s].lo_mm, hi = ray.data()[s].hi_mm;
      int k0 = static_cast<int>(std::ceil(m_.index_of(lo)));
      while (m_.position(k0) < lo) ++k0;
      while (m_.position(k0 - 1) >= lo) --k0;
      int k1 = static_cast<int>(std::floor(m_.index_of(hi)));
      while (m_.position(k1) > hi) --k1;
      while (m_.position(k1 + 1) <= hi) ++k1;
      k0 = std::max(k0, k_lo);
      k1 = std::min(k1, k_hi);
      if (k0 <= k1) visit(k0, k1);
    }
  }

  static constexpr std::size_t kNodeColumns = (kBrick + 1) * (kBrick + 1);
  static constexpr std::uint32_t kFullColumn = (1u << (kBrick + 1)) - 1u;  // a brick's 17 nodes

  // Lattice x and y of brick column c's first node.
  std::pair<int, int> column_origin(int c) const {
    return {lo_[0] + (c % bricks_[0]) * kBrick, lo_[1] + (c / bricks_[0]) * kBrick};
  }

  // 64-bit words per node column over the lattice's height, with room for a brick's 17
  // bits read past the last node.
  std::size_t column_words() const { return static_cast<std::size_t>(count_[2] + 64) / 64 + 1; }

  // The inside nodes of brick column c's node columns (17 x 17, x fastest), a bit per node
  // over the lattice's height (the bricks' column bits are not kept between the passes:
  // 1.2 KB a brick).
  void node_bits(int c, std::vector<std::uint64_t>& bits) const {
    const std::size_t words = column_words();
    bits.assign(kNodeColumns * words, 0);
    const auto [x0, y0] = column_origin(c);
    for (std::size_t col = 0; col < kNodeColumns; ++col) {
      std::uint64_t* row = bits.data() + col * words;
      column_nodes(x0 + static_cast<int>(col % (kBrick + 1)), y0 + static_cast<int>(col / (kBrick + 1)), lo_[2],
                   lo_[2] + count_[2] - 1, [&](int k0, int k1) { set_bits(row, k0 - lo_[2], k1 - lo_[2]); });
    }
  }

  // Bits shift .. shift + kBrick of a node column's bits.
  static std::uint32_t levels(const std::uint64_t* row, int shift) {
    const std::size_t w = static_cast<std::size_t>(shift) >> 6;
    const int offset = shift & 63;
    std::uint64_t v = row[w] >> offset;
    if (offset > 64 - (kBrick + 1)) v |= row[w + 1] << (64 - offset);
    return static_cast<std::uint32_t>(v) & kFullColumn;
  }

  // The node signs of the brick `shift` nodes up its column, from the column's node bits.
  void brick_signs(const std::vector<std::uint64_t>& bits, int shift, BrickSigns& out) const {
    const std::size_t words = column_words();
    for (std::size_t col = 0; col < kNodeColumns; ++col) out.column[col] = levels(bits.data() + col * words, shift);
  }

  // Where the ray of family `axis` at (iu, iw) crosses between nodes n and n + 1: the
  // ray's endpoint there (the middle when the ray has none: the z rays decided otherwise).
  double crossing(int axis, int iu, int iw, int n) const {
    const Family& f = m_.families[static_cast<std::size_t>(axis)];
    const double a = m_.position(n), b = m_.position(n + 1);
    if (f.contains(iu, iw)) {
      const SegmentList& ray = f.at(iu, iw);
      for (std::uint32_t s = 0; s < ray.size(); ++s) {
        const DexelSegment& seg = ray.data()[s];
        if (seg.lo_mm >= a && seg.lo_mm <= b) return seg.lo_mm;
        if (seg.hi_mm >= a && seg.hi_mm <= b) return seg.hi_mm;
        if (seg.lo_mm > b) break;
      }
    }
    return 0.5 * (a + b);
  }

  // A whole brick crossed by one axis plane that no cut touched (a stock face, a level
  // floor): every node column steps once along one axis at the same place, and every
  // crossing on that axis is the same number. vertices() would merge all its cells into one
  // vertex; this gives the same cells and the same vertex (the same sums, in the same
  // order) without looking at each cell's twelve edges. False: not such a brick.
  bool plane(BrickMesh& b, const BrickSigns& sg) const {
    for (int a = 0; a < 3; ++a)
      if (lo_[static_cast<std::size_t>(a)] + count_[static_cast<std::size_t>(a)] - 1 -
              b.origin[static_cast<std::size_t>(a)] <
          kBrick)
        return false;
    constexpr std::uint32_t kFull = (1u << (kBrick + 1)) - 1u, kSteps = (1u << kBrick) - 1u;
    // Bit k of a pattern: node k inside; its steps: bit k when nodes k and k + 1 differ.
    auto single_step = [](std::uint32_t pattern, int& step) {
      const std::uint32_t steps = (pattern ^ (pattern >> 1)) & kSteps;
      if (steps == 0 || (steps & (steps - 1)) != 0) return false;
      step = __builtin_ctz(steps);
      return true;
    };
    int axis = -1, step = 0;
    const std::uint32_t first = sg.column[0];
    if (std::all_of(sg.column.begin(), sg.column.end(), [&](std::uint32_t c) { return c == first; })) {
      if (!single_step(first, step)) return false;
      axis = 2;
    } else {
      if (!std::all_of(sg.column.begin(), sg.column.end(), [&](std::uint32_t c) { return c == 0 || c == kFull; }))
        return false;
      std::uint32_t along_x = 0, along_y = 0;
      for (int k = 0; k <= kBrick; ++k) {
        along_x |= (sg.at(k, 0) != 0 ? 1u : 0u) << k;
        along_y |= (sg.at(0, k) != 0 ? 1u : 0u) << k;
      }
      bool by_x = true, by_y = true;
      for (int y = 0; y <= kBrick; ++y)
        for (int x = 0; x <= kBrick; ++x) {
          const bool in = sg.at(x, y) != 0;
          by_x = by_x && in == (((along_x >> x) & 1u) != 0);
          by_y = by_y && in == (((along_y >> y) & 1u) != 0);
        }
      if (by_x && single_step(along_x, step))
        axis = 0;
      else if (by_y && single_step(along_y, step))
        axis = 1;
      else
        return false;
    }
    // The crossings: the rays along `axis` through the brick's nodes of the other two axes.
    const auto [o1, o2] = kOther[static_cast<std::size_t>(axis)];
    const int g = b.origin[static_cast<std::size_t>(axis)] + step;
    const int g1 = b.origin[static_cast<std::size_t>(o1)], g2 = b.origin[static_cast<std::size_t>(o2)];
    // crossing() takes (u, w) as its family orders them: z rays (x, y), x rays (y, z), y rays (x, z).
    const double value = crossing(axis, g1, g2, g);
    for (int j = 0; j <= kBrick; ++j)
      for (int i = 0; i <= kBrick; ++i)
        if (crossing(axis, g1 + i, g2 + j, g) != value) return false;
    // The cells at `step` along the axis, in Morton order, each adding its four crossings
    // in the order vertices() visits them.
    std::array<std::uint16_t, kBrick * kBrick> codes;
    std::size_t n = 0;
    for (int j = 0; j < kBrick; ++j)
      for (int i = 0; i < kBrick; ++i) {
        std::array<int, 3> cell;
        cell[static_cast<std::size_t>(axis)] = step;
        cell[static_cast<std::size_t>(o1)] = i;
        cell[static_cast<std::size_t>(o2)] = j;
        codes[n++] = static_cast<std::uint16_t>(morton(cell[0], cell[1], cell[2]));
      }
    std::sort(codes.begin(), codes.end());
    b.cells.assign(codes.begin(), codes.end());
    b.vertex.assign(codes.size(), 0);
    Vector3d sum = Vector3d::Zero();
    for (std::uint16_t code : codes) {
      const std::array<int, 3> cell = unmorton(code);
      const int i = cell[static_cast<std::size_t>(o1)], j = cell[static_cast<std::size_t>(o2)];
      for (int d = 0; d < 4; ++d) {
        const int e1 = d & 1, e2 = d >> 1;
        Vector3d at;
        at[axis] = value;
        at[o1] = m_.position(g1 + i + e1);
        at[o2] = m_.position(g2 + j + e2);
        sum += at;
      }
    }
    b.points.assign(1, sum / static_cast<double>(4 * static_cast<int>(codes.size())));
    return true;
  }

  // The brick's active cells and their (merged) vertices; false when it has none.
  bool vertices(BrickMesh& b, const BrickSigns& sg) const {
    const int limit[3] = {std::min(kBrick, lo_[0] + count_[0] - 1 - b.origin[0]),
                          std::min(kBrick, lo_[1] + count_[1] - 1 - b.origin[1]),
                          std::min(kBrick, lo_[2] + count_[2] - 1 - b.origin[2])};
    // Per active cell: its crossings (a run of `points`) and which way the surface faces
    // across each of them (bit 2a: toward +a, bit 2a + 1: toward -a, from inside to outside).
    struct Cell {
      std::uint16_t code;
      std::uint8_t facing;
      std::uint8_t count;
      std::uint32_t first;
    };
    std::vector<Cell> cells;
    std::vector<Vector3d> points;
    for (int y = 0; y < limit[1]; ++y) {
      for (int x = 0; x < limit[0]; ++x) {
        const std::uint32_t c00 = sg.at(x, y), c10 = sg.at(x + 1, y), c01 = sg.at(x, y + 1), c11 = sg.at(x + 1, y + 1);
        const std::uint32_t all = c00 & c10 & c01 & c11, any = c00 | c10 | c01 | c11;
        const std::uint32_t agree = ~(all ^ any);  // the four columns agree at this node
        const std::uint32_t uniform = agree & (agree >> 1) & ~(all ^ (all >> 1));
        std::uint32_t active = ~uniform & ((1u << limit[2]) - 1u);
        while (active != 0) {
          const int z = __builtin_ctz(active);
          active &= active - 1;
          Cell cell{static_cast<std::uint16_t>(morton(x, y, z)), 0, 0, static_cast<std::uint32_t>(points.size())};
          const int gx = b.origin[0] + x, gy = b.origin[1] + y, gz = b.origin[2] + z;
          // An edge whose ends differ: its crossing (looked up only then) joins the cell's.
          auto edge = [&](int axis, bool lower_inside, bool upper_inside, auto&& at) {
            if (lower_inside == upper_inside) return;
            cell.facing |= static_cast<std::uint8_t>(1u << (2 * axis + (lower_inside ? 0 : 1)));
            points.push_back(at());
            ++cell.count;
          };
          for (int d = 0; d < 4; ++d) {
            const int e1 = d & 1, e2 = d >> 1;
            edge(2, sg.inside(x + e1, y + e2, z), sg.inside(x + e1, y + e2, z + 1), [&] {
              return Vector3d(m_.position(gx + e1), m_.position(gy + e2), crossing(2, gx + e1, gy + e2, gz));
            });
            edge(0, sg.inside(x, y + e1, z + e2), sg.inside(x + 1, y + e1, z + e2), [&] {
              return Vector3d(crossing(0, gy + e1, gz + e2, gx), m_.position(gy + e1), m_.position(gz + e2));
            });
            edge(1, sg.inside(x + e1, y, z + e2), sg.inside(x + e1, y + 1, z + e2), [&] {
              return Vector3d(m_.position(gx + e1), crossing(1, gx + e1, gz + e2, gy), m_.position(gz + e2));
            });
          }
          cells.push_back(cell);
        }
      }
    }
    if (cells.empty()) return false;
    std::sort(cells.begin(), cells.end(), [](const Cell& p, const Cell& q) { return p.code < q.code; });
    // Octree merging, level by level: a block's cells are a run of the Morton order.
    const std::size_t n = cells.size();
    std::vector<std::uint32_t> group(n);     // the run start of each cell's merged block
    std::vector<std::uint8_t> merged(n, 1);  // the cell's block so far is one vertex
    for (std::size_t i = 0; i < n; ++i) group[i] = static_cast<std::uint32_t>(i);
    double tolerance = kFlatTolerance * m_.v;
    // Without flat merging only exact axis planes merge (untouched stock faces, floors of a
    // level flat end mill): such a block meets a differently inclined one only across
    // cells that hold both, so none of its triangles crosses a crease.
    const bool any_plane = m_.flat_merging;
    if (!any_plane) tolerance = kExactPlane_mm;
    for (int level = 1; level <= kBrickLevels; ++level) {
      const int shift = 3 * level;
      for (std::size_t first = 0; first < n;) {
        std::size_t last = first;
        while (last < n && (cells[last].code >> shift) == (cells[first].code >> shift)) ++last;
        bool candidate = true;
        for (std::size_t i = first; i < last && candidate; ++i) candidate = merged[i] != 0;
        if (candidate && last - first > 1 && flat(cells, points, first, last, tolerance, any_plane)) {
          for (std::size_t i = first; i < last; ++i) group[i] = static_cast<std::uint32_t>(first);
        } else {
          for (std::size_t i = first; i < last; ++i) merged[i] = 0;
        }
        first = last;
      }
    }
    // Each vertex at the mean of its cells' crossings.
    b.cells.resize(n);
    b.vertex.resize(n);
    std::vector<int> members;
    for (std::size_t i = 0; i < n; ++i) {
      b.cells[i] = cells[i].code;
      if (group[i] == i) {
        b.points.push_back(Vector3d::Zero());
        members.push_back(0);
      }
      const std::uint32_t vertex = static_cast<std::uint32_t>(b.points.size() - 1);
      b.vertex[i] = vertex;
      for (std::uint32_t k = 0; k < cells[i].count; ++k) b.points[vertex] += points[cells[i].first + k];
      members[vertex] += cells[i].count;
    }
    for (std::size_t p = 0; p < b.points.size(); ++p) b.points[p] /= std::max(members[p], 1);
    return true;
  }

  // Whether the cells first..last hold one flat sheet: the surface faces one way along each
  // axis (two sheets of a thin wall face opposite ways) and every crossing lies within
  // `tolerance` of one plane.
  template <class Cells>
  static bool flat(const Cells& cells, const std::vector<Vector3d>& points, std::size_t first, std::size_t last,
                   double tolerance, bool any_plane) {
    std::uint8_t facing = 0;
    for (std::size_t i = first; i < last; ++i) facing |= cells[i].facing;
    for (int a = 0; a < 3; ++a)
      if (((facing >> (2 * a)) & 3u) == 3u) return false;
    Vector3d lo = points[cells[first].first], hi = lo, mean = Vector3d::Zero();
    std::size_t count = 0;
    for (std::size_t i = first; i < last; ++i) {
      for (std::uint32_t k = 0; k < cells[i].count; ++k) {
        const Vector3d& p = points[cells[i].first + k];
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
        mean += p;
        ++count;
      }
    }
    if ((hi - lo).minCoeff() <= 2.0 * tolerance) return true;  // an axis plane
    if (!any_plane) return false;
    mean /= static_cast<double>(count);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = first; i < last; ++i) {
      for (std::uint32_t k = 0; k < cells[i].count; ++k) {
        const Vector3d d = points[cells[i].first + k] - mean;
        cov += d * d.transpose();
      }
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    const Vector3d normal = eig.eigenvectors().col(0);
    for (std::size_t i = first; i < last; ++i)
      for (std::uint32_t k = 0; k < cells[i].count; ++k)
        if (std::abs(normal.dot(points[cells[i].first + k] - mean)) > tolerance) return false;
    return true;
  }

  // The vertex (global index) of the cell at lattice index g, which must be active.
  int vertex_of(const std::array<int, 3>& g) const {
    std::array<int, 3> brick, local;
    for (int a = 0; a < 3; ++a) {
      const int rel = g[static_cast<std::size_t>(a)] - lo_[static_cast<std::size_t>(a)];
      brick[static_cast<std::size_t>(a)] = rel / kBrick;
      local[static_cast<std::size_t>(a)] = rel % kBrick;
    }
    const std::size_t column = static_cast<std::size_t>(brick[1] * bricks_[0] + brick[0]);
    const auto first = bricks_list_.begin() + static_cast<std::ptrdiff_t>(column_first_[column]);
    const auto last = bricks_list_.begin() + static_cast<std::ptrdiff_t>(column_first_[column + 1]);
    const int z0 = lo_[2] + brick[2] * kBrick;
    const auto it = std::lower_bound(first, last, z0, [](const BrickMesh& b, int z) { return b.origin[2] < z; });
    if (it == last || it->origin[2] != z0) return -1;
    const std::uint16_t code = static_cast<std::uint16_t>(morton(local[0], local[1], local[2]));
    const auto c = std::lower_bound(it->cells.begin(), it->cells.end(), code);
    if (c == it->cells.end() || *c != code) return -1;
    return static_cast<int>(it->first_vertex + it->vertex[static_cast<std::size_t>(c - it->cells.begin())]);
  }

  // The faces of every sign-changing edge starting at one of the brick's active cells'
  // lowest node.
  void quads(const BrickMesh& b, const BrickSigns& sg, CellTable& local, std::vector<Triangle>& out) const {
    // The brick's own cells by position in `local` (most quads stay inside their brick),
    // cleared again on the way out.
    struct Clear {
      CellTable& local;
      const std::vector<std::uint16_t>& cells;
      ~Clear() {
        for (std::uint16_t code : cells) local[code] = -1;
      }
    } clear{local, b.cells};
    for (std::size_t i = 0; i < b.cells.size(); ++i) local[b.cells[i]] = static_cast<int>(b.first_vertex + b.vertex[i]);
    // A brick merged into one vertex (a flat sheet, a plane brick) has quads only across its
    // lower faces: one whose four cells all lie in the brick has four equal corners.
    const bool one_vertex = b.points.size() == 1;
    for (std::uint16_t code : b.cells) {
      const auto [x, y, z] = unmorton(code);
      if (one_vertex && x > 0 && y > 0 && z > 0) continue;
      const bool in = sg.inside(x, y, z);
      for (int a = 0; a < 3; ++a) {
        const bool other = a == 0 ? sg.inside(x + 1, y, z) : a == 1 ? sg.inside(x, y + 1, z) : sg.inside(x, y, z + 1);
        if (other == in) continue;
        // Cells around the edge, counter-clockwise seen from +a.
        const int e1 = (a + 1) % 3, e2 = (a + 2) % 3;
        std::array<int, 4> v;
        const int offsets[4][2] = {{0, 0}, {-1, 0}, {-1, -1}, {0, -1}};
        bool ok = true;
        for (int q = 0; q < 4; ++q) {
          std::array<int, 3> c = {x, y, z};
          c[static_cast<std::size_t>(e1)] += offsets[q][0];
          c[static_cast<std::size_t>(e2)] += offsets[q][1];
          if (c[0] >= 0 && c[1] >= 0 && c[2] >= 0) {
            v[static_cast<std::size_t>(q)] = local[static_cast<std::size_t>(morton(c[0], c[1], c[2]))];
          } else {
            for (int k = 0; k < 3; ++k) c[static_cast<std::size_t>(k)] += b.origin[static_cast<std::size_t>(k)];
            v[static_cast<std::size_t>(q)] = vertex_of(c);
          }
          ok = ok && v[static_cast<std::size_t>(q)] >= 0;
        }
        if (!ok) continue;
        if (!in) std::swap(v[1], v[3]);  // the surface faces -a
        emit(v, out);
      }
    }
  }

  void emit(const std::array<int, 4>& v, std::vector<Triangle>& out) const {
    // Merged cells share vertices: drop repeated corners, keeping the cyclic order.
    std::array<int, 4> u;
    int n = 0;
    for (int q = 0; q < 4; ++q) {
      const int c = v[static_cast<std::size_t>(q)];
      if (n > 0 && u[static_cast<std::size_t>(n - 1)] == c) continue;
      u[static_cast<std::size_t>(n++)] = c;
    }
    if (n > 1 && u[static_cast<std::size_t>(n - 1)] == u[0]) --n;
    if (n == 3) {
      out.emplace_back(u[0], u[1], u[2]);
    } else if (n == 4) {
      out.emplace_back(u[0], u[1], u[2]);
      out.emplace_back(u[0], u[2], u[3]);
    }
  }

  const DexelStock::Impl& m_;
  std::array<int, 3> lo_{}, count_{}, bricks_{};
  std::vector<BrickMesh> bricks_list_;
  std::vector<std::size_t> column_first_;
};

SurfaceMesh contour_mesh(const DexelStock::Impl& m) { return Contour(m).run(); }

}  // namespace

SurfaceMesh DexelStock::surface() const {
  const Impl& m = *impl_;
  const double v = m.v;
  SurfaceMesh mesh = contour_mesh(m);
  // The moves that made the crossings around each vertex: its candidates on the exact surface.
  const std::size_t count = mesh.mesh.vertices_mm.size();
  std::vector<std::vector<int>> nearby(count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 512), [&](const auto& range) {
    for (std::size_t p = range.begin(); p != range.end(); ++p) {
      const Vector3d& x = mesh.mesh.vertices_mm[p];
      Eigen::Vector3i base;
      for (int a = 0; a < 3; ++a) base[a] = static_cast<int>(std::floor(m.index_of(x[a])));
      std::vector<int>& ids = nearby[p];
      for (const Family& f : m.families) {
        const auto [a1, a2] = kOther[static_cast<std::size_t>(f.axis)];
        const double s_lo = m.position(base[f.axis] - 1), s_hi = m.position(base[f.axis] + 2);
        for (int iw = base[a2] - 1; iw <= base[a2] + 2; ++iw) {
          for (int iu = base[a1] - 1; iu <= base[a1] + 2; ++iu) {
            if (!f.contains(iu, iw)) continue;
            const SegmentList& ray = f.at(iu, iw);
            for (std::uint32_t s = 0; s < ray.size(); ++s) {
              const DexelSegment& seg = ray.data()[s];
              if (seg.lo_move != kNoMove && seg.lo_mm >= s_lo && seg.lo_mm <= s_hi) ids.push_back(seg.lo_move);
              if (seg.hi_move != kNoMove && seg.hi_mm >= s_lo && seg.hi_mm <= s_hi) ids.push_back(seg.hi_move);
            }
          }
        }
      }
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    }
  });
  // A vertex lies in its lattice cell, so the surface is within a cell diagonal.
  detail::project_onto_machined_surface(m.moves, m.cutters, m.initial_distance, nearby, 2.0 * v, mesh);
  return mesh;
}

double DexelStock::volume_mm3() const {
  const Impl& m = *impl_;
  double total = 0.0;
  for (const Family& f : m.families) total += f.length_mm;
  return total * m.v * m.v / 3.0;
}

std::size_t DexelStock::memory_bytes() const {
  std::size_t bytes = sizeof(Impl) + impl_->moves.size() * sizeof(Move);
  for (const Family& f : impl_->families) {
    bytes += f.rays.size() * sizeof(SegmentList);
    for (const SegmentList& ray : f.rays) bytes += ray.heap_bytes();
  }
  return bytes;
}

Eigen::AlignedBox3d DexelStock::bounds() const { return impl_->shape_bounds; }

std::vector<DexelSegment> DexelStock::ray(int axis, int iu, int iw) const {
  const Family& f = impl_->families.at(static_cast<std::size_t>(axis));
  if (!f.contains(iu, iw)) return {};
  const SegmentList& r = f.at(iu, iw);
  return {r.data(), r.data() + r.size()};
}

std::vector<DexelEndpoint> DexelStock::endpoints() const {
  const Impl& m = *impl_;
  // Rows of all three families in order: each row's count, then each row fills its own
  // part of the list in parallel (the same order as one pass through the rays).
  std::vector<std::pair<int, int>> rows;  // family, iw
  for (int a = 0; a < 3; ++a) {
    const Family& f = m.families[static_cast<std::size_t>(a)];
    for (int iw = f.lo_w; iw < f.lo_w + f.n_w; ++iw) rows.emplace_back(a, iw);
  }
  std::vector<std::size_t> start(rows.size() + 1, 0);
  tbb::parallel_for(std::size_t{0}, rows.size(), [&](std::size_t r) {
    const Family& f = m.families[static_cast<std::size_t>(rows[r].first)];
    std::size_t n = 0;
    for (int iu = f.lo_u; iu < f.lo_u + f.n_u; ++iu) n += 2 * f.at(iu, rows[r].second).size();
    start[r + 1] = n;
  });
  for (std::size_t r = 0; r < rows.size(); ++r) start[r + 1] += start[r];
  std::vector<DexelEndpoint> out(start.back());
  tbb::parallel_for(std::size_t{0}, rows.size(), [&](std::size_t r) {
    const Family& f = m.families[static_cast<std::size_t>(rows[r].first)];
    const int iw = rows[r].second;
    std::size_t next = start[r];
    for (int iu = f.lo_u; iu < f.lo_u + f.n_u; ++iu) {
      const SegmentList& ray = f.at(iu, iw);
      for (std::uint32_t s = 0; s < ray.size(); ++s) {
        const DexelSegment& seg = ray.data()[s];
        out[next++] = {m.point(f.axis, iu, iw, seg.lo_mm), seg.lo_move, f.axis};
        out[next++] = {m.point(f.axis, iu, iw, seg.hi_mm), seg.hi_move, f.axis};
      }
    }
  });
  return out;
}

}  // namespace vcut::removal
