// Five-axis moves (issue #5 item 6): a tilting cutter's swept volume cut as translation
// pieces, against a brute-force minimum over 10^4 cutter instances of the rigid motion (tip
// straight, axis on the great circle, written out here with its own Rodrigues rotation).
// The difference must stay within the stated bound plus the brute force's own sampling error.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "slab_distance.h"
#include "vcut/removal/move.h"
#include "vcut/removal/sweep.h"

namespace vcut::removal {
namespace {

Cutter make(CutterType type, double d, double r, double flute) {
  Cutter c;
  c.type = type;
  c.diameter_mm = d;
  c.corner_radius_mm = r;
  c.flute_length_mm = flute;
  c.length_mm = flute;
  c.tip_angle_deg = type == CutterType::VBit ? 90.0 : 0.0;
  return c;
}

// The rigid motion's instance at t: tip p0 + t (p1 - p0); the tool frame turned from a0 by
// the fraction t of the angle between a0 and a1 about their common normal.
struct RigidMotion {
  Eigen::Vector3d p0, p1, a0, a1;

  Eigen::Matrix3d tool_to_work(double t) const {  // tool +Z -> the axis at t
    const Eigen::Vector3d n = a0.cross(a1);
    const double angle = std::atan2(n.norm(), a0.dot(a1));
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(t * angle, n.normalized()).toRotationMatrix();
    const Eigen::Matrix3d start = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), a0).toRotationMatrix();
    return turn * start;
  }
  double instance_distance(const Cutter& c, const Eigen::Vector3d& x, double t) const {
    const Eigen::Vector3d tip = p0 + t * (p1 - p0);
    return cutter_distance(c, tool_to_work(t).transpose() * (x - tip));
  }
  // The point at `local` (the tool's frame, from its tip) of the instance at t.
  Eigen::Vector3d point(double t, const Eigen::Vector3d& local) const {
    return p0 + t * (p1 - p0) + tool_to_work(t) * local;
  }
};

// The pieces' sweep distance at p (the least over the pieces), and the rigid motion's by brute
// force over instances + 1 instants. With `slabs` (the pieces' moves): each piece's sweep
// within its slab's sweep (the larger of the two distances, at most the distance to their
// common part), the least the cut takes: a ray with material there gets the piece's whole
// interval.
double pieces_distance(const std::vector<TranslationSweep>& sweeps, const Eigen::Vector3d& p,
                       const std::vector<Move>* slabs = nullptr) {
  double d = 1e300;
  for (std::size_t i = 0; i < sweeps.size(); ++i)
    d = std::min(d, slabs == nullptr ? sweeps[i].distance(p)
                                     : std::max(sweeps[i].distance(p), test::slab_distance((*slabs)[i], p)));
  return d;
}
double brute_distance(const RigidMotion& motion, const Cutter& c, const Eigen::Vector3d& p, int instances) {
  double d = 1e300;
  for (int i = 0; i <= instances; ++i)
    d = std::min(d, motion.instance_distance(c, p, static_cast<double>(i) / instances));
  return d;
}

// `count` points drawn from `sampling` (x, y, z in turn) near the pieces' swept surface (|d| <=
// near_mm): a point inside either sweep lies within `slack` of the other (the distance to a set
// is at most its signed distance; with `slabs`, pieces_distance's, which is at most the
// distance to each piece's part in its slab). Returns the largest difference of the two
// distances seen.
double expect_within_both_ways(const std::vector<TranslationSweep>& sweeps, const RigidMotion& motion, const Cutter& c,
                               int instances, const Eigen::AlignedBox3d& sampling, double near_mm, int count,
                               double slack, std::mt19937& rng, const std::string& what,
                               const std::vector<Move>* slabs = nullptr) {
  std::uniform_real_distribution<double> x(sampling.min().x(), sampling.max().x()),
      y(sampling.min().y(), sampling.max().y()), z(sampling.min().z(), sampling.max().z());
  double worst = 0.0;
  for (int near = 0; near < count;) {
    const Eigen::Vector3d p(x(rng), y(rng), z(rng));
    const double pieces_d = pieces_distance(sweeps, p, slabs);
    if (std::abs(pieces_d) > near_mm) continue;
    const double brute = brute_distance(motion, c, p, instances);
    if (pieces_d <= 0.0) {
      EXPECT_LE(brute, slack) << what << " at " << p.transpose();
    }
    if (brute <= 0.0) {
      EXPECT_LE(pieces_d, slack) << what << " at " << p.transpose();
    }
    worst = std::max(worst, std::abs(pieces_d - brute));
    ++near;
  }
  return worst;
}

