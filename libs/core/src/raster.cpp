/// \file raster.cpp
/// Terrain rasters through GDAL (see raster.hpp): reading, GeoTIFF writing, CRS helpers and the
/// bilinear Terrain surface. GDAL is confined to this file, vector.cpp and png.cpp.

#include "geohaz/core/raster.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <gdal_rat.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <mutex>

#include "gdal_common.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster_extra.hpp"
#include "geohaz/core/resources.hpp"

namespace geohaz {

namespace detail {

void ensure_gdal_registered() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

std::string gdal_last_error() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg && *msg) ? std::string(" (GDAL: ") + msg + ")" : std::string();
}

bool parse_srs(const std::string& text, OGRSpatialReference& srs) {
  if (text.empty()) return false;
  QuietGdalErrors quiet;
  return srs.SetFromUserInput(text.c_str()) == OGRERR_NONE;
}

}  // namespace detail

using detail::ensure_gdal_registered;
using detail::gdal_last_error;
using detail::QuietGdalErrors;

// ---------------------------------------------------------------------------------------------
// Raster

Raster Raster::like(double fill, std::optional<double> nodata_value) const {
  Raster r;
  r.nx = nx;
  r.ny = ny;
  r.geotransform = geotransform;
  r.crs_wkt = crs_wkt;
  r.nodata = nodata_value;
  r.data.assign(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), fill);
  return r;
}

Vec2 Raster::cell_centre(int col, int row) const noexcept {
  return {geotransform[0] + (col + 0.5) * geotransform[1], geotransform[3] + (row + 0.5) * geotransform[5]};
}

Vec2 Raster::to_pixel(const Vec2& p) const noexcept {
  return {(p.x() - geotransform[0]) / geotransform[1] - 0.5, (p.y() - geotransform[3]) / geotransform[5] - 0.5};
}

bool Raster::is_nodata(double v) const noexcept {
  // NaN is never data, whatever the declared nodata value.
  if (std::isnan(v)) return true;
  return nodata.has_value() && v == *nodata;
}

std::array<Vec2, 2> Raster::extent() const noexcept {
  const double x0 = geotransform[0], x1 = geotransform[0] + nx * geotransform[1];
  const double y0 = geotransform[3], y1 = geotransform[3] + ny * geotransform[5];
  return {Vec2(std::min(x0, x1), std::min(y0, y1)), Vec2(std::max(x0, x1), std::max(y0, y1))};
}

// ---------------------------------------------------------------------------------------------
// CRS helpers

bool crs_is_geographic(const std::string& wkt) {
  OGRSpatialReference srs;
  if (!detail::parse_srs(wkt, srs)) return false;
  return srs.IsGeographic() && !srs.IsProjected();
}

bool crs_equal(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  if (a == b) return true;
  OGRSpatialReference sa, sb;
  if (!detail::parse_srs(a, sa) || !detail::parse_srs(b, sb)) return false;
  const char* options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES", "CRITERION=EQUIVALENT_EXCEPT_AXIS_ORDER_GEOGCRS",
                           nullptr};
  return sa.IsSame(&sb, options);
}

std::string crs_to_wkt(const std::string& definition) {
  if (definition.empty()) return {};
  ensure_gdal_registered();
  OGRSpatialReference srs;
  QuietGdalErrors quiet;
  if (srs.SetFromUserInput(definition.c_str()) != OGRERR_NONE)
    throw InputError(
        "not a coordinate reference system GDAL understands (use e.g. EPSG:32632 or WKT)" + gdal_last_error(), "", "",
        definition);
  char* out = nullptr;
  const char* options[] = {"FORMAT=WKT2_2018", nullptr};
  srs.exportToWkt(&out, options);
  std::string wkt = out ? out : "";
  CPLFree(out);
  return wkt;
}

