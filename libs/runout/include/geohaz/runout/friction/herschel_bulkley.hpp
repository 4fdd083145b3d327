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
/// b = s* − Δt τ_y/(ρ h) (stop when b ≤ 0). G increases with ζ; it is solved by Halley's method
/// in ln ζ (U is close to a power of ζ at both ends), safeguarded by Newton steps and bisection, to
/// an estimated 1e-13 in ln ζ. From the particle's (ζ, (ζ/K)^{1/n}) of its last step, kept by the
/// solver in the store (BasalExcessStress, BasalShearRate; a warm start), one evaluation and a
/// sixth-order series step usually prove that tolerance (series_step; the solver steps its
/// particles in blocks, several series steps side by side in vector lanes, with the same bits:
/// speed_after_friction_block); where they do not, the
/// iteration runs from there (one or two iterations and no libm call). Without it, it starts from
/// the larger of the two asymptotic inverses (both below the root of U = b; three pows). ζ and
/// (ζ/K)^{1/n} are updated by the factors e^{−δ}, e^{−δ/n} from Padé approximants while the steps
/// are small. Forest drag
/// (extra_drag) follows as a second implicit drag step (operator splitting).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

/// The law's terms for one particle.
struct HerschelBulkleyTerms {
  double rest;  ///< τ_y/(ρ h) (m/s²)
  double tau_y, consistency, n, h, rho;
  double extra_drag = 0.0;  ///< forest drag (1/m)
  StepMemory memory{};      ///< the particle's last (ζ, (ζ/K)^{1/n}), given by the solver