TEST(FiveAxisSweep, TiltingCuttersWithinTheStatedBound) {
  constexpr int kInstances = 10000;
  const double tilt = 30.0 * M_PI / 180.0;
  std::mt19937 rng(17);
  for (const Cutter& c : {make(CutterType::Flat, 10, 0, 20), make(CutterType::Ball, 6, 3, 15),
                          make(CutterType::BullNose, 8, 1, 12), make(CutterType::VBit, 6, 0, 5)}) {
    const RigidMotion motion{{0, 0, 0}, {2.0, 1.0, -0.5}, {0, 0, 1}, {std::sin(tilt), 0, std::cos(tilt)}};
    Move base;
    base.start_mm = motion.p0;
    base.end_mm = motion.p1;
    for (double bound : {0.05, 0.01}) {
      constexpr double kWhole = std::numeric_limits<double>::infinity();
      const TurningSplit split = five_axis_split(c, kWhole, motion.a0, motion.a1, bound);
      const int n = split.pieces;
      EXPECT_LE(rotation_error_mm(c, kWhole, tilt, split), bound);
      EXPECT_GT(rotation_error_mm(c, kWhole, tilt, {n - 1, split.pivot_mm}), bound) << "not the fewest pieces";
      std::vector<Move> pieces;
      append_five_axis_move(pieces, base, motion.a0, motion.a1, split);
      ASSERT_EQ(static_cast<int>(pieces.size()), n);
      // The pivot's path ends where the rigid motion's does.
      EXPECT_LT(
          (pieces.back().end_mm + split.pivot_mm * pieces.back().axis - motion.p1 - split.pivot_mm * motion.a1).norm(),
          1e-12);
      std::vector<TranslationSweep> sweeps;
      for (const Move& m : pieces) sweeps.emplace_back(c, m);
      // Brute force: d_true <= d_brute <= d_true + V / (2 N), V the fastest cutter point's path.
      const double reach = std::hypot(c.radius_mm(), c.flute_length_mm);
      const double brute_error = ((motion.p1 - motion.p0).norm() + tilt * reach) / (2.0 * kInstances);
      std::uniform_real_distribution<double> x(-8, 10), y(-7, 8), z(-3, 20);
      int near_surface = 0;
      double worst = 0.0;
      while (near_surface < 150) {
        const Eigen::Vector3d p(x(rng), y(rng), z(rng));
        const double pieces_d = pieces_distance(sweeps, p);
        if (std::abs(pieces_d) > 1.0) continue;  // near the swept surface only
        ++near_surface;
        const double brute = brute_distance(motion, c, p, kInstances);
        worst = std::max(worst, std::abs(pieces_d - brute));
        EXPECT_LE(std::abs(pieces_d - brute), bound + brute_error + 1e-6)
            << to_string(c.type) << " bound " << bound << " at " << p.transpose();
      }
      // The bound is not vacuous: the error is a sizeable part of it for coarse bounds.
      if (bound == 0.05 && c.type == CutterType::Flat) {
        EXPECT_GT(worst, 0.1 * bound);
      }
    }
  }
}

