#pragma once
/// \file surface.hpp
/// The terrain a debris flow runs over, as seen by the solver: elevation z(x, y) and its gradient
/// at a map point, or "not here" (outside the raster or over nodata). Two implementations, chosen
/// at compile time (the solver is a template on the surface type):
///  - GridSurface: bilinear interpolation of a north-up elevation grid between cell centres (the
///    DSM; the same convention as geohaz::Raster / geohaz::Terrain, without GDAL).
///  - InclinedPlane: an analytical plane z = z0 + s·(x, y), unbounded or bounded in a box (tests).
/// GridGeometry is the north-up grid shared by the DSM, the release thickness and the hazard maps.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz::runout {

/// A north-up grid: column c, row r (row 0 north) covers [x0 + c·dx, x0 + (c+1)·dx] ×
/// [y0 − (r+1)·dy, y0 − r·dy]; x0 is the west edge, y0 the north edge, dx, dy > 0 (m).
struct GridGeometry {
  int nx = 0, ny = 0;
  double x0 = 0.0, y0 = 0.0, dx = 1.0, dy = 1.0;

  std::size_t cells() const noexcept { return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny); }
  std::size_t index(int col, int row) const noexcept {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(col);
  }
  Vec2 centre(int col, int row) const noexcept { return {x0 + (col + 0.5) * dx, y0 - (row + 0.5) * dy}; }
  /// Cell holding p; false when p is outside the grid.
  bool cell_of(const Vec2& p, int& col, int& row) const noexcept {
    const double fc = (p.x() - x0) / dx, fr = (y0 - p.y()) / dy;
    if (!(fc >= 0.0 && fr >= 0.0 && fc < nx && fr < ny)) return false;
    col = static_cast<int>(fc);
    row = static_cast<int>(fr);
    return true;
  }
  double cell_area() const noexcept { return dx * dy; }
};

/// Elevation and gradient at a point.
struct SurfaceSample {
  double z;
  Vec2 grad;  ///< (∂z/∂x, ∂z/∂y)
};

/// Bilinear surface over a north-up elevation grid (values at cell centres; NaN = nodata).
class GridSurface {
 public:
  GridSurface() = default;
  /// \param values nx·ny elevations (m), row-major, row 0 north; NaN marks nodata.
  GridSurface(GridGeometry g, std::vector<double> values) : g_(g), z_(std::move(values)) {}

  const GridGeometry& geometry() const noexcept { return g_; }
  const std::vector<double>& values() const noexcept { return z_; }

  /// Elevation and gradient at p; false outside the area where the four surrounding cell centres
  /// hold data (a particle there leaves the simulation).
  bool sample(const Vec2& p, SurfaceSample& s) const noexcept {
    const double px = (p.x() - g_.x0) / g_.dx - 0.5;
    const double py = (g_.y0 - p.y()) / g_.dy - 0.5;
    if (!(px >= 0.0 && py >= 0.0 && px < g_.nx - 1 && py < g_.ny - 1)) return false;
    const int i = static_cast<int>(px), j = static_cast<int>(py);
    const double fx = px - i, fy = py - j;
    const std::size_t k = g_.index(i, j);
    const double z00 = z_[k], z10 = z_[k + 1], z01 = z_[k + g_.nx], z11 = z_[k + g_.nx + 1];
    if (std::isnan(z00 + z10 + z01 + z11)) return false;
    const double top = z00 + fx * (z10 - z00), bottom = z01 + fx * (z11 - z01);
    s.z = top + fy * (bottom - top);
    const double dzdpx = (1.0 - fy) * (z10 - z00) + fy * (z11 - z01);
    const double dzdpy = (1.0 - fx) * (z01 - z00) + fx * (z11 - z10);
    s.grad = Vec2(dzdpx / g_.dx, -dzdpy / g_.dy);
    return true;
  }

  /// A grid filled from z(x, y) at the cell centres (synthetic terrain, tests).
  static GridSurface from_function(const GridGeometry& g, const std::function<double(double, double)>& z) {
    std::vector<double> v(g.cells());
    for (int r = 0; r < g.ny; ++r)
      for (int c = 0; c < g.nx; ++c) {
        const Vec2 p = g.centre(c, r);
        v[g.index(c, r)] = z(p.x(), p.y());
      }
    return GridSurface(g, std::move(v));
  }

 private:
  GridGeometry g_;
  std::vector<double> z_;
};

/// Analytical plane z = z0 + slope·p, valid inside [lo, hi] (unbounded by default). Tests and
/// periodic benchmark domains.
struct InclinedPlane {
  double z0 = 0.0;
  Vec2 slope = Vec2::Zero();  ///< (∂z/∂x, ∂z/∂y), e.g. (−tan θ, 0) for a plane falling towards +x
  Vec2 lo = Vec2::Constant(-std::numeric_limits<double>::infinity());
  Vec2 hi = Vec2::Constant(std::numeric_limits<double>::infinity());

  bool sample(const Vec2& p, SurfaceSample& s) const noexcept {
    if (!(p.x() >= lo.x() && p.y() >= lo.y() && p.x() <= hi.x() && p.y() <= hi.y())) return false;
    s.z = z0 + slope.dot(p);
    s.grad = slope;
    return true;
  }
};

/// Two planes joined along x = x_break: slope `slope_upper` (∂z/∂x) for x < x_break, then
/// `slope_lower` (flat run-out: 0). Continuous elevation, z(x_break) = 0.
struct SlopeToRunout {
  double x_break = 0.0;
  double slope_upper = -0.5;
  double slope_lower = 0.0;
  bool sample(const Vec2& p, SurfaceSample& s) const noexcept {
    const double a = p.x() < x_break ? slope_upper : slope_lower;
    s.z = a * (p.x() - x_break);
    s.grad = Vec2(a, 0.0);
    return std::isfinite(p.x()) && std::isfinite(p.y());
  }
};

}  // namespace geohaz::runout
