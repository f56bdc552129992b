#include "vcut/io/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "vcut/io/atomic_file.h"

namespace vcut::io {
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

// The two back ends draw the same primitives.
class Canvas {
 public:
  virtual ~Canvas() = default;
  virtual void line(Point2 a, Point2 b, Rgb c, double width, bool dashed) = 0;
  virtual void polyline(const std::vector<Point2>& p, Rgb c, double width) = 0;
  virtual void rect(double x0, double y0, double x1, double y1, Rgb fill, const Rgb* stroke) = 0;
  virtual void disc(Point2 centre, double r, Rgb c) = 0;
  virtual void ring(Point2 centre, double r, Rgb c, double width) = 0;
  virtual void text(const std::string& s, Point2 at, double height, Rgb c, Align align, bool vertical) = 0;
};

class PngCanvas : public Canvas {
 public:
  explicit PngCanvas(Image& image) : image_(image) {}
  void line(Point2 a, Point2 b, Rgb c, double width, bool dashed) override {
    if (!dashed) {
      draw_line(image_, a, b, c, width);
      return;
    }
    const double length = std::hypot(b.x - a.x, b.y - a.y), dash = 8.0, gap = 5.0;
    for (double s = 0.0; s < length; s += dash + gap) {
      const double e = std::min(length, s + dash);
      draw_line(image_, {a.x + (b.x - a.x) * s / length, a.y + (b.y - a.y) * s / length},
                {a.x + (b.x - a.x) * e / length, a.y + (b.y - a.y) * e / length}, c, width);
    }
  }
  void polyline(const std::vector<Point2>& p, Rgb c, double width) override { draw_polyline(image_, p, c, width); }
  void rect(double x0, double y0, double x1, double y1, Rgb fill, const Rgb* stroke) override {
    fill_rect(image_, x0, y0, x1, y1, fill);
    if (stroke) draw_polyline(image_, {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, {x0, y0}}, *stroke, 1.0);
  }
  void disc(Point2 centre, double r, Rgb c) override { fill_circle(image_, centre, r, c); }
  void ring(Point2 centre, double r, Rgb c, double width) override {
    std::vector<Point2> p;
    for (int i = 0; i <= 64; ++i) p.push_back({centre.x + r * std::cos(i * M_PI / 32), centre.y + r * std::sin(i * M_PI / 32)});
    draw_polyline(image_, p, c, width);
  }
  void text(const std::string& s, Point2 at, double height, Rgb c, Align align, bool vertical) override {
    draw_text(image_, s, at, height, c, align, vertical ? M_PI / 2 : 0.0);
  }