// The bound behind the pieces' reach (move.h): a cylinder of half height h and radius R about
// its middle, turned by theta about an axis square to its own through that middle, has every
// point within max(h, R) sin(theta) of the cylinder as it was (its distance is convex, so the
// rim circles are the worst), and a rim point comes that far. Measured here on the rims of
// cylinders wide and tall, with the exact distance to a cylinder.
TEST(FiveAxisSweep, ATurnedCylinderStaysWithinTheLargerOfItsHalfHeightAndRadius) {
  auto cylinder_distance = [](const Eigen::Vector3d& y, double h, double radius) {
    return std::hypot(std::max(0.0, y.head<2>().norm() - radius), std::max(0.0, std::abs(y.z()) - h));
  };
  for (const double h : {0.0, 1.0, 3.0, 4.5, 12.0})
    for (const double radius : {0.0, 1.0, 3.0, 5.0})
      for (const double theta : {1e-3, 0.01, 0.1, 0.4}) {
        if (h == 0.0 && radius == 0.0) continue;
        const Eigen::Matrix3d turn = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()).toRotationMatrix();
        double worst = 0.0;
        for (int i = 0; i < 3600; ++i) {
          const double psi = 2 * M_PI * i / 3600.0;
          for (const double z : {-h, h}) {
            const Eigen::Vector3d rim(radius * std::cos(psi), radius * std::sin(psi), z);
            worst = std::max(worst, cylinder_distance(turn * rim, h, radius));
          }
        }
        const double bound = std::max(h, radius) * std::sin(theta);
        EXPECT_LE(worst, bound * (1 + 1e-12)) << "h " << h << " R " << radius << " theta " << theta;
        // The rim point in the plane of the turn: on one side it leaves the side wall by
        // h sin(theta) - R (1 - cos(theta)), on the other the end face by R sin(theta) - h (1 - cos(theta)).
        const double corner = std::max(h * std::sin(theta) - radius * (1 - std::cos(theta)),
                                       radius * std::sin(theta) - h * (1 - std::cos(theta)));
        EXPECT_GE(worst, corner - 1e-12) << "h " << h << " R " << radius << " theta " << theta;
        EXPECT_GT(worst, 0.99 * bound - std::min(h, radius) * theta * theta / 2);
        // The bound the pieces used before, sqrt(h^2 + R^2) theta, is loose where h and R are alike.
        if (h == 3.0 && radius == 3.0) {
          EXPECT_LT(worst, 0.75 * std::hypot(h, radius) * theta);
        }
      }
}

// highest_point_in_box_mm: points of the tool (radius R, any height, any offset) placed by the
// rigid motion at random instants, and by the pieces' axes, that fall inside the box lie no
// higher than the bound; and the bound is near the truth (a point a little below it does
// come inside, for the tilts and boxes taken here).
TEST(FiveAxisSweep, NoPointAboveTheHeightComesInsideTheBox) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-5, -5, 0), Eigen::Vector3d(40, 30, 12));
  int bounded = 0;
  double ratio_sum = 0.0;
  for (int trial = 0; trial < 40; ++trial) {
    const double radius = 2 + 4 * unit(rng);
    auto random_axis = [&](double tilt_deg) {
      const double tilt = tilt_deg * M_PI / 180.0, azimuth = 2 * M_PI * unit(rng);
      return Eigen::Vector3d(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
    };
    const Eigen::Vector3d a0 = random_axis(5 + 40 * unit(rng));
    // A turn of up to 20 deg from a0 (W5 and the impeller turn 1 deg a move).
    const Eigen::Vector3d a1 = Eigen::AngleAxisd((20 * unit(rng)) * M_PI / 180.0, a0.unitOrthogonal()) * a0;
    const Eigen::Vector3d p0(40 * unit(rng), 30 * unit(rng), 2 + 8 * unit(rng));
    const Eigen::Vector3d p1 = p0 + Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5) * 4.0;
    const double highest = highest_point_in_box_mm(radius, p0, p1, a0, a1, box);
    if (!std::isfinite(highest)) continue;
    ++bounded;
    const RigidMotion motion{p0, p1, a0, a1};
    const Eigen::Vector3d n = a0.cross(a1);
    const double angle = std::atan2(n.norm(), a0.dot(a1));
    double highest_inside = 0.0;
    for (int i = 0; i < 20000; ++i) {
      const double t = unit(rng), h = (highest + 10.0) * unit(rng), rho = radius * std::sqrt(unit(rng));
      const double phi = 2 * M_PI * unit(rng);
      // The axis at t on the great circle, and (for a piece) at a second instant.
      const Eigen::Vector3d a = Eigen::AngleAxisd(t * angle, n.normalized()) * a0;
      const Eigen::Vector3d piece_a = Eigen::AngleAxisd(unit(rng) * angle, n.normalized()) * a0;
      for (const Eigen::Vector3d& axis : {a, piece_a}) {
        const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
        const Eigen::Vector3d x =
            motion.p0 + t * (motion.p1 - motion.p0) + h * axis + rho * (std::cos(phi) * e1 + std::sin(phi) * e2);
        if (box.contains(x)) highest_inside = std::max(highest_inside, h);
      }
    }
    EXPECT_LE(highest_inside, highest) << "trial " << trial;
    EXPECT_GT(highest_inside, 0.5 * highest) << "trial " << trial << ": a loose bound";
    ratio_sum += highest_inside / highest;
  }
  EXPECT_GT(bounded, 30);
  EXPECT_GT(ratio_sum / bounded, 0.85) << "the bound is loose on the whole";
}

