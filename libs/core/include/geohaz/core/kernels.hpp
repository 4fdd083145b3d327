#pragma once
/// \file kernels.hpp
/// SPH smoothing kernels, chosen at compile time (template parameter of the solver), so the pair
/// loop has no dispatch. All kernels have support radius 2h and are normalised so that
/// ∫ W dV = 1 in Dim dimensions.
///
///  - CubicSpline (Monaghan & Lattanzio 1985), SPH-slope paper (2020), eq. 9 / Bui et al. (2010), eq. 4:
///      W = α_d { 2/3 − q² + q³/2  (0 ≤ q < 1);  (2 − q)³/6  (1 ≤ q < 2);  0 }
///    with α_d = 15/(7πh²) in 2D and 3/(2πh³) in 3D for this form of the polynomial
///    (equivalently 10/(7πh²) and 1/(πh³) for the form  1 − 3q²/2 + 3q³/4,  (2−q)³/4).
///  - WendlandC2 (Wendland 1995, scaled to support 2h as in Dehnen & Aly 2012):
///      W = α_d (1 − q/2)⁴ (2q + 1),   α_d = 7/(4πh²) in 2D, 21/(16πh³) in 3D.

#include <cmath>
#include <numbers>

#include "geohaz/core/vec.hpp"

namespace geohaz {

/// Cubic B-spline kernel in Dim dimensions.
template <int Dim>
struct CubicSpline {
  static_assert(Dim == 1 || Dim == 2 || Dim == 3);
  static constexpr double support = 2.0;  ///< support radius in units of h
  static constexpr const char* name = "cubic_spline";

  static constexpr double sigma(double h) noexcept {
    if constexpr (Dim == 1)
      return 1.0 / h;
    else if constexpr (Dim == 2)
      return 15.0 / (7.0 * std::numbers::pi * h * h);
    else
      return 3.0 / (2.0 * std::numbers::pi * h * h * h);
  }
  /// Dimensionless shape w(q) and its derivative dw/dq: W = σ_d w(r/h), dW/dr = σ_d w'(r/h)/h.
  /// Pair loops that precompute σ_d and 1/h call these directly (no division per pair).
  static double shape(double q) noexcept {
    if (q < 1.0) return 2.0 / 3.0 - q * q + 0.5 * q * q * q;
    if (q < 2.0) {
      const double t = 2.0 - q;
      return t * t * t / 6.0;
    }
    return 0.0;
  }
  static double shape_derivative(double q) noexcept {
    if (q < 1.0) return -2.0 * q + 1.5 * q * q;
    if (q < 2.0) {
      const double t = 2.0 - q;
      return -0.5 * t * t;
    }
    return 0.0;
  }
  /// W(r, h)
  static double value(double r, double h) noexcept { return sigma(h) * shape(r / h); }
  /// dW/dr (r, h)
  static double derivative(double r, double h) noexcept { return sigma(h) * shape_derivative(r / h) / h; }
  /// ∇_i W(x_i − x_j) given xij = x_i − x_j and r = |xij| > 0.
  static Vec<Dim> gradient(const Vec<Dim>& xij, double r, double h) noexcept {
    if (r <= 0.0) return Vec<Dim>::Zero();
    return xij * (derivative(r, h) / r);
  }
};

/// Wendland C2 kernel in Dim dimensions (2D and 3D), support 2h.
template <int Dim>
struct WendlandC2 {
  static_assert(Dim == 2 || Dim == 3, "Wendland C2 is defined here for 2D and 3D");
  static constexpr double support = 2.0;
  static constexpr const char* name = "wendland_c2";

  static constexpr double sigma(double h) noexcept {
    if constexpr (Dim == 2)
      return 7.0 / (4.0 * std::numbers::pi * h * h);
    else
      return 21.0 / (16.0 * std::numbers::pi * h * h * h);
  }
  /// Dimensionless shape w(q) = (1 − q/2)⁴(2q + 1) and dw/dq = −5q(1 − q/2)³ (see CubicSpline).
  static double shape(double q) noexcept {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q;
    const double t2 = t * t;
    return t2 * t2 * (2.0 * q + 1.0);
  }
  static double shape_derivative(double q) noexcept {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q;
    return -5.0 * q * t * t * t;
  }
  static double value(double r, double h) noexcept { return sigma(h) * shape(r / h); }
  static double derivative(double r, double h) noexcept { return sigma(h) * shape_derivative(r / h) / h; }
  static Vec<Dim> gradient(const Vec<Dim>& xij, double r, double h) noexcept {
    if (r <= 0.0) return Vec<Dim>::Zero();
    return xij * (derivative(r, h) / r);
  }
};

}  // namespace geohaz
