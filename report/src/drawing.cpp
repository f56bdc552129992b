#include "vcut/report/drawing.h"

#include <cairo-ft.h>
#include <cairo-svg.h>
#include <cairo.h>
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "vcut/io/input_error.h"

namespace vcut::report {
namespace {

// DejaVu Sans, loaded once from the file CMake found (VCUT_FONT_FILE; the environment
// variable of that name replaces it) and kept for the process.
struct Font {
  cairo_font_face_t* face = nullptr;
  double cap_per_em = 0.0;  // the height of 'H' over the em
};

const Font& font() {
  static const Font loaded = [] {
    FT_Library library = nullptr;
    FT_Face face = nullptr;
    if (FT_Init_FreeType(&library) != 0) throw std::runtime_error("FreeType could not start");
    const char* env = std::getenv("VCUT_FONT_FILE");
    const std::string file = env != nullptr && *env != '\0' ? env : VCUT_FONT_FILE;
    if (FT_New_Face(library, file.c_str(), 0, &face) != 0 || FT_Load_Char(face, 'H', FT_LOAD_NO_SCALE) != 0) {
      FT_Done_FreeType(library);
      throw InputError("font file " + file + ": cannot be read (expected DejaVu Sans, Debian's fonts-dejavu-core)");
    }
    Font f;
    f.cap_per_em = static_cast<double>(face->glyph->metrics.height) / face->units_per_EM;
    f.face = cairo_ft_font_face_create_for_ft_face(face, FT_LOAD_NO_HINTING);
    return f;
  }();
  return loaded;
}

// Grey anti-aliasing, no hinting: glyph shapes and advances scale exactly with the size.
void use_font(cairo_t* cr) {
  cairo_set_font_face(cr, font().face);
  cairo_font_options_t* options = cairo_font_options_create();
  cairo_font_options_set_antialias(options, CAIRO_ANTIALIAS_GRAY);
  cairo_font_options_set_hint_style(options, CAIRO_HINT_STYLE_NONE);
  cairo_font_options_set_hint_metrics(options, CAIRO_HINT_METRICS_OFF);
  cairo_set_font_options(cr, options);
  cairo_font_options_destroy(options);
}

// The text with every byte that does not start a well-formed UTF-8 sequence replaced by '?'
// (Cairo refuses a string that is not UTF-8 and stops drawing).
std::string valid_utf8(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char b = byte(i);
    const std::size_t n = b < 0x80                ? 1
                          : b >= 0xc2 && b < 0xe0 ? 2
                          : b >= 0xe0 && b < 0xf0 ? 3
                          : b >= 0xf0 && b < 0xf5 ? 4
                                                  : 0;
    bool ok = n > 0 && i + n <= s.size();
    for (std::size_t k = 1; ok && k < n; ++k) ok = (byte(i + k) & 0xc0) == 0x80;
    // No overlong three- and four-byte forms, no surrogates, nothing past U+10FFFF.
    if (ok && n == 3) ok = !(b == 0xe0 && byte(i + 1) < 0xa0) && !(b == 0xed && byte(i + 1) >= 0xa0);
    if (ok && n == 4) ok = !(b == 0xf0 && byte(i + 1) < 0x90) && !(b == 0xf4 && byte(i + 1) >= 0x90);
    if (ok) {
      out.append(s, i, n);
      i += n;
    } else {
      out += '?';
      ++i;
    }
  }
  return out;
}

double em_px(double cap_height_px) { return cap_height_px / font().cap_per_em; }

void set_colour(cairo_t* cr, Rgb c) { cairo_set_source_rgb(cr, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0); }

void check(cairo_t* cr, const char* what) {
  if (cairo_status(cr) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(std::string(what) + ": " + cairo_status_to_string(cairo_status(cr)));
}

// ---- Images as Cairo surfaces (RGB24: one 32-bit word a pixel) ----------------------------

// A cairo_write_func_t appending to the std::string `closure` points to.
cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

// A new surface holding the image's pixels; the caller destroys it.
cairo_surface_t* to_surface(const Image& image) {
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, image.width, image.height);
  if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(surface);
    throw std::runtime_error("image of " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                             " px: " + cairo_status_to_string(cairo_surface_status(surface)));
  }
  cairo_surface_flush(surface);
  unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  const std::uint8_t* rgb = image.rgb.data();
  for (int y = 0; y < image.height; ++y) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::size_t>(y) * stride);
    for (int x = 0; x < image.width; ++x, rgb += 3)
      row[x] = 0xff000000u | std::uint32_t{rgb[0]} << 16 | std::uint32_t{rgb[1]} << 8 | rgb[2];
  }
  cairo_surface_mark_dirty(surface);
  return surface;
}

