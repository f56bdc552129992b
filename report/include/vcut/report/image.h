// 8-bit RGB raster images and their PNG files; drawing on them is drawing.h's (Cairo).
// Coordinates are pixels, x right, y down; pixel (i, j) covers [i, i+1) x [j, j+1), its centre
// is (i + 0.5, j + 0.5).
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

// Short axis labels: `significant` digits, trailing zeros and exponent padding dropped
// (0.005, 1e-3, 250, 1.5e6).
std::string format_label(double value, int significant = 3);

}  // namespace vcut::report
