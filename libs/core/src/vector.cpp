/// \file vector.cpp
/// Polygons and lines from OGR data sources (Shapefile, GeoJSON, GeoPackage, ...), and raster cells
/// written as polygons, see raster.hpp.

#include <cpl_string.h>
#include <gdal_alg.h>
#include <gdal_priv.h>
#include <gdal_utils.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <vector>

#include "gdal_common.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"

namespace geohaz {

namespace {

/// Even-odd crossing test against one ring (closed or not).
bool ring_contains(const std::vector<Vec2>& ring, const Vec2& p) noexcept {
  bool inside = false;
  const std::size_t n = ring.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2& a = ring[i];
    const Vec2& b = ring[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x_cross = a.x() + (p.y() - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
      if (p.x() < x_cross) inside = !inside;
    }
  }
  return inside;
}

/// Ring vertices without the repeated closing vertex.
std::vector<Vec2> ring_points(const OGRLinearRing* ring) {
  std::vector<Vec2> pts;
  if (!ring) return pts;
  const int n = ring->getNumPoints();
  pts.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) pts.emplace_back(ring->getX(i), ring->getY(i));
  if (pts.size() > 1 && pts.front() == pts.back()) pts.pop_back();
  return pts;
}

void add_polygon(const OGRPolygon* poly, double attribute, std::vector<Polygon>& out) {
  if (!poly || poly->IsEmpty()) return;
  Polygon p;
  p.outer = ring_points(poly->getExteriorRing());
  if (p.outer.size() < 3) return;
  for (int k = 0; k < poly->getNumInteriorRings(); ++k) {
    auto hole = ring_points(poly->getInteriorRing(k));
    if (hole.size() >= 3) p.holes.push_back(std::move(hole));
  }
  p.attribute = attribute;
  out.push_back(std::move(p));
}

}  // namespace

bool Polygon::contains(const Vec2& p) const noexcept {
  if (outer.size() < 3 || !ring_contains(outer, p)) return false;
  for (const auto& h : holes)
    if (h.size() >= 3 && ring_contains(h, p)) return false;
  return true;
}

namespace {

/// The first layer of an OGR data source, the index of a numeric attribute, and the transformation
/// to a target CRS (null when the layer is already in it), shared by the polygon and line readers.
struct VectorLayer {
  std::unique_ptr<GDALDataset> ds;
  OGRLayer* layer = nullptr;
  int field = -1;
  std::unique_ptr<OGRCoordinateTransformation> ct;