  /// Mean speed of the steady layer at excess basal stress ζ > 0 (m/s).
  double mean_speed(double zeta) const noexcept {
    const double tau = tau_y + zeta;
    return n * h / (n + 1.0) * std::pow(zeta / consistency, 1.0 / n) * zeta *
           ((n + 1.0) / (2.0 * n + 1.0) * zeta + tau_y) / (tau * tau);
  }
  /// e^x for |x| ≤ 1/4 to round-off (truncation < 5e-17 relative) without libm: its Taylor
  /// polynomial of degree 3 for |x| < 1e-4, else the diagonal Padé approximant P_m(x)/P_m(−x) of
  /// order m = 3 (|x| < 0.02), 4 (|x| < 0.1) or 5, whose error is about
  /// (m!)²/((2m)! (2m + 1)!) |x|^{2m+1}. The updates of the iteration below are small, and this
  /// costs a fraction of a libm exp.
  static double small_exp(double x) noexcept {
    const double ax = std::abs(x), x2 = x * x;
    if (ax < 1e-4) return 1.0 + x * (1.0 + x * (1.0 / 2 + x * (1.0 / 6)));
    double even, odd;  // the even and odd parts of P_m
    if (ax < 0.02) {
      even = 1.0 + x2 * (1.0 / 10), odd = x * (1.0 / 2 + x2 * (1.0 / 120));
    } else if (ax < 0.1) {
      even = 1.0 + x2 * (3.0 / 28 + x2 * (1.0 / 1680)), odd = x * (1.0 / 2 + x2 * (1.0 / 84));
    } else {
      even = 1.0 + x2 * (1.0 / 9 + x2 * (1.0 / 1008)), odd = x * (1.0 / 2 + x2 * (1.0 / 72 + x2 * (1.0 / 30240)));
    }
    return (even + odd) / (even - odd);
  }
  /// Root of U(ζ) + c ζ = b (b > 0, c ≥ 0): ζ, U(ζ) and the basal shear rate (ζ/K)^{1/n}.
  struct Root {
    double zeta, speed, rate;
  };
  /// From (ζ₀, (ζ₀/K)^{1/n}) = (zeta0, rate0) when both are > 0 (a warm start: the particle's last
  /// step), else from the cold start below.
  Root excess_stress(double b, double c, double zeta0 = 0.0, double rate0 = 0.0) const noexcept {
    double zeta = zeta0, q = rate0;
    const double u = solve(b, c, zeta, q);
    return {zeta, u, q};
  }
  /// The cold start at the larger asymptotic inverse: U ≈ a c0 q for ζ ≫ τ_y, U ≈ c0 q ζ/τ_y for
  /// ζ ≪ τ_y, q = (ζ/K)^{1/n}; both lie above U, so the start is below the root. Each gives q
  /// without a pow. Out of line: the warm start is the common case.
  [[gnu::noinline]] void cold_start(double b, double& zeta, double& q) const noexcept {
    const double a = (n + 1.0) / (2.0 * n + 1.0), c0 = n * h / (n + 1.0);
    q = b / (a * c0), zeta = consistency * std::pow(q, n);
    if (tau_y > 0.0) {
      const double zb = std::pow(b * tau_y * std::pow(consistency, 1.0 / n) / c0, n / (n + 1.0));
      if (zb > zeta) zeta = zb, q = b * tau_y / (c0 * zb);
    }
  }
  /// The derivatives σ^(j), j = 1..5, of the logistic function (σ' = σ(1 − σ)) as polynomials in
  /// its value f: the y-derivatives of f_a, f_z and −ρ below.
  template <class T>
  [[gnu::always_inline]] static std::array<T, 5> logistic_derivatives(const T& f) noexcept {
    const T g = f * (1.0 - f), e = 1.0 - 2.0 * f;
    return {g, g * e, g * (1.0 - 6.0 * g), g * e * (1.0 - 12.0 * g), g * (1.0 + g * (-30.0 + 120.0 * g))};
  }
  /// The warm step in one evaluation (series_step for one particle, series_lanes for several side
  /// by side). With B(y) = b − cζ₀e^y the root of G is the root of
  ///   H(y) = ln U(y) − ln B(y),   y = ln(ζ/ζ₀),
  /// which is nearly linear: H' = p + ρ (ρ = cζ/B), and since ln U = const + (1 + 1/n) y + ln w −
  /// 2 ln τ with f_a' = f_a(1 − f_a), f_z' = f_z(1 − f_z), ρ' = ρ(1 + ρ), every higher derivative is
  /// a polynomial in f_a, f_z and ρ: H^(k) = σ^(k−1)(f_a) − 2 σ^(k−1)(f_z) − σ^(k−1)(−ρ), with σ^(j)
  /// the logistic function's derivatives in its value. H(0) = ln(U₀/B₀) = 2 artanh s,
  /// s = (U₀ − B₀)/(U₀ + B₀), by its series to s¹³ (|s| < 0.1: truncation < 2e-16). The Taylor
  /// series of H to order 6 is reverted, y = t + c₂t² + … + c₆t⁶ with t = −H(0)/H'(0), a_k =
  /// H^(k)/(k! H'). Its terms fall by a factor ~4|t a₂| each (the series of the quadratic's root);
  /// the step is accepted when the last one times 8|t|√(3(a₂² + a₃² + a₄²)) (≥ 8|t|(|a₂| + |a₃| +
  /// |a₄|)), the estimate of what is left, is below 1e-13, as the iteration below is solved to, and
  /// |t| ≤ 0.05 (the omitted a₇t⁷ < 1e-13); these tests are made on squares (no absolute values,
  /// the same code for one or several particles); else nothing is changed and the iteration runs.
  /// The speed returned is B(y) = b − cζ, which with ρ < 1 < p carries less of the error in y than
  /// U(ζ) (ρ against p). ζ = ζ₀e^y by the Taylor polynomial of e^y to degree 9 (|y| ≤ 0.1:
  /// truncation < 3e-17), (ζ/K)^{1/n} by the (5, 5) Padé approximant of small_exp (|y/n| ≤ 1/4:
  /// < 3e-17) without its branches.
  bool series_step(double b, double c, double& zeta_io, double& q_io, double& speed) const noexcept {
    bool ok;
    series_lanes(tau_y, n, h, b, c, zeta_io, q_io, speed, ok);
    return ok;
  }
  /// series_step for T = double, or for several particles side by side (T = DoubleLanes or
  /// DoubleLanes4, each lane with its own law and state), written once so that both give the same
  /// bits: every test is a mask, and where it fails the lane's (ζ, q) is left as it was (ok false
  /// there). The start is tested here too (warm()).
  template <class T, class Mask>
  [[gnu::always_inline]] static void series_lanes(const T& tau_y, const T& n, const T& h, const T& b, const T& c,
                                                  T& zeta_io, T& q_io, T& speed, Mask& ok) noexcept {
    const T a = (n + 1.0) / (2.0 * n + 1.0), inv_n = 1.0 / n, c0 = n * h / (n + 1.0);
    const T z0 = zeta_io, q0 = q_io, az = a * z0, w = az + tau_y, tau = tau_y + z0, cz = c * z0, b0 = b - cz;
    const T num = c0 * q0 * z0 * w, den = b0 * (tau * tau);  // U₀ = num/τ², B₀ = den/τ²
    const T sg = (num - den) / (num + den), rho = cz / b0, s2 = sg * sg;
    ok = (z0 > 0.0) & (q0 > 0.0) & (z0 < HUGE_VAL) & (q0 < HUGE_VAL) & (s2 < 0.01) & (rho >= 0.0) & (rho < 1.0);
    const T fa = az / w, fz = z0 / tau;
    const std::array<T, 5> da = logistic_derivatives(fa), dz = logistic_derivatives(fz);
    const std::array<T, 5> dr = logistic_derivatives(T(-rho));
    const T ih1 = 1.0 / (1.0 + inv_n + fa - 2.0 * fz + rho);
    constexpr std::array<double, 5> inv_fact{1.0 / 2, 1.0 / 6, 1.0 / 24, 1.0 / 120, 1.0 / 720};
    std::array<T, 5> ak;  // a_2 … a_6
    for (std::size_t j = 0; j < 5; ++j) ak[j] = (da[j] - 2.0 * dz[j] - dr[j]) * (inv_fact[j] * ih1);
    const T a2 = ak[0], a3 = ak[1], a4 = ak[2], a5 = ak[3], a6 = ak[4], a22 = a2 * a2;
    const T c2 = -a2, c3 = 2.0 * a22 - a3, c4 = a2 * (5.0 * (a3 - a22)) - a4;
    const T c5 = a22 * (14.0 * a22 - 21.0 * a3) + 6.0 * a2 * a4 + 3.0 * a3 * a3 - a5;
    const T c6 =
        a22 * (a2 * (84.0 * a3 - 42.0 * a22) - 28.0 * a4) - 28.0 * a2 * a3 * a3 + 7.0 * (a2 * a5 + a3 * a4) - a6;
    const T s4 = s2 * s2;
    const T h0 = 2.0 * sg *
                 ((1.0 + s2 * (1.0 / 3)) +
                  s4 * ((1.0 / 5 + s2 * (1.0 / 7)) + s4 * ((1.0 / 9 + s2 * (1.0 / 11)) + s4 * (1.0 / 13))));
    const T t = -h0 * ih1, t2 = t * t, t3 = t2 * t;
    const T y = t * ((1.0 + c2 * t) + t2 * (c3 + c4 * t) + t3 * t * (c5 + c6 * t));
    const T y2 = y * y, y4 = y2 * y2, t6 = t3 * t3;
    ok = ok & ((c6 * c6) * (t6 * t6) * (192.0 * t2 * (a22 + a3 * a3 + a4 * a4)) < 1e-26) & (t2 <= 0.0025) &
         (y2 * (inv_n * inv_n) <= 0.0625);
    const T ey = (1.0 + y) + y2 * (1.0 / 2 + y * (1.0 / 6)) +
                 y4 * ((1.0 / 24 + y * (1.0 / 120)) + y2 * (1.0 / 720 + y * (1.0 / 5040)) +
                       y4 * (1.0 / 40320 + y * (1.0 / 362880)));
    const T x = y * inv_n, x2 = x * x;
    const T even = 1.0 + x2 * (1.0 / 9 + x2 * (1.0 / 1008)), odd = x * (1.0 / 2 + x2 * (1.0 / 72 + x2 * (1.0 / 30240)));
    zeta_io = ok ? T(z0 * ey) : z0;
    q_io = ok ? T(q0 * ((even + odd) / (even - odd))) : q0;
    speed = b - c * zeta_io;
  }
  /// Whether (ζ, q) is a usable start (a particle's last step, both positive and finite).
  static bool warm(double zeta, double q) noexcept { return zeta > 0.0 && q > 0.0 && zeta < HUGE_VAL && q < HUGE_VAL; }
  /// excess_stress in place: (zeta, q) from the start to the root; returns U at the root (the
  /// series step from a warm start, else the iteration below).
  double solve(double b, double c, double& zeta_io, double& q_io) const noexcept {
    double speed;
    if (warm(zeta_io, q_io) && series_step(b, c, zeta_io, q_io, speed)) return speed;
    return iterate(b, c, zeta_io, q_io);
  }
  /// solve's iteration, from the warm start or (without one) the cold start. Out of line: the
  /// series step is the common case.
  [[gnu::noinline]] double iterate(double b, double c, double& zeta_io, double& q_io) const noexcept {
    const double a = (n + 1.0) / (2.0 * n + 1.0), inv_n = 1.0 / n, c0 = n * h / (n + 1.0), k1 = 1.0 + inv_n;
    const double m = std::max(1.0, inv_n);  // |δ| m bounds both exponents of the updates
    double zeta = zeta_io, q = q_io;
    if (!warm(zeta, q)) cold_start(b, zeta, q);
    // Halley's method in y = ln(ζ/ζ₀) (U is close to a power of ζ at both ends). With w = aζ + τ_y,
    // τ = τ_y + ζ, f_a = aζ/w, f_z = ζ/τ and G(y) = U + cζ − b, U = c0 q f_z w/τ:
    //   G' = U p + cζ,  G'' = U (p² + f_a (1 − f_a) − 2 f_z (1 − f_z)) + cζ,  p = 1 + 1/n + f_a − 2 f_z
    // (p > 1/n). The step is Halley's δ = 2 G G'/(2 G'² − G G'') where that corrects Newton's G/G'
    // by a factor in (1/2, 2), else Newton's; bisection where a large step would leave the bracket
    // of the root. A Halley step δ leaves an error ≈ (p²/12) δ³ in ln ζ (as for U ∝ e^{p y}), a
    // Newton step ≈ (p/2) δ²: the iteration stops when that is below 1e-13. ζ and q are updated by
    // e^{−δ}, e^{−δ/n} from small_exp while the steps are small (libm exp else).
    const double z0 = zeta, q0 = q;
    double y = 0.0, lo = -HUGE_VAL, hi = HUGE_VAL, u = 0.0;
    for (int it = 0; it < 60; ++it) {
      const double az = a * zeta, w = az + tau_y, tau = tau_y + zeta;
      const double iw = 1.0 / w, itau = 1.0 / tau;
      const double fa = az * iw, fz = zeta * itau;
      const double cz = c * zeta;
      u = c0 * q * fz * (w * itau);
      const double g = u + cz - b, p = k1 + fa - 2.0 * fz;
      const double g1 = u * p + cz, g2 = u * (p * p + fa * (1.0 - fa) - 2.0 * fz * (1.0 - fz)) + cz;
      const double den = 2.0 * g1 * g1 - g * g2;
      const bool halley = den > g1 * g1;
      double delta = halley ? 2.0 * g * g1 / den : g / g1;
      const double ad = std::abs(delta);
      if (ad * m <= 0.25) {
        // Small step (the converging regime): updates without libm.
        zeta *= small_exp(-delta);
        q *= small_exp(-delta * inv_n);
        y -= delta;
        if (halley ? p * p * ad * ad * ad < 1.2e-12 : p * ad * ad < 2e-13) break;
        continue;
      }
      // Large step: bracket the root with the points seen here (a valid, if loose, bracket) and
      // bisect where the step would leave it.
      (g > 0.0 ? hi : lo) = y;
      if (!(y - delta > lo && y - delta < hi) && lo > -HUGE_VAL && hi < HUGE_VAL) {
        if (hi - lo < 2e-13) break;
        delta = y - 0.5 * (lo + hi);
      }
      y -= delta;
      zeta = z0 * std::exp(y);
      q = q0 * std::exp(y * inv_n);
    }
    const double tau = tau_y + zeta;
    zeta_io = zeta, q_io = q;
    return c0 * q * zeta * (a * zeta + tau_y) / (tau * tau);
  }
  /// τ_b(s)/(ρ h) of the steady layer at mean speed s.
  double acceleration(double s) const noexcept {
    return s > 0.0 ? (tau_y + excess_stress(s, 0.0).zeta) / (rho * h) : rest;
  }
};