 private:
  Image& image_;
};

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string colour(Rgb c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

class SvgCanvas : public Canvas {
 public:
  std::string body;
  void line(Point2 a, Point2 b, Rgb c, double width, bool dashed) override {
    body += "<line x1=\"" + num(a.x) + "\" y1=\"" + num(a.y) + "\" x2=\"" + num(b.x) + "\" y2=\"" + num(b.y) + "\" stroke=\"" +
            colour(c) + "\" stroke-width=\"" + num(width) + "\"" + (dashed ? " stroke-dasharray=\"8 5\"" : "") + "/>\n";
  }
  void polyline(const std::vector<Point2>& p, Rgb c, double width) override {
    body += "<polyline fill=\"none\" stroke=\"" + colour(c) + "\" stroke-width=\"" + num(width) +
            "\" stroke-linejoin=\"round\" points=\"";
    for (std::size_t i = 0; i < p.size(); ++i) body += (i ? " " : "") + num(p[i].x) + "," + num(p[i].y);
    body += "\"/>\n";
  }
  void rect(double x0, double y0, double x1, double y1, Rgb fill, const Rgb* stroke) override {
    body += "<rect x=\"" + num(x0) + "\" y=\"" + num(y0) + "\" width=\"" + num(x1 - x0) + "\" height=\"" + num(y1 - y0) +
            "\" fill=\"" + colour(fill) + "\"" + (stroke ? " stroke=\"" + colour(*stroke) + "\"" : std::string()) + "/>\n";
  }
  void disc(Point2 centre, double r, Rgb c) override {
    body += "<circle cx=\"" + num(centre.x) + "\" cy=\"" + num(centre.y) + "\" r=\"" + num(r) + "\" fill=\"" + colour(c) + "\"/>\n";
  }
  void ring(Point2 centre, double r, Rgb c, double width) override {
    body += "<circle cx=\"" + num(centre.x) + "\" cy=\"" + num(centre.y) + "\" r=\"" + num(r) + "\" fill=\"none\" stroke=\"" +
            colour(c) + "\" stroke-width=\"" + num(width) + "\"/>\n";
  }
  void text(const std::string& s, Point2 at, double height, Rgb c, Align align, bool vertical) override {
    const char* anchor = align == Align::kLeft ? "start" : align == Align::kCenter ? "middle" : "end";
    // The stroke font's height is that of capitals; a sans-serif's is about 0.72 em.
    body += "<text x=\"" + num(at.x) + "\" y=\"" + num(at.y) + "\" font-size=\"" + num(height / 0.72) + "\" fill=\"" + colour(c) +
            "\" text-anchor=\"" + anchor + "\"" +
            (vertical ? " transform=\"rotate(-90 " + num(at.x) + " " + num(at.y) + ")\"" : std::string()) + ">" + escape(s) +
            "</text>\n";
  }
};

void draw_panel(Canvas& canvas, const Plot& plot, std::size_t index) {
  const PlotPanel& panel = plot.panels[index];
  const PanelFrame f = panel_frame(plot, index);
  const double x0 = f.x.px_min, x1 = f.x.px_max, y0 = f.y.px_max, y1 = f.y.px_min;  // y0 top, y1 bottom
  const Rgb white{255, 255, 255};
  canvas.rect(x0, y0, x1, y1, white, nullptr);
  for (double t : f.x.ticks()) {
    const double x = f.x.to_px(t);
    canvas.line({x, y0}, {x, y1}, kGrid, 1.0, false);
    canvas.text(format_label(t), {x, y1 + 18.0}, kTickText, kMuted, Align::kCenter, false);
  }
  for (double t : f.y.ticks()) {
    const double y = f.y.to_px(t);
    canvas.line({x0, y}, {x1, y}, kGrid, 1.0, false);
    canvas.text(format_label(t), {x0 - 7.0, y + kTickText / 2.0}, kTickText, kMuted, Align::kRight, false);
  }
  canvas.polyline({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, {x0, y0}}, kFrame, 1.0);
  canvas.text(panel.title, {(x0 + x1) / 2.0, y0 - 14.0}, kPanelTitleText, kInk, Align::kCenter, false);
  canvas.text(panel.x_label, {(x0 + x1) / 2.0, y1 + 44.0}, kLabelText, kInk, Align::kCenter, false);
  canvas.text(panel.y_label, {x0 - 62.0, (y0 + y1) / 2.0}, kLabelText, kInk, Align::kCenter, true);

  for (const PlotMarkLine& m : panel.marks) {
    if (m.horizontal) {
      const double y = f.y.to_px(m.value);
      canvas.line({x0, y}, {x1, y}, m.colour, 1.5, true);
      canvas.text(m.label, {x1 - 6.0, y - 5.0}, kPointText, m.colour, Align::kRight, false);
    } else {
      const double x = f.x.to_px(m.value);
      canvas.line({x, y0}, {x, y1}, m.colour, 1.5, true);
      canvas.text(m.label, {x + 5.0, y0 + 16.0}, kPointText, m.colour, Align::kLeft, false);
    }
  }
  for (const PlotSeries& s : panel.series) {
    std::vector<Point2> px;
    for (const Point2& p : s.points)
      if (std::isfinite(p.x) && std::isfinite(p.y)) px.push_back({f.x.to_px(p.x), f.y.to_px(p.y)});
    if (s.line && px.size() > 1) canvas.polyline(px, s.colour, 2.0);
    if (s.markers)
      for (const Point2& p : px) canvas.disc(p, 4.0, s.colour);
  }
  for (const PlotSeries& s : panel.series)
    for (std::size_t i = 0; i < s.points.size() && i < s.labels.size(); ++i) {
      const Point2& p = s.points[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || s.labels[i].empty()) continue;
      canvas.text(s.labels[i], {f.x.to_px(p.x) + 7.0, f.y.to_px(p.y) - 7.0}, kPointText, kMuted, Align::kLeft, false);
    }
  for (const PlotHighlight& h : panel.highlights) {
    const Point2 p{f.x.to_px(h.at.x), f.y.to_px(h.at.y)};
    canvas.ring(p, 9.0, h.colour, 2.0);
    canvas.text(h.label, {p.x + 12.0, p.y + 20.0}, kPointText, h.colour, Align::kLeft, false);
  }

  // Legend: top right inside the frame.
  std::vector<std::pair<std::string, Rgb>> entries;
  for (const PlotSeries& s : panel.series)
    if (!s.name.empty()) entries.push_back({s.name, s.colour});
  if (entries.empty()) return;
  double text_px = 0.0;
  for (const auto& e : entries) text_px = std::max(text_px, text_width(e.first, kLabelText));
  const double row = 20.0, w = 40.0 + text_px, h = 10.0 + row * static_cast<double>(entries.size());
  // In the corner with the fewest points, labels and rings under it (top right on a tie).
  double lx = x1 - 10.0 - w, ly = y0 + 10.0;
  int fewest = std::numeric_limits<int>::max();
  for (const Point2 corner : {Point2{x1 - 10.0 - w, y0 + 10.0}, Point2{x0 + 10.0, y0 + 10.0}, Point2{x1 - 10.0 - w, y1 - 10.0 - h},
                              Point2{x0 + 10.0, y1 - 10.0 - h}}) {
    int under = 0;
    auto count = [&](double x, double y, double margin) {
      under += x > corner.x - margin && x < corner.x + w + margin && y > corner.y - margin && y < corner.y + h + margin;
    };
    for (const PlotSeries& s : panel.series)
      for (std::size_t i = 0; i < s.points.size(); ++i) {
        const Point2& p = s.points[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
        const double x = f.x.to_px(p.x), y = f.y.to_px(p.y);
        count(x, y, 6.0);
        if (i < s.labels.size() && !s.labels[i].empty()) count(x + 7.0 + text_width(s.labels[i], kPointText), y - 7.0, 4.0);
      }
    for (const PlotHighlight& hl : panel.highlights) count(f.x.to_px(hl.at.x), f.y.to_px(hl.at.y), 12.0);
    if (under < fewest) {
      fewest = under;
      lx = corner.x;
      ly = corner.y;
    }
  }
  const Rgb legend_fill{250, 250, 250};
  canvas.rect(lx, ly, lx + w, ly + h, legend_fill, &kFrame);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const double y = ly + 5.0 + row * (static_cast<double>(i) + 0.5);
    canvas.line({lx + 8.0, y}, {lx + 28.0, y}, entries[i].second, 2.0, false);
    canvas.disc({lx + 18.0, y}, 3.5, entries[i].second);
    canvas.text(entries[i].first, {lx + 34.0, y + kLabelText / 2.0}, kLabelText, kInk, Align::kLeft, false);
  }
}

void draw_plot(Canvas& canvas, const Plot& plot) {
  canvas.rect(0, 0, plot.width_px, plot.height_px, {255, 255, 255}, nullptr);
  canvas.text(plot.title, {plot.width_px / 2.0, 34.0}, kTitleText, kInk, Align::kCenter, false);
  for (std::size_t i = 0; i < plot.panels.size(); ++i) draw_panel(canvas, plot, i);
  if (!plot.footnote.empty())
    canvas.text(plot.footnote, {16.0, plot.height_px - 14.0}, kTickText, kMuted, Align::kLeft, false);
}

}  // namespace

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
  const int d0 = static_cast<int>(std::ceil(std::log10(min) - 1e-9)), d1 = static_cast<int>(std::floor(std::log10(max) + 1e-9));
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
  for (const PlotMarkLine& m : panel.marks) (m.horizontal ? ey : ex).add(m.value, m.horizontal ? panel.log_y : panel.log_x);
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
  SvgCanvas canvas;
  draw_plot(canvas, plot);
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" +
         std::to_string(plot.width_px) + "\" height=\"" + std::to_string(plot.height_px) + "\" viewBox=\"0 0 " +
         std::to_string(plot.width_px) + " " + std::to_string(plot.height_px) +
         "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n" + canvas.body + "</svg>\n";
}

Image render_png(const Plot& plot) {
  Image image(plot.width_px, plot.height_px);
  PngCanvas canvas(image);
  draw_plot(canvas, plot);
  return image;
}

void write_plot(const std::string& svg_path, const std::string& png_path, const Plot& plot) {
  write_text_atomically(svg_path, render_svg(plot));
  write_png(png_path, render_png(plot));
}

}  // namespace vcut::io
