#include "vcut/report/plot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "vcut/io/atomic_file.h"

namespace vcut::report {
namespace {

// Layout (px): the title band on top, the footnote band below, and in each panel the room
// for its title, tick labels and axis labels around the frame.
constexpr double kTop = 84.0, kBottom = 84.0, kLeft = 86.0, kRight = 64.0;  // right: room for point labels
constexpr double kTitleText = 18.0, kPanelTitleText = 14.0, kLabelText = 12.0, kTickText = 11.0, kPointText = 10.0;
const Rgb kInk{40, 40, 40}, kGrid{228, 228, 228}, kFrame{150, 150, 150}, kMuted{90, 90, 90};

// What a panel's axis covers: the finite values it must show.
struct Extent {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v, bool log) {
    if (!std::isfinite(v) || (log && v <= 0.0)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return lo > hi; }
};

PlotAxis make_axis(Extent e, bool log, double px_min, double px_max) {
  PlotAxis a;
  a.log = log;
  a.px_min = px_min;
  a.px_max = px_max;
  if (log) {
    double l0 = e.empty() ? -6.0 : std::log10(e.lo), l1 = e.empty() ? 0.0 : std::log10(e.hi);
    if (l1 - l0 < 1e-9) {
      l0 -= 0.5;
      l1 += 0.5;
    }
    const double pad = 0.08 * (l1 - l0);
    a.min = std::pow(10.0, l0 - pad);
    a.max = std::pow(10.0, l1 + pad);
    return a;
  }
  double lo = e.empty() ? 0.0 : e.lo, hi = e.empty() ? 1.0 : e.hi;
  if (hi - lo < 1e-12 * std::max(1.0, std::abs(lo))) {
    const double half = std::max(1e-9, 0.1 * std::abs(lo));
    lo -= half;
    hi += half;
  }
  const double pad = 0.05 * (hi - lo);
  a.min = lo - pad;
  a.max = hi + pad;
  return a;
}

std::vector<double> linear_ticks(double lo, double hi) {
  std::vector<double> out;
  const double raw = (hi - lo) / 5.0;
  if (!(raw > 0.0) || !std::isfinite(raw)) return out;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10.0 * decade;
  for (double m : {1.0, 2.0, 5.0})
    if (m * decade >= raw) {
      step = m * decade;
      break;
    }
  for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * step; k += 1.0) {
    const double v = k * step;
    out.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  }
  return out;
}

// Tick labels with as many significant digits as it takes to tell neighbours apart (a narrow
// range, 0.001 to 0.00102, needs more than the usual 3).
std::vector<std::string> tick_labels(const std::vector<double>& ticks) {
  std::vector<std::string> labels;
  for (int digits = 3; digits <= 12; ++digits) {
    labels.clear();
    for (double t : ticks) labels.push_back(format_label(t, digits));
    if (std::adjacent_find(labels.begin(), labels.end()) == labels.end()) break;
  }
  return labels;
}

// ---- Label placement ------------------------------------------------------------------------
// Each label tries a few spots around what it names and takes the first with the least clutter
// under it. A label's box is its advance width, the cap height above the baseline and a third
// of it below (DejaVu Sans's descenders reach 0.32 of the cap height).

struct Box {
  double x0, y0, x1, y1;
};

Box text_box(const std::string& text, Point2 at, double height_px, Align align) {
  const double w = text_width(text, height_px);
  const double left = align == Align::kLeft ? at.x : align == Align::kCenter ? at.x - w / 2 : at.x - w;
  return {left, at.y - height_px, left + w, at.y + height_px / 3.0};
}

Box around(Point2 p, double r) { return {p.x - r, p.y - r, p.x + r, p.y + r}; }

double overlap_area(const Box& a, const Box& b) {
  const double w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
  const double h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
  return w > 0.0 && h > 0.0 ? w * h : 0.0;
}

bool within(const Box& inner, const Box& outer) {
  return inner.x0 >= outer.x0 && inner.x1 <= outer.x1 && inner.y0 >= outer.y0 && inner.y1 <= outer.y1;
}

// Whether the segment ab passes through the box (Liang-Barsky clipping).
bool crosses(Point2 a, Point2 b, const Box& box) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a.x - box.x0, box.x1 - a.x, a.y - box.y0, box.y1 - a.y};
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0)
      t0 = std::max(t0, t);  // entering
    else
      t1 = std::min(t1, t);  // leaving
    if (t0 > t1) return false;
  }
  return true;
}