/// Speed after the implicit Herschel–Bulkley step (header comment), then the forest drag.
inline double speed_after_friction(double s_star, double dt, const HerschelBulkleyTerms& t) noexcept {
  const double b = s_star - dt * t.rest;
  double* const zeta = t.memory.stress;
  double* const rate = t.memory.rate;
  if (b <= 0.0) {
    if (zeta) *zeta = *rate = 0.0;  // at rest: no memory
    return 0.0;
  }
  // s = U(ζ) rather than b − Δt ζ/(ρ h), which cancels as the particle comes to rest.
  double z = 0.0, q = 0.0;
  const double s = t.solve(b, dt / (t.rho * t.h), zeta ? *zeta : z, zeta ? *rate : q);
  return speed_after_drag(std::min(s, b), t.extra_drag * dt);
}

/// The steps of a block of particles, bit for bit those of speed_after_friction: the warm series
/// steps V's lanes side by side (series_lanes); a particle that stops, has no usable start or
/// whose series step is not accepted takes speed_after_friction.
template <class V>
[[gnu::always_inline]] inline void lane_block(std::span<const double> s_star, double dt,
                                              std::span<const HerschelBulkleyTerms> t, std::span<double> s) noexcept {
  constexpr std::size_t lanes = sizeof(V) / sizeof(double);
  std::size_t k = 0;
  for (; k + lanes <= s.size(); k += lanes) {
    V tau_y, n, h, rho, rest, ss, zeta, q, speed;
    for (std::size_t l = 0; l < lanes; ++l) {
      const HerschelBulkleyTerms& tl = t[k + l];
      tau_y[l] = tl.tau_y, n[l] = tl.n, h[l] = tl.h, rho[l] = tl.rho, rest[l] = tl.rest, ss[l] = s_star[k + l];
      zeta[l] = tl.memory.stress ? *tl.memory.stress : 0.0;
      q[l] = tl.memory.stress ? *tl.memory.rate : 0.0;
    }
    const V b = ss - dt * rest, c = dt / (rho * h);
    decltype(b > 0.0) ok;
    HerschelBulkleyTerms::series_lanes(tau_y, n, h, b, c, zeta, q, speed, ok);
    ok &= b > 0.0;
    for (std::size_t l = 0; l < lanes; ++l) {
      const HerschelBulkleyTerms& tl = t[k + l];
      if (!ok[l]) {
        s[k + l] = speed_after_friction(s_star[k + l], dt, tl);
        continue;
      }
      *tl.memory.stress = zeta[l], *tl.memory.rate = q[l];
      s[k + l] = speed_after_drag(std::min(speed[l], b[l]), tl.extra_drag * dt);
    }
  }
  for (; k < s.size(); ++k) s[k] = speed_after_friction(s_star[k], dt, t[k]);
}