  VectorLayer(const std::string& file, const std::string& attribute, const std::string& target_wkt, const char* what) {
    check_input_file(file, file, "");
    ds.reset(GDALDataset::Open(file.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
    if (!ds) throw InputError("cannot read as a vector data source" + detail::gdal_last_error(), file);
    if (ds->GetLayerCount() < 1) throw InputError("the data source has no layer", file);
    layer = ds->GetLayer(0);
    if (!layer) throw InputError("cannot open the first layer" + detail::gdal_last_error(), file);
    if (!attribute.empty()) {
      OGRFeatureDefn* defn = layer->GetLayerDefn();
      field = defn->GetFieldIndex(attribute.c_str());
      if (field < 0) {
        std::string fields;
        for (int i = 0; i < defn->GetFieldCount(); ++i)
          fields += (i ? ", " : "") + std::string(defn->GetFieldDefn(i)->GetNameRef());
        throw InputError("no attribute '" + attribute + "' in layer '" + layer->GetName() +
                             "'; available fields: " + (fields.empty() ? "(none)" : fields),
                         file, "attribute", attribute);
      }
      const OGRFieldType type = defn->GetFieldDefn(field)->GetType();
      if (type != OFTInteger && type != OFTInteger64 && type != OFTReal)
        throw InputError("attribute '" + attribute + "' is not numeric (" + OGRFieldDefn::GetFieldTypeName(type) + ")",
                         file, "attribute", attribute);
    }
    // Reprojection to the target CRS when the layer's differs.
    const OGRSpatialReference* layer_srs = layer->GetSpatialRef();
    OGRSpatialReference target;
    if (target_wkt.empty()) return;
    if (!detail::parse_srs(target_wkt, target))
      throw InputError("the target CRS cannot be interpreted", file, "", target_wkt);
    if (!layer_srs || layer_srs->IsEmpty()) {
      std::cerr << "warning: " << file << ": the " << what << " have no CRS; taken to be in the target CRS\n";
      return;
    }
    const char* options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES",
                             "CRITERION=EQUIVALENT_EXCEPT_AXIS_ORDER_GEOGCRS", nullptr};
    if (layer_srs->IsSame(&target, options)) return;
    OGRSpatialReference source(*layer_srs);
    source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    ct.reset(OGRCreateCoordinateTransformation(&source, &target));
    if (!ct)
      throw InputError(std::string("cannot transform the ") + what + " to the target CRS" + detail::gdal_last_error(),
                       file);
  }

  double value(const OGRFeature& f) const {
    return (field >= 0 && f.IsFieldSetAndNotNull(field)) ? f.GetFieldAsDouble(field)
                                                         : std::numeric_limits<double>::quiet_NaN();
  }
};

void add_line(const OGRLineString* line, double attribute, std::int64_t feature, std::vector<Polyline>& out) {
  if (!line || line->getNumPoints() < 2) return;
  Polyline p;
  p.feature = feature;
  for (int i = 0; i < line->getNumPoints(); ++i) p.vertices.emplace_back(line->getX(i), line->getY(i));
  p.attribute = attribute;
  out.push_back(std::move(p));
}

}  // namespace

std::vector<std::string> vector_field_names(const std::filesystem::path& path) {
  detail::ensure_gdal_registered();
  const std::string file = path.string();
  detail::QuietGdalErrors quiet;
  VectorLayer v(file, "", "", "features");
  std::vector<std::string> names;
  const OGRFeatureDefn* defn = v.layer->GetLayerDefn();
  for (int i = 0; i < defn->GetFieldCount(); ++i) names.emplace_back(defn->GetFieldDefn(i)->GetNameRef());
  return names;
}

std::vector<Polygon> read_polygons(const std::filesystem::path& path, const std::string& attribute,
                                   const std::string& target_wkt) {
  detail::ensure_gdal_registered();
  const std::string file = path.string();
  detail::QuietGdalErrors quiet;
  VectorLayer v(file, attribute, target_wkt, "polygons");
  std::vector<Polygon> out;
  v.layer->ResetReading();
  for (auto& feature : *v.layer) {
    const OGRGeometry* g0 = feature->GetGeometryRef();
    if (!g0) continue;
    const double value = v.value(*feature);
    std::unique_ptr<OGRGeometry> g(g0->clone());
    const auto type = wkbFlatten(g->getGeometryType());
    if (type != wkbPolygon && type != wkbMultiPolygon) {
      // Curved polygons and the like: linearise; anything else (points, lines) is not a polygon.
      if (type == wkbCurvePolygon || type == wkbMultiSurface) {
        g.reset(g->getLinearGeometry());
        if (!g) continue;
      } else {
        continue;
      }
    }
    if (v.ct && g->transform(v.ct.get()) != OGRERR_NONE)
      throw InputError("polygon " + std::to_string(feature->GetFID()) + " cannot be transformed to the target CRS" +
                           detail::gdal_last_error(),
                       file);
    const auto flat = wkbFlatten(g->getGeometryType());
    if (flat == wkbPolygon) {
      add_polygon(g->toPolygon(), value, out);
    } else if (flat == wkbMultiPolygon) {
      for (const OGRPolygon* part : *g->toMultiPolygon()) add_polygon(part, value, out);
    }
  }
  if (out.empty()) throw InputError("no polygon in the first layer ('" + std::string(v.layer->GetName()) + "')", file);
  return out;
}

std::vector<Polyline> read_lines(const std::filesystem::path& path, const std::string& attribute,
                                 const std::string& target_wkt) {
  detail::ensure_gdal_registered();
  const std::string file = path.string();
  detail::QuietGdalErrors quiet;
  VectorLayer v(file, attribute, target_wkt, "lines");
  std::vector<Polyline> out;
  v.layer->ResetReading();
  for (auto& feature : *v.layer) {
    const OGRGeometry* g0 = feature->GetGeometryRef();
    if (!g0) continue;
    std::unique_ptr<OGRGeometry> g(g0->clone());
    auto type = wkbFlatten(g->getGeometryType());
    if (type == wkbCircularString || type == wkbCompoundCurve || type == wkbMultiCurve) {
      g.reset(g->getLinearGeometry());
      if (!g) continue;
      type = wkbFlatten(g->getGeometryType());
    }
    if (type != wkbLineString && type != wkbMultiLineString)
      throw InputError(
          "feature " + std::to_string(feature->GetFID()) + " is a " + OGRGeometryTypeToName(type) + ", not a line",
          file);
    if (v.ct && g->transform(v.ct.get()) != OGRERR_NONE)
      throw InputError("line " + std::to_string(feature->GetFID()) + " cannot be transformed to the target CRS" +
                           detail::gdal_last_error(),
                       file);
    const double value = v.value(*feature);
    if (type == wkbLineString) {
      add_line(g->toLineString(), value, feature->GetFID(), out);
    } else {
      for (const OGRLineString* part : *g->toMultiLineString()) add_line(part, value, feature->GetFID(), out);
    }
  }
  if (out.empty()) throw InputError("no line in the first layer ('" + std::string(v.layer->GetName()) + "')", file);
  return out;
}

std::size_t write_raster_polygons(const std::filesystem::path& path, const Raster& values, const std::string& attribute,
                                  const std::string& layer) {
  const std::string file = path.string();
  std::string ext = path.extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  const char* driver_name = ext == ".gpkg" ? "GPKG" : ext == ".geojson" ? "GeoJSON" : nullptr;
  if (!driver_name) throw InputError("polygons are written as GeoPackage (.gpkg) or GeoJSON (.geojson)", file, "", ext);
  if (values.nx <= 0 || values.ny <= 0 ||
      values.data.size() != static_cast<std::size_t>(values.nx) * static_cast<std::size_t>(values.ny))
    throw InputError("cannot polygonise an empty or inconsistent raster", file);
  detail::ensure_gdal_registered();
  OGRSpatialReference srs;
  if (!values.crs_wkt.empty() && !detail::parse_srs(values.crs_wkt, srs))
    throw InputError("the raster's CRS cannot be interpreted", file, "", values.crs_wkt);
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  detail::QuietGdalErrors quiet;

  // The values and the mask of the cells to write, as in-memory bands.
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* drv = GetGDALDriverManager()->GetDriverByName(driver_name);
  if (!mem || !drv) throw std::runtime_error(std::string("GDAL has no MEM or ") + driver_name + " driver");
  std::unique_ptr<GDALDataset> src(mem->Create("", values.nx, values.ny, 2, GDT_Float32, nullptr));
  if (!src) throw std::runtime_error("GDAL cannot create an in-memory raster" + detail::gdal_last_error());
  std::array<double, 6> gt = values.geotransform;
  src->SetGeoTransform(gt.data());
  std::vector<float> v(values.data.size()), mask(values.data.size());
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double x = values.data[k];
    const bool in = !values.is_nodata(x) && std::isfinite(x) && x > 0.0;
    v[k] = in ? static_cast<float>(x) : 0.0f;
    mask[k] = in ? 1.0f : 0.0f;
  }
  if (src->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, values.nx, values.ny, v.data(), values.nx, values.ny, GDT_Float32,
                                      0, 0, nullptr) != CE_None ||
      src->GetRasterBand(2)->RasterIO(GF_Write, 0, 0, values.nx, values.ny, mask.data(), values.nx, values.ny,
                                      GDT_Float32, 0, 0, nullptr) != CE_None)
    throw std::runtime_error("GDAL cannot fill an in-memory raster" + detail::gdal_last_error());

  // From here on a failure is the file system's: IoError, and no file is left.
  const std::string tmp = file + ".partial";
  std::error_code ec;
  std::filesystem::remove(tmp, ec);
  const auto fail = [&](const std::string& what) {
    const std::string msg = detail::gdal_last_error();
    std::error_code e2;
    std::filesystem::remove(tmp, e2);
    return IoError(what + msg, file);
  };
  std::size_t count = 0;
  {
    std::unique_ptr<GDALDataset> ds(drv->Create(tmp.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!ds) throw fail("cannot create the polygon file");
    OGRLayer* lyr = ds->CreateLayer(layer.c_str(), values.crs_wkt.empty() ? nullptr : &srs, wkbPolygon, nullptr);
    if (!lyr) throw fail("cannot create the layer '" + layer + "'");
    OGRFieldDefn field(attribute.c_str(), OFTReal);
    if (lyr->CreateField(&field) != OGRERR_NONE) throw fail("cannot create the field '" + attribute + "'");
    const bool transaction = ds->TestCapability(ODsCTransactions) && ds->StartTransaction() == OGRERR_NONE;
    const CPLErr err = GDALFPolygonize(src->GetRasterBand(1), src->GetRasterBand(2), OGRLayer::ToHandle(lyr), 0,
                                       nullptr, nullptr, nullptr);
    if (err != CE_None) throw fail("polygonising the cells failed");
    if (transaction && ds->CommitTransaction() != OGRERR_NONE) throw fail("cannot write the polygons");
    count = static_cast<std::size_t>(lyr->GetFeatureCount());
    CPLErrorReset();
  }  // closes the file (writes the rest)
  if (CPLGetLastErrorType() == CE_Failure || CPLGetLastErrorType() == CE_Fatal)
    throw fail("writing the polygons failed");
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw IoError("cannot move the polygon file into place: " + ec.message(), file);
  }
  return count;
}

}  // namespace geohaz

