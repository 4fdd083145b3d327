#pragma once
// A bare line plot for the validation pages (no text: the axes ranges and ticks are given in the
// docs that show the picture): frame, grid lines at every tick, curves as lines, measurements as
// dots. Shared by the validation tests of the models.
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "geohaz/core/raster.hpp"

namespace geohaz::testing {

struct Curve {
  std::vector<double> x, y;
  std::array<std::uint8_t, 3> colour;
  bool dots = false;
};

inline void plot(const std::filesystem::path& path, const std::vector<Curve>& curves, double x0, double x1, double y0,
                 double y1, double xtick, double ytick) {
  const int W = 640, H = 420, m = 40;
  geohaz::Image img(W, H);
  auto px = [&](double x) { return m + (x - x0) / (x1 - x0) * (W - 2 * m); };
  auto py = [&](double y) { return H - m - (y - y0) / (y1 - y0) * (H - 2 * m); };
  const std::array<std::uint8_t, 3> grid{220, 220, 220}, black{0, 0, 0};
  for (double x = x0; x <= x1 + 1e-9; x += xtick) img.line(px(x), py(y0), px(x), py(y1), grid);
  for (double y = y0; y <= y1 + 1e-9; y += ytick) img.line(px(x0), py(y), px(x1), py(y), grid);
  img.line(px(x0), py(y0), px(x1), py(y0), black);
  img.line(px(x0), py(y0), px(x0), py(y1), black);
  img.line(px(x1), py(y0), px(x1), py(y1), black);
  img.line(px(x0), py(y1), px(x1), py(y1), black);
  for (const auto& c : curves)
    for (std::size_t i = 0; i < c.x.size(); ++i) {
      if (c.dots)
        img.fill_circle(px(c.x[i]), py(c.y[i]), 5, c.colour);
      else if (i)
        img.line(px(c.x[i - 1]), py(c.y[i - 1]), px(c.x[i]), py(c.y[i]), c.colour);
    }
  std::filesystem::create_directories(path.parent_path());
  geohaz::write_png(path, img);
}

/// The quasi-2D column-collapse run-out laws of Lube et al. (2005) as plot curves
/// (docs/validation/column_collapse.md): 1.2a up to a = 2.8 (black) and 1.9a^{2/3} from a = 1.8
/// (grey); between 1.8 and 2.8 the data lie between the two branches.
inline std::array<Curve, 2> lube_runout_curves() {
  Curve law{{}, {}, {0, 0, 0}, false}, law2{{}, {}, {130, 130, 130}, false};
  for (double a = 0.0; a <= 2.8 + 1e-9; a += 0.05) {
    law.x.push_back(a);
    law.y.push_back(1.2 * a);
  }
  for (double a = 1.8; a <= 3.5 + 1e-9; a += 0.05) {
    law2.x.push_back(a);
    law2.y.push_back(1.9 * std::pow(a, 2.0 / 3.0));
  }
  return {law, law2};
}

}  // namespace geohaz::testing
