// A rotating cutter's cutting part as a solid, in the tool frame: tip (lowest point on the
// axis) at the origin, axis +Z toward the spindle. Lengths in mm.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <string>

namespace vcut::removal {

// VBit: a pointed chamfer (engraving) cutter, a cone of `tip_angle_deg` included angle up to
// the diameter, then a cylinder up to the flute length.
enum class CutterType { Flat, Ball, BullNose, VBit };

struct Cutter {
  CutterType type = CutterType::Flat;
  double diameter_mm = 0.0;
  double corner_radius_mm = 0.0;  // 0 flat, diameter/2 ball, in between bull-nose
  double flute_length_mm = 0.0;   // height of the cutting part above the tip
  double shank_diameter_mm = 0.0;
  double length_mm = 0.0;        // out of the holder
  double gauge_length_mm = 0.0;  // spindle nose (gauge line) to tip, for the machine's kinematics
  double tip_angle_deg = 0.0;    // VBit: included angle of the cone, (0, 180)
  // The holder, a cylinder from `length_mm` up along the axis; 0 = none given (not checked).
  double holder_diameter_mm = 0.0;
  double holder_length_mm = 0.0;
  // A holder model instead (the machine check): a closed mesh whose origin is the spindle nose
  // (gauge line), +z into the spindle, the holder hanging below it. Empty: none.
  std::string holder_mesh_file;

  double radius_mm() const { return 0.5 * diameter_mm; }
};

// Radius of the cutter's cross-section at height h above the tip (0 outside [0, flute length]).
double section_radius(const Cutter& cutter, double h_mm);
// Height above the tip of the cutter's underside at distance rho from the axis (rho <= R).
double underside_height(const Cutter& cutter, double rho_mm);

// The cutting part as a rounded cylinder: a core cylinder K of radius R - r spanning
// z in [r, max(r, H - r)] grown by a ball of radius r (seed 003's tool model: every APT
// end mill of this family is such a Minkowski sum). Its top is rounded too; the top lies
// at the flute length, where the shank takes over.
struct CutterCore {
  double core_radius_mm;  // R - r
  double z_low_mm;        // r
  double z_high_mm;       // max(r, H - r)
  double rounding_mm;     // r
};

// A V-bit is not such a sum: its core is its bounding cylinder (radius R, z in [0, H]), used
// for bounds only.
CutterCore core_of(const Cutter& cutter);

// section_radius of a cutter that is not a V-bit, from its core (worked out once): the core's
// radius plus the rounding's half-chord at height h_mm (0 below the tip or above the flutes).
inline double core_section_radius(const CutterCore& k, double flute_length_mm, double h_mm) {
  if (h_mm < 0.0 || h_mm > flute_length_mm) return 0.0;
  const double off = h_mm < k.z_low_mm ? k.z_low_mm - h_mm : (h_mm > k.z_high_mm ? h_mm - k.z_high_mm : 0.0);
  return k.core_radius_mm + std::sqrt(std::max(0.0, k.rounding_mm * k.rounding_mm - off * off));
}

// Signed distance (mm, negative inside) from a tool-frame point to the cutting part.
double cutter_distance(const Cutter& cutter, const Eigen::Vector3d& p_tool_mm);

std::string to_string(CutterType type);

}  // namespace vcut::removal
