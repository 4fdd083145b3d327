#pragma once
/// \file infiltration.hpp
/// Rainfall infiltration into an infinite slope: the pressure head ψ(Z, t) of the linearised
/// Richards equation for a rainfall history of piecewise-constant intensities (Iverson 2000,
/// "Landslide triggering by rain infiltration", Water Resources Research 36(7):1897–1910, the
/// infinite-depth solution, eqs. 27–28; in the form TRIGRS evaluates it, Baum, Savage & Godt 2002,
/// USGS OFR 02-424, eqs. 2–4, and Baum, Savage & Godt 2008, USGS OFR 2008-1159).
///
/// Coordinates: Z is the depth below the ground surface measured vertically (m), δ the slope
/// angle, d the depth of the initial (steady) water table below the surface, measured vertically.
/// The soil is saturated or tension-saturated (Iverson's "wet initial conditions"): the hydraulic
/// diffusivity is its maximum D₀ throughout, and the conductivity normal to the slope is K_s.
///
/// Equations as implemented. Slope-normal diffusion written in the vertical coordinate,
///     ∂ψ/∂t = D₁ ∂²ψ/∂Z²,       D₁ = D₀ / cos²δ,       D̂ = 4 D₀ / cos²δ,
/// with ψ(Z, 0) = β (Z − d) (steady slope-parallel flow below a water table at depth d, with the
/// long-term infiltration I_ZLT: β = cos²δ − I_ZLT/K_s) and at the surface the infiltration flux of
/// step n, I_nZ = min(I_n, K_s) (rain beyond K_s runs off, as in TRIGRS). By superposition of the
/// constant-flux solutions of the steps n = 1..N, each switched on at T_n and off at T_{n+1},
///     ψ(Z, t) = β (Z − d) + Z Σ_n (I_nZ / K_s) [ H(t − T_n) R(t* − T_n*) − H(t − T_{n+1}) R(t* − T_{n+1}*) ],
///     t* = t / (Z²/D̂),   T_n* = T_n / (Z²/D̂),
///     R(t*) = √(t*/π) exp(−1/t*) − erfc(1/√t*)                    (Iverson 2000, eq. 27b),
/// i.e. Z·(I/K_s)·R(t*) = (I/K_s) √(D̂ t) ierfc(Z/√(D̂ t)), the classic response of a half space to a
/// constant surface gradient. At Z = 0 the limit √(D̂ t/π)(I/K_s) is used (as TRIGRS does). The sum
/// is evaluated telescoped, Σ_k Δr_k R(t* − T_k*) over the instants T_k where the ratio r = I_Z/K_s
/// changes by Δr_k (one term per change, not two per step).
/// The cap (Iverson 2000, §5, the "β line"): the linearised solution grows without bound while
/// rain continues, but pressure heads cannot exceed those of slope-parallel flow with the water
/// table at the ground surface, so ψ ≤ β Z (TRIGRS applies the same limit).
///
/// Validity (Iverson 2000, §4): a thin soil, Z² ≪ A (A the upslope contributing area) and times
/// t ≪ A/D₀, so lateral flow has not yet built up; the response to short rain is then vertical.
/// Units SI: m, s, m/s, m²/s.

#include <cstddef>
#include <vector>

namespace geohaz {
class ConfigReader;
}

namespace geohaz::sph {

/// A rainfall history of piecewise-constant intensity: I_n over [T_n, T_{n+1}), n = 0..N−1, then
/// no rain. T_0 = 0.
struct RainfallHistory {
  std::vector<double> times;        ///< T_0 = 0 < T_1 < … < T_N (s): N + 1 step boundaries
  std::vector<double> intensities;  ///< I_n ≥ 0 (m/s), N values

  /// N equal steps of `step` seconds with the given intensities (m/s).
  static RainfallHistory uniform_steps(double step, const std::vector<double>& intensities);
  /// End of the rain T_N (s).
  double end() const noexcept { return times.empty() ? 0.0 : times.back(); }
  /// Intensity at time t (0 before 0 and after the end), m/s.
  double intensity_at(double t) const noexcept;
  /// Rain depth fallen up to time t (m).
  double depth_until(double t) const noexcept;
  /// InputError (naming `source` and `key`) unless the times increase from 0 and the intensities are
  /// finite and non-negative, one per step.
  void validate(const char* source, const char* key) const;
};

/// Iverson's response function R(t*) (see the file comment), R ≥ 0, R(0) = 0.
double iverson_response(double tstar) noexcept;

/// The hydraulic properties of the soil and the background flux.
struct InfiltrationParameters {
  double conductivity = 1e-5;  ///< K_s, saturated hydraulic conductivity (m/s), > 0
  double diffusivity = 5e-5;   ///< D₀, maximum hydraulic diffusivity (m²/s), > 0
  double steady_flux = 0.0;    ///< I_ZLT, long-term (initial) infiltration rate (m/s), 0 ≤ I_ZLT < K_s cos²δ
};

/// The rainfall history as the infiltration model sees it: the changes Δr_k of r = min(I, K_s)/K_s
/// at the instants T_k (telescoped superposition), shared by every cell of a map.
class InfiltrationHistory {
 public:
  InfiltrationHistory(const InfiltrationParameters& p, const RainfallHistory& rain);
  const InfiltrationParameters& parameters() const noexcept { return p_; }
  /// The instants T_k at which r changes (s) and the changes Δr_k.
  const std::vector<double>& change_times() const noexcept { return t_; }
  const std::vector<double>& changes() const noexcept { return dr_; }
  /// β = cos²δ − I_ZLT/K_s for a slope of angle δ (rad).
  double beta(double slope) const noexcept;
  /// ψ(Z, t) (m) at vertical depth Z ≥ 0 (m) and time t ≥ 0 (s) on a slope of angle δ (rad) with the
  /// initial water table at vertical depth d ≥ 0 (m), capped at β Z.
  double pressure_head(double Z, double t, double slope, double d) const noexcept;
  /// The same without the cap (the linear solution itself; for tests and diagnostics).
  double pressure_head_uncapped(double Z, double t, double slope, double d) const noexcept;
  /// The transient sum Σ_k Δr_k R((t − T_k)·inv_zstar) at time t (s), inv_zstar = D̂/Z² (1/s), Z > 0:
  /// ψ = β (Z − d) + Z · response_sum(t, D̂/Z²). The map evaluates it with the per-cell constants
  /// precomputed.
  double response_sum(double t, double inv_zstar) const noexcept;

 private:
  InfiltrationParameters p_;
  std::vector<double> t_, dr_;
};

/// The infiltration keys shared by `slope-stability` and `sph-slope` ([hydrology] and [rain]; one
/// declaration of their names, units, defaults, ranges and help).
struct InfiltrationKeys {
  InfiltrationParameters hydrology;
  double water_table_depth = 1.5;  ///< d, initial water table depth below the ground, vertical (m)
  RainfallHistory rain;            ///< rain.step, rain.intensity
};

/// Read (or, in describe mode, declare) hydrology.conductivity, hydrology.diffusivity,
/// hydrology.steady_infiltration, hydrology.water_table_depth, rain.step and rain.intensity, and check
/// what their ranges cannot (I_ZLT < K_s, the rain's steps): InputError naming the key.
InfiltrationKeys read_infiltration_keys(ConfigReader& cfg);

}  // namespace geohaz::sph
