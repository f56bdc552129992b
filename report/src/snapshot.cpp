#include "vcut/report/snapshot.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "vcut/io/atomic_file.h"
#include "vcut/io/input_error.h"
#include "vcut/report/drawing.h"

namespace vcut::report {
namespace {

// Screen positions in fixed point, 1/256 px, so that edge functions are exact integers: the
// top-left rule then gives every pixel centre on a shared edge to exactly one triangle.
constexpr int kSubpixelBits = 8;
constexpr std::int64_t kSubpixel = 1 << kSubpixelBits, kHalf = kSubpixel / 2;
// Rows a band holds: bands are rasterised in parallel, each pixel by one band, and within a
// band triangles go in mesh order, so the result does not depend on the thread count.
constexpr int kBandRows = 16;
constexpr double kPi = 3.14159265358979323846;
constexpr double kOutlineStepPx = 3.0, kOutlineShade = 0.3;
const Rgb kInk{40, 40, 40};
const Rgb kUniformGrey{200, 200, 200};

struct ScreenVertex {
  std::int64_t x, y;  // 1/256 px
  float depth;        // mm toward the camera from the bounding-box centre
};

// First and last pixel index whose centre lies in [lo, hi] (fixed point).
std::array<std::int64_t, 2> centres_within(std::int64_t lo, std::int64_t hi) {
  const auto floor_div = [](std::int64_t a, std::int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
  return {floor_div(lo - kHalf + kSubpixel - 1, kSubpixel), floor_div(hi - kHalf, kSubpixel)};
}

struct Frame {  // picture plane: right, up, toward camera; scale px/mm about a centre
  Eigen::Vector3d right, up, toward, centre_mm;
  double px_per_mm = 1.0, centre_x_px = 0.0, centre_y_px = 0.0;
  double half_depth_mm = 0.0;  // the box's corners lie within +-this toward the camera
};

Frame fit_frame(const removal::TriangleMesh& mesh, const Eigen::Vector3d& toward_camera, double x0, double y0,
                double x1, double y1, double margin_px) {
  Frame f;
  f.toward = toward_camera.normalized();
  Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(f.toward);
  if (right.norm() < 1e-9) right = Eigen::Vector3d::UnitY().cross(f.toward);
  f.right = right.normalized();
  f.up = f.toward.cross(f.right);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
  for (const auto& v : mesh.vertices_mm) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  f.centre_mm = (lo + hi) / 2;
  double half_r = 0, half_u = 0;  // half extents of the box corners projected on the screen
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p((corner & 1 ? hi : lo).x(), (corner & 2 ? hi : lo).y(), (corner & 4 ? hi : lo).z());
    half_r = std::max(half_r, std::abs((p - f.centre_mm).dot(f.right)));
    half_u = std::max(half_u, std::abs((p - f.centre_mm).dot(f.up)));
    f.half_depth_mm = std::max(f.half_depth_mm, std::abs((p - f.centre_mm).dot(f.toward)));
  }
  const double room_x = std::max(1.0, x1 - x0 - 2 * margin_px), room_y = std::max(1.0, y1 - y0 - 2 * margin_px);
  f.px_per_mm = std::min(room_x / std::max(2 * half_r, 1e-12), room_y / std::max(2 * half_u, 1e-12));
  f.centre_x_px = (x0 + x1) / 2, f.centre_y_px = (y0 + y1) / 2;
  return f;
}

void rasterise(const removal::TriangleMesh& mesh, const std::vector<Rgb>& colours, const Frame& frame,
               const SnapshotOptions& options, Image& image) {
  const int width = image.width, height = image.height;
  const size_t n_vertices = mesh.vertices_mm.size(), n_triangles = mesh.triangles.size();
  std::vector<ScreenVertex> screen(n_vertices);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n_vertices), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Eigen::Vector3d d = mesh.vertices_mm[i] - frame.centre_mm;
      const double x = frame.centre_x_px + frame.px_per_mm * d.dot(frame.right);
      const double y = frame.centre_y_px - frame.px_per_mm * d.dot(frame.up);
      screen[i] = {std::llround(std::clamp(x, -1e6, 1e6) * kSubpixel),
                   std::llround(std::clamp(y, -1e6, 1e6) * kSubpixel), static_cast<float>(d.dot(frame.toward))};
    }
  });

  // Bin triangles into bands of rows by a counting sort, keeping mesh order within a band.
  const int n_bands = (height + kBandRows - 1) / kBandRows;
  const auto band_range = [&](const Eigen::Vector3i& t) -> std::array<int, 2> {
    const ScreenVertex &a = screen[t[0]], &b = screen[t[1]], &c = screen[t[2]];
    auto rows = centres_within(std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y}));
    auto cols = centres_within(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}));
    rows = {std::max<std::int64_t>(rows[0], 0), std::min<std::int64_t>(rows[1], height - 1)};
    if (rows[0] > rows[1] || cols[0] > std::min<std::int64_t>(cols[1], width - 1) || cols[1] < 0) return {1, 0};
    return {static_cast<int>(rows[0] / kBandRows), static_cast<int>(rows[1] / kBandRows)};
  };
  // In fixed chunks of the mesh, counted and filled in parallel: chunk c's triangles of band b
  // follow those of the chunks before it, so the order is the mesh's for any thread count.
  const size_t chunk = std::max<size_t>(4096, (n_triangles + 63) / 64);
  const size_t chunks = (n_triangles + chunk - 1) / chunk;
  std::vector<size_t> counts(chunks * static_cast<size_t>(n_bands), 0);  // chunk-major
  tbb::parallel_for(size_t{0}, chunks, [&](size_t c) {
    size_t* count = counts.data() + c * n_bands;
    for (size_t i = c * chunk; i < std::min(n_triangles, (c + 1) * chunk); ++i) {
      const auto [b0, b1] = band_range(mesh.triangles[i]);
      for (int b = b0; b <= b1; ++b) ++count[b];
    }
  });
  std::vector<size_t> start(n_bands + 1, 0);
  for (int b = 0; b < n_bands; ++b) {
    size_t at = start[b];
    for (size_t c = 0; c < chunks; ++c) {  // each chunk's count becomes its first slot
      const size_t n = counts[c * n_bands + b];
      counts[c * n_bands + b] = at;
      at += n;
    }
    start[b + 1] = at;
  }
  std::vector<std::uint32_t> binned(start[n_bands]);
  tbb::parallel_for(size_t{0}, chunks, [&](size_t c) {
    size_t* fill = counts.data() + c * n_bands;
    for (size_t i = c * chunk; i < std::min(n_triangles, (c + 1) * chunk); ++i) {
      const auto [b0, b1] = band_range(mesh.triangles[i]);
      for (int b = b0; b <= b1; ++b) binned[fill[b]++] = static_cast<std::uint32_t>(i);
    }
  });

  std::vector<float> depth(static_cast<size_t>(width) * height, -std::numeric_limits<float>::infinity());
  const double cue_per_mm = frame.half_depth_mm > 0 ? options.depth_cue / (2 * frame.half_depth_mm) : 0.0;
  tbb::parallel_for(tbb::blocked_range<int>(0, n_bands, 1), [&](const tbb::blocked_range<int>& bands) {
    for (int band = bands.begin(); band < bands.end(); ++band) {
      const std::int64_t row_lo = band * kBandRows, row_hi = std::min(height, (band + 1) * kBandRows) - 1;
      for (size_t k = start[band]; k < start[band + 1]; ++k) {
        const Eigen::Vector3i& t = mesh.triangles[binned[k]];
        int ia = t[0], ib = t[1], ic = t[2];
        const auto edge = [&](int p, int q, std::int64_t px, std::int64_t py) {
          return (screen[q].x - screen[p].x) * (py - screen[p].y) - (screen[q].y - screen[p].y) * (px - screen[p].x);
        };
        std::int64_t area2 = edge(ia, ib, screen[ic].x, screen[ic].y);
        if (area2 == 0) continue;
        if (area2 < 0) std::swap(ib, ic), area2 = -area2;  // two-sided: orient every triangle alike
        const Eigen::Vector3d n =
            (mesh.vertices_mm[t[1]] - mesh.vertices_mm[t[0]]).cross(mesh.vertices_mm[t[2]] - mesh.vertices_mm[t[0]]);
        const double shade =
            options.ambient + (1 - options.ambient) * std::abs(n.dot(frame.toward)) / std::max(n.norm(), 1e-300);
        const ScreenVertex &a = screen[ia], &b = screen[ib], &c = screen[ic];
        auto rows = centres_within(std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y}));
        auto cols = centres_within(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}));
        rows = {std::max(rows[0], row_lo), std::min(rows[1], row_hi)};
        cols = {std::max<std::int64_t>(cols[0], 0), std::min<std::int64_t>(cols[1], width - 1)};
        // Edge p->q: value at pixel centres; in this orientation (y down) an edge is top when
        // horizontal going +x, left when going -y. Others need a value > 0, i.e. >= 1.
        const int opposite[3][2] = {{ib, ic}, {ic, ia}, {ia, ib}};  // weights of a, b, c
        std::int64_t row_value[3], step_x[3], step_y[3], bias[3];
        for (int e = 0; e < 3; ++e) {
          const ScreenVertex &p = screen[opposite[e][0]], &q = screen[opposite[e][1]];
          const std::int64_t dx = q.x - p.x, dy = q.y - p.y;
          step_x[e] = -dy * kSubpixel, step_y[e] = dx * kSubpixel;
          bias[e] = (dy == 0 && dx > 0) || dy < 0 ? 0 : 1;
          row_value[e] = edge(opposite[e][0], opposite[e][1], cols[0] * kSubpixel + kHalf, rows[0] * kSubpixel + kHalf);
        }
        const Rgb &ca = colours.empty() ? kUniformGrey : colours[ia],
                  &cb = colours.empty() ? kUniformGrey : colours[ib],
                  &cc = colours.empty() ? kUniformGrey : colours[ic];
        const double inv_area = 1.0 / static_cast<double>(area2);
        for (std::int64_t y = rows[0]; y <= rows[1]; ++y) {
          std::int64_t w[3] = {row_value[0], row_value[1], row_value[2]};
          for (std::int64_t x = cols[0]; x <= cols[1]; ++x) {
            if (w[0] >= bias[0] && w[1] >= bias[1] && w[2] >= bias[2]) {
              const double l0 = w[0] * inv_area, l1 = w[1] * inv_area, l2 = 1.0 - l0 - l1;
              const float z = static_cast<float>(l0 * a.depth + l1 * b.depth + l2 * c.depth);
              const size_t pixel = static_cast<size_t>(y) * width + x;
              if (z > depth[pixel]) {  // strictly nearer: on a tie the earlier triangle stays
                depth[pixel] = z;
                const double cued = shade * (1 - cue_per_mm * (frame.half_depth_mm - z));
                for (int k3 = 0; k3 < 3; ++k3)
                  image.rgb[pixel * 3 + k3] = static_cast<std::uint8_t>(
                      std::clamp(cued * (l0 * ca[k3] + l1 * cb[k3] + l2 * cc[k3]) + 0.5, 0.0, 255.0));
              }
            }
            for (int e = 0; e < 3; ++e) w[e] += step_x[e];
          }
          for (int e = 0; e < 3; ++e) row_value[e] += step_y[e];
        }
      }
    }
  });
  if (!options.outline) return;
  // Outlines on the near side of depth steps (second difference below -kOutlineStepPx pixel
  // widths, so that planes seen at a grazing angle stay clear) and along silhouettes: pocket
  // rims and steps, which a light at the camera leaves flat.
  const float step_mm = static_cast<float>(kOutlineStepPx / frame.px_per_mm);
  const float empty = -std::numeric_limits<float>::infinity();
  tbb::parallel_for(tbb::blocked_range<int>(1, std::max(1, height - 1)), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 1; x + 1 < width; ++x) {
        const size_t pixel = static_cast<size_t>(y) * width + x;
        const float z = depth[pixel];
        if (z == empty) continue;
        bool edge = false;
        for (const size_t d : {size_t{1}, static_cast<size_t>(width)}) {
          const float before = depth[pixel - d], after = depth[pixel + d];
          edge = edge || before == empty || after == empty || before + after - 2 * z < -step_mm;
        }
        if (edge)
          for (int k = 0; k < 3; ++k)
            image.rgb[pixel * 3 + k] = static_cast<std::uint8_t>(image.rgb[pixel * 3 + k] * kOutlineShade);
      }
  });
}

