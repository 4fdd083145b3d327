#pragma once
/// \file plot.hpp
/// The one line plotter of geohaz's PNG figures, on core's Image (raster.hpp) with its Pango text:
/// a panel that maps data to pixels, its frame, its axes numbered at nice_ticks, and curves. The
/// runout figures (profile.png, gauges.png) and the validation plots of the tests draw with it; the
/// SVG plots of the report page (libs/report) take their ticks from the same nice_ticks and
/// nice_range.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"

namespace geohaz {

/// A panel of a plot: its data range and its pixel box (y up in the data, down in the picture).
struct PlotPanel {
  double x0, x1, y0, y1;         ///< data range
  int left, top, width, height;  ///< pixel box
  double px(double x) const { return left + (x - x0) / (x1 - x0) * width; }
  double py(double y) const { return top + height - (y - y0) / (y1 - y0) * height; }
};

/// [lo, hi] rounded out to nice ticks (widened first when empty).
void nice_range(double& lo, double& hi);

/// The panel's frame in `colour` (left, bottom, top, right edges).
void draw_frame(Image& img, const PlotPanel& f, std::array<std::uint8_t, 3> colour = {0, 0, 0});

/// Frame, grid, ticks numbered at nice steps (about 8 on x, 5 on y), the x title below and the y
/// title above the panel; text at `scale` (capitals 7 · scale pixels high).
void draw_axes(Image& img, const PlotPanel& f, const std::string& x_title, const std::string& y_title, int scale);

/// A polyline `width` pixels thick (vertical offsets of a one-pixel line); a segment with a
/// non-finite end is left out (a gap).
void draw_polyline(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
                   std::array<std::uint8_t, 3> colour, int width = 1);

}  // namespace geohaz
