#pragma once
/// \file plot_support.hpp
/// Axes and curves of the runout line figures (profile.png, gauges.png), drawn on core's Image
/// with its Pango text (internal to libs/runout; not installed).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"

namespace geohaz::runout::detail {

/// A panel of a plot: data range and its pixel box.
struct Panel {
  double x0, x1, y0, y1;  // data
  int left, top, width, height;
  double px(double x) const { return left + (x - x0) / (x1 - x0) * width; }
  double py(double y) const { return top + height - (y - y0) / (y1 - y0) * height; }
};

/// Frame, grid, ticks numbered at nice steps, the x title below and the y title above the panel.
void axes(Image& img, const Panel& f, const std::string& x_title, const std::string& y_title, int s);

/// A polyline `width` pixels thick; a segment with a non-finite end is left out (a gap).
void thick_polyline(Image& img, const Panel& f, const std::vector<double>& x, const std::vector<double>& y,
                    std::array<std::uint8_t, 3> c, int width);

}  // namespace geohaz::runout::detail
