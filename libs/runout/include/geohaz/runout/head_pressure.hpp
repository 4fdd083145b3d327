#pragma once
/// \file head_pressure.hpp
/// The flow-head pressure of the depth-averaged debris-flow model as an inter-particle force
/// (SWJTU lecture 2010, section 3, "pressure due to the soil-water mixture head is modeled with
/// inter-particle force", including the effective-length extension):
///
///     a_i = Σ_j  C · g · (V_j / d0³) · f(|d|/d0) · d/|d|,      d = x_i − x_j  (map view)
///
///     f(x) = (1 − x)/(1 + x)          0 ≤ x < 1
///     f(x) = −½ (x − 1)(x − 2)        1 ≤ x < 2     (continuous reading, see below)
///     f(x) = 0                        x ≥ 2
///
/// For particles of the reference volume V0 = h0·d0² this is the lecture's p = ρ g (h0/d0) f d/|d|
/// per unit mass (times C). The seed transcribes the second branch as −½[(x − 3/2)² + 1/8], which
/// jumps at x = 1 (from 0 to −1/4) and at x = 2 (from −1/4 to 0); with −1/4 in place of +1/8 the
/// bracket factorises into (x − 1)(x − 2): continuous at both ends, zero at x = 1 and x = 2.
///
/// Normalisation C. The force is the SPH gradient −g Σ V_j ∇W_f of the kernel W_f(r) whose radial
/// derivative is −f(r/d0)/d0³; its integral is ∫W_f dA = π ∫₀² x² f(x) dx = π·I with
/// I = (2 ln 2 − 4/3) + 23/120 ≈ 0.2446. With C = 1/(π I) ≈ 1.301 the continuum limit of the force is
/// exactly −g ∇h, the pressure term of the shallow-water equations, so waves travel at √(g h) (dam
/// break: Ritter). C = 1 reproduces the lecture's raw coefficient (waves slower by √(πI) ≈ 0.877).

#include <cmath>
#include <numbers>

namespace geohaz::runout {

/// Shape function and constants of the head-pressure force (SWJTU lecture 2010, §3, continuous reading).
struct HeadPressureForce {
  /// Support of f in units of d0.
  static constexpr double support = 2.0;

  /// f(x), x = |d|/d0 ≥ 0 (dimensionless).
  static constexpr double shape(double x) noexcept {
    if (x < 1.0) return (1.0 - x) / (1.0 + x);
    if (x < 2.0) return -0.5 * (x - 1.0) * (x - 2.0);
    return 0.0;
  }

  /// I = ∫₀² x² f(x) dx in closed form: ∫₀¹ x²(1−x)/(1+x) dx = 2 ln 2 − 4/3 (write the fraction as
  /// −1 + 2/(1+x)); the second branch contributes ∫₁² x²·(−½)(x−1)(x−2) dx = 23/120.
  static double second_moment() noexcept {
    const double first = 2.0 * std::numbers::ln2 - 1.0 - 1.0 / 3.0;  // ∫₀¹ x²(−1 + 2/(1+x)) dx
    const double second = 23.0 / 120.0;                              // ∫₁² x²·(−½)(x−1)(x−2) dx
    return first + second;
  }

  /// Normalisation making the continuum limit −g∇h (C = 1/(π I) ≈ 1.301).
  static double consistent_normalisation() noexcept { return 1.0 / (std::numbers::pi * second_moment()); }
};

}  // namespace geohaz::runout
