// Tests of the study plots (plot.h): axis mapping and ticks worked out by hand, the SVG and
// the PNG agreeing on where a marker is, labels apart, and atomic writing.
#include <gtest/gtest.h>
#include <vcut/io/input_error.h>
#include <vcut/report/plot.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace vcut::report {
namespace {
namespace fs = std::filesystem;

TEST(PlotAxis, LinearAndLogMapping) {
  PlotAxis linear;
  linear.min = 0.0;
  linear.max = 10.0;
  linear.px_min = 100.0;
  linear.px_max = 300.0;
  EXPECT_DOUBLE_EQ(linear.to_px(0.0), 100.0);
  EXPECT_DOUBLE_EQ(linear.to_px(2.5), 150.0);
  EXPECT_DOUBLE_EQ(linear.to_px(10.0), 300.0);
  // A y axis runs upward: px_min (the bottom) is the larger pixel row.
  PlotAxis log;
  log.log = true;
  log.min = 1e-3;
  log.max = 1e-1;
  log.px_min = 500.0;
  log.px_max = 100.0;
  EXPECT_NEAR(log.to_px(1e-2), 300.0, 1e-9);  // the middle decade, half way
  EXPECT_NEAR(log.to_px(1e-1), 100.0, 1e-9);
  EXPECT_NEAR(log.to_px(0.0), 500.0, 1e-9);  // not drawable on a log scale: the minimum
  EXPECT_NEAR(log.to_px(-5.0), 500.0, 1e-9);
  EXPECT_NEAR(log.to_px(1e-5), 500.0, 1e-9);  // below the range: the minimum
}

TEST(PlotAxis, Ticks) {
  PlotAxis a;
  a.min = 0.0;
  a.max = 10.0;
  EXPECT_EQ(a.ticks(), (std::vector<double>{0, 2, 4, 6, 8, 10}));  // 10 / 5 = 2: a 1-2-5 step
  a.min = -0.3;
  a.max = 0.75;
  const std::vector<double> t = a.ticks();  // 1.05 / 5 = 0.21 -> step 0.5: 0 and 0.5 lie within
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0], 0.0);
  EXPECT_NEAR(t[1], 0.5, 1e-12);
  a.log = true;
  a.min = 1e-4;
  a.max = 1e-1;
  const std::vector<double> decades = a.ticks();  // four decades: no 2s and 5s
  ASSERT_EQ(decades.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(decades[static_cast<std::size_t>(i)], std::pow(10.0, -4 + i), 1e-18);
  a.min = 0.03;
  a.max = 0.7;  // one decade inside: 0.05, 0.1, 0.2, 0.5
  const std::vector<double> filled = a.ticks();
  ASSERT_EQ(filled.size(), 4u);
  EXPECT_NEAR(filled[0], 0.05, 1e-15);
  EXPECT_NEAR(filled[1], 0.1, 1e-15);
  EXPECT_NEAR(filled[2], 0.2, 1e-15);
  EXPECT_NEAR(filled[3], 0.5, 1e-15);
}

Plot sample_plot() {
  Plot plot;
  plot.title = "a <&> \"title\"";
  PlotPanel p;
  p.title = "log-log";
  p.log_x = p.log_y = true;
  p.series.push_back({"max", {214, 39, 40}, {{50, 0.07}, {100, 0.017}, {200, 0.004}}, true, true, {"8", "4", "2"}});
  p.marks.push_back({true, 0.01, "accuracy", {200, 40, 40}});
  p.highlights.push_back({{200, 0.004}, "recommended", {0, 150, 60}});
  PlotPanel q;
  q.title = "linear";
  q.series.push_back({"one", {31, 119, 180}, {{1.0, 2.0}, {3.0, 0.0}}, false, true, {}});
  plot.panels = {p, q};
  return plot;
}