// A tool standing out of the box turns in fewer pieces, and every point of its core (radius
// R - r, heights r to H - r) whose ball of radius r reaches into the box (grown by the pieces'
// tips' offset from the tip's path, as the pipeline grows it) in the rigid motion or in a
// piece lies within the bound of the other's core at the same instant: the core turned about
// the arc's normal by the angle at t, or by the piece's middle angle on the piece's own
// straight path (written out here with its own rotation). And the pieces' sweep stays within the
// bound of the rigid motion's inside the box: a point of the box inside either lies within
// the bound (plus the brute force's sampling) of the other.
TEST(FiveAxisSweep, FewerPiecesWithinTheBoundInsideTheBox) {
  constexpr int kInstances = 4000;
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-10, -10, -10), Eigen::Vector3d(10, 10, 3));
  const double tilt = 25.0 * M_PI / 180.0, bound = 0.01;
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Cutter& c : {make(CutterType::Ball, 6, 3, 25), make(CutterType::BullNose, 8, 1, 25)}) {
    const Eigen::Vector3d a0(0, std::sin(tilt), std::cos(tilt));
    const Eigen::Vector3d a1 = Eigen::Vector3d(std::sin(tilt) * 0.3, std::sin(tilt), std::cos(tilt)).normalized();
    const RigidMotion motion{{0, 0, 0}, {1.5, 0.5, 0.2}, a0, a1};
    const Eigen::Vector3d normal = a0.cross(a1).normalized();
    const double angle = std::atan2(a0.cross(a1).norm(), a0.dot(a1));
    // The box grown as the pipeline grows it: the whole cutter's pivot, one piece.
    const double pivot_whole = 0.5 * (c.corner_radius_mm + (c.flute_length_mm - c.corner_radius_mm));
    const Eigen::Vector3d off = Eigen::Vector3d::Constant(pivot_whole * (angle / 2 + angle * angle / 8));
    const Eigen::AlignedBox3d grown(box.min() - off, box.max() + off);
    const double height = highest_point_in_box_mm(c.radius_mm(), motion.p0, motion.p1, a0, a1, grown);
    ASSERT_LT(height, 8.0);
    const TurningSplit split = five_axis_split(c, height, a0, a1, bound);
    const int n = split.pieces;
    const int whole = five_axis_split(c, std::numeric_limits<double>::infinity(), a0, a1, bound).pieces;
    EXPECT_LT(2 * n, whole) << to_string(c.type);
    Move base;
    base.start_mm = motion.p0;
    base.end_mm = motion.p1;
    std::vector<Move> pieces;
    append_five_axis_move(pieces, base, a0, a1, split);
    ASSERT_EQ(static_cast<int>(pieces.size()), n);
    auto turned = [&](double fraction) { return Eigen::AngleAxisd(fraction * angle, normal).toRotationMatrix(); };
    // Instance by instance, the core's points (the axis from r up, R - r about it): each
    // point of one instance lies within the bound of the other instance's core.
    const double r = c.corner_radius_mm, core_radius = c.radius_mm() - r, core_top = 25.0 - r;
    double worst_point = 0.0;
    const Eigen::Vector3d e1 = a0.unitOrthogonal(), e2 = a0.cross(e1);
    auto near_box = [&](const Eigen::Vector3d& x) { return grown.exteriorDistance(x) <= r; };
    // The distance from x to the core of the instance with its tip at `tip`, turned by `turn`
    // from a0.
    auto core_distance = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& tip, const Eigen::Matrix3d& turn) {
      const Eigen::Vector3d y = turn.transpose() * (x - tip);
      const double along = y.dot(a0), across = (y - along * a0).norm();
      const double out_radial = std::max(0.0, across - core_radius);
      const double out_axial = std::max({0.0, r - along, along - core_top});
      return std::hypot(out_radial, out_axial);
    };
    for (int i = 0; i < 200000; ++i) {
      const double t = unit(rng), h = r + (core_top - r) * unit(rng), rho = core_radius * std::sqrt(unit(rng));
      const double phi = 2 * M_PI * unit(rng);
      const int k = std::min(n - 1, static_cast<int>(t * n));
      const Move& p = pieces[static_cast<std::size_t>(k)];
      EXPECT_LT((turned((k + 0.5) / n) * a0 - p.axis).norm(), 1e-12);
      const Eigen::Vector3d point = h * a0 + rho * (std::cos(phi) * e1 + std::sin(phi) * e2);
      const double along = t * n - k;  // the fraction of the piece
      const Eigen::Vector3d rigid_tip = motion.p0 + t * (motion.p1 - motion.p0);
      const Eigen::Vector3d piece_tip = p.start_mm + along * (p.end_mm - p.start_mm);
      const Eigen::Matrix3d rigid_turn = turned(t), piece_turn = turned((k + 0.5) / n);
      const Eigen::Vector3d rigid = rigid_tip + rigid_turn * point, piece = piece_tip + piece_turn * point;
      if (near_box(rigid)) worst_point = std::max(worst_point, core_distance(rigid, piece_tip, piece_turn));
      if (near_box(piece)) worst_point = std::max(worst_point, core_distance(piece, rigid_tip, rigid_turn));
    }
    EXPECT_LE(worst_point, bound) << to_string(c.type);
    EXPECT_GT(worst_point, 0.5 * bound) << to_string(c.type) << ": the points never came near the bound";
    // The sweeps.
    std::vector<TranslationSweep> sweeps;
    for (const Move& m : pieces) sweeps.emplace_back(c, m);
    const double brute_error =
        ((motion.p1 - motion.p0).norm() + angle * std::hypot(c.radius_mm(), 25.0)) / (2.0 * kInstances);
    expect_within_both_ways(sweeps, motion, c, kInstances, {Eigen::Vector3d(-6, -6, -2), Eigen::Vector3d(8, 8, 3)},
                            0.05, 100, bound + brute_error + 1e-6, rng, to_string(c.type));
  }
}

