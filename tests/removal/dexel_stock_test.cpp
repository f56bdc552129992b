// The tri-dexel stock along its rays (issue 9): endpoints against closed-form surfaces of
// the sweeps (within 1 um), small features a coarse simulator loses (within v/10 at
// v = 0.05 mm), a tilted tool, mesh stocks and determinism. Expected values are derived
// from the geometry of each cut, never taken from vcut's output.
#include "vcut/removal/dexel_stock.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "sanitized.h"
#include "slab_distance.h"
#include "test_meshes.h"
#include "vcut/removal/cutter.h"
#include "vcut/removal/mesh.h"
#include "vcut/removal/move.h"
#include "vcut/removal/sweep.h"

namespace vcut::removal {
namespace {

constexpr double kEndpointTol_mm = 1e-3 * 1e-3 * 1000;  // 1 um

Cutter make(CutterType type, double d, double r, double flutes = 25) {
  Cutter c;
  c.type = type;
  c.diameter_mm = d;
  c.corner_radius_mm = r;
  c.flute_length_mm = flutes;
  c.length_mm = 40;
  return c;
}

Move line(Eigen::Vector3d a, Eigen::Vector3d b, Eigen::Vector3d axis = Eigen::Vector3d::UnitZ()) {
  Move m;
  m.start_mm = a;
  m.end_mm = b;
  m.axis = axis.normalized();
  return m;
}

// Distance from p to the segment a-b.
double segment_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - a - t * d).norm();
}

// Endpoints made by move `id` (not the initial stock's faces).
std::vector<DexelEndpoint> cut_points(const DexelStock& stock, int id) {
  std::vector<DexelEndpoint> out;
  for (const auto& e : stock.endpoints())
    if (e.move == id) out.push_back(e);
  return out;
}

TEST(DexelStock, BallRampEndpointsLieOnTheSweptSphere) {
  // A 6 mm ball ramping down across a box along a skew direction: below the ball centre's
  // height the sweep's surface is the set at distance 3 from the centre's segment.
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  DexelStock stock(box, 0.1);
  MoveList list;
  list.cutters.push_back(make(CutterType::Ball, 6, 3));
  const Eigen::Vector3d a(-5, 4, 1.0), b(45, 26, -4.0);
  list.moves = {line(a, b)};
  stock.cut(list, {});
  const Eigen::Vector3d ca = a + Eigen::Vector3d(0, 0, 3), cb = b + Eigen::Vector3d(0, 0, 3);
  int checked = 0;
  double worst = 0.0;
  for (const auto& e : cut_points(stock, 0)) {
    // On the lower half of the swept ball (the side walls above it are the shank's cylinder).
    const Eigen::Vector3d d = cb - ca;
    const double t = std::clamp((e.x_mm - ca).dot(d) / d.squaredNorm(), 0.0, 1.0);
    if (e.x_mm.z() > (ca + t * d).z() - 1e-3) continue;
    worst = std::max(worst, std::abs(segment_distance(e.x_mm, ca, cb) - 3.0));
    ++checked;
  }
  EXPECT_LT(worst, kEndpointTol_mm);
  EXPECT_GT(checked, 5000);
}

TEST(DexelStock, BallWallsAcrossTheMotionLieOnTheSweptDisc) {
  // A 6 mm ball ramping down along x: above the higher ball centre the sweep's slice is the
  // disc of radius 3 swept along the tip's path, so every wall point the move leaves on a y
  // ray (square to the motion) there lies 3 from the path's segment in the xy plane: on the
  // flat walls y = 15 +- 3 beside the path, on the end discs beyond it.
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  DexelStock stock(box, 0.1);
  MoveList list;
  list.cutters.push_back(make(CutterType::Ball, 6, 3));
  const Eigen::Vector3d a(5, 15, -8), b(35, 15, -11);
  list.moves = {line(a, b)};
  stock.cut(list, {});
  const double above_centres = a.z() + 3.0;
  int walls = 0, ends = 0;
  double worst = 0.0;
  for (const auto& e : cut_points(stock, 0)) {
    if (e.axis != 1 || e.x_mm.z() <= above_centres + 1e-6) continue;
    const Eigen::Vector2d p(e.x_mm.x(), e.x_mm.y());
    const double t = std::clamp((p.x() - a.x()) / (b.x() - a.x()), 0.0, 1.0);
    const Eigen::Vector2d nearest(a.x() + t * (b.x() - a.x()), 15.0);
    worst = std::max(worst, std::abs((p - nearest).norm() - 3.0));
    ++(t > 0.0 && t < 1.0 ? walls : ends);
  }
  EXPECT_LT(worst, kEndpointTol_mm);
  EXPECT_GT(walls, 2 * 49 * 290);  // two walls over the 30 mm path on every row above the centres
  EXPECT_GT(ends, 2 * 49 * 50);
}

TEST(DexelStock, FlatAndBullEndpointsLieOnTheirSweeps) {
  // Horizontal moves (closed form) and ramps (bracketing search) of a flat and a bull-nose
  // end mill. Check: the endpoint is on the boundary of the union of the cutter's poses,
  // i.e. min over t of the cutter's signed distance from the pose at t is zero; that
  // minimum is found here by dense sampling and golden refinement, independently of the
  // engine's slice formulas.
  for (const double r : {0.0, 2.0}) {
    for (const double drop : {0.0, 3.0}) {
      const BoxShape box{{0, 0, -20}, {40, 30, 0}};
      DexelStock stock(box, 0.1);
      MoveList list;
      const Cutter cutter = make(r == 0 ? CutterType::Flat : CutterType::BullNose, 10, r);
      list.cutters.push_back(cutter);
      const Eigen::Vector3d a(-8, 6, -1.0), b(48, 22, -1.0 - drop);
      list.moves = {line(a, b)};
      stock.cut(list, {});
      auto sweep_distance = [&](const Eigen::Vector3d& x) {
        auto f = [&](double t) { return cutter_distance(cutter, x - (a + t * (b - a))); };
        double best_t = 0.0, best = f(0.0);
        for (int i = 1; i <= 2000; ++i) {
          const double t = i / 2000.0;
          if (f(t) < best) {
            best = f(t);
            best_t = t;
          }
        }
        double lo = std::max(0.0, best_t - 1.0 / 2000), hi = std::min(1.0, best_t + 1.0 / 2000);
        for (int i = 0; i < 100; ++i) {
          const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
          (f(m1) < f(m2) ? hi : lo) = (f(m1) < f(m2) ? m2 : m1);
        }
        return std::min(best, f(0.5 * (lo + hi)));
      };
      double worst = 0.0;
      int checked = 0;
      const auto points = cut_points(stock, 0);
      for (std::size_t i = 0; i < points.size(); i += 7) {  // a sample: the check is slow
        worst = std::max(worst, std::abs(sweep_distance(points[i].x_mm)));
        ++checked;
      }
      EXPECT_LT(worst, kEndpointTol_mm) << "r " << r << " drop " << drop;
      EXPECT_GT(checked, 500);
    }
  }
}

TEST(DexelStock, TiltedFlatEndMillFlank) {
  // A flat D10 end mill tilted 30 deg in the yz plane, moved along x through the box's
  // +y side: its flank leaves the plane at distance R = 5 from the plane spanned by x and
  // the tool axis through the tip's path.
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  DexelStock stock(box, 0.1);
  MoveList list;
  list.cutters.push_back(make(CutterType::Flat, 10, 0, 30));
  const double angle = 30.0 * M_PI / 180.0;
  const Eigen::Vector3d axis(0, -std::sin(angle), std::cos(angle));
  const Eigen::Vector3d a(-10, 31, -12), b(50, 31, -12);
  list.moves = {line(a, b, axis)};
  stock.cut(list, {});
  const Eigen::Vector3d n = Eigen::Vector3d::UnitX().cross(axis).normalized();  // points to -y-ish
  int checked = 0;
  double worst = 0.0;
  for (const auto& e : cut_points(stock, 0)) {
    const Eigen::Vector3d q = e.x_mm - a;
    const double along = q.dot(axis);
    // The flank only: away from the tip face and from the box's end faces.
    if (along < 0.2 || e.x_mm.x() < 1 || e.x_mm.x() > 39 || std::abs(q.dot(n)) < 4) continue;
    worst = std::max(worst, std::abs(std::abs(q.dot(n)) - 5.0));
    ++checked;
  }
  EXPECT_LT(worst, kEndpointTol_mm);
  EXPECT_GT(checked, 1000);
}

// The sweeps of `list`'s moves, which the stock numbered from `first_id`; the farthest any
// endpoint they made lies from its own sweep, and how many each made.
std::vector<TranslationSweep> sweeps_and_endpoints(const DexelStock& stock, const MoveList& list, int first_id,
                                                   double& worst, std::vector<int>& made) {
  std::vector<TranslationSweep> sweeps;
  for (const Move& m : list.moves) sweeps.emplace_back(list.cutters[static_cast<std::size_t>(m.cutter)], m);
  worst = 0.0;
  made.assign(list.moves.size(), 0);
  for (const auto& e : stock.endpoints()) {
    if (e.move < first_id) continue;  // the initial stock's faces, or earlier moves
    const std::size_t i = static_cast<std::size_t>(e.move - first_id);
    worst = std::max(worst, std::abs(sweeps[i].distance(e.x_mm)));
    ++made[i];
  }
  return sweeps;
}

// Material left inside sweeps: the least of the sweeps' distances, plus the endpoint
// tolerance, at every remaining segment's midpoint of the 40 x 30 x 20 box at v = 0.25 (below
// 0: a ray a move should have cut but did not keeps a segment through its sweep).
double deepest_left_inside(const DexelStock& stock, const std::vector<TranslationSweep>& sweeps, int* split = nullptr) {
  const double v = 0.25;
  const int index_lo[3] = {0, 0, -80}, index_hi[3] = {160, 120, 0};
  double deepest = 0.0;
  for (int family = 0; family < 3; ++family) {
    const int a1 = family == 0 ? 1 : 0, a2 = family == 2 ? 1 : 2;
    for (int iu = index_lo[a1]; iu < index_hi[a1]; ++iu)
      for (int iw = index_lo[a2]; iw < index_hi[a2]; ++iw) {
        const std::vector<DexelSegment> ray = stock.ray(family, iu, iw);
        if (split != nullptr) *split += ray.size() > 1 ? 1 : 0;
        for (const DexelSegment& seg : ray) {
          Eigen::Vector3d x;
          x[family] = 0.5 * (static_cast<double>(seg.lo_mm) + seg.hi_mm);
          x[a1] = (iu + 0.5) * v;
          x[a2] = (iw + 0.5) * v;
          for (const TranslationSweep& sweep : sweeps) deepest = std::min(deepest, sweep.distance(x) + kEndpointTol_mm);
        }
      }
  }
  return deepest;
}

// Material taken outside the sweeps: the most that a point just inside either end of a
// ray's gap (0.01 mm in, or its middle when shorter) lies outside every sweep, over the 40 x
// 30 x 20 box at v = 0.25 (above 0: a cut reached past the sweep, say up to the material's
// top, where no endpoint of the move shows it); on the z rays also every 0.05 mm along the
// gap (where two sweeps' cuts join, what one took too many lies inside the gap).
double farthest_taken_outside(const DexelStock& stock, const std::vector<TranslationSweep>& sweeps) {
  const double v = 0.25;
  const int index_lo[3] = {0, 0, -80}, index_hi[3] = {160, 120, 0};
  const double box_lo[3] = {0, 0, -20}, box_hi[3] = {40, 30, 0};
  double farthest = 0.0;
  for (int family = 0; family < 3; ++family) {
    const int a1 = family == 0 ? 1 : 0, a2 = family == 2 ? 1 : 2;
    for (int iu = index_lo[a1]; iu < index_hi[a1]; ++iu)
      for (int iw = index_lo[a2]; iw < index_hi[a2]; ++iw) {
        const std::vector<DexelSegment> ray = stock.ray(family, iu, iw);
        double from = box_lo[family];
        auto gap = [&](double a, double b) {
          if (b - a <= 1e-6) return;
          const double in = std::min(0.01, 0.5 * (b - a));
          std::vector<double> at = {a + in, b - in};
          if (family == 2)
            for (double s = a + 0.05; s < b - 0.05; s += 0.05) at.push_back(s);
          for (double s : at) {
            Eigen::Vector3d x;
            x[family] = s;
            x[a1] = (iu + 0.5) * v;
            x[a2] = (iw + 0.5) * v;
            double nearest = std::numeric_limits<double>::infinity();
            for (const TranslationSweep& sweep : sweeps)
              if (nearest > 0.0 && sweep.bounds().exteriorDistance(x) < nearest)
                nearest = std::min(nearest, sweep.distance(x));
            farthest = std::max(farthest, nearest - kEndpointTol_mm);
          }
        };
        for (const DexelSegment& seg : ray) {
          gap(from, seg.lo_mm);
          from = seg.hi_mm;
        }
        gap(from, box_hi[family]);
      }
  }
  return farthest;
}

