#include "vcut/report/image.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "vcut/io/atomic_file.h"
#include "vcut/io/input_error.h"

namespace vcut::report {
namespace {

// ---- PNG (ISO/IEC 15948: signature, IHDR, IDAT, IEND; CRC-32 over type and data) ----------

void put_u32(std::string& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xff));
}

void put_chunk(std::string& out, const char* type, const std::string& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const std::string body = std::string(type, 4) + data;
  out += body;
  put_u32(out, static_cast<std::uint32_t>(
                   crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
}

// The Paeth predictor (PNG spec §9.4).
int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// Filtered rows: each a filter-type byte and the row; per row the filter whose output has the
// smallest sum of |signed byte|, the heuristic the PNG spec recommends (§12.8).
std::string filter_rows(const Image& image) {
  const size_t stride = static_cast<size_t>(image.width) * 3;
  std::string out;
  out.reserve((stride + 1) * static_cast<size_t>(image.height));
  std::vector<std::uint8_t> zeros(stride, 0), best, trial(stride);
  for (int y = 0; y < image.height; ++y) {
    const std::uint8_t* row = image.rgb.data() + y * stride;
    const std::uint8_t* up = y > 0 ? row - stride : zeros.data();
    long best_cost = -1;
    int best_type = 0;
    for (int type = 0; type < 5; ++type) {
      long cost = 0;
      for (size_t i = 0; i < stride; ++i) {
        const int a = i >= 3 ? row[i - 3] : 0, b = up[i], c = i >= 3 ? up[i - 3] : 0;
        const int predictor = type == 0 ? 0 : type == 1 ? a : type == 2 ? b : type == 3 ? (a + b) / 2 : paeth(a, b, c);
        trial[i] = static_cast<std::uint8_t>(row[i] - predictor);
        cost += std::abs(static_cast<int>(static_cast<std::int8_t>(trial[i])));
      }
      if (best_cost < 0 || cost < best_cost) best_cost = cost, best_type = type, best = trial;
    }
    out.push_back(static_cast<char>(best_type));
    out.append(best.begin(), best.end());
  }
  return out;
}

// ---- Coverage rasterisation -----------------------------------------------------------------

double clamp01(double v) { return std::min(1.0, std::max(0.0, v)); }

double distance_to_segment(double px, double py, Point2 a, Point2 b) {
  const double dx = b.x - a.x, dy = b.y - a.y, length2 = dx * dx + dy * dy;
  const double t = length2 > 0 ? clamp01(((px - a.x) * dx + (py - a.y) * dy) / length2) : 0.0;
  return std::hypot(px - (a.x + t * dx), py - (a.y + t * dy));
}

// Strokes all segments as one shape: coverage is the maximum over the segments, so joins and
// crossings are not darkened twice. Pixel coverage ~ half-width + 1/2 - centre distance.
void stroke(Image& image, const std::vector<std::array<Point2, 2>>& segments, Rgb colour, double width_px) {
  if (segments.empty() || image.width <= 0 || image.height <= 0) return;
  const double reach = width_px / 2 + 0.5, peak = std::min(1.0, width_px);
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& s : segments)
    for (const Point2& p : s)
      x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  const int bx0 = std::max(0, static_cast<int>(std::floor(x0 - reach)));
  const int by0 = std::max(0, static_cast<int>(std::floor(y0 - reach)));
  const int bx1 = std::min(image.width - 1, static_cast<int>(std::floor(x1 + reach)));
  const int by1 = std::min(image.height - 1, static_cast<int>(std::floor(y1 + reach)));
  if (bx0 > bx1 || by0 > by1) return;
  const int w = bx1 - bx0 + 1;
  std::vector<float> coverage(static_cast<size_t>(w) * (by1 - by0 + 1), 0.0f);
  for (const auto& [a, b] : segments) {
    const int sx0 = std::max(bx0, static_cast<int>(std::floor(std::min(a.x, b.x) - reach)));
    const int sx1 = std::min(bx1, static_cast<int>(std::floor(std::max(a.x, b.x) + reach)));
    const int sy0 = std::max(by0, static_cast<int>(std::floor(std::min(a.y, b.y) - reach)));
    const int sy1 = std::min(by1, static_cast<int>(std::floor(std::max(a.y, b.y) + reach)));
    for (int y = sy0; y <= sy1; ++y)
      for (int x = sx0; x <= sx1; ++x) {
        const double c = std::min(peak, clamp01(reach - distance_to_segment(x + 0.5, y + 0.5, a, b)));
        float& cell = coverage[static_cast<size_t>(y - by0) * w + (x - bx0)];
        cell = std::max(cell, static_cast<float>(c));
      }
  }
  for (int y = by0; y <= by1; ++y)
    for (int x = bx0; x <= bx1; ++x) {
      const float c = coverage[static_cast<size_t>(y - by0) * w + (x - bx0)];
      if (c > 0) image.blend(x, y, colour, c);
    }
}

// A polyline's segments; a single point is a dot (a zero-length segment).
void append_polyline(std::vector<std::array<Point2, 2>>& segments, const std::vector<Point2>& points) {
  for (size_t i = 0; i < points.size(); ++i)
    if (i > 0 || points.size() == 1) segments.push_back({points[i > 0 ? i - 1 : 0], points[i]});
}

// ---- Stroke font ----------------------------------------------------------------------------
// Glyphs on a grid of digits "xy": x 0..4, y with the baseline at 2, x-height 6, capitals 8,
// descenders down to 0 and brackets 1..9. Points of a polyline are separated by spaces,
// polylines by '|'; a lone point is a dot. Advance: ink width + 2 (digits all 4 + 2).
constexpr int kBaseline = 2, kCapUnits = 6, kGap = 2, kSpaceUnits = 4;
const char* const kGlyphs[95] = {
    "",                                                    // space
    "08 04|02",                                            // !
    "08 07|18 17",                                         // "
    "17 13|37 33|06 46|04 44",                             // #
    "47 38 18 07 06 15 35 44 43 32 12 03|29 21",           // $
    "02 48|07 08 18 17 07|32 33 43 42 32",                 // %
    "42 06 07 18 28 27 04 03 12 22 44",                    // &
    "08 07",                                               // '
    "29 17 13 21",                                         // (
    "09 17 13 01",                                         // )
    "27 23|06 44|04 46",                                   // *
    "26 22|04 44",                                         // +
    "12 01",                                               // ,
    "04 34",                                               // -
    "02",                                                  // .
    "02 48",                                               // /
    "12 03 07 18 38 47 43 32 12",                          // 0
    "17 28 22|12 32",                                      // 1
    "07 18 38 47 46 02 42",                                // 2
    "07 18 38 47 46 35 44 43 32 12 03|15 35",              // 3
    "32 38 04 44",                                         // 4
    "48 08 05 35 44 43 32 12 03",                          // 5
    "47 38 18 07 03 12 32 43 44 35 05",                    // 6
    "08 48 12",                                            // 7
    "18 07 06 15 35 46 47 38 18|15 04 03 12 32 43 44 35",  // 8
    "03 12 32 43 47 38 18 07 06 15 45",                    // 9
    "05|02",                                               // :
    "15|12 01",                                            // ;
    "46 04 42",                                            // <
    "05 45|03 43",                                         // =
    "06 44 02",                                            // >
    "07 18 38 47 46 35 25 24|22",                          // ?
    "33 36 16 14 23 33 43 47 38 18 07 03 12 42",           // @
    "02 28 42|15 35",                                      // A
    "02 08 38 47 46 35 05|35 44 43 32 02",                 // B
    "47 38 18 07 03 12 32 43",                             // C
    "02 08 38 47 43 32 02",                                // D
    "48 08 02 42|05 35",                                   // E
    "48 08 02|05 35",                                      // F
    "47 38 18 07 03 12 32 43 45 25",                       // G
    "08 02|48 42|05 45",                                   // H
    "08 28|18 12|02 22",                                   // I
    "28 48 43 32 12 03",                                   // J
    "08 02|48 04|15 42",                                   // K
    "08 02 42",                                            // L
    "02 08 25 48 42",                                      // M
    "02 08 42 48",                                         // N
    "12 03 07 18 38 47 43 32 12",                          // O
    "02 08 38 47 46 35 05",                                // P
    "12 03 07 18 38 47 43 32 12|23 41",                    // Q
    "02 08 38 47 46 35 05|25 42",                          // R
    "47 38 18 07 06 15 35 44 43 32 12 03",                 // S
    "08 48|28 22",                                         // T
    "08 03 12 32 43 48",                                   // U
    "08 22 48",                                            // V
    "08 12 25 32 48",                                      // W
    "08 42|02 48",                                         // X
    "08 25 48|25 22",                                      // Y
    "08 48 02 42",                                         // Z
    "19 09 01 11",                                         // [
    "08 42",                                               // backslash
    "09 19 11 01",                                         // ]
    "06 18 26",                                            // ^
    "00 40",                                               // _
    "08 17",                                               // `
    "16 36 45 42|44 14 03 12 32 43",                       // a
    "08 02|03 12 32 43 45 36 16 05",                       // b
    "45 36 16 05 03 12 32 43",                             // c
    "48 42|43 32 12 03 05 16 36 45",                       // d
    "04 44 45 36 16 05 03 12 42",                          // e
    "38 28 17 12|06 36",                                   // f
    "46 41 30 10 01|45 36 16 05 04 13 33 44",              // g
    "08 02|05 16 36 45 42",                                // h
    "16 12|18",                                            // i
    "26 21 10 00|28",                                      // j
    "08 02|36 03|14 32",                                   // k
    "08 03 12",                                            // l
    "02 06|05 16 25 22|25 36 45 42",                       // m
    "02 06|05 16 36 45 42",                                // n
    "05 16 36 45 43 32 12 03 05",                          // o
    "06 00|05 16 36 45 43 32 12 03",                       // p
    "46 40|45 36 16 05 03 12 32 43",                       // q
    "02 06|05 16 36",                                      // r
    "45 36 16 05 14 34 43 32 12 03",                       // s
    "18 13 22 32|06 36",                                   // t
    "06 03 12 32 43|46 42",                                // u
    "06 22 46",                                            // v
    "06 12 24 32 46",                                      // w
    "06 42|02 46",                                         // x
    "06 23|46 00",                                         // y
    "06 46 02 42",                                         // z
    "29 19 16 05 14 11 21",                                // {
    "09 01",                                               // |
    "09 19 16 25 14 11 01",                                // }
    "04 15 34 45",                                         // ~
};

const char* glyph_of(char c) {
  const unsigned u = static_cast<unsigned char>(c);
  return kGlyphs[(u >= 32 && u <= 126 ? u : '?') - 32];
}

// Horizontal ink extent of a glyph in grid units (digits share one so columns align).
std::array<int, 2> ink_x(char c) {
  if (c >= '0' && c <= '9') return {0, 4};
  int lo = 9, hi = -1;
  for (const char* p = glyph_of(c); *p; ++p) {
    if (*p == ' ' || *p == '|') continue;
    lo = std::min(lo, *p - '0'), hi = std::max(hi, *p - '0');
    ++p;  // past the y digit
  }
  return hi < 0 ? std::array<int, 2>{0, kSpaceUnits - kGap} : std::array<int, 2>{lo, hi};
}

double advance_units(char c) {
  const auto [lo, hi] = ink_x(c);
  return hi - lo + kGap;
}

}  // namespace

