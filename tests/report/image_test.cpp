// Tests of the PNG writer, the 2D drawing and the mesh snapshots. PNG files are decoded here
// from the spec (ISO/IEC 15948: chunk CRCs with zlib's crc32, IDAT inflated with zlib's
// uncompress, the five row filters undone), not by the writer's code. Pixel counts of
// rendered shapes are worked out from the view fit by hand, each in a comment beside it, and
// the ink of drawn shapes from their areas.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <vcut/report/drawing.h>
#include <vcut/report/image.h>
#include <vcut/io/input_error.h>
#include <vcut/report/snapshot.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

namespace vcut::report {
namespace {
namespace fs = std::filesystem;
using removal::TriangleMesh;

constexpr double kPi = 3.14159265358979323846;

fs::path test_dir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(::testing::TempDir()) / "vcut_image" / info->name();
  fs::create_directories(dir);
  return dir;
}

std::uint32_t read_u32(const std::string& s, size_t at) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | static_cast<std::uint8_t>(s[at + i]);
  return v;
}

// Decodes an 8-bit RGB non-interlaced PNG; any deviation from the spec is a test failure.
Image decode_png(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(file.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  Image image;
  std::string idat;
  bool ended = false;
  for (size_t at = 8; at + 12 <= file.size() && !ended;) {
    const std::uint32_t length = read_u32(file, at);
    const std::string type = file.substr(at + 4, 4), data = file.substr(at + 8, length);
    const uLong crc = crc32(0, reinterpret_cast<const Bytef*>(file.data() + at + 4), length + 4);
    EXPECT_EQ(read_u32(file, at + 8 + length), crc) << "CRC of chunk " << type;
    if (type == "IHDR") {
      image.width = static_cast<int>(read_u32(data, 0));
      image.height = static_cast<int>(read_u32(data, 4));
      EXPECT_EQ(data.substr(8), std::string("\x08\x02\x00\x00\x00", 5)) << "8-bit RGB, no interlace";
    } else if (type == "IDAT") {
      idat += data;
    }
    ended = type == "IEND";
    at += 12 + length;
  }
  EXPECT_TRUE(ended);
  const size_t stride = static_cast<size_t>(image.width) * 3;
  std::vector<std::uint8_t> raw((stride + 1) * image.height);
  uLongf raw_size = raw.size();
  EXPECT_EQ(uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(idat.data()), idat.size()), Z_OK);
  EXPECT_EQ(raw_size, raw.size());
  image.rgb.assign(stride * image.height, 0);
  for (int y = 0; y < image.height; ++y) {
    const int type = raw[y * (stride + 1)];
    const std::uint8_t* in_row = &raw[y * (stride + 1) + 1];
    std::uint8_t* out = &image.rgb[y * stride];
    for (size_t i = 0; i < stride; ++i) {
      const int a = i >= 3 ? out[i - 3] : 0, b = y > 0 ? out[i - stride] : 0;
      const int c = i >= 3 && y > 0 ? out[i - stride - 3] : 0;
      const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
      const int paeth = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      const int predictor[5] = {0, a, b, (a + b) / 2, paeth};
      EXPECT_LT(type, 5);
      out[i] = static_cast<std::uint8_t>(in_row[i] + predictor[type < 5 ? type : 0]);
    }
  }
  return image;
}

TEST(Png, EveryPixelSurvivesTheRoundTrip) {
  // Flat areas, gradients and noise, so that the writer picks different row filters.
  Image image(97, 61);
  std::mt19937 random(7);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb noise{std::uint8_t(random()), std::uint8_t(random()), std::uint8_t(random())};
      const Rgb ramp{std::uint8_t(3 * x), std::uint8_t(4 * y), std::uint8_t(x * y)};
      image.set(x, y, y < 15 ? Rgb{10, 200, 30} : y < 40 ? ramp : noise);
    }
  const std::string path = (test_dir() / "round_trip.png").string();
  write_png(path, image);
  const Image decoded = decode_png(path);
  EXPECT_EQ(decoded.width, 97);
  EXPECT_EQ(decoded.height, 61);
  EXPECT_EQ(decoded.rgb, image.rgb);
}

