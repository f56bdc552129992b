#include "vcut/removal/move.h"

#include <Eigen/Geometry>

#include "vcut/kinematics/densify.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vcut::removal {

bool ListSource::next(std::vector<Move>& out, std::size_t wanted) {
  const std::size_t n = std::min(wanted, list_.moves.size() - at_);
  out.insert(out.end(), list_.moves.begin() + static_cast<std::ptrdiff_t>(at_),
             list_.moves.begin() + static_cast<std::ptrdiff_t>(at_ + n));
  at_ += n;
  return n > 0;
}
namespace {

constexpr int kMaxPieces = 1 << 16;
// A ball's parts are r of its core, but no more than this many: each takes at least a piece a
// move (a D1 ball with a 19 mm core in W5's ball rows: 38 parts cut in 0.273 s, 8 in 0.170 s,
// the whole cutter in 0.196 s).
constexpr double kMaxParts = 8.0;

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The bound for a split of a turn by angle_rad, given the reach of the core about the pivot.
double split_error_mm(double reach_mm, double angle_rad, const TurningSplit& split) {
  const double phi = angle_rad / std::max(1, split.pieces);
  return reach_mm * phi / 2.0 + std::abs(split.pivot_mm) * phi * phi / 8.0;
}

}  // namespace

void rotation_reach_mm(const Cutter& cutter, double height_mm, double& pivot_mm, double& reach_mm) {
  double lo, hi, radius;
  if (cutter.type == CutterType::VBit) {
    lo = 0.0;
    hi = std::min(cutter.flute_length_mm, height_mm);
    radius = cutter.radius_mm();
  } else {
    const CutterCore core = core_of(cutter);
    lo = core.z_low_mm;
    hi = std::min(core.z_high_mm, height_mm + core.rounding_mm);
    radius = core.core_radius_mm;
  }
  hi = std::max(hi, lo);
  pivot_mm = 0.5 * (lo + hi);
  // A V-bit's points each move by at most their distance from the pivot times the turn; a
  // core cylinder (half height h, radius Rc about its middle) turned into itself is nowhere
  // farther than max(h, Rc) sin(theta) from where it was (move.h).
  reach_mm = cutter.type == CutterType::VBit ? std::hypot(radius, 0.5 * (hi - lo)) : std::max(radius, 0.5 * (hi - lo));
}

double rotation_error_mm(const Cutter& cutter, double height_mm, double angle_rad, const TurningSplit& split) {
  double pivot_mm, reach_mm;
  rotation_reach_mm(cutter, height_mm, pivot_mm, reach_mm);
  return split_error_mm(reach_mm, angle_rad, split);
}

TurningSplit five_axis_split(const Cutter& cutter, double height_mm, const Eigen::Vector3d& axis0,
                             const Eigen::Vector3d& axis1, double bound_mm) {
  TurningSplit split;
  const double angle = angle_between(axis0.normalized(), axis1.normalized());
  double reach_mm;
  rotation_reach_mm(cutter, height_mm, split.pivot_mm, reach_mm);
  if (angle == 0.0) {
    split.pivot_mm = 0.0;  // no turn: the tip's own path, exactly
    return split;
  }
  // The first order term alone gives n; the second order one (the pivot's path) adds a piece
  // now and then.
  const double n = std::ceil(reach_mm * angle / (2.0 * bound_mm) - 1e-12);
  split.pieces = static_cast<int>(std::clamp(n, 1.0, static_cast<double>(kMaxPieces)));
  while (split.pieces < kMaxPieces && split_error_mm(reach_mm, angle, split) > bound_mm) ++split.pieces;
  return split;
}

double highest_point_in_box_mm(double radius_mm, const Eigen::Vector3d& tip0, const Eigen::Vector3d& tip1,
                               const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1,
                               const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3d a0 = axis0.normalized(), a1 = axis1.normalized();
  const double angle = angle_between(a0, a1);
  double highest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k)
    for (const double sign : {-1.0, 1.0}) {
      // Face n = sign e_k, offset o: inside means n.x <= o.
      const double offset = sign > 0.0 ? box.max()[k] : -box.min()[k];
      const double along_min = std::min(sign * a0[k], sign * a1[k]) - angle * angle / 8.0;
      if (!(along_min > 0.0)) continue;
      const double tip_min = std::min(sign * tip0[k], sign * tip1[k]);
      const double spread = radius_mm * std::sqrt(std::max(0.0, 1.0 - along_min * along_min));
      highest = std::min(highest, (offset - tip_min + spread) / along_min);
    }
  return std::max(0.0, highest);
}

