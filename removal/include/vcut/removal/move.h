// A move: the rigid motion of the cutter between two consecutive tool poses in the
// workpiece frame (mm). The engines cut translations (tool axis constant) exactly; a
// five-axis move (the axis turning on a great circle) becomes a few such translations with
// a stated error bound (five_axis_split). The block index leads back to the NC line.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "vcut/removal/cutter.h"

namespace vcut::removal {

// What a probe (a move with `rapid` set: it never cuts, and material it meets is a
// collision) stands for.
enum class ProbeKind : std::uint8_t {
  Rapid,           // the cutting part at rapid traverse (G0)
  Shank,           // the shank, from the flute length to the holder, following a move
  Holder,          // the holder, following a move
  SpindleStopped,  // the cutting part of a feed move made with the spindle stopped
};

struct Move {
  Eigen::Vector3d start_mm = Eigen::Vector3d::Zero();  // tool tip
  Eigen::Vector3d end_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, tip -> spindle
  int cutter = 0;                                   // index into MoveList::cutters
  int block = -1;                                   // index of the NC block it came from
  bool rapid = false;                               // rapids never cut: touching material is a collision
  ProbeKind probe = ProbeKind::Rapid;               // with `rapid`: what the probe stands for
  // The heights above the tip along the axis (mm) outside which the move need not cut: the
  // points of a turning cutter that its other parts hold (append_part_pieces). The cut may
  // still take any of the move's sweep there, and passes over a ray only where the ray has no
  // material in the sweep of this slab.
  double slab_low_mm = -std::numeric_limits<double>::infinity();
  double slab_high_mm = std::numeric_limits<double>::infinity();
};

struct MoveList {
  std::vector<Cutter> cutters;
  std::vector<Move> moves;
};

// Moves handed over in program order a bounded batch at a time, so that a program's moves
// are never all held at once (Stock::cut pulls them; issue #22's values that stream).
class MoveSource {
 public:
  virtual ~MoveSource() = default;
  // Every cutter the moves name (Move::cutter indexes it), known before the first move.
  virtual const std::vector<Cutter>& cutters() const = 0;
  // Appends the next moves to `out`: about `wanted` of them (a source may finish what one
  // block makes, a few more); false, with nothing appended, when none are left.
  virtual bool next(std::vector<Move>& out, std::size_t wanted) = 0;
  // The moves in all where known ahead (progress), else 0.
  virtual std::size_t size_hint() const { return 0; }
};

// A whole MoveList as a source.
class ListSource : public MoveSource {
 public:
  explicit ListSource(const MoveList& list) : list_(list) {}
  const std::vector<Cutter>& cutters() const override { return list_.cutters; }
  bool next(std::vector<Move>& out, std::size_t wanted) override;
  std::size_t size_hint() const override { return list_.moves.size(); }

