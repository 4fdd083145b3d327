#include "geohaz/runout/synthetic_terrain.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace geohaz::runout {

const char* const kSyntheticValleyCrsWkt =
    "PROJCS[\"WGS 84 / UTM zone 54N\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,"
    "298.257223563,AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],PRIMEM[\"Greenwich\",0,"
    "AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],"
    "AUTHORITY[\"EPSG\",\"4326\"]],PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"latitude_of_origin\",0],"
    "PARAMETER[\"central_meridian\",141],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],"
    "PARAMETER[\"false_northing\",0],UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"Easting\",EAST],"
    "AXIS[\"Northing\",NORTH],AUTHORITY[\"EPSG\",\"32654\"]]";

double SyntheticValley::thalweg_y(double x) const noexcept {
  const double y_mid = y0 - 0.5 * ny * cell;
  return y_mid + meander_amplitude * std::sin(2.0 * std::numbers::pi * (x - x0) / meander_wavelength);
}

double SyntheticValley::elevation(double x, double y) const noexcept {
  // Thalweg elevation: integral of the piecewise-linear gradient S(s), s = x − x0.
  const double L = length();
  const double s = x - x0;
  const double a = head_length, b = channel_start, c = fan_start * L, d = fan_end * L;
  // Breakpoints and gradients of the piecewise-linear S(s).
  const double ss[5] = {0.0, a, b, c, d};
  const double sv[5] = {s_head, s_head, s_channel, s_channel, s_fan};
  double drop = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double lo = ss[k], hi = ss[k + 1];
    if (s <= lo) break;
    const double t = std::min(s, hi);
    const double slope_at_t = sv[k] + (sv[k + 1] - sv[k]) * (t - lo) / (hi - lo);
    drop += 0.5 * (sv[k] + slope_at_t) * (t - lo);
  }
  if (s > d) drop += s_fan * (s - d);
  if (s < 0.0) drop = s_head * s;
  const double u = (y - thalweg_y(x)) / half_width;
  return top - drop + side_height * u * u;
}

SyntheticValley SyntheticValley::scaled(double f) const {
  SyntheticValley v = *this;
  v.nx = std::max(8, static_cast<int>(std::lround(nx * f)));
  v.ny = std::max(8, static_cast<int>(std::lround(ny * f)));
  v.head_length *= f;
  v.channel_start *= f;
  v.meander_amplitude *= f;
  v.meander_wavelength *= f;
  v.side_height *= f;
  v.half_width *= f;
  v.top = top * f;
  return v;
}

}  // namespace geohaz::runout