// A long ball, flat or bull-nose end mill turns part by part (cutter_parts, part_split,
// append_part_pieces), a ball's parts halved too (halved_parts). The parts' union is the
// cutter: outside it the least of the parts' distances is the cutter's (the distance to a
// union), inside it some part holds the point. Inside the stock's box (grown by box_for_pieces,
// for the top part's pivot) the parts' pieces sweep within the bound of the rigid motion's and
// the rigid motion within the bound of theirs (brute force over 4,000 instances), the parts
// whose core starts above the height left out.
TEST(FiveAxisSweep, LongCuttersTurnPartByPartWithinTheBound) {
  constexpr int kInstances = 4000;
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Cutter& c :
       {make(CutterType::Ball, 6, 3, 25), make(CutterType::Ball, 3, 1.5, 15), make(CutterType::Ball, 1, 0.5, 20),
        make(CutterType::Flat, 4, 0, 25), make(CutterType::BullNose, 5, 1, 25)}) {
    for (const bool halved : {false, true}) {
      if (halved && c.type != CutterType::Ball) continue;
      const double r = c.corner_radius_mm, core = c.flute_length_mm - 2 * r;
      const std::vector<CutterPart> whole_parts = cutter_parts(c);
      const std::vector<CutterPart> parts = halved ? halved_parts(whole_parts) : whole_parts;
      // A ball's parts r / 2 of the core long, or an eighth of it where longer (8 of them each: the
      // D6 ball's 19 mm core in parts of 2.375 mm, the D3's 12 mm in parts of r = 1.5 mm); a flat or
      // bull-nose end mill's 2 Rc (7 and 8 of them). Halved, twice as many, each half as long.
      const double length =
          c.type == CutterType::Ball ? std::max(r / 2, core / 8) : std::max(2 * (c.radius_mm() - r), core / 8);
      ASSERT_EQ(whole_parts.size(), static_cast<std::size_t>(std::ceil(core / length - 1e-9))) << to_string(c.type);
      ASSERT_EQ(parts.size(), (halved ? 2 : 1) * whole_parts.size());
      for (std::size_t j = 0; j < parts.size(); ++j) {  // end to end up the core
        const double own = parts[j].cutter.flute_length_mm - 2 * r;
        EXPECT_NEAR(own, j + 1 < parts.size() ? length / (halved ? 2 : 1) : core - parts[j].offset_mm, 1e-12);
        if (j > 0) {
          EXPECT_NEAR(parts[j].offset_mm, parts[j - 1].offset_mm + length / (halved ? 2 : 1), 1e-12);
        }
      }
      int outside = 0, inside = 0;
      for (int i = 0; i < 20000; ++i) {
        const double across = 1.3 * c.radius_mm();
        const Eigen::Vector3d y(across * (2 * unit(rng) - 1), across * (2 * unit(rng) - 1),
                                c.flute_length_mm * 1.2 * unit(rng) - 2);
        const double whole = cutter_distance(c, y);
        double least = std::numeric_limits<double>::infinity();
        for (const CutterPart& part : parts)
          least = std::min(least, cutter_distance(part.cutter, y - part.offset_mm * Eigen::Vector3d::UnitZ()));
        if (whole > 0.0) {
          EXPECT_NEAR(least, whole, 1e-12) << y.transpose();
          ++outside;
        } else {
          EXPECT_LE(least, 0.0) << y.transpose();
          ++inside;
        }
      }
      EXPECT_GT(inside, 1000);
      EXPECT_GT(outside, 1000);

      // A turn of 25 deg about a tilted axis while the tip moves, the box's top 6 mm above the
      // tip: the upper parts stay out of it.
      const Eigen::AlignedBox3d box(Eigen::Vector3d(-10, -10, -10), Eigen::Vector3d(10, 10, 6));
      const double tilt = 25.0 * M_PI / 180.0;
      const Eigen::Vector3d a0(0, std::sin(tilt), std::cos(tilt));
      const Eigen::Vector3d a1 = Eigen::Vector3d(std::sin(tilt) * 0.3, std::sin(tilt), std::cos(tilt)).normalized();
      const RigidMotion motion{{0, 0, 0}, {1.5, 0.5, 0.2}, a0, a1};
      const double angle = std::atan2(a0.cross(a1).norm(), a0.dot(a1));
      const Eigen::AlignedBox3d grown = box_for_pieces(c, a0, a1, box);
      // The top part's core's middle; a ball's top half's lies higher, a quarter of that part up.
      const CutterPart& top_part = whole_parts.back();
      const double top_core = top_part.cutter.flute_length_mm - 2 * r;
      const double top_pivot =
          top_part.offset_mm + r + (c.type == CutterType::Ball && whole_parts.size() > 1 ? 0.75 : 0.5) * top_core;
      EXPECT_NEAR(grown.max().z() - box.max().z(), top_pivot * (angle / 2 + angle * angle / 8), 1e-12);
      const double height = highest_point_in_box_mm(c.radius_mm(), motion.p0, motion.p1, a0, a1, grown);
      ASSERT_LT(height, c.flute_length_mm - 2 * r);
      // The parts' pieces of a rigid motion, each with its slab; `highest`, the highest part
      // with pieces.
      auto part_pieces = [&](const RigidMotion& turn, double bound, std::size_t& highest, int& left_out) {
        Move base;
        base.start_mm = turn.p0;
        base.end_mm = turn.p1;
        const std::vector<TurningSplit> splits = part_splits(parts, height, turn.a0, turn.a1, bound, highest);
        left_out = 0;
        for (std::size_t j = 0; j < parts.size(); ++j) {
          if (splits[j].pieces == 0) {
            EXPECT_GT(parts[j].offset_mm, height);
            ++left_out;
          }
        }
        std::vector<Move> pieces;
        for (std::size_t j = 0; j < parts.size(); ++j)
          append_part_pieces(pieces, base, turn.a0, turn.a1, parts[j], static_cast<int>(j), splits[j], j == highest);
        return pieces;
      };
      auto sweeps_of = [&](const std::vector<Move>& pieces) {
        std::vector<TranslationSweep> sweeps;
        for (const Move& m : pieces) sweeps.emplace_back(parts[static_cast<std::size_t>(m.cutter)].cutter, m);
        return sweeps;
      };
      // The same turn with the tip standing still: the pieces then move square to their axes
      // (the pivot's chord), and their slabs' sweeps reach no further than the slabs (a tip
      // moving along the axis carries a slab over its neighbour's).
      const RigidMotion still{motion.p0, motion.p0, a0, a1};
      for (const double bound : {0.05, 0.01}) {
        std::size_t highest;
        int left_out;
        const std::vector<Move> pieces = part_pieces(motion, bound, highest, left_out);
        EXPECT_GT(left_out, 0);
        const std::vector<TranslationSweep> sweeps = sweeps_of(pieces);
        const double brute_error =
            ((motion.p1 - motion.p0).norm() + angle * std::hypot(c.radius_mm(), c.flute_length_mm)) /
            (2.0 * kInstances);
        // The pieces whole, then each within its part's slab (append_part_pieces): the same bound.
        const std::vector<Move>* const ways[] = {nullptr, &pieces};
        for (const std::vector<Move>* slabs : ways) {
          const std::string what =
              "r " + std::to_string(r) + (halved ? ", halved" : "") + (slabs != nullptr ? ", slabs" : "");
          const double worst = expect_within_both_ways(sweeps, motion, c, kInstances,
                                                       {Eigen::Vector3d(-6, -6, -2), Eigen::Vector3d(8, 8, 6)}, 0.2,
                                                       120, bound + brute_error + 1e-6, rng, what, slabs);
          if (bound == 0.05) {
            EXPECT_GT(worst, 0.1 * bound) << what << ": the error never came near the bound";
          }
        }
        // Where two parts' slabs meet (part j's core top, j + 1's bottom): points of the rigid
        // motion's instances just inside the tool's surface at that height lie within the bound
        // of the parts' pieces within their slabs, for both motions. Half of them on the side
        // of the axis that the turn raises or lowers most (their offset along w x a, w the turn's
        // axis), where a piece's turn moves a point's height by up to r phi / 2: where two parts'
        // pieces turn apart (their counts differ), slabs without that margin leave such points of
        // the still turn out (22 of them; a margin of r phi / 4 passes).
        for (const RigidMotion& turn : {motion, still}) {
          std::size_t top;
          int out;
          const std::vector<Move> turn_pieces = part_pieces(turn, bound, top, out);
          const std::vector<TranslationSweep> turn_sweeps = sweeps_of(turn_pieces);
          ASSERT_GE(top, 1u);
          for (std::size_t j = 0; j < top; ++j) {
            const double h = parts[j + 1].offset_mm + r;
            for (int i = 0; i < 800; ++i) {
              const double t = unit(rng), rho = c.radius_mm() * (1 - 1e-3 * unit(rng));
              double psi = 2 * M_PI * unit(rng);
              if (i % 2 == 0) {
                const Eigen::Vector3d w = turn.a0.cross(turn.a1).normalized();
                const Eigen::Vector3d raised = turn.tool_to_work(t).transpose() * w.cross(turn.tool_to_work(t).col(2));
                psi = std::atan2(raised.y(), raised.x()) + (i % 4 == 0 ? 0.0 : M_PI);
              }
              const Eigen::Vector3d local(rho * std::cos(psi), rho * std::sin(psi), h + 0.002 * (2 * unit(rng) - 1));
              const Eigen::Vector3d x = turn.point(t, local);
              ASSERT_LE(turn.instance_distance(c, x, t), 0.0);
              EXPECT_LE(pieces_distance(turn_sweeps, x, &turn_pieces), bound + 1e-6)
                  << "r " << r << ", bound " << bound << ": between parts " << j << " and " << j + 1 << " at t " << t;
            }
          }
        }
      }
    }
  }
}
}  // namespace
}  // namespace vcut::removal
