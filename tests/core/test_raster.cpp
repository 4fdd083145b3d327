// Unit tests for raster.hpp / raster_extra.hpp: GDAL raster I/O, CRS checks, the bilinear Terrain,
// profiles, OGR polygons and the quick-look PNG.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "child_process.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"
#include "tiff_header.hpp"

namespace fs = std::filesystem;
using namespace geohaz;

namespace {

/// A unique temporary directory per test, removed afterwards.
class RasterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("geohaz_raster_" + std::string(info->name()) + "_" + std::to_string(rd()) + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
}

/// A raster on a UTM 32N grid: x0 = 500000, y0 = 5200000, cells dx × dy.
Raster make_grid(int nx, int ny, double dx, double dy) {
  Raster r;
  r.nx = nx;
  r.ny = ny;
  r.geotransform = {500000.0, dx, 0.0, 5200000.0, 0.0, -dy};
  r.crs_wkt = crs_to_wkt("EPSG:32632");
  r.data.assign(static_cast<std::size_t>(nx) * ny, 0.0);
  return r;
}

template <class F>
void fill(Raster& r, F f) {
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) {
      const Vec2 c = r.cell_centre(col, row);
      r.at(col, row) = f(c.x(), c.y());
    }
}

bool contains_text(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Reading and writing

TEST_F(RasterTest, GeoTiffRoundTripKeepsGridCrsNodataAndValues) {
  Raster r = make_grid(7, 5, 10.0, 12.5);
  r.nodata = -9999.0;
  // Values exactly representable in Float32, so the round trip is exact.
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) r.at(col, row) = 1000.0 + col + 0.25 * row;
  r.at(3, 2) = -9999.0;
  const fs::path out = dir_ / "dem.tif";
  write_geotiff(out, r);
  // Only the final file: no "*.partial" left behind.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir_)) {
    ++files;
    EXPECT_EQ(e.path().filename(), "dem.tif");
  }
  EXPECT_EQ(files, 1);

  const Raster back = read_raster(out);
  ASSERT_EQ(back.nx, 7);
  ASSERT_EQ(back.ny, 5);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(back.geotransform[k], r.geotransform[k]) << "term " << k;
  EXPECT_TRUE(crs_equal(back.crs_wkt, r.crs_wkt));
  EXPECT_FALSE(crs_equal(back.crs_wkt, crs_to_wkt("EPSG:32633")));
  ASSERT_TRUE(back.nodata.has_value());
  EXPECT_EQ(*back.nodata, -9999.0);
  EXPECT_TRUE(back.is_nodata(back.at(3, 2)));
  for (std::size_t i = 0; i < r.data.size(); ++i) EXPECT_EQ(back.data[i], r.data[i]) << "value " << i;
}

TEST_F(RasterTest, GeoTiffFloat64KeepsDoublesExactly) {
  Raster r = make_grid(3, 4, 2.0, 2.0);
  for (std::size_t i = 0; i < r.data.size(); ++i) r.data[i] = 0.1 * static_cast<double>(i) + 1e-12;
  write_geotiff(dir_ / "f64.tif", r, true);
  const Raster back = read_raster(dir_ / "f64.tif");
  EXPECT_FALSE(back.nodata.has_value());
  for (std::size_t i = 0; i < r.data.size(); ++i) EXPECT_EQ(back.data[i], r.data[i]);
}

TEST_F(RasterTest, WriteToMissingDirectoryThrowsAndLeavesNothing) {
  const Raster r = make_grid(2, 2, 1.0, 1.0);
  // An output that cannot be created is an I/O failure (exit code 3), not bad input.
  EXPECT_THROW(write_geotiff(dir_ / "no" / "such" / "dir.tif", r), IoError);
  EXPECT_FALSE(fs::exists(dir_ / "no"));
}

TEST_F(RasterTest, ReadsEsriAsciiGrid) {
  const fs::path asc = dir_ / "grid.asc";
  write_file(asc,
             "ncols 4\nnrows 3\nxllcorner 1000\nyllcorner 2000\ncellsize 5\nNODATA_value -9999\n"
             "1 2 3 4\n5 6 -9999 8\n9 10 11 12\n");
  const Raster r = read_raster(asc, CrsPolicy::Any);
  ASSERT_EQ(r.nx, 4);
  ASSERT_EQ(r.ny, 3);
  EXPECT_DOUBLE_EQ(r.geotransform[0], 1000.0);
  EXPECT_DOUBLE_EQ(r.geotransform[1], 5.0);
  EXPECT_DOUBLE_EQ(r.geotransform[3], 2015.0);  // yll + nrows·cellsize: row 0 is the north edge
  EXPECT_DOUBLE_EQ(r.geotransform[5], -5.0);
  EXPECT_TRUE(r.crs_wkt.empty());
  ASSERT_TRUE(r.nodata.has_value());
  EXPECT_EQ(*r.nodata, -9999.0);
  EXPECT_EQ(r.at(0, 0), 1.0);
  EXPECT_EQ(r.at(3, 2), 12.0);
  EXPECT_TRUE(r.is_nodata(r.at(2, 1)));
  EXPECT_FALSE(r.is_nodata(r.at(1, 1)));
  const Vec2 c = r.cell_centre(0, 0);
  EXPECT_DOUBLE_EQ(c.x(), 1002.5);
  EXPECT_DOUBLE_EQ(c.y(), 2012.5);
  const auto ext = r.extent();
  EXPECT_DOUBLE_EQ(ext[0].x(), 1000.0);
  EXPECT_DOUBLE_EQ(ext[0].y(), 2000.0);
  EXPECT_DOUBLE_EQ(ext[1].x(), 1020.0);
  EXPECT_DOUBLE_EQ(ext[1].y(), 2015.0);
  // No CRS under RequireProjected: a warning, and the grid is read all the same (metres).
  const Raster again = read_raster(asc);
  EXPECT_EQ(again.data, r.data);
}