// Ink of a drawing, in pixels: the sum of (255 - red) / 255 over the image (black on white).
double ink(const Image& image) {
  double sum = 0.0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) sum += (255 - image.get(x, y)[0]) / 255.0;
  return sum;
}

TEST(Drawing, LineCoversItsArea) {
  const Point2 a{10.3, 20.7}, b{90.1, 61.2};
  Drawing drawing{Image(100, 80)};
  drawing.line(a, b, {0, 0, 0}, 2.0);
  const Image image = drawing.image();
  // A 2 px stroke with round caps covers length x 2 + pi (the two half discs of radius 1).
  const double dx = b.x - a.x, dy = b.y - a.y, length = std::hypot(dx, dy);
  EXPECT_NEAR(ink(image), 2 * length + kPi, 0.01 * 2 * length);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const double px = x + 0.5 - a.x, py = y + 0.5 - a.y, along = (px * dx + py * dy) / length;
      const double off = along < 0        ? std::hypot(px, py)
                         : along > length ? std::hypot(x + 0.5 - b.x, y + 0.5 - b.y)
                                          : std::abs(px * dy - py * dx) / length;
      // A pixel reaches sqrt(2)/2 from its centre: beyond half the width plus that, no ink; a
      // centre within half the width less that, all ink.
      if (off > 1.0 + 0.71) {
        EXPECT_EQ(image.get(x, y), (Rgb{255, 255, 255})) << x << "," << y;
      }
      if (off < 1.0 - 0.71 && along > 1 && along < length - 1) {
        EXPECT_EQ(image.get(x, y), (Rgb{0, 0, 0})) << x << "," << y;
      }
    }
}

TEST(Drawing, RectangleCoverage) {
  Drawing drawing{Image(10, 10)};
  drawing.rect(2.5, 3.0, 5.0, 4.0, {0, 0, 0});
  const Image image = drawing.image();
  EXPECT_NEAR(image.get(2, 3)[0], 127.5, 1.0);  // half covered
  EXPECT_EQ(image.get(3, 3), (Rgb{0, 0, 0}));
  EXPECT_EQ(image.get(4, 3), (Rgb{0, 0, 0}));
  EXPECT_EQ(image.get(5, 3), (Rgb{255, 255, 255}));
  EXPECT_EQ(image.get(3, 4), (Rgb{255, 255, 255}));
  EXPECT_NEAR(ink(image), 2.5, 0.01);
}

TEST(Drawing, DiscAndRingCoverTheirAreas) {
  Drawing drawing{Image(60, 60)};
  drawing.disc({20.3, 20.6}, 8.0, {0, 0, 0});
  EXPECT_NEAR(ink(drawing.image()), kPi * 64, 0.01 * kPi * 64);
  Drawing ring{Image(60, 60)};
  ring.ring({30.0, 30.0}, 20.0, {0, 0, 0}, 2.0);  // the annulus between radii 19 and 21
  EXPECT_NEAR(ink(ring.image()), kPi * (21 * 21 - 19 * 19), 0.01 * kPi * 80);
}

