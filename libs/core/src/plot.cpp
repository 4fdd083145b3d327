/// \file plot.cpp
/// The plotter of the PNG figures (plot.hpp), drawn through Image and draw_text only; the recorded
/// panels are read back through read_png_text and read_image (raster_extra.hpp).

#include "geohaz/core/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "geohaz/core/raster_extra.hpp"

namespace geohaz {

double PlotPanel::py(double y) const {
  if (!log_y) return top + height - (y - y0) / (y1 - y0) * height;
  const double l0 = std::log10(y0), l1 = std::log10(y1);
  const double l = y > 0 ? std::clamp(std::log10(y), l0, l1) : l0;
  return top + height - (l - l0) / (l1 - l0) * height;
}

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

namespace {

/// The y tick values of a panel: nice ticks, or the decades of a logarithmic axis.
std::vector<double> y_ticks(const PlotPanel& f, int n) {
  if (!f.log_y) return nice_ticks(f.y0, f.y1, n);
  std::vector<double> t;
  for (int k = static_cast<int>(std::ceil(std::log10(f.y0) - 1e-9)); k <= std::floor(std::log10(f.y1) + 1e-9); ++k)
    t.push_back(std::pow(10.0, k));
  return t;
}

}  // namespace

std::array<std::vector<double>, 2> axes_ticks(const PlotPanel& f, const AxesStyle& style) {
  std::array<std::vector<double>, 2> t{nice_ticks(f.x0, f.x1, style.x_ticks), y_ticks(f, style.y_ticks)};
  if (style.same_step && !f.log_y && t[0].size() >= 2) {
    const double step = t[0][1] - t[0][0], eps = 1e-9 * step;
    std::vector<double> y;
    for (double k = std::ceil((f.y0 - eps) / step); k * step <= f.y1 + eps; k += 1.0) y.push_back(k * step);
    if (y.size() >= 2) t[1] = std::move(y);
  }
  return t;
}

void draw_axes(Image& img, const PlotPanel& f, const std::string& x_title, const std::string& y_title, int s,
               const AxesStyle& style) {
  const std::array<std::uint8_t, 3> black{0, 0, 0}, grid{225, 225, 225};
  const auto ticks = axes_ticks(f, style);
  for (double v : ticks[0]) {
    const double x = f.px(v);
    if (style.grid) img.line(x, f.top, x, f.top + f.height, grid);
    img.line(x, f.top + f.height, x, f.top + f.height + 6, black);
    const std::string t = format_tick(v);
    draw_text(img, static_cast<int>(x) - text_width(t, s) / 2, f.top + f.height + 10, t, s);
  }
  for (double v : ticks[1]) {
    const double y = f.py(v);
    if (style.grid) img.line(f.left, y, f.left + f.width, y, grid);
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

void draw_bars(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
               std::array<std::uint8_t, 3> c, int width, double base) {
  for (std::size_t k = 0; k < x.size() && k < y.size(); ++k) {
    if (!std::isfinite(x[k]) || !std::isfinite(y[k]) || y[k] == base) continue;
    // Whole pixels, so that neighbouring bars a spacing wide tile without seams.
    const int x0 = static_cast<int>(std::lround(f.px(x[k]) - 0.5 * width));
    const int ya = static_cast<int>(std::lround(f.py(base))), yb = static_cast<int>(std::lround(f.py(y[k])));
    for (int py = std::min(ya, yb); py <= std::max(ya, yb); ++py)
      for (int px = x0; px < x0 + std::max(1, width); ++px) img.set(px, py, c);
  }
}

void draw_markers(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
                  std::array<std::uint8_t, 3> c, double radius) {
  for (std::size_t k = 0; k < x.size() && k < y.size(); ++k)
    if (std::isfinite(x[k]) && std::isfinite(y[k])) img.fill_circle(f.px(x[k]), f.py(y[k]), radius, c);
}

PlotPanel equal_scale_panel(double x0, double x1, double y0, double y1, int left, int top, int max_width,
                            int max_height) {
  const double wx = std::max(x1 - x0, 1e-12), wy = std::max(y1 - y0, 1e-12);
  // Pixels per data unit, one less than the box so that rounding the sides up stays inside it.
  const double scale = std::min(std::max(1, max_width - 1) / wx, std::max(1, max_height - 1) / wy);
  const int w = std::max(1, static_cast<int>(std::ceil(wx * scale - 1e-9)));
  const int h = std::max(1, static_cast<int>(std::ceil(wy * scale - 1e-9)));
  return {x0, x0 + w / scale, y0, y0 + h / scale, left, top, w, h};
}

void draw_discs(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
                const std::vector<std::array<std::uint8_t, 3>>& colours, double radius) {
  const double r = std::max(1.0, radius * f.width / (f.x1 - f.x0));
  for (std::size_t k = 0; k < x.size() && k < y.size() && k < colours.size(); ++k)
    if (std::isfinite(x[k]) && std::isfinite(y[k])) img.fill_circle(f.px(x[k]), f.py(y[k]), r, colours[k]);
}

void draw_picture(Image& img, const Image& picture, int x0, int y0) {
  for (int y = 0; y < picture.height; ++y)
    for (int x = 0; x < picture.width; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * picture.width + x) * 3;
      img.set(x0 + x, y0 + y, {picture.rgb[i], picture.rgb[i + 1], picture.rgb[i + 2]});
    }
}

namespace {

/// The top-left corner of each legend entry, from (0, 0), rows wrapped at max_width.
std::vector<std::array<int, 2>> legend_layout(const std::vector<LegendEntry>& entries, int max_width, int s) {
  const int th = 7 * s;
  std::vector<std::array<int, 2>> pos;
  int lx = 0, ly = 0;
  for (const auto& e : entries) {
    const int w = 14 * s + text_width(e.text, s);
    if (lx > 0 && lx + w > max_width) {
      lx = 0;
      ly += th + 8;
    }
    pos.push_back({lx, ly});
    lx += w + 20;
  }
  return pos;
}

}  // namespace

int legend_height(const std::vector<LegendEntry>& entries, int max_width, int s) {
  if (entries.empty()) return 0;
  return legend_layout(entries, max_width, s).back()[1] + 7 * s;
}

void draw_legend(Image& img, int x, int y, int max_width, const std::vector<LegendEntry>& entries, int s) {
  const int th = 7 * s;
  const auto pos = legend_layout(entries, max_width, s);
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const int ex = x + pos[k][0], ey = y + pos[k][1];
    for (int a = 0; a < th; ++a)
      for (int b = 0; b < th; ++b) img.set(ex + b, ey + a, entries[k].colour);
    draw_text(img, ex + th + 8, ey, entries[k].text, s);
  }
}

void write_plot_png(const std::filesystem::path& path, const Image& img, const std::vector<PlotPanel>& panels,
                    int scale) {
  std::ostringstream rec;
  rec << "scale=" << scale;
  for (const auto& f : panels) rec << ";panel=" << f.left << ',' << f.top << ',' << f.width << ',' << f.height;
  write_png(path, img, {{"geohaz_plot", rec.str()}});
}

namespace {

/// A dark pixel (antialiased text and lines: all channels below 128).
bool dark(const Image& img, int x, int y) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return false;
  const std::size_t i = (static_cast<std::size_t>(y) * img.width + x) * 3;
  return img.rgb[i] < 128 && img.rgb[i + 1] < 128 && img.rgb[i + 2] < 128;
}

/// The fraction of dark pixels on the straight row or column from (x0, y0) to (x1, y1).
double dark_fraction(const Image& img, int x0, int y0, int x1, int y1) {
  int n = 0, d = 0;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x, ++n) d += dark(img, x, y);
  return n ? static_cast<double>(d) / n : 0.0;
}