TEST_F(RasterTest, SouthUpGridIsFlippedToNorthUp) {
  Raster r = make_grid(2, 3, 1.0, 1.0);
  r.geotransform = {0.0, 1.0, 0.0, 100.0, 0.0, 1.0};  // row 0 at the south edge, y = 100..101
  r.data = {1, 2, 3, 4, 5, 6};
  write_geotiff(dir_ / "south.tif", r);
  const Raster back = read_raster(dir_ / "south.tif");
  EXPECT_DOUBLE_EQ(back.geotransform[3], 103.0);
  EXPECT_DOUBLE_EQ(back.geotransform[5], -1.0);
  EXPECT_EQ(back.data, (std::vector<double>{5, 6, 3, 4, 1, 2}));
}

TEST_F(RasterTest, RotatedGeotransformIsAnInputError) {
  Raster r = make_grid(3, 3, 1.0, 1.0);
  r.geotransform[2] = 0.1;
  r.geotransform[4] = 0.1;
  write_geotiff(dir_ / "rotated.tif", r);
  try {
    read_raster(dir_ / "rotated.tif");
    FAIL() << "rotated raster was accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains_text(e.what(), "rotated")) << e.what();
    EXPECT_TRUE(contains_text(e.what(), "rotated.tif")) << e.what();
  }
}

TEST_F(RasterTest, GeographicCrsIsAnInputErrorSuggestingGdalwarp) {
  Raster r = make_grid(3, 3, 0.001, 0.001);
  r.geotransform = {9.0, 0.001, 0.0, 45.0, 0.0, -0.001};
  r.crs_wkt = crs_to_wkt("EPSG:4326");
  EXPECT_TRUE(crs_is_geographic(r.crs_wkt));
  EXPECT_FALSE(crs_is_geographic(crs_to_wkt("EPSG:32632")));
  write_geotiff(dir_ / "lonlat.tif", r);
  try {
    read_raster(dir_ / "lonlat.tif");
    FAIL() << "geographic raster was accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains_text(e.what(), "gdalwarp -t_srs EPSG:32632")) << e.what();  // lon 9°: UTM 32N
    EXPECT_TRUE(contains_text(e.what(), "lonlat.tif")) << e.what();
  }
  EXPECT_NO_THROW(read_raster(dir_ / "lonlat.tif", CrsPolicy::Any));
}

TEST_F(RasterTest, UnreadableOrMissingRasterIsAnInputErrorNamingTheFile) {
  write_file(dir_ / "junk.tif", "this is not a raster");
  try {
    read_raster(dir_ / "junk.tif");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (dir_ / "junk.tif").string());
  }
  EXPECT_THROW(read_raster(dir_ / "missing.tif"), InputError);
  EXPECT_THROW(crs_to_wkt("EPSG:999999999"), InputError);
}

// ---------------------------------------------------------------------------------------------
// Terrain

TEST(RasterTerrain, BilinearIsExactOnAPlaneWithItsGradientAndNormal) {
  // z = a + b x + c y is bilinear, so interpolation between centres reproduces it to rounding.
  const double a = 1234.5, b = 0.37, c = -0.81;
  Raster r = make_grid(20, 15, 2.0, 3.0);
  fill(r, [&](double x, double y) { return a + b * (x - 500000.0) + c * (y - 5200000.0); });
  const Terrain t(r);
  std::mt19937 gen(42);
  const Vec2 lo = r.cell_centre(0, r.ny - 1), hi = r.cell_centre(r.nx - 1, 0);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y());
  const Vec3 n_exact = Vec3(-b, -c, 1.0).normalized();
  for (int k = 0; k < 1000; ++k) {
    const double x = ux(gen), y = uy(gen);
    ASSERT_TRUE(t.valid(x, y));
    // Tolerance: rounding of z ≈ 1e3 (1e-13 relative) and of the coordinates ≈ 5e6 (1e-9 absolute).
    EXPECT_NEAR(t.elevation(x, y), a + b * (x - 500000.0) + c * (y - 5200000.0), 1e-9);
    const Vec2 g = t.gradient(x, y);
    EXPECT_NEAR(g.x(), b, 1e-9);
    EXPECT_NEAR(g.y(), c, 1e-9);
    EXPECT_NEAR((t.normal(x, y) - n_exact).norm(), 0.0, 1e-9);
  }
  // The centre grid's corners are inside; beyond the outermost centres is outside.
  EXPECT_TRUE(t.valid(lo.x(), lo.y()));
  EXPECT_TRUE(t.valid(hi.x(), hi.y()));
  EXPECT_NEAR(t.elevation(hi.x(), hi.y()), a + b * (hi.x() - 500000.0) + c * (hi.y() - 5200000.0), 1e-9);
  EXPECT_FALSE(t.valid(lo.x() - 0.01, lo.y()));
  EXPECT_FALSE(t.valid(hi.x(), hi.y() + 0.01));
  EXPECT_TRUE(std::isnan(t.elevation(hi.x() + 1.0, hi.y())));
  EXPECT_TRUE(std::isnan(t.gradient(lo.x(), lo.y() - 1.0).x()));
  EXPECT_FALSE(t.valid(std::nan(""), lo.y()));
  // to_pixel is centre-based.
  const Vec2 p = r.to_pixel(r.cell_centre(4, 7));
  EXPECT_NEAR(p.x(), 4.0, 1e-12);
  EXPECT_NEAR(p.y(), 7.0, 1e-12);
}

