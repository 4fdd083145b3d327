// GIS-ready outputs (docs/runout.md "Outputs"): a GeoTIFF carries its band description, unit and
// nodata, is tiled with internal overviews (the Cloud-Optimized layout), and its QGIS style files
// parse as XML with the expected ramp or classes. Read back with GDAL itself.
#include <cpl_minixml.h>
#include <gdal_priv.h>
#include <gdal_rat.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"

namespace fs = std::filesystem;

namespace {

fs::path dir() {
  const fs::path d = fs::temp_directory_path() / ("geohaz_gis_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct XmlTree {
  CPLXMLNode* root;
  explicit XmlTree(const std::string& text) : root(CPLParseXMLString(text.c_str())) {}
  ~XmlTree() {
    if (root) CPLDestroyXMLNode(root);
  }
};

}  // namespace

TEST(GeoTiff, CarriesDescriptionUnitNodataTilesAndOverviews) {
  geohaz::Raster r;
  r.nx = 700;
  r.ny = 600;
  r.geotransform = {1000.0, 5.0, 0.0, 9000.0, 0.0, -5.0};
  r.nodata = -9999.0;
  r.description = "peak flow depth, normal to the bed";
  r.unit = "m";
  r.data.resize(static_cast<std::size_t>(r.nx) * r.ny);
  for (std::size_t k = 0; k < r.data.size(); ++k)
    r.data[k] = (k % 97 == 0) ? -9999.0 : 0.001 * static_cast<double>(k % 1000);
  const fs::path f = dir() / "depth.tif";
  geohaz::write_geotiff(f, r);

  // Through geohaz's reader: the same values, description and unit.
  const geohaz::Raster back = geohaz::read_raster(f, geohaz::CrsPolicy::Any);
  EXPECT_EQ(back.description, r.description);
  EXPECT_EQ(back.unit, "m");
  ASSERT_TRUE(back.nodata.has_value());
  EXPECT_EQ(*back.nodata, -9999.0);
  for (std::size_t k = 0; k < r.data.size(); k += 1013) EXPECT_FLOAT_EQ(back.data[k], r.data[k]) << k;

  // Through GDAL: tiled 256 × 256, internal overviews, COG layout.
  GDALAllRegister();
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(f.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  ASSERT_TRUE(ds);
  GDALRasterBand* b = ds->GetRasterBand(1);
  int bx = 0, by = 0;
  b->GetBlockSize(&bx, &by);
  EXPECT_EQ(bx, 256);
  EXPECT_EQ(by, 256);
  EXPECT_GE(b->GetOverviewCount(), 1);
  const char* layout = ds->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE");
  ASSERT_NE(layout, nullptr);
  EXPECT_STREQ(layout, "COG");
  // Overviews are nearest-neighbour: every overview value is a value of the full raster (no mean).
  GDALRasterBand* ov = b->GetOverview(0);
  std::vector<float> row(static_cast<std::size_t>(ov->GetXSize()));
  ASSERT_EQ(ov->RasterIO(GF_Read, 0, 0, ov->GetXSize(), 1, row.data(), ov->GetXSize(), 1, GDT_Float32, 0, 0, nullptr),
            CE_None);
  for (float v : row) {
    const double scaled = static_cast<double>(v) / 0.001;
    EXPECT_TRUE(v == -9999.0f || std::abs(scaled - std::round(scaled)) < 1e-3) << v;
  }
}

TEST(QgisStyle, RampAndClassesParseAsXml) {
  const fs::path ramp = dir() / "speed.qml", classes = dir() / "intensity.qml";
  geohaz::write_qgis_ramp_style(ramp, geohaz::ColourRamp::Magma, 0.0, 42.0, "m/s", 0.0);
  geohaz::write_qgis_class_style(classes, {{2.0, "medium: reached, not strong", {245, 130, 32}},
                                           {3.0, "strong: h > 1 m & v > 1 m/s", {200, 30, 45}}});
  {
    XmlTree x(slurp(ramp));
    ASSERT_NE(x.root, nullptr);
    const CPLXMLNode* shader = CPLGetXMLNode(x.root, "=qgis.pipe.rasterrenderer.rastershader.colorrampshader");
    ASSERT_NE(shader, nullptr);
    EXPECT_STREQ(CPLGetXMLValue(x.root, "=qgis.pipe.rasterrenderer.type", ""), "singlebandpseudocolor");
    int items = 0;
    std::string last_label;
    for (const CPLXMLNode* n = shader->psChild; n; n = n->psNext)
      if (n->eType == CXT_Element && std::string(n->pszValue) == "item") {
        ++items;
        last_label = CPLGetXMLValue(n, "label", "");
      }
    EXPECT_EQ(items, 9);
    EXPECT_EQ(last_label, "42 m/s");
  }
  {
    XmlTree x(slurp(classes));
    ASSERT_NE(x.root, nullptr);
    const CPLXMLNode* pal = CPLGetXMLNode(x.root, "=qgis.pipe.rasterrenderer.colorPalette");
    ASSERT_NE(pal, nullptr);
    std::vector<std::string> values, labels;
    for (const CPLXMLNode* n = pal->psChild; n; n = n->psNext)
      if (n->eType == CXT_Element) {
        values.emplace_back(CPLGetXMLValue(n, "value", ""));
        labels.emplace_back(CPLGetXMLValue(n, "label", ""));
      }
    EXPECT_EQ(values, (std::vector<std::string>{"2", "3"}));
    EXPECT_EQ(labels[1], "strong: h > 1 m & v > 1 m/s");  // escaped in the file, intact when parsed
  }
}

// Issue #33: intensity classes as vector zones. A 60 × 40 grid of 5 m cells holding three classes
// (an L-shaped class 3 zone, a class 2 block with a hole, two separate class 1 blocks) and
// nodata; the GeoPackage's polygons, opened with OGR, cover exactly the raster's class areas
// (cell count × 25 m²), the fields hold class, label and colour, and the KML opens too.
TEST(ClassZones, GeoPackageAreasEqualTheRasterClassAreas) {
  geohaz::Raster r;
  r.nx = 60;
  r.ny = 40;
  r.geotransform = {500000.0, 5.0, 0.0, 5200000.0, 0.0, -5.0};
  r.crs_wkt = geohaz::crs_to_wkt("EPSG:32632");
  r.nodata = -9999.0;
  r.data.assign(static_cast<std::size_t>(r.nx) * r.ny, 0.0);
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) {
      double v = 0.0;
      if ((col < 10 && row < 30) || (row >= 20 && row < 30 && col < 25)) v = 3.0;  // L shape
      if (col >= 30 && col < 50 && row >= 5 && row < 25 && !(col >= 38 && col < 42 && row >= 12 && row < 16))
        v = 2.0;  // block with a hole
      if ((col >= 52 && row >= 30) || (col >= 12 && col < 16 && row >= 2 && row < 6)) v = 1.0;
      if (row == 39 && col < 5) v = -9999.0;
      r.at(col, row) = v;
    }
  double expected[4] = {0, 0, 0, 0};
  for (double v : r.data)
    if (v >= 1.0 && v <= 3.0) expected[static_cast<int>(v)] += 25.0;
  const fs::path dir = fs::temp_directory_path() / ("geohaz_zones_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::vector<geohaz::StyleClass> legend = {
      {1.0, "low", {255, 221, 51}}, {2.0, "medium", {245, 130, 32}}, {3.0, "strong", {200, 30, 45}}};
  geohaz::write_class_zones(dir / "zones.gpkg", dir / "zones.kml", r, "intensity", legend);
  EXPECT_FALSE(fs::exists(dir / "zones.gpkg.partial"));
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open((dir / "zones.gpkg").string().c_str(), GDAL_OF_VECTOR));
  ASSERT_TRUE(ds);
  OGRLayer* lyr = ds->GetLayerByName("intensity");
  ASSERT_NE(lyr, nullptr);
  double area[4] = {0, 0, 0, 0};
  int features = 0;
  for (auto& f : *lyr) {
    ++features;
    const int k = f->GetFieldAsInteger("class");
    ASSERT_GE(k, 1);
    ASSERT_LE(k, 3);
    area[k] += f->GetGeometryRef()->toPolygon()->get_Area();
    EXPECT_STREQ(f->GetFieldAsString("label"), legend[k - 1].label.c_str());
    EXPECT_EQ(std::string(f->GetFieldAsString("colour")).size(), 7u);
  }
  EXPECT_EQ(features, 4);  // L, block (its hole inside it), two low blocks
  for (int k = 1; k <= 3; ++k) EXPECT_NEAR(area[k], expected[k], 1e-6) << "class " << k;
  EXPECT_TRUE(lyr->GetSpatialRef() && lyr->GetSpatialRef()->GetAuthorityCode(nullptr) &&
              std::string(lyr->GetSpatialRef()->GetAuthorityCode(nullptr)) == "32632");
  std::unique_ptr<GDALDataset> kml(GDALDataset::Open((dir / "zones.kml").string().c_str(), GDAL_OF_VECTOR));
  ASSERT_TRUE(kml);
  EXPECT_EQ(kml->GetLayer(0)->GetFeatureCount(), features);
  fs::remove_all(dir);
}

