#pragma once
/// \file herschel_bulkley.hpp
/// Herschel–Bulkley fluid (τ = τ_y + K γ̇ⁿ where sheared, rigid where |τ| < τ_y; Herschel &
/// Bulkley 1926; for muddy debris flows n ≈ 1/3, Coussot 1997) in its exact depth-averaged form.
/// In steady uniform flow the shear stress falls linearly from τ_b at the bed to 0 at the surface;
/// integrating K (du/dz)ⁿ = τ − τ_y below the yield height and averaging over the depth gives the
/// mean speed (ζ = τ_b − τ_y, the excess basal stress)
///
///     U(τ_b) = (n h/(n + 1)) (ζ/K)^{1/n} ζ ((n + 1) ζ/(2n + 1) + τ_y) / τ_b²,
///
/// and the plug speed u_p = (n h/(n + 1)) (ζ/K)^{1/n} ζ/τ_b (n = 1: Bingham's plug-flow cubic;
/// τ_y = 0: the power-law film U = (n/(2n + 1)) h (τ_b/K)^{1/n}). No approximation of U(τ_b) is
/// used; the yield is at τ_b = τ_y exactly.
///
/// Implicit step: s = s* − Δt τ_b/(ρ h) with s = U(τ_b), i.e. G(ζ) = U(ζ) + Δt ζ/(ρ h) − b = 0,
/// b = s* − Δt τ_y/(ρ h) (stop when b ≤ 0). G increases with ζ; it is solved by Newton's method in
/// ln ζ (U is close to a power of ζ at both ends) from the larger of the two asymptotic inverses
/// (both below the root of U = b), safeguarded by bisection, to a relative 1e-12; ζ and
/// (ζ/K)^{1/n} are updated by factors e^{−δ}, e^{−δ/n} from a Taylor polynomial once the steps δ
/// are small (about 4 iterations and 3 libm pows per particle-step). Forest drag
/// (extra_drag) follows as a second implicit drag step (operator splitting).

#include <algorithm>
#include <cmath>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

/// The law's terms for one particle.
struct HerschelBulkleyTerms {
  double rest;  ///< τ_y/(ρ h) (m/s²)
  double tau_y, consistency, n, h, rho;
  double extra_drag = 0.0;  ///< forest drag (1/m)