struct Spot {
  Point2 at;  // baseline
  Align align;
};

class LabelPlacer {
 public:
  explicit LabelPlacer(Box area) : area_(area) {}
  void add_text(const Box& b) { text_.push_back(b); }   // never covered by a label
  void add_mark(const Box& b) { marks_.push_back(b); }  // covered only when nothing else fits
  void add_line(Point2 a, Point2 b) { lines_.push_back({a, b}); }

  // The first of `spots` with the least clutter under it, its box then taken. A label that
  // would leave the area or cover other text gets no spot, unless `always`: then the least
  // bad one.
  std::optional<Spot> place(const std::string& text, double height_px, const std::vector<Spot>& spots, bool always) {
    std::optional<Spot> best;
    double best_cost = std::numeric_limits<double>::infinity();
    for (const Spot& s : spots) {
      const Box b = text_box(text, s.at, height_px, s.align);
      // Hard faults (outside, over text) outweigh any clutter of markers and lines.
      double cost = within(b, area_) ? 0.0 : 1e9;
      for (const Box& t : text_) cost += 1e6 * overlap_area(b, t);
      // Covering a marker hides data; crossing a line only makes the text harder to read.
      for (const Box& m : marks_) cost += 10.0 * overlap_area(b, m);
      for (const auto& [p, q] : lines_) cost += crosses(p, q, b) ? 20.0 : 0.0;
      if (cost < best_cost) best_cost = cost, best = s;
    }
    if (!best || (!always && best_cost >= 1e6)) return std::nullopt;
    text_.push_back(text_box(text, best->at, height_px, best->align));
    return best;
  }

 private:
  Box area_;
  std::vector<Box> text_, marks_;
  std::vector<std::array<Point2, 2>> lines_;
};

// Spots beside a marker of radius r: right, left, above, below, the upper ones first.
std::vector<Spot> spots_beside(Point2 p, double r, double height_px) {
  const double gap = r + 2.0, below = p.y + gap + height_px, above = p.y - gap;
  return {{{p.x + gap, above}, Align::kLeft},
          {{p.x + gap, below}, Align::kLeft},
          {{p.x - gap, above}, Align::kRight},
          {{p.x - gap, below}, Align::kRight},
          {{p.x, above - 2.0}, Align::kCenter},
          {{p.x, below + 2.0}, Align::kCenter},
          {{p.x + gap + 2.0, p.y + height_px / 2.0}, Align::kLeft},
          {{p.x - gap - 2.0, p.y + height_px / 2.0}, Align::kRight}};
}

// Spots along a mark line at pixel `at_px` (a row when horizontal, else a column): near its
// right (or top) end first.
std::vector<Spot> spots_along_mark(bool horizontal, double at_px, const Box& frame) {
  const double h = kPointText;
  if (!horizontal)
    return {{{at_px + 5.0, frame.y0 + 16.0}, Align::kLeft},
            {{at_px - 5.0, frame.y0 + 16.0}, Align::kRight},
            {{at_px + 5.0, frame.y1 - 8.0}, Align::kLeft},
            {{at_px - 5.0, frame.y1 - 8.0}, Align::kRight}};
  const double mid = (frame.x0 + frame.x1) / 2.0, above = at_px - 5.0, below = at_px + 5.0 + h;
  return {{{frame.x1 - 6.0, above}, Align::kRight}, {{frame.x1 - 6.0, below}, Align::kRight},
          {{frame.x0 + 6.0, above}, Align::kLeft},  {{frame.x0 + 6.0, below}, Align::kLeft},
          {{mid, above}, Align::kCenter},           {{mid, below}, Align::kCenter}};
}