// One move through a 40 x 30 x 20 box at v = 0.25: every endpoint it made lies on its swept
// volume's surface, and no material is left inside it, measured with TranslationSweep's
// distance (a search over the move for the point's nearest instance, independent of the
// rays' closed forms, root march and window).
void expect_cut_matches_the_sweep_distance(const Cutter& cutter, const Move& m, const std::string& label) {
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  const double v = 0.25;
  DexelStock stock(box, v);
  MoveList list;
  list.cutters.push_back(cutter);
  list.moves = {m};
  stock.cut(list, {});
  const TranslationSweep sweep(list.cutters[0], m);
  double worst = 0.0;
  int checked = 0;
  for (const auto& e : cut_points(stock, 0)) {
    worst = std::max(worst, std::abs(sweep.distance(e.x_mm)));
    ++checked;
  }
  EXPECT_LT(worst, kEndpointTol_mm) << label;
  EXPECT_GT(checked, 100) << label;
  // Material left: every remaining segment's midpoint is outside the sweep.
  const double deepest = deepest_left_inside(stock, {sweep});
  EXPECT_EQ(deepest, 0.0) << label;
}

// The same for cutters at random tilts (5..70 deg) moving in random directions (along, across
// and against the tool axis).
void expect_random_tilted_moves_match_the_sweep_distance(unsigned seed, int trials,
                                                         const std::function<Cutter(double)>& cutter) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < trials; ++trial) {
    const Cutter c = cutter(4 + 8 * unit(rng));
    const double tilt = (5 + 65 * unit(rng)) * M_PI / 180.0, azimuth = 2 * M_PI * unit(rng);
    const Eigen::Vector3d axis(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
    const Eigen::Vector3d a(8 + 24 * unit(rng), 6 + 18 * unit(rng), -10 * unit(rng));
    Eigen::Vector3d step(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    if (trial % 3 == 0) step += 2.0 * axis;  // a strong component along the tool axis
    expect_cut_matches_the_sweep_distance(c, line(a, a + 12.0 * step.normalized(), axis),
                                          "trial " + std::to_string(trial));
  }
}

TEST(DexelStock, RandomTiltedFlatMovesMatchTheSweepDistance) {
  expect_random_tilted_moves_match_the_sweep_distance(29, 8, [](double d) { return make(CutterType::Flat, d, 0, 20); });
}

// The same for the other tools (the ball's closed form, the root march of the bull-nose and
// V-bit; the rays of all three pass the tilted window first).
TEST(DexelStock, RandomTiltedBallBullNoseAndVBitMovesMatchTheSweepDistance) {
  int n = 0;
  expect_random_tilted_moves_match_the_sweep_distance(31, 12, [&n](double d) {
    switch (n++ % 3) {
      case 0:
        return make(CutterType::Ball, d, d / 2, 20);
      case 1:
        return make(CutterType::BullNose, d, d / 4, 20);
      default: {
        Cutter c = make(CutterType::VBit, d, 0, 20);
        c.tip_angle_deg = 90;
        return c;
      }
    }
  });
}

// The tilted bull-nose at random tilts and motions, and in the configurations a kernel has to
// treat apart: the motion square to the tool axis with the axis tilted in a coordinate plane
// (the plane of a ray family's rays and the motion then holds the axis, and meets the flat
// bottom in a chord), the motion along a family's rays, along the tool axis, and nearly along
// a ray.
TEST(DexelStock, TiltedBullNoseMovesMatchTheSweepDistance) {
  expect_random_tilted_moves_match_the_sweep_distance(
      37, 10, [](double d) { return make(CutterType::BullNose, d, d / (3 + (static_cast<int>(d * 7) % 3)), 20); });
  const Cutter bull = make(CutterType::BullNose, 10, 2, 20);
  const double tilt = 25 * M_PI / 180.0;
  const Eigen::Vector3d a_yz(0, -std::sin(tilt), std::cos(tilt)), a_xz(std::sin(tilt), 0, std::cos(tilt));
  const Eigen::Vector3d p(12, 14, -4);
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(14, 0, 0), a_yz), "x across a yz tilt");
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(0, 12, 0), a_xz), "y across an xz tilt");
  expect_cut_matches_the_sweep_distance(bull, line(p, p + 10 * a_yz.cross(Eigen::Vector3d::UnitX()), a_yz),
                                        "square to the axis in the yz plane");
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(0, 0, -3), a_xz), "down z");
  expect_cut_matches_the_sweep_distance(bull, line(p, p - 6 * a_yz, a_yz), "plunge along the axis");
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(14, 1e-9, 0), a_xz), "nearly along x");
}

// An upright bull-nose moving up or down: its horizontal rays take the tilted tool's march
// (the bracket, the band's exact ends, the root march), its z rays Newton steps on the
// underside. Ramps down and up from inside the box, across and along the rays, and a
// plunge: every endpoint on the sweep (within 1 um of TranslationSweep's distance), none
// inside it.
TEST(DexelStock, UprightBullNoseRampsMatchTheSweepDistance) {
  const Cutter bull = make(CutterType::BullNose, 10, 2, 20);
  const Eigen::Vector3d p(14, 12, -2), up(0, 0, 1);
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(14, 5, -3), up), "ramp down");
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(-6, 8, 1.5), up), "ramp up");
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(12, 0, -0.5), up), "along x");
  expect_cut_matches_the_sweep_distance(bull, line(p, p + Eigen::Vector3d(0, 0, -4), up), "plunge");
}

// The tilted V-bit's closed form (RaySweep::cone_interval) at random tilts and motions, with
// 60, 90 and 120 deg cones, some cut off at a flute length below their full diameter, and
// where its points degenerate: the motion across the rays of a tilt in their plane, along the
// tool axis, square to it and down z; the axis along x (x rays parallel to it), moving across
// and along it. Every endpoint lies on the sweep (within 1 um of TranslationSweep's distance,
// a search over the move on the profile's slope) and no material is left inside it.
TEST(DexelStock, TiltedVBitMovesMatchTheSweepDistance) {
  int n = 0;
  expect_random_tilted_moves_match_the_sweep_distance(43, 12, [&n](double d) {
    Cutter c = make(CutterType::VBit, d, 0, n % 4 == 3 ? 0.3 * d : 20);
    c.tip_angle_deg = 60.0 + 30.0 * (n++ % 3);
    return c;
  });
  Cutter vbit = make(CutterType::VBit, 8, 0, 20);
  vbit.tip_angle_deg = 90;
  const double tilt = 35 * M_PI / 180.0;
  const Eigen::Vector3d a_yz(0, -std::sin(tilt), std::cos(tilt)), p(12, 14, -4);
  expect_cut_matches_the_sweep_distance(vbit, line(p, p + Eigen::Vector3d(14, 0, 0), a_yz), "x across a yz tilt");
  expect_cut_matches_the_sweep_distance(vbit, line(p, p - 6 * a_yz, a_yz), "plunge along the axis");
  expect_cut_matches_the_sweep_distance(vbit, line(p, p + 10 * a_yz.cross(Eigen::Vector3d::UnitX()), a_yz),
                                        "square to the axis");
  expect_cut_matches_the_sweep_distance(vbit, line(p, p + Eigen::Vector3d(0, 0, -3), a_yz), "down z");
  const Eigen::Vector3d along_x(1, 0, 0), q(6, 15, -8);
  expect_cut_matches_the_sweep_distance(vbit, line(q, q + Eigen::Vector3d(0, 8, 2), along_x), "axis along x");
  expect_cut_matches_the_sweep_distance(vbit, line(q, q + Eigen::Vector3d(10, 0, 0), along_x), "along x, axis along x");
}

// Several tilted bull-nose and V-bit moves crossing one region of a box, cut in one call: the
// later moves meet rays that earlier ones have cut already (split in two by a tilted tool,
// trimmed at one end), where the root march looks only at the material left. Every endpoint
// lies on the surface of the sweep of the move that made it (within 1 um, TranslationSweep's
// distance), and no material is left inside any sweep.
TEST(DexelStock, TiltedMovesThroughCutMaterialMatchTheirSweeps) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  const double v = 0.25;
  DexelStock stock(box, v);
  MoveList list;
  list.cutters = {make(CutterType::BullNose, 8, 2, 20), make(CutterType::BullNose, 6, 1, 20)};
  Cutter vbit = make(CutterType::VBit, 10, 0, 20);
  vbit.tip_angle_deg = 90;
  list.cutters.push_back(vbit);
  for (int i = 0; i < 9; ++i) {
    const double tilt = (15 + 55 * unit(rng)) * M_PI / 180.0, azimuth = 2 * M_PI * unit(rng);
    const Eigen::Vector3d axis(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
    // Through the box's middle, in a random direction, some along the tool axis.
    const Eigen::Vector3d mid(20 + 4 * (unit(rng) - 0.5), 15 + 4 * (unit(rng) - 0.5), -6 - 6 * unit(rng));
    Eigen::Vector3d step(unit(rng) - 0.5, unit(rng) - 0.5, 0.6 * (unit(rng) - 0.5));
    if (i % 4 == 3) step += axis;
    step = 8.0 * step.normalized();
    Move m = line(mid - step, mid + step, axis);
    m.cutter = i % 3;
    list.moves.push_back(m);
  }
  stock.cut(list, {});
  double worst;
  std::vector<int> made;
  const std::vector<TranslationSweep> sweeps = sweeps_and_endpoints(stock, list, 0, worst, made);
  EXPECT_LT(worst, kEndpointTol_mm);
  for (std::size_t i = 0; i < made.size(); ++i) EXPECT_GT(made[i], 50) << "move " << i;
  int split = 0;  // rays holding more than one interval: the cuts made tunnels
  const double deepest = deepest_left_inside(stock, sweeps, &split);
  EXPECT_EQ(deepest, 0.0);
  EXPECT_GT(split, 500);
}

// Upright bull-nose ramps of every kind the raster makes (along x, along y, skew; down and up,
// shallow to steep; short flutes whose top corner comes inside the block, and long ones)
// chained through the block, each through what the ones before cut: the horizontal rays'
// entries and exits where the section changes along the move (the corner's heights) come from
// the instances' sections (upright_ramp), checked here against the sweep's own distance (a
// search over the move in three dimensions): every endpoint each move made lies on its sweep
// within 1 um, none of the material left lies inside a sweep, and none was taken outside them.
TEST(DexelStock, RandomUprightBullNoseRampsMatchTheSweepDistance) {
  std::mt19937 rng(61);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  DexelStock stock(box, 0.25);
  MoveList list;
  list.cutters = {make(CutterType::BullNose, 6, 1, 25), make(CutterType::BullNose, 10, 3, 25),
                  make(CutterType::BullNose, 8, 0.5, 6), make(CutterType::BullNose, 5, 2, 5)};
  Eigen::Vector3d at(8, 8, -6);
  for (int i = 0; i < 24; ++i) {
    const double length = 2.0 + 6.0 * unit(rng);
    Eigen::Vector3d step;
    switch (i % 3) {
      case 0:  // along x, as a raster's rows
        step = {unit(rng) < 0.5 ? -length : length, 0.0, 0.0};
        break;
      case 1:  // along y
        step = {0.0, unit(rng) < 0.5 ? -length : length, 0.0};
        break;
      default: {
        const double angle = 2 * M_PI * unit(rng);
        step = {length * std::cos(angle), length * std::sin(angle), 0.0};
      }
    }
    const double slope = (i % 4 < 2 ? 0.02 : 0.2) + 0.5 * unit(rng);  // shallow and steep
    step.z() = (i % 2 ? 1.0 : -1.0) * slope * length;
    Eigen::Vector3d to = at + step;
    to = to.cwiseMax(Eigen::Vector3d(6, 6, -12)).cwiseMin(Eigen::Vector3d(34, 24, -2));
    if ((to - at).head<2>().norm() < 1.0 || std::abs(to.z() - at.z()) < 0.01) to.z() = at.z() + (i % 2 ? 0.3 : -0.3);
    Move m = line(at, to);
    m.cutter = i % 4;
    list.moves.push_back(m);
    at = to;
  }
  stock.cut(list, {});
  double worst;
  std::vector<int> made;
  const std::vector<TranslationSweep> sweeps = sweeps_and_endpoints(stock, list, 0, worst, made);
  EXPECT_LT(worst, kEndpointTol_mm);
  int moves_seen = 0;
  for (const int n : made) moves_seen += n > 20 ? 1 : 0;
  EXPECT_GE(moves_seen, 10);
  int endpoints = 0;
  for (const int n : made) endpoints += n;
  EXPECT_GT(endpoints, 3000);
  EXPECT_EQ(deepest_left_inside(stock, sweeps), 0.0);
  EXPECT_EQ(farthest_taken_outside(stock, sweeps), 0.0);
}

