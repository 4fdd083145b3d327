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
/// middle one; one is negative, one above 1). It is solved in t = 1 − r (plug_root below) to
/// 1e-13 relative in t and 1 − t: from the particle's ζ = τ_b − τ_y of its last step (kept by the
/// solver in the store's BasalExcessStress) by the cubic's reversion series to order 4 and one
/// Newton step, two divisions, accepted when its error bound proves the tolerance (the solver's
/// blocks of particles take it side by side in vector lanes, with the same bits:
/// speed_after_friction_block); else (cold start, or a jump) by Halley's
/// method. Not by the trigonometric formula, whose acos is ill-conditioned near the yield
/// (relative error in the speed up to 20 % at s*/K' = 1e-12, where this root is good to ~2e-13, as
/// up to s*/K' = 1e5) and which costs an acos and a cos per particle-step.
/// τ_y = 0 is the Newtonian film, a = 3 μ_B s/(ρ h²). Forest drag (extra_drag) is applied after the law's step
/// as a second implicit drag step (operator splitting, first order in Δt; it cannot move a particle).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

/// The law's terms for one particle: τ_b(U) of the plug-flow cubic.
struct BinghamTerms {
  double rest;              ///< τ_y/(ρ h) (m/s²)
  double speed_scale;       ///< K' = h τ_y/(6 μ_B) (m/s)
  double visc;              ///< 3 μ_B/(ρ h²) (1/s): the τ_y = 0 (Newtonian) limit
  double inv_speed_scale;   ///< 1/K' = 6 μ_B/(h τ_y) (s/m)
  double tau_y;             ///< τ_y (Pa), to turn the kept ζ into t = ζ/(τ_y + ζ)
  double inv_viscosity;     ///< 1/μ_B (1/(Pa·s)), for the kept γ̇_b = ζ/μ_B
  double extra_drag = 0.0;  ///< forest drag (1/m)
  StepMemory memory{};      ///< the particle's last (ζ, γ̇_b), given by the solver