constexpr double kMarkerRadius = 4.0, kRingRadius = 9.0, kLegendRow = 20.0;

void draw_panel(Drawing& drawing, const Plot& plot, std::size_t index) {
  const PlotPanel& panel = plot.panels[index];
  const PanelFrame f = panel_frame(plot, index);
  const double x0 = f.x.px_min, x1 = f.x.px_max, y0 = f.y.px_max, y1 = f.y.px_min;  // y0 top, y1 bottom
  const Rgb white{255, 255, 255};
  drawing.rect(x0, y0, x1, y1, white, nullptr);
  const std::vector<double> x_ticks = f.x.ticks(), y_ticks = f.y.ticks();
  const std::vector<std::string> x_labels = tick_labels(x_ticks), y_labels = tick_labels(y_ticks);
  for (std::size_t i = 0; i < x_ticks.size(); ++i) {
    const double x = f.x.to_px(x_ticks[i]);
    drawing.line({x, y0}, {x, y1}, kGrid, 1.0, false);
    drawing.text(x_labels[i], {x, y1 + 18.0}, kTickText, kMuted, Align::kCenter);
  }
  for (std::size_t i = 0; i < y_ticks.size(); ++i) {
    const double y = f.y.to_px(y_ticks[i]);
    drawing.line({x0, y}, {x1, y}, kGrid, 1.0, false);
    drawing.text(y_labels[i], {x0 - 7.0, y + kTickText / 2.0}, kTickText, kMuted, Align::kRight);
  }
  drawing.polyline({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, {x0, y0}}, kFrame, 1.0);
  drawing.text(panel.title, {(x0 + x1) / 2.0, y0 - 14.0}, kPanelTitleText, kInk, Align::kCenter);
  drawing.text(panel.x_label, {(x0 + x1) / 2.0, y1 + 44.0}, kLabelText, kInk, Align::kCenter);
  drawing.text(panel.y_label, {x0 - 62.0, (y0 + y1) / 2.0}, kLabelText, kInk, Align::kCenter, M_PI / 2);

  const auto finite = [](const Point2& p) { return std::isfinite(p.x) && std::isfinite(p.y); };
  const auto to_px = [&](const Point2& p) { return Point2{f.x.to_px(p.x), f.y.to_px(p.y)}; };
  // Labels may use the margin kept right of the frame, short of the next panel's axis labels.
  LabelPlacer placer({x0 + 2.0, y0 + 2.0, x1 + kRight - 6.0, y1 - 2.0});

  for (const PlotMarkLine& m : panel.marks) {
    if (!std::isfinite(m.value)) continue;
    Point2 a{x0, f.y.to_px(m.value)}, b{x1, a.y};
    if (!m.horizontal) a = {f.x.to_px(m.value), y0}, b = {a.x, y1};
    drawing.line(a, b, m.colour, 1.5, true);
    placer.add_line(a, b);
  }
  for (const PlotSeries& s : panel.series) {
    std::vector<Point2> px;
    for (const Point2& p : s.points)
      if (finite(p)) px.push_back(to_px(p));
    if (s.line && px.size() > 1) {
      drawing.polyline(px, s.colour, 2.0);
      for (std::size_t i = 1; i < px.size(); ++i) placer.add_line(px[i - 1], px[i]);
    }
    for (const Point2& p : px) {
      if (s.markers) drawing.disc(p, kMarkerRadius, s.colour);
      placer.add_mark(around(p, kMarkerRadius));
    }
  }
  for (const PlotHighlight& h : panel.highlights) {
    if (!finite(h.at)) continue;
    const Point2 p = to_px(h.at);
    drawing.ring(p, kRingRadius, h.colour, 2.0);
    placer.add_mark(around(p, kRingRadius + 1.0));
  }

  // The labels, the most important first: marks, highlights, then the points in series order.
  // A point label with no free spot is left out rather than drawn over other text.
  struct Label {
    std::string text;
    Spot spot;
    Rgb colour;
  };
  const auto place_labels = [&](LabelPlacer p, std::size_t& left_out) {
    std::vector<Label> out;
    left_out = 0;
    for (const PlotMarkLine& m : panel.marks) {
      if (!std::isfinite(m.value) || m.label.empty()) continue;
      const double at_px = m.horizontal ? f.y.to_px(m.value) : f.x.to_px(m.value);
      const std::vector<Spot> spots = spots_along_mark(m.horizontal, at_px, {x0, y0, x1, y1});
      if (const auto spot = p.place(m.label, kPointText, spots, true)) out.push_back({m.label, *spot, m.colour});
    }
    for (const PlotHighlight& hl : panel.highlights) {
      if (!finite(hl.at) || hl.label.empty()) continue;
      const std::vector<Spot> spots = spots_beside(to_px(hl.at), kRingRadius, kPointText);
      if (const auto spot = p.place(hl.label, kPointText, spots, true)) out.push_back({hl.label, *spot, hl.colour});
    }
    for (const PlotSeries& s : panel.series)
      for (std::size_t i = 0; i < s.points.size() && i < s.labels.size(); ++i) {
        if (!finite(s.points[i]) || s.labels[i].empty()) continue;
        const std::vector<Spot> spots = spots_beside(to_px(s.points[i]), kMarkerRadius, kPointText);
        if (const auto spot = p.place(s.labels[i], kPointText, spots, false))
          out.push_back({s.labels[i], *spot, kMuted});
        else
          ++left_out;
      }
    return out;
  };

  // Legend: in the corner where the fewest points and rings lie under it and the fewest labels
  // are left out for it; top right on a tie.
  std::vector<std::pair<std::string, Rgb>> entries;
  for (const PlotSeries& s : panel.series)
    if (!s.name.empty()) entries.push_back({s.name, s.colour});
  std::size_t left_out = 0;
  std::vector<Label> labels = place_labels(placer, left_out);
  Box legend{};
  if (!entries.empty()) {
    double text_px = 0.0;
    for (const auto& e : entries) text_px = std::max(text_px, text_width(e.first, kLabelText));
    const double w = 40.0 + text_px, h = 10.0 + kLegendRow * static_cast<double>(entries.size());
    std::size_t fewest = std::numeric_limits<std::size_t>::max();
    for (const Point2 corner : {Point2{x1 - 10.0 - w, y0 + 10.0}, Point2{x0 + 10.0, y0 + 10.0},
                                Point2{x1 - 10.0 - w, y1 - 10.0 - h}, Point2{x0 + 10.0, y1 - 10.0 - h}}) {
      const Box box{corner.x, corner.y, corner.x + w, corner.y + h};
      LabelPlacer with_legend = placer;
      with_legend.add_text(box);
      std::size_t under = 0;
      std::vector<Label> placed = place_labels(with_legend, under);
      for (const PlotSeries& s : panel.series)
        for (const Point2& p : s.points)
          if (finite(p)) under += overlap_area(around(to_px(p), kMarkerRadius + 2.0), box) > 0.0;
      for (const PlotHighlight& hl : panel.highlights)
        if (finite(hl.at)) under += overlap_area(around(to_px(hl.at), kRingRadius + 3.0), box) > 0.0;
      if (under < fewest) fewest = under, legend = box, labels = std::move(placed);
    }
  }

  for (const Label& l : labels) drawing.text(l.text, l.spot.at, kPointText, l.colour, l.spot.align);
  if (entries.empty()) return;
  const Rgb legend_fill{250, 250, 250};
  drawing.rect(legend.x0, legend.y0, legend.x1, legend.y1, legend_fill, &kFrame);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const double y = legend.y0 + 5.0 + kLegendRow * (static_cast<double>(i) + 0.5);
    drawing.line({legend.x0 + 8.0, y}, {legend.x0 + 28.0, y}, entries[i].second, 2.0, false);
    drawing.disc({legend.x0 + 18.0, y}, 3.5, entries[i].second);
    drawing.text(entries[i].first, {legend.x0 + 34.0, y + kLabelText / 2.0}, kLabelText, kInk, Align::kLeft);
  }
}

}  // namespace