// Upright flat and bull-nose end mills ramping through material earlier ramps cut: their
// kernels see only the rays' material (the z rays' top, below which the sweep's top needs no
// search; the horizontal rays' march over [bottom, top] alone). Ramps down and up in random
// directions through the block's middle, the flutes short enough that the tops of most stay
// inside it: every endpoint each move made lies on its sweep, none of the material left lies
// inside any sweep, and none was taken outside them.
TEST(DexelStock, UprightRampsThroughCutMaterialMatchTheirSweeps) {
  std::mt19937 rng(47);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  DexelStock stock(box, 0.25);
  MoveList list;
  list.cutters = {make(CutterType::BullNose, 8, 2, 20), make(CutterType::BullNose, 6, 1, 9),
                  make(CutterType::Flat, 6, 0, 8),      make(CutterType::Flat, 50, 0, 5),
                  make(CutterType::BullNose, 6, 1, 5),  make(CutterType::Flat, 6, 0, 5)};
  // The block faced 1.2 mm down first; two ramps at the end whose tops rise from just below
  // that face (where the z rays' material top lies just above the sweep's lowest top; the
  // bull-nose's rim, whose top is r lower, from just above it).
  Move face = line({-30, 15, -1.2}, {70, 15, -1.2}, Eigen::Vector3d::UnitZ());
  face.cutter = 3;
  list.moves.push_back(face);
  for (int i = 0; i < 12; ++i) {
    const Eigen::Vector3d mid(20 + 6 * (unit(rng) - 0.5), 15 + 6 * (unit(rng) - 0.5), -9 - 6 * unit(rng));
    Eigen::Vector3d step(unit(rng) - 0.5, unit(rng) - 0.5, 0.0);
    step = 8.0 * step.normalized();
    step.z() = (i % 2 ? 3.0 : -3.0) * unit(rng) + (i % 2 ? 0.5 : -0.5);
    Move m = line(mid - step, mid + step, Eigen::Vector3d::UnitZ());
    m.cutter = i % 3;
    list.moves.push_back(m);
  }
  for (int c : {4, 5}) {
    const double y = c == 4 ? 2.0 : 27.0;  // beside the ramps above
    Move m = line({6, y, c == 4 ? -6.15 : -6.4}, {34, y + 1, -5.45}, Eigen::Vector3d::UnitZ());
    m.cutter = c;
    list.moves.push_back(m);
  }
  stock.cut(list, {});
  double worst;
  std::vector<int> made;
  const std::vector<TranslationSweep> sweeps = sweeps_and_endpoints(stock, list, 0, worst, made);
  EXPECT_LT(worst, kEndpointTol_mm);
  for (std::size_t i = 0; i < made.size(); ++i) EXPECT_GT(made[i], 50) << "move " << i;
  int split = 0;
  const double deepest = deepest_left_inside(stock, sweeps, &split);
  EXPECT_EQ(deepest, 0.0);
  EXPECT_GT(split, 500);
  EXPECT_EQ(farthest_taken_outside(stock, sweeps), 0.0);
}

// Tilted moves through a comb: fifteen upright slots first leave the x rays in up to sixteen
// intervals, so the cut's search for a ray's material in a tilted tool's window bisects
// (more than eight intervals) instead of scanning. A bull-nose, a ball and a V-bit then cut
// along x through the comb: every endpoint they made lies on its own sweep and no material is
// left inside any of their sweeps (TranslationSweep's distance, as above).
TEST(DexelStock, TiltedMovesThroughAComb) {
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  const double v = 0.25;
  DexelStock stock(box, v);
  MoveList comb;
  comb.cutters = {make(CutterType::Flat, 1, 0, 30)};
  for (int i = 0; i < 15; ++i) {
    const double x = 3.0 + 2.4 * i;
    comb.moves.push_back(line({x, -2, -16}, {x, 32, -16}));
  }
  stock.cut(comb, {});
  int shredded = 0;
  for (int iw = -64; iw < -4; ++iw)
    for (int iu = 0; iu < 120; ++iu) shredded += stock.ray(0, iu, iw).size() > 8 ? 1 : 0;
  ASSERT_GT(shredded, 1000) << "the x rays are not left in more than eight intervals";
  MoveList list;
  Cutter vbit = make(CutterType::VBit, 10, 0, 20);
  vbit.tip_angle_deg = 90;
  list.cutters = {make(CutterType::BullNose, 8, 2, 20), make(CutterType::Ball, 6, 3, 20), vbit};
  const double tilt = 25 * M_PI / 180.0;
  const Eigen::Vector3d axes[3] = {{0, std::sin(tilt), std::cos(tilt)},
                                   {std::sin(tilt) * 0.6, -std::sin(tilt) * 0.8, std::cos(tilt)},
                                   {-std::sin(tilt), 0.2, std::cos(tilt)}};
  for (int i = 0; i < 3; ++i) {
    const double y = 7.0 + 8.0 * i, z = -9.0 + 1.5 * i;
    Move m = line({-2, y, z}, {42, y + 1.0, z - 0.5}, axes[i].normalized());
    m.cutter = i;
    list.moves.push_back(m);
  }
  stock.cut(list, {});
  double worst;
  std::vector<int> made;
  const std::vector<TranslationSweep> sweeps =
      sweeps_and_endpoints(stock, list, static_cast<int>(comb.moves.size()), worst, made);
  EXPECT_LT(worst, kEndpointTol_mm);
  for (std::size_t i = 0; i < made.size(); ++i) EXPECT_GT(made[i], 200) << "move " << i;
  const double deepest = deepest_left_inside(stock, sweeps);
  EXPECT_EQ(deepest, 0.0);
}