TEST(RasterTerrain, NodataInvalidatesTheFourSurroundingPatches) {
  Raster r = make_grid(10, 10, 5.0, 5.0);
  r.nodata = -9999.0;
  fill(r, [](double, double) { return 100.0; });
  r.at(5, 5) = -9999.0;
  const Terrain t(r);
  const Vec2 c = r.cell_centre(5, 5);
  for (double ox : {-4.9, -0.1, 0.0, 0.1, 4.9})
    for (double oy : {-4.9, 0.0, 4.9}) {
      EXPECT_FALSE(t.valid(c.x() + ox, c.y() + oy)) << ox << " " << oy;
      EXPECT_TRUE(std::isnan(t.elevation(c.x() + ox, c.y() + oy)));
    }
  EXPECT_TRUE(t.valid(c.x() + 5.1, c.y()));
  EXPECT_TRUE(t.valid(c.x(), c.y() - 5.1));
  EXPECT_DOUBLE_EQ(t.elevation(c.x() + 7.0, c.y() + 7.0), 100.0);
  // NaN cells count as nodata even without a declared nodata value.
  Raster q = make_grid(4, 4, 1.0, 1.0);
  q.at(1, 1) = std::nan("");
  const Terrain tq(q);
  const Vec2 qc = q.cell_centre(1, 1);
  EXPECT_FALSE(tq.valid(qc.x() + 0.5, qc.y() + 0.5));
  EXPECT_TRUE(tq.valid(qc.x() + 1.5, qc.y() - 1.5));
}

TEST(RasterTerrain, SampleTerrainMatchesElevationAndGradient) {
  Raster r = make_grid(30, 20, 2.0, 2.0);
  r.nodata = -9999.0;
  fill(r,
       [](double x, double y) { return 100.0 + std::sin(0.05 * (x - 500000.0)) * std::cos(0.07 * (y - 5200000.0)); });
  r.at(10, 10) = -9999.0;
  const Terrain t(r);
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> ux(499990.0, 500070.0), uy(5199950.0, 5200010.0);
  int valid = 0, invalid = 0;
  for (int k = 0; k < 2000; ++k) {
    const double x = ux(gen), y = uy(gen);
    TerrainSample s{};
    const bool ok = sample_terrain(t, x, y, s);
    ASSERT_EQ(ok, t.valid(x, y));
    if (!ok) {
      ++invalid;
      EXPECT_TRUE(std::isnan(t.elevation(x, y)));
      continue;
    }
    ++valid;
    EXPECT_EQ(s.z, t.elevation(x, y));
    EXPECT_EQ(s.gradient, t.gradient(x, y));
    // The gradient is the derivative of the interpolated surface (central difference, step 1e-4 m
    // inside one patch: error of order 1e-8 from rounding of z ≈ 100).
    const double h = 1e-4;
    if (t.valid(x - h, y) && t.valid(x + h, y) && t.valid(x, y - h) && t.valid(x, y + h) &&
        std::floor(r.to_pixel({x - h, y}).x()) == std::floor(r.to_pixel({x + h, y}).x()) &&
        std::floor(r.to_pixel({x, y - h}).y()) == std::floor(r.to_pixel({x, y + h}).y())) {
      EXPECT_NEAR(s.gradient.x(), (t.elevation(x + h, y) - t.elevation(x - h, y)) / (2 * h), 1e-6);
      EXPECT_NEAR(s.gradient.y(), (t.elevation(x, y + h) - t.elevation(x, y - h)) / (2 * h), 1e-6);
    }
  }
  EXPECT_GT(valid, 800);    // ≈ 46 % of the sampled box lies inside the centre grid
  EXPECT_GT(invalid, 800);  // outside the centre grid and around the nodata cell
  // A single cell has no patch: Terrain rejects it (TooSmallRasterIsRejected), and so does the
  // core sampler (test_terrain.cpp).
}

TEST(RasterTerrain, TooSmallRasterIsRejected) {
  EXPECT_THROW(Terrain(make_grid(1, 5, 1.0, 1.0)), InputError);
}

// ---------------------------------------------------------------------------------------------
// Profiles