Eigen::AlignedBox3d box_for_pieces(const Cutter& cutter, const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1,
                                   const Eigen::AlignedBox3d& box) {
  double pivot_mm = 0.0;
  std::vector<CutterPart> parts = cutter_parts(cutter);
  if (cutter.type == CutterType::Ball && parts.size() > 1) {  // a ball's halves too (their top one's pivot is higher)
    const std::vector<CutterPart> halves = halved_parts(parts);
    parts.insert(parts.end(), halves.begin(), halves.end());
  }
  for (const CutterPart& part : parts) {
    double pivot, reach_mm;
    rotation_reach_mm(part.cutter, std::numeric_limits<double>::infinity(), pivot, reach_mm);
    pivot_mm = std::max(pivot_mm, part.offset_mm + pivot);
  }
  const double angle = angle_between(axis0.normalized(), axis1.normalized());
  const Eigen::Vector3d off = Eigen::Vector3d::Constant(pivot_mm * (angle / 2.0 + angle * angle / 8.0));
  return {box.min() - off, box.max() + off};
}

void append_five_axis_move(std::vector<Move>& out, const Move& move, const Eigen::Vector3d& axis0,
                           const Eigen::Vector3d& axis1, const TurningSplit& split) {
  const Eigen::Vector3d a = axis0.normalized(), b = axis1.normalized();
  const int n = std::max(1, split.pieces);
  const double c = split.pivot_mm;
  // The pivot at the fraction t of the move (its path: the tip's straight line, the axis on the arc).
  auto pivot = [&](int k) {
    const Eigen::Vector3d tip =
        k == n ? move.end_mm
               : Eigen::Vector3d(move.start_mm + (static_cast<double>(k) / n) * (move.end_mm - move.start_mm));
    return c == 0.0 ? tip : Eigen::Vector3d(tip + c * kinematics::great_circle(a, b, static_cast<double>(k) / n));
  };
  Eigen::Vector3d from = pivot(0);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d to = pivot(k + 1);
    Move piece = move;
    piece.axis = kinematics::great_circle(a, b, (k + 0.5) / n);
    piece.start_mm = c == 0.0 ? from : Eigen::Vector3d(from - c * piece.axis);
    piece.end_mm = c == 0.0 ? to : Eigen::Vector3d(to - c * piece.axis);
    out.push_back(piece);
    from = to;
  }
}

std::vector<CutterPart> cutter_parts(const Cutter& cutter) {
  const double r = cutter.corner_radius_mm, core = cutter.flute_length_mm - 2.0 * r;
  double length;
  if (cutter.type == CutterType::Ball) {
    if (!(r > 0.0) || !(core > 2.0 * r)) return {{cutter, 0.0}};
    length = std::max(0.5 * r, core / kMaxParts);
  } else if (cutter.type == CutterType::Flat || cutter.type == CutterType::BullNose) {
    const double rc = cutter.radius_mm() - r;
    if (!(rc > 0.0) || !(core > 4.0 * rc)) return {{cutter, 0.0}};
    length = std::max(2.0 * rc, core / kMaxParts);
  } else {
    return {{cutter, 0.0}};
  }
  const int n = static_cast<int>(std::ceil(core / length - 1e-9));
  std::vector<CutterPart> parts;
  for (int j = 0; j < n; ++j) {
    CutterPart part{cutter, j * length};
    part.cutter.flute_length_mm = std::min(length, core - j * length) + 2.0 * r;
    part.cutter.length_mm = part.cutter.flute_length_mm;
    parts.push_back(part);
  }
  return parts;
}

std::vector<CutterPart> halved_parts(const std::vector<CutterPart>& parts) {
  std::vector<CutterPart> halves;
  for (const CutterPart& part : parts) {
    const double r_mm = part.cutter.corner_radius_mm, half_mm = 0.5 * (part.cutter.flute_length_mm - 2.0 * r_mm);
    CutterPart low = part;
    low.cutter.flute_length_mm = half_mm + 2.0 * r_mm;
    low.cutter.length_mm = low.cutter.flute_length_mm;
    CutterPart high = low;
    high.offset_mm = part.offset_mm + half_mm;
    halves.push_back(low);
    halves.push_back(high);
  }
  return halves;
}

TurningSplit part_split(const CutterPart& part, double height_mm, const Eigen::Vector3d& axis0,
                        const Eigen::Vector3d& axis1, double bound_mm) {
  // A part whose core starts above height + r has its whole ball above the height.
  if (part.offset_mm > height_mm) return {0, 0.0};
  TurningSplit split = five_axis_split(part.cutter, height_mm - part.offset_mm, axis0, axis1, bound_mm);
  const double angle = angle_between(axis0.normalized(), axis1.normalized());
  if (angle == 0.0) return split;  // no turn: the tip's own path
  double pivot_mm, reach_mm;
  rotation_reach_mm(part.cutter, height_mm - part.offset_mm, pivot_mm, reach_mm);
  split.pivot_mm += part.offset_mm;
  while (split.pieces < kMaxPieces && split_error_mm(reach_mm, angle, split) > bound_mm) ++split.pieces;
  return split;
}