  /// Mean speed of the steady layer at excess basal stress ζ > 0 (m/s).
  double mean_speed(double zeta) const noexcept {
    const double tau = tau_y + zeta;
    return n * h / (n + 1.0) * std::pow(zeta / consistency, 1.0 / n) * zeta *
           ((n + 1.0) / (2.0 * n + 1.0) * zeta + tau_y) / (tau * tau);
  }
  /// e^x for |x| ≤ 1/4 by its Taylor polynomial (degree 6 for |x| < 1e-3, else 14; truncation
  /// < 1e-20, below round-off): the Newton updates below are small, and this costs a fraction of
  /// a libm exp.
  static double small_exp(double x) noexcept {
    if (std::abs(x) < 1e-3)
      return 1.0 + x * (1.0 + x * (1.0 / 2 + x * (1.0 / 6 + x * (1.0 / 24 + x * (1.0 / 120 + x * (1.0 / 720))))));
    double p = 1.0 / 87178291200.0;  // 1/14!
    constexpr double inv_fact[14] = {
        1.0,        1.0,         1.0 / 2,      1.0 / 6,       1.0 / 24,       1.0 / 120,       1.0 / 720,
        1.0 / 5040, 1.0 / 40320, 1.0 / 362880, 1.0 / 3628800, 1.0 / 39916800, 1.0 / 479001600, 1.0 / 6227020800};
    for (int k = 13; k >= 0; --k) p = inv_fact[k] + x * p;
    return p;
  }
  /// Root of U(ζ) + c ζ = b (b > 0, c ≥ 0): ζ and U(ζ).
  struct Root {
    double zeta, speed;
  };
  Root excess_stress(double b, double c) const noexcept {
    const double a = (n + 1.0) / (2.0 * n + 1.0), inv_n = 1.0 / n, c0 = n * h / (n + 1.0);
    // Start at the larger asymptotic inverse: U ≈ a c0 q for ζ ≫ τ_y, U ≈ c0 q ζ/τ_y for ζ ≪ τ_y,
    // q = (ζ/K)^{1/n}; both lie above U, so the start is below the root. Each gives q without a pow.
    double q = b / (a * c0), zeta = consistency * std::pow(q, n);
    if (tau_y > 0.0) {
      const double zb = std::pow(b * tau_y * std::pow(consistency, inv_n) / c0, n / (n + 1.0));
      if (zb > zeta) zeta = zb, q = b * tau_y / (c0 * zb);
    }
    // Newton in y = ln(ζ/ζ₀) (U is close to a power of ζ at both ends), bracketed.
    const double zeta0 = zeta, q0 = q;
    double y = 0.0, lo = -HUGE_VAL, hi = HUGE_VAL, u = 0.0;
    for (int it = 0; it < 60; ++it) {
      const double tau = tau_y + zeta;
      u = c0 * q * zeta * (a * zeta + tau_y) / (tau * tau);
      const double gval = u + c * zeta - b;
      (gval > 0.0 ? hi : lo) = y;
      // dG/d ln ζ = U (1 + 1/n + aζ/(aζ + τ_y) − 2ζ/τ) + c ζ  (> 0).
      const double slope = u * (1.0 + inv_n + a * zeta / (a * zeta + tau_y) - 2.0 * zeta / tau) + c * zeta;
      double step = gval / slope;
      if (!(y - step > lo && y - step < hi) && lo > -HUGE_VAL && hi < HUGE_VAL) step = y - 0.5 * (lo + hi);
      y -= step;
      if (std::abs(step * inv_n) <= 0.25 && std::abs(step) <= 0.25) {
        zeta *= small_exp(-step);
        q *= small_exp(-step * inv_n);
      } else {
        zeta = zeta0 * std::exp(y);
        q = q0 * std::exp(y * inv_n);
      }
      // Quadratic convergence: after a step δ the error is O(δ²), here < 1e-12 in ln ζ.
      if (std::abs(step) < 1e-6) break;
    }
    const double tau = tau_y + zeta;
    return {zeta, c0 * q * zeta * (a * zeta + tau_y) / (tau * tau)};
  }
  /// τ_b(s)/(ρ h) of the steady layer at mean speed s.
  double acceleration(double s) const noexcept {
    return s > 0.0 ? (tau_y + excess_stress(s, 0.0).zeta) / (rho * h) : rest;
  }
};

/// Speed after the implicit Herschel–Bulkley step (header comment), then the forest drag.
inline double speed_after_friction(double s_star, double dt, const HerschelBulkleyTerms& t) noexcept {
  const double b = s_star - dt * t.rest;
  if (b <= 0.0) return 0.0;
  // s = U(ζ) rather than b − Δt ζ/(ρ h), which cancels as the particle comes to rest.
  const double s = t.excess_stress(b, dt / (t.rho * t.h)).speed;
  return speed_after_drag(std::min(s, b), t.extra_drag * dt);
}

struct HerschelBulkleyFriction {
  double tau_y = 100.0;           ///< yield stress τ_y (Pa)
  double consistency = 30.0;      ///< consistency K (Pa·sⁿ)
  double flow_index = 1.0 / 3.0;  ///< flow index n (1): < 1 shear-thinning
  static constexpr const char* name = "herschel_bulkley";
  static constexpr const char* summary =
      "Herschel-Bulkley fluid, exact depth-averaged plug flow (tau_y, consistency, flow_index; Coussot 1997)";
  HerschelBulkleyTerms terms(double /*g*/, double /*g_n*/, double h_n, double /*speed*/, double rho) const noexcept {
    return {tau_y / (rho * h_n), tau_y, consistency, flow_index, h_n, rho};
  }
};

}  // namespace geohaz::runout
