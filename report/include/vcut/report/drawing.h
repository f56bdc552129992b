// Drawing in 2D through Cairo: one drawing path for the raster (an Image, then PNG) and SVG.
// Text is DejaVu Sans read from its file, not looked up through fontconfig, with hinting off,
// so the pixels do not depend on the fonts or the settings of the machine. Coordinates are
// pixels, x right, y down; pixel (i, j) covers [i, i+1) x [j, j+1).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "vcut/report/image.h"

namespace vcut::report {

// Loads the font texts are drawn with (once a process); throws InputError naming the file
// when it cannot be read, so that a run stops before its work instead of at its pictures.
void require_font();

enum class Align { kLeft, kCenter, kRight };

// A text as drawn: its ink box (px) on the drawing, after alignment and turning.
struct DrawnText {
  std::string text;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

class Drawing {
 public:
  // Draws onto a copy of `image`'s pixels; image() gives them back.
  explicit Drawing(const Image& image);
  // Records an SVG document of this size (px); svg() closes and returns it.
  static Drawing svg(int width_px, int height_px);
  Drawing(Drawing&&) noexcept;
  Drawing& operator=(Drawing&&) noexcept;
  ~Drawing();

  // Strokes have round caps and joins; dashes are 8 px on, 5 px off.
  void line(Point2 from, Point2 to, Rgb colour, double width_px = 1.0, bool dashed = false);
  void polyline(const std::vector<Point2>& points, Rgb colour, double width_px = 1.0);
  // The rectangle [x0, x1] x [y0, y1] filled, and outlined 1 px wide when `stroke` is given.
  void rect(double x0, double y0, double x1, double y1, Rgb fill, const Rgb* stroke = nullptr);
  void disc(Point2 centre, double radius_px, Rgb colour);
  void ring(Point2 centre, double radius_px, Rgb colour, double width_px);
  // `height_px` is the height of capitals; (x, y) is on the baseline at the start, middle or
  // end of the text as `align` says, and the text is turned angle_rad counter-clockwise about
  // it (pi/2 reads bottom to top). Bytes that are not UTF-8 are drawn as '?'.
  void text(const std::string& text, Point2 at, double height_px, Rgb colour, Align align = Align::kLeft,
            double angle_rad = 0.0);

  const std::vector<DrawnText>& texts() const { return texts_; }  // every text drawn, in order
  Image image() const;                                            // the raster's pixels (logic_error on an SVG drawing)
  std::string svg();  // the finished SVG document (logic_error on a raster drawing)

 private:
  struct Surface;
  explicit Drawing(std::unique_ptr<Surface> surface);
  std::unique_ptr<Surface> surface_;
  std::vector<DrawnText> texts_;
};

// Advance width (px) of the text at this capital height, proportional to it.
double text_width(const std::string& text, double height_px);

}  // namespace vcut::report
