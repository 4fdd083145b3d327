#include "geohaz/sph/infiltration.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <string>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"

namespace geohaz::sph {

namespace {

std::string number(double v) {
  std::ostringstream o;
  o << std::setprecision(6) << v;
  return o.str();
}

}  // namespace

RainfallHistory RainfallHistory::uniform_steps(double step, const std::vector<double>& intensities) {
  RainfallHistory r;
  r.intensities = intensities;
  r.times.resize(intensities.size() + 1);
  for (std::size_t n = 0; n < r.times.size(); ++n) r.times[n] = step * static_cast<double>(n);
  return r;
}

double RainfallHistory::intensity_at(double t) const noexcept {
  if (times.size() < 2 || !(t >= times.front()) || t >= times.back()) return 0.0;
  const auto it = std::upper_bound(times.begin(), times.end(), t);
  return intensities[static_cast<std::size_t>(it - times.begin()) - 1];
}

double RainfallHistory::depth_until(double t) const noexcept {
  double d = 0.0;
  for (std::size_t n = 0; n < intensities.size(); ++n) {
    const double a = times[n], b = std::min(times[n + 1], t);
    if (b > a) d += intensities[n] * (b - a);
  }
  return d;
}

void RainfallHistory::validate(const char* source, const char* key) const {
  if (intensities.empty() || times.size() != intensities.size() + 1)
    throw InputError("the rainfall history needs one intensity per step (" + std::to_string(intensities.size()) +
                         " intensities, " + std::to_string(times.size()) + " step boundaries)",
                     source, key);
  if (times.front() != 0.0) throw InputError("the rain must start at t = 0 s", source, key, std::to_string(times[0]));
  for (std::size_t n = 0; n + 1 < times.size(); ++n)
    if (!(times[n + 1] > times[n]) || !std::isfinite(times[n + 1]))
      throw InputError("the rain's step times must increase (step " + std::to_string(n) + ")", source, key,
                       std::to_string(times[n + 1]));
  for (std::size_t n = 0; n < intensities.size(); ++n)
    if (!(intensities[n] >= 0.0) || !std::isfinite(intensities[n]))
      throw InputError("rain intensity of step " + std::to_string(n) + " must be finite and >= 0 m/s", source, key,
                       std::to_string(intensities[n]));
}

double iverson_response(double tstar) noexcept {
  // Below t* = 1/700 both terms are < 1e-300: exp(−1/t*) underflows and erfc(1/√t*) with it.
  if (!(tstar > 1.0 / 700.0)) return 0.0;
  const double x = 1.0 / tstar;
  return std::sqrt(tstar / std::numbers::pi) * std::exp(-x) - std::erfc(std::sqrt(x));
}

InfiltrationHistory::InfiltrationHistory(const InfiltrationParameters& p, const RainfallHistory& rain) : p_(p) {
  double previous = 0.0;
  for (std::size_t n = 0; n <= rain.intensities.size(); ++n) {
    const double r = n < rain.intensities.size() ? std::min(rain.intensities[n], p.conductivity) / p.conductivity : 0.0;
    if (r != previous) {
      t_.push_back(rain.times[n]);
      dr_.push_back(r - previous);
      previous = r;
    }
  }
}

double InfiltrationHistory::beta(double slope) const noexcept {
  const double c = std::cos(slope);
  return c * c - p_.steady_flux / p_.conductivity;
}

double InfiltrationHistory::pressure_head_uncapped(double Z, double t, double slope, double d) const noexcept {
  const double c = std::cos(slope);
  const double dhat = 4.0 * p_.diffusivity / (c * c);  // D̂ = 4 D₀/cos²δ
  double psi = beta(slope) * (Z - d);
  if (Z > 0.0) {
    psi += Z * response_sum(t, dhat / (Z * Z));
  } else {
    double sum = 0.0;
    for (std::size_t k = 0; k < t_.size() && t_[k] < t; ++k)
      sum += dr_[k] * std::sqrt((t - t_[k]) * dhat / std::numbers::pi);
    psi += sum;
  }
  return psi;
}

double InfiltrationHistory::response_sum(double t, double inv_zstar) const noexcept {
  double sum = 0.0;
  for (std::size_t k = 0; k < t_.size() && t_[k] < t; ++k) sum += dr_[k] * iverson_response((t - t_[k]) * inv_zstar);
  return sum;
}

double InfiltrationHistory::pressure_head(double Z, double t, double slope, double d) const noexcept {
  return std::min(pressure_head_uncapped(Z, t, slope, d), beta(slope) * Z);
}

InfiltrationKeys read_infiltration_keys(ConfigReader& cfg) {
  InfiltrationKeys k;
  auto& h = k.hydrology;
  h.conductivity = cfg.get("hydrology.conductivity", h.conductivity, Range::positive(),
                           {"m/s", "saturated hydraulic conductivity K_s (rain beyond it runs off)",
                            "rain: saturated hydraulic conductivity K_s"});
  h.diffusivity = cfg.get(
      "hydrology.diffusivity", h.diffusivity, Range::positive(),
      {"m^2/s", "maximum hydraulic diffusivity D_0 (= K_s / specific storage)", "rain: hydraulic diffusivity D_0"});
  h.steady_flux = cfg.get("hydrology.steady_infiltration", h.steady_flux, Range::non_negative(),
                          {"m/s", "long-term infiltration rate I_ZLT before the rain (< K_s cos^2 delta)",
                           "rain: steady background infiltration"});
  k.water_table_depth =
      cfg.get("hydrology.water_table_depth", k.water_table_depth, Range::non_negative(),
              {"m", "initial water table depth d below the ground, vertical (>= 0: not above the ground)",
               "rain: initial water-table depth"});
  const double step = cfg.get("rain.step", 3600.0, Range::open_closed(0.0, 1e7),
                              {"s", "length of each rain step", "rain: hyetograph step"});
  const std::vector<double> intensity =
      cfg.get_array("rain.intensity", {2.78e-6}, Range::closed(0.0, 1e-2),
                    {"m/s", "intensity of each step in turn (1 mm/h = 2.778e-7 m/s); then no rain", "rain: intensity"});
  k.rain = RainfallHistory::uniform_steps(step, intensity);
  if (h.steady_flux >= h.conductivity)
    throw InputError("the long-term infiltration must be below K_s (" + number(h.conductivity) + " m/s)", cfg.source(),
                     "hydrology.steady_infiltration", number(h.steady_flux));
  k.rain.validate(cfg.source().c_str(), "rain.intensity");
  return k;
}

}  // namespace geohaz::sph