// On a processor with AVX2 the ball's rays, the bull-nose's bracket (a ball swept over a
// parallelogram), the tilted flat end mill's ellipse and the windows of a run of tilted moves
// cut together (a random tilted chain's: no hand-over) are found four rays at a time, else
// ray by ray; VCUT_SCALAR_KERNELS asks for the second everywhere. The same operations in the
// same order: `list` cut both ways through the 40 x 30 x 20 box at v = 0.25 leaves every ray
// the same intervals, to the bit and to the move that made each end. Returns the volume
// removed.
double expect_the_same_rays_four_at_a_time(const MoveList& list) {
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  double removed[2];
  auto cut = [&](bool scalar) {
    if (scalar) ::setenv("VCUT_SCALAR_KERNELS", "1", 1);
    auto stock = std::make_unique<DexelStock>(box, 0.25);
    removed[scalar] = stock->cut(list, {}).removed_volume_mm3;
    ::unsetenv("VCUT_SCALAR_KERNELS");
    return stock;
  };
  const std::unique_ptr<DexelStock> lanes = cut(false), scalar = cut(true);
  EXPECT_EQ(removed[0], removed[1]);
  const int index_lo[3] = {0, 0, -80}, index_hi[3] = {160, 120, 0};
  int differ = 0, cut_rays = 0;
  for (int family = 0; family < 3; ++family) {
    const int a1 = family == 0 ? 1 : 0, a2 = family == 2 ? 1 : 2;
    for (int iu = index_lo[a1]; iu < index_hi[a1]; ++iu)
      for (int iw = index_lo[a2]; iw < index_hi[a2]; ++iw) {
        const std::vector<DexelSegment> a = lanes->ray(family, iu, iw), b = scalar->ray(family, iu, iw);
        bool same = a.size() == b.size();
        for (std::size_t k = 0; same && k < a.size(); ++k)
          same = a[k].lo_mm == b[k].lo_mm && a[k].hi_mm == b[k].hi_mm && a[k].lo_move == b[k].lo_move &&
                 a[k].hi_move == b[k].hi_move;
        differ += same ? 0 : 1;
        for (const DexelSegment& seg : a) cut_rays += seg.lo_move >= 0 || seg.hi_move >= 0 ? 1 : 0;
      }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(cut_rays, 20000);
  return removed[0];
}

bool have_avx2() {
#if defined(__x86_64__)
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

// A chain of 60 random tilted moves (the axis turning a few degrees a move, every move
// starting where the last ended, through what the earlier ones cut; the tools' tops within
// the stock): steps of up to `step` mm across (from -step / 3), the axis nudged by up to
// `turn` / 2 a move, move i with cutter cutter_of(i).
template <class CutterOf>
MoveList random_tilted_chain(std::vector<Cutter> cutters, unsigned seed, Eigen::Vector3d axis, double step, double turn,
                             CutterOf cutter_of) {
  MoveList list;
  list.cutters = std::move(cutters);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::Vector3d at(6, 6, -8);
  for (int i = 0; i < 60; ++i) {
    Eigen::Vector3d to =
        at + Eigen::Vector3d(step * unit(rng) - step / 3.0, step * unit(rng) - step / 3.0, 2.0 * unit(rng) - 1.0);
    to = to.cwiseMax(Eigen::Vector3d(4, 4, -14)).cwiseMin(Eigen::Vector3d(36, 26, -4));
    axis = (axis.normalized() + turn * Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, 0)).normalized();
    if (axis.z() < std::cos(60 * M_PI / 180.0)) axis.z() = 1.0;  // keep within 60 deg of upright
    Move m = line(at, to, axis);
    m.cutter = cutter_of(i);
    list.moves.push_back(m);
    at = to;
  }
  return list;
}

// Tilted ball and bull-nose moves.
TEST(DexelStock, TiltedBallAndBullNoseCutTheSameFourRaysAtATime) {
  if (!have_avx2()) GTEST_SKIP() << "no AVX2 here: only the scalar kernels run";
  const MoveList list = random_tilted_chain({make(CutterType::Ball, 6, 3, 12), make(CutterType::BullNose, 8, 2, 12)},
                                            53, {0.2, 0.3, 1.0}, 3.0, 0.08, [](int i) { return i / 30; });
  EXPECT_GT(expect_the_same_rays_four_at_a_time(list), 500.0);
}

// Tilted V-bits (the cone's closed form four rays at a time): a 90 deg one and a 60 deg one
// cut off at a flute length below its full diameter, so that the rays meet the cone, the
// cylinder, the top and the line where they join.
TEST(DexelStock, TiltedVBitCutsTheSameFourRaysAtATime) {
  if (!have_avx2()) GTEST_SKIP() << "no AVX2 here: only the scalar kernels run";
  Cutter wide = make(CutterType::VBit, 8, 0, 12), narrow = make(CutterType::VBit, 6, 0, 2.5);
  wide.tip_angle_deg = 90;
  narrow.tip_angle_deg = 60;
  const MoveList list =
      random_tilted_chain({wide, narrow}, 61, {0.25, -0.2, 1.0}, 3.0, 0.08, [](int i) { return i % 3 == 2 ? 1 : 0; });
  EXPECT_GT(expect_the_same_rays_four_at_a_time(list), 300.0);
}

// Tilted flat end mills (the ellipse's closed form four rays at a time): a long one, and one
// 4 mm tall whose top stays inside the stock, so that the rays walk the lines t = 0, t = 1
// and both end planes' and meet the corners.
TEST(DexelStock, TiltedFlatCutsTheSameFourRaysAtATime) {
  if (!have_avx2()) GTEST_SKIP() << "no AVX2 here: only the scalar kernels run";
  const MoveList list = random_tilted_chain({make(CutterType::Flat, 6, 0, 12), make(CutterType::Flat, 10, 0, 4)}, 59,
                                            {-0.3, 0.2, 1.0}, 4.5, 0.1, [](int i) { return i % 2; });
  EXPECT_GT(expect_the_same_rays_four_at_a_time(list), 500.0);
}

// A zig-zag raster in x over a wavy floor (8 rows of 24 steps along x and in z, the rows
// below, between and above a ball's centres; the rows from level_from on level at -9 mm),
// row r with cutter cutter_of(r), then a ramp in y and a plunge.
template <class CutterOf>
MoveList wavy_raster(std::vector<Cutter> cutters, int level_from, CutterOf cutter_of) {
  MoveList list;
  list.cutters = std::move(cutters);
  Eigen::Vector3d at(2, 3, -2);
  for (int row = 0; row < 8; ++row) {
    for (int i = 1; i <= 24; ++i) {
      const double x = row % 2 == 0 ? 2 + 1.5 * i : 38 - 1.5 * i;
      const Eigen::Vector3d to(x, 3 + 3.0 * row, row < level_from ? -6 - 2.5 * std::sin(0.4 * x + row) : -9.0);
      Move m = line(at, to);
      m.cutter = cutter_of(row);
      list.moves.push_back(m);
      at = to;
    }
  }
  list.moves.push_back(line(at, {at.x(), 28, -3}));
  list.moves.push_back(line({20, 15, 2}, {20, 15, -12}));
  return list;
}

// An upright ball.
TEST(DexelStock, UprightBallCutsTheSameFourRaysAtATime) {
  if (!have_avx2()) GTEST_SKIP() << "no AVX2 here: only the scalar kernels run";
  const MoveList list = wavy_raster({make(CutterType::Ball, 6, 3, 12)}, 8, [](int) { return 0; });
  EXPECT_GT(expect_the_same_rays_four_at_a_time(list), 500.0);
}

// An upright bull-nose (every move a ramp but on two level rows): its vertical rays four at
// a time where an end of the move settles them, the rest by the scalar search; its horizontal
// rows where the section stays the full radius four at a time.
TEST(DexelStock, UprightBullNoseCutsTheSameFourRaysAtATime) {
  if (!have_avx2()) GTEST_SKIP() << "no AVX2 here: only the scalar kernels run";
  const MoveList list = wavy_raster({make(CutterType::BullNose, 6, 1, 12), make(CutterType::BullNose, 10, 3, 4)}, 6,
                                    [](int row) { return row % 3 == 2 ? 1 : 0; });
  EXPECT_GT(expect_the_same_rays_four_at_a_time(list), 500.0);
}

// An upright flat end mill (ramps: its section never changes) and a V-bit on the level rows:
// their horizontal rays' closed form four at a time, across the motion and along it.
TEST(DexelStock, UprightFlatAndVBitCutTheSameFourRaysAtATime) {
  if (!have_avx2()) GTEST_SKIP() << "no AVX2 here: only the scalar kernels run";
  Cutter vbit = make(CutterType::VBit, 6, 0, 12);
  vbit.tip_angle_deg = 90;
  const MoveList list =
      wavy_raster({make(CutterType::Flat, 6, 0, 12), vbit}, 6, [](int row) { return row >= 6 ? 1 : 0; });
  EXPECT_GT(expect_the_same_rays_four_at_a_time(list), 500.0);
}

// An upright V-bit on the wavy rows (every move a ramp): its horizontal rays' cone closed form
// four at a time; a 90 deg one and a 60 deg one cut off below its full diameter.
TEST(DexelStock, UprightVBitRampsCutTheSameFourRaysAtATime) {
  if (!have_avx2()) GTEST_SKIP() << "no AVX2 here: only the scalar kernels run";
  Cutter wide = make(CutterType::VBit, 6, 0, 12), narrow = make(CutterType::VBit, 6, 0, 2.5);
  wide.tip_angle_deg = 90;
  narrow.tip_angle_deg = 60;
  const MoveList list = wavy_raster({wide, narrow}, 8, [](int row) { return row % 3 == 2 ? 1 : 0; });
  EXPECT_GT(expect_the_same_rays_four_at_a_time(list), 300.0);
}

// The tilted flat end mill where its ellipse degenerates into strips: moving along its own
// axis (or off it by rounding, in a ray family's plane with the axis) and with a ray family
// along the axis. Also a plunge along a lattice axis, where both hold.
TEST(DexelStock, FlatEndMillAlongItsAxisAndRaysAlongTheAxis) {
  const Cutter flat = make(CutterType::Flat, 8, 0, 20);
  const double tilt = 25 * M_PI / 180.0;
  const Eigen::Vector3d a_yz(0, -std::sin(tilt), std::cos(tilt));
  const Eigen::Vector3d p(20, 14, -4);
  expect_cut_matches_the_sweep_distance(flat, line(p, p - 7 * a_yz, a_yz), "plunge along a tilted axis");
  expect_cut_matches_the_sweep_distance(flat, line(p - 7 * a_yz, p, a_yz), "retract along a tilted axis");
  // As APT's six decimals leave a plunge: 3e-5 mm off the axis over 7 mm, in the plane of the
  // tilt (for the x and z rays the offset's motion and the ray then run side by side).
  const Eigen::Vector3d a_xz(std::sin(tilt), 0, std::cos(tilt)), off_xz(std::cos(tilt), 0, -std::sin(tilt));
  expect_cut_matches_the_sweep_distance(flat, line(p, p - 7 * a_xz + 3e-5 * off_xz, a_xz), "plunge off the axis");
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY(), x = Eigen::Vector3d::UnitX();
  expect_cut_matches_the_sweep_distance(flat, line({5, 5, -6}, {30, 5, -9}, y), "horizontal along y, moving in xz");
  expect_cut_matches_the_sweep_distance(flat, line({5, 8, -14}, {5, 20, -6}, x), "horizontal along x, moving in yz");
  expect_cut_matches_the_sweep_distance(flat, line({5, 5, -6}, {30, 11, -9}, y), "horizontal along y, moving in xyz");
  expect_cut_matches_the_sweep_distance(flat, line({9, 8, -14}, {4, 20, -6}, x), "horizontal along x, moving in xyz");
  expect_cut_matches_the_sweep_distance(flat, line({25, 10, -8}, {15, 10, -8}, x), "horizontal along x, plunging");
}

// A rapid's depth in material is the shortest, over the three ray families, of the longest
// stretch of a ray's material inside the rapid's sweep. Worked out here ray by ray, each ray's
// stretch inside the sweep found from the sweep's signed distance (sampled, then bisected),
// for tilted and upright probes through a stock whose rays hold several intervals (a tunnel
// and a slot cut first): the cut's windows and its skipping of rays that cannot be longer
// must not lose the longest.
TEST(DexelStock, RapidDepthIsTheLongestOverlapAlongTheRays) {
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  const double v = 0.5;
  DexelStock stock(box, v);
  MoveList cuts;
  cuts.cutters.push_back(make(CutterType::Ball, 6, 3, 20));
  cuts.moves = {line({-5, 2, -10}, {45, 2, -10}, Eigen::Vector3d::UnitY()),  // a tunnel along x, 6 mm wide
                line({20, -5, -4}, {20, 35, -4})};                           // a slot along y
  stock.cut(cuts, {});
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 8; ++trial) {
    MoveList list;
    const double d = 3 + 4 * unit(rng);
    list.cutters.push_back(trial % 2 == 0 ? make(CutterType::Flat, d, 0, 15) : make(CutterType::Ball, d, d / 2, 15));
    const double tilt = (trial == 0 ? 0.0 : 5 + 60 * unit(rng)) * M_PI / 180.0, azimuth = 2 * M_PI * unit(rng);
    const Eigen::Vector3d axis(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
    const Eigen::Vector3d a(8 + 24 * unit(rng), 6 + 18 * unit(rng), -2 - 8 * unit(rng));
    const Eigen::Vector3d step(unit(rng) - 0.5, unit(rng) - 0.5, 0.3 * (unit(rng) - 0.5));
    Move rapid = line(a, a + 10.0 * step.normalized(), axis);
    rapid.rapid = true;
    list.moves = {rapid};
    const CutResult r = stock.cut(list, {});
    const TranslationSweep sweep(list.cutters[0], rapid);
    double expected = std::numeric_limits<double>::infinity();
    for (int family = 0; family < 3; ++family) {
      const int a1 = family == 0 ? 1 : 0, a2 = family == 2 ? 1 : 2;
      const double s_lo = sweep.bounds().min()[family] - 1.0, s_hi = sweep.bounds().max()[family] + 1.0;
      double longest = 0.0;
      const Eigen::Vector3d& bmin = sweep.bounds().min();
      const Eigen::Vector3d& bmax = sweep.bounds().max();
      for (int iu = static_cast<int>(std::floor(bmin[a1] / v)) - 1; iu * v < bmax[a1]; ++iu)
        for (int iw = static_cast<int>(std::floor(bmin[a2] / v)) - 1; iw * v < bmax[a2]; ++iw) {
          const auto ray = stock.ray(family, iu, iw);
          if (ray.empty()) continue;
          Eigen::Vector3d x;
          x[a1] = (iu + 0.5) * v;
          x[a2] = (iw + 0.5) * v;
          auto inside = [&](double s) {
            x[family] = s;
            return sweep.distance(x) <= 0.0;
          };
          // The sweep is convex: the ray is inside it on one interval, bracketed by samples.
          constexpr double kStep_mm = 0.05;
          double first = 0.0, last = 0.0;
          bool found = false;
          for (double s = s_lo; s <= s_hi; s += kStep_mm)
            if (inside(s)) {
              if (!found) first = s;
              found = true;
              last = s;
            }
          if (!found) continue;
          auto edge = [&](double in, double out) {
            for (int k = 0; k < 60; ++k) {
              const double mid = 0.5 * (in + out);
              (inside(mid) ? in : out) = mid;
            }
            return in;
          };
          const double lo = edge(first, first - kStep_mm), hi = edge(last, last + kStep_mm);
          for (const DexelSegment& seg : ray)
            longest = std::max(longest, std::min<double>(seg.hi_mm, hi) - std::max<double>(seg.lo_mm, lo));
        }
      if (longest > 0.0) expected = std::min(expected, longest);
    }
    const std::string label = "trial " + std::to_string(trial);
    ASSERT_GT(expected, 1.0) << label;  // each rapid runs well into the material
    ASSERT_EQ(r.collisions.size(), 1u) << label;
    EXPECT_NEAR(r.collisions[0].depth_mm, expected, 1e-6) << label;
    EXPECT_NEAR(r.removed_volume_mm3, 0.0, 1e-12) << label;
  }
}

// Groove geometry read off the rays: depth from the z rays, width from the y rays at one
// height (the rays cross the groove, which runs along x).
struct Groove {
  double depth_mm = 0, width_mm = 0;
};
Groove measure(const DexelStock& stock, double x, int iz) {
  const double v = stock.spacing_mm();
  const int ix = static_cast<int>(std::lround(x / v - 0.5));
  Groove g;
  for (int iy = static_cast<int>(5 / v); iy < static_cast<int>(15 / v); ++iy) {
    const auto ray = stock.ray(2, ix, iy);
    if (!ray.empty()) g.depth_mm = std::max(g.depth_mm, -static_cast<double>(ray.back().hi_mm));
  }
  const auto ray = stock.ray(1, ix, iz);
  for (std::size_t s = 1; s < ray.size(); ++s)
    g.width_mm = std::max(g.width_mm, static_cast<double>(ray[s].lo_mm - ray[s - 1].hi_mm));
  return g;
}

TEST(DexelStock, SmallFeaturesAtFiftyMicrons) {
  // At v = 0.05 mm: a 1 mm flat groove 0.2 deep and a 0.5 mm ball groove 0.1 deep, along x
  // at y = 10.013. Widths read on the y rays at z = (-2 + 0.5) v = -0.075: 1.0 for the flat,
  // 2 sqrt(0.25^2 - (0.15 + 0.075)^2) for the ball (its centre at z = 0.15); depths 0.2
  // and 0.1 less the ball's rise at the z ray nearest its centre (0.012 mm off); within v/10.
  constexpr double v = 0.05;
  const BoxShape box{{0, 0, -2}, {20, 20, 0}};
  for (const bool ball : {false, true}) {
    DexelStock stock(box, v);
    MoveList list;
    list.cutters.push_back(ball ? make(CutterType::Ball, 0.5, 0.25, 2) : make(CutterType::Flat, 1.0, 0, 2));
    const double depth = ball ? 0.1 : 0.2;
    list.moves = {line({-1, 10.013, -depth}, {21, 10.013, -depth})};
    stock.cut(list, {});
    const Groove g = measure(stock, 7.3, -2);
    const double rise = ball ? 0.25 - std::sqrt(0.25 * 0.25 - 0.012 * 0.012) : 0.0;
    const double width = ball ? 2 * std::sqrt(0.25 * 0.25 - 0.225 * 0.225) : 1.0;
    EXPECT_NEAR(g.depth_mm, depth - rise, v / 10) << (ball ? "ball" : "flat");
    EXPECT_NEAR(g.width_mm, width, v / 10) << (ball ? "ball" : "flat");
    // Along the rays the values are exact, far inside v/10.
    EXPECT_NEAR(g.depth_mm, depth - rise, 1e-5) << (ball ? "ball" : "flat");
    EXPECT_NEAR(g.width_mm, width, 1e-5) << (ball ? "ball" : "flat");
  }
}

Cutter vbit(double angle_deg) {
  Cutter c;
  c.type = CutterType::VBit;
  c.diameter_mm = 6;
  c.tip_angle_deg = angle_deg;
  c.flute_length_mm = 10;
  c.length_mm = 30;
  return c;
}

TEST(DexelStock, VBitEngravingAlongAPolylineWithCorners) {
  // A 90 deg V-bit engraving 0.1 mm deep at v = 0.05 mm along a polyline with two sharp
  // corners. On the straight leg along x at y = 10.013 the groove's walls are the planes
  // |y - 10.013| = (z + 0.1) tan 45: its width on the y rays at z = -0.075 is 2 * 0.025, its
  // depth under the z rays 0.012 mm off the tip's line is 0.1 - 0.012; every endpoint the
  // leg made lies on those planes within 1 um.
  constexpr double v = 0.05, depth = 0.1, y0 = 10.013;
  const BoxShape box{{0, 0, -2}, {20, 20, 0}};
  DexelStock stock(box, v);
  MoveList list;
  list.cutters.push_back(vbit(90));
  list.moves = {line({-1, y0, 1}, {-1, y0, -depth}), line({-1, y0, -depth}, {12, y0, -depth}),
                line({12, y0, -depth}, {15, 16, -depth}), line({15, 16, -depth}, {13, 18, -depth})};
  stock.cut(list, {});
  const Groove g = measure(stock, 7.3, -2);
  EXPECT_NEAR(g.depth_mm, depth - 0.012, 1e-5);
  EXPECT_NEAR(g.width_mm, 2 * 0.025, 1e-5);
  int checked = 0;
  double worst = 0.0;
  for (const auto& e : cut_points(stock, 1)) {
    const Eigen::Vector3d& p = e.x_mm;
    if (p.x() < 0.5 || p.x() > 11) continue;  // away from the corners
    worst = std::max(worst, std::abs(std::abs(p.y() - y0) - (p.z() + depth)));
    ++checked;
  }
  EXPECT_LT(worst, kEndpointTol_mm);
  EXPECT_GT(checked, 400);
  // Past the corner the next leg (to (15, 16)) cut a groove too: a z ray under its middle.
  const int ix = static_cast<int>(std::lround(13.5 / v - 0.5)), iy = static_cast<int>(std::lround(13.0 / v - 0.5));
  const auto ray = stock.ray(2, ix, iy);
  ASSERT_FALSE(ray.empty());
  EXPECT_LT(ray.back().hi_mm, -0.05);
}

// The machined mesh's top on the vertical line through (x, y): the highest triangle it meets
// (lowest() when none does).
double mesh_top_mm(const TriangleMesh& mesh, double x, double y) {
  double top = std::numeric_limits<double>::lowest();
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d &a = mesh.vertices_mm[static_cast<std::size_t>(t[0])],
                          &b = mesh.vertices_mm[static_cast<std::size_t>(t[1])],
                          &c = mesh.vertices_mm[static_cast<std::size_t>(t[2])];
    const double det = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (std::abs(det) < 1e-18) continue;  // seen edge-on from above
    const double u = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / det;
    const double w = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / det;
    if (u < -1e-12 || w < -1e-12 || u + w > 1 + 1e-12) continue;
    top = std::max(top, a.z() + u * (b.z() - a.z()) + w * (c.z() - a.z()));
  }
  return top;
}