  /// t = 1 − r = 1 − τ_y/τ_b ∈ (0, 1) after a step and 1/r.
  struct PlugRoot {
    double t, inv_r;
  };
  /// The root after a step from s* of length Δt, s* > Δt a_rest (Δt = 0: the steady relation at
  /// U = s*). With P = s*/K' and D = P − Δt a_rest/K' > 0 the cubic is f(t) = t³ − 3t² − P t + D = 0:
  /// f(0) = D > 0 > f(1) = −2 − Δt a_rest/K', and f is decreasing and concave on [0, 1], so the root
  /// is unique there. It is wanted to 1e-13 relative in both t and 1 − t (1 − r sets the speed near
  /// the plug limit t → 1).
  ///
  /// Warm start (ζ₀ > 0, the particle's τ_b − τ_y of its last step, i.e. w = ζ₀/τ₀ with
  /// τ₀ = τ_y + ζ₀): the cubic is exact around w, f(w + ε) = f + f′ε + (f″/2)ε² + ε³, so its small
  /// root is the reversion series
  /// ε = x − A x² + (2A² − B) x³ + 5A(B − A²) x⁴ + O(x⁵),
  /// x = −f/f′, A = f″/(2f′), B = 1/f′ (f, f′, f″ at w). All four of w, x, A, B come from one
  /// division, 1/(τ₀³ f′(w)) (the numerators are polynomials in ζ₀ and τ₀). The series' terms fall
  /// by ~4|A x| each, which in accelerating flow (|A x| ~ 0.01–0.05) leaves 1e-10 to 1e-6 in t:
  /// one Newton step follows, t = t₄ − r/(1 + δ), where f′ being quadratic gives
  /// f′(w + ε) = f′(w)(1 + δ), δ = 2Aε + 3Bε², exactly, and r = f(w + ε) B = ε − x + Aε² + Bε³ is
  /// computed from ε alone (no cancellation against t). The step leaves
  /// ((3t₄ − 3) e² − e³)/f′(t₄) with e ≈ r/(1 + δ) the error of t₄, i.e. at most
  /// (4/3)³ (|A| + 3|B| (|ε| + |r|)) r² for |δ| ≤ 1/4: accepted when that is below
  /// 1e-13 min(t, 1 − t), else Halley's method goes on from there (from the cold start if the
  /// point left (0, 1)). 1/r = 1/(1 − t) is the second division.
  /// Cold start: the root of the quadratic part 3t² + P t − D (below the root: f(t₀) = t₀³ > 0).
  /// Halley's method: a step d leaves an error ≈ C d³, C = f″²/(4f′²) + 1/|f′| (f′ < 0 on
  /// [0, 1], f‴ = 6); it stops when that is below 1e-13 min(t, 1 − t), tested without a division:
  /// 1–2 iterations, no libm call but one sqrt.
  PlugRoot plug_root(double s_star, double dt, double zeta0) const noexcept {
    const double P = s_star * inv_speed_scale, D = (s_star - dt * rest) * inv_speed_scale;
    PlugRoot root{-1.0, 0.0};
    if (zeta0 > 0.0 && warm_step(P, D, zeta0, root)) return root;
    double t = root.t;
    if (!(t > 0.0 && t < 1.0)) t = 2.0 * D / (P + std::sqrt(P * P + 12.0 * D));
    t = halley(P, D, t);
    return {t, 1.0 / (1.0 - t)};
  }
  /// The warm step (series and Newton step, above) of the cubic (P, D) from ζ₀ > 0: true and the
  /// root where its error bound proves the tolerance, else false with root.t the point reached.
  bool warm_step(double P, double D, double zeta0, PlugRoot& root) const noexcept {
    bool ok;
    warm_lanes(tau_y, P, D, zeta0, root.t, root.inv_r, ok);
    return ok;
  }
  /// warm_step for one particle (T = double) or several side by side (T = DoubleLanes, each lane
  /// with its own law and state), written once so that both give the same bits: t is the point
  /// reached and inv_r = 1/(1 − t), an answer where ok.
  template <class T, class Mask>
  [[gnu::always_inline]] static void warm_lanes(const T& tau_y, const T& P, const T& D, const T& zeta0, T& t, T& inv_r,
                                                Mask& ok) noexcept {
    const T z = zeta0, tau = tau_y + z, tau2 = tau * tau, tau3 = tau2 * tau;
    const T n1 = (3.0 * z - 6.0 * tau) * z - P * tau2;             // τ₀² f′(w)
    const T n0 = ((z - 3.0 * tau) * z - P * tau2) * z + D * tau3;  // τ₀³ f(w)
    const T X = 1.0 / (tau * n1), x = -n0 * X, B = tau3 * X, A = -3.0 * tau_y * tau2 * X;
    const T c3 = 2.0 * A * A - B, c4 = 5.0 * A * (B - A * A);
    const T e = x * ((1.0 - A * x) + (x * x) * (c3 + c4 * x)), t4 = z * n1 * X + e;
    const T r = (e - x) + e * e * (A + B * e), d = e * (2.0 * A + 3.0 * B * e);
    t = t4 - r / (1.0 + d);
    const T one_minus = 1.0 - t4, near = t4 < one_minus ? t4 : one_minus;  // min(t₄, 1 − t₄)
    const T abs_a = A < 0.0 ? T(-A) : A, abs_b = B < 0.0 ? T(-B) : B, abs_e = e < 0.0 ? T(-e) : e,
            abs_r = r < 0.0 ? T(-r) : r;
    ok = (t4 > 0.0) & (t4 < 1.0) & (d * d <= 0.0625) &
         ((abs_a + 3.0 * abs_b * (abs_e + abs_r)) * (r * r) <= 4.2e-14 * near);
    inv_r = 1.0 / (1.0 - t);
  }
  /// At u = 1 − r: the speed K' (1 − r)²(2 + r)/r (exact as r → 1) and ζ = τ_b − τ_y = τ_y (1 − r)/r,
  /// for one particle or several side by side.
  template <class T>
  [[gnu::always_inline]] static void plug_state(const T& speed_scale, const T& tau_y, const T& u, const T& inv_r,
                                                T& speed, T& zeta) noexcept {
    speed = speed_scale * u * u * (3.0 - u) * inv_r;
    zeta = tau_y * u * inv_r;
  }
  /// Halley's method on the plug cubic from t (above).
  static double halley(double P, double D, double t) noexcept {
    for (int k = 0; k < 8; ++k) {
      const double t2 = t * t, f = (t - 3.0) * t2 - P * t + D, f1 = 3.0 * t2 - 6.0 * t - P, f2 = 6.0 * t - 6.0;
      const double d = 2.0 * f * f1 / (2.0 * f1 * f1 - f * f2);
      t -= d;
      const double ad = std::abs(d);
      if ((0.25 * f2 * f2 - f1) * (ad * ad * ad) <= 1e-13 * std::min(t, 1.0 - t) * (f1 * f1)) break;
    }
    return t;
  }
  /// plug_root's t, from the particle's last t (t_warm ∈ (0, 1), i.e. ζ₀ = τ_y t/(1 − t)) or cold.
  double plug_deficit(double s_star, double dt, double t_warm = 0.0) const noexcept {
    const double z0 = t_warm > 0.0 && t_warm < 1.0 ? tau_y * t_warm / (1.0 - t_warm) : 0.0;
    return plug_root(s_star, dt, z0).t;
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
    const auto [u, inv_r] = t.plug_root(s_star, dt, zeta ? *zeta : 0.0);  // 1 − r, 1/r
    double excess;
    BinghamTerms::plug_state(t.speed_scale, t.tau_y, u, inv_r, s, excess);
    if (zeta) *zeta = excess, *t.memory.rate = excess * t.inv_viscosity;
  }
  return speed_after_drag(s, t.extra_drag * dt);
}

