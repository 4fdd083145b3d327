#pragma once
// Internal to libs/core/src: the few GDAL helpers shared by raster.cpp, vector.cpp and png.cpp.
// Only those files include GDAL; nothing outside src/ sees this header.

#include <cpl_error.h>
#include <ogr_spatialref.h>

#include <string>

namespace geohaz::detail {

/// GDALAllRegister() exactly once.
void ensure_gdal_registered();

/// " (GDAL: <last message>)" or "" — appended to InputError messages.
std::string gdal_last_error();

/// Parse a CRS in any form GDAL accepts; false when it cannot.
bool parse_srs(const std::string& text, OGRSpatialReference& srs);

/// Silences GDAL's own stderr printing while we turn its failures into InputError messages
/// (which carry CPLGetLastErrorMsg()).
class QuietGdalErrors {
 public:
  QuietGdalErrors() {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietGdalErrors() { CPLPopErrorHandler(); }
  QuietGdalErrors(const QuietGdalErrors&) = delete;
  QuietGdalErrors& operator=(const QuietGdalErrors&) = delete;
};

}  // namespace geohaz::detail
