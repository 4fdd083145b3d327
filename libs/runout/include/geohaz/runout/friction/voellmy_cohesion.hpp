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

/// φ(x) = (1 − e^{−x})/x for x ≥ 0 to ~1e-14 relative: its Taylor polynomial of degree 5 below
/// x = 0.01 (truncation x⁶/720 < 2e-15), else with libm's exp, which is faster than expm1 and
/// loses at most ~1e-16/x to the subtraction there.
inline double one_minus_exp_ratio(double x) noexcept {
  if (x < 1e-2) return 1.0 - x * (1.0 / 2 - x * (1.0 / 6 - x * (1.0 / 24 - x * (1.0 / 120 - x * (1.0 / 720)))));
  return (1.0 - std::exp(-x)) / x;
}

struct VoellmyCohesionFriction {
  double mu = 0.15;       ///< Coulomb coefficient μ (1)
  double xi = 500.0;      ///< turbulence coefficient ξ (m/s²)
  double cohesion = 0.0;  ///< C (Pa)
  static constexpr const char* name = "voellmy_cohesion";
  static constexpr const char* summary =
      "Voellmy with cohesion, S = muN + rho g v^2/xi + (1-mu)C(1-exp(-N/C)) (mu, xi, cohesion; RAMMS)";
  FrictionTerms terms(double g, double g_n, double h_n, double /*speed*/, double rho) const noexcept {
    if (cohesion <= 0.0) return {g_n * mu, g / (xi * h_n)};
    // a_rest = g_n (μ + (1 − μ) φ(x)), φ(x) = (1 − e^{−x})/x, x = N/C.
    return {g_n * (mu + (1.0 - mu) * one_minus_exp_ratio(rho * g_n * h_n / cohesion)), g / (xi * h_n)};
  }
};

}  // namespace geohaz::runout