void draw_plot(Drawing& drawing, const Plot& plot) {
  drawing.rect(0, 0, plot.width_px, plot.height_px, {255, 255, 255}, nullptr);
  drawing.text(plot.title, {plot.width_px / 2.0, 34.0}, kTitleText, kInk, Align::kCenter);
  for (std::size_t i = 0; i < plot.panels.size(); ++i) draw_panel(drawing, plot, i);
  if (!plot.footnote.empty())
    drawing.text(plot.footnote, {16.0, plot.height_px - 14.0}, kTickText, kMuted, Align::kLeft);
}

double PlotAxis::to_px(double value) const {
  double t;
  if (log) {
    const double v = value > min ? value : min;
    t = (std::log10(v) - std::log10(min)) / (std::log10(max) - std::log10(min));
  } else {
    t = (value - min) / (max - min);
  }
  return px_min + t * (px_max - px_min);
}

std::vector<double> PlotAxis::ticks() const {
  if (!log) return linear_ticks(min, max);
  std::vector<double> out;
  const int d0 = static_cast<int>(std::ceil(std::log10(min) - 1e-9)),
            d1 = static_cast<int>(std::floor(std::log10(max) + 1e-9));
  const bool fill = d1 - d0 + 1 < 3;
  for (int d = d0 - 1; d <= d1; ++d)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fill) continue;
      const double v = m * std::pow(10.0, d);
      if (v >= min * (1 - 1e-9) && v <= max * (1 + 1e-9)) out.push_back(v);
    }
  if (out.size() < 2) return linear_ticks(min, max);
  return out;
}

