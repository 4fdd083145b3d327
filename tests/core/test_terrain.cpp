// Unit tests for terrain.hpp: the one bilinear sampler (BilinearGrid), its edge and nodata rules,
// and core Terrain (raster.hpp) built on it.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/terrain.hpp"

namespace {

using namespace geohaz;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// 7 × 5 cells of 2 m × 3 m (non-square, so x and y cannot be swapped unnoticed), west edge
// x0 = 1000 m, north edge y0 = 2000 m.
GridGeometry small_grid() {
  return {7, 5, 1000.0, 2000.0, 2.0, 3.0};
}

template <class F>
std::vector<double> at_centres(const GridGeometry& g, F f) {
  std::vector<double> v(g.cells());
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) v[g.index(c, r)] = f(g.centre(c, r).x(), g.centre(c, r).y());
  return v;
}

// Points on the closed hull of the cell centres: random inside, along the four centre lines of the
// border cells, and the four corner centres.
std::vector<Vec2> hull_points(const GridGeometry& g, unsigned seed) {
  const Vec2 lo = g.centre(0, g.ny - 1), hi = g.centre(g.nx - 1, 0);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y());
  std::vector<Vec2> pts;
  for (int k = 0; k < 1000; ++k) pts.emplace_back(ux(gen), uy(gen));
  for (int k = 0; k < 50; ++k) {
    const double x = ux(gen), y = uy(gen);
    pts.emplace_back(x, lo.y());
    pts.emplace_back(x, hi.y());
    pts.emplace_back(lo.x(), y);
    pts.emplace_back(hi.x(), y);
  }
  for (const Vec2& c : {lo, hi, Vec2(lo.x(), hi.y()), Vec2(hi.x(), lo.y())}) pts.push_back(c);
  return pts;
}

TEST(BilinearGrid, ReproducesAPlaneAndABilinearFunctionWithTheirGradientsOnTheWholeCentreHull) {
  // Bilinear interpolation is exact for f = a + b x + c y + d x y (a plane when d = 0); so is its
  // gradient (b + d y, c + d x) inside every patch. Tolerances: f ≈ 250 carries rounding of a few
  // 1e-14, coordinates ≈ 2000 of about 2e-13 m; 1e-11 (value) and 1e-12 (gradient) leave a
  // margin of 10–100 and still catch a weight or a sign mixed up (errors of order 0.1–1).
  const GridGeometry g = small_grid();
  for (const double d : {0.0, 0.013}) {
    const auto f = [&](double x, double y) {
      const double u = x - 1000.0, v = y - 2000.0;
      return 250.0 + 0.37 * u - 0.81 * v + d * u * v;
    };
    const BilinearGrid grid(g, at_centres(g, f));
    for (const Vec2& p : hull_points(g, 42)) {
      TerrainSample s{};
      ASSERT_TRUE(grid.sample(p, s)) << p.transpose();
      const double u = p.x() - 1000.0, v = p.y() - 2000.0;
      EXPECT_NEAR(s.z, f(p.x(), p.y()), 1e-11) << p.transpose();
      EXPECT_NEAR(s.gradient.x(), 0.37 + d * v, 1e-12) << p.transpose();
      EXPECT_NEAR(s.gradient.y(), -0.81 + d * u, 1e-12) << p.transpose();
    }
  }
}

TEST(BilinearGrid, GoldenValuesInsideAndOnTheLastCentreLine) {
  // 3 × 3 cells of 10 m, x0 = 0, y0 = 30; values row by row from the north (worked by hand).
  const GridGeometry g{3, 3, 0.0, 30.0, 10.0, 10.0};
  const BilinearGrid grid(g, {1, 2, 4,  //
                              3, 5, 9,  //
                              7, 8, 6});
  TerrainSample s{};
  BilinearPatch patch{};
  // (u, v) = (0.25, 0.5): patch (0, 0) = {1, 2; 3, 5}: top 1.25, bottom 3.5, z = 2.375;
  // ∂z/∂x = (0.5·1 + 0.5·2)/10, ∂z/∂y = −(0.75·2 + 0.25·3)/10 (rows run south).
  ASSERT_TRUE(grid.sample(Vec2(7.5, 20.0), s, patch));
  EXPECT_EQ(s.z, 2.375);
  EXPECT_DOUBLE_EQ(s.gradient.x(), 0.15);
  EXPECT_DOUBLE_EQ(s.gradient.y(), -0.225);
  EXPECT_EQ(patch.index, 0u);
  EXPECT_EQ(patch.fx, 0.25);
  EXPECT_EQ(patch.fy, 0.5);
  // (u, v) = (2, 1.5), on the east centre line: the last patch (1, 1) = {5, 9; 8, 6} with fx = 1,
  // z halfway between 9 and 6, ∂z/∂y = +0.3 (falling southward), ∂z/∂x from the last patch.
  ASSERT_TRUE(grid.sample(Vec2(25.0, 10.0), s, patch));
  EXPECT_EQ(s.z, 7.5);
  EXPECT_DOUBLE_EQ(s.gradient.x(), 0.1);
  EXPECT_DOUBLE_EQ(s.gradient.y(), 0.3);
  EXPECT_EQ(patch.index, g.index(1, 1));
  EXPECT_EQ(patch.fx, 1.0);
  EXPECT_EQ(patch.fy, 0.5);
  // The south-east corner centre: the last patch with fractions 1, 1 gives its value.
  ASSERT_TRUE(grid.sample(g.centre(2, 2), s, patch));
  EXPECT_EQ(s.z, 6.0);
  EXPECT_EQ(patch.index, g.index(1, 1));
  EXPECT_EQ(patch.fx, 1.0);
  EXPECT_EQ(patch.fy, 1.0);
}