Image::Image(int w, int h, Rgb fill) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3) {
  for (size_t i = 0; i < rgb.size(); i += 3) std::copy(fill.begin(), fill.end(), rgb.begin() + i);
}

Rgb Image::get(int x, int y) const {
  const size_t i = (static_cast<size_t>(y) * width + x) * 3;
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void Image::set(int x, int y, Rgb colour) {
  if (!contains(x, y)) return;
  std::copy(colour.begin(), colour.end(), rgb.begin() + (static_cast<size_t>(y) * width + x) * 3);
}

void Image::blend(int x, int y, Rgb colour, double alpha) {
  if (!contains(x, y)) return;
  std::uint8_t* p = rgb.data() + (static_cast<size_t>(y) * width + x) * 3;
  for (int k = 0; k < 3; ++k) p[k] = static_cast<std::uint8_t>(std::lround(p[k] + clamp01(alpha) * (colour[k] - p[k])));
}

std::string encode_png(const Image& image) {
  const std::string raw = filter_rows(image);
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::string compressed(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(compressed.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                static_cast<uLong>(raw.size()), 6) != Z_OK)
    throw InputError("PNG: zlib compression failed");
  compressed.resize(size);

  std::string header;
  put_u32(header, static_cast<std::uint32_t>(image.width));
  put_u32(header, static_cast<std::uint32_t>(image.height));
  header += std::string("\x08\x02\x00\x00\x00",
                        5);  // 8 bits, truecolour, deflate, filter 0, no interlace
  std::string png("\x89PNG\r\n\x1a\n", 8);
  put_chunk(png, "IHDR", header);
  put_chunk(png, "IDAT", compressed);
  put_chunk(png, "IEND", "");
  return png;
}

void write_png(const std::string& path, const Image& image) { io::write_text_atomically(path, encode_png(image)); }

void draw_line(Image& image, Point2 from, Point2 to, Rgb colour, double width_px) {
  stroke(image, {{from, to}}, colour, width_px);
}

void draw_polyline(Image& image, const std::vector<Point2>& points, Rgb colour, double width_px) {
  std::vector<std::array<Point2, 2>> segments;
  append_polyline(segments, points);
  stroke(image, segments, colour, width_px);
}

void fill_rect(Image& image, double x0, double y0, double x1, double y1, Rgb colour) {
  if (x0 > x1) std::swap(x0, x1);
  if (y0 > y1) std::swap(y0, y1);
  const int ix0 = std::max(0, static_cast<int>(std::floor(x0))),
            ix1 = std::min(image.width - 1, static_cast<int>(std::ceil(x1)) - 1);
  const int iy0 = std::max(0, static_cast<int>(std::floor(y0))),
            iy1 = std::min(image.height - 1, static_cast<int>(std::ceil(y1)) - 1);
  for (int y = iy0; y <= iy1; ++y) {
    const double cy = std::min(y + 1.0, y1) - std::max(double(y), y0);
    for (int x = ix0; x <= ix1; ++x) image.blend(x, y, colour, cy * (std::min(x + 1.0, x1) - std::max(double(x), x0)));
  }
}

void fill_circle(Image& image, Point2 centre, double radius_px, Rgb colour) {
  // A dot stroked with width 2 r is the disc, anti-aliased the same way as lines.
  stroke(image, {{centre, centre}}, colour, 2 * radius_px);
}

double text_width(const std::string& text, double height_px) {
  if (text.empty()) return 0.0;
  double units = -kGap;
  for (char c : text) units += advance_units(c);
  return units * height_px / kCapUnits;
}

void draw_text(Image& image, const std::string& text, Point2 at, double height_px, Rgb colour, Align align,
               double angle_rad) {
  const double unit = height_px / kCapUnits;
  // Text frame: u along the baseline, v up; on screen (y down) u -> (cos, -sin), v -> (-sin, -cos).
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  const double width = text_width(text, height_px);
  double pen = align == Align::kLeft ? 0.0 : align == Align::kCenter ? -width / 2 : -width;
  const auto place = [&](double u, double v) { return Point2{at.x + u * c - v * s, at.y - u * s - v * c}; };
  std::vector<std::array<Point2, 2>> segments;
  for (char ch : text) {
    const int left = ink_x(ch)[0];
    for (const char* p = glyph_of(ch); *p;) {
      std::vector<Point2> line;
      for (; *p && *p != '|'; ++p) {
        if (*p == ' ') continue;
        line.push_back(place(pen + (p[0] - '0' - left) * unit, (p[1] - '0' - kBaseline) * unit));
        ++p;  // past the y digit
      }
      if (*p == '|') ++p;
      append_polyline(segments, line);
    }
    pen += advance_units(ch) * unit;
  }
  stroke(image, segments, colour, std::max(1.0, height_px / 10));
}

std::string format_label(double value, int significant) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", std::max(1, significant), value);
  std::string text = buffer;
  const size_t e = text.find('e');
  if (e == std::string::npos) return text == "-0" ? "0" : text;
  std::string mantissa = text.substr(0, e), exponent = text.substr(e + 1);
  if (mantissa.find('.') != std::string::npos) {
    while (mantissa.back() == '0') mantissa.pop_back();
    if (mantissa.back() == '.') mantissa.pop_back();
  }
  const bool negative = exponent[0] == '-';
  exponent.erase(0, exponent[0] == '-' || exponent[0] == '+' ? 1 : 0);
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return mantissa + "e" + (negative ? "-" : "") + exponent;
}

}  // namespace vcut::report
