#pragma once
/// \file friction_terms.hpp
/// The one form every basal law of the debris-runout model is reduced to, and its implicit step.
///
/// A law turns the local state (g, g_n = bed-normal gravity, h_n = bed-normal depth, the surface
/// speed s and the density ρ) into a deceleration a(s) = τ_b(s)/(ρ h_n) acting against the
/// velocity, split as
///
///     a(s) = a_rest + a_move(s),   a_move(0) = 0, a_move increasing,
///
/// a_rest being the yield part that can hold a particle at rest. The friction step solves
///
///     s = s* − Δt a(s),  s ≥ 0                                   (backward Euler in the speed)
///
/// for the speed s after friction, s* the speed after the driving forces: if s* ≤ Δt a_rest the
/// particle stops (and a particle at rest stays at rest while its driving stays below the yield:
/// no creep), else the root is unique because a is increasing. The step can stop a particle but
/// never reverse it, and a steady state of the discrete step satisfies the law exactly (the
/// deceleration is evaluated at the new speed). Laws whose a_move is a polynomial of degree ≤ 2
/// return FrictionTerms (closed-form root); the others return their own terms type with the same
/// members `rest`, `extra_drag` and `acceleration(s)` and their own speed_after_friction overload.
/// A terms type with a member `memory` (StepMemory) solves its step iteratively and starts from the
/// particle's state of its last step, which the solver points it to (the store's per-particle
/// fields); without it (null pointers, as in the unit tests) the step starts cold. The answer is
/// the same to the iteration's tolerance either way.
///
/// Each law owns its coefficients (core/law_parameters.hpp): `parameters` (key of model.<key>,
/// default, range, unit, meaning), `set(j, v)` and, where needed, `from_parameters` and `check`.
/// The coefficients several laws read are declared once below and shared by those laws.

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include "geohaz/core/law_parameters.hpp"

