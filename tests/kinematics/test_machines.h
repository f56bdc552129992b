// Machines of every kind the pose engine must serve, built in code for the kinematics
// tests (the bundled YAML files are tested through io): the six kinds of issue #3 plus a
// 45-degree nutating head.
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "vcut/kinematics/machine.h"

namespace vcut::kinematics {

constexpr double kDeg = M_PI / 180.0;

inline AxisSpec linear(char letter, Eigen::Vector3d direction, double lo, double hi) {
  AxisSpec a;
  a.letter = letter;
  a.kind = AxisKind::Linear;
  a.direction = direction.normalized();
  a.limits = std::make_pair(lo, hi);
  return a;
}

inline AxisSpec rotary(char letter, Eigen::Vector3d axis, Eigen::Vector3d center, double lo_deg, double hi_deg) {
  AxisSpec a;
  a.letter = letter;
  a.kind = AxisKind::Rotary;
  a.direction = axis.normalized();
  a.center_mm = center;
  if (lo_deg < hi_deg) a.limits = std::make_pair(lo_deg * kDeg, hi_deg * kDeg);
  return a;
}

constexpr double kContinuous = 0.0;  // lo = hi = 0: no limits

inline MachineSpec spec(const std::string& name, const std::string& topology, std::vector<AxisSpec> axes,
                        Eigen::Vector3d gauge = Eigen::Vector3d::Zero(),
                        Eigen::Vector3d origin = Eigen::Vector3d::Zero()) {
  MachineSpec s;
  s.name = name;
  s.topology = topology;
  s.axes = std::move(axes);
  s.gauge_point_mm = gauge;
  s.workpiece_origin_mm = origin;
  return s;
}

// One machine of each kind the issue names, plus a nutating (45 deg) head, which no
// special-case solver would cover.
inline std::vector<MachineSpec> machines() {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  std::vector<MachineSpec> out;
  out.push_back(
      spec("3axis", "WXYFZT", {linear('X', -x, -400, 400), linear('Y', -y, -250, 250), linear('Z', z, -300, 200)}));
  out.push_back(spec("trt-ac", "WCAFXYZT",
                     {linear('X', x, -300, 300), linear('Y', y, -300, 300), linear('Z', z, -300, 300),
                      rotary('A', x, {0, 20, 10}, -120, 30), rotary('C', z, {0, 0, 0}, kContinuous, kContinuous)},
                     {0, 0, 150}, {5, -3, 40}));
  out.push_back(spec("trt-bc", "WCBFXYZT",
                     {linear('X', x, -300, 300), linear('Y', y, -300, 300), linear('Z', z, -300, 300),
                      rotary('B', y, {0, 0, 50}, -110, 110), rotary('C', z, {1, 2, 0}, -360, 360)},
                     {0, 0, 200}));
  out.push_back(spec("head-table", "WCFXYZBT",
                     {linear('X', x, -500, 500), linear('Y', y, -500, 500), linear('Z', z, -500, 500),
                      rotary('B', y, {0, 0, 150}, -100, 100), rotary('C', z, {0, 0, 0}, kContinuous, kContinuous)},
                     {0, 0, 0}, {0, 0, 20}));
  out.push_back(spec("head-head", "WFXYZCAT",
                     {linear('X', x, -800, 800), linear('Y', y, -800, 800), linear('Z', z, -800, 800),
                      rotary('C', z, {0, 0, 0}, -360, 360), rotary('A', x, {0, 0, 180}, -110, 110)}));
  out.push_back(spec("gantry", "WYXZCAT",
                     {linear('Y', y, -2000, 2000), linear('X', x, -3000, 3000), linear('Z', z, -1500, 1000),
                      rotary('C', z, {0, 0, 2800}, -360, 360), rotary('A', x, {0, -75, 2800}, -110, 110)},
                     {0, 0, 2400}));
  out.push_back(spec("nutating", "WCFXYZBT",
                     {linear('X', x, -500, 500), linear('Y', y, -500, 500), linear('Z', z, -500, 500),
                      rotary('B', Eigen::Vector3d(0, -1, 1), {0, 0, 120}, -180, 180),
                      rotary('C', z, {0, 0, 0}, kContinuous, kContinuous)}));
  return out;
}

}  // namespace vcut::kinematics