// ---------------------------------------------------------------------------------------------
// Class zones as polygons

namespace geohaz {

void write_class_zones(const std::filesystem::path& gpkg, const std::filesystem::path& kml, const Raster& classes,
                       const std::string& layer, const std::vector<StyleClass>& legend) {
  detail::ensure_gdal_registered();
  detail::QuietGdalErrors quiet;
  const std::string file = gpkg.string();
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* gpkg_driver = GetGDALDriverManager()->GetDriverByName("GPKG");
  GDALDriver* kml_driver = GetGDALDriverManager()->GetDriverByName("KML");
  if (!mem || !gpkg_driver) throw std::runtime_error("GDAL lacks the MEM or GPKG driver");
  // The class raster as Int32, nodata and classes ≤ 0 masked out.
  std::unique_ptr<GDALDataset> src(mem->Create("", classes.nx, classes.ny, 2, GDT_Int32, nullptr));
  if (!src) throw std::runtime_error("cannot create an in-memory raster" + detail::gdal_last_error());
  std::array<double, 6> gt = classes.geotransform;
  src->SetGeoTransform(gt.data());
  std::vector<std::int32_t> value(classes.data.size()), mask(classes.data.size());
  for (std::size_t k = 0; k < value.size(); ++k) {
    const double v = classes.data[k];
    const bool on = std::isfinite(v) && !classes.is_nodata(v) && v > 0.0;
    value[k] = on ? static_cast<std::int32_t>(std::lround(v)) : 0;
    mask[k] = on ? 1 : 0;
  }
  if (src->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, classes.nx, classes.ny, value.data(), classes.nx, classes.ny,
                                      GDT_Int32, 0, 0, nullptr) != CE_None ||
      src->GetRasterBand(2)->RasterIO(GF_Write, 0, 0, classes.nx, classes.ny, mask.data(), classes.nx, classes.ny,
                                      GDT_Int32, 0, 0, nullptr) != CE_None)
    throw std::runtime_error("cannot fill the in-memory raster" + detail::gdal_last_error());