std::vector<Vec2> transform_points(const std::vector<Vec2>& pts, const std::string& from_wkt,
                                   const std::string& to_wkt) {
  if (from_wkt.empty() || to_wkt.empty() || crs_equal(from_wkt, to_wkt)) return pts;
  ensure_gdal_registered();
  OGRSpatialReference from, to;
  if (!detail::parse_srs(from_wkt, from)) throw InputError("cannot interpret the source CRS", "", "", from_wkt);
  if (!detail::parse_srs(to_wkt, to)) throw InputError("cannot interpret the target CRS", "", "", to_wkt);
  from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  to.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  QuietGdalErrors quiet;
  std::unique_ptr<OGRCoordinateTransformation> ct(OGRCreateCoordinateTransformation(&from, &to));
  if (!ct) throw InputError("no coordinate transformation between the two CRS" + gdal_last_error());
  std::vector<double> x(pts.size()), y(pts.size());
  std::vector<int> ok(pts.size(), 0);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    x[i] = pts[i].x();
    y[i] = pts[i].y();
  }
  ct->Transform(static_cast<int>(pts.size()), x.data(), y.data(), nullptr, ok.data());
  std::vector<Vec2> out(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!ok[i] || !std::isfinite(x[i]) || !std::isfinite(y[i]))
      throw InputError("point (" + std::to_string(pts[i].x()) + ", " + std::to_string(pts[i].y()) +
                       ") cannot be transformed to the target CRS" + gdal_last_error());
    out[i] = Vec2(x[i], y[i]);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Reading and writing

Raster read_raster(const std::filesystem::path& path, CrsPolicy policy) {
  ensure_gdal_registered();
  const std::string file = path.string();
  check_input_file(file, file, "");
  QuietGdalErrors quiet;
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds) throw InputError("cannot read as a raster" + gdal_last_error(), file);
  if (ds->GetRasterCount() < 1) throw InputError("the dataset has no raster band", file);

  Raster r;
  r.nx = ds->GetRasterXSize();
  r.ny = ds->GetRasterYSize();
  if (r.nx <= 0 || r.ny <= 0) throw InputError("the raster is empty (0 columns or rows)", file);

  std::array<double, 6> gt{};
  const bool has_gt = ds->GetGeoTransform(gt.data()) == CE_None;
  if (!has_gt) {
    if (policy == CrsPolicy::RequireProjected)
      throw InputError("the raster has no georeferencing (geotransform); a georeferenced grid is required", file);
    gt = {0.0, 1.0, 0.0, 0.0, 0.0, -1.0};  // plain pixel grid, row 0 at the top
  }
  if (gt[2] != 0.0 || gt[4] != 0.0)
    throw InputError("rotated geotransform (rotation terms " + std::to_string(gt[2]) + ", " + std::to_string(gt[4]) +
                         ") is not supported; make it north-up with `gdalwarp in.tif out.tif`",
                     file);
  if (!(gt[1] > 0.0) || gt[5] == 0.0 || !std::isfinite(gt[5]))
    throw InputError("invalid cell size (dx = " + std::to_string(gt[1]) + ", dy = " + std::to_string(gt[5]) + ")",
                     file);

  if (const OGRSpatialReference* srs = ds->GetSpatialRef(); srs && !srs->IsEmpty()) {
    char* wkt = nullptr;
    const char* options[] = {"FORMAT=WKT2_2018", nullptr};
    srs->exportToWkt(&wkt, options);
    r.crs_wkt = wkt ? wkt : "";
    CPLFree(wkt);
    if (policy == CrsPolicy::RequireProjected && srs->IsGeographic() && !srs->IsProjected()) {
      // Suggest the UTM zone of the raster's centre (assuming degrees of longitude/latitude).
      const double lon = gt[0] + 0.5 * r.nx * gt[1], lat = gt[3] + 0.5 * r.ny * gt[5];
      std::string epsg = "EPSG:32632";
      if (std::abs(lon) <= 180.0 && std::abs(lat) <= 84.0) {
        const int zone = std::clamp(static_cast<int>(std::floor((lon + 180.0) / 6.0)) + 1, 1, 60);
        epsg = "EPSG:" + std::to_string((lat >= 0.0 ? 32600 : 32700) + zone);
      }
      throw InputError(
          "the raster is in a geographic CRS (degrees), but simulations need a projected CRS in metres; "
          "reproject it first, e.g. `gdalwarp -t_srs " +
              epsg + " " + file + " projected.tif` (" + epsg +
              " is the UTM zone of the raster's centre; a local projected CRS works too)",
          file);
    }
  } else if (policy == CrsPolicy::RequireProjected) {
    std::cerr << "warning: " << file << ": the raster has no CRS; its coordinates are taken as metres\n";
  }

  GDALRasterBand* band = ds->GetRasterBand(1);
  int has_nodata = 0;
  const double nd = band->GetNoDataValue(&has_nodata);
  if (has_nodata) r.nodata = nd;
  if (const char* d = band->GetDescription()) r.description = d;
  for (const char* item : {"TIFFTAG_COPYRIGHT", "ATTRIBUTION", "COPYRIGHT", "LICENSE"})
    if (const char* a = ds->GetMetadataItem(item); a && *a && r.attribution.empty()) r.attribution = a;
  if (const char* u = band->GetUnitType()) r.unit = u;

  // The header alone may declare any size (a 1.8 MB sparse GeoTIFF can declare 10^10 cells): check
  // before allocating. Two copies of 8-byte values: the Raster and the model's own grid or Terrain.
  const double cells = static_cast<double>(r.nx) * static_cast<double>(r.ny);
  check_memory(2.0 * 8.0 * cells,
               std::to_string(r.nx) + " × " + std::to_string(r.ny) + " cells, two copies of 8 bytes each", file, "");
  r.data.resize(static_cast<std::size_t>(r.nx) * static_cast<std::size_t>(r.ny));
  if (band->RasterIO(GF_Read, 0, 0, r.nx, r.ny, r.data.data(), r.nx, r.ny, GDT_Float64, 0, 0, nullptr) != CE_None)
    throw InputError("cannot read band 1" + gdal_last_error(), file);

  if (gt[5] > 0.0) {
    // South-up grid (row 0 at the south edge): flip the rows so the Raster is north-up.
    for (int row = 0; row < r.ny / 2; ++row)
      std::swap_ranges(r.data.begin() + static_cast<std::ptrdiff_t>(row) * r.nx,
                       r.data.begin() + static_cast<std::ptrdiff_t>(row + 1) * r.nx,
                       r.data.begin() + static_cast<std::ptrdiff_t>(r.ny - 1 - row) * r.nx);
    gt[3] += r.ny * gt[5];
    gt[5] = -gt[5];
  }
  r.geotransform = gt;
  return r;
}