namespace geohaz::runout {

/// Manning's n: modified Manning and (as the turbulent-dispersive n_td) O'Brien–Julien.
inline constexpr ParamSpec kManningNParameter{
    "n",
    0.06,
    Range::closed(0.005, 0.5),
    "s/m^(1/3)",
    "Manning roughness n",
    "for obrien_julien the turbulent-dispersive n_td; 0.02–0.1 for natural channels"};
/// The Coulomb coefficient of Voellmy, Coulomb and Voellmy with cohesion.
inline constexpr ParamSpec kCoulombMuParameter{"mu", 0.15, Range::closed(0.0, 2.0), "1",
                                               "Coulomb friction coefficient μ"};
/// Voellmy's turbulence coefficient (Voellmy and Voellmy with cohesion).
inline constexpr ParamSpec kVoellmyXiParameter{"xi", 500.0, Range::open_closed(0.0, 1e5), "m/s^2",
                                               "Voellmy turbulence coefficient ξ"};
/// The yield stress of the viscoplastic laws (Bingham, Herschel–Bulkley, O'Brien–Julien).
inline constexpr ParamSpec kYieldStressParameter{
    "tau_y", 100.0, Range::closed(0.0, 1e6), "Pa", "yield stress τ_y", "mud matrices 0.1 Pa to a few kPa"};
/// The Bingham (plastic) viscosity of Bingham and O'Brien–Julien.
inline constexpr ParamSpec kBinghamViscosityParameter{"viscosity",
                                                      10.0,
                                                      Range::open_closed(1e-6, 1e6),
                                                      "Pa*s",
                                                      "Bingham (plastic) viscosity μ_B, η",
                                                      "mud matrices 0.01–100"};

/// Where an iterative law keeps a particle's state between steps (see above); null: none.
struct StepMemory {
  double* stress = nullptr;  ///< a stress of the last step (Pa), 0: none
  double* rate = nullptr;    ///< a shear rate of the last step (1/s), 0: none
};

/// Deceleration a(s) = rest + visc·s + drag·s² (m/s²), plus the drag of the surroundings
/// (forest) added by the solver in extra_drag: a law's own shear is acceleration(s).
struct FrictionTerms {
  double rest;              ///< yield part (m/s²)
  double drag;              ///< coefficient of s² (1/m)
  double visc = 0.0;        ///< coefficient of s (1/s): laminar (viscous) resistance
  double extra_drag = 0.0;  ///< coefficient of s² from outside the law (forest, 1/m)
  /// The law's basal deceleration τ_b/(ρ h_n) at speed s (without extra_drag).
  double acceleration(double s) const noexcept { return rest + (visc + drag * s) * s; }
};

/// h^{−1/3} for h > 0 (normal, finite) to ~1 ulp (measured ≤ 2e-16 relative for h = 1e-30 to
/// 1e30) without a libm call or a division: an integer estimate of the exponent (within 3.5 %),
/// then Newton's iteration y ← y (4 − h y³)/3 (error e → ~2e²), three times and once more in the
/// form y + y (1 − h y³)/3, which rounds better.
inline double inverse_cbrt(double h) noexcept {
  double y = std::bit_cast<double>(0x553ef0ff289dd796ull - std::bit_cast<std::uint64_t>(h) / 3);
  const double h3 = h * (1.0 / 3);
  for (int k = 0; k < 3; ++k) y = y * (4.0 / 3 - h3 * (y * y * y));
  return y + y * ((1.0 - h * (y * y * y)) * (1.0 / 3));
}

/// Speed after an implicit step of the drag k s² alone: root of Δt k s² + s − s₀ = 0.
inline double speed_after_drag(double s0, double kdt) noexcept {
  return kdt > 0.0 && s0 > 0.0 ? 2.0 * s0 / (1.0 + std::sqrt(1.0 + 4.0 * kdt * s0)) : s0;
}

/// Speed after one implicit friction step: solves s = s* − Δt (rest + visc s + (drag + extra) s²)
/// for s ≥ 0, i.e. the friction may stop a particle but never reverse it.
inline double speed_after_friction(double s_star, double dt, const FrictionTerms& t) noexcept {
  const double b = s_star - dt * t.rest;
  if (b <= 0.0) return 0.0;
  const double kdt = (t.drag + t.extra_drag) * dt, c = 1.0 + t.visc * dt;
  if (kdt <= 0.0) return b / c;
  // Root of kdt·s² + c·s − b = 0, written without cancellation.
  return 2.0 * b / (c + std::sqrt(c * c + 4.0 * kdt * b));
}

/// Doubles side by side in one vector register (GCC/Clang vector extension): the lanes of a law's
/// block step. Arithmetic and comparisons act lane by lane with the IEEE rounding of the scalar
/// operation (no fused multiply–add: the AVX2 block steps are built with target("avx2") alone, and
/// GEOHAZ_NATIVE builds with -ffp-contract=off), a comparison gives
/// a mask of 0/−1 lanes, and `m ? a : b` selects by lane, so a step written once as a template over
/// double and lanes gives the same bits either way. Two lanes are SSE2 (x86-64's baseline); four
/// are AVX2, used where the processor has it (has_avx2()).
using DoubleLanes = double __attribute__((vector_size(16)));
using DoubleLanes4 = double __attribute__((vector_size(32)));
/// Whether this processor runs AVX2 (tested once).
inline bool has_avx2() noexcept {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

/// The solver steps the friction of its particles in blocks of this many (solver.hpp, integrate).
inline constexpr std::size_t kFrictionBlock = 16;

/// A law whose step gains from doing several particles at once defines, for its terms type,
/// `template <class V> void lane_block(s_star, dt, span<const Terms> t, s)`: the block's steps with
/// V's lanes side by side (V = DoubleLanes or DoubleLanes4), bit for bit those of
/// speed_after_friction. It is found by argument-dependent lookup.
template <class Terms>
concept HasLaneBlock = requires(std::span<const double> a, std::span<const Terms> t, std::span<double> s) {
  lane_block<DoubleLanes>(a, 0.0, t, s);
};
#if defined(__x86_64__) && defined(__GNUC__)
/// lane_block on four lanes, built for AVX2 (without FMA).
template <class Terms>
[[gnu::target("avx2")]] void lane_block_avx2(std::span<const double> s_star, double dt, std::span<const Terms> t,
                                             std::span<double> s) noexcept {
  lane_block<DoubleLanes4>(s_star, dt, t, s);
}
#endif

/// The friction steps of a block of particles: s[k] = speed_after_friction(s_star[k], dt, t[k]),
/// through the law's lane_block where it has one (four lanes where the processor runs AVX2, else
/// two), one particle at a time otherwise.
template <class Terms>
void speed_after_friction_block(std::span<const double> s_star, double dt, std::span<const Terms> t,
                                std::span<double> s) noexcept {
  if constexpr (HasLaneBlock<Terms>) {
#if defined(__x86_64__) && defined(__GNUC__)
    if (has_avx2()) return lane_block_avx2(s_star, dt, t, s);
#endif
    lane_block<DoubleLanes>(s_star, dt, t, s);
  } else {
    for (std::size_t k = 0; k < s.size(); ++k) s[k] = speed_after_friction(s_star[k], dt, t[k]);
  }
}

}  // namespace geohaz::runout
