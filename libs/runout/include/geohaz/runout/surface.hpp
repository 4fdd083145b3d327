#pragma once
/// \file surface.hpp
/// The terrain a debris flow runs over, as seen by the solver: elevation z(x, y), its gradient and
/// its curvature (Hessian) at a map point, or "not here" (outside the raster or over nodata).
/// Implementations are chosen at compile time (the solver is a template on the surface type):
///  - GridSurface: bilinear interpolation of a north-up elevation grid between cell centres (the
///    DSM; the same convention as geohaz::Raster / geohaz::Terrain, without GDAL), with the
///    Hessian from second differences of the grid over a stencil of the particle scale (below);
///  - InclinedPlane, SlopeToRunout, CylindricalTrough: analytical surfaces for tests.
/// GridGeometry is the north-up grid shared by the DSM, the release thickness and the hazard maps.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
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

/// Elevation, gradient and curvature at a point.
struct SurfaceSample {
  double z;
  Vec2 grad;  ///< (∂z/∂x, ∂z/∂y) (1)
  Vec3 hess;  ///< (∂²z/∂x², ∂²z/∂x∂y, ∂²z/∂y²) (1/m)
};

/// Bilinear surface over a north-up elevation grid (values at cell centres; NaN = nodata).
///
/// Curvature. The bilinear surface is flat inside a cell and kinks at cell edges, so its own second
/// derivatives are useless to a particle (zero, or Dirac). The Hessian is instead taken from
/// second differences of the grid over a stencil of k = max(1, round(L/Δ)) cells, L the curvature
/// scale (the solver uses the particle spacing d0), at every cell centre:
///     z_xx = (z[c+k] − 2 z[c] + z[c−k]) / (kΔx)²,   z_yy likewise,
///     z_xy = (z[c+k, r+k] − z[c+k, r−k] − z[c−k, r+k] + z[c−k, r−k]) / (4 kΔx kΔy)
/// (exact for a quadratic surface; smoothed over 2kΔ for anything else), the stencil shrunk near
/// the edges and zero where it would reach nodata; between centres it is interpolated bilinearly
/// like the elevation. Stored as float: the curvature needs no more than 7 digits.
class GridSurface {
 public:
  GridSurface() = default;
  /// \param values nx·ny elevations (m), row-major, row 0 north; NaN marks nodata.
  /// \param curvature_scale L (m) of the Hessian stencil; ≤ 0: one cell.
  GridSurface(GridGeometry g, std::vector<double> values, double curvature_scale = 0.0) : g_(g), z_(std::move(values)) {
    compute_curvature(curvature_scale);
  }

  const GridGeometry& geometry() const noexcept { return g_; }
  const std::vector<double>& values() const noexcept { return z_; }
  /// Stencil half-width of the Hessian (cells).
  int curvature_cells() const noexcept { return k_; }
  /// The stencil half-width for a curvature scale L (m) on this grid: max(1, round(L/Δ)).
  int curvature_cells_for(double scale) const noexcept {
    const double cell = std::min(g_.dx, g_.dy);
    return scale > cell ? std::max(1, static_cast<int>(std::lround(scale / cell))) : 1;
  }
  /// A copy whose Hessian is taken over the scale L (m).
  GridSurface with_curvature_scale(double scale) const {
    GridSurface s;
    s.g_ = g_;
    s.z_ = z_;
    s.compute_curvature(scale);
    return s;
  }

  /// Elevation, gradient and Hessian at p; false outside the area where the four surrounding cell
  /// centres hold data (a particle there leaves the simulation).
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
    const double w00 = (1.0 - fx) * (1.0 - fy), w10 = fx * (1.0 - fy), w01 = (1.0 - fx) * fy, w11 = fx * fy;
    const float* h00 = &hess_[3 * k];
    const float* h10 = h00 + 3;
    const float* h01 = h00 + 3 * static_cast<std::size_t>(g_.nx);
    const float* h11 = h01 + 3;
    for (int c = 0; c < 3; ++c) s.hess[c] = w00 * h00[c] + w10 * h10[c] + w01 * h01[c] + w11 * h11[c];
    return true;
  }

  /// A grid filled from z(x, y) at the cell centres (synthetic terrain, tests).
  static GridSurface from_function(const GridGeometry& g, const std::function<double(double, double)>& z,
                                   double curvature_scale = 0.0) {
    std::vector<double> v(g.cells());
    for (int r = 0; r < g.ny; ++r)
      for (int c = 0; c < g.nx; ++c) {
        const Vec2 p = g.centre(c, r);
        v[g.index(c, r)] = z(p.x(), p.y());
      }
    return GridSurface(g, std::move(v), curvature_scale);
  }

 private:
  void compute_curvature(double scale) {
    k_ = curvature_cells_for(scale);
    hess_.assign(3 * g_.cells(), 0.0f);
    const auto z = [&](int c, int r) { return z_[g_.index(c, r)]; };
#pragma omp parallel for schedule(static)
    for (int r = 0; r < g_.ny; ++r)
      for (int c = 0; c < g_.nx; ++c) {
        const int k = std::min({k_, c, g_.nx - 1 - c, r, g_.ny - 1 - r});
        if (k < 1) continue;
        const double hx = k * g_.dx, hy = k * g_.dy;
        // Map y points north while rows run south: r − k is north (+y).
        const double xx = (z(c + k, r) - 2.0 * z(c, r) + z(c - k, r)) / (hx * hx);
        const double yy = (z(c, r - k) - 2.0 * z(c, r) + z(c, r + k)) / (hy * hy);
        const double xy = (z(c + k, r - k) - z(c + k, r + k) - z(c - k, r - k) + z(c - k, r + k)) / (4.0 * hx * hy);
        if (!std::isfinite(xx + yy + xy)) continue;  // the stencil reaches nodata
        float* h = &hess_[3 * g_.index(c, r)];
        h[0] = static_cast<float>(xx);
        h[1] = static_cast<float>(xy);
        h[2] = static_cast<float>(yy);
      }
  }

  GridGeometry g_;
  std::vector<double> z_;
  std::vector<float> hess_;  // (z_xx, z_xy, z_yy) per cell centre
  int k_ = 1;
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
    s.hess = Vec3::Zero();
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
    s.hess = Vec3::Zero();  // the kink at x_break is not resolved (a Dirac)
    return std::isfinite(p.x()) && std::isfinite(p.y());
  }
};

/// A trough whose cross-section (in x) is a circle of radius R centred R above the axis x = xc:
/// z = R − √(R² − (x − xc)²) for |x − xc| < R (tests of the bed-curvature terms: a particle in it
/// moves on a vertical circle).
struct CylindricalTrough {
  double radius = 100.0;
  double xc = 0.0;
  bool sample(const Vec2& p, SurfaceSample& s) const noexcept {
    const double u = p.x() - xc, w2 = radius * radius - u * u;
    if (!(w2 > 0.0) || !std::isfinite(p.y())) return false;
    const double w = std::sqrt(w2);
    s.z = radius - w;
    s.grad = Vec2(u / w, 0.0);
    s.hess = Vec3(radius * radius / (w2 * w), 0.0, 0.0);
    return true;
  }
};

}  // namespace geohaz::runout
