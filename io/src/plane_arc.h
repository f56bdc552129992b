// The geometry of a programmed arc in its plane, as the G-code and SINUMERIK readers share it
// (rs274ngc's and Siemens' rules agree). Points are the plane's two coordinates, mm. Each
// function returns an error message (empty when the arc is fine); the reader names the place.
// Internal to vcut::io.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <string>

#include "reader_util.h"

namespace vcut::io::detail {

// Points closer than this coincide (full circles, zero radius): far below any machine's
// resolution, far above the rounding of mm values up to 1e6 mm (~1e-10).
inline constexpr double kSamePointMm = 1e-9;
// Radius arcs: |R| may fall short of half the chord by this times max(1, |R|) before it is an
// error; this only absorbs rounding of the printed values.
inline constexpr double kRadiusRoundingRelative = 1e-9;
// Centre arcs: a radius mismatch is allowed up to the reader's absolute tolerance, or up to
// `relative` times the larger radius while it stays within `ceiling_mm` (LinuxCNC 2.9: 0.1 %
// up to 100 x the absolute tolerance; SINUMERIK: $MN_CIRCLE_ERROR_FACTOR 0.1 %, no ceiling).
struct ArcTolerance {
  double absolute_mm = 0.0;
  double relative = 0.0;
  double ceiling_mm = 0.0;
  double allowed_mm(double radius_mm) const {
    return std::max(absolute_mm, std::min(ceiling_mm, relative * radius_mm));
  }
};

// A centre arc from s to e about `center`: both ends off the centre and equally far from it
// within the tolerance. `code` is "G2" or "G3".
inline std::string centre_arc_error(const Eigen::Vector2d& s, const Eigen::Vector2d& e, const Eigen::Vector2d& center,
                                    const ArcTolerance& tolerance, const std::string& code) {
  const double r_start = (s - center).norm(), r_end = (e - center).norm();
  if (r_start <= kSamePointMm || r_end <= kSamePointMm) {
    return "zero-radius " + code + " arc (expected the centre away from the start and the end)";
  }
  const double allowed = tolerance.allowed_mm(std::max(r_start, r_end));
  if (std::abs(r_end - r_start) > allowed) {
    return code + " arc end is not on its circle: radius " + num(r_start) + " mm at the start, " + num(r_end) +
           " mm at the end (expected equal within " + num(allowed) + " mm)";
  }
  return {};
}

// The centre of a radius arc: on the chord's perpendicular bisector, to the right of s -> e
// for G2 with a positive radius or G3 with a negative one (negative: the arc longer than 180
// deg). `word` is the radius word as written ("R", "CR=") and `centre_words` the centre's
// ("I/J/K"), for the messages. |R| may fall short of half the chord by short_tolerance_mm
// (LinuxCNC: 0.00005 in = 0.00127 mm); the arc is then a half circle.
inline std::string radius_arc_centre(const Eigen::Vector2d& s, const Eigen::Vector2d& e, double radius, bool clockwise,
                                     const std::string& code, const std::string& word, const std::string& centre_words,
                                     Eigen::Vector2d& center, double short_tolerance_mm = 0.0) {
  const Eigen::Vector2d d = e - s;
  const double chord = d.norm();
  if (chord <= kSamePointMm) {
    return code + " " + word + " arc that ends where it starts (expected " + centre_words + " for a full circle)";
  }
  const double abs_r = std::abs(radius);
  const std::string name = word.back() == '=' ? word.substr(0, word.size() - 1) : word;
  double half = chord / 2.0;
  if (half - abs_r > std::max(short_tolerance_mm, kRadiusRoundingRelative * std::max(1.0, abs_r))) {
    return "arc radius |" + name + "| = " + num(abs_r) + " mm is less than half the chord, " + num(half) +
           " mm (expected |" + name + "| >= " + num(half) + " mm)";
  }
  half = std::min(half, abs_r);
  const double to_center = std::sqrt((abs_r - half) * (abs_r + half));
  const Eigen::Vector2d left = Eigen::Vector2d(-d.y(), d.x()) / chord;
  const bool right = (clockwise && radius > 0.0) || (!clockwise && radius < 0.0);
  center = (s + e) / 2.0 + (right ? -to_center : to_center) * left;
  return {};
}

}  // namespace vcut::io::detail