std::vector<TurningSplit> part_splits(const std::vector<CutterPart>& parts, double height_mm,
                                      const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1, double bound_mm,
                                      std::size_t& highest) {
  std::vector<TurningSplit> splits;
  highest = 0;
  for (std::size_t j = 0; j < parts.size(); ++j) {
    splits.push_back(part_split(parts[j], height_mm, axis0, axis1, bound_mm));
    if (splits[j].pieces > 0) highest = j;
  }
  return splits;
}

void append_part_pieces(std::vector<Move>& out, const Move& move, const Eigen::Vector3d& axis0,
                        const Eigen::Vector3d& axis1, const CutterPart& part, int part_cutter,
                        const TurningSplit& split, bool highest) {
  if (split.pieces == 0) return;
  Move m = move;
  m.cutter = part_cutter;
  // The part's core heights from r to r + core above its tip, grown by the margin (move.h; and
  // a hair for the rounding of the heights); the lowest part down through the tip's end, the
  // highest up through its top.
  const double r = part.cutter.corner_radius_mm, core = part.cutter.flute_length_mm - 2.0 * r;
  const double phi = angle_between(axis0.normalized(), axis1.normalized()) / std::max(1, split.pieces);
  double margin = r * phi / 2.0 + 1e-6;
  if (part.cutter.radius_mm() > r) {
    // A core of radius Rc > 0: its instances lie within e of each other as sets only.
    double part_pivot_mm, reach_mm;
    rotation_reach_mm(part.cutter, std::numeric_limits<double>::infinity(), part_pivot_mm, reach_mm);
    const double c = std::abs(split.pivot_mm), c_part = std::abs(split.pivot_mm - part.offset_mm);
    const double e = reach_mm * phi / 2.0 + c * phi * phi / 8.0;
    margin =
        e + part.cutter.radius_mm() * phi / 2.0 + (part.cutter.flute_length_mm + c_part + c) * phi * phi / 8.0 + 1e-6;
  }
  m.slab_low_mm = part.offset_mm > 0.0 ? r - margin : -std::numeric_limits<double>::infinity();
  m.slab_high_mm = highest ? std::numeric_limits<double>::infinity() : r + core + margin;
  const std::size_t first = out.size();
  append_five_axis_move(out, m, axis0, axis1, split);
  for (std::size_t i = first; i < out.size(); ++i) {
    out[i].start_mm += part.offset_mm * out[i].axis;
    out[i].end_mm += part.offset_mm * out[i].axis;
  }
}

std::vector<ToolBody> add_tool_bodies(MoveList& list) {
  const std::size_t n = list.cutters.size();
  std::vector<ToolBody> bodies(n);
  auto cylinder = [&](double diameter_mm, double length_mm) {
    Cutter c;
    c.type = CutterType::Flat;
    c.diameter_mm = diameter_mm;
    c.shank_diameter_mm = diameter_mm;
    c.flute_length_mm = length_mm;
    c.length_mm = length_mm;
    list.cutters.push_back(c);
    return static_cast<int>(list.cutters.size() - 1);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Cutter c = list.cutters[i];  // a copy: push_back may move the vector
    const double shank_mm = c.length_mm - c.flute_length_mm;
    const double shank_diameter_mm = c.shank_diameter_mm > 0.0 ? c.shank_diameter_mm : c.diameter_mm;
    if (shank_mm > 1e-9 && shank_diameter_mm > 0.0) {
      bodies[i].shank = cylinder(shank_diameter_mm, shank_mm);
      bodies[i].shank_height_mm = c.flute_length_mm;
    }
    if (c.holder_diameter_mm > 0.0 && c.holder_length_mm > 0.0) {
      bodies[i].holder = cylinder(c.holder_diameter_mm, c.holder_length_mm);
      bodies[i].holder_height_mm = std::max(c.length_mm, c.flute_length_mm);
    }
  }
  return bodies;
}

void append_body_probes(std::vector<Move>& out, const Move& move, const ToolBody& body) {
  auto probe = [&](int cutter, double height_mm, ProbeKind kind) {
    if (cutter < 0) return;
    Move p = move;
    p.start_mm = move.start_mm + height_mm * move.axis;
    p.end_mm = move.end_mm + height_mm * move.axis;
    p.cutter = cutter;
    p.rapid = true;
    p.probe = kind;
    out.push_back(p);
  };
  probe(body.shank, body.shank_height_mm, ProbeKind::Shank);
  probe(body.holder, body.holder_height_mm, ProbeKind::Holder);
}

}  // namespace vcut::removal