namespace {

/// Copy an in-memory raster into a Cloud-Optimized GeoTIFF at `path` (deflate, 256 × 256 tiles,
/// nearest-neighbour overviews) through "<path>.partial", renamed when complete; a PAM side-car
/// (.aux.xml, where GDAL keeps a raster attribute table) is renamed with it.
void copy_to_cog(GDALDataset* src, const std::filesystem::path& path) {
  const std::string file = path.string();
  // The COG driver does not depend on the extension, so "<name>.partial" (the project-wide
  // temporary name that remove_partial_files() knows) works.
  const std::string tmp = file + ".partial";
  GDALDriver* cog = GetGDALDriverManager()->GetDriverByName("COG");
  if (!cog) throw std::runtime_error("GDAL has no COG driver");
  // From here on a failure is the file system's (full disk, size limit, permission): IoError.
  const char* options[] = {"COMPRESS=DEFLATE", "BLOCKSIZE=256", "RESAMPLING=NEAREST", "OVERVIEWS=AUTO", nullptr};
  CPLErrorReset();
  bool ok = true;
  {
    std::unique_ptr<GDALDataset> ds(
        cog->CreateCopy(tmp.c_str(), src, FALSE, const_cast<char**>(options), nullptr, nullptr));
    if (!ds) {
      const std::string msg = gdal_last_error();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      std::filesystem::remove(tmp + ".aux.xml", ec);
      throw IoError("cannot write the GeoTIFF" + msg, file);
    }
    ok = CPLGetLastErrorType() != CE_Failure && CPLGetLastErrorType() != CE_Fatal;
  }  // closes the dataset (writes the rest)
  ok = ok && CPLGetLastErrorType() != CE_Failure && CPLGetLastErrorType() != CE_Fatal;
  std::error_code ec;
  if (!ok) {
    const std::string msg = gdal_last_error();
    std::filesystem::remove(tmp, ec);
    std::filesystem::remove(tmp + ".aux.xml", ec);
    throw IoError("writing the GeoTIFF failed" + msg, file);
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    std::filesystem::remove(tmp + ".aux.xml", ec);
    throw IoError("cannot move the GeoTIFF into place: " + ec.message(), file);
  }
  if (std::filesystem::exists(tmp + ".aux.xml", ec)) {
    std::filesystem::rename(tmp + ".aux.xml", file + ".aux.xml", ec);
    if (ec) throw IoError("cannot move the GeoTIFF's side-car into place: " + ec.message(), file + ".aux.xml");
  }
}

void check_writable(const Raster& r, const std::string& file, OGRSpatialReference& srs) {
  if (r.nx <= 0 || r.ny <= 0 || r.data.size() != static_cast<std::size_t>(r.nx) * static_cast<std::size_t>(r.ny))
    throw InputError("cannot write an empty or inconsistent raster (" + std::to_string(r.nx) + " x " +
                         std::to_string(r.ny) + ", " + std::to_string(r.data.size()) + " values)",
                     file);
  ensure_gdal_registered();
  if (!r.crs_wkt.empty() && !detail::parse_srs(r.crs_wkt, srs))
    throw InputError("the raster's CRS cannot be interpreted", file, "", r.crs_wkt);
}

}  // namespace

