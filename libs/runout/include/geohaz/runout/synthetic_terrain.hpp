#pragma once
/// \file synthetic_terrain.hpp
/// A synthetic mountain valley DSM for examples, regression tests and the lecture-scale validation
/// (SWJTU lecture 2010, §3: a debris flow travelling 4.8 km in 10 min over a 2.5 m DSM).
///
/// The valley runs west → east. Its thalweg falls with a longitudinal gradient S(s) that is steep
/// at the head (S_head over the first `head_length`), eases linearly to S_channel by
/// `channel_start`, stays there to `fan_start`, then eases to S_fan (< i_cr, a flat fan where the
/// flow deposits) by `fan_end`. The thalweg meanders: y_c(x) = y_mid + A sin(2πx/λ). Across it the
/// valley is parabolic: z += side_height·((y − y_c)/half_width)². Elevations in metres.

#include <string>

#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {

struct SyntheticValley {
  int nx = 2000, ny = 1000;                              ///< cells
  double cell = 2.5;                                     ///< cell size (m)
  double x0 = 480000.0;                                  ///< west edge (m, UTM 54N)
  double y0 = 4310000.0;                                 ///< north edge (m)
  double top = 1500.0;                                   ///< thalweg elevation at the west edge (m)
  double s_head = 0.45, s_channel = 0.24, s_fan = 0.04;  ///< longitudinal gradients (1)
  double head_length = 600.0, channel_start = 1500.0, fan_start = 0.78,
         fan_end = 0.88;                                          ///< m; fan as fraction of length
  double meander_amplitude = 120.0, meander_wavelength = 2500.0;  ///< m
  double side_height = 60.0, half_width = 400.0;                  ///< m

  double length() const noexcept { return nx * cell; }
  GridGeometry geometry() const noexcept { return {nx, ny, x0, y0, cell, cell}; }
  /// Thalweg position y_c at map x (m).
  double thalweg_y(double x) const noexcept;
  /// Elevation at (x, y) (m).
  double elevation(double x, double y) const noexcept;
  /// The DSM on its grid.
  GridSurface surface() const {
    return GridSurface::from_function(geometry(), [this](double x, double y) { return elevation(x, y); });
  }
  /// A scaled-down copy (fewer, same-size-in-metres-per-cell… cells) for fast tests: `factor` < 1
  /// shrinks the extent and every length scale.
  SyntheticValley scaled(double factor) const;
};

/// WKT of WGS 84 / UTM zone 54N (EPSG:32654), the CRS of the synthetic DSM (the lecture's case is in
/// northern Japan).
extern const char* const kSyntheticValleyCrsWkt;

}  // namespace geohaz::runout
