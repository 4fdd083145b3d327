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
/// middle one; one is negative, one above 1). It is solved in t = 1 − r (plug_deficit below) to
/// 1e-13 relative in t and 1 − t: from the particle's t of its last step (kept by the solver as
/// ζ = τ_b − τ_y in the store's BasalExcessStress) by the cubic's reversion series, one division,
/// accepted when its residual proves the tolerance; else (cold start, or a jump) by Halley's
/// method. Not by the trigonometric formula, whose acos is ill-conditioned near the yield
/// (relative error in the speed up to 20 % at s*/K' = 1e-12, where this root is good to ~2e-13, as
/// up to s*/K' = 1e5) and which costs an acos and a cos per particle-step.
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
  double inv_speed_scale;   ///< 1/K' = 6 μ_B/(h τ_y) (s/m), a division off the step's critical path
  double tau_y;             ///< τ_y (Pa), to turn the kept ζ into t = ζ/(τ_y + ζ)
  double inv_viscosity;     ///< 1/μ_B (1/(Pa·s)), for the kept γ̇_b = ζ/μ_B
  double extra_drag = 0.0;  ///< forest drag (1/m)
  StepMemory memory{};      ///< the particle's last (ζ, γ̇_b), given by the solver

  /// t = 1 − r = 1 − τ_y/τ_b ∈ (0, 1) after a step from s* of length Δt, s* > Δt a_rest (Δt = 0:
  /// the steady relation at U = s*). With P = s*/K' and D = P − Δt a_rest/K' > 0 the cubic is
  /// f(t) = t³ − 3t² − P t + D = 0: f(0) = D > 0 > f(1) = −2 − Δt a_rest/K', and f is decreasing
  /// and concave on [0, 1], so the root is unique there. The root is wanted to 1e-13 relative in
  /// both t and 1 − t (1 − r sets the speed near the plug limit t → 1).
  ///
  /// Warm start (t_warm ∈ (0, 1): the particle's t of its last step): the cubic is exact around
  /// w = t_warm, f(w + ε) = f + f′ε + (f″/2)ε² + ε³, so its small root is the reversion series
  /// ε = x − A x² + (2A² − B) x³ + 5A(B − A²) x⁴ + (14A⁴ − 21A²B + 3B²) x⁵ + O(x⁶),
  /// x = −f/f′, A = f″/(2f′), B = 1/f′ (f, f′, f″ at w): one division and no iteration. It is
  /// accepted when the residual proves it, |f(w + ε)| ≤ 1e-13 min(t, 1 − t) |f′(w)| (error in t
  /// ≈ |f|/|f′|), which holds while the speed changes by ≲ 1 % per step; else Halley's method goes
  /// on from there (from the cold start if w + ε left (0, 1)).
  /// Cold start: the root of the quadratic part 3t² + P t − D (below the root: f(t₀) = t₀³ > 0).
  /// Halley's method: a step d leaves an error ≈ C d³, C = f″²/(4f′²) + 1/|f′| (f′ < 0 on
  /// [0, 1], f‴ = 6); it stops when that is below 1e-13 min(t, 1 − t), tested without a division:
  /// 1–2 iterations, no libm call but one sqrt.
  double plug_deficit(double s_star, double dt, double t_warm = 0.0) const noexcept {
    const double P = s_star * inv_speed_scale, D = (s_star - dt * rest) * inv_speed_scale;
    const auto cold = [&] { return 2.0 * D / (P + std::sqrt(P * P + 12.0 * D)); };
    double t;
    if (t_warm > 0.0 && t_warm < 1.0) {
      const double w = t_warm, w2 = w * w, f = (w - 3.0) * w2 - P * w + D, f1 = 3.0 * w2 - 6.0 * w - P;
      const double B = 1.0 / f1, A = (3.0 * w - 3.0) * B, x = -f * B, A2 = A * A;
      const double c4 = 5.0 * A * (B - A2), c5 = A2 * (14.0 * A2 - 21.0 * B) + 3.0 * B * B;
      t = w + x * (1.0 + x * (-A + x * ((2.0 * A2 - B) + x * (c4 + x * c5))));
      const double residual = ((t - 3.0) * t * t - P * t + D) * f1;  // f(t) f′(w): compared with f′(w)²
      if (t > 0.0 && t < 1.0) {
        if (std::abs(residual) <= 1e-13 * std::min(t, 1.0 - t) * (f1 * f1)) return t;
      } else {
        t = cold();
      }
    } else {
      t = cold();
    }
    for (int k = 0; k < 8; ++k) {
      const double t2 = t * t, f = (t - 3.0) * t2 - P * t + D, f1 = 3.0 * t2 - 6.0 * t - P, f2 = 6.0 * t - 6.0;
      const double d = 2.0 * f * f1 / (2.0 * f1 * f1 - f * f2);
      t -= d;
      const double ad = std::abs(d);
      if ((0.25 * f2 * f2 - f1) * (ad * ad * ad) <= 1e-13 * std::min(t, 1.0 - t) * (f1 * f1)) break;
    }
    return t;
  }
  /// τ_b(s)/(ρ h) of the steady plug flow at mean speed s.
  double acceleration(double s) const noexcept {
    if (rest == 0.0) return visc * s;
    return s > 0.0 ? rest / (1.0 - plug_deficit(s, 0.0)) : rest;
  }
};

/// Speed after the implicit Bingham step (header comment), then the forest drag. With a memory
/// the step starts from the particle's last ζ = τ_b − τ_y (t = ζ/(τ_y + ζ)) and leaves its new ζ
/// and basal shear rate γ̇_b = ζ/μ_B there (0 at rest: the next start is cold).
inline double speed_after_friction(double s_star, double dt, const BinghamTerms& t) noexcept {
  double s;
  if (t.rest == 0.0) {
    s = s_star / (1.0 + t.visc * dt);
  } else {
    double* const zeta = t.memory.stress;
    if (s_star <= dt * t.rest) {
      if (zeta) *zeta = *t.memory.rate = 0.0;  // at rest: no memory
      return 0.0;
    }
    const double z0 = zeta ? *zeta : 0.0;
    const double u = t.plug_deficit(s_star, dt, z0 > 0.0 ? z0 / (t.tau_y + z0) : 0.0);  // 1 − r
    const double inv_r = 1.0 / (1.0 - u);
    s = t.speed_scale * u * u * (3.0 - u) * inv_r;  // K' (1 − r)²(2 + r)/r, exact as r → 1
    if (zeta) {
      *zeta = t.tau_y * u * inv_r;  // τ_b − τ_y = τ_y (1 − r)/r
      *t.memory.rate = *zeta * t.inv_viscosity;
    }
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
    return {tau_y / (rho * h_n),
            h_n * tau_y / (6.0 * viscosity),
            3.0 * viscosity / (rho * h_n * h_n),
            6.0 * viscosity / (h_n * tau_y),
            tau_y,
            1.0 / viscosity};
  }
};

}  // namespace geohaz::runout
