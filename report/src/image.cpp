#include "vcut/report/image.h"

#include <fmt/format.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "cairo_image.h"
#include "vcut/io/atomic_file.h"
#include "vcut/io/input_error.h"

namespace vcut::report {
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
  for (int k = 0; k < 3; ++k)
    p[k] = static_cast<std::uint8_t>(std::lround(p[k] + std::clamp(alpha, 0.0, 1.0) * (colour[k] - p[k])));
}

std::string encode_png(const Image& image) {
  cairo_surface_t* surface = to_surface(image);
  std::string png;
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface, append_to_string, &png);
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS) throw InputError(std::string("PNG: ") + cairo_status_to_string(status));
  return png;
}

void write_png(const std::string& path, const Image& image) { io::write_text_atomically(path, encode_png(image)); }

std::string format_label(double value, int significant) {
  std::string text = fmt::format("{:.{}g}", value, std::max(1, significant));
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