TEST(BilinearGrid, TheHalfCellEdgeBandAndTheOutsideAreNotDefined) {
  const GridGeometry g = small_grid();
  const BilinearGrid grid(g, at_centres(g, [](double x, double y) { return x + y; }));
  const double west = g.x0, east = g.x0 + g.nx * g.dx, north = g.y0, south = g.y0 - g.ny * g.dy;
  const double xc = g.centre(3, 0).x(), yc = g.centre(0, 2).y();  // a column and a row inside
  // The outermost centre lines are inside (closed hull) ...
  for (const Vec2& p : {Vec2(west + 0.5 * g.dx, yc), Vec2(east - 0.5 * g.dx, yc), Vec2(xc, north - 0.5 * g.dy),
                        Vec2(xc, south + 0.5 * g.dy)})
    EXPECT_TRUE(grid.valid(p)) << p.transpose();
  // ... the band between them and the raster edge is not (only two of a patch's centres exist),
  // nor is anything beyond the edge, nor NaN or infinite coordinates.
  const double eps = 1e-9;
  const double inf = std::numeric_limits<double>::infinity();
  for (const Vec2& p :
       {Vec2(west + 0.5 * g.dx - eps, yc), Vec2(west + 0.25 * g.dx, yc), Vec2(west, yc), Vec2(west - 5.0, yc),
        Vec2(east - 0.5 * g.dx + eps, yc), Vec2(east - 0.25 * g.dx, yc), Vec2(east, yc), Vec2(east + 5.0, yc),
        Vec2(xc, north - 0.5 * g.dy + eps), Vec2(xc, north - 0.1 * g.dy), Vec2(xc, north + 5.0),
        Vec2(xc, south + 0.5 * g.dy - eps), Vec2(xc, south + 0.1 * g.dy), Vec2(xc, south - 5.0),
        Vec2(west + 0.2 * g.dx, north - 0.2 * g.dy), Vec2(kNaN, yc), Vec2(xc, kNaN), Vec2(inf, yc), Vec2(xc, -inf)}) {
    TerrainSample s{42.0, Vec2(1.0, 2.0)};
    BilinearPatch patch{7, 0.5, 0.5};
    EXPECT_FALSE(grid.sample(p, s, patch)) << p.transpose();
    EXPECT_EQ(s.z, 42.0);  // outputs untouched
    EXPECT_EQ(s.gradient, Vec2(1.0, 2.0));
    EXPECT_EQ(patch.index, 7u);
  }
  // An empty grid is nowhere defined.
  EXPECT_FALSE(BilinearGrid().valid(Vec2(0.5, -0.5)));
}

TEST(BilinearGrid, NodataRemovesTheFourPatchesAroundIt) {
  const GridGeometry g = small_grid();
  std::vector<double> v = at_centres(g, [](double x, double y) { return 0.5 * x - 0.25 * y; });
  const int cn = 3, rn = 2;  // the nodata centre
  v[g.index(cn, rn)] = kNaN;
  const BilinearGrid grid(g, v);
  const Vec2 c = g.centre(cn, rn);
  // Inside the four patches that have it as a corner (up to one cell around it): not defined.
  for (const double ox : {-0.99, -0.5, 0.0, 0.5, 0.99})
    for (const double oy : {-0.99, -0.5, 0.0, 0.5, 0.99})
      EXPECT_FALSE(grid.valid(c + Vec2(ox * g.dx, oy * g.dy))) << ox << " " << oy;
  // One cell further in every direction the patches are whole again.
  for (const Vec2& o : {Vec2(1.01, 0.0), Vec2(-1.01, 0.0), Vec2(0.0, 1.01), Vec2(0.0, -1.01), Vec2(1.5, 1.5)})
    EXPECT_TRUE(grid.valid(c + Vec2(o.x() * g.dx, o.y() * g.dy))) << o.transpose();
  // On an inner centre line a point belongs to the patch east (south) of it: the line one cell east
  // of the nodata centre is defined, the line one cell west is not (its patch reaches the nodata).
  EXPECT_TRUE(grid.valid(g.centre(cn + 1, rn)));
  EXPECT_FALSE(grid.valid(g.centre(cn - 1, rn)));
  EXPECT_TRUE(grid.valid(g.centre(cn, rn + 1)));
  EXPECT_FALSE(grid.valid(g.centre(cn, rn - 1)));
}

