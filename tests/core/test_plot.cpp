// Core's plotter (plot.hpp): the panel's mappings (linear and logarithmic), and check_plot_png,
// which tells a figure with numbered, titled axes from one that lost them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

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

TEST(DrawLegend, RowsWrapAtTheGivenWidth) {
  const std::vector<LegendEntry> e{{{0, 0, 0}, "intact bond"}, {{255, 0, 0}, "tensile crack"}};
  EXPECT_EQ(legend_height({}, 500, 2), 0);
  EXPECT_EQ(legend_height(e, 1000, 2), 14);      // one row of capitals 7 · 2 high
  EXPECT_EQ(legend_height(e, 100, 2), 14 + 22);  // two rows, 8 px apart
}

}  // namespace
}  // namespace geohaz