// Issue #33: styles an engineer reads. Ramp labels rounded to 3 digits ("1.58 m", not
// "1.58471 m"); a classed style at 0.5/1/2 m with the maps' class colours; the intensity raster as
// Byte with a colour table and a raster attribute table.
TEST(QgisStyle, LabelsRoundedClassedRampsAndAByteClassRaster) {
  const fs::path ramp = dir() / "depth_ramp.qml", classed = dir() / "depth.qml";
  geohaz::write_qgis_ramp_style(ramp, geohaz::ColourRamp::Viridis, 0.0, 1.58471, "m", 0.0);
  EXPECT_NE(slurp(ramp).find("label=\"1.58 m\""), std::string::npos);
  EXPECT_EQ(slurp(ramp).find("1.58471 m"), std::string::npos);
  geohaz::write_qgis_classed_style(classed, geohaz::ColourRamp::Viridis, {0.5, 1.0, 2.0}, "m", 0.0);
  {
    XmlTree x(slurp(classed));
    ASSERT_NE(x.root, nullptr);
    const CPLXMLNode* shader = CPLGetXMLNode(x.root, "=qgis.pipe.rasterrenderer.rastershader.colorrampshader");
    ASSERT_NE(shader, nullptr);
    EXPECT_STREQ(CPLGetXMLValue(shader, "colorRampType", ""), "DISCRETE");
    std::vector<std::string> values, labels, colours;
    for (const CPLXMLNode* n = shader->psChild; n; n = n->psNext)
      if (n->eType == CXT_Element && std::string(n->pszValue) == "item") {
        values.emplace_back(CPLGetXMLValue(n, "value", ""));
        labels.emplace_back(CPLGetXMLValue(n, "label", ""));
        colours.emplace_back(CPLGetXMLValue(n, "color", ""));
      }
    ASSERT_EQ(values.size(), 4u);
    EXPECT_EQ(values[0], "0.5");
    EXPECT_EQ(values[3], "inf");
    EXPECT_EQ(labels[0], "< 0.5 m");
    EXPECT_EQ(labels[1], "0.5\u20131 m");
    EXPECT_EQ(labels[3], "\u2265 2 m");
    const auto c = geohaz::class_colour(geohaz::ColourRamp::Viridis, 3, 4);  // the map's top class
    char hex[8];
    std::snprintf(hex, sizeof hex, "#%02x%02x%02x", c[0], c[1], c[2]);
    EXPECT_EQ(colours[3], hex);
  }
  geohaz::Raster r;
  r.nx = 4;
  r.ny = 2;
  r.geotransform = {500000.0, 5.0, 0.0, 5200000.0, 0.0, -5.0};
  r.crs_wkt = geohaz::crs_to_wkt("EPSG:32632");
  r.nodata = -9999.0;
  r.description = "intensity class";
  r.unit = "1";
  r.data = {0, 1, 2, 3, -9999, 3, 2, 0};
  const std::vector<geohaz::StyleClass> legend = {
      {1.0, "low", {255, 221, 51}}, {2.0, "medium", {245, 130, 32}}, {3.0, "strong", {200, 30, 45}}};
  const fs::path tif = dir() / "intensity.tif";
  geohaz::write_class_geotiff(tif, r, legend);
  EXPECT_FALSE(fs::exists(dir() / "intensity.tif.partial"));
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(tif.string().c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(ds);
  GDALRasterBand* b = ds->GetRasterBand(1);
  EXPECT_EQ(b->GetRasterDataType(), GDT_Byte);
  int has = 0;
  EXPECT_EQ(b->GetNoDataValue(&has), 255.0);
  EXPECT_TRUE(has);
  std::uint8_t v[8];
  ASSERT_EQ(b->RasterIO(GF_Read, 0, 0, 4, 2, v, 4, 2, GDT_Byte, 0, 0, nullptr), CE_None);
  const std::uint8_t want[8] = {0, 1, 2, 3, 255, 3, 2, 0};
  for (int k = 0; k < 8; ++k) EXPECT_EQ(v[k], want[k]) << k;
  const GDALColorTable* ct = b->GetColorTable();
  ASSERT_NE(ct, nullptr);
  EXPECT_EQ(ct->GetColorEntry(3)->c1, 200);
  EXPECT_EQ(ct->GetColorEntry(3)->c4, 255);
  // Not reached: white (a TIFF colour map holds no alpha; intensity.qml leaves 0 undrawn).
  EXPECT_EQ(ct->GetColorEntry(0)->c1, 255);
  EXPECT_EQ(ct->GetColorEntry(0)->c2, 255);
  const GDALRasterAttributeTable* rat = b->GetDefaultRAT();
  ASSERT_NE(rat, nullptr);
  ASSERT_EQ(rat->GetRowCount(), 3);
  EXPECT_EQ(rat->GetValueAsInt(2, 0), 3);
  EXPECT_STREQ(rat->GetValueAsString(2, 1), "strong");
}
