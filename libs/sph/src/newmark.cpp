#include "geohaz/sph/newmark.hpp"

#include <algorithm>
#include <cmath>

#include "geohaz/core/errors.hpp"

namespace geohaz::sph {

NewmarkResult newmark_displacement(const std::vector<double>& a, double dt, double ay) {
  if (!(dt > 0.0)) throw InputError("the Newmark time step must be positive", "", "dt", std::to_string(dt));
  if (!(ay >= 0.0)) throw InputError("the yield acceleration must not be negative", "", "yield_acceleration");
  NewmarkResult r;
  double v = 0.0;
  bool sliding = false;
  for (std::size_t k = 0; k + 1 < a.size(); ++k) {
    // Within the step the excess e(τ) = e0 + slope τ is linear, τ ∈ [0, dt].
    const double e0 = a[k] - ay, slope = (a[k + 1] - a[k]) / dt;
    double tau = 0.0;  // the part of the step already integrated
    while (tau < dt) {
      if (!sliding) {  // at rest: the block starts where the excess turns positive
        if (e0 + slope * tau > 0.0) {
          sliding = true;
        } else if (slope > 0.0 && -e0 / slope > tau && -e0 / slope < dt) {
          tau = -e0 / slope;
          sliding = true;
        } else {
          break;
        }
        ++r.episodes;
      }
      // Sliding from τ with velocity v: v(τ + s) = v + e s + slope s²/2 until it returns to 0.
      const double e = e0 + slope * tau, h = dt - tau;
      const double eps = 1e-12 * dt;
      double stop = h;
      auto take = [&](double root) {
        if (root > eps && root < stop) stop = root;
      };
      if (std::abs(slope) * h < 1e-12 * (std::abs(e) + ay + 1e-300)) {
        if (e < 0.0) take(-v / e);
      } else {
        const double disc = e * e - 2.0 * slope * v;
        if (disc >= 0.0) {
          const double sq = std::sqrt(disc);
          take((-e - sq) / slope);
          take((-e + sq) / slope);
        }
      }
      const double vend = v + e * stop + 0.5 * slope * stop * stop;
      r.displacement += v * stop + 0.5 * e * stop * stop + slope * stop * stop * stop / 6.0;
      double vmax = std::max(v, vend);
      if (slope < 0.0 && e > 0.0 && -e / slope < stop) vmax = std::max(vmax, v - 0.5 * e * e / slope);
      r.max_velocity = std::max(r.max_velocity, vmax);
      r.sliding_time += stop;
      tau += stop;
      if (stop < h) {
        v = 0.0;  // the block stops; it may start again later in the step
        sliding = false;
      } else {
        v = std::max(vend, 0.0);
      }
    }
  }
  r.final_velocity = sliding ? v : 0.0;
  return r;
}

NewmarkResult newmark_displacement(const EarthquakeLoading& record, double ay, int direction, double end_time,
                                   double dt) {
  if (!(end_time > 0.0)) throw InputError("the Newmark duration must be positive", "", "end_time");
  if (!(dt > 0.0)) throw InputError("the Newmark time step must be positive", "", "dt", std::to_string(dt));
  const auto n = static_cast<std::size_t>(std::ceil(end_time / dt));
  const double h = end_time / static_cast<double>(n);
  std::vector<double> a(n + 1);
  const double sgn = direction < 0 ? -1.0 : 1.0;
  for (std::size_t k = 0; k <= n; ++k) a[k] = sgn * record.horizontal(static_cast<double>(k) * h);
  return newmark_displacement(a, h, ay);
}

}  // namespace geohaz::sph