  const std::string tmp = file + ".partial";
  const std::string ktmp = kml.empty() ? std::string() : kml.string() + ".partial";
  std::error_code ec;
  std::filesystem::remove(tmp, ec);
  // A failure (a full disk) leaves no half-written file: the datasets are closed while the exception
  // unwinds out of the block, then their temporary files are removed and the error goes on.
  try {
    std::unique_ptr<GDALDataset> out(gpkg_driver->Create(tmp.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!out) throw IoError("cannot create the GeoPackage" + detail::gdal_last_error(), file);
    OGRSpatialReference srs;
    const bool has_srs = !classes.crs_wkt.empty() && detail::parse_srs(classes.crs_wkt, srs);
    if (has_srs) srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    OGRLayer* lyr = out->CreateLayer(layer.c_str(), has_srs ? &srs : nullptr, wkbPolygon, nullptr);
    if (!lyr) throw IoError("cannot create the layer " + layer + detail::gdal_last_error(), file);
    OGRFieldDefn cls("class", OFTInteger);
    OGRFieldDefn label("label", OFTString);
    OGRFieldDefn colour("colour", OFTString);
    if (lyr->CreateField(&cls) != OGRERR_NONE || lyr->CreateField(&label) != OGRERR_NONE ||
        lyr->CreateField(&colour) != OGRERR_NONE)
      throw IoError("cannot create the layer's fields" + detail::gdal_last_error(), file);
    out->StartTransaction();
    // 4-connected polygons of equal class (GDALPolygonize), written into field 0 ("class").
    if (GDALPolygonize(src->GetRasterBand(1), src->GetRasterBand(2), lyr, 0, nullptr, nullptr, nullptr) != CE_None)
      throw IoError("cannot polygonise the classes" + detail::gdal_last_error(), file);
    // Labels and colours (the OGR style string lets QGIS and Google Earth draw each class).
    lyr->ResetReading();
    std::vector<std::unique_ptr<OGRFeature>> feats;
    while (OGRFeature* f = lyr->GetNextFeature()) feats.emplace_back(f);
    for (auto& f : feats) {
      const int k = f->GetFieldAsInteger(0);
      for (const auto& c : legend)
        if (std::lround(c.value) == k) {
          char hex[8];
          std::snprintf(hex, sizeof hex, "#%02x%02x%02x", c.colour[0], c.colour[1], c.colour[2]);
          f->SetField(1, c.label.c_str());
          f->SetField(2, hex);
          f->SetStyleString((std::string("BRUSH(fc:") + hex + "b0);PEN(c:" + hex + ",w:1px)").c_str());
        }
      if (lyr->SetFeature(f.get()) != OGRERR_NONE)
        throw IoError("cannot label the zones" + detail::gdal_last_error(), file);
    }
    if (out->CommitTransaction() != OGRERR_NONE)
      throw IoError("cannot write the GeoPackage" + detail::gdal_last_error(), file);
    // KML (WGS 84, as Google Earth and phones read it) as a copy of the layer.
    if (!kml.empty() && kml_driver) {
      std::filesystem::remove(ktmp, ec);
      CPLStringList args;
      for (const char* a : {"-f", "KML", "-t_srs", "EPSG:4326", "-dsco", "NameField=label"}) args.AddString(a);
      std::unique_ptr<GDALVectorTranslateOptions, void (*)(GDALVectorTranslateOptions*)> opts(
          GDALVectorTranslateOptionsNew(args.List(), nullptr), GDALVectorTranslateOptionsFree);
      GDALDatasetH in = GDALDataset::ToHandle(out.get());
      int usage = 0;
      GDALDatasetH k = GDALVectorTranslate(ktmp.c_str(), nullptr, 1, &in, opts.get(), &usage);
      if (!k) throw IoError("cannot write the KML" + detail::gdal_last_error(), kml.string());
      GDALClose(k);
      std::filesystem::rename(ktmp, kml, ec);
      if (ec) throw IoError("cannot move the KML into place: " + ec.message(), kml.string());
    }
  } catch (...) {
    std::error_code e2;
    std::filesystem::remove(tmp, e2);
    if (!ktmp.empty()) std::filesystem::remove(ktmp, e2);
    throw;
  }
  std::filesystem::rename(tmp, gpkg, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw IoError("cannot move the GeoPackage into place: " + ec.message(), file);
  }
}

}  // namespace geohaz