TEST(RasterProfile, PlaneProfileHasTheSpacingVerticesAndExactElevations) {
  Raster r = make_grid(50, 40, 2.0, 2.0);
  auto plane = [](double x, double y) { return 500.0 + 0.2 * (x - 500000.0) - 0.1 * (y - 5200000.0); };
  fill(r, plane);
  const Terrain t(r);
  const std::vector<Vec2> line = {{500010.0, 5199930.0}, {500060.0, 5199930.0}, {500060.0, 5199990.0}};
  const double spacing = 7.0;
  const auto prof = extract_profile(t, line, spacing);
  // Segment 1 (50 m): 0,7,...,49 then 50; segment 2 (60 m): +7,...,+56 then +60.
  ASSERT_EQ(prof.size(), 8u + 1u + 8u + 1u);
  EXPECT_EQ(prof.front().s, 0.0);
  EXPECT_EQ(prof.front().x, line[0].x());
  EXPECT_EQ(prof.front().y, line[0].y());
  int vertices_found = 0;
  for (std::size_t k = 0; k < prof.size(); ++k) {
    const auto& p = prof[k];
    EXPECT_NEAR(p.z, plane(p.x, p.y), 1e-9);
    if (k > 0) {
      const double ds = p.s - prof[k - 1].s;
      EXPECT_GT(ds, 0.0);
      EXPECT_LE(ds, spacing + 1e-12);
      // s is the distance along the polyline: equal to the chord inside a segment.
      EXPECT_NEAR(ds, std::hypot(p.x - prof[k - 1].x, p.y - prof[k - 1].y), 1e-9);
    }
    for (const auto& v : line)
      if (p.x == v.x() && p.y == v.y()) ++vertices_found;
  }
  EXPECT_EQ(vertices_found, 3);
  EXPECT_NEAR(prof[7].s, 49.0, 1e-12);
  EXPECT_NEAR(prof[8].s, 50.0, 1e-12);
  EXPECT_NEAR(prof[9].s, 57.0, 1e-12);
  EXPECT_NEAR(prof.back().s, 110.0, 1e-12);
}

TEST(RasterProfile, ConeProfileFollowsTheSurface) {
  // Cone z = 200 − 0.5 r around (500050, 5199950) on 1 m cells. Bilinear error away from the
  // apex is ≤ h²/8 · (|z_xx| + 2|z_xy| + |z_yy|) ≤ (1/8)(4 · 0.5/r) ≤ 0.05 m for r ≥ 5 m.
  Raster r = make_grid(100, 100, 1.0, 1.0);
  const double cx = 500050.0, cy = 5199950.0;
  auto cone = [&](double x, double y) { return 200.0 - 0.5 * std::hypot(x - cx, y - cy); };
  fill(r, cone);
  const Terrain t(r);
  const auto prof = extract_profile(t, {{cx - 40.0, cy + 5.0}, {cx + 40.0, cy + 5.0}}, 2.0);
  ASSERT_EQ(prof.size(), 41u);
  for (const auto& p : prof) EXPECT_NEAR(p.z, cone(p.x, p.y), 0.05) << "s = " << p.s;
  for (std::size_t k = 1; k < prof.size(); ++k) EXPECT_NEAR(prof[k].s - prof[k - 1].s, 2.0, 1e-9);
  // Highest point where the line passes closest to the apex (s = 40 m): z = 200 − 0.5·5.
  const auto top = std::max_element(prof.begin(), prof.end(), [](auto& a, auto& b) { return a.z < b.z; });
  EXPECT_NEAR(top->s, 40.0, 1e-9);
  EXPECT_NEAR(top->z, 197.5, 0.05);
}

TEST(RasterProfile, BadProfilesAreInputErrors) {
  Raster r = make_grid(10, 10, 1.0, 1.0);
  const Terrain t(r);
  const Vec2 a = r.cell_centre(1, 1), b = r.cell_centre(8, 8);
  EXPECT_THROW(extract_profile(t, {a, b}, 0.0), InputError);
  EXPECT_THROW(extract_profile(t, {a, b}, -1.0), InputError);
  EXPECT_THROW(extract_profile(t, {a}, 1.0), InputError);
  EXPECT_THROW(extract_profile(t, {a, Vec2(b.x() + 100.0, b.y())}, 1.0), InputError);
  EXPECT_NO_THROW(extract_profile(t, {a, b}, 1.0));
}

// ---------------------------------------------------------------------------------------------
// Polygons

namespace {
// A 0.01° square at lon 9–9.01°, lat 45–45.01° with a 0.002° hole in its middle (GeoJSON: WGS 84,
// lon/lat order), a thickness attribute and a text field.
const char* kSquareWithHole = R"({"type": "FeatureCollection", "features": [
 {"type": "Feature", "properties": {"thickness": 2.5, "name": "release"},
  "geometry": {"type": "Polygon", "coordinates": [
    [[9.0, 45.0], [9.01, 45.0], [9.01, 45.01], [9.0, 45.01], [9.0, 45.0]],
    [[9.004, 45.004], [9.004, 45.006], [9.006, 45.006], [9.006, 45.004], [9.004, 45.004]]]}},
 {"type": "Feature", "properties": {"thickness": 1.0, "name": "point"},
  "geometry": {"type": "Point", "coordinates": [9.1, 45.1]}}]})";
}  // namespace