// Issue 24 item 5: the meshed surface keeps its creases. A 90 deg V-bit engraving 0.1 mm deep
// at v = 0.05 mm, along x with its bottom crease midway between two rows of nodes (y = 10.0,
// z = -0.1, where the groove is exactly a cell wide at the nodes' height: the worst case,
// and the bench's round coordinates) and along a line at 30 deg to the rays: the mesh's
// floor on the crease lies at the tip's depth within 0.005 mm (the closed form: the V's
// bottom is the tip's path). Before, the cells' vertices at the mean of their crossings cut
// the crease 0.02-0.03 mm high. A 2 mm flat end mill's slots 0.5 mm deep at 30 and 45 deg to
// the rays: 0.02 mm outside a wall the mesh is the stock's top within 0.005 mm, 0.02 mm inside
// it the slot's floor (before: a stair-stepped chamfer up to 0.05 mm wide along the edge).
TEST(DexelStock, MeshKeepsVBitCreasesAndSlotEdges) {
  constexpr double v = 0.05, depth = 0.1;
  const BoxShape box{{0, 0, -2}, {12, 12, 0}};
  DexelStock stock(box, v);
  MoveList list;
  list.cutters.push_back(vbit(90));
  list.cutters.push_back(make(CutterType::Flat, 2, 0, 10));
  const double c30 = std::cos(M_PI / 6), s30 = std::sin(M_PI / 6);
  const Eigen::Vector3d a(1, 10, -depth), b(11, 10, -depth);                            // along x, y = 10.0
  const Eigen::Vector3d p(1, 1.5, -depth), q = p + 8.0 * Eigen::Vector3d(c30, s30, 0);  // 30 deg
  const Eigen::Vector3d slot0(1.3, 4.2, -0.5), slot1 = slot0 + 8.0 * Eigen::Vector3d(c30, s30, 0);
  const Eigen::Vector3d slot45_0(8.5, 0.8, -0.5), slot45_1 = slot45_0 + 3.0 * Eigen::Vector3d(M_SQRT1_2, M_SQRT1_2, 0);
  const Eigen::Vector3d up(0, 0, 1);
  auto cut = [&](int cutter, const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
    for (Move m : {line(from + up, from), line(from, to), line(to, to + up)}) {
      m.cutter = cutter;
      list.moves.push_back(m);
    }
  };
  cut(0, a, b);
  cut(0, p, q);
  cut(1, slot0, slot1);
  cut(1, slot45_0, slot45_1);
  stock.cut(list, {});
  const TriangleMesh mesh = stock.surface().mesh;
  double worst = 0.0;
  int checked = 0;
  for (int i = 0; i <= 40; ++i) {
    const double t = 0.1 + 0.8 * i / 40.0;
    for (const auto& [from, to] : {std::pair(a, b), std::pair(p, q)}) {
      const Eigen::Vector3d on = from + t * (to - from);
      const double top = mesh_top_mm(mesh, on.x(), on.y());
      ASSERT_GT(top, -1.0) << "no surface above " << on.transpose();
      worst = std::max(worst, std::abs(top - -depth));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 82);
  EXPECT_LT(worst, 0.005) << "the V's floor off its crease";
  // The slots' walls: the lines at 1 mm (the radius) from their centre lines.
  double outside = 0.0, inside = 0.0;
  for (const auto& [from, to] : {std::pair(slot0, slot1), std::pair(slot45_0, slot45_1)}) {
    const Eigen::Vector3d along = (to - from).normalized(), side(-along.y(), along.x(), 0);
    for (int i = 0; i <= 40; ++i) {
      const Eigen::Vector3d on = from + (0.1 + 0.8 * i / 40.0) * (to - from);
      for (double sign : {-1.0, 1.0}) {
        const Eigen::Vector3d out = on + sign * 1.02 * side, in = on + sign * 0.98 * side;
        outside = std::max(outside, std::abs(mesh_top_mm(mesh, out.x(), out.y()) - 0.0));
        inside = std::max(inside, std::abs(mesh_top_mm(mesh, in.x(), in.y()) - -0.5));
      }
    }
  }
  EXPECT_LT(outside, 0.005) << "the slot's top edge chamfered";
  EXPECT_LT(inside, 0.005) << "the slot's bottom edge rounded";
}

// Issue 24 item 5, where creases meet and end: a 90 deg V-bit 0.1 mm deep at v = 0.05 mm on
// round coordinates (its walls pass through the nodes 0.025 mm below the top nodes' row, the
// worst case for the lattice), a bar along x from a plunge at (2, 6) to (8, 6) and a stem from
// a plunge at (5, 6) on the bar down to (5, 2): a T where three creases meet, and three
// groove ends where a crease ends in the plunge's cone. The floor is the tip's path (closed
// form: -0.1 mm) all along both creases up to their ends. Before, the cells at the T held
// their crossings in the nodes' plane and were merged into one flat vertex (the floor 0.03 mm
// high beside the T), and at a groove's end the cone's narrow fan of planes was cut off as if
// undetermined (up to 0.012 mm high).
TEST(DexelStock, MeshKeepsVBitJunctionsAndGrooveEnds) {
  constexpr double v = 0.05, depth = 0.1;
  const BoxShape box{{0, 0, -2}, {10, 10, 0}};
  DexelStock stock(box, v);
  MoveList list;
  list.cutters.push_back(vbit(90));
  const Eigen::Vector3d up(0, 0, 1);
  const Eigen::Vector3d bar0(2, 6, -depth), bar1(8, 6, -depth), stem0(5, 6, -depth), stem1(5, 2, -depth);
  for (const auto& [from, to] : {std::pair(bar0, bar1), std::pair(stem0, stem1)})
    for (const Move& m : {line(from + up, from), line(from, to), line(to, to + up)}) list.moves.push_back(m);
  stock.cut(list, {});
  const TriangleMesh mesh = stock.surface().mesh;
  double worst = 0.0;
  Eigen::Vector3d worst_at = Eigen::Vector3d::Zero();
  int checked = 0;
  for (const auto& [from, to] : {std::pair(bar0, bar1), std::pair(stem0, stem1)}) {
    // Every 0.0037 mm along the crease (not a fraction of a cell), ends included.
    const double length = (to - from).norm();
    for (double s = 0.0; s <= length; s += 0.0037) {
      const Eigen::Vector3d on = from + s / length * (to - from);
      const double off = std::abs(mesh_top_mm(mesh, on.x(), on.y()) - -depth);
      if (off > worst) {
        worst = off;
        worst_at = on;
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 2700);
  EXPECT_LT(worst, 0.005) << "the V's floor off its crease at " << worst_at.transpose();
}

TEST(DexelStock, VBitRampMatchesTheConeSweep) {
  // A 60 deg V-bit ramping down (the cone's closed form on the x and y rays, where the section
  // changes along the move; Newton steps on z): every endpoint is on the boundary of the
  // union of the cone's poses, checked by dense sampling along the move.
  const BoxShape box{{0, 0, -5}, {20, 10, 0}};
  DexelStock stock(box, 0.1);
  MoveList list;
  const Cutter cutter = vbit(60);
  list.cutters.push_back(cutter);
  const Eigen::Vector3d a(-1, 4, 0.5), b(21, 6, -1.5);
  list.moves = {line(a, b)};
  stock.cut(list, {});
  double worst = 0.0;
  int checked = 0;
  const auto points = cut_points(stock, 0);
  for (std::size_t i = 0; i < points.size(); i += 5) {
    const Eigen::Vector3d& x = points[i].x_mm;
    double best = std::numeric_limits<double>::infinity();
    double best_t = 0.0;
    for (int k = 0; k <= 4000; ++k) {
      const double t = k / 4000.0, d = cutter_distance(cutter, x - (a + t * (b - a)));
      if (d < best) {
        best = d;
        best_t = t;
      }
    }
    double lo = std::max(0.0, best_t - 1e-3), hi = std::min(1.0, best_t + 1e-3);
    for (int k = 0; k < 100; ++k) {
      const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
      if (cutter_distance(cutter, x - (a + m1 * (b - a))) < cutter_distance(cutter, x - (a + m2 * (b - a))))
        hi = m2;
      else
        lo = m1;
    }
    best = std::min(best, cutter_distance(cutter, x - (a + 0.5 * (lo + hi) * (b - a))));
    worst = std::max(worst, std::abs(best));
    ++checked;
  }
  EXPECT_LT(worst, kEndpointTol_mm);
  EXPECT_GT(checked, 300);
}

TEST(DexelStock, MeshStockMatchesTheAnalyticBox) {
  const Eigen::Vector3d lo(0.03, 0.07, -9.96), hi(20.01, 10.02, 0.04);
  DexelStock analytic(BoxShape{lo, hi}, 0.1);
  DexelStock meshed(test::box_mesh(lo, hi), 0.1);
  for (int axis = 0; axis < 3; ++axis)
    for (int iw = -2; iw < 110; iw += 3)
      for (int iu = -2; iu < 210; iu += 5) {
        const auto a = analytic.ray(axis, iu, iw), b = meshed.ray(axis, iu, iw);
        ASSERT_EQ(a.size(), b.size()) << axis << " " << iu << " " << iw;
        for (std::size_t s = 0; s < a.size(); ++s) {
          EXPECT_NEAR(a[s].lo_mm, b[s].lo_mm, 1e-5);
          EXPECT_NEAR(a[s].hi_mm, b[s].hi_mm, 1e-5);
        }
      }
  EXPECT_NEAR(meshed.volume_mm3(), analytic.volume_mm3(), 1e-6 * analytic.volume_mm3());
}

TEST(DexelStock, OpenMeshStockIsRefused) {
  TriangleMesh open = test::box_mesh({0, 0, 0}, {10, 10, 10});
  open.triangles.pop_back();
  EXPECT_THROW(DexelStock(open, 0.1), std::invalid_argument);
}

TEST(DexelStock, CylinderStockVolume) {
  const CylinderShape c{{5, 5, -10}, {0, 0, 1}, 20.0, 10.0};
  DexelStock stock(c, 0.1);
  const double exact = M_PI * 20 * 20 * 10;
  EXPECT_NEAR(stock.volume_mm3(), exact, exact * 2e-3);
}

// One thread, two, and an arena of seven (the cut bins a batch's moves in as many chunks as
// its arena has slots: 1,200 moves make 7 chunks there, one on one thread): a ball's zig-zag
// (whose slivers and ties show a tile's moves taken out of program order) and a bull-nose's.
TEST(DexelStock, SameRaysForOneTwoAndSevenThreads) {
  auto run = [](const MoveList& list, int threads) {
    std::optional<DexelStock> stock;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
      stock.emplace(BoxShape{{0, 0, -10}, {30, 20, 0}}, 0.1);
      stock->cut(list, {});
    });
    return std::make_pair(stock->endpoints(), stock->surface());
  };
  auto zigzag = [](const Cutter& cutter, int moves) {
    MoveList list;
    list.cutters.push_back(cutter);
    Eigen::Vector3d p(-5, 2, -1);
    for (int i = 0; i < moves; ++i) {
      const double f = 300.0 / moves;
      const Eigen::Vector3d q(2 + 0.09 * f * i, 2 + 16 * (i % 2), -1.0 - 0.01 * f * i);
      list.moves.push_back(line(p, q));
      p = q;
    }
    return list;
  };
  for (const MoveList& list :
       {zigzag(make(CutterType::Ball, 6, 3), 1200), zigzag(make(CutterType::BullNose, 6, 1), 300)}) {
    const auto [e1, s1] = run(list, 1);
    for (int threads : {2, 7}) {
      const auto [e2, s2] = run(list, threads);
      ASSERT_EQ(e1.size(), e2.size()) << threads;
      for (std::size_t i = 0; i < e1.size(); ++i) {
        ASSERT_EQ(std::memcmp(e1[i].x_mm.data(), e2[i].x_mm.data(), 3 * sizeof(double)), 0) << threads;
        ASSERT_EQ(e1[i].move, e2[i].move) << threads;
      }
      ASSERT_EQ(s1.mesh.vertices_mm.size(), s2.mesh.vertices_mm.size());
      EXPECT_EQ(std::memcmp(s1.mesh.vertices_mm.data(), s2.mesh.vertices_mm.data(),
                            s1.mesh.vertices_mm.size() * sizeof(Eigen::Vector3d)),
                0);
      EXPECT_EQ(s1.vertex_move, s2.vertex_move);
    }
  }
}

// Cuts `chain` in one call and one move per call into two stocks of `box` at 0.1 mm and
// expects the same material on every ray (within 1 um; `exact`: the same floats and the same
// move on every endpoint); returns the rays holding material and the volume left.
std::pair<std::size_t, double> expect_chain_cuts_as_one_by_one(const MoveList& chain, const BoxShape& box,
                                                               bool exact = false) {
  DexelStock together(box, 0.1), alone(box, 0.1);
  together.cut(chain, {});
  for (const Move& m : chain.moves) {
    MoveList one;
    one.cutters = chain.cutters;
    one.moves.push_back(m);
    alone.cut(one, {});
  }
  EXPECT_NEAR(together.volume_mm3(), alone.volume_mm3(), 1e-6);
  std::size_t rays = 0;
  for (int family = 0; family < 3; ++family) {
    for (int iu = -2; iu < 210; ++iu) {
      for (int iw = -2; iw < 210; ++iw) {
        const auto a = together.ray(family, iu, iw), b = alone.ray(family, iu, iw);
        EXPECT_EQ(a.size(), b.size()) << "family " << family << " ray " << iu << ", " << iw;
        if (a.size() != b.size()) return {rays, together.volume_mm3()};
        for (std::size_t k = 0; k < a.size(); ++k) {
          if (exact) {
            const bool same = a[k].lo_mm == b[k].lo_mm && a[k].hi_mm == b[k].hi_mm && a[k].lo_move == b[k].lo_move &&
                              a[k].hi_move == b[k].hi_move;
            EXPECT_TRUE(same) << "family " << family << " ray " << iu << ", " << iw;
            if (!same) return {rays, together.volume_mm3()};
            continue;
          }
          EXPECT_NEAR(a[k].lo_mm, b[k].lo_mm, kEndpointTol_mm) << "family " << family << " ray " << iu << ", " << iw;
          EXPECT_NEAR(a[k].hi_mm, b[k].hi_mm, kEndpointTol_mm) << "family " << family << " ray " << iu << ", " << iw;
        }
        rays += !a.empty();
      }
    }
  }
  return {rays, together.volume_mm3()};
}

// A chain of moves cut in one call (each ray left to whichever neighbour's instance covers
// it) against the same moves cut one call each (no move can rely on another): the same
// material on every ray. The chain climbs, descends, turns back on itself, turns corners
// and runs diagonally; a ball end with an upright and a tilted axis (any motion hands
// over), a flat end mill and a V-bit on level rows (motion square to the axis hands over
// for any cutter; the V-bit's ramps between do not), flat and bull-nose end mills upright
// and tilted on rows that climb and descend (their cores' bound on h); a shank probe between
// moves (it removes nothing and must not break the chain).
TEST(DexelStock, ChainedMovesCutWhatTheyCutOneByOne) {
  struct Case {
    Cutter cutter;
    Eigen::Vector3d axis;
    bool level_rows;
  };
  Cutter vbit = make(CutterType::VBit, 3, 0, 12);
  vbit.tip_angle_deg = 90;
  const Case cases[] = {{make(CutterType::Ball, 3, 1.5, 12), Eigen::Vector3d(0, 0, 1), false},
                        {make(CutterType::Ball, 3, 1.5, 12), Eigen::Vector3d(0.3, -0.2, 1).normalized(), false},
                        {make(CutterType::Flat, 3, 0, 12), Eigen::Vector3d(0, 0, 1), true},
                        {vbit, Eigen::Vector3d(0, 0, 1), true},
                        {make(CutterType::Flat, 3, 0, 12), Eigen::Vector3d(0, 0, 1), false},
                        {make(CutterType::BullNose, 3, 0.75, 12), Eigen::Vector3d(0, 0, 1), false},
                        {make(CutterType::Flat, 3, 0, 12), Eigen::Vector3d(-0.2, 0.3, 1).normalized(), false},
                        {make(CutterType::BullNose, 3, 0.75, 12), Eigen::Vector3d(0.3, -0.2, 1).normalized(), false}};
  for (const Case& c : cases) {
    const Eigen::Vector3d& axis = c.axis;
    MoveList chain;
    chain.cutters.push_back(c.cutter);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> step(-0.6, 0.6), dip(-0.25, 0.2);
    Eigen::Vector3d p(3, 3, 9);
    for (int i = 0; i < 240; ++i) {
      Eigen::Vector3d q;
      if (i % 40 < 20)
        q = p + Eigen::Vector3d((i / 40) % 2 ? -0.5 : 0.5, 0, c.level_rows ? 0.0 : dip(rng));  // rows
      else if (i % 40 < 23)
        q = p + Eigen::Vector3d(0, 0.35, 0);  // stepover
      else
        q = p + Eigen::Vector3d(step(rng), step(rng), dip(rng));  // wandering
      q.z() = std::clamp(q.z(), 6.0, 11.0);
      q.x() = std::clamp(q.x(), 1.0, 19.0);
      q.y() = std::clamp(q.y(), 1.0, 14.0);
      chain.moves.push_back(line(p, q, axis));
      if (i == 100) {
        Move probe = line(q, q, axis);
        probe.rapid = true;
        probe.probe = ProbeKind::Shank;
        chain.moves.push_back(probe);
      }
      p = q;
    }
    const auto [rays, volume_mm3] = expect_chain_cuts_as_one_by_one(chain, {{0, 0, 0}, {20, 15, 10}});
    EXPECT_GT(rays, 40000u);
    EXPECT_LT(volume_mm3, 3000.0 - 100.0);  // the chain did cut (the V-bit least)
  }
}

// Turning moves' consecutive pieces over the same tile (a move's and the next's) are cut row
// by row together (removal/dexel_cut.cpp, cut_pieces): the rays with material in a window
// around all the pieces first where the pieces cover much the same rays, each piece its own
// rays where they lie apart. Either way every ray must meet the pieces in program order, each seeing what the
// ones before left, as when each piece is cut in a call of its own (then no run forms): the
// same intervals to the bit, and the same move on every endpoint. Tilted ball, bull-nose,
// flat and V-bit tools turning by up to 9 deg a move, on short moves (pieces over the same
// rays) and long ones (pieces apart), a tight bound (more pieces than a run takes), and a
// shank probe between two moves' pieces (it ends a run).
TEST(DexelStock, TurningPiecesCutTogetherAsOneByOne) {
  Cutter vbit = make(CutterType::VBit, 4, 0, 10);
  vbit.tip_angle_deg = 90;
  const Cutter cutters[] = {make(CutterType::Ball, 3, 1.5, 8), make(CutterType::BullNose, 4, 0.8, 8),
                            make(CutterType::Flat, 3, 0, 8), vbit};
  int variant = 0;
  for (const Cutter& cutter : cutters) {
    for (const double step_mm : {0.3, 3.0}) {
      // Under the sanitizers every cutter at one of the two steps, in turn (sanitized.h).
      const int k = variant++;
      if (test::sanitized() && (k / 2 + k % 2) % 2 != 0) continue;
      MoveList pieces;
      pieces.cutters.push_back(cutter);
      std::mt19937 rng(5);
      std::uniform_real_distribution<double> turn(-0.05, 0.05), wander(-step_mm, step_mm), dip(-0.3, 0.3);
      Eigen::Vector3d p(3, 3, 7), axis = Eigen::Vector3d(0.3, 0.25, 1).normalized();
      for (int i = 0; i < 40; ++i) {
        Eigen::Vector3d q = p + Eigen::Vector3d(i % 15 < 12 ? step_mm * ((i / 15) % 2 ? -1 : 1) : wander(rng),
                                                i % 15 < 12 ? 0.05 : 0.4, dip(rng));
        q = q.cwiseMax(Eigen::Vector3d(1, 1, 4)).cwiseMin(Eigen::Vector3d(19, 14, 9));
        Eigen::Vector3d next = (axis + Eigen::Vector3d(turn(rng), turn(rng), 0)).normalized();
        if (next.z() < 0.8) next = Eigen::Vector3d(0.3, 0.25, 1).normalized();
        Move m = line(p, q, next);
        m.block = i;
        const TurningSplit split = five_axis_split(cutter, 8.0, axis, next, i % 7 == 0 ? 0.001 : 0.01);
        append_five_axis_move(pieces.moves, m, axis, next, split);
        if (i == 20) {
          Move probe = line(q, q, next);
          probe.rapid = true;
          probe.probe = ProbeKind::Shank;
          probe.block = i;
          pieces.moves.push_back(probe);
        }
        p = q;
        axis = next;
      }
      ASSERT_GT(pieces.moves.size(), 200u);
      SCOPED_TRACE(testing::Message() << "cutter " << static_cast<int>(cutter.type) << ", steps of " << step_mm);
      const auto [rays, volume_mm3] = expect_chain_cuts_as_one_by_one(pieces, {{0, 0, 0}, {20, 15, 10}}, true);
      EXPECT_GT(rays, 40000u);
      EXPECT_LT(volume_mm3, 3000.0 - 50.0);  // the pieces did cut
    }
  }
}

// A long ball, flat and bull-nose end mill turning deep in the 40 x 30 x 20 box (v = 0.25),
// cut part by part (cutter_parts, part_split, append_part_pieces), each part's pieces passing
// over the rays that hold no material in the sweep of their slab (Move::slab_low_mm,
// slab_high_mm: the tilted window's heights). Every ray keeps at least the material the same
// pieces without slabs leave (so nothing more is taken), and nothing is left inside any
// piece's sweep within its slab's sweep (at every remaining segment's middle and just inside
// its ends: a ray the window passed over wrongly keeps such material).
void expect_parts_cut_within_their_slabs(const Cutter& cutter) {
  SCOPED_TRACE(to_string(cutter.type));
  const std::vector<CutterPart> parts = cutter_parts(cutter);
  const BoxShape box{{0, 0, -20}, {40, 30, 0}};
  const Eigen::AlignedBox3d material(box.min_mm, box.max_mm);
  MoveList list;
  for (const CutterPart& part : parts) list.cutters.push_back(part.cutter);
  // Three turning moves 14 mm deep, the axis tilting 10-30 deg and swinging about z, and a
  // turn on the spot.
  const Eigen::Vector3d tips[] = {{8, 10, -14}, {20, 12, -13}, {30, 18, -15}, {30, 18, -15}};
  const Eigen::Vector3d axes[] = {
      Eigen::Vector3d(0.2, 0.1, 1).normalized(), Eigen::Vector3d(-0.3, 0.35, 1).normalized(),
      Eigen::Vector3d(0.5, -0.2, 1).normalized(), Eigen::Vector3d(0.1, 0.5, 1).normalized()};
  int highest_parts = 0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d &a0 = axes[i], &a1 = axes[i + 1];
    const double height = highest_point_in_box_mm(cutter.radius_mm(), tips[i], tips[i + 1], a0, a1,
                                                  box_for_pieces(cutter, a0, a1, material));
    std::size_t highest;
    const std::vector<TurningSplit> splits = part_splits(parts, height, a0, a1, 0.01, highest);
    highest_parts += static_cast<int>(highest);
    for (std::size_t j = 0; j < parts.size(); ++j)
      append_part_pieces(list.moves, line(tips[i], tips[i + 1]), a0, a1, parts[j], static_cast<int>(j), splits[j],
                         j == highest);
  }
  ASSERT_GE(highest_parts, 9);  // three slab boundaries or more inside the stock a move, on average
  MoveList whole = list;
  for (Move& m : whole.moves) {
    m.slab_low_mm = -std::numeric_limits<double>::infinity();
    m.slab_high_mm = std::numeric_limits<double>::infinity();
  }
  DexelStock stock(box, 0.25), reference(box, 0.25);
  stock.cut(list, {});
  reference.cut(whole, {});
  std::vector<TranslationSweep> sweeps;
  for (const Move& m : list.moves) sweeps.emplace_back(list.cutters[static_cast<std::size_t>(m.cutter)], m);
  // The least over the pieces of the larger of the sweep's distance and the slab's sweep's
  // (along the axis), at x.
  auto within_slabs = [&](const Eigen::Vector3d& x) {
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < sweeps.size(); ++i) {
      const Move& m = list.moves[i];
      if (sweeps[i].bounds().exteriorDistance(x) >= least) continue;
      const double slab = test::slab_distance(m, x);
      if (slab < least) least = std::min(least, std::max(sweeps[i].distance(x), slab));
    }
    return least;
  };
  const double v = 0.25;
  const int index_lo[3] = {0, 0, -80}, index_hi[3] = {160, 120, 0};
  // Every ray; every third row and column of them under the sanitizers (sanitized.h).
  const int stride = test::sanitized() ? 3 : 1;
  double deepest = 0.0;
  int checked = 0, kept_more = 0;
  for (int family = 0; family < 3; ++family) {
    const int a1 = family == 0 ? 1 : 0, a2 = family == 2 ? 1 : 2;
    for (int iu = index_lo[a1]; iu < index_hi[a1]; iu += stride)
      for (int iw = index_lo[a2]; iw < index_hi[a2]; iw += stride) {
        const std::vector<DexelSegment> ray = stock.ray(family, iu, iw), less = reference.ray(family, iu, iw);
        for (const DexelSegment& seg : less) {
          // Within the root march's tolerance: a bull-nose piece's march starts at the
          // window's end, which the slab moves.
          const bool held = std::any_of(ray.begin(), ray.end(), [&](const DexelSegment& mine) {
            return mine.lo_mm <= seg.lo_mm + kEndpointTol_mm && mine.hi_mm >= seg.hi_mm - kEndpointTol_mm;
          });
          if (!held) {
            std::string mine;
            for (const DexelSegment& m : ray)
              mine += " [" + std::to_string(m.lo_mm) + ", " + std::to_string(m.hi_mm) + "]";
            ADD_FAILURE() << "family " << family << " ray " << iu << ", " << iw << ": [" << seg.lo_mm << ", "
                          << seg.hi_mm << "] not kept; kept:" << mine;
          }
        }
        kept_more += ray.size() != less.size() || !std::equal(ray.begin(), ray.end(), less.begin(),
                                                              [](const DexelSegment& p, const DexelSegment& q) {
                                                                return p.lo_mm == q.lo_mm && p.hi_mm == q.hi_mm;
                                                              });
        for (const DexelSegment& seg : ray) {
          const double in = std::min(0.01, 0.5 * (static_cast<double>(seg.hi_mm) - seg.lo_mm));
          for (const double s : {seg.lo_mm + in, 0.5 * (static_cast<double>(seg.lo_mm) + seg.hi_mm), seg.hi_mm - in}) {
            Eigen::Vector3d x;
            x[family] = s;
            x[a1] = (iu + 0.5) * v;
            x[a2] = (iw + 0.5) * v;
            deepest = std::min(deepest, within_slabs(x) + kEndpointTol_mm);
            ++checked;
          }
        }
      }
  }
  EXPECT_EQ(deepest, 0.0);
  EXPECT_GT(checked, 100000 / (stride * stride));
  // The slabs did pass over some material the whole pieces take (the ball's; a flat end
  // mill's parts leave the same rays).
  if (cutter.type == CutterType::Ball) {
    EXPECT_GT(kept_more, 0);
  }
}

