#pragma once
/// \file bingham.hpp
/// Bingham plastic (τ = τ_y + μ_B γ̇ where sheared, rigid where |τ| < τ_y) in its exact
/// depth-averaged form: the steady uniform plug flow of a layer of depth h under the basal shear
/// τ_b ≥ τ_y has the mean speed (Johnson 1970; Pastor et al. 2004, eq. of the "plug-flow cubic")
///
///     U = (h τ_b/(6 μ_B)) (1 − r)² (2 + r),   r = τ_y/τ_b,
///
/// equivalently 2τ_b³ − 3(τ_y + 2μ_B U/h) τ_b² + τ_y³ = 0; its plug (the layer above
/// z = h(1 − r)) moves at u_p = (h τ_b/(2μ_B)) (1 − r)². geohaz uses this cubic itself, not the
/// usual approximation τ_b ≈ 3/2 τ_y + 3μ_B U/h (which drops τ_y³ and so puts the yield at
/// 3/2 τ_y): a layer starts to move exactly when τ_b = ρ g h_n sin θ exceeds τ_y.
///
/// The implicit step in closed form: with K' = h τ_y/(6μ_B) (m/s) and a_rest = τ_y/(ρ h), the
/// step s = s* − Δt τ_b(s)/(ρ h) with s = K' (1 − r)²(2 + r)/r and τ_b = τ_y/r becomes the
/// depressed cubic r³ − (3 + s*/K') r + 2 + Δt a_rest/K' = 0, whose root in (0, 1) (the middle
/// one; one negative, one above 1) is taken by the trigonometric formula. τ_y = 0 is the
/// Newtonian film, a = 3 μ_B s/(ρ h²). Forest drag (extra_drag) is applied after the law's step
/// as a second implicit drag step (operator splitting, first order in Δt; it cannot move a particle).

#include <algorithm>
#include <cmath>
#include <numbers>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

/// The law's terms for one particle: τ_b(U) of the plug-flow cubic.
struct BinghamTerms {
  double rest;              ///< τ_y/(ρ h) (m/s²)
  double speed_scale;       ///< K' = h τ_y/(6 μ_B) (m/s)
  double visc;              ///< 3 μ_B/(ρ h²) (1/s): the τ_y = 0 (Newtonian) limit
  double extra_drag = 0.0;  ///< forest drag (1/m)

  /// r = τ_y/τ_b ∈ (0, 1] after a step from s* of length Δt (Δt = 0: the steady relation at U = s*).
  double ratio(double s_star, double dt) const noexcept {
    const double p = 3.0 + s_star / speed_scale, q = 2.0 + dt * rest / speed_scale;  // r³ − p r + q = 0
    const double m = std::sqrt(p / 3.0);
    const double c = std::clamp(-q / (2.0 * m * m * m), -1.0, 1.0);
    return 2.0 * m * std::cos(std::acos(c) / 3.0 - 2.0 * std::numbers::pi / 3.0);
  }
  /// τ_b(s)/(ρ h) of the steady plug flow at mean speed s.
  double acceleration(double s) const noexcept {
    if (rest == 0.0) return visc * s;
    return s > 0.0 ? rest / ratio(s, 0.0) : rest;
  }
};

/// Speed after the implicit Bingham step (header comment), then the forest drag.
inline double speed_after_friction(double s_star, double dt, const BinghamTerms& t) noexcept {
  double s;
  if (t.rest == 0.0) {
    s = s_star / (1.0 + t.visc * dt);
  } else {
    if (s_star <= dt * t.rest) return 0.0;
    const double r = t.ratio(s_star, dt);
    s = t.speed_scale * (1.0 - r) * (1.0 - r) * (2.0 + r) / r;  // no cancellation as r → 1
  }
  return speed_after_drag(s, t.extra_drag * dt);
}

struct BinghamFriction {
  double tau_y = 100.0;     ///< yield stress τ_y (Pa)
  double viscosity = 10.0;  ///< plastic viscosity μ_B (Pa·s)
  static constexpr const char* name = "bingham";
  static constexpr const char* summary =
      "Bingham plastic, exact plug-flow cubic (tau_y, viscosity; Pastor et al. 2004)";
  BinghamTerms terms(double /*g*/, double /*g_n*/, double h_n, double /*speed*/, double rho) const noexcept {
    return {tau_y / (rho * h_n), h_n * tau_y / (6.0 * viscosity), 3.0 * viscosity / (rho * h_n * h_n)};
  }
};

}  // namespace geohaz::runout