void write_geotiff(const std::filesystem::path& path, const Raster& r, bool float64) {
  const std::string file = path.string();
  OGRSpatialReference srs;
  check_writable(r, file, srs);
  QuietGdalErrors quiet;
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  if (!mem) throw std::runtime_error("GDAL has no MEM driver");
  // The raster is assembled in memory, then copied by the COG driver (tiles, overviews, layout).
  std::unique_ptr<GDALDataset> src(mem->Create("", r.nx, r.ny, 1, float64 ? GDT_Float64 : GDT_Float32, nullptr));
  if (!src) throw std::runtime_error("GDAL cannot create an in-memory raster" + gdal_last_error());
  std::array<double, 6> gt = r.geotransform;
  src->SetGeoTransform(gt.data());
  if (!r.crs_wkt.empty()) src->SetSpatialRef(&srs);
  GDALRasterBand* band = src->GetRasterBand(1);
  if (r.nodata) band->SetNoDataValue(*r.nodata);
  if (!r.description.empty()) band->SetDescription(r.description.c_str());
  if (!r.unit.empty()) band->SetUnitType(r.unit.c_str());
  if (band->RasterIO(GF_Write, 0, 0, r.nx, r.ny, const_cast<double*>(r.data.data()), r.nx, r.ny, GDT_Float64, 0, 0,
                     nullptr) != CE_None)
    throw std::runtime_error("GDAL cannot fill an in-memory raster" + gdal_last_error());
  copy_to_cog(src.get(), path);
}

void write_class_geotiff(const std::filesystem::path& path, const Raster& r, const std::vector<StyleClass>& legend) {
  const std::string file = path.string();
  OGRSpatialReference srs;
  check_writable(r, file, srs);
  QuietGdalErrors quiet;
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  if (!mem) throw std::runtime_error("GDAL has no MEM driver");
  std::unique_ptr<GDALDataset> src(mem->Create("", r.nx, r.ny, 1, GDT_Byte, nullptr));
  if (!src) throw std::runtime_error("GDAL cannot create an in-memory raster" + gdal_last_error());
  std::array<double, 6> gt = r.geotransform;
  src->SetGeoTransform(gt.data());
  if (!r.crs_wkt.empty()) src->SetSpatialRef(&srs);
  GDALRasterBand* band = src->GetRasterBand(1);
  constexpr std::uint8_t kNodata = 255;
  band->SetNoDataValue(kNodata);
  if (!r.description.empty()) band->SetDescription(r.description.c_str());
  if (!r.unit.empty()) band->SetUnitType(r.unit.c_str());
  std::vector<std::uint8_t> v(r.data.size());
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double x = r.data[k];
    v[k] =
        !std::isfinite(x) || r.is_nodata(x) ? kNodata : static_cast<std::uint8_t>(std::clamp(std::lround(x), 0L, 254L));
  }
  if (band->RasterIO(GF_Write, 0, 0, r.nx, r.ny, v.data(), r.nx, r.ny, GDT_Byte, 0, 0, nullptr) != CE_None)
    throw std::runtime_error("GDAL cannot fill an in-memory raster" + gdal_last_error());
  // Colour table: each class in its colour, everything else (0 = not reached, nodata) white.
  GDALColorTable ct;
  for (int k = 0; k < 256; ++k) {
    GDALColorEntry e{255, 255, 255, 0};
    for (const auto& c : legend)
      if (std::lround(c.value) == k) e = {c.colour[0], c.colour[1], c.colour[2], 255};
    ct.SetColorEntry(k, &e);
  }
  band->SetColorTable(&ct);
  band->SetColorInterpretation(GCI_PaletteIndex);
  // Raster attribute table: value, class label, colour.
  GDALDefaultRasterAttributeTable rat;
  rat.CreateColumn("value", GFT_Integer, GFU_MinMax);
  rat.CreateColumn("class", GFT_String, GFU_Name);
  rat.CreateColumn("red", GFT_Integer, GFU_Red);
  rat.CreateColumn("green", GFT_Integer, GFU_Green);
  rat.CreateColumn("blue", GFT_Integer, GFU_Blue);
  rat.SetRowCount(static_cast<int>(legend.size()));
  for (std::size_t k = 0; k < legend.size(); ++k) {
    const int row = static_cast<int>(k);
    rat.SetValue(row, 0, static_cast<int>(std::lround(legend[k].value)));
    rat.SetValue(row, 1, legend[k].label.c_str());
    for (int c = 0; c < 3; ++c) rat.SetValue(row, 2 + c, static_cast<int>(legend[k].colour[c]));
  }
  band->SetDefaultRAT(&rat);
  copy_to_cog(src.get(), path);
}