// The marker at (3, 0) in the second panel: a 4 px disc in its colour, at the pixel the
// frame maps it to, in both back ends.
TEST(Plot, SvgAndPngPutAMarkerWhereTheFrameSays) {
  const Plot plot = sample_plot();
  const PanelFrame f = panel_frame(plot, 1);
  EXPECT_GT(f.x.px_min, plot.width_px / 2.0);  // the second panel is the right half
  const double x = f.x.to_px(3.0), y = f.y.to_px(0.0);
  const Image image = render_png(plot);
  const Rgb c = image.get(static_cast<int>(x), static_cast<int>(y));
  EXPECT_EQ(c, (Rgb{31, 119, 180}));
  // Cairo writes the disc as a path of arcs starting at its rightmost point, (x + 4, y),
  // filled with the series' colour in percent.
  const std::string svg = render_svg(plot);
  char fill[96];
  std::snprintf(fill, sizeof fill, "fill:rgb(%f%%,%f%%,%f%%);", 100 * 31 / 255.0, 100 * 119 / 255.0, 100 * 180 / 255.0);
  bool marker = false;
  for (std::size_t at = svg.find(fill); at != std::string::npos; at = svg.find(fill, at + 1)) {
    const std::size_t d = svg.find("d=\"M ", at);
    if (d == std::string::npos) break;
    double mx = 0, my = 0;
    if (std::sscanf(svg.c_str() + d, "d=\"M %lf %lf", &mx, &my) == 2)
      marker = marker || (std::abs(mx - (x + 4.0)) < 0.01 && std::abs(my - y) < 0.01);
  }
  EXPECT_TRUE(marker) << "no disc path at (" << x + 4.0 << ", " << y << ") filled " << fill;
  EXPECT_EQ(svg.find("<&>"), std::string::npos);
  EXPECT_EQ(svg.rfind("</svg>\n"), svg.size() - 7);
  // The log panel: the x range holds 50..200, the y range 0.004..0.07 and the mark.
  const PanelFrame g = panel_frame(plot, 0);
  EXPECT_LT(g.x.min, 50.0);
  EXPECT_GT(g.x.max, 200.0);
  EXPECT_LT(g.y.min, 0.004);
  EXPECT_GT(g.y.max, 0.07);
}

// The same plot gives the same SVG bytes however much was drawn before it in the process
// (Cairo numbers its surfaces process-wide).
TEST(Plot, SvgBytesDoNotDependOnWhatWasDrawnBefore) {
  const std::string first = render_svg(sample_plot());
  for (int i = 0; i < 5; ++i) render_png(sample_plot());
  EXPECT_EQ(render_svg(sample_plot()), first);
}

TEST(Plot, WriteIsAtomicAndNamesAnUnwritablePath) {
  const fs::path dir = fs::path(::testing::TempDir()) / "vcut_plot_write";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_plot((dir / "p.svg").string(), (dir / "p.png").string(), sample_plot());
  EXPECT_GT(fs::file_size(dir / "p.svg"), 1000u);
  EXPECT_GT(fs::file_size(dir / "p.png"), 1000u);
  std::ofstream(dir / "blocker") << "a file where a folder should be";
  try {
    write_plot((dir / "blocker" / "p.svg").string(), (dir / "blocker" / "p.png").string(), sample_plot());
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("blocker"), std::string::npos) << e.what();
  }
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) files += entry.is_regular_file();
  EXPECT_EQ(files, 3u);  // p.svg, p.png, blocker: no temporaries left
  fs::remove_all(dir);
}

// An empty panel and a panel whose values are all one number still get a drawable range.
TEST(Plot, DegenerateRanges) {
  Plot plot;
  PlotPanel empty, flat;
  empty.log_y = true;
  flat.series.push_back({"flat", {0, 0, 0}, {{2.0, 5.0}, {2.0, 5.0}}, true, true, {}});
  plot.panels = {empty, flat};
  for (std::size_t i = 0; i < 2; ++i) {
    const PanelFrame f = panel_frame(plot, i);
    EXPECT_LT(f.x.min, f.x.max);
    EXPECT_LT(f.y.min, f.y.max);
    EXPECT_TRUE(std::isfinite(f.y.to_px(5.0)));
  }
  EXPECT_NO_THROW(render_png(plot));
}

