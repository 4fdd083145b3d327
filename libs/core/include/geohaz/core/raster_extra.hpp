#pragma once
/// \file raster_extra.hpp
/// Small additions to raster.hpp (kept apart so raster.hpp stays the agreed contract).

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <string>

#include "geohaz/core/raster.hpp"

namespace geohaz {

/// The WKT of a CRS given in any form GDAL understands: WKT, "EPSG:32632", a PROJ string or
/// PROJJSON (for config keys such as `crs = "EPSG:32632"`). InputError naming `definition` when
/// GDAL cannot interpret it. An empty definition gives "".
std::string crs_to_wkt(const std::string& definition);

/// Read a picture (PNG, or any GDAL raster with 1, 3 or 4 bands of bytes) into an RGB Image;
/// one band is read as grey. Used to check the quick-look and plot outputs. InputError naming the
/// file when it cannot be read.
Image read_image(const std::filesystem::path& path);

/// Elevation and gradient of a Terrain's bilinear surface at one point.
struct TerrainSample {
  double z;       ///< elevation, m
  Vec2 gradient;  ///< (∂z/∂x, ∂z/∂y), dimensionless
};

/// Elevation and gradient of the bilinear surface through the cell centres of `r` (any north-up
/// raster, e.g. a release-thickness grid) in one cell lookup, inline for the per-particle hot loops (the same
/// surface as Terrain::elevation / gradient, which call it). False (and `out` untouched) where
/// Terrain::valid is false: outside the cell-centre grid or next to nodata.
inline bool sample_terrain(const Raster& r, double x, double y, TerrainSample& out) noexcept {
  // Centre-based fractional pixel coordinates (see Raster::to_pixel); v grows southward.
  const double u = (x - r.geotransform[0]) / r.geotransform[1] - 0.5;
  const double v = (y - r.geotransform[3]) / r.geotransform[5] - 0.5;
  // Negated test so that NaN coordinates are rejected too; a patch needs 2 × 2 centres.
  if (!(u >= 0.0 && v >= 0.0 && u <= r.nx - 1 && v <= r.ny - 1) || r.nx < 2 || r.ny < 2) return false;
  const int i = static_cast<int>(u) < r.nx - 2 ? static_cast<int>(u) : r.nx - 2;  // last centre line:
  const int j = static_cast<int>(v) < r.ny - 2 ? static_cast<int>(v) : r.ny - 2;  // last patch, offset 1
  const double fx = u - i, fy = v - j;
  const double* row0 = r.data.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(r.nx) + i;
  const double* row1 = row0 + r.nx;
  const double z00 = row0[0], z10 = row0[1], z01 = row1[0], z11 = row1[1];
  if (std::isnan(z00 + z10 + z01 + z11)) return false;
  if (r.nodata) {
    const double nd = *r.nodata;
    if (z00 == nd || z10 == nd || z01 == nd || z11 == nd) return false;
  }
  const double top = z00 + fx * (z10 - z00), bottom = z01 + fx * (z11 - z01);
  out.z = top + fy * (bottom - top);
  out.gradient = Vec2(((1.0 - fy) * (z10 - z00) + fy * (z11 - z01)) / r.geotransform[1],
                      ((1.0 - fx) * (z01 - z00) + fx * (z11 - z10)) / r.geotransform[5]);
  return true;
}

/// Same, on a Terrain.
inline bool sample_terrain(const Terrain& t, double x, double y, TerrainSample& out) noexcept {
  return sample_terrain(t.raster(), x, y, out);
}

}  // namespace geohaz
