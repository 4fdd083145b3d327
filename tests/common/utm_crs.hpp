#pragma once
// Test helper: the WKT of WGS 84 / UTM zone N (north), EPSG:326NN, for synthetic rasters that need
// a projected CRS in metres (the water-table and section tests write their DSMs with it).
#include <string>

namespace geohaz::testing {

inline std::string utm_wkt(int zone) {
  const int cm = -183 + 6 * zone;
  return "PROJCS[\"WGS 84 / UTM zone " + std::to_string(zone) +
         "N\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563]],PRIMEM["
         "\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]],PROJECTION[\"Transverse_Mercator\"],PARAMETER["
         "\"latitude_of_origin\",0],PARAMETER[\"central_meridian\"," +
         std::to_string(cm) +
         "],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],PARAMETER[\"false_northing\",0],"
         "UNIT[\"metre\",1],AUTHORITY[\"EPSG\",\"" +
         std::to_string(32600 + zone) + "\"]]";
}

}  // namespace geohaz::testing
