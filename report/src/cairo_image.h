// Images as Cairo surfaces (RGB24: one 32-bit word a pixel), for the drawing and the PNG writer.
#pragma once

#include <cairo.h>

#include "vcut/report/image.h"

namespace vcut::report {

// A new surface holding the image's pixels; the caller destroys it.
cairo_surface_t* to_surface(const Image& image);
Image to_image(cairo_surface_t* surface);
// A cairo_write_func_t appending to the std::string `closure` points to.
cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length);

}  // namespace vcut::report
