// Unit tests for the OGR line reader (raster.hpp read_lines): lines and multi-line parts with
// their attribute, reprojection, refusal of non-line features; and the bundled thalweg.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"

namespace geohaz {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path d = fs::path(GEOHAZ_BINARY_DIR) / "test-scratch" / "vector";
  fs::create_directories(d);
  return d / name;
}

void write_geojson(const fs::path& p, const std::string& features) {
  std::ofstream f(p);
  f << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32654"}},)"
    << R"("features":[)" << features << "]}";
}

TEST(ReadLines, LinesAndMultiLinePartsWithTheirAttribute) {
  const fs::path p = scratch("lines.geojson");
  write_geojson(p, R"({"type":"Feature","properties":{"height":3.5},"geometry":{"type":"LineString",)"
                   R"("coordinates":[[480000,4309000],[480010,4309000],[480010,4309020]]}},)"
                   R"({"type":"Feature","properties":{"height":2},"geometry":{"type":"MultiLineString",)"
                   R"("coordinates":[[[0,0],[1,1]],[[2,2],[3,3],[4,5]]]}})");
  const auto lines = read_lines(p, "height", "");
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0].vertices.size(), 3u);
  EXPECT_EQ(lines[0].vertices[2], Vec2(480010, 4309020));
  EXPECT_EQ(lines[0].attribute, 3.5);
  EXPECT_EQ(lines[1].vertices.size(), 2u);
  EXPECT_EQ(lines[2].vertices.back(), Vec2(4, 5));
  EXPECT_EQ(lines[2].attribute, 2.0);
}

TEST(ReadLines, ReprojectedToTheTargetCrs) {
  const fs::path p = scratch("utm.geojson");
  write_geojson(p, R"({"type":"Feature","properties":{},"geometry":{"type":"LineString",)"
                   R"("coordinates":[[500000,4300000],[500000,4310000]]}})");
  const std::string wgs84 = crs_to_wkt("EPSG:4326");
  const auto lines = read_lines(p, "", wgs84);
  ASSERT_EQ(lines.size(), 1u);
  // UTM 54N easting 500000 is the central meridian, 141° E.
  EXPECT_NEAR(lines[0].vertices[0].x(), 141.0, 1e-6);
  EXPECT_NEAR(lines[0].vertices[1].y() - lines[0].vertices[0].y(), 10000.0 / 111000.0, 1e-3);
}

TEST(ReadLines, RefusesPointsAndPolygonsNamingTheFeature) {
  const fs::path p = scratch("points.geojson");
  write_geojson(p, R"({"type":"Feature","properties":{},"geometry":{"type":"Point","coordinates":[1,2]}})");
  try {
    read_lines(p, "", "");
    ADD_FAILURE() << "a point was read as a line";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a line"), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), p.string());
  }
  EXPECT_THROW(read_lines(p, "nonexistent", ""), InputError);
}

TEST(ReadLines, BundledAlplehnerThalweg) {
  // data/terrain/alr/path_aimec.shp: one line from the release area down to the valley, in the
  // DTM's CRS (MGI / Austria Lambert), about 3.3 km long.
  const auto lines = read_lines(fs::path(GEOHAZ_SOURCE_DIR) / "data/terrain/alr/path_aimec.shp", "", "");
  ASSERT_EQ(lines.size(), 1u);
  double length = 0.0;
  for (std::size_t i = 1; i < lines[0].vertices.size(); ++i)
    length += (lines[0].vertices[i] - lines[0].vertices[i - 1]).norm();
  EXPECT_GT(length, 2500.0);
  EXPECT_LT(length, 5000.0);
}

// write_raster_polygons (issue #32): equal-valued 4-connected cells form one polygon along the
// cell edges with the value as attribute; each cell centre lies in exactly its own polygon; nodata,
// NaN and values <= 0 are left out; read back by read_polygons.
TEST(WriteRasterPolygons, CellsBecomePolygonsThatContainTheirCentres) {
  Raster r;
  r.nx = 5;
  r.ny = 4;
  r.geotransform = {500000.0, 2.0, 0.0, 4300000.0, 0.0, -2.0};
  r.crs_wkt = crs_to_wkt("EPSG:32632");
  r.nodata = -9999.0;
  // Two blocks of 1.5, one cell of 0.75 touching the first block, nodata, a NaN and zeros.
  r.data = {1.5,          1.5,  0.0,  0.0,     1.5,  //
            1.5,          0.75, 0.0,  -9999.0, 1.5,  //
            0.0,          0.0,  0.0,  0.0,     0.0,  //
            std::nan(""), 0.0,  -1.0, 0.0,     0.0};
  const fs::path p = scratch("cells.gpkg");
  fs::remove(p);
  EXPECT_EQ(write_raster_polygons(p, r, "thickness", "release"), 3u);
  EXPECT_FALSE(fs::exists(p.string() + ".partial"));
  const auto polys = read_polygons(p, "thickness", r.crs_wkt);
  ASSERT_EQ(polys.size(), 3u);
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) {
      const double v = r.at(col, row);
      const bool in = std::isfinite(v) && v > 0.0 && v != -9999.0;
      int inside = 0;
      double attribute = 0.0;
      for (const auto& poly : polys)
        if (poly.contains(r.cell_centre(col, row))) {
          ++inside;
          attribute = poly.attribute;
        }
      EXPECT_EQ(inside, in ? 1 : 0) << col << ", " << row;
      if (in) {
        EXPECT_EQ(attribute, v) << col << ", " << row;
      }
    }
  EXPECT_THROW(write_raster_polygons(scratch("cells.shp"), r, "thickness", "release"), InputError);
}

}  // namespace
}  // namespace geohaz
