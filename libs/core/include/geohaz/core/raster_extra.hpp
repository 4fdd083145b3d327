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

/// The text chunk `key` of a PNG written by write_png (as GDAL reads it back), "" when it has none
/// or the file cannot be read.
std::string read_png_text(const std::filesystem::path& path, const std::string& key);

/// Elevation and gradient of a Terrain's bilinear surface in one cell look-up (BilinearGrid::sample,
/// the same surface as Terrain::elevation / gradient). False (and `out` untouched) where
/// Terrain::valid is false: outside the closed cell-centre hull or next to nodata.
inline bool sample_terrain(const Terrain& t, double x, double y, TerrainSample& out) noexcept {
  return t.grid().sample(Vec2(x, y), out);
}

}  // namespace geohaz
