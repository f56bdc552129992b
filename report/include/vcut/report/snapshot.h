// Headless pictures of a triangle mesh in the workpiece frame (mm, z up): an orthographic
// view fitted to the bounding box, z-buffered, per-vertex colours interpolated per pixel and
// shaded Lambert + ambient by a light at the camera (two-sided), depth-cued and outlined where
// the depth jumps. Identical for any thread count. The mesh is rasterised here rather than by
// Cairo, which has no depth buffer: its painter's order would need millions of triangles
// sorted, and the bands drawn in parallel keep the bytes the same for any thread count. The
// title and the colour bar are drawn with Cairo (drawing.h).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "vcut/report/image.h"
#include "vcut/removal/mesh.h"

namespace vcut::report {

// Unit vector from the scene toward the camera: "iso" (+1, -1, +1), "top" +z, "front" -y,
// "right" +x. Other names are a vcut::InputError. The screen's up is +z projected on the
// picture plane (+y when looking along z), its right is up x toward-camera.
Eigen::Vector3d view_direction(const std::string& name);

// A colour bar at the right of the picture: its label reads upward beside the bar, `ticks`
// evenly spaced values (both ends included) are written beside it with format_label.
struct ColourScale {
  std::string label;  // e.g. "deviation (mm)"
  double min_value = 0.0, max_value = 1.0;
  std::function<Rgb(double)> colour;
  int ticks = 5;
};

struct SnapshotOptions {
  int width_px = 1600, height_px = 1200;
  double margin = 0.05;   // free border around the mesh, a fraction of the smaller side
  double ambient = 0.35;  // shade = ambient + (1 - ambient) |n . l|
  // Depth cue, so that faces seen square-on still show their steps: the shade falls linearly
  // to (1 - depth_cue) times at the far end of the bounding box.
  double depth_cue = 0.25;
  bool outline = true;  // darken silhouettes and depth steps
  Rgb background{225, 225, 225};
  std::string title;  // at the top when not empty
  std::optional<ColourScale> legend;
};

// `colours` holds one colour per vertex, or is empty for a uniform light grey; any other
// size is a programmer error (std::invalid_argument). `toward_camera` need not be unit.
Image render_snapshot(const removal::TriangleMesh& mesh, const std::vector<Rgb>& colours,
                      const Eigen::Vector3d& toward_camera, const SnapshotOptions& options);

// Writes <stem>_iso.png, <stem>_top.png and <stem>_front.png into `folder` (created when
// missing), each titled "<title> (<view>)", atomically; returns those file names.
std::vector<std::string> write_snapshots(const std::string& folder, const std::string& stem,
                                         const removal::TriangleMesh& mesh, const std::vector<Rgb>& colours,
                                         const SnapshotOptions& options);

}  // namespace vcut::report