double tick_value(const ColourScale& scale, int i) {
  return scale.min_value + i * (scale.max_value - scale.min_value) / (std::max(2, scale.ticks) - 1);
}

double text_px(const SnapshotOptions& o) { return std::max(10.0, o.height_px / 45.0); }

// Width (px) the colour bar and its labels take at the right edge.
double legend_width(const SnapshotOptions& o) {
  if (!o.legend) return 0.0;
  const double h = text_px(o);
  const int ticks = std::max(2, o.legend->ticks);
  double labels = 0;
  for (int i = 0; i < ticks; ++i) labels = std::max(labels, text_width(format_label(tick_value(*o.legend, i)), h));
  return h * 0.8 + (o.legend->label.empty() ? 0 : 2 * h) + 1.2 * h + 0.5 * h + 0.4 * h + labels + h;
}

void draw_legend(Drawing& drawing, const SnapshotOptions& o, int width_px, int height_px, double top_px) {
  const ColourScale& scale = *o.legend;
  const double h = text_px(o), bar_w = 1.2 * h;
  double x = width_px - legend_width(o) + 0.8 * h;
  const double y0 = top_px + 0.15 * (height_px - top_px), y1 = height_px - 0.15 * (height_px - top_px);
  if (!scale.label.empty()) {
    drawing.text(scale.label, {x + h, (y0 + y1) / 2}, h, kInk, Align::kCenter, kPi / 2);
    x += 2 * h;
  }
  for (int row = static_cast<int>(std::floor(y0)); row < static_cast<int>(std::ceil(y1)); ++row) {
    const double value = scale.max_value + (row + 0.5 - y0) / (y1 - y0) * (scale.min_value - scale.max_value);
    drawing.rect(x, std::max(double(row), y0), x + bar_w, std::min(row + 1.0, y1),
                 scale.colour ? scale.colour(value) : kUniformGrey);
  }
  drawing.polyline({{x, y0}, {x + bar_w, y0}, {x + bar_w, y1}, {x, y1}, {x, y0}}, kInk, 1.0);
  const int ticks = std::max(2, scale.ticks);
  for (int i = 0; i < ticks; ++i) {
    const double y = y1 + static_cast<double>(i) / (ticks - 1) * (y0 - y1);
    drawing.line({x + bar_w, y}, {x + bar_w + 0.5 * h, y}, kInk, 1.0);
    drawing.text(format_label(tick_value(scale, i)), {x + bar_w + 0.9 * h, y + h / 2}, h, kInk);
  }
}

}  // namespace