 private:
  const MoveList& list_;
  std::size_t at_ = 0;
};

// A five-axis move: the tip goes straight from `move.start_mm` to `move.end_mm` while the tool
// axis turns on the great circle from axis0 to axis1 (ARCHITECTURE §8). It is cut as n
// pieces, piece k a translation with the axis at the piece's middle instant that carries one
// point of the axis, the pivot c above the tip, along the chord of that point's path over the
// piece (c = 0: the tip, straight). A flat, ball or bull-nose cutter is its core grown by the
// corner radius r, so an instance's signed distance is the core's distance less r, off by at
// most as much as the two instances' cores lie apart; a V-bit is no such sum and takes its own
// points.
// Over a piece the axis turns by phi = angle / n; a rigid instance and the piece's at the same
// instant differ by the pivot's offset, at most c (1 - cos(phi / 2)) <= c phi^2 / 8 (the
// pivot's path, an arc's chord away from its chord), and a turn by theta <= phi / 2 about an
// axis w square to the tool's through the pivot. With c at the middle of the core's part that
// matters (below height_mm above the tip; half height h, radius Rc), the turned core K' lies
// within max(h, Rc) sin(theta) of K (and K of K'): d(., K) is convex, so over K' it is largest
// on a rim circle; a rim point h a + Rc (cos(psi) u + sin(psi) w), u = w x a, turns to axial
// coordinate h cos(theta) - Rc cos(psi) sin(theta) and radius P with P^2 = Rc^2 + X, X = h^2
// sin^2 + 2 h Rc cos(psi) sin cos - Rc^2 cos^2(psi) sin^2 (of theta). For cos(psi) >= 0, P - Rc
// <= h sin(theta), and where it passes the far end face (Rc tan(theta / 2) > h) P <= Rc and
// the face's excess is under Rc sin(theta); for cos(psi) = -g < 0 the near end face's
// excess is at most Rc g sin(theta), and where P > Rc, (P - Rc)^2 <= X, so the squares add to at
// most h^2 sin^2(theta) - 2 h Rc g sin cos <= h^2 sin^2(theta). (A point's own path, sqrt(h^2 +
// Rc^2) theta, was the bound before: up to 1.4x the pieces where h and Rc are alike.) A V-bit
// is no cylinder and keeps its points' paths. Sampling instances instead would be first order
// in the step at a sharp rim; here only the rotation is discretised.
struct TurningSplit {
  int pieces = 1;
  double pivot_mm = 0.0;  // c, above the tip along the axis
};
// The pivot and reach for the cutter's part below height_mm above the tip (+inf: all of it):
// for a flat, ball or bull-nose, the core from r to min(H - r, height + r) (a core point
// higher has its whole ball above the height) and its radius R - r, reach the larger of the
// radius and half the height; for a V-bit, its points up to min(H, height) and its radius,
// reach the hypotenuse.
void rotation_reach_mm(const Cutter& cutter, double height_mm, double& pivot_mm, double& reach_mm);
// The bound on the error of the split's pieces (mm), turning by angle_rad in all.
double rotation_error_mm(const Cutter& cutter, double height_mm, double angle_rad, const TurningSplit& split);
// The fewest pieces that keep the error within bound_mm (at least 1), for the cutter's part
// below height_mm (+inf: the whole cutter).
TurningSplit five_axis_split(const Cutter& cutter, double height_mm, const Eigen::Vector3d& axis0,
                             const Eigen::Vector3d& axis1, double bound_mm);

// Material never leaves the initial stock's box, so only the points of the tool that come
// inside it need the bound. The height above the tip (mm) over which no point of a tool of
// radius radius_mm (its widest body) comes inside `box` at any instant of the five-axis move
// from (tip0, axis0) to (tip1, axis1), in the rigid motion or in any of its pieces (their
// axes lie on the same great circle, their tips on the tip's path: a pivot off the tip takes
// them off it by at most c (phi / 2 + phi^2 / 8), for which the box is grown): +inf where the
// axis never points out through a face of the box. A point at height h and offset rho
// (|rho| <= R) from the axis is outside the face with outward normal n and offset o when
// n.p + h n.a - R sqrt(1 - (n.a)^2) > o; over the move n.p is smallest at an end, and n.a, a
// sinusoid of the arc's angle, is at least the smaller end value less angle^2 / 8 (its
// chord's error).
double highest_point_in_box_mm(double radius_mm, const Eigen::Vector3d& tip0, const Eigen::Vector3d& tip1,
                               const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1,
                               const Eigen::AlignedBox3d& box);
// `box` grown by the most any piece's tip leaves the tip's path for a move turning from axis0
// to axis1: c (angle / 2 + angle^2 / 8) with the highest pivot c any piece may have (the whole
// cutter's, or its top part's: cutter_parts, or for a ball its top half's: halved_parts) and a
// single piece (highest_point_in_box_mm on it then bounds the pieces too).
Eigen::AlignedBox3d box_for_pieces(const Cutter& cutter, const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1,
                                   const Eigen::AlignedBox3d& box);
// Appends the split's pieces of `move` (its `axis` is ignored) to `out`.
void append_five_axis_move(std::vector<Move>& out, const Move& move, const Eigen::Vector3d& axis0,
                           const Eigen::Vector3d& axis1, const TurningSplit& split);

// A long cutter's turning moves cut part by part. A ball, flat or bull-nose end mill is its
// core (the cylinder of radius Rc = R - r about the axis from r to H - r) grown by r, and the
// union of the core's parts grown by r is the cutter (a Minkowski sum takes unions apart):
// each part is an end mill of the same kind, its tip offset_mm up the axis. A part needs the
// pieces for its own reach (the larger of Rc and half its core: the bound above), so the parts
// take about as many pieces as the whole, but each piece is a short one where the whole's was
// the full length, and cuts only its own slab (append_part_pieces): the rays across the axis
// meet far fewer of them (the impeller's 3 mm ball with a 12 mm core: its cut 1.36x faster
// without its shank's probes). A ball's parts' cores are r / 2 long (W5's ball rows, r = 3
// mm, each part within its slab: parts of 2.375 mm cut 0.933x the time of parts of 3 mm, and
// nearer the answer of a turn tolerance ten times finer), a flat or bull-nose end mill's 2 Rc
// (a reach of Rc), or an eighth of the core where that is longer (every part takes a piece a
// move at least: W5's ball rows with parts of 1.19 mm for every move 0.83x, but the impeller's
// 1.014x; halved_parts below where they take no more pieces), the last one shorter; a ball whose
// core is not longer than 2r, a flat or bull-nose end mill whose core is not longer than 4 Rc,
// and a V-bit are one part, the whole.
struct CutterPart {
  Cutter cutter;
  double offset_mm = 0.0;  // the part's tip above the cutter's
};
std::vector<CutterPart> cutter_parts(const Cutter& cutter);
// Each of `parts` cut in two at the middle of its core: the same cutter in twice as many parts,
// each half as long. For a ball (reach: half its core) a turning move then needs about half the
// pieces a part, and where that rounds to no more pieces in all, each piece cuts about half the
// rays (pipeline's CutMoves takes them there: W5's ball rows, turning about 0.8 deg a move, 2
// pieces a part or 1 a half, cut 0.79x; the impeller unchanged).
std::vector<CutterPart> halved_parts(const std::vector<CutterPart>& parts);
// The split of part `part` of a turning move from axis0 to axis1: the pieces for its core's part
// below height_mm above the cutter's tip (rotation_reach_mm on the part, its height less its
// offset), the pivot measured from the cutter's tip (its own plus the offset, whose path's
// sagitta the count allows for). None (0 pieces) where the part lies wholly above the height.
TurningSplit part_split(const CutterPart& part, double height_mm, const Eigen::Vector3d& axis0,
                        const Eigen::Vector3d& axis1, double bound_mm);
// part_split for each of `parts`, and `highest`: the highest part with pieces (the one that
// append_part_pieces takes up through the cutter's top).
std::vector<TurningSplit> part_splits(const std::vector<CutterPart>& parts, double height_mm,
                                      const Eigen::Vector3d& axis0, const Eigen::Vector3d& axis1, double bound_mm,
                                      std::size_t& highest);
// Appends the pieces of a part's split (cutter index part_cutter in the move list) of `move`,
// the tool's: as append_five_axis_move with the pivot from the tool's tip, each piece's tip
// then offset_mm up its axis. Each piece's slab (Move::slab_low_mm, slab_high_mm) is the
// part's own: a point of the tool at a height its core spans (above the first part's core
// top: the tip's end; below the highest part's core bottom, `highest`: its top) lies in that
// part at the same height, offset square to the axis from the core point c there. A ball's
// core is a segment: the piece's instance carries c (the same point of the segment) within the
// bound e and the offset turned by at most phi / 2 (phi the piece's turn), so the point comes
// within e at a height off by at most r sin(phi / 2): its slab is the part's core heights grown
// by r phi / 2. A core cylinder (Rc > 0) lies within e of the piece's only as a set: the
// nearest point of the piece's core to c lies within e, at a height (the piece's frame) off by
// at most e + Rc theta + (|h| + c) theta^2 / 2 and the sagitta c phi^2 / 8 (theta <= phi / 2,
// h the height, c the pivot's), the offset adds r theta: the slab is grown by e + R phi / 2 +
// (H + |c_part| + |c|) phi^2 / 8, with e the whole part's reach phi / 2 + |c| phi^2 / 8. The
// parts' slabs cut together what their whole pieces cut, within the same bound.
void append_part_pieces(std::vector<Move>& out, const Move& move, const Eigen::Vector3d& axis0,
                        const Eigen::Vector3d& axis1, const CutterPart& part, int part_cutter,
                        const TurningSplit& split, bool highest);

// The non-cutting parts of the tools: for each cutter, the index in MoveList::cutters of its
// shank and its holder (flat cylinders, tip at their lower face), -1 where it has none, and
// the height of that face above the cutter's tip (mm).
struct ToolBody {
  int shank = -1, holder = -1;
  double shank_height_mm = 0.0, holder_height_mm = 0.0;
};
// Adds the shank and holder cylinders of every cutter in `list` to its cutters. A shank
// exists when the tool sticks out of the holder beyond its flutes, a holder when its
// diameter and length are given.
std::vector<ToolBody> add_tool_bodies(MoveList& list);
// Appends the shank and holder probes riding on `move` (a translation) to `out`: each the
// same motion raised along the tool axis to the part's lower face. Placed after the move
// itself, they meet what the cutting part left.
void append_body_probes(std::vector<Move>& out, const Move& move, const ToolBody& body);

}  // namespace vcut::removal
