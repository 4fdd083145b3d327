#include "geohaz/runout/release.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace geohaz::runout {

SeedReport seed_release(const GridGeometry& grid, const std::vector<double>& thickness, double d0, double h0,
                        RunoutStore& store) {
  SeedReport rep;
  const double v0 = h0 * d0 * d0;
  const int kx = std::max(1, static_cast<int>(std::lround(d0 / grid.dx)));
  const int ky = std::max(1, static_cast<int>(std::lround(d0 / grid.dy)));
  const double area = grid.cell_area();
  for (int br = 0; br < grid.ny; br += ky) {
    for (int bc = 0; bc < grid.nx; bc += kx) {
      double vb = 0.0;
      int cmin = grid.nx, cmax = -1, rmin = grid.ny, rmax = -1;
      for (int r = br; r < std::min(br + ky, grid.ny); ++r)
        for (int c = bc; c < std::min(bc + kx, grid.nx); ++c) {
          const double t = thickness[grid.index(c, r)];
          if (!(t > 0.0)) continue;
          vb += t * area;
          cmin = std::min(cmin, c);
          cmax = std::max(cmax, c);
          rmin = std::min(rmin, r);
          rmax = std::max(rmax, r);
        }
      if (cmax < 0) continue;
      rep.volume_given += vb;
      const long nb = std::max(1L, std::lround(vb / v0));
      // Sub-lattice a × b over the bounding box of the release cells, aspect-matched.
      const double w = (cmax - cmin + 1) * grid.dx, hgt = (rmax - rmin + 1) * grid.dy;
      const long a = std::clamp(std::lround(std::sqrt(static_cast<double>(nb) * w / hgt)), 1L, nb);
      const long b = (nb + a - 1) / a;
      const double x_left = grid.x0 + cmin * grid.dx, y_top = grid.y0 - rmin * grid.dy;
      const double vp = vb / static_cast<double>(nb);
      const std::size_t first = store.append(static_cast<std::size_t>(nb));
      for (long k = 0; k < nb; ++k) {
        const long row = k / a, col = k % a;
        // The last, partly filled row is centred.
        const long in_row = std::min(a, nb - row * a);
        const double offset = 0.5 * static_cast<double>(a - in_row);
        const std::size_t i = first + static_cast<std::size_t>(k);
        store.get<Position<2>>()[i] =
            Vec2(x_left + (col + offset + 0.5) * w / a, y_top - (row + 0.5) * hgt / static_cast<double>(b));
        store.get<Volume>()[i] = vp;
        store.get<ParticleId>()[i] = static_cast<std::int64_t>(i);
        rep.volume_seeded += vp;
      }
      rep.particles += static_cast<std::size_t>(nb);
    }
  }
  return rep;
}

std::vector<double> bin_point_volumes(const GridGeometry& grid, const std::vector<Vec2>& points,
                                      const std::vector<double>& volumes, std::size_t& outside) {
  std::vector<double> t(grid.cells(), 0.0);
  outside = std::numeric_limits<std::size_t>::max();
  const double inv_area = 1.0 / grid.cell_area();
  for (std::size_t i = 0; i < points.size(); ++i) {
    int c, r;
    if (!grid.cell_of(points[i], c, r)) {
      outside = i;
      return {};
    }
    t[grid.index(c, r)] += volumes[i] * inv_area;
  }
  return t;
}

}  // namespace geohaz::runout