TEST_F(RasterTest, ReadPolygonsReprojectsGeoJsonWithHoleAndAttribute) {
  const fs::path gj = dir_ / "release.geojson";
  write_file(gj, kSquareWithHole);
  const std::string utm32 = crs_to_wkt("EPSG:32632");
  const auto polys = read_polygons(gj, "thickness", utm32);
  ASSERT_EQ(polys.size(), 1u);  // the point feature is not a polygon
  const Polygon& p = polys[0];
  EXPECT_EQ(p.attribute, 2.5);
  ASSERT_EQ(p.outer.size(), 4u);  // closing vertex dropped
  ASSERT_EQ(p.holes.size(), 1u);
  // lon 9° is the central meridian of UTM 32: x = 500000 m exactly; lat 45° on it is at
  // northing 0.9996 × 4 984 944.4 m (meridian arc) = 4 982 950.4 m.
  EXPECT_NEAR(p.outer[0].x(), 500000.0, 1e-3);
  EXPECT_NEAR(p.outer[0].y(), 4982950.4, 1.0);
  // All vertices agree with transform_points.
  const auto expect =
      transform_points({{9.0, 45.0}, {9.01, 45.0}, {9.01, 45.01}, {9.0, 45.01}}, crs_to_wkt("EPSG:4326"), utm32);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR((p.outer[k] - expect[k]).norm(), 0.0, 1e-6);
  // contains: inside the ring, inside the hole, outside.
  const auto mid = transform_points({{9.005, 45.005}, {9.002, 45.005}, {9.02, 45.005}, {9.005, 45.0085}},
                                    crs_to_wkt("EPSG:4326"), utm32);
  EXPECT_FALSE(p.contains(mid[0]));  // in the hole
  EXPECT_TRUE(p.contains(mid[1]));
  EXPECT_FALSE(p.contains(mid[2]));
  EXPECT_TRUE(p.contains(mid[3]));
  // Without a target CRS the coordinates stay in degrees; without an attribute it is NaN.
  const auto raw = read_polygons(gj, "", "");
  ASSERT_EQ(raw.size(), 1u);
  EXPECT_DOUBLE_EQ(raw[0].outer[1].x(), 9.01);
  EXPECT_TRUE(std::isnan(raw[0].attribute));
}

TEST_F(RasterTest, ReadPolygonsMissingAttributeListsTheFields) {
  const fs::path gj = dir_ / "release.geojson";
  write_file(gj, kSquareWithHole);
  try {
    read_polygons(gj, "depth", "");
    FAIL() << "missing attribute accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains_text(e.what(), "depth")) << e.what();
    EXPECT_TRUE(contains_text(e.what(), "thickness")) << e.what();
    EXPECT_TRUE(contains_text(e.what(), "name")) << e.what();
  }
  EXPECT_THROW(read_polygons(gj, "name", ""), InputError);  // not numeric
}

TEST_F(RasterTest, ReadPolygonsRejectsUnreadableAndPolygonFreeSources) {
  write_file(dir_ / "bad.geojson", "{ not json");
  EXPECT_THROW(read_polygons(dir_ / "bad.geojson", "", ""), InputError);
  EXPECT_THROW(read_polygons(dir_ / "missing.shp", "", ""), InputError);
  write_file(dir_ / "points.geojson",
             R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
                 "geometry": {"type": "Point", "coordinates": [9.1, 45.1]}}]})");
  try {
    read_polygons(dir_ / "points.geojson", "", "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_TRUE(contains_text(e.what(), "no polygon")) << e.what();
  }
}

TEST(RasterPolygon, ContainsWithHoleAndUnclosedRing) {
  Polygon p;
  p.outer = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  p.holes = {{{4, 4}, {6, 4}, {6, 6}, {4, 6}}};
  EXPECT_TRUE(p.contains({1, 1}));
  EXPECT_TRUE(p.contains({9, 5}));
  EXPECT_FALSE(p.contains({5, 5}));
  EXPECT_FALSE(p.contains({-1, 5}));
  EXPECT_FALSE(p.contains({5, 11}));
}

// ---------------------------------------------------------------------------------------------
// Pictures

TEST(RasterRamp, EndpointsAreTheControlColours) {
  EXPECT_EQ(ramp_colour(ColourRamp::Viridis, 0.0), (std::array<std::uint8_t, 3>{68, 1, 84}));
  EXPECT_EQ(ramp_colour(ColourRamp::Viridis, 1.0), (std::array<std::uint8_t, 3>{253, 231, 37}));
  EXPECT_EQ(ramp_colour(ColourRamp::Viridis, 2.0), ramp_colour(ColourRamp::Viridis, 1.0));  // clamped
  EXPECT_EQ(ramp_colour(ColourRamp::Magma, -1.0), (std::array<std::uint8_t, 3>{0, 0, 4}));
  EXPECT_EQ(ramp_colour(ColourRamp::BlueRed, 0.5), (std::array<std::uint8_t, 3>{247, 247, 247}));
  // The full 256-entry tables: t = 0.125 is entry 32 of matplotlib's viridis, (0.278826,
  // 0.175490, 0.483397) in sRGB fractions; the middle of magma is entry 128, (0.716387, 0.214982,
  // 0.475290).
  EXPECT_EQ(ramp_colour(ColourRamp::Viridis, 0.125), (std::array<std::uint8_t, 3>{71, 45, 123}));
  EXPECT_EQ(ramp_colour(ColourRamp::Magma, 0.5), (std::array<std::uint8_t, 3>{183, 55, 121}));
  // Perceptually uniform: the lightness rises monotonically along viridis (sum of channels as a
  // proxy, weighted as luma).
  double last = -1.0;
  for (int k = 0; k <= 255; k += 5) {
    const auto c = ramp_colour(ColourRamp::Viridis, k / 255.0);
    const double luma = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    EXPECT_GT(luma, last) << k;
    last = luma;
  }
}