/// The steps of a block of particles, bit for bit those of speed_after_friction: the warm step of
/// the plug cubic for V's lanes side by side (warm_lanes); a particle that stops, has no memory,
/// is a Newtonian film (τ_y = 0) or whose warm step is not accepted takes speed_after_friction.
template <class V>
[[gnu::always_inline]] inline void lane_block(std::span<const double> s_star, double dt,
                                              std::span<const BinghamTerms> t, std::span<double> s) noexcept {
  constexpr std::size_t lanes = sizeof(V) / sizeof(double);
  std::size_t k = 0;
  for (; k + lanes <= s.size(); k += lanes) {
    V rest, scale, inv_scale, tau_y, ss, zeta0;
    for (std::size_t l = 0; l < lanes; ++l) {
      const BinghamTerms& tl = t[k + l];
      rest[l] = tl.rest, scale[l] = tl.speed_scale, inv_scale[l] = tl.inv_speed_scale, tau_y[l] = tl.tau_y;
      ss[l] = s_star[k + l];
      zeta0[l] = tl.memory.stress ? *tl.memory.stress : 0.0;
    }
    const V P = ss * inv_scale, D = (ss - dt * rest) * inv_scale;
    V u, inv_r;
    decltype(P > 0.0) ok;
    BinghamTerms::warm_lanes(tau_y, P, D, zeta0, u, inv_r, ok);
    ok &= (zeta0 > 0.0) & (rest != 0.0) & (ss > dt * rest);
    V speed, zeta;
    BinghamTerms::plug_state(scale, tau_y, u, inv_r, speed, zeta);
    for (std::size_t l = 0; l < lanes; ++l) {
      const BinghamTerms& tl = t[k + l];
      if (!ok[l]) {
        s[k + l] = speed_after_friction(s_star[k + l], dt, tl);
        continue;
      }
      *tl.memory.stress = zeta[l], *tl.memory.rate = zeta[l] * tl.inv_viscosity;
      s[k + l] = speed_after_drag(speed[l], tl.extra_drag * dt);
    }
  }
  for (; k < s.size(); ++k) s[k] = speed_after_friction(s_star[k], dt, t[k]);
}

struct BinghamFriction {
  static constexpr std::array<ParamSpec, 2> parameters{{kYieldStressParameter, kBinghamViscosityParameter}};
  double tau_y = kYieldStressParameter.def;           ///< yield stress τ_y (Pa)
  double viscosity = kBinghamViscosityParameter.def;  ///< plastic viscosity μ_B (Pa·s)
  static constexpr const char* name = "bingham";
  static constexpr const char* summary =
      "Bingham plastic, exact plug-flow cubic (tau_y, viscosity; Pastor et al. 2004)";
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? tau_y : viscosity) = v, true; }
  /// The per-particle coefficients with one division: the reciprocals of ρh, μ_B and hτ_y all
  /// follow from 1/(ρ h τ_y μ_B) (τ_y = 0: the Newtonian film, rest = 0).
  BinghamTerms terms(double /*g*/, double /*g_n*/, double h_n, double /*speed*/, double rho) const noexcept {
    const double rh = rho * h_n;
    if (!(tau_y > 0.0)) return {0.0, 0.0, 3.0 * viscosity / (rh * h_n), HUGE_VAL, tau_y, 1.0 / viscosity};
    const double tv = tau_y * viscosity, x = 1.0 / (rh * tv), inv_rh = tv * x, inv_viscosity = rh * tau_y * x;
    return {tau_y * inv_rh,
            h_n * tau_y * inv_viscosity * (1.0 / 6.0),
            3.0 * viscosity * rho * (inv_rh * inv_rh),
            6.0 * viscosity * viscosity * rho * x,
            tau_y,
            inv_viscosity};
  }
};

}  // namespace geohaz::runout
