// The prescribed pore pressure of the SPH solver (pore_pressure.hpp): the soil column of r_u, the
// pressure head of rain infiltration on a section or a 3D strip, the water table over a 3D strip.
#include "geohaz/sph/pore_pressure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "geohaz/sph/scenario.hpp"

namespace geohaz::sph {

double OverburdenProfile::column(double zg, double z) const noexcept {
  if (!(zg > z)) return 0.0;
  double m = 0.0, top = zg;
  if (surface_layer_depth > 0.0) {  // the cover by depth, as column_of in limit_equilibrium.cpp
    const double zl = zg - surface_layer_depth;
    m = surface_density * (zg - std::max(z, zl));
    top = zl;
    if (!(top > z)) return m;
  }
  if (tops.empty()) return m + densities.front() * (top - z);
  double lo = -1e300;
  for (std::size_t k = 0; k <= tops.size(); ++k) {
    const double hi = k < tops.size() ? tops[k] : 1e300;
    const double a = std::max(lo, z), b = std::min(hi, top);
    if (b > a) m += densities[k] * (b - a);
    lo = hi;
  }
  return m;
}

double OverburdenProfile::mass_above(double x, double z) const noexcept {
  // The profile's own interpolation, as Bishop's slices take it.
  return column(surface_at(ground, x), z);
}

double OverburdenProfile::mass_above(double x, double y, double z) const noexcept {
  return column(grid->ground_at(x, y), z);
}

StripGrid::Locus StripGrid::locate(double x, double y) const noexcept {
  auto one = [](double v, double v0, double d, int n, int& k, double& w) {
    const double f = std::clamp((v - v0) / d, 0.0, static_cast<double>(n - 1));
    k = std::min(static_cast<int>(f), n - 2);
    w = f - k;
  };
  int i = 0, j = 0;
  Locus q{};
  one(x, x0, dx, nx, i, q.wx);
  one(y, y0, dy, ny, j, q.wy);
  q.node = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
  q.cell = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx - 1) + static_cast<std::size_t>(i);
  return q;
}

double StripGrid::at(const std::vector<double>& f, const Locus& q) const noexcept {
  const std::size_t a = q.node, b = a + static_cast<std::size_t>(nx);
  return (1.0 - q.wy) * ((1.0 - q.wx) * f[a] + q.wx * f[a + 1]) + q.wy * ((1.0 - q.wx) * f[b] + q.wx * f[b + 1]);
}

double StripGrid::cell_slope(std::size_t k) const noexcept {
  const std::size_t i = k % static_cast<std::size_t>(nx - 1), j = k / static_cast<std::size_t>(nx - 1);
  const std::size_t a = j * static_cast<std::size_t>(nx) + i, b = a + static_cast<std::size_t>(nx);
  // The mean of the bilinear patch's gradient over the cell.
  const double gx = 0.5 * ((ground[a + 1] - ground[a]) + (ground[b + 1] - ground[b])) / dx;
  const double gy = 0.5 * ((ground[b] - ground[a]) + (ground[b + 1] - ground[a + 1])) / dy;
  return std::atan(std::hypot(gx, gy));
}

double WaterTableGrid::level(double x, double y, double dz) const noexcept {
  const Locus q = locate(x, y);
  return std::min(at(table, q) + dz, at(ground, q));
}

RainPorePressure::Segment RainPorePressure::segment(double delta) const noexcept {
  const double c = std::cos(delta);
  return Segment{history_.beta(delta), 4.0 * history_.parameters().diffusivity / (c * c)};
}

RainPorePressure::RainPorePressure(const InfiltrationParameters& p, const RainfallHistory& rain,
                                   std::vector<std::array<double, 2>> ground, double water_table_depth,
                                   std::vector<std::array<double, 2>> clock)
    : history_(p, rain), rain_(rain), ground_(std::move(ground)), clock_(std::move(clock)), d_(water_table_depth) {
  // Segment 0 lies before the first vertex and the last one beyond the last vertex: level ground.
  segment_.push_back(segment(0.0));
  for (std::size_t k = 1; k < ground_.size(); ++k) {
    const double dx = ground_[k][0] - ground_[k - 1][0];
    // A vertical step is never the segment above a point (segment_of takes the one before it).
    segment_.push_back(segment(dx > 0.0 ? std::atan(std::abs(ground_[k][1] - ground_[k - 1][1]) / dx) : 0.0));
  }
  segment_.push_back(segment(0.0));
}

RainPorePressure::RainPorePressure(const InfiltrationParameters& p, const RainfallHistory& rain,
                                   std::shared_ptr<const StripGrid> grid, double water_table_depth,
                                   std::vector<std::array<double, 2>> clock)
    : history_(p, rain), rain_(rain), clock_(std::move(clock)), grid_(std::move(grid)), d_(water_table_depth) {
  const std::size_t cells = static_cast<std::size_t>(grid_->nx - 1) * static_cast<std::size_t>(grid_->ny - 1);
  for (std::size_t k = 0; k < cells; ++k) segment_.push_back(segment(grid_->cell_slope(k)));
}

double RainPorePressure::smallest_beta() const noexcept {
  double b = 1e300;
  for (const auto& s : segment_) b = std::min(b, s.beta);
  return b;
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

double RainPorePressure::head_in(const Segment& s, double Z, double t_rain) const noexcept {
  if (!(Z > 0.0)) return -std::numeric_limits<double>::infinity();
  // InfiltrationHistory::pressure_head with the segment's constants: β (Z − d) + Z Σ Δr R(t* − T*), capped at β Z.
  const double psi = s.beta * (Z - d_) + Z * history_.response_sum(t_rain, s.dhat / (Z * Z));
  return std::min(psi, s.beta * Z);
}

double RainPorePressure::head(double x, double z, double t_rain) const noexcept {
  return head_in(segment_[segment_of(x)], surface_at(ground_, x) - z, t_rain);
}

double RainPorePressure::head(double x, double y, double z, double t_rain) const noexcept {
  const auto q = grid_->locate(x, y);
  return head_in(segment_[q.cell], grid_->at(grid_->ground, q) - z, t_rain);
}

double RainPorePressure::initial_level(double x) const noexcept {
  return surface_at(ground_, x) - d_;
}

double RainPorePressure::initial_level(double x, double y) const noexcept {
  return grid_->ground_at(x, y) - d_;
}

}  // namespace geohaz::sph