TEST_F(RasterTest, ImageWritesAPngThatGdalReadsBack) {
  Image img(40, 30);
  img.line(0, 0, 39, 0, {255, 0, 0});
  img.fill_circle(20, 15, 3, {0, 0, 255});
  img.set(100, 100, {0, 0, 0});  // out of range: ignored
  write_png(dir_ / "plot.png", img);
  EXPECT_FALSE(fs::exists(dir_ / "plot.png.partial"));
  const Image back = read_image(dir_ / "plot.png");
  ASSERT_EQ(back.width, 40);
  ASSERT_EQ(back.height, 30);
  EXPECT_EQ(back.rgb, img.rgb);
  auto px = [&](int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * back.width + x) * 3;
    return std::array<std::uint8_t, 3>{back.rgb[i], back.rgb[i + 1], back.rgb[i + 2]};
  };
  EXPECT_EQ(px(17, 0), (std::array<std::uint8_t, 3>{255, 0, 0}));
  EXPECT_EQ(px(20, 17), (std::array<std::uint8_t, 3>{0, 0, 255}));
  EXPECT_EQ(px(5, 20), (std::array<std::uint8_t, 3>{255, 255, 255}));
}

TEST_F(RasterTest, QuicklookHasHillshadeOverlayAndColourBar) {
  Raster dem = make_grid(300, 200, 5.0, 5.0);
  fill(dem, [](double x, double y) {
    return 1000.0 + 0.3 * (x - 500000.0) + 200.0 * std::exp(-std::pow((y - 5199500.0) / 200.0, 2));
  });
  Raster over = dem.like(-1.0, -1.0);
  for (int row = 50; row < 100; ++row)
    for (int col = 100; col < 150; ++col) over.at(col, row) = 1.0 + (col - 100) * 0.1;
  QuicklookOptions o;
  o.title = "max depth";
  o.unit = "m";
  const MapLayout lay = write_quicklook_png(dir_ / "quick.png", dem, &over, o);
  const Image img = read_image(dir_ / "quick.png");
  // Print size: 1800 px wide, the whole 1500 m × 1000 m raster in a frame of at least 1600 px.
  EXPECT_EQ(img.width, 1800);
  EXPECT_EQ(img.height, lay.height);
  EXPECT_GE(lay.frame_w, 1600);
  EXPECT_NEAR(lay.frame_w * lay.metres_per_pixel, 1500.0, 1.0);
  EXPECT_NEAR(lay.frame_h * lay.metres_per_pixel, 1000.0, 1.0);
  auto px = [&](double x, double y) {
    const std::size_t i = (static_cast<std::size_t>(y) * img.width + static_cast<std::size_t>(x)) * 3;
    return std::array<int, 3>{img.rgb[i], img.rgb[i + 1], img.rgb[i + 2]};
  };
  auto grey = [](std::array<int, 3> c) { return c[0] == c[1] && c[1] == c[2]; };
  // Pixel of a map point (metres from the raster's west and north edges).
  const auto at = [&](double east, double south) {
    return px(lay.frame_x + east / lay.metres_per_pixel, lay.frame_y + south / lay.metres_per_pixel);
  };
  // The overlay block (500–750 m east, 250–500 m south) is coloured; the hillshade around it grey
  // (probed 3 px inside and outside its edges: the cells are drawn as cells, nearest).
  int coloured = 0, probes = 0;
  for (double e = 505; e < 750; e += 10)
    for (double s = 255; s < 500; s += 10) {
      ++probes;
      coloured += !grey(at(e, s));
    }
  EXPECT_EQ(coloured, probes);
  int grey_outside = 0, outside = 0;
  for (double e = 20; e < 1500; e += 37)
    for (double s = 20; s < 1000; s += 37) {
      if (e > 480 && e < 770 && s > 230 && s < 520) continue;
      if (e < 400 && s > 700) continue;  // the scale bar's box
      ++outside;
      grey_outside += grey(at(e, s));
    }
  EXPECT_EQ(grey_outside, outside);
  // GDAL's hillshade varies (sunny and shaded slopes), not one flat grey.
  EXPECT_NE(at(50, 200), at(50, 800));
  // The colour bar below the frame carries the ramp; ticks and the CRS with its EPSG code.
  int bar = 0;
  for (int y = lay.legend_y; y < lay.legend_y + lay.legend_h; ++y)
    for (int x = lay.legend_x; x < lay.legend_x + lay.legend_w; x += 3) bar += !grey(px(x, y));
  EXPECT_GT(bar, 2000);
  EXPECT_GE(lay.x_ticks, 3);
  EXPECT_GE(lay.y_ticks, 2);
  EXPECT_NE(lay.crs_label.find("EPSG:32632"), std::string::npos) << lay.crs_label;
  EXPECT_NE(lay.crs_label.find("UTM zone 32N"), std::string::npos) << lay.crs_label;
  // A large raster still gives one print-size picture.
  Raster wide = make_grid(3300, 12, 1.0, 1.0);
  fill(wide, [](double x, double) { return 0.01 * (x - 500000.0); });
  write_quicklook_png(dir_ / "wide.png", wide, nullptr, ColourRamp::Terrain, "elevation (m)");
  const Image w = read_image(dir_ / "wide.png");
  EXPECT_EQ(w.width, 1800);
  // Mismatched overlay grid is an input error, and nothing is written.
  const Raster small = make_grid(10, 10, 5.0, 5.0);
  EXPECT_THROW(write_quicklook_png(dir_ / "bad.png", dem, &small, ColourRamp::Magma, "x"), InputError);
  EXPECT_FALSE(fs::exists(dir_ / "bad.png"));
}

