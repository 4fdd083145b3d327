// The prescribed pore pressure of the SPH solver (pore_pressure.hpp): the soil column of r_u, the
// pressure head of rain infiltration on a section, the water table over a 3D strip.
#include "geohaz/sph/pore_pressure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

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

double WaterTableGrid::level(double x, double y, double dz) const noexcept {
  auto locate = [](double v, double v0, double d, int n, int& k, double& w) {
    const double f = std::clamp((v - v0) / d, 0.0, static_cast<double>(n - 1));
    k = std::min(static_cast<int>(f), n - 2);
    w = f - k;
  };
  int i = 0, j = 0;
  double wx = 0.0, wy = 0.0;
  locate(x, x0, dx, nx, i, wx);
  locate(y, y0, dy, ny, j, wy);
  auto at = [&](const std::vector<double>& f) {
    const std::size_t a = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
    const std::size_t b = a + static_cast<std::size_t>(nx);
    return (1.0 - wy) * ((1.0 - wx) * f[a] + wx * f[a + 1]) + wy * ((1.0 - wx) * f[b] + wx * f[b + 1]);
  };
  return std::min(at(table) + dz, at(ground));
}

RainPorePressure::RainPorePressure(const InfiltrationParameters& p, const RainfallHistory& rain,
                                   std::vector<std::array<double, 2>> ground, double water_table_depth,
                                   std::vector<std::array<double, 2>> clock)
    : history_(p, rain), rain_(rain), ground_(std::move(ground)), clock_(std::move(clock)), d_(water_table_depth) {
  // Segment 0 lies before the first vertex and the last one beyond the last vertex: level ground.
  auto segment = [&](double delta) {
    const double c = std::cos(delta);
    return Segment{history_.beta(delta), 4.0 * p.diffusivity / (c * c)};
  };
  segment_.push_back(segment(0.0));
  for (std::size_t k = 1; k < ground_.size(); ++k) {
    const double dx = ground_[k][0] - ground_[k - 1][0];
    // A vertical step is never the segment above a point (segment_of takes the one before it).
    segment_.push_back(segment(dx > 0.0 ? std::atan(std::abs(ground_[k][1] - ground_[k - 1][1]) / dx) : 0.0));
  }
  segment_.push_back(segment(0.0));
}

std::size_t RainPorePressure::segment_of(double x) const noexcept {
  // As surface_at: the first vertex k ≥ 1 with x ≤ x_k, segment (k − 1, k).
  if (ground_.empty() || x <= ground_.front()[0]) return 0;
  const auto it =
      std::lower_bound(ground_.begin() + 1, ground_.end(), x, [](const auto& q, double v) { return q[0] < v; });
  return static_cast<std::size_t>(it - ground_.begin());
}

double RainPorePressure::slope_at(double x) const noexcept {
  const std::size_t k = segment_of(x);
  if (k == 0 || k >= ground_.size()) return 0.0;
  const double dx = ground_[k][0] - ground_[k - 1][0];
  return dx > 0.0 ? std::atan(std::abs(ground_[k][1] - ground_[k - 1][1]) / dx) : 0.0;
}

double RainPorePressure::rain_time(double t) const noexcept {
  if (clock_.empty()) return t;
  if (t <= clock_.front()[0]) return clock_.front()[1];
  if (t >= clock_.back()[0]) return clock_.back()[1];
  const auto it = std::upper_bound(clock_.begin(), clock_.end(), t, [](double v, const auto& q) { return v < q[0]; });
  const auto& a = *(it - 1);
  const auto& b = *it;
  return a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0]);
}

double RainPorePressure::head(double x, double z, double t_rain) const noexcept {
  const double Z = surface_at(ground_, x) - z;
  if (!(Z > 0.0)) return -std::numeric_limits<double>::infinity();
  const Segment& s = segment_[segment_of(x)];
  // InfiltrationHistory::pressure_head with the segment's constants: β (Z − d) + Z Σ Δr R(t* − T*), capped at β Z.
  const double psi = s.beta * (Z - d_) + Z * history_.response_sum(t_rain, s.dhat / (Z * Z));
  return std::min(psi, s.beta * Z);
}

double RainPorePressure::initial_level(double x) const noexcept {
  return surface_at(ground_, x) - d_;
}

}  // namespace geohaz::sph