// A value a log axis cannot show (0) is drawn, at the bottom of the frame, not dropped.
TEST(Plot, LogValueZeroIsDrawnAtTheAxisMinimum) {
  Plot plot;
  PlotPanel p;
  p.log_y = true;
  p.series.push_back({"", {214, 39, 40}, {{1.0, 0.1}, {2.0, 0.0}, {3.0, 0.01}}, false, true, {}});
  plot.panels = {p};
  const PanelFrame f = panel_frame(plot, 0);
  EXPECT_NEAR(f.y.to_px(0.0), f.y.px_min, 1e-9);
  const Image image = render_png(plot);
  EXPECT_EQ(image.get(static_cast<int>(f.x.to_px(2.0)), static_cast<int>(f.y.px_min)), (Rgb{214, 39, 40}));
}

// The texts drawn on the plot that start with `prefix`, with their ink boxes.
std::vector<DrawnText> drawn_texts(const Plot& plot, const std::string& prefix) {
  Drawing drawing{Image(plot.width_px, plot.height_px)};
  draw_plot(drawing, plot);
  std::vector<DrawnText> out;
  for (const DrawnText& t : drawing.texts())
    if (t.text.rfind(prefix, 0) == 0) out.push_back(t);
  return out;
}

// Ten long labels on points crowded into a plateau: the ones drawn do not overlap each other,
// the mark's label or the legend, and stay in the panel's column. Spread out along a diagonal
// (and with no legend taking a corner), all ten are drawn.
TEST(Plot, PointLabelsDoNotOverlap) {
  Plot plot;
  plot.width_px = 1000;
  PlotPanel crowded;
  crowded.log_x = crowded.log_y = true;
  PlotSeries s{"label test series", {214, 39, 40}, {}, true, true, {}};
  for (int i = 0; i < 10; ++i) {
    s.points.push_back({std::pow(2.0, i), 0.001 * (1.0 + 0.002 * i)});
    s.labels.push_back("setting " + std::to_string(i) + " mm/0.125 deg");
  }
  PlotSeries scale{"", {31, 119, 180}, {{1.0, 1.0}, {512.0, 1.0}}, false, true, {}};
  crowded.series = {s, scale};  // three decades of y: the labelled points lie within 1 px of each other
  crowded.marks.push_back({true, 0.00101, "setting mark", {200, 40, 40}});
  PlotPanel spread = crowded;
  spread.marks.clear();
  spread.series = {s};
  spread.series[0].name.clear();
  for (int i = 0; i < 10; ++i) spread.series[0].points[static_cast<std::size_t>(i)].y = std::pow(2.0, -i);
  plot.panels = {crowded, spread};
  const std::vector<DrawnText> texts = drawn_texts(plot, "setting");
  const std::vector<DrawnText> legend = drawn_texts(plot, "label test series");
  ASSERT_EQ(legend.size(), 1u);
  std::size_t in_spread = 0;
  for (std::size_t i = 0; i < texts.size(); ++i) {
    const DrawnText& a = texts[i];
    const bool second = a.x0 >= plot.width_px / 2.0;
    in_spread += second && a.text != "setting mark";
    // Within its column: half of the width each.
    EXPECT_GE(a.x0, second ? plot.width_px / 2.0 : 0.0) << a.text;
    EXPECT_LE(a.x1, second ? plot.width_px : plot.width_px / 2.0) << a.text;
    const PanelFrame f = panel_frame(plot, second ? 1 : 0);
    EXPECT_GE(a.y0, f.y.px_max) << a.text;
    EXPECT_LE(a.y1, f.y.px_min) << a.text;
    std::vector<DrawnText> others(texts.begin() + static_cast<std::ptrdiff_t>(i) + 1, texts.end());
    others.insert(others.end(), legend.begin(), legend.end());
    for (const DrawnText& b : others) {
      const bool apart = a.x1 <= b.x0 || b.x1 <= a.x0 || a.y1 <= b.y0 || b.y1 <= a.y0;
      EXPECT_TRUE(apart) << "'" << a.text << "' overlaps '" << b.text << "'";
    }
  }
  EXPECT_EQ(in_spread, 10u);
  EXPECT_GE(texts.size() - in_spread, 3u);  // the mark's label and at least a couple of points
}

}  // namespace
}  // namespace vcut::report
