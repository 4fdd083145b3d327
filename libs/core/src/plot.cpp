/// \file plot.cpp
/// The line plotter of the PNG figures (plot.hpp), drawn through Image and draw_text only.

#include "geohaz/core/plot.hpp"

#include <algorithm>
#include <cmath>

namespace geohaz {

void nice_range(double& lo, double& hi) {
  if (!(hi > lo)) {
    const double d = std::max(1e-9, std::abs(lo) * 0.05 + (lo == 0 ? 1 : 0));
    lo -= d;
    hi += d;
  }
  const auto t = nice_ticks(lo, hi, 5);
  if (t.size() >= 2) {
    const double step = t[1] - t[0];
    lo = std::floor(lo / step + 1e-9) * step;
    hi = std::ceil(hi / step - 1e-9) * step;
  }
}

void draw_frame(Image& img, const PlotPanel& f, std::array<std::uint8_t, 3> colour) {
  img.line(f.left, f.top, f.left, f.top + f.height, colour);
  img.line(f.left, f.top + f.height, f.left + f.width, f.top + f.height, colour);
  img.line(f.left, f.top, f.left + f.width, f.top, colour);
  img.line(f.left + f.width, f.top, f.left + f.width, f.top + f.height, colour);
}

void draw_axes(Image& img, const PlotPanel& f, const std::string& x_title, const std::string& y_title, int s) {
  const std::array<std::uint8_t, 3> black{0, 0, 0}, grid{225, 225, 225};
  for (double v : nice_ticks(f.x0, f.x1, 8)) {
    const double x = f.px(v);
    img.line(x, f.top, x, f.top + f.height, grid);
    img.line(x, f.top + f.height, x, f.top + f.height + 6, black);
    const std::string t = format_tick(v);
    draw_text(img, static_cast<int>(x) - text_width(t, s) / 2, f.top + f.height + 10, t, s);
  }
  for (double v : nice_ticks(f.y0, f.y1, 5)) {
    const double y = f.py(v);
    img.line(f.left, y, f.left + f.width, y, grid);
    img.line(f.left - 6, y, f.left, y, black);
    const std::string t = format_tick(v);
    draw_text(img, f.left - 10 - text_width(t, s), static_cast<int>(y) - 7 * s / 2, t, s);
  }
  draw_frame(img, f, black);
  draw_text(img, f.left + (f.width - text_width(x_title, s)) / 2, f.top + f.height + 20 + 7 * s, x_title, s);
  draw_text(img, f.left, f.top - 12 - 7 * s, y_title, s);
}

void draw_polyline(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
                   std::array<std::uint8_t, 3> c, int width) {
  for (std::size_t k = 1; k < x.size() && k < y.size(); ++k) {
    if (!std::isfinite(y[k - 1]) || !std::isfinite(y[k])) continue;
    for (int o = -width / 2; o <= width / 2; ++o)
      img.line(f.px(x[k - 1]), f.py(y[k - 1]) + o, f.px(x[k]), f.py(y[k]) + o, c);
  }
}

}  // namespace geohaz
