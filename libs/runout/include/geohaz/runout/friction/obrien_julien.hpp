#pragma once
/// \file obrien_julien.hpp
/// The quadratic rheology of O'Brien & Julien (1985) and O'Brien, Julien & Fullerton (1993) in the
/// depth-integrated form of FLO-2D (FLO-2D reference manual, "Sediment concentration and
/// rheology"): the friction slope of a mudflow is the sum of a yield, a viscous and a
/// turbulent-dispersive slope,
///
///     S_f = τ_y/(ρ g h) + K η U/(8 ρ g h²) + n_td² U²/h^{4/3},
///
/// τ_y the yield stress (Pa), η the Bingham viscosity (Pa·s), K the laminar resistance parameter
/// (24 for laminar sheet flow on a smooth plane, up to ~5·10⁴ on rough vegetated ground), n_td the
/// turbulent-dispersive Manning coefficient (s/m^{1/3}). τ_b = ρ g h S_f, so with h = h_n
///
///     a = g S_f = τ_y/(ρ h_n) + (K η/(8 ρ h_n²)) s + (g n_td²/h_n^{4/3}) s²:
///
/// rest, visc and drag of the closed-form implicit step. With K = 24 the viscous term is the
/// Newtonian laminar film (U = ρ g h² S/(3η)). Steady uniform flow on slope θ: the positive root
/// of drag s² + visc s + rest − g sin θ = 0 (at rest while g sin θ ≤ τ_y/(ρ h_n)).
/// The optional parameterisation by the volumetric sediment concentration C_v (O'Brien & Julien
/// 1988), τ_y = α₂ exp(β₂ C_v), η = α₁ exp(β₁ C_v), is resolved by the config reader.

#include <cmath>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

struct OBrienJulienFriction {
  double tau_y = 100.0;     ///< yield stress τ_y (Pa)
  double viscosity = 10.0;  ///< Bingham viscosity η (Pa·s)
  double laminar_k = 24.0;  ///< laminar resistance parameter K (1)
  double n_td = 0.06;       ///< turbulent-dispersive Manning coefficient (s/m^{1/3})
  static constexpr const char* name = "obrien_julien";
  static constexpr const char* summary =
      "O'Brien-Julien quadratic, yield + viscous + turbulent (tau_y, viscosity, laminar_k, n; or cv; FLO-2D)";
  FrictionTerms terms(double g, double /*g_n*/, double h_n, double /*speed*/, double rho) const noexcept {
    const double rh = rho * h_n;
    return {tau_y / rh, g * n_td * n_td / (h_n * std::cbrt(h_n)), laminar_k * viscosity / (8.0 * rh * h_n)};
  }
};

}  // namespace geohaz::runout