// Issue #33: a map an engineer can hand on. A 300 × 200 grid of 5 m cells, an overlay block of
// 50 × 50 cells (cols 100–149, rows 50–99) at 2.6 m, an extent 50 m around it (cols 90–159 ×
// rows 40–109: 350 m × 350 m), classes at 0.5/1/2 m, the block's outline, a line, scale bar and
// north arrow.
TEST_F(RasterTest, QuicklookOnAnExtentWithClassesOutlinesScaleBarAndArrow) {
  Raster dem = make_grid(300, 200, 5.0, 5.0);
  fill(dem, [](double x, double y) { return 1000.0 + 0.2 * (x - 500000.0) - 0.1 * (y - 5200000.0); });
  Raster over = dem.like(0.0, -9999.0);
  for (int row = 50; row < 100; ++row)
    for (int col = 100; col < 150; ++col) over.at(col, row) = 2.6;
  QuicklookOptions o;
  o.title = "peak flow depth";
  o.unit = "m";
  o.ramp = ColourRamp::Viridis;
  o.overlay_min = 0.01;
  o.class_breaks = {0.5, 1.0, 2.0};
  o.extent = map_extent(over, 0.01, 50.0);
  o.scale_bar = true;
  o.north_arrow = true;
  o.outlines = mask_outlines(over, 0.01);
  o.lines = {{dem.cell_centre(95, 45), dem.cell_centre(155, 45)}};
  o.attribution = "Terrain: test data";
  ASSERT_EQ(o.outlines.size(), 1u);
  EXPECT_EQ(o.outlines[0].size(), 5u);  // the block's four corners, closed
  const auto& e = *o.extent;
  EXPECT_DOUBLE_EQ(e[0], 500000.0 + 90 * 5.0);
  EXPECT_DOUBLE_EQ(e[2], 500000.0 + 160 * 5.0);
  EXPECT_DOUBLE_EQ(e[3], 5200000.0 - 40 * 5.0);
  EXPECT_DOUBLE_EQ(e[1], 5200000.0 - 110 * 5.0);
  const MapLayout lay = write_quicklook_png(dir_ / "map.png", dem, &over, o);
  const Image img = read_image(dir_ / "map.png");
  ASSERT_EQ(img.width, 1800);
  EXPECT_NEAR(lay.frame_w * lay.metres_per_pixel, 350.0, 1.0);
  auto px = [&](double x, double y) {
    const std::size_t i = (static_cast<std::size_t>(y) * img.width + static_cast<std::size_t>(x)) * 3;
    return std::array<int, 3>{img.rgb[i], img.rgb[i + 1], img.rgb[i + 2]};
  };
  const auto at = [&](double east, double south) {  // metres from the extent's west and north edges
    return px(lay.frame_x + east / lay.metres_per_pixel, lay.frame_y + south / lay.metres_per_pixel);
  };
  // 2.6 m is in the top class (≥ 2 m), drawn in its exact legend colour: viridis at 0.95.
  const auto top = ramp_colour(ColourRamp::Viridis, 0.95);
  const std::array<int, 3> top_i{top[0], top[1], top[2]};
  EXPECT_EQ(at(175, 175), top_i);
  EXPECT_EQ(at(100, 240), top_i);
  // The legend shows the four class swatches in their exact colours and the two symbols.
  int swatch_top = 0, swatch_low = 0;
  const auto low = ramp_colour(ColourRamp::Viridis, 0.1);
  for (int y = lay.legend_y; y < lay.legend_y + lay.legend_h; ++y)
    for (int x = lay.legend_x; x < lay.legend_x + lay.legend_w; ++x) {
      const auto c = px(x, y);
      swatch_top += c == top_i;
      swatch_low += c == std::array<int, 3>{low[0], low[1], low[2]};
    }
  EXPECT_GT(swatch_top, 400);  // a 26 × 26 px swatch less its border
  EXPECT_GT(swatch_low, 400);
  // Scale bar: the longest 1/2/5 × 10^k m within a quarter of the frame: 50 m; its first quarter
  // black, its second white.
  EXPECT_DOUBLE_EQ(lay.scale_bar_m, 50.0);
  EXPECT_NEAR(lay.scale_bar_px, 50.0 / lay.metres_per_pixel, 1.0);
  const int q = lay.scale_bar_px / 4, yb = lay.scale_bar_y - 5;
  EXPECT_EQ(px(lay.scale_bar_x + q / 2, yb), (std::array<int, 3>{0, 0, 0}));
  EXPECT_EQ(px(lay.scale_bar_x + q + q / 2, yb), (std::array<int, 3>{255, 255, 255}));
  // North arrow: black pixels in the frame's upper right corner.
  int arrow = 0;
  for (int y = lay.frame_y; y < lay.frame_y + 140; ++y)
    for (int x = lay.frame_x + lay.frame_w - 80; x < lay.frame_x + lay.frame_w; ++x)
      arrow += px(x, y) == std::array<int, 3>{0, 0, 0};
  EXPECT_GT(arrow, 300);
  // The line along row 45 (5–10 m south of the extent's edge… its centre 27.5 m) is dark.
  EXPECT_EQ(at(175, 27.5), (std::array<int, 3>{25, 25, 25}));
  // Ticks on both axes and the CRS line.
  EXPECT_GE(lay.x_ticks, 3);
  EXPECT_GE(lay.y_ticks, 3);
  EXPECT_NE(lay.crs_label.find("EPSG:32632"), std::string::npos);
  // Decreasing class breaks are refused.
  o.class_breaks = {1.0, 0.5};
  EXPECT_THROW(write_quicklook_png(dir_ / "bad.png", dem, &over, o), InputError);
}