Eigen::Vector3d view_direction(const std::string& name) {
  if (name == "iso") return Eigen::Vector3d(1, -1, 1).normalized();
  if (name == "top") return Eigen::Vector3d::UnitZ();
  if (name == "front") return -Eigen::Vector3d::UnitY();
  if (name == "right") return Eigen::Vector3d::UnitX();
  throw InputError("unknown view '" + name + "' (expected iso, top, front or right)");
}

Image render_snapshot(const removal::TriangleMesh& mesh, const std::vector<Rgb>& colours,
                      const Eigen::Vector3d& toward_camera, const SnapshotOptions& options) {
  if (!colours.empty() && colours.size() != mesh.vertices_mm.size())
    throw std::invalid_argument("render_snapshot: one colour per vertex expected");
  if (options.width_px <= 0 || options.height_px <= 0 || toward_camera.norm() == 0)
    throw std::invalid_argument("render_snapshot: empty image or no view direction");
  Image image(options.width_px, options.height_px, options.background);
  const double h = text_px(options), top = options.title.empty() ? 0.0 : 2.2 * h;
  if (!mesh.triangles.empty()) {
    const double margin = options.margin * std::min(options.width_px, options.height_px);
    const Frame frame =
        fit_frame(mesh, toward_camera, 0, top, options.width_px - legend_width(options), options.height_px, margin);
    rasterise(mesh, colours, frame, options, image);
  }
  if (options.title.empty() && !options.legend) return image;
  Drawing drawing(image);
  if (!options.title.empty())
    drawing.text(options.title, {options.width_px / 2.0, 1.6 * h}, 1.25 * h, kInk, Align::kCenter);
  if (options.legend) draw_legend(drawing, options, options.width_px, options.height_px, top);
  return drawing.image();
}

std::vector<std::string> write_snapshots(const std::string& folder, const std::string& stem,
                                         const removal::TriangleMesh& mesh, const std::vector<Rgb>& colours,
                                         const SnapshotOptions& options) {
  io::ensure_writable_folder(folder);
  const std::array<const char*, 3> views = {"iso", "top", "front"};
  std::vector<std::string> names;
  for (const char* view : views) names.push_back(stem + "_" + view + ".png");
  // The views side by side (a view's PNG encoding is one thread's work).
  tbb::parallel_for(size_t{0}, views.size(), [&](size_t k) {
    SnapshotOptions titled = options;
    if (!titled.title.empty()) titled.title += std::string(" (") + views[k] + ")";
    write_png((std::filesystem::path(folder) / names[k]).string(),
              render_snapshot(mesh, colours, view_direction(views[k]), titled));
  });
  return names;
}

}  // namespace vcut::report
