/// \file vector.cpp
/// Polygons from OGR data sources (Shapefile, GeoJSON, GeoPackage, ...), see raster.hpp.

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "gdal_common.hpp"

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

std::vector<Polygon> read_polygons(const std::filesystem::path& path, const std::string& attribute,
                                   const std::string& target_wkt) {
  detail::ensure_gdal_registered();
  const std::string file = path.string();
  detail::QuietGdalErrors quiet;

  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(file.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds) throw InputError("cannot read as a vector data source" + detail::gdal_last_error(), file);
  if (ds->GetLayerCount() < 1) throw InputError("the data source has no layer", file);
  OGRLayer* layer = ds->GetLayer(0);
  if (!layer) throw InputError("cannot open the first layer" + detail::gdal_last_error(), file);

  int field = -1;
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
  std::unique_ptr<OGRCoordinateTransformation> ct;
  const OGRSpatialReference* layer_srs = layer->GetSpatialRef();
  OGRSpatialReference target;
  if (!target_wkt.empty()) {
    if (!detail::parse_srs(target_wkt, target))
      throw InputError("the target CRS cannot be interpreted", file, "", target_wkt);
    if (!layer_srs || layer_srs->IsEmpty()) {
      std::cerr << "warning: " << file << ": the polygons have no CRS; taken to be in the target CRS\n";
    } else {
      const char* options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES",
                               "CRITERION=EQUIVALENT_EXCEPT_AXIS_ORDER_GEOGCRS", nullptr};
      if (!layer_srs->IsSame(&target, options)) {
        OGRSpatialReference source(*layer_srs);
        source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
        target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
        ct.reset(OGRCreateCoordinateTransformation(&source, &target));
        if (!ct) throw InputError("cannot transform the polygons to the target CRS" + detail::gdal_last_error(), file);
      }
    }
  }

  std::vector<Polygon> out;
  layer->ResetReading();
  for (auto& feature : *layer) {
    const OGRGeometry* g0 = feature->GetGeometryRef();
    if (!g0) continue;
    const double value = (field >= 0 && feature->IsFieldSetAndNotNull(field))
                             ? feature->GetFieldAsDouble(field)
                             : std::numeric_limits<double>::quiet_NaN();
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
    if (ct && g->transform(ct.get()) != OGRERR_NONE)
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
  if (out.empty()) throw InputError("no polygon in the first layer ('" + std::string(layer->GetName()) + "')", file);
  return out;
}

}  // namespace geohaz
