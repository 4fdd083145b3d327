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
/// (both below the root of U = b), safeguarded by bisection, to a relative 1e-12. Forest drag
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
  /// The excess stress ζ with U(ζ) + c ζ = b (b > 0, c ≥ 0).
  double excess_stress(double b, double c) const noexcept {
    const double a = (n + 1.0) / (2.0 * n + 1.0), hn = n * h;
    // Asymptotic inverses: U ≈ (n h/(2n+1)) (ζ/K)^{1/n} for ζ ≫ τ_y, (n h/(n+1)) (ζ/K)^{1/n} ζ/τ_y for ζ ≪ τ_y.
    double z = consistency * std::pow(b / (a * hn / (n + 1.0)), n);
    if (tau_y > 0.0)
      z = std::max(z, std::pow(std::pow(consistency, 1.0 / n) * b * (n + 1.0) * tau_y / hn, n / (n + 1.0)));
    const double log_k = std::log(consistency), inv_n = 1.0 / n;
    double y = std::log(z), lo = -1e300, hi = 1e300;
    for (int it = 0; it < 60; ++it) {
      const double zeta = std::exp(y), tau = tau_y + zeta;
      const double u = hn / (n + 1.0) * std::exp((y - log_k) * inv_n) * zeta * (a * zeta + tau_y) / (tau * tau);
      const double gval = u + c * zeta - b;
      (gval > 0.0 ? hi : lo) = y;
      // dG/d ln ζ = U (1 + 1/n + aζ/(aζ + τ_y) − 2ζ/τ) + c ζ  (> 0).
      const double slope = u * (1.0 + inv_n + a * zeta / (a * zeta + tau_y) - 2.0 * zeta / tau) + c * zeta;
      double step = gval / slope;
      double next = y - step;
      if (!(next > lo && next < hi) && lo > -1e299 && hi < 1e299) {
        next = 0.5 * (lo + hi);
        step = y - next;
      }
      y = next;
      if (std::abs(step) < 1e-12) break;
    }
    return std::exp(y);
  }
  /// τ_b(s)/(ρ h) of the steady layer at mean speed s.
  double acceleration(double s) const noexcept { return s > 0.0 ? (tau_y + excess_stress(s, 0.0)) / (rho * h) : rest; }
};

/// Speed after the implicit Herschel–Bulkley step (header comment), then the forest drag.
inline double speed_after_friction(double s_star, double dt, const HerschelBulkleyTerms& t) noexcept {
  const double b = s_star - dt * t.rest;
  if (b <= 0.0) return 0.0;
  // s = U(ζ) rather than b − Δt ζ/(ρ h), which cancels as the particle comes to rest.
  const double s = t.mean_speed(t.excess_stress(b, dt / (t.rho * t.h)));
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
