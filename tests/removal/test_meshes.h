// Closed test meshes built by hand: prisms from a polygon in the (y, z) plane.
#pragma once

#include <Eigen/Core>

#include <array>
#include <vector>

#include "vcut/removal/mesh.h"

namespace vcut::removal::test {

// Extrudes a counter-clockwise (y, z) polygon along x over [x0, x1]; `cap` triangulates it
// (counter-clockwise index triples).
inline TriangleMesh extrude_yz(const std::vector<Eigen::Vector2d>& polygon, const std::vector<Eigen::Vector3i>& cap,
                               double x0, double x1) {
  TriangleMesh m;
  const int n = static_cast<int>(polygon.size());
  for (double x : {x0, x1})
    for (const auto& p : polygon) m.vertices_mm.emplace_back(x, p.x(), p.y());
  for (const auto& t : cap) {
    m.triangles.emplace_back(t[0] + n, t[1] + n, t[2] + n);  // +x cap
    m.triangles.emplace_back(t[0], t[2], t[1]);              // -x cap
  }
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    m.triangles.emplace_back(i, j, j + n);
    m.triangles.emplace_back(i, j + n, i + n);
  }
  return m;
}

// A box [0,length] x [0,40] x [-20,0] with a rectangular slot along x centred at y = 20,
// `half_width` wide each side and `depth` deep.
inline TriangleMesh slotted_block(double half_width, double depth, double length = 60.0) {
  const std::vector<Eigen::Vector2d> polygon = {{0, -20},
                                                {40, -20},
                                                {40, 0},
                                                {20 + half_width, 0},
                                                {20 + half_width, -depth},
                                                {20 - half_width, -depth},
                                                {20 - half_width, 0},
                                                {0, 0}};
  return extrude_yz(polygon, {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 7}}, 0.0, length);
}

inline TriangleMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const std::vector<Eigen::Vector2d> polygon = {{lo.y(), lo.z()}, {hi.y(), lo.z()}, {hi.y(), hi.z()}, {lo.y(), hi.z()}};
  return extrude_yz(polygon, {{0, 1, 2}, {0, 2, 3}}, lo.x(), hi.x());
}

}  // namespace vcut::removal::test
