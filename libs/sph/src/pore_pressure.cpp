// The prescribed pore pressure of the SPH solver (pore_pressure.hpp): the soil column of r_u.
#include "geohaz/sph/pore_pressure.hpp"

#include <algorithm>

#include "geohaz/sph/scenario.hpp"

namespace geohaz::sph {

double OverburdenProfile::mass_above(double x, double z) const noexcept {
  const double zg = surface_at(ground, x);  // the profile's own interpolation, as Bishop's slices take it
  if (!(zg > z)) return 0.0;
  if (tops.empty()) return densities.front() * (zg - z);
  double m = 0.0, lo = -1e300;
  for (std::size_t k = 0; k <= tops.size(); ++k) {
    const double hi = k < tops.size() ? tops[k] : 1e300;
    const double a = std::max(lo, z), b = std::min(hi, zg);
    if (b > a) m += densities[k] * (b - a);
    lo = hi;
  }
  return m;
}

}  // namespace geohaz::sph