TEST(DexelStock, TurningLongCuttersCutPartByPartWithinTheirSlabs) {
  expect_parts_cut_within_their_slabs(make(CutterType::Ball, 6, 3, 25));
  expect_parts_cut_within_their_slabs(make(CutterType::Flat, 6, 0, 25));
  expect_parts_cut_within_their_slabs(make(CutterType::BullNose, 8, 1, 25));
}

// 300 moves of one cutter at a fixed axis sunk deep into the 20 x 15 x 10 block: rows along x
// that climb and descend by up to dip_mm a move and turn back, stepovers, and stretches that
// wander (random draws from `seed`, in a fixed order).
MoveList deep_raster(const Cutter& cutter, const Eigen::Vector3d& axis, unsigned seed, double dip_mm) {
  MoveList chain;
  chain.cutters.push_back(cutter);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> step(-0.6, 0.6), dip(-dip_mm, dip_mm);
  Eigen::Vector3d p(3, 3, 6);
  for (int i = 0; i < 300; ++i) {
    Eigen::Vector3d q;
    if (i % 50 < 30)
      q = p + Eigen::Vector3d((i / 50) % 2 ? -0.45 : 0.45, 0.02, dip(rng));  // rows
    else if (i % 50 < 33)
      q = p + Eigen::Vector3d(0, 0.4, 0);  // stepover
    else
      q = p + Eigen::Vector3d(step(rng), step(rng), dip(rng));  // wandering
    q.z() = std::clamp(q.z(), 3.0, 8.5);
    q.x() = std::clamp(q.x(), 1.0, 19.0);
    q.y() = std::clamp(q.y(), 1.0, 14.0);
    chain.moves.push_back(line(p, q, axis));
    p = q;
  }
  return chain;
}

