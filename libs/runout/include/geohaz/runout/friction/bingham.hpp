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
/// depressed cubic r³ − (3 + s*/K') r + 2 + Δt a_rest/K' = 0, whose root in (0, 1) is wanted (the
/// middle one; one is negative, one above 1). It is solved in t = 1 − r (plug_deficit below) by
/// Halley's method rather than by the trigonometric formula, whose acos is ill-conditioned near the
/// yield (relative error in the speed up to 20 % at s*/K' = 1e-12; Halley's root is good to 1e-14
/// there and to < 1e-11 up to s*/K' = 1e5) and which costs an acos and a cos per particle-step.
/// τ_y = 0 is the Newtonian film, a = 3 μ_B s/(ρ h²). Forest drag (extra_drag) is applied after the law's step
/// as a second implicit drag step (operator splitting, first order in Δt; it cannot move a particle).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

/// The law's terms for one particle: τ_b(U) of the plug-flow cubic.
struct BinghamTerms {
  double rest;              ///< τ_y/(ρ h) (m/s²)
  double speed_scale;       ///< K' = h τ_y/(6 μ_B) (m/s)
  double visc;              ///< 3 μ_B/(ρ h²) (1/s): the τ_y = 0 (Newtonian) limit
  double extra_drag = 0.0;  ///< forest drag (1/m)

  /// t = 1 − r = 1 − τ_y/τ_b ∈ (0, 1) after a step from s* of length Δt, s* > Δt a_rest (Δt = 0:
  /// the steady relation at U = s*). With P = s*/K' and D = P − Δt a_rest/K' > 0 the cubic is
  /// f(t) = t³ − 3t² − P t + D = 0: f(0) = D > 0 > f(1) = −2 − Δt a_rest/K', and f is decreasing
  /// and concave on [0, 1], so the root is unique there. Halley's method starts from the root of
  /// the quadratic part 3t² + P t − D (below the root: f(t₀) = t₀³ > 0) and stops after a step
  /// below 2e-5 t, which leaves ~(2e-5)³ relative; 1–3 iterations, no libm call but one sqrt.
  double plug_deficit(double s_star, double dt) const noexcept {
    const double ik = 1.0 / speed_scale, P = s_star * ik, D = (s_star - dt * rest) * ik;
    double t = 2.0 * D / (P + std::sqrt(P * P + 12.0 * D));
    for (int k = 0; k < 8; ++k) {
      const double t2 = t * t, f = (t - 3.0) * t2 - P * t + D, f1 = 3.0 * t2 - 6.0 * t - P, f2 = 6.0 * t - 6.0;
      const double d = 2.0 * f * f1 / (2.0 * f1 * f1 - f * f2);
      t -= d;
      if (std::abs(d) <= 2e-5 * t) break;
    }
    return t;
  }
  /// τ_b(s)/(ρ h) of the steady plug flow at mean speed s.
  double acceleration(double s) const noexcept {
    if (rest == 0.0) return visc * s;
    return s > 0.0 ? rest / (1.0 - plug_deficit(s, 0.0)) : rest;
  }
};

/// Speed after the implicit Bingham step (header comment), then the forest drag.
inline double speed_after_friction(double s_star, double dt, const BinghamTerms& t) noexcept {
  double s;
  if (t.rest == 0.0) {
    s = s_star / (1.0 + t.visc * dt);
  } else {
    if (s_star <= dt * t.rest) return 0.0;
    const double u = t.plug_deficit(s_star, dt);        // 1 − r
    s = t.speed_scale * u * u * (3.0 - u) / (1.0 - u);  // K' (1 − r)²(2 + r)/r, exact as r → 1
  }
  return speed_after_drag(s, t.extra_drag * dt);
}

struct BinghamFriction {
  static constexpr std::array<ParamSpec, 2> parameters{{kYieldStressParameter, kBinghamViscosityParameter}};
  double tau_y = kYieldStressParameter.def;           ///< yield stress τ_y (Pa)
  double viscosity = kBinghamViscosityParameter.def;  ///< plastic viscosity μ_B (Pa·s)
  static constexpr const char* name = "bingham";
  static constexpr const char* summary =
      "Bingham plastic, exact plug-flow cubic (tau_y, viscosity; Pastor et al. 2004)";
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? tau_y : viscosity) = v, true; }
  BinghamTerms terms(double /*g*/, double /*g_n*/, double h_n, double /*speed*/, double rho) const noexcept {
    return {tau_y / (rho * h_n), h_n * tau_y / (6.0 * viscosity), 3.0 * viscosity / (rho * h_n * h_n)};
  }
};

}  // namespace geohaz::runout
