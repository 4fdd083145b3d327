#pragma once
/// \file terrain.hpp
/// The one bilinear terrain sampler of geohaz (issue #11 item 5): a north-up grid of values at
/// cell centres, interpolated bilinearly between them. Core `Terrain` (raster.hpp: SPH sections,
/// DEM terrain profiles) and runout `GridSurface` (runout/surface.hpp: the per-particle look-up,
/// which adds its curvature on top) are both built on BilinearGrid, so they give the same
/// elevation and gradient at every point, bit for bit. No GDAL here.
///
/// The surface. With fractional centre-based pixel coordinates
///     u = (x − x0)/Δx − ½,   v = (y0 − y)/Δy − ½          (centre of cell (c, r) at (u, v) = (c, r)),
/// the patch (i, j) = (⌊u⌋, ⌊v⌋) and fractions fx = u − i, fy = v − j,
///     z = (1−fy)[(1−fx) z00 + fx z10] + fy[(1−fx) z01 + fx z11]      (z00 = z[i, j], z10 = z[i+1, j], ...),
///     ∂z/∂x = [(1−fy)(z10 − z00) + fy(z11 − z01)] / Δx,
///     ∂z/∂y = −[(1−fx)(z01 − z00) + fx(z11 − z10)] / Δy                (rows run south, y north),
/// i.e. the exact derivative of the interpolated surface inside a patch. A plane is reproduced
/// exactly (to rounding), value and gradient.
///
/// Where it is defined (the one edge rule): on the closed hull of the cell centres,
/// 0 ≤ u ≤ nx − 1 and 0 ≤ v ≤ ny − 1, wherever the four centres of the patch hold data. On the last
/// centre line (u = nx − 1 or v = ny − 1) the last patch is used with fraction 1, so the east and
/// south edges behave like the west and north ones. Everywhere else the surface is "not here"
/// (sample() returns false; Terrain gives NaN):
///  - the band within half a cell of the raster's outer edge, beyond the outermost centres: there
///    only one or two of the four centres exist, and any value would be an extrapolation the data
///    do not support (a flow or a section drawn there has no terrain under it);
///  - every patch with a nodata (NaN) centre, i.e. up to one cell around a nodata cell: the raster's
///    outside is treated exactly like nodata;
///  - points outside the raster, and NaN coordinates.
/// Consumers that need the half-cell band keep their input inside the centre hull (extract_profile
/// reports the point that leaves it).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz {

/// A north-up grid: column c, row r (row 0 north) covers [x0 + c·dx, x0 + (c+1)·dx] ×
/// [y0 − (r+1)·dy, y0 − r·dy]; x0 is the west edge, y0 the north edge, dx, dy > 0 (m). The grid of
/// a DSM, of a release-thickness raster and of the hazard maps.
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

/// Elevation and gradient of the bilinear surface at one point.
struct TerrainSample {
  double z;       ///< elevation, m
  Vec2 gradient;  ///< (∂z/∂x, ∂z/∂y), dimensionless
};

/// The patch a sample was taken in, for interpolating other per-centre quantities with the same
/// weights (runout's curvature): w00 = (1−fx)(1−fy), w10 = fx(1−fy), w01 = (1−fx)fy, w11 = fx·fy.
struct BilinearPatch {
  std::size_t index;  ///< grid index of the patch's north-west centre (i, j); east is +1, south +nx
  double fx, fy;      ///< fractions east and south within the patch, in [0, 1]
};

/// Values at the cell centres of a north-up grid and the bilinear surface through them (see the
/// file comment for the formulas and the edge rule). NaN marks nodata.
class BilinearGrid {
 public:
  /// An empty grid: every point is outside.
  BilinearGrid() = default;
  /// \param g      the grid (at least 2 × 2 cells, dx, dy > 0 m);
  /// \param values g.cells() values, row-major, row 0 north; NaN = nodata.
  /// InputError when the grid is smaller than 2 × 2, its cells are not positive, or the number of
  /// values does not match.
  BilinearGrid(const GridGeometry& g, std::vector<double> values);

  const GridGeometry& geometry() const noexcept { return g_; }
  const std::vector<double>& values() const noexcept { return z_; }

  /// Elevation and gradient at p, and the patch they came from; false (outputs untouched) where
  /// the surface is not defined (outside the closed centre hull or next to nodata). Inline: this
  /// is the per-particle look-up of the runout solver.
  bool sample(const Vec2& p, TerrainSample& s, BilinearPatch& patch) const noexcept {
    const double px = (p.x() - g_.x0) / g_.dx - 0.5;
    const double py = (g_.y0 - p.y()) / g_.dy - 0.5;
    int i, j;
    if (px >= 0.0 && py >= 0.0 && px < g_.nx - 1 && py < g_.ny - 1) [[likely]] {
      i = static_cast<int>(px);
      j = static_cast<int>(py);
    } else {
      // Off the half-open patches: only the east and south lines of centres are still on the
      // surface (the last patch, fraction 1). Negated test so that NaN coordinates are rejected.
      // Kept out of the common path, which then costs what the half-open test alone did.
      if (!(px >= 0.0 && py >= 0.0 && px <= g_.nx - 1 && py <= g_.ny - 1)) return false;
      i = std::min(static_cast<int>(px), g_.nx - 2);
      j = std::min(static_cast<int>(py), g_.ny - 2);
    }
    const double fx = px - i, fy = py - j;
    const std::size_t k = g_.index(i, j);
    const double z00 = z_[k], z10 = z_[k + 1], z01 = z_[k + g_.nx], z11 = z_[k + g_.nx + 1];
    if (std::isnan(z00 + z10 + z01 + z11)) return false;
    const double top = z00 + fx * (z10 - z00), bottom = z01 + fx * (z11 - z01);
    s.z = top + fy * (bottom - top);
    const double dzdpx = (1.0 - fy) * (z10 - z00) + fy * (z11 - z01);
    const double dzdpy = (1.0 - fx) * (z01 - z00) + fx * (z11 - z10);
    s.gradient = Vec2(dzdpx / g_.dx, -dzdpy / g_.dy);
    patch = {k, fx, fy};
    return true;
  }
  /// Elevation and gradient at p (see above).
  bool sample(const Vec2& p, TerrainSample& s) const noexcept {
    BilinearPatch patch;
    return sample(p, s, patch);
  }
  /// Whether the surface is defined at p.
  bool valid(const Vec2& p) const noexcept {
    TerrainSample s;
    return sample(p, s);
  }

 private:
  GridGeometry g_;
  std::vector<double> z_;
};

}  // namespace geohaz
