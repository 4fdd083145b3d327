// Core's plotter (plot.hpp): the panel's mappings (linear and logarithmic), the panel at equal
// scale and its layer of coloured discs (particle pictures), the colour bar's ends, and
// check_plot_png, which tells a figure with numbered, titled axes from one that lost them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include "geohaz/core/plot.hpp"
#include "geohaz/core/raster_extra.hpp"

namespace fs = std::filesystem;

namespace geohaz {
namespace {

fs::path temp_file(const std::string& name) {
  const auto d = fs::temp_directory_path() / ("geohaz_test_plot_" + std::to_string(getpid()));
  fs::create_directories(d);
  return d / name;
}

const PlotPanel kPanel{0.0, 100.0, 0.0, 2.0, 90, 40, 600, 300};

TEST(PlotPanel, MapsTheDataRangeOntoThePixelBox) {
  EXPECT_DOUBLE_EQ(kPanel.px(0.0), 90.0);
  EXPECT_DOUBLE_EQ(kPanel.px(100.0), 690.0);
  EXPECT_DOUBLE_EQ(kPanel.py(0.0), 340.0);  // y up in the data, down in the picture
  EXPECT_DOUBLE_EQ(kPanel.py(2.0), 40.0);
}

TEST(PlotPanel, LogarithmicAxisPutsTheGeometricMeanInTheMiddle) {
  const PlotPanel f{0.0, 1.0, 1e-4, 1e-0, 0, 0, 100, 400, true};
  EXPECT_NEAR(f.py(1e-4), 400.0, 1e-9);
  EXPECT_NEAR(f.py(1e-2), 200.0, 1e-9);
  EXPECT_NEAR(f.py(1.0), 0.0, 1e-9);
  EXPECT_NEAR(f.py(0.0), 400.0, 1e-9);   // nothing to take the logarithm of: the bottom edge
  EXPECT_NEAR(f.py(1e-9), 400.0, 1e-9);  // below the range: clamped to it
}

TEST(CheckPlotPng, AxesNumberedAndTitledPass) {
  Image img(760, 420);
  draw_axes(img, kPanel, "distance (m)", "thickness (m)", 2);
  draw_polyline(img, kPanel, {0, 50, 100}, {0, 2, 1}, {200, 0, 0}, 2);
  draw_bars(img, kPanel, {10, 20, 30}, {0.5, 1.0, 1.5}, {160, 120, 70}, 3);
  draw_markers(img, kPanel, {60, 70}, {1.0, 1.2}, {0, 0, 200});
  const fs::path p = temp_file("axes.png");
  write_plot_png(p, img, {kPanel}, 2);
  EXPECT_TRUE(check_plot_png(p).empty()) << check_plot_png(p).front();
  fs::remove_all(p.parent_path());
}

TEST(CheckPlotPng, FigureThatLostItsAxesIsFlagged) {
  Image img(760, 420);
  draw_frame(img, kPanel);
  draw_polyline(img, kPanel, {0, 50, 100}, {0, 2, 1}, {200, 0, 0}, 2);
  const fs::path p = temp_file("bare.png");
  write_plot_png(p, img, {kPanel}, 2);
  const auto problems = check_plot_png(p);
  ASSERT_EQ(problems.size(), 4u);
  EXPECT_EQ(problems[0], "panel 1: fewer than two numbered ticks on the y axis");
  EXPECT_EQ(problems[1], "panel 1: fewer than two numbered ticks on the x axis");
  EXPECT_EQ(problems[2], "panel 1: no x axis title");
  EXPECT_EQ(problems[3], "panel 1: no y axis title");
  // Nothing at all: no frame either; a PNG without the record is not a plot of ours.
  write_plot_png(p, Image(760, 420), {kPanel}, 2);
  EXPECT_EQ(check_plot_png(p).front(), "panel 1: no frame");
  write_png(p, img);
  EXPECT_EQ(check_plot_png(p).front(), "records no plot layout (not written by write_plot_png)");
  fs::remove_all(p.parent_path());
}

TEST(EqualScalePanel, SameScaleOnBothAxesWithinTheBox) {
  // Wide: 480 m by 150 m into 1000 x 800 pixels; the width limits the scale.
  const PlotPanel w = equal_scale_panel(0.0, 480.0, 1000.0, 1150.0, 100, 50, 1000, 800);
  EXPECT_NEAR(w.width / (w.x1 - w.x0), w.height / (w.y1 - w.y0), 1e-9);  // pixels per metre on x = on y
  EXPECT_LE(w.width, 1000);
  EXPECT_GE(w.width, 998);
  EXPECT_NEAR(w.height, 150.0 / 480.0 * w.width, 1.0);
  EXPECT_LE(w.x1 - 480.0, (w.x1 - w.x0) / w.width);  // widened by less than a pixel
  EXPECT_GE(w.x1, 480.0);
  EXPECT_GE(w.y1, 1150.0);
  // Tall: the height limits it.
  const PlotPanel t = equal_scale_panel(-1.0, 1.0, 0.0, 10.0, 0, 0, 1000, 501);
  EXPECT_NEAR(t.width / (t.x1 - t.x0), t.height / (t.y1 - t.y0), 1e-9);
  EXPECT_EQ(t.height, 500);
  EXPECT_EQ(t.width, 100);
  // A circle of data radius 1 spans as many pixels across as up.
  EXPECT_NEAR(t.px(1.0) - t.px(-1.0), t.py(4.0) - t.py(6.0), 1e-9);
}

TEST(AxesTicks, SameStepNumbersTheYAxisAtTheXStep) {
  const PlotPanel f = equal_scale_panel(0.0, 120.0, 0.0, 30.0, 100, 60, 1000, 800);
  const auto plain = axes_ticks(f, {8, 5, false});
  ASSERT_GE(plain[0].size(), 2u);
  ASSERT_GE(plain[1].size(), 2u);
  EXPECT_NE(plain[0][1] - plain[0][0], plain[1][1] - plain[1][0]);  // 20 m on x, 10 m on y: unequal
  const auto same = axes_ticks(f, {8, 5, false, true});
  EXPECT_EQ(same[0], plain[0]);
  ASSERT_GE(same[1].size(), 2u);
  EXPECT_DOUBLE_EQ(same[1][1] - same[1][0], same[0][1] - same[0][0]);
  EXPECT_DOUBLE_EQ(same[1].front(), 0.0);
  // Too short a y axis for two ticks at the x step: the y axis keeps its own step.
  const PlotPanel thin = equal_scale_panel(0.0, 120.0, 0.0, 12.0, 100, 60, 1000, 800);
  EXPECT_EQ(axes_ticks(thin, {8, 5, false, true})[1], axes_ticks(thin, {8, 5, false})[1]);
}

TEST(DrawDiscs, DiscLandsAtItsDataPointWithItsDataRadius) {
  const PlotPanel f = equal_scale_panel(0.0, 10.0, 0.0, 5.0, 40, 30, 401, 401);  // 40 px per metre
  ASSERT_EQ(f.width, 400);
  Image img(500, 300);
  const std::array<std::uint8_t, 3> red{220, 30, 30}, blue{30, 30, 220};
  draw_discs(img, f, {3.0, 8.0}, {1.0, 4.0}, {red, blue}, 0.25);  // 10 px radius
  for (const auto& [col, x, z] : {std::tuple{red, 3.0, 1.0}, std::tuple{blue, 8.0, 4.0}}) {
    double sx = 0, sy = 0, n = 0;
    for (int py = 0; py < img.height; ++py)
      for (int px = 0; px < img.width; ++px) {
        const std::size_t i = (static_cast<std::size_t>(py) * img.width + px) * 3;
        if (img.rgb[i] == col[0] && img.rgb[i + 1] == col[1] && img.rgb[i + 2] == col[2]) {
          sx += px;
          sy += py;
          ++n;
        }
      }
    ASSERT_GT(n, 0);
    EXPECT_NEAR(sx / n, 40 + 40 * x, 0.6) << "disc at x = " << x;             // px(3) = 160, px(8) = 360
    EXPECT_NEAR(sy / n, 30 + f.height - 40 * z, 0.6) << "disc at z = " << z;  // y up in the data
    EXPECT_NEAR(n, std::numbers::pi * 100.0, 0.15 * std::numbers::pi * 100.0)
        << "disc at x = " << x;  // radius 0.25 m = 10 px
  }
}

TEST(DrawColourBar, EndsCarryTheRampsEndColours) {
  Image img(400, 120);
  const int h = draw_colour_bar(img, 20, 10, 300, ColourRamp::Viridis, 0.0, 7.0, "displacement (m)", 2);
  EXPECT_GT(h, 20);
  auto at = [&](int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * img.width + x) * 3;
    return std::array<std::uint8_t, 3>{img.rgb[i], img.rgb[i + 1], img.rgb[i + 2]};
  };
  EXPECT_EQ(at(20, 15), ramp_colour(ColourRamp::Viridis, 0.0));   // vmin at the left end
  EXPECT_EQ(at(319, 15), ramp_colour(ColourRamp::Viridis, 1.0));  // vmax at the right end
  EXPECT_EQ(at(320, 15), (std::array<std::uint8_t, 3>{255, 255, 255}));
}

TEST(CheckPlotPng, ParticlePictureAtEqualScalePasses) {
  const PlotPanel f = equal_scale_panel(0.0, 20.0, 0.0, 8.0, 100, 60, 600, 400);
  Image img(f.left + f.width + 40, f.top + f.height + 150);
  std::vector<double> x, z;
  std::vector<std::array<std::uint8_t, 3>> c;
  for (int i = 0; i < 40; ++i)
    for (int k = 0; k < 8 && k < 8 - i / 5; ++k) {
      x.push_back(0.25 + 0.5 * i);
      z.push_back(0.25 + 0.5 * k);
      c.push_back(ramp_colour(ColourRamp::Viridis, i / 39.0));
    }
  draw_discs(img, f, x, z, c, 0.25);
  draw_axes(img, f, "x (m)", "z (m)", 2, {6, 4, false});
  draw_colour_bar(img, f.left, f.top + f.height + 60, f.width, ColourRamp::Viridis, 0.0, 1.0, "t (1)", 2);
  const fs::path p = temp_file("discs.png");
  write_plot_png(p, img, {f}, 2);
  EXPECT_TRUE(check_plot_png(p).empty()) << check_plot_png(p).front();
  fs::remove_all(p.parent_path());
}

TEST(DrawLegend, RowsWrapAtTheGivenWidth) {
  const std::vector<LegendEntry> e{{{0, 0, 0}, "intact bond"}, {{255, 0, 0}, "tensile crack"}};
  EXPECT_EQ(legend_height({}, 500, 2), 0);
  EXPECT_EQ(legend_height(e, 1000, 2), 14);      // one row of capitals 7 · 2 high
  EXPECT_EQ(legend_height(e, 100, 2), 14 + 22);  // two rows, 8 px apart
}

}  // namespace
}  // namespace geohaz