TEST(Drawing, TextScalesWithItsHeight) {
  const std::string text = "Accuracy 0.005 mm, 1e-3 (q = 12) {ok}";
  const double small = text_width(text, 12.0);
  EXPECT_GT(small, 0.0);
  EXPECT_NEAR(text_width(text, 36.0), 3 * small, 1e-3);  // no hinting: advances scale exactly
  EXPECT_NEAR(text_width(text + text, 12.0), 2 * small, 1e-3);
  EXPECT_EQ(text_width("", 20.0), 0.0);

  // Capitals stand the height (cap height) above the baseline, to a pixel of anti-aliasing;
  // the ink starts after x (the H's side bearing) and ends before x + text_width. The box
  // the drawing records is that ink.
  const double height = 40;
  Drawing drawing{Image(400, 100)};
  drawing.text("HELLO", {20.0, 70.0}, height, {0, 0, 0});
  const Image image = drawing.image();
  int top = 100, bottom = -1, left = 400, right = -1;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (image.get(x, y)[0] < 128)
        top = std::min(top, y), bottom = std::max(bottom, y), left = std::min(left, x), right = std::max(right, x);
  EXPECT_NEAR(top, 70 - height, 1.0);
  EXPECT_NEAR(bottom + 1, 70, 1.0);
  EXPECT_GT(left, 20);
  EXPECT_LT(left, 20 + 0.25 * height);
  EXPECT_LT(right + 1, 20 + text_width("HELLO", height));
  ASSERT_EQ(drawing.texts().size(), 1u);
  const DrawnText& box = drawing.texts()[0];
  EXPECT_NEAR(box.y0, top, 1.0);
  EXPECT_NEAR(box.y1, bottom + 1, 1.0);
  EXPECT_NEAR(box.x0, left, 1.0);
  EXPECT_NEAR(box.x1, right + 1, 1.0);

  // Turned a quarter counter-clockwise about its middle: it reads upward, the cap height now
  // across x, left of the point (no round letter: an O overshoots the cap height), and along
  // y what the same text upright spans along x, mirrored (x - 70 upright is 200 - y turned).
  Drawing turned{Image(400, 400)};
  turned.text("HELL", {70.0, 200.0}, height, {0, 0, 0}, Align::kCenter, kPi / 2);
  turned.text("HELL", {70.0, 350.0}, height, {0, 0, 0}, Align::kCenter);
  const DrawnText &up = turned.texts()[0], &flat = turned.texts()[1];
  EXPECT_NEAR(up.x1 - up.x0, height, 1.0);
  EXPECT_NEAR(up.x1, 70.0, 1.0);
  EXPECT_NEAR(200.0 - up.y1, flat.x0 - 70.0, 0.01);
  EXPECT_NEAR(200.0 - up.y0, flat.x1 - 70.0, 0.01);
}

// Bytes that are not UTF-8 are drawn as '?' (Cairo would stop drawing on them); UTF-8 is drawn.
TEST(Drawing, TextThatIsNotUtf8) {
  Drawing drawing{Image(200, 50)};
  drawing.text(
      "a\xff\xc3"
      "b \xc2\xb5m \xe2\x82",
      {5.0, 30.0}, 12.0, {0, 0, 0});
  drawing.line({0, 44.5}, {200, 44.5}, {0, 0, 0});  // still drawing after it: row 44 covered
  ASSERT_EQ(drawing.texts().size(), 1u);
  EXPECT_EQ(drawing.texts()[0].text, "a??b \xc2\xb5m ??");
  EXPECT_EQ(drawing.image().get(100, 44)[0], 0);
}

TEST(Drawing, SvgIsOneDocumentOfItsSize) {
  Drawing drawing = Drawing::svg(320, 200);
  drawing.rect(10, 10, 100, 50, {255, 0, 0});
  drawing.text("label", {20, 40}, 12.0, {0, 0, 0});
  const std::string svg = drawing.svg();
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("width=\"320px\" height=\"200px\""), std::string::npos) << svg.substr(0, 300);
  EXPECT_EQ(svg.rfind("</svg>"), svg.size() - 7);
  EXPECT_THROW(drawing.image(), std::logic_error);
  EXPECT_THROW(Drawing(Image(4, 4)).svg(), std::logic_error);
}

TEST(Drawing, Labels) {
  EXPECT_EQ(format_label(0.005), "0.005");
  EXPECT_EQ(format_label(1e-5), "1e-5");
  EXPECT_EQ(format_label(1.5e6), "1.5e6");
  EXPECT_EQ(format_label(250.0), "250");
  EXPECT_EQ(format_label(0.1 + 0.2), "0.3");
  EXPECT_EQ(format_label(-2e-7, 2), "-2e-7");
}

TriangleMesh square(double side_mm, double angle_rad) {
  TriangleMesh mesh;
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  for (const auto& [u, v] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}})
    mesh.vertices_mm.emplace_back(side_mm * (c * u - s * v), side_mm * (s * u + c * v), 0.0);
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

int count_not(const Image& image, Rgb background) {
  int n = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) n += image.get(x, y) != background;
  return n;
}

