#pragma once
// A bare line plot for the validation pages (no text: the axes ranges and ticks are given in the
// docs that show the picture): frame, grid lines at every tick, curves as lines, measurements as
// dots, on core's plotter (geohaz/core/plot.hpp). Shared by the validation tests of the models.
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "geohaz/core/plot.hpp"
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
  const geohaz::PlotPanel f{x0, x1, y0, y1, m, m, W - 2 * m, H - 2 * m};  // core's plotter (plot.hpp)
  const std::array<std::uint8_t, 3> grid{220, 220, 220}, black{0, 0, 0};
  for (double x = x0; x <= x1 + 1e-9; x += xtick) img.line(f.px(x), f.py(y0), f.px(x), f.py(y1), grid);
  for (double y = y0; y <= y1 + 1e-9; y += ytick) img.line(f.px(x0), f.py(y), f.px(x1), f.py(y), grid);
  geohaz::draw_frame(img, f, black);
  for (const auto& c : curves) {
    if (c.dots)
      geohaz::draw_markers(img, f, c.x, c.y, c.colour, 5);
    else
      geohaz::draw_polyline(img, f, c.x, c.y, c.colour);
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