// A tilted ball end mill at a fixed axis (3+2) hands rays over row by row: each row's rays
// that the move before surely cut (its end instance is this move's start) and those the next
// move surely cuts and will not pass over are skipped before their material is looked at
// (the spans of removal/dexel_cut.cpp's covered_spans and uncovered_spans). The same chain cut
// in one call and one move per call leaves the same material on every ray. A short ball (its
// core 0.5 mm long) sunk deep into a tall block: its top cap cuts too, where the hand-over's
// height clamp matters; rows that climb and descend (the motion along the axis of both
// signs), turn back and wander, at two tilts.
TEST(DexelStock, TiltedBallRasterHandsOverRowByRow) {
  for (const Eigen::Vector3d& tilt : {Eigen::Vector3d(0.35, 0.2, 1), Eigen::Vector3d(-0.1, 0.6, 1)}) {
    const MoveList chain = deep_raster(make(CutterType::Ball, 3, 1.5, 3.5), tilt.normalized(), 11, 0.4);
    const auto [rays, volume_mm3] = expect_chain_cuts_as_one_by_one(chain, {{0, 0, 0}, {20, 15, 10}});
    EXPECT_GT(rays, 40000u);
    EXPECT_LT(volume_mm3, 3000.0 - 150.0);  // the chain cut deep
  }
}

// Flat and bull-nose end mills moving along their axis hand rays over by h's bound for their
// core (removal/dexel_cut.cpp, Handover): h <= 0 and no point below the core's bottom while
// the tool goes down, none above its top while it goes up. Short tools (flutes 3.5 mm) sunk
// deep into a tall block, so that both ends of the core pass through material, on rows that
// climb and descend steeply, turn back and wander, upright (row by row) and at two tilts
// (row by row and ray by ray): the chain cut in one call leaves what it leaves cut one move
// per call.
TEST(DexelStock, FlatAndBullNoseRampsHandOverByTheirCore) {
  const Cutter cutters[] = {make(CutterType::Flat, 3, 0, 3.5), make(CutterType::BullNose, 3, 0.6, 3.5)};
  const Eigen::Vector3d axes[] = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.35, 0.2, 1).normalized(),
                                  Eigen::Vector3d(-0.1, 0.6, 1).normalized()};
  for (const Cutter& cutter : cutters) {
    for (const Eigen::Vector3d& axis : axes) {
      const auto [rays, volume_mm3] =
          expect_chain_cuts_as_one_by_one(deep_raster(cutter, axis, 13, 0.5), {{0, 0, 0}, {20, 15, 10}});
      EXPECT_GT(rays, 40000u);
      EXPECT_LT(volume_mm3, 3000.0 - 150.0);  // the chain cut deep
    }
  }
}

// The hand-over tests' storage is kept from batch to batch (4,096 moves): a move that takes
// no hand-over must not see the one the move at its place in the batch before took. A chain
// of 4,096 tilted ball moves (each handing over to the next) over one end of the stock, then
// 300 tilted V-bit moves descending over the other end (not square to their axis: no
// hand-over) leave the same rays, bit for bit, cut in one call as in two (where the second
// call's hand-overs start afresh).
TEST(DexelStock, AMoveWithoutHandOverSeesNoneFromTheBatchBefore) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, 0.2, 1).normalized();
  MoveList balls, bulls;
  Cutter vbit = make(CutterType::VBit, 4, 0, 5);
  vbit.tip_angle_deg = 90;
  balls.cutters = {make(CutterType::Ball, 3, 1.5, 3.5), vbit};
  bulls.cutters = balls.cutters;
  Eigen::Vector3d p(1, 1, 9);
  for (int i = 0; i < 4096; ++i) {
    const int k = i % 128;
    const Eigen::Vector3d q(1 + 0.05 * ((i / 128) % 2 ? 128 - k : k), 1 + 13.0 * i / 4096, 9);
    balls.moves.push_back(line(p, q, axis));
    p = q;
  }
  p = {11, 1, 9.5};
  for (int i = 0; i < 300; ++i) {
    const int k = i % 40;
    const Eigen::Vector3d q(11 + 0.2 * ((i / 40) % 2 ? 40 - k : k), 1 + 0.04 * i, 9.5 - 0.01 * i);
    Move m = line(p, q, axis);
    m.cutter = 1;
    bulls.moves.push_back(m);
    p = q;
  }
  const BoxShape box{{0, 0, 0}, {20, 15, 10}};
  DexelStock in_one(box, 0.1), in_two(box, 0.1);
  MoveList both = balls;
  both.moves.insert(both.moves.end(), bulls.moves.begin(), bulls.moves.end());
  in_one.cut(both, {});
  in_two.cut(balls, {});
  in_two.cut(bulls, {});
  const std::vector<DexelEndpoint> a = in_one.endpoints(), b = in_two.endpoints();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(std::memcmp(a[i].x_mm.data(), b[i].x_mm.data(), 3 * sizeof(double)), 0) << i;
    ASSERT_EQ(a[i].move, b[i].move) << i;
  }
  // Both chains cut: endpoints of the last ball move and of the last V-bit move.
  EXPECT_TRUE(std::any_of(a.begin(), a.end(), [](const DexelEndpoint& e) { return e.move == 4095; }));
  EXPECT_TRUE(std::any_of(a.begin(), a.end(), [](const DexelEndpoint& e) { return e.move == 4395; }));
}

// The stock pulls moves a batch at a time (4,096), each batch looking at the cutting moves
// on either side of it for its hand-over tests. Where the batches fall must not change the
// cut: a raster of 9,000 moves cut as it is, behind 1, 1,000 or 4,095 rapids far from the
// stock (moving every batch boundary), and handed over three moves at a time, leaves the
// same rays bit for bit, each endpoint's move id shifted by the rapids in front.
TEST(DexelStock, BatchBoundariesDoNotChangeTheCut) {
  MoveList raster;
  raster.cutters.push_back(make(CutterType::Ball, 3, 1.5, 12));
  Eigen::Vector3d p(1, 1, 8.5);
  for (int row = 0; row < 24; ++row)
    for (int i = 0; i < 375; ++i) {
      const Eigen::Vector3d q(row % 2 ? 19.75 - 0.05 * (i + 1) : 1 + 0.05 * (i + 1), 1 + 0.55 * row + 0.0015 * i,
                              8.5 - 0.002 * i);
      raster.moves.push_back(line(p, q));
      p = q;
    }
  const BoxShape box{{0, 0, 0}, {20, 15, 10}};
  DexelStock reference(box, 0.1);
  reference.cut(raster, {});
  const std::vector<DexelEndpoint> expected = reference.endpoints();
  auto same_rays = [&](const DexelStock& stock, int shift) {
    const std::vector<DexelEndpoint> got = stock.endpoints();
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(std::memcmp(got[i].x_mm.data(), expected[i].x_mm.data(), 3 * sizeof(double)), 0) << i;
      ASSERT_EQ(got[i].move, expected[i].move < 0 ? -1 : expected[i].move + shift) << i;
    }
  };
  for (int rapids : {1, 1000, 4095}) {
    MoveList shifted;
    shifted.cutters = raster.cutters;
    for (int i = 0; i < rapids; ++i) {
      Move away = line({100, 100, 50}, {101, 100, 50});
      away.rapid = true;
      shifted.moves.push_back(away);
    }
    shifted.moves.insert(shifted.moves.end(), raster.moves.begin(), raster.moves.end());
    DexelStock stock(box, 0.1);
    const CutResult r = stock.cut(shifted, {});
    EXPECT_TRUE(r.collisions.empty());
    same_rays(stock, rapids);
  }
  // A source that hands over three moves at a time.
  class Trickle : public MoveSource {
   public:
    explicit Trickle(const MoveList& list) : list_(list) {}
    const std::vector<Cutter>& cutters() const override { return list_.cutters; }
    bool next(std::vector<Move>& out, std::size_t) override {
      const std::size_t n = std::min<std::size_t>(3, list_.moves.size() - at_);
      out.insert(out.end(), list_.moves.begin() + static_cast<std::ptrdiff_t>(at_),
                 list_.moves.begin() + static_cast<std::ptrdiff_t>(at_ + n));
      at_ += n;
      return n > 0;
    }

   private:
    const MoveList& list_;
    std::size_t at_ = 0;
  } trickle(raster);
  DexelStock stock(box, 0.1);
  stock.cut(trickle, {});
  same_rays(stock, 0);
}

