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

#include <cmath>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

struct VoellmyCohesionFriction {
  double mu = 0.15;       ///< Coulomb coefficient μ (1)
  double xi = 500.0;      ///< turbulence coefficient ξ (m/s²)
  double cohesion = 0.0;  ///< C (Pa)
  static constexpr const char* name = "voellmy_cohesion";
  static constexpr const char* summary =
      "Voellmy with cohesion, S = muN + rho g v^2/xi + (1-mu)C(1-exp(-N/C)) (mu, xi, cohesion; RAMMS)";
  FrictionTerms terms(double g, double g_n, double h_n, double /*speed*/, double rho) const noexcept {
    double rest = g_n * mu;
    if (cohesion > 0.0) rest -= (1.0 - mu) * (cohesion / (rho * h_n)) * std::expm1(-rho * g_n * h_n / cohesion);
    return {rest, g / (xi * h_n)};
  }
};

}  // namespace geohaz::runout
