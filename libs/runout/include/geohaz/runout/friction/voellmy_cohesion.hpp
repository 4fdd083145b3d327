#pragma once
/// \file voellmy_cohesion.hpp
/// Voellmy friction with cohesion in the form of RAMMS (RAMMS::DEBRIS FLOW and ::AVALANCHE since
/// version 1.6.20; Bartelt et al. 2017, RAMMS::DEBRIS FLOW user manual v1.7, "Cohesion"):
///
///     S = μ N + ρ g |v|²/ξ + (1 − μ) C − (1 − μ) C exp(−N/C),     N = ρ g_n h_n,
///
/// C the cohesion (Pa). Unlike a Mohr–Coulomb cohesion c + μN, the cohesive part vanishes with N
/// (a thin film carries none) and tends to (1 − μ) C for N ≫ C. It is speed independent, so it
/// joins the yield part: divided by ρ h_n,
///
///     a_rest = μ g_n + (1 − μ) (C/(ρ h_n)) (1 − exp(−ρ g_n h_n / C)),   drag = g/(ξ h_n).
///
/// Steady uniform flow on slope θ: g sin θ = a_rest + g s²/(ξ h_n), so
/// s = √(ξ h_n (sin θ − a_rest/g)); the layer holds at rest while g sin θ ≤ a_rest.
/// C = 0 is Voellmy. (For μ > 1 the cohesive part would be negative; the reader keeps μ ≤ 1.)

#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

/// φ(x) = (1 − e^{−x})/x for x ≥ 0 to ~1e-14 relative: its Taylor polynomial of degree 5 below
/// x = 0.01 (truncation x⁶/720 < 2e-15), else with libm's exp, which is faster than expm1 and
/// loses at most ~1e-16/x to the subtraction there.
inline double one_minus_exp_ratio(double x) noexcept {
  if (x < 1e-2) return 1.0 - x * (1.0 / 2 - x * (1.0 / 6 - x * (1.0 / 24 - x * (1.0 / 120 - x * (1.0 / 720)))));
  return (1.0 - std::exp(-x)) / x;
}

struct VoellmyCohesionFriction {
  static constexpr std::array<ParamSpec, 3> parameters{
      {kCoulombMuParameter,
       kVoellmyXiParameter,
       {"cohesion", 0.0, Range::closed(0.0, 1e6), "Pa", "cohesion C of the RAMMS form",
        "no published range for debris, docs/runout.md"}}};
  double mu = kCoulombMuParameter.def;  ///< Coulomb coefficient μ (1)
  double xi = kVoellmyXiParameter.def;  ///< turbulence coefficient ξ (m/s²)
  double cohesion = parameters[2].def;  ///< C (Pa)
  static constexpr const char* name = "voellmy_cohesion";
  static constexpr const char* summary =
      "Voellmy with cohesion, S = muN + rho g v^2/xi + (1-mu)C(1-exp(-N/C)) (mu, xi, cohesion; RAMMS)";
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? mu : j == 1 ? xi : cohesion) = v, true; }
  /// μ ≤ 1 with a cohesion: the RAMMS term (1 − μ) C must not be negative.
  static std::optional<ParamProblem> check(const ParamValues& v) {
    if (v["cohesion"] > 0.0 && v["mu"] > 1.0)
      return ParamProblem{"mu",
                          "voellmy_cohesion needs model.mu ≤ 1 with a cohesion (the RAMMS term (1 − μ) C would be "
                          "negative)",
                          std::to_string(v["mu"])};
    return std::nullopt;
  }
  FrictionTerms terms(double g, double g_n, double h_n, double /*speed*/, double rho) const noexcept {
    if (cohesion <= 0.0) return {g_n * mu, g / (xi * h_n)};
    // a_rest = g_n (μ + (1 − μ) φ(x)), φ(x) = (1 − e^{−x})/x, x = N/C.
    return {g_n * (mu + (1.0 - mu) * one_minus_exp_ratio(rho * g_n * h_n / cohesion)), g / (xi * h_n)};
  }
};

}  // namespace geohaz::runout
