#pragma once
/// \file surface.hpp
/// The terrain a debris flow runs over, as seen by the solver: elevation z(x, y), its gradient and
/// its curvature (Hessian) at a map point, or "not here" (outside the raster or over nodata).
/// Implementations are chosen at compile time (the solver is a template on the surface type):
///  - GridSurface: the core bilinear sampler (geohaz::BilinearGrid, core/terrain.hpp: the same
///    surface, edge rule and nodata rule as geohaz::Terrain, without GDAL) over the DSM, plus the
///    Hessian from second differences of the grid over a stencil of the particle scale (below);
///  - InclinedPlane, SlopeToRunout, CylindricalTrough: analytical surfaces for tests.
/// GridGeometry (core/terrain.hpp) is the north-up grid shared by the DSM, the release thickness
/// and the hazard maps.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "geohaz/core/parallel.hpp"
#include "geohaz/core/terrain.hpp"
#include "geohaz/core/vec.hpp"

namespace geohaz::runout {

/// The north-up grid of the DSM, release and hazard maps (moved to the core with the sampler).
using geohaz::GridGeometry;

/// Elevation, gradient and curvature at a point.
struct SurfaceSample {
  double z;
  Vec2 grad;  ///< (∂z/∂x, ∂z/∂y) (1)
  Vec3 hess;  ///< (∂²z/∂x², ∂²z/∂x∂y, ∂²z/∂y²) (1/m)
};

/// Bilinear surface over a north-up elevation grid (values at cell centres; NaN = nodata): elevation
/// and gradient from the core sampler geohaz::BilinearGrid (where it is defined: the closed hull of
/// the cell centres, away from nodata; see core/terrain.hpp), curvature added here.
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
  /// InputError when the grid is smaller than 2 × 2 or the values do not match it (BilinearGrid).
  GridSurface(const GridGeometry& g, std::vector<double> values, double curvature_scale = 0.0)
      : grid_(g, std::move(values)) {
    compute_curvature(curvature_scale);
  }

  const GridGeometry& geometry() const noexcept { return grid_.geometry(); }
  const std::vector<double>& values() const noexcept { return grid_.values(); }
  /// The elevation sampler without the curvature (the same surface as geohaz::Terrain).
  const BilinearGrid& grid() const noexcept { return grid_; }
  /// Stencil half-width of the Hessian (cells).
  int curvature_cells() const noexcept { return k_; }
  /// The stencil half-width for a curvature scale L (m) on this grid: max(1, round(L/Δ)).
  int curvature_cells_for(double scale) const noexcept {
    const double cell = std::min(grid_.geometry().dx, grid_.geometry().dy);
    return scale > cell ? std::max(1, static_cast<int>(std::lround(scale / cell))) : 1;
  }
  /// A copy whose Hessian is taken over the scale L (m).
  GridSurface with_curvature_scale(double scale) const {
    GridSurface s;
    s.grid_ = grid_;
    s.compute_curvature(scale);
    return s;
  }

  /// Elevation, gradient and Hessian at p; false where the bilinear surface is not defined
  /// (outside the closed hull of the cell centres or next to nodata: a particle there leaves the
  /// simulation). The Hessian is interpolated with the weights of the elevation's patch.
  bool sample(const Vec2& p, SurfaceSample& s) const noexcept {
    TerrainSample t;
    BilinearPatch patch;
    if (!grid_.sample(p, t, patch)) return false;
    s.z = t.z;
    s.grad = t.gradient;
    const double fx = patch.fx, fy = patch.fy;
    const double w00 = (1.0 - fx) * (1.0 - fy), w10 = fx * (1.0 - fy), w01 = (1.0 - fx) * fy, w11 = fx * fy;
    const float* h00 = &hess_[3 * patch.index];
    const float* h10 = h00 + 3;
    const float* h01 = h00 + 3 * static_cast<std::size_t>(grid_.geometry().nx);
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
    const GridGeometry& g = grid_.geometry();
    const std::vector<double>& values = grid_.values();
    k_ = curvature_cells_for(scale);
    hess_.assign(3 * g.cells(), 0.0f);
    const auto z = [&](int c, int r) { return values[g.index(c, r)]; };
#pragma omp parallel for schedule(static) if (parallel_worth(g.cells()))
    for (int r = 0; r < g.ny; ++r)
      for (int c = 0; c < g.nx; ++c) {
        const int k = std::min({k_, c, g.nx - 1 - c, r, g.ny - 1 - r});
        if (k < 1) continue;
        const double hx = k * g.dx, hy = k * g.dy;
        // Map y points north while rows run south: r − k is north (+y).
        const double xx = (z(c + k, r) - 2.0 * z(c, r) + z(c - k, r)) / (hx * hx);
        const double yy = (z(c, r - k) - 2.0 * z(c, r) + z(c, r + k)) / (hy * hy);
        const double xy = (z(c + k, r - k) - z(c + k, r + k) - z(c - k, r - k) + z(c - k, r + k)) / (4.0 * hx * hy);
        if (!std::isfinite(xx + yy + xy)) continue;  // the stencil reaches nodata
        float* h = &hess_[3 * g.index(c, r)];
        h[0] = static_cast<float>(xx);
        h[1] = static_cast<float>(xy);
        h[2] = static_cast<float>(yy);
      }
  }

  BilinearGrid grid_;
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