TEST(Snapshot, SquareFromTopCoversItsArea) {
  SnapshotOptions options;
  options.width_px = 300, options.height_px = 200, options.margin = 0.1;
  const std::vector<Rgb> red(4, Rgb{200, 0, 0});
  // Margin 0.1 * 200 = 20 px: room 260 x 160 px, so 16 px/mm; the 10 mm square is 160 px a
  // side, centred at (150, 100): corners on whole pixels, no pixel centre on its outline, and
  // the shared diagonal through pixel centres counted once: exactly 160^2 pixels, unshaded.
  const Image image = render_snapshot(square(10, 0), red, view_direction("top"), options);
  EXPECT_EQ(count_not(image, options.background), 160 * 160);
  EXPECT_EQ(image.get(150, 100), (Rgb{200, 0, 0}));
  EXPECT_EQ(image.get(69, 100), options.background);
  EXPECT_EQ(image.get(71, 100), (Rgb{200, 0, 0}));
  EXPECT_EQ(image.get(70, 100), (Rgb{60, 0, 0})) << "outlined: 0.3 times";

  // Turned 30 deg: the box is 10 (cos 30 + sin 30) = 13.66 mm wide and high, fitted into
  // 400 - 2 * 20 = 360 px about the image centre. Centre sampling differs from the area only in
  // pixels the outline crosses: at most the perimeter times (|cos| + |sin|) of its slope, plus
  // the corners. A second count, pixel centres inside the square mapped by hand, may differ
  // only where the 1/256 px snapping of the corners moves the outline past a centre.
  options.width_px = options.height_px = 400, options.margin = 0.05;
  const double angle = kPi / 6, spread = std::cos(angle) + std::sin(angle);
  const double scale = 360 / (10 * spread), side_px = 10 * scale;
  const TriangleMesh turned = square(10, angle);
  const int n = count_not(render_snapshot(turned, red, view_direction("top"), options), options.background);
  EXPECT_NEAR(n, side_px * side_px, 4 * side_px * spread + 4);

  const double centre_x_mm = 10 * (std::cos(angle) - std::sin(angle)) / 2, centre_y_mm = 10 * spread / 2;
  int inside = 0;
  for (int y = 0; y < 400; ++y)
    for (int x = 0; x < 400; ++x) {
      // Back to the square's own (u, v) in mm: undo the screen map, then the turn.
      const double X = (x + 0.5 - 200) / scale + centre_x_mm, Y = -(y + 0.5 - 200) / scale + centre_y_mm;
      const double u = std::cos(angle) * X + std::sin(angle) * Y, v = -std::sin(angle) * X + std::cos(angle) * Y;
      inside += u > 0 && u < 10 && v > 0 && v < 10;
    }
  EXPECT_NEAR(n, inside, 4 * side_px / 64);
}

// The unit cube, outward counter-clockwise triangles, coloured (255 x, 255 y, 255 z).
TriangleMesh unit_cube(std::vector<Rgb>& colours) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices_mm.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
    colours.push_back(
        {std::uint8_t(255 * (i & 1)), std::uint8_t(255 * ((i >> 1) & 1)), std::uint8_t(255 * ((i >> 2) & 1))});
  }
  mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return mesh;
}

TEST(Snapshot, NearerFacesHideFartherOnes) {
  std::vector<Rgb> colours;
  TriangleMesh cube = unit_cube(colours);
  SnapshotOptions options;
  options.width_px = options.height_px = 101;
  for (int order = 0; order < 2; ++order) {
    // From the top the z = 1 face is seen face-on (shade 1): its colour at the middle is
    // (127.5, 127.5, 255) give or take the half-pixel offset; the z = 0 face would have blue 0.
    const Image top = render_snapshot(cube, colours, view_direction("top"), options);
    EXPECT_EQ(top.get(50, 50)[2], 255) << "order " << order;
    EXPECT_NEAR(top.get(50, 50)[0], 127.5, 2.0);
    // From the front (-y) the y = 0 face: green 0 everywhere it shows.
    const Image front = render_snapshot(cube, colours, view_direction("front"), options);
    EXPECT_EQ(front.get(50, 50)[1], 0) << "order " << order;
    EXPECT_NEAR(front.get(50, 50)[2], 127.5, 2.0);
    std::reverse(cube.triangles.begin(), cube.triangles.end());
  }
}

