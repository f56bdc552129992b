// Line charts for studies, as SVG and PNG drawn one way (drawing.h): panels side by side, each with
// linear or log axes, series of points (joined, with markers and labels), dashed marks at a
// value and rings around chosen points.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "vcut/report/drawing.h"
#include "vcut/report/image.h"

namespace vcut::report {

struct PlotSeries {
  std::string name;  // in the panel's legend
  Rgb colour{31, 119, 180};
  std::vector<Point2> points;       // data coordinates, in the given order
  bool line = true;                 // join the points
  bool markers = true;              // a filled circle at each point
  std::vector<std::string> labels;  // empty, or one short label per point written beside it
};

// A dashed horizontal (y = value) or vertical (x = value) line across the panel, labelled.
struct PlotMarkLine {
  bool horizontal = true;
  double value = 0.0;
  std::string label;
  Rgb colour{200, 40, 40};
};

// A ring drawn around one data point, with a label (e.g. the recommended setting).
struct PlotHighlight {
  Point2 at;
  std::string label;
  Rgb colour{0, 150, 60};
};

struct PlotPanel {
  std::string title, x_label, y_label;
  bool log_x = false, log_y = false;
  std::vector<PlotSeries> series;
  std::vector<PlotMarkLine> marks;
  std::vector<PlotHighlight> highlights;
};

struct Plot {
  std::string title;              // over all panels
  std::vector<PlotPanel> panels;  // side by side, equal widths
  std::string footnote;           // one line at the bottom, may be empty
  int width_px = 1400, height_px = 620;
};

// A panel axis: data -> pixel. Log axes map log10(value); values <= 0 (or below the range)
// on a log axis are drawn at the axis minimum.
struct PlotAxis {
  double min = 0.0, max = 1.0;  // data range shown
  bool log = false;
  double px_min = 0.0, px_max = 1.0;  // pixel positions of min and max (y: px_min is the bottom)
  double to_px(double value) const;
  // "Nice" values within [min, max]: steps of 1, 2 or 5 times a power of ten (about 5 of
  // them); log: the decades, with 2 and 5 between them when fewer than 3 decades are shown.
  std::vector<double> ticks() const;
};

// The axes of panel `index` as laid out in a plot of this size (shared by SVG and PNG).
struct PanelFrame {
  PlotAxis x, y;
};
PanelFrame panel_frame(const Plot& plot, std::size_t index);

// The plot drawn onto a drawing of its size; render_svg and render_png draw it this one way.
void draw_plot(Drawing& drawing, const Plot& plot);
std::string render_svg(const Plot& plot);  // a complete standalone SVG document
Image render_png(const Plot& plot);
// Writes both files atomically (temporary then rename); errors are vcut::InputError naming
// the path.
void write_plot(const std::string& svg_path, const std::string& png_path, const Plot& plot);

}  // namespace vcut::report