PanelFrame panel_frame(const Plot& plot, std::size_t index) {
  const PlotPanel& panel = plot.panels.at(index);
  const double width = static_cast<double>(plot.width_px) / static_cast<double>(plot.panels.size());
  const double left = width * static_cast<double>(index);
  Extent ex, ey;
  for (const PlotSeries& s : panel.series)
    for (const Point2& p : s.points) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
      ex.add(p.x, panel.log_x);
      ey.add(p.y, panel.log_y);
    }
  for (const PlotMarkLine& m : panel.marks)
    (m.horizontal ? ey : ex).add(m.value, m.horizontal ? panel.log_y : panel.log_x);
  for (const PlotHighlight& h : panel.highlights) {
    ex.add(h.at.x, panel.log_x);
    ey.add(h.at.y, panel.log_y);
  }
  PanelFrame f;
  f.x = make_axis(ex, panel.log_x, left + kLeft, left + width - kRight);
  f.y = make_axis(ey, panel.log_y, plot.height_px - kBottom, kTop);
  return f;
}

std::string render_svg(const Plot& plot) {
  Drawing drawing = Drawing::svg(plot.width_px, plot.height_px);
  draw_plot(drawing, plot);
  return drawing.svg();
}

Image render_png(const Plot& plot) {
  Drawing drawing{Image(plot.width_px, plot.height_px)};
  draw_plot(drawing, plot);
  return drawing.image();
}

void write_plot(const std::string& svg_path, const std::string& png_path, const Plot& plot) {
  io::write_text_atomically(svg_path, render_svg(plot));
  write_png(png_path, render_png(plot));
}

}  // namespace vcut::report