// ---------------------------------------------------------------------------------------------
// Terrain: bilinear surface through the cell centres. These functions are called per particle
// per step, so they do no allocation and no GDAL calls.

namespace {

/// The grid of a north-up raster (checked by the caller).
GridGeometry north_up_geometry(const Raster& r) {
  return {r.nx, r.ny, r.geotransform[0], r.geotransform[3], r.cell_size_x(), r.cell_size_y()};
}

/// The raster's values with nodata (the declared value or NaN) as NaN, for BilinearGrid.
std::vector<double> values_with_nan_nodata(Raster& r) {
  std::vector<double> z = std::move(r.data);
  for (double& v : z)
    if (r.is_nodata(v)) v = std::numeric_limits<double>::quiet_NaN();
  return z;
}

}  // namespace

Terrain::Terrain(Raster r) {
  if (r.nx < 2 || r.ny < 2)
    throw InputError("a terrain needs at least 2 x 2 cells (got " + std::to_string(r.nx) + " x " +
                     std::to_string(r.ny) + ")");
  if (r.data.size() != static_cast<std::size_t>(r.nx) * static_cast<std::size_t>(r.ny))
    throw InputError("terrain raster size does not match its data");
  if (!(r.geotransform[1] > 0.0) || !(r.geotransform[5] < 0.0) || r.geotransform[2] != 0.0 || r.geotransform[4] != 0.0)
    throw InputError("terrain raster must be north-up with dx > 0 and dy < 0");
  const GridGeometry g = north_up_geometry(r);
  grid_ = BilinearGrid(g, values_with_nan_nodata(r));
}

bool Terrain::valid(double x, double y) const noexcept {
  return grid_.valid(Vec2(x, y));
}

double Terrain::elevation(double x, double y) const noexcept {
  TerrainSample s;
  return grid_.sample(Vec2(x, y), s) ? s.z : std::numeric_limits<double>::quiet_NaN();
}

Vec2 Terrain::gradient(double x, double y) const noexcept {
  TerrainSample s;
  return grid_.sample(Vec2(x, y), s) ? s.gradient : Vec2::Constant(std::numeric_limits<double>::quiet_NaN());
}

Vec3 Terrain::normal(double x, double y) const noexcept {
  const Vec2 g = gradient(x, y);
  const Vec3 n(-g.x(), -g.y(), 1.0);
  return n / n.norm();
}

// ---------------------------------------------------------------------------------------------
// Profiles

std::vector<ProfilePoint> extract_profile(const Terrain& terrain, const std::vector<Vec2>& polyline, double spacing) {
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw InputError("profile spacing must be a positive number of metres", "", "spacing", std::to_string(spacing));
  if (polyline.size() < 2)
    throw InputError("a profile needs a polyline of at least 2 vertices (got " + std::to_string(polyline.size()) + ")");
  std::vector<ProfilePoint> out;
  double s0 = 0.0;
  auto add = [&](double s, const Vec2& p) {
    const double z = terrain.elevation(p.x(), p.y());
    if (!std::isfinite(z))
      throw InputError("the profile leaves the terrain data at (" + std::to_string(p.x()) + ", " +
                       std::to_string(p.y()) + "), s = " + std::to_string(s) + " m");
    out.push_back({s, p.x(), p.y(), z});
  };
  add(0.0, polyline.front());
  for (std::size_t k = 0; k + 1 < polyline.size(); ++k) {
    const Vec2 a = polyline[k], b = polyline[k + 1];
    const double len = (b - a).norm();
    // Samples every `spacing` from the segment start; the end vertex closes the segment (the last
    // interval of a segment is ≤ spacing). A sample closer than 1e-9·spacing to the vertex is the vertex.
    for (int m = 1;; ++m) {
      const double d = m * spacing;
      if (d >= len - 1e-9 * spacing) break;
      add(s0 + d, a + (b - a) * (d / len));
    }
    s0 += len;
    if (len > 0.0) add(s0, b);
  }
  return out;
}

}  // namespace geohaz