struct HerschelBulkleyFriction {
  static constexpr std::array<ParamSpec, 3> parameters{
      {kYieldStressParameter,
       {"consistency", 30.0, Range::open_closed(1e-6, 1e6), "Pa*s^n", "consistency K of τ = τ_y + K γ̇^n"},
       {"flow_index", 1.0 / 3.0, Range::closed(0.1, 2.0), "1", "flow index n of τ = τ_y + K γ̇^n", "muds ≈ 1/3"}}};
  double tau_y = kYieldStressParameter.def;  ///< yield stress τ_y (Pa)
  double consistency = parameters[1].def;    ///< consistency K (Pa·sⁿ)
  double flow_index = parameters[2].def;     ///< flow index n (1): < 1 shear-thinning
  static constexpr const char* name = "herschel_bulkley";
  static constexpr const char* summary =
      "Herschel-Bulkley fluid, exact depth-averaged plug flow (tau_y, consistency, flow_index; Coussot 1997)";
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? tau_y : j == 1 ? consistency : flow_index) = v, true; }
  HerschelBulkleyTerms terms(double /*g*/, double /*g_n*/, double h_n, double /*speed*/, double rho) const noexcept {
    return {tau_y / (rho * h_n), tau_y, consistency, flow_index, h_n, rho};
  }
};

}  // namespace geohaz::runout