// The stock keeps the geometry of the moves its ray endpoints name (the mesher projects onto
// them), not of every move: a 3 mm ball's groove cut in 400,000 moves of 0.045 um leaves at
// most 2 endpoints on each of the stock's ~2,400 rays (v = 0.5 mm), so at most ~4,800 moves
// are named. The record is pruned whenever it has doubled and grown by 65,536 moves: at most
// 2 x 4,800 + 65,536 moves (92 bytes each) are held, twice that with vector growth: under
// 14 MB. Holding every move would take 400,000 x 92 bytes = 36.8 MB.
TEST(DexelStock, MoveRecordGrowsWithTheSurfaceNotTheProgram) {
  const BoxShape box{{0, 0, 0}, {20, 10, 10}};
  DexelStock stock(box, 0.5);
  const std::size_t before = stock.memory_bytes();
  MoveList list;
  list.cutters.push_back(make(CutterType::Ball, 3, 1.5, 12));
  const int n = 400000;
  Eigen::Vector3d p(1, 5, 9);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d q = p + Eigen::Vector3d(18.0 / n, 0, 0);
    list.moves.push_back(line(p, q));
    p = q;
  }
  const CutResult cut = stock.cut(list, {});
  const std::size_t grown = stock.memory_bytes() - before;
  EXPECT_LT(grown, std::size_t{14} << 20);
  // The cut happened: the ball (centre 0.5 mm above the top) leaves a groove whose section is
  // the circular segment of height h = 1, r^2 acos((r - h) / r) - (r - h) sqrt(2 r h - h^2) =
  // 2.0626 mm2 for r = 1.5, over 18 mm, plus the spherical cap pi h^2 (3 r - h) / 3 = 3.665
  // mm3 at the two ends together: 40.79 mm3, within 15 % at v = 0.5 mm.
  EXPECT_NEAR(cut.removed_volume_mm3, 40.79, 0.15 * 40.79);
  // The moves kept are those the surface needs: the groove's vertices, projected onto the
  // moves their cells name, lie on its wall, the cylinder of radius 1.5 about y = 5, z = 10.5,
  // or within the sagitta 0.5^2 / (8 x 1.5) = 0.021 mm inside it where the mesher leaves a
  // vertex at its crossings' mean (one row of them here); one projected onto another move
  // than the one its cell names (pruned away) lies elsewhere.
  const SurfaceMesh surface = stock.surface();
  int on_wall = 0;
  for (const Eigen::Vector3d& q : surface.mesh.vertices_mm) {
    // Not the top face, the box's other faces, the groove's ends.
    if (q.z() > 10.0 - 1e-6 || q.z() < 8.5 || std::abs(q.y() - 5.0) > 2.0 || q.x() < 2.0 || q.x() > 17.0) continue;
    EXPECT_NEAR(std::hypot(q.y() - 5.0, q.z() - 10.5), 1.5, 0.025) << q.transpose();
    ++on_wall;
  }
  EXPECT_GT(on_wall, 100);
}

// Whether the mesh is closed and consistently wound (every directed edge meets its reverse
// exactly once), and then the volume it encloses (mm3).
::testing::AssertionResult closed_volume(const TriangleMesh& mesh, double& volume) {
  std::map<std::pair<int, int>, int> edges;
  volume = 0.0;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
    const Eigen::Vector3d &a = mesh.vertices_mm[static_cast<std::size_t>(t[0])],
                          &b = mesh.vertices_mm[static_cast<std::size_t>(t[1])],
                          &c = mesh.vertices_mm[static_cast<std::size_t>(t[2])];
    volume += a.dot(b.cross(c)) / 6.0;
  }
  for (const auto& [e, n] : edges) {
    if (n != 1)
      return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second << " used twice the same way";
    if (edges.count({e.second, e.first}) == 0)
      return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second << " has no partner";
  }
  return ::testing::AssertionSuccess();
}

// The surface from dual contouring: closed and consistently wound (every directed edge
// meets its reverse exactly once), enclosing the analytic volume, its vertices on the exact
// surface; the untouched faces merged in both modes, the curved groove only with flat
// merging.
TEST(DexelStock, ContouredSurfaceIsClosedAndEnclosesTheSolid) {
  const BoxShape box{{0, 0, 0}, {20, 10, 10}};
  MoveList list;
  list.cutters.push_back(make(CutterType::Ball, 4, 2, 12));
  // A 4 mm ball groove across the block, its centre on the top face: a half-disc of radius
  // 2 removed along 20 mm.
  list.moves.push_back(line({-5, 3, 8}, {25, 3, 8}));
  const double groove_mm3 = 0.5 * M_PI * 4.0 * 20.0;
  std::array<std::size_t, 2> triangles{};
  for (bool merge : {true, false}) {
    DexelStock stock(box, 0.1);
    stock.set_flat_merging(merge);
    stock.cut(list, {});
    const SurfaceMesh s = stock.surface();
    triangles[merge ? 0 : 1] = s.mesh.triangles.size();
    double volume = 0.0;
    ASSERT_TRUE(closed_volume(s.mesh, volume));
    // Chords across the groove's curve lie inside the solid by up to v^2 / (8 r) over its
    // 2 pi * 20 mm2: at most 0.04 mm3; creases at the groove's rims cut within a cell.
    EXPECT_NEAR(volume, 2000.0 - groove_mm3, 0.3) << (merge ? "merged" : "full");
    for (const Eigen::Vector3d& x : s.mesh.vertices_mm) {
      const double groove = segment_distance(x, {-5, 3, 10}, {25, 3, 10}) - 2.0;
      const double solid = std::max(-groove, std::max((box.min_mm - x).maxCoeff(), (x - box.max_mm).maxCoeff()));
      ASSERT_LT(std::abs(solid), 0.1 * 0.1 + 1e-9) << x.transpose();  // v/10
    }
  }
  // Unmerged, the surface (about 1,046 mm2: the box's 1,000 less the groove's 80 mm2 mouth
  // plus its 126 mm2 half-cylinder) would be 104,600 cells at 0.1 mm, two triangles each.
  // Both modes merge the five untouched faces (exact axis planes, 920 mm2) into blocks of
  // up to 16 cells; flat merging also the groove, within v/25 of a plane over a few cells.
  EXPECT_LT(triangles[1], 52300u);
  EXPECT_LT(triangles[0], triangles[1]) << triangles[0] << " vs " << triangles[1];
}

// A hole's wall (a flat end mill D8 plunged 6 mm along an axis 20 deg from z, D32's kind) at
// v = 0.05 mm: between 1 and 5 mm deep its 100 mm2 of cylinder cross about 50,000 cells;
// blocks of 4 cells a side stay within the merging tolerance of a plane on a 4 mm radius, so
// the wall there keeps under 7,000 vertices (4,849), each within v/5 of the wall. (When a
// block of one cell ended the merging of the blocks around it: 9,452.)
TEST(DexelStock, CurvedWallMergesIntoBlocks) {
  const BoxShape box{{0, 0, 0}, {16, 12, 10}};
  const double tilt = 20.0 * M_PI / 180.0;
  const Eigen::Vector3d axis(std::sin(tilt), 0.0, std::cos(tilt));
  const Eigen::Vector3d entry(8, 6, 10), bottom = entry - 6.0 * axis;
  MoveList list;
  list.cutters.push_back(make(CutterType::Flat, 8, 0, 20));
  list.moves.push_back(line(entry + 10.0 * axis, bottom, axis));
  DexelStock stock(box, 0.05);
  stock.cut(list, {});
  const SurfaceMesh s = stock.surface();
  auto radial = [&](const Eigen::Vector3d& x) { return (x - bottom - (x - bottom).dot(axis) * axis).norm(); };
  auto wall = [&](const Eigen::Vector3d& x) {
    const double depth = (entry - x).dot(axis);
    return depth >= 1.0 && depth <= 5.0 && x.z() <= 9.5 && std::abs(radial(x) - 4.0) <= 0.3;
  };
  int on_wall = 0;
  for (const Eigen::Vector3d& x : s.mesh.vertices_mm) {
    if (!wall(x)) continue;
    EXPECT_LT(std::abs(radial(x) - 4.0), 0.01) << x.transpose();
    ++on_wall;
  }
  EXPECT_GT(on_wall, 1000);
  EXPECT_LT(on_wall, 7000) << "vertices on the wall";
  // And the triangles between them: their centres within v/10 (the chord of a merged block,
  // about 0.2 mm on a 4 mm radius, lies 0.0013 mm inside).
  for (const Eigen::Vector3i& t : s.mesh.triangles) {
    const Eigen::Vector3d& a = s.mesh.vertices_mm[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = s.mesh.vertices_mm[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = s.mesh.vertices_mm[static_cast<std::size_t>(t[2])];
    if (wall(a) && wall(b) && wall(c)) {
      EXPECT_LT(std::abs(radial((a + b + c) / 3.0) - 4.0), 0.005);
    }
  }
}

// An untouched box whose far faces (x, y and z high) lie in the mesher's last bricks, fewer
// than 16 cells deep: every vertex on the box's surface, every triangle lying on a face
// facing out of the solid, and each face's triangles covering no more than the face.
TEST(DexelStock, UntouchedFacesInPartialBricksFaceOutward) {
  const BoxShape box{{0, 0, 0}, {10.37, 7.61, 3.13}};  // no side a multiple of 16 cells at 0.1 mm
  DexelStock stock(box, 0.1);
  const SurfaceMesh s = stock.surface();
  for (const Eigen::Vector3d& x : s.mesh.vertices_mm) {
    const double solid = std::max((box.min_mm - x).maxCoeff(), (x - box.max_mm).maxCoeff());
    ASSERT_LT(std::abs(solid), 1e-6) << "a vertex off the box's surface: " << x.transpose();
  }
  std::array<double, 6> area{};  // per face: -x, +x, -y, +y, -z, +z
  std::size_t on_faces = 0;
  for (const auto& t : s.mesh.triangles) {
    const Eigen::Vector3d &a = s.mesh.vertices_mm[static_cast<std::size_t>(t[0])],
                          &b = s.mesh.vertices_mm[static_cast<std::size_t>(t[1])],
                          &c = s.mesh.vertices_mm[static_cast<std::size_t>(t[2])];
    const Eigen::Vector3d n = (b - a).cross(c - a);  // twice the area, along the outward normal
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        const double plane = side == 0 ? box.min_mm[axis] : box.max_mm[axis];
        if (std::abs(a[axis] - plane) > 1e-9 || std::abs(b[axis] - plane) > 1e-9 || std::abs(c[axis] - plane) > 1e-9)
          continue;
        ++on_faces;
        const double outward = side == 0 ? -n[axis] : n[axis];
        ASSERT_GT(outward, 0.0) << "a triangle on face " << 2 * axis + side << " faces inward: " << a.transpose()
                                << " / " << b.transpose() << " / " << c.transpose();
        area[static_cast<std::size_t>(2 * axis + side)] += 0.5 * outward;
      }
    }
  }
  // Most of the surface lies on the faces (the rest: the strips along the box's edges).
  EXPECT_GT(on_faces, s.mesh.triangles.size() / 2);
  const Eigen::Vector3d size = box.max_mm - box.min_mm;
  for (int axis = 0; axis < 3; ++axis) {
    const double face = size[(axis + 1) % 3] * size[(axis + 2) % 3];
    for (int side = 0; side < 2; ++side) {
      EXPECT_LE(area[static_cast<std::size_t>(2 * axis + side)], face + 1e-9) << "face " << 2 * axis + side;
      EXPECT_GT(area[static_cast<std::size_t>(2 * axis + side)], 0.5 * face) << "face " << 2 * axis + side;
    }
  }
}

// A groove in the bricks at the top of the lattice (fewer than 16 cells high): the top face
// lies midway between two nodes, so a ray over the groove, with no endpoint there, gives the
// same crossing as the face (the middle of the edge). Bricks whose first node column is clean
// face and the rest groove must still be meshed as the groove, not as the face.
TEST(DexelStock, GrooveInTheLatticesTopBricksIsNotTakenForTheFace) {
  const BoxShape box{{0, 0, 0}, {12, 12, 10}};  // at 0.1 mm the top bricks hold 7 cells in z
  MoveList list;
  list.cutters.push_back(make(CutterType::Ball, 2, 1, 12));
  list.moves.push_back(line({-5, 2.9, 9}, {17, 2.9, 9}));  // ball centre on the top: y 1.9 to 3.9
  DexelStock stock(box, 0.1);
  stock.cut(list, {});
  const SurfaceMesh s = stock.surface();
  double volume = 0.0;
  ASSERT_TRUE(closed_volume(s.mesh, volume));
  EXPECT_NEAR(volume, 1440.0 - 0.5 * M_PI * 12.0, 0.3);
  for (const Eigen::Vector3d& x : s.mesh.vertices_mm) {
    const double groove = segment_distance(x, {-5, 2.9, 10}, {17, 2.9, 10}) - 1.0;
    const double solid = std::max(-groove, std::max((box.min_mm - x).maxCoeff(), (x - box.max_mm).maxCoeff()));
    ASSERT_LT(std::abs(solid), 0.1 * 0.1 + 1e-9) << x.transpose();  // v/10
  }
}

TEST(DexelStock, MemoryEstimateCoversTheRealUse) {
  const BoxShape box{{0, 0, -20}, {60, 40, 0}};
  DexelStock stock(box, 0.1);
  const std::size_t estimate = estimate_dexel_memory_bytes(box, 0.1);
  EXPECT_GE(estimate, stock.memory_bytes());
  // Beyond the rays the estimate adds the meshing's grids: at most 128 bytes per surface
  // cell (the box's 8,800 mm2 at 0.1 mm are 880,000 cells).
  EXPECT_LE(estimate, stock.memory_bytes() + static_cast<std::size_t>(880000.0 * 128));
}

}  // namespace
}  // namespace vcut::removal