// A soup of overlapping random triangles: many depth tests and ties between bands.
TEST(Snapshot, SameBytesForOneAndTwoThreads) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> coordinate(0.0, 50.0), jitter(-3.0, 3.0);
  TriangleMesh mesh;
  std::vector<Rgb> colours;
  for (int t = 0; t < 20000; ++t) {
    const Eigen::Vector3d centre(coordinate(random), coordinate(random), coordinate(random));
    for (int k = 0; k < 3; ++k) {
      mesh.vertices_mm.push_back(centre + Eigen::Vector3d(jitter(random), jitter(random), jitter(random)));
      colours.push_back({std::uint8_t(random()), std::uint8_t(random()), std::uint8_t(random())});
    }
    mesh.triangles.emplace_back(3 * t, 3 * t + 1, 3 * t + 2);
  }
  SnapshotOptions options;
  options.width_px = 640, options.height_px = 480, options.title = "Threads";
  options.legend = ColourScale{"value (mm)", -0.05, 0.05,
                               [](double v) {
                                 return Rgb{std::uint8_t(128 + 2000 * v), 0, 0};
                               },
                               5};
  std::vector<Image> images;
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    images.push_back(render_snapshot(mesh, colours, view_direction("iso"), options));
  }
  EXPECT_EQ(images[0].rgb, images[1].rgb);
  EXPECT_GT(count_not(images[0], options.background), 640 * 480 / 4);
}

// Where two triangles tie in depth the earlier in the mesh stays, however far apart they lie
// in it: a red square first, 9,000 small grey triangles beside it, then a blue square on the
// red one (the triangles are binned to rows in chunks of the mesh; the blue one's chunk comes
// two after the red one's).
TEST(Snapshot, OnATieTheEarlierTriangleStays) {
  TriangleMesh mesh = square(10, 0);
  std::vector<Rgb> colours(4, Rgb{200, 0, 0});
  for (int t = 0; t < 9000; ++t) {
    const Eigen::Vector3d corner(12.0 + 0.1 * (t % 80), 0.1 * (t / 80), 0.0);
    const int first = static_cast<int>(mesh.vertices_mm.size());
    for (const Eigen::Vector3d& d :
         {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.05, 0, 0), Eigen::Vector3d(0, 0.05, 0)})
      mesh.vertices_mm.push_back(corner + d);
    colours.insert(colours.end(), 3, Rgb{120, 120, 120});
    mesh.triangles.emplace_back(first, first + 1, first + 2);
  }
  const int blue = static_cast<int>(mesh.vertices_mm.size());
  for (const Eigen::Vector3d& v : square(10, 0).vertices_mm) mesh.vertices_mm.push_back(v);
  colours.insert(colours.end(), 4, Rgb{0, 0, 200});
  mesh.triangles.emplace_back(blue, blue + 1, blue + 2);
  mesh.triangles.emplace_back(blue, blue + 2, blue + 3);
  SnapshotOptions options;
  options.width_px = 400, options.height_px = 300;
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    const Image image = render_snapshot(mesh, colours, view_direction("top"), options);
    int red = 0, blues = 0;
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        const Rgb c = image.get(x, y);
        red += c[0] > 0 && c[1] == 0 && c[2] == 0;
        blues += c[2] > 0 && c[0] == 0;
      }
    EXPECT_GT(red, 1000) << threads;
    EXPECT_EQ(blues, 0) << threads;
  }
}

TEST(Snapshot, WritesThreeViews) {
  std::vector<Rgb> colours;
  const TriangleMesh cube = unit_cube(colours);
  SnapshotOptions options;
  options.width_px = 320, options.height_px = 240, options.title = "Cube";
  const fs::path folder = test_dir() / "views";
  const auto names = write_snapshots(folder.string(), "cube", cube, colours, options);
  ASSERT_EQ(names, (std::vector<std::string>{"cube_iso.png", "cube_top.png", "cube_front.png"}));
  for (const auto& name : names) {
    const Image image = decode_png((folder / name).string());
    EXPECT_EQ(image.width, 320);
    EXPECT_EQ(image.height, 240);
  }
  EXPECT_THROW(view_direction("left"), InputError);
}

}  // namespace
}  // namespace vcut::report
