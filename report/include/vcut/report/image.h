// 8-bit RGB raster images, PNG output, and a small anti-aliased 2D canvas for plots: lines,
// rectangles, circles and text in a built-in stroke font. Coordinates are pixels, x right,
// y down; pixel (i, j) covers [i, i+1) x [j, j+1), its centre is (i + 0.5, j + 0.5).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vcut::report {

using Rgb = std::array<std::uint8_t, 3>;

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // row-major from the top-left, 3 bytes a pixel

  Image() = default;
  Image(int width, int height, Rgb fill = {255, 255, 255});

  bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  Rgb get(int x, int y) const;
  void set(int x, int y, Rgb colour);  // ignored outside the image
  // Mixes `colour` in with weight alpha in [0, 1] (coverage): out = in + alpha (colour - in).
  void blend(int x, int y, Rgb colour, double alpha);
};

// PNG (RGB, 8 bits, no interlace; each row filtered by the minimum-sum-of-absolute-differences
// heuristic, zlib level 6), written atomically. Errors are vcut::InputError naming `path`.
void write_png(const std::string& path, const Image& image);
std::string encode_png(const Image& image);

struct Point2 {
  double x = 0, y = 0;
};

// Strokes with round caps and joins, anti-aliased by the covered fraction of each pixel
// (approximated by the distance of its centre to the stroke).
void draw_line(Image& image, Point2 from, Point2 to, Rgb colour, double width_px = 1.0);
void draw_polyline(Image& image, const std::vector<Point2>& points, Rgb colour, double width_px = 1.0);
// Exact area coverage of the rectangle [x0, x1] x [y0, y1].
void fill_rect(Image& image, double x0, double y0, double x1, double y1, Rgb colour);
void fill_circle(Image& image, Point2 centre, double radius_px, Rgb colour);

// Text in the built-in stroke font (ASCII 32..126; other bytes draw as '?'). `height_px` is
// the height of capitals and digits; descenders reach height_px / 3 below the baseline.
// (x, y) is on the baseline, at the start, middle or end of the text as `align` says; the
// text is turned angle_rad counter-clockwise about that point (pi/2 reads bottom to top).
enum class Align { kLeft, kCenter, kRight };
void draw_text(Image& image, const std::string& text, Point2 at, double height_px, Rgb colour,
               Align align = Align::kLeft, double angle_rad = 0.0);
// Advance width of the text (px), proportional to height_px.
double text_width(const std::string& text, double height_px);

// Short axis labels: `significant` digits, trailing zeros and exponent padding dropped
// (0.005, 1e-3, 250, 1.5e6).
std::string format_label(double value, int significant = 3);

}  // namespace vcut::report