/// Groups of consecutive rows (along y) or columns (along x) of the box holding a dark pixel.
int dark_groups(const Image& img, int x0, int y0, int x1, int y1, bool along_y) {
  int groups = 0;
  bool in = false;
  for (int a = along_y ? y0 : x0; a <= (along_y ? y1 : x1); ++a) {
    bool any = false;
    for (int b = along_y ? x0 : y0; b <= (along_y ? x1 : y1) && !any; ++b)
      any = along_y ? dark(img, b, a) : dark(img, a, b);
    if (any && !in) ++groups;
    in = any;
  }
  return groups;
}

}  // namespace

std::vector<std::string> check_plot_png(const std::filesystem::path& path) {
  const std::string rec = read_png_text(path, "geohaz_plot");
  if (rec.empty()) return {"records no plot layout (not written by write_plot_png)"};
  int s = 2;
  std::vector<std::array<int, 4>> boxes;
  std::istringstream in(rec);
  std::string item;
  while (std::getline(in, item, ';')) {
    if (item.rfind("scale=", 0) == 0) s = std::atoi(item.c_str() + 6);
    if (item.rfind("panel=", 0) != 0) continue;
    std::array<int, 4> b{};
    std::istringstream nums(item.substr(6));
    std::string n;
    for (int k = 0; k < 4 && std::getline(nums, n, ','); ++k) b[k] = std::atoi(n.c_str());
    boxes.push_back(b);
  }
  if (boxes.empty()) return {"records no plot panel"};
  const Image img = read_image(path);
  std::vector<std::string> problems;
  for (std::size_t p = 0; p < boxes.size(); ++p) {
    const auto [l, t, w, h] = boxes[p];
    const std::string name = "panel " + std::to_string(p + 1) + ": ";
    const int th = 7 * s;
    // Frame: the left and bottom edges drawn along most of their length (curves and bars may
    // cross them).
    if (dark_fraction(img, l, t, l, t + h) < 0.8 || dark_fraction(img, l, t + h, l + w, t + h) < 0.8)
      problems.push_back(name + "no frame");
    if (dark_groups(img, std::max(0, l - 200), t - th / 2, l - 9, t + h + th / 2, true) < 2)
      problems.push_back(name + "fewer than two numbered ticks on the y axis");
    if (dark_groups(img, l - w / 20, t + h + 10, l + w + w / 20, t + h + 10 + th, false) < 2)
      problems.push_back(name + "fewer than two numbered ticks on the x axis");
    if (dark_groups(img, l, t + h + 20 + th, l + w, t + h + 20 + 2 * th, false) < 1)
      problems.push_back(name + "no x axis title");
    if (dark_groups(img, l, t - 12 - th, l + w, t - 12, false) < 1) problems.push_back(name + "no y axis title");
  }
  return problems;
}

}  // namespace geohaz