Image to_image(cairo_surface_t* surface) {
  cairo_surface_flush(surface);
  Image image(cairo_image_surface_get_width(surface), cairo_image_surface_get_height(surface));
  const unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  std::uint8_t* rgb = image.rgb.data();
  for (int y = 0; y < image.height; ++y) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<std::size_t>(y) * stride);
    for (int x = 0; x < image.width; ++x, rgb += 3) {
      rgb[0] = static_cast<std::uint8_t>(row[x] >> 16);
      rgb[1] = static_cast<std::uint8_t>(row[x] >> 8);
      rgb[2] = static_cast<std::uint8_t>(row[x]);
    }
  }
  return image;
}

}  // namespace

void require_font() { font(); }

// ---- Drawing ---------------------------------------------------------------------------------

struct Drawing::Surface {
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = nullptr;
  bool is_svg = false;
  std::string svg;  // the SVG stream's bytes so far

  ~Surface() {
    if (cr) cairo_destroy(cr);
    if (surface) cairo_surface_destroy(surface);
  }
  void start() {
    cr = cairo_create(surface);
    check(cr, "drawing");
    use_font(cr);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  }
};

Drawing::Drawing(std::unique_ptr<Surface> surface) : surface_(std::move(surface)) { surface_->start(); }

Drawing::Drawing(const Image& image) : surface_(std::make_unique<Surface>()) {
  surface_->surface = to_surface(image);
  surface_->start();
}

Drawing Drawing::svg(int width_px, int height_px) {
  auto s = std::make_unique<Surface>();
  s->is_svg = true;
  s->surface = cairo_svg_surface_create_for_stream(append_to_string, &s->svg, width_px, height_px);
  cairo_svg_surface_restrict_to_version(s->surface, CAIRO_SVG_VERSION_1_1);
  cairo_svg_surface_set_document_unit(s->surface, CAIRO_SVG_UNIT_PX);
  return Drawing(std::move(s));
}

Drawing::Drawing(Drawing&&) noexcept = default;
Drawing& Drawing::operator=(Drawing&&) noexcept = default;
Drawing::~Drawing() = default;

void Drawing::line(Point2 from, Point2 to, Rgb colour, double width_px, bool dashed) {
  cairo_t* cr = surface_->cr;
  cairo_move_to(cr, from.x, from.y);
  cairo_line_to(cr, to.x, to.y);
  const double dashes[2] = {8.0, 5.0};
  cairo_set_dash(cr, dashes, dashed ? 2 : 0, 0.0);
  set_colour(cr, colour);
  cairo_set_line_width(cr, width_px);
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0.0);
}

void Drawing::polyline(const std::vector<Point2>& points, Rgb colour, double width_px) {
  if (points.empty()) return;
  cairo_t* cr = surface_->cr;
  cairo_move_to(cr, points[0].x, points[0].y);
  for (std::size_t i = 1; i < points.size(); ++i) cairo_line_to(cr, points[i].x, points[i].y);
  set_colour(cr, colour);
  cairo_set_line_width(cr, width_px);
  cairo_stroke(cr);
}

void Drawing::rect(double x0, double y0, double x1, double y1, Rgb fill, const Rgb* stroke) {
  cairo_t* cr = surface_->cr;
  cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
  set_colour(cr, fill);
  if (!stroke) {
    cairo_fill(cr);
    return;
  }
  cairo_fill_preserve(cr);
  set_colour(cr, *stroke);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);
}

