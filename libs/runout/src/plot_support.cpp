/// \file plot_support.cpp
/// Axes and curves of the runout line figures (plot_support.hpp).

#include "plot_support.hpp"

#include <cmath>

namespace geohaz::runout::detail {

void axes(Image& img, const Panel& f, const std::string& x_title, const std::string& y_title, int s) {
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
  img.line(f.left, f.top, f.left, f.top + f.height, black);
  img.line(f.left, f.top + f.height, f.left + f.width, f.top + f.height, black);
  img.line(f.left, f.top, f.left + f.width, f.top, black);
  img.line(f.left + f.width, f.top, f.left + f.width, f.top + f.height, black);
  draw_text(img, f.left + (f.width - text_width(x_title, s)) / 2, f.top + f.height + 20 + 7 * s, x_title, s);
  draw_text(img, f.left, f.top - 12 - 7 * s, y_title, s);
}

void thick_polyline(Image& img, const Panel& f, const std::vector<double>& x, const std::vector<double>& y,
                    std::array<std::uint8_t, 3> c, int width) {
  for (std::size_t k = 1; k < x.size() && k < y.size(); ++k) {
    if (!std::isfinite(y[k - 1]) || !std::isfinite(y[k])) continue;
    for (int o = -width / 2; o <= width / 2; ++o)
      img.line(f.px(x[k - 1]), f.py(y[k - 1]) + o, f.px(x[k]), f.py(y[k]) + o, c);
  }
}

}  // namespace geohaz::runout::detail