TEST(BilinearGrid, PatchWeightsInterpolateAnyFieldOnTheSameCentres) {
  // runout's GridSurface interpolates its curvature with the patch of the elevation: the weights
  // (1−fx)(1−fy), fx(1−fy), (1−fx)fy, fx·fy over index, +1, +nx, +nx+1 give back the elevation.
  const GridGeometry g = small_grid();
  const std::vector<double> v = at_centres(g, [](double x, double y) { return std::sin(0.3 * x) * std::cos(0.2 * y); });
  const BilinearGrid grid(g, v);
  for (const Vec2& p : hull_points(g, 3)) {
    TerrainSample s{};
    BilinearPatch q{};
    ASSERT_TRUE(grid.sample(p, s, q));
    ASSERT_GE(q.fx, 0.0);
    ASSERT_LE(q.fx, 1.0);
    ASSERT_GE(q.fy, 0.0);
    ASSERT_LE(q.fy, 1.0);
    const std::size_t k = q.index, n = static_cast<std::size_t>(g.nx);
    const double z = (1 - q.fx) * (1 - q.fy) * v[k] + q.fx * (1 - q.fy) * v[k + 1] + (1 - q.fx) * q.fy * v[k + n] +
                     q.fx * q.fy * v[k + n + 1];
    EXPECT_NEAR(z, s.z, 1e-14);  // |v| ≤ 1: a few rounding errors
  }
}

TEST(BilinearGrid, BadGridsAreInputErrors) {
  EXPECT_THROW(BilinearGrid({1, 5, 0.0, 0.0, 1.0, 1.0}, std::vector<double>(5, 0.0)), InputError);
  EXPECT_THROW(BilinearGrid({5, 1, 0.0, 0.0, 1.0, 1.0}, std::vector<double>(5, 0.0)), InputError);
  EXPECT_THROW(BilinearGrid({0, 0, 0.0, 0.0, 1.0, 1.0}, {}), InputError);
  EXPECT_THROW(BilinearGrid({3, 3, 0.0, 0.0, 1.0, 1.0}, std::vector<double>(8, 0.0)), InputError);
  EXPECT_THROW(BilinearGrid({3, 3, 0.0, 0.0, 0.0, 1.0}, std::vector<double>(9, 0.0)), InputError);
  EXPECT_THROW(BilinearGrid({3, 3, 0.0, 0.0, 1.0, -1.0}, std::vector<double>(9, 0.0)), InputError);
  EXPECT_THROW(BilinearGrid({3, 3, 0.0, 0.0, kNaN, 1.0}, std::vector<double>(9, 0.0)), InputError);
  EXPECT_NO_THROW(BilinearGrid({2, 2, 0.0, 0.0, 1.0, 1.0}, std::vector<double>(4, 0.0)));
}

TEST(Terrain, IsTheCoreSamplerBitForBitWithDeclaredNodataAsNaN) {
  // The same grid as a Raster (GDAL geotransform, dy < 0, nodata −9999) and as a BilinearGrid
  // (nodata NaN): Terrain must be the same surface, to the last bit, at every point, and NaN
  // exactly where the sampler says "not here".
  const GridGeometry g = small_grid();
  std::vector<double> v = at_centres(g, [](double x, double y) { return 100.0 + std::sin(0.3 * x) + 0.01 * y; });
  Raster r;
  r.nx = g.nx;
  r.ny = g.ny;
  r.geotransform = {g.x0, g.dx, 0.0, g.y0, 0.0, -g.dy};
  r.nodata = -9999.0;
  r.data = v;
  r.data[g.index(4, 1)] = -9999.0;
  v[g.index(4, 1)] = kNaN;
  const Terrain t(r);
  const BilinearGrid grid(g, v);
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> ux(g.x0 - 1.0, g.x0 + g.nx * g.dx + 1.0),
      uy(g.y0 - g.ny * g.dy - 1.0, g.y0 + 1.0);
  std::vector<Vec2> pts = hull_points(g, 5);
  for (int k = 0; k < 2000; ++k) pts.emplace_back(ux(gen), uy(gen));
  int defined = 0, undefined = 0;
  for (const Vec2& p : pts) {
    TerrainSample s{};
    const bool ok = grid.sample(p, s);
    ASSERT_EQ(t.valid(p.x(), p.y()), ok) << p.transpose();
    if (ok) {
      ++defined;
      EXPECT_EQ(t.elevation(p.x(), p.y()), s.z);
      EXPECT_EQ(t.gradient(p.x(), p.y()), s.gradient);
    } else {
      ++undefined;
      EXPECT_TRUE(std::isnan(t.elevation(p.x(), p.y())));
      EXPECT_TRUE(std::isnan(t.gradient(p.x(), p.y()).x()));
    }
  }
  EXPECT_GT(defined, 1000);  // the hull points away from the nodata cell, and part of the box
  EXPECT_GT(undefined, 500);
}

}  // namespace
