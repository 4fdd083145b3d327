// GIS-ready outputs (docs/runout.md "Outputs"): a GeoTIFF carries its band description, unit and
// nodata, is tiled with internal overviews (the Cloud-Optimized layout), and its QGIS style files
// parse as XML with the expected ramp or classes. Read back with GDAL itself.
#include <cpl_minixml.h>
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"

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
