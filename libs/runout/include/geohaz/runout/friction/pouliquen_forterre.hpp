#pragma once
/// \file pouliquen_forterre.hpp
/// The depth-averaged granular friction law of Pouliquen & Forterre (2002), the depth-averaged
/// form of μ(I): from the stopping thickness of a layer on a rough incline,
///
///     h_stop(θ) = L (tan δ₂ − tan θ)/(tan θ − tan δ₁),
///
/// and the flow rule of steady uniform flows Fr = u/√(g h cos θ) = β h/h_stop(θ) − γ (Pouliquen
/// 1999 with γ = 0; Forterre & Pouliquen 2003 with an offset γ), the basal friction coefficient is
///
///     μ(h, Fr) = tan δ₁ + (tan δ₂ − tan δ₁)/(1 + β h/(L (Fr + γ)))    for Fr + γ ≥ β,
///     μ(h, Fr) = μ_stop(h) = tan δ₁ + (tan δ₂ − tan δ₁)/(1 + h/L)       for Fr + γ < β,
///
/// τ_b = μ ρ g_n h_n, Fr = s/√(g_n h_n). The second line is the κ → 0 limit of Pouliquen &
/// Forterre's intermediate branch (their κ = 10⁻³), with their starting angle δ₃ taken equal to δ₁
/// (no start/stop hysteresis, which a per-step law without memory cannot tell apart): μ is then
/// continuous and non-decreasing in Fr, and μ_stop(h) g_n is the yield part a_rest. A layer
/// thinner than h_stop(θ) therefore stops and stays at rest; a thicker one reaches
/// Fr = β h/h_stop(θ) − γ.
///
/// Implicit step: if s* ≤ Δt a_rest the particle stops; if the plateau step s = s* − Δt a_rest has
/// Fr + γ ≤ β it is the root; otherwise, with x = Fr + γ, w = √(g_n h_n), c = β h/L,
/// b = s* − Δt g_n tan δ₁ + w γ and D = Δt g_n (tan δ₂ − tan δ₁), the step is the positive root of
/// w x² + (w c − b + D) x − b c = 0, s = w (x − γ). Forest drag follows as a second implicit drag
/// step (operator splitting).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <optional>
#include <string>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

/// The law's terms for one particle.
struct PouliquenForterreTerms {
  double rest;              ///< μ_stop(h) g_n (m/s²)
  double g_n;               ///< bed-normal gravity (m/s²)
  double tan1, dtan;        ///< tan δ₁, tan δ₂ − tan δ₁
  double c;                 ///< β h/L
  double w;                 ///< √(g_n h_n) (m/s)
  double beta, gamma;       ///< flow rule
  double extra_drag = 0.0;  ///< forest drag (1/m)

  double acceleration(double s) const noexcept {
    const double x = s / w + gamma;
    return x <= beta ? rest : g_n * (tan1 + dtan * x / (x + c));
  }
};

inline double speed_after_friction(double s_star, double dt, const PouliquenForterreTerms& t) noexcept {
  if (!(t.w > 0.0)) return speed_after_drag(s_star, t.extra_drag * dt);  // off the bed: no normal stress
  const double sp = s_star - dt * t.rest;
  if (sp <= 0.0) return 0.0;
  double s = sp;
  if (sp / t.w + t.gamma > t.beta) {
    const double b = s_star - dt * t.g_n * t.tan1 + t.w * t.gamma;
    const double bb = t.w * t.c - b + dt * t.g_n * t.dtan, disc = std::sqrt(bb * bb + 4.0 * t.w * b * t.c);
    const double x = bb >= 0.0 ? 2.0 * b * t.c / (bb + disc) : (disc - bb) / (2.0 * t.w);
    s = std::max(t.w * (x - t.gamma), 0.0);
  }
  return speed_after_drag(s, t.extra_drag * dt);
}

struct PouliquenForterreFriction {
  // Defaults: 0.5 mm glass beads on a rough bed (Forterre & Pouliquen 2003): δ₁ = 20.9°,
  // δ₂ = 32.76°, L = 0.65 mm, β = 0.136, γ = 0. The angles are read in degrees and held as their
  // tangents (the struct's tangents are the published ones, which round to the degrees to 0.01°:
  // a test checks it).
  static constexpr std::array<ParamSpec, 5> parameters{
      {{"delta1", 20.9, Range::open_closed(0.0, 60.0), "deg", "δ₁: slope below which no layer flows"},
       {"delta2", 32.76, Range::open_closed(0.0, 80.0), "deg", "δ₂ > δ₁: slope above which no layer stops"},
       {"hstop_length", 6.5e-4, Range::open_closed(0.0, 100.0), "m",
        "L of h_stop(θ) = L (tan δ₂ − tan θ)/(tan θ − tan δ₁)", "a few grain diameters"},
       {"flow_rule_beta", 0.136, Range::open_closed(0.0, 10.0), "1",
        "β of the flow rule u/√(g h cos θ) = β h/h_stop − γ"},
       {"flow_rule_gamma", 0.0, Range::closed(0.0, 10.0), "1", "γ of the flow rule u/√(g h cos θ) = β h/h_stop − γ"}}};
  double tan_delta1 = 0.38186;        ///< tan δ₁ (1): below δ₁ no layer flows
  double tan_delta2 = 0.64347;        ///< tan δ₂ (1): above δ₂ no layer stops
  double length = parameters[2].def;  ///< L (m), the h_stop length scale (about a grain diameter)
  double beta = parameters[3].def;    ///< β of the flow rule (1)
  double gamma = parameters[4].def;   ///< γ of the flow rule (1)
  static constexpr const char* name = "pouliquen";
  static constexpr const char* summary =
      "Pouliquen-Forterre mu(Fr, h) with h_stop (delta1, delta2, hstop_length, flow_rule_beta, flow_rule_gamma; P&F "
      "2002)";
  /// δ₁, δ₂ in degrees (as model.delta1, model.delta2); the law holds their tangents.
  bool set(std::size_t j, double v) noexcept {
    if (j < 2) return (j == 0 ? tan_delta1 : tan_delta2) = std::tan(v * std::numbers::pi / 180.0), true;
    return (j == 2 ? length : j == 3 ? beta : gamma) = v, true;
  }
  static std::optional<ParamProblem> check(const ParamValues& v) {
    if (!(v["delta2"] > v["delta1"]))
      return ParamProblem{"delta2", "model.delta2 must exceed model.delta1 (" + std::to_string(v["delta1"]) + " deg)",
                          std::to_string(v["delta2"])};
    return std::nullopt;
  }
  /// h_stop(θ) (m) on a slope tan θ (infinite at or below δ₁, 0 at or above δ₂).
  double h_stop(double tan_theta) const noexcept {
    const double t1 = tan_delta1, t2 = tan_delta2;
    if (tan_theta <= t1) return HUGE_VAL;
    return std::max(length * (t2 - tan_theta) / (tan_theta - t1), 0.0);
  }
  PouliquenForterreTerms terms(double /*g*/, double g_n, double h_n, double /*speed*/, double /*rho*/) const noexcept {
    const double t1 = tan_delta1, t2 = tan_delta2;
    const double mu_stop = t1 + (t2 - t1) / (1.0 + h_n / length);
    return {g_n * mu_stop, g_n, t1, t2 - t1, beta * h_n / length, std::sqrt(g_n * h_n), beta, gamma};
  }
};

}  // namespace geohaz::runout