TEST(QuicklookTicks, NiceTicksFallOnOneTwoFiveSteps) {
  const auto u = nice_ticks(0.0, 1.0, 5);  // step 0.2, both ends included
  ASSERT_EQ(u.size(), 6u);
  for (std::size_t k = 0; k < u.size(); ++k) EXPECT_NEAR(u[k], 0.2 * k, 1e-12);
  const auto t = nice_ticks(0.3, 2.7, 5);  // raw step 0.48 → 0.5: 0.5 … 2.5
  ASSERT_EQ(t.size(), 5u);
  EXPECT_DOUBLE_EQ(t.front(), 0.5);
  EXPECT_DOUBLE_EQ(t.back(), 2.5);
  EXPECT_TRUE(nice_ticks(1.0, 1.0, 4).empty());
  EXPECT_EQ(format_tick(1e6), "1e+06");
  EXPECT_EQ(format_tick(0.25), "0.25");
  EXPECT_EQ(format_tick(-1e-320), "0");
}

// ---------------------------------------------------------------------------------------------
// The real DTM shipped in data/terrain/alr (see data/terrain/README.md for the figures).

TEST(RasterRealTerrain, AlplehnerDtmAndReleasePolygon) {
  const fs::path dir = fs::path(GEOHAZ_SOURCE_DIR) / "data" / "terrain" / "alr";
  const Raster dem = read_raster(dir / "avaAlr.tif");
  EXPECT_EQ(dem.nx, 417);
  EXPECT_EQ(dem.ny, 915);
  EXPECT_DOUBLE_EQ(dem.cell_size_x(), 5.0);
  EXPECT_DOUBLE_EQ(dem.cell_size_y(), 5.0);
  EXPECT_FALSE(dem.crs_wkt.empty());
  EXPECT_FALSE(crs_is_geographic(dem.crs_wkt));
  EXPECT_TRUE(crs_equal(dem.crs_wkt, crs_to_wkt("EPSG:31287")));
  double lo = 1e30, hi = -1e30;
  for (double v : dem.data)
    if (!dem.is_nodata(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  EXPECT_NEAR(lo, 566.0, 1.0);
  EXPECT_NEAR(hi, 2452.0, 1.0);

  const auto rel = read_polygons(dir / "relAlr.shp", "thickness", dem.crs_wkt);
  ASSERT_GE(rel.size(), 1u);
  const Terrain terrain(dem);
  for (const auto& p : rel) {
    EXPECT_DOUBLE_EQ(p.attribute, 1.0);
    for (const auto& v : p.outer) EXPECT_TRUE(terrain.valid(v.x(), v.y()));  // release on the DTM
  }
}

// ---------------------------------------------------------------------------------------------
// Issue #12: full disk while writing a GeoTIFF or PNG, and a header declaring an absurd size.

// A full disk (a 2 kB file size limit in a child process) used to be reported as "input error",
// exit code 2: it is an IoError naming the file, and no ".partial" file is left.
TEST_F(RasterTest, FullDiskWhileWritingGeoTiffOrPngIsAnIoError) {
  Raster r = make_grid(200, 200, 1.0, 1.0);
  fill(r, [](double x, double y) { return std::sin(x) * std::cos(y); });  // does not compress away
  geohaz::testing::ChildLimits lim;
  lim.file_size = 2000;
  const auto tif = geohaz::testing::run_in_child(
      [&] {
        try {
          write_geotiff(dir_ / "big.tif", r);
        } catch (const IoError&) {
          return 3;
        } catch (const InputError&) {
          return 2;
        }
        return 0;
      },
      lim);
  ASSERT_TRUE(tif.exited) << tif.describe();
  EXPECT_EQ(tif.code, 3);
  const auto png = geohaz::testing::run_in_child(
      [&] {
        try {
          write_quicklook_png(dir_ / "big.png", r, nullptr, ColourRamp::Terrain, "elevation (m)");
        } catch (const IoError&) {
          return 3;
        } catch (const InputError&) {
          return 2;
        }
        return 0;
      },
      lim);
  ASSERT_TRUE(png.exited) << png.describe();
  EXPECT_EQ(png.code, 3);
  for (const auto& e : fs::directory_iterator(dir_)) ADD_FAILURE() << "left behind: " << e.path();
}

// A 100000 × 100000 GeoTIFF header on a few kB of data ended in std::bad_alloc naming nothing:
// now an InputError naming the file and the memory it would need, before anything is allocated.
TEST_F(RasterTest, HeaderDeclaringTooManyCellsIsAnInputErrorNamingTheFile) {
  const fs::path tif = dir_ / "huge.tif";
  Raster r = make_grid(8, 8, 1.0, 1.0);
  write_geotiff(tif, r);
  ASSERT_TRUE(geohaz::testing::set_tiff_size(tif, 100000, 100000));
  try {
    read_raster(tif);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), tif.string());
    EXPECT_TRUE(contains_text(e.what(), "100000 × 100000 cells")) << e.what();
    EXPECT_TRUE(contains_text(e.what(), "of memory")) << e.what();
  }
}