void Drawing::disc(Point2 centre, double radius_px, Rgb colour) {
  cairo_t* cr = surface_->cr;
  cairo_new_sub_path(cr);
  cairo_arc(cr, centre.x, centre.y, radius_px, 0.0, 2 * M_PI);
  set_colour(cr, colour);
  cairo_fill(cr);
}

void Drawing::ring(Point2 centre, double radius_px, Rgb colour, double width_px) {
  cairo_t* cr = surface_->cr;
  cairo_new_sub_path(cr);
  cairo_arc(cr, centre.x, centre.y, radius_px, 0.0, 2 * M_PI);
  set_colour(cr, colour);
  cairo_set_line_width(cr, width_px);
  cairo_stroke(cr);
}

void Drawing::text(const std::string& text, Point2 at, double height_px, Rgb colour, Align align, double angle_rad) {
  if (text.empty()) return;
  const std::string utf8 = valid_utf8(text);
  cairo_t* cr = surface_->cr;
  cairo_save(cr);
  cairo_set_font_size(cr, em_px(height_px));
  cairo_text_extents_t e;
  cairo_text_extents(cr, utf8.c_str(), &e);
  const double start = align == Align::kLeft ? 0.0 : align == Align::kCenter ? -e.x_advance / 2 : -e.x_advance;
  cairo_translate(cr, at.x, at.y);
  cairo_rotate(cr, -angle_rad);  // y is down: a negative turn is counter-clockwise on the page
  cairo_move_to(cr, start, 0.0);
  set_colour(cr, colour);
  cairo_show_text(cr, utf8.c_str());
  DrawnText drawn{utf8, INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (const double u : {e.x_bearing, e.x_bearing + e.width})
    for (const double v : {e.y_bearing, e.y_bearing + e.height}) {
      double x = start + u, y = v;
      cairo_user_to_device(cr, &x, &y);
      drawn.x0 = std::min(drawn.x0, x), drawn.x1 = std::max(drawn.x1, x);
      drawn.y0 = std::min(drawn.y0, y), drawn.y1 = std::max(drawn.y1, y);
    }
  cairo_restore(cr);
  check(cr, "drawing text");
  texts_.push_back(std::move(drawn));
}

Image Drawing::image() const {
  if (surface_->is_svg) throw std::logic_error("Drawing::image: an SVG drawing has no pixels");
  check(surface_->cr, "drawing");
  return to_image(surface_->surface);
}

std::string Drawing::svg() {
  if (!surface_->is_svg) throw std::logic_error("Drawing::svg: a raster drawing");
  check(surface_->cr, "drawing");
  cairo_surface_finish(surface_->surface);
  if (cairo_surface_status(surface_->surface) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(std::string("SVG: ") + cairo_status_to_string(cairo_surface_status(surface_->surface)));
  // Cairo numbers the surfaces of the whole process ("surface97" after 96 others): the
  // document's group is named the same every time, so that its bytes do not depend on what
  // was drawn before. Nothing in our documents refers to that id.
  std::string& svg = surface_->svg;
  const std::string group = "<g id=\"surface";
  const std::size_t at = svg.find(group);
  if (at != std::string::npos) {
    const std::size_t digits = at + group.size(), end = svg.find('"', digits);
    if (end != std::string::npos && end > digits) svg.replace(digits, end - digits, "1");
  }
  return svg;
}

double text_width(const std::string& text, double height_px) {
  if (text.empty()) return 0.0;
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1);
  cairo_t* cr = cairo_create(surface);
  use_font(cr);
  cairo_set_font_size(cr, em_px(height_px));
  cairo_text_extents_t e;
  cairo_text_extents(cr, valid_utf8(text).c_str(), &e);
  cairo_destroy(cr);
  cairo_surface_destroy(surface);
  return e.x_advance;
}

}  // namespace vcut::report
