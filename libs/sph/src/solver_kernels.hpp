#pragma once
// Private to libs/sph/src: the kernel and pair geometry the SPH solver's passes share
// (solver_passes.cpp: the updated-Lagrangian step; solver_total_lagrangian.cpp: the
// total-Lagrangian formulation; solver.cpp: the time integration).

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "geohaz/core/kernels.hpp"
#include "geohaz/sph/solver.hpp"

namespace geohaz::sph {

constexpr std::uint8_t kRoller = static_cast<std::uint8_t>(Kind::RollerWall);

/// Minimum-image displacement a − b: the core's (Periodicity::min_image, the one Neighbours uses).
template <int Dim>
struct MinimumImage {
  const Periodicity<Dim>& per;
  bool any;
  explicit MinimumImage(const Periodicity<Dim>& p) : per(p), any(p.any()) {}
  Vec<Dim> operator()(const Vec<Dim>& a, const Vec<Dim>& b) const noexcept {
    return any ? per.min_image(a - b) : Vec<Dim>(a - b);
  }
};

/// Kernel constants of the pair loops: W = σ w(q), ∇W = x_ij σ/h w'(q)/r with q = r/h.
template <class Kernel>
struct PairKernel {
  double inv_h, sigma, sigma_h, cutoff2, w_self;
  explicit PairKernel(double h)
      : inv_h(1.0 / h),
        sigma(Kernel::sigma(h)),
        sigma_h(sigma * inv_h),
        cutoff2((Kernel::support * h) * (Kernel::support * h)),
        w_self(Kernel::value(0.0, h)) {}
};

/// The quadratic-complete kernel basis of pair (i, j) (step 2): b_ij = F_ij p_ij with
/// p_ij = [r; h m(r/h)], r = x_j − x_i, m the Dim(Dim+1)/2 products r_a r_b/h² (a ≤ b), and
/// F_ij = |∇_i W_ij|/|r| ≥ 0, so that its first Dim components are ∇_i W_ij = F_ij r (passed as gw).
/// m is even in r, so b_ji is b_ij with its first Dim components negated.
template <int Dim, int N>
inline Eigen::Matrix<double, N, 1> kernel_basis(const Vec<Dim>& gw, double F, const Vec<Dim>& xij,
                                                double inv_h) noexcept {
  Eigen::Matrix<double, N, 1> b;
  b.template head<Dim>() = gw;
  const Vec<Dim> s = xij * (F * inv_h);
  int k = Dim;
  for (int a = 0; a < Dim; ++a)
    for (int c = a; c < Dim; ++c) b[k++] = s[a] * xij[c];
  return b;
}

/// A of one particle i (step 2, SphSolver::gradient_correction; docs there): the first Dim rows
/// of B_i⁻¹ (quadratic) or [M_i⁻¹ 0] (linear), [I 0] where the moments are degenerate. `pairs(f)`
/// calls f(V_j, x_ij, r) for every neighbour j within the support (x_ij = x_i − x_j, r = |x_ij| > 0).
/// Shared by the updated-Lagrangian pass (current positions, every step) and the total-Lagrangian
/// setup (reference positions, once).
template <int Dim, int N, class Kernel, class Pairs>
Eigen::Matrix<double, Dim, N> correction_matrix(const PairKernel<Kernel>& K, bool quadratic, Pairs&& pairs) {
  constexpr double kMinMomentDet = Dim == 2 ? 0.2 * 0.2 : 0.2 * 0.2 * 0.2;
  constexpr double kMinRcond = 1e-4;
  using Basis = Eigen::Matrix<double, N, 1>;
  using Moments = Eigen::Matrix<double, N, N>;
  Eigen::Matrix<double, Dim, N> A = Eigen::Matrix<double, Dim, N>::Zero();
  A.template leftCols<Dim>().setIdentity();
  if (!quadratic) {  // the linear correction alone: C_i = M_i⁻¹ (Bonet & Lok 1999)
    Mat<Dim> M = Mat<Dim>::Zero();
    pairs([&](double Vj, const Vec<Dim>& xij, double r) {
      const Vec<Dim> gw = xij * (K.sigma_h * Kernel::shape_derivative(r * K.inv_h) / r);
      M.noalias() -= Vj * gw * xij.transpose();  // V_j ∇W_ij ⊗ (x_j − x_i)
    });
    if (M.determinant() >= kMinMomentDet) A.template leftCols<Dim>() = M.inverse();
    return A;
  }
  Moments B = Moments::Zero();  // upper triangle only until the factorisation
  pairs([&](double Vj, const Vec<Dim>& xij, double r) {
    const double F = -K.sigma_h * Kernel::shape_derivative(r * K.inv_h) / r;  // |∇_i W_ij|/r
    Basis p;                                                                  // [r; h m(r/h)], r = x_j − x_i
    p.template head<Dim>() = -xij;
    int c = Dim;
    for (int a = 0; a < Dim; ++a)
      for (int d = a; d < Dim; ++d) p[c++] = xij[a] * xij[d] * K.inv_h;
    const double wgt = Vj * F;
    for (int a = 0; a < N; ++a)  // V_j b_ij ⊗ p_ij = V_j F_ij p_ij ⊗ p_ij (symmetric)
      for (int d = a; d < N; ++d) B(a, d) += wgt * p[a] * p[d];
  });
  Mat<Dim> M;
  for (int a = 0; a < Dim; ++a)
    for (int d = 0; d < Dim; ++d) M(a, d) = B(std::min(a, d), std::max(a, d));
  if (!(M.determinant() >= kMinMomentDet)) return A;
  // Cholesky B = L Lᵀ (B is symmetric positive semi-definite), in place in the lower triangle;
  // (max L_kk / min L_kk)² estimates the condition number.
  bool ok = true;
  double dmin = std::numeric_limits<double>::infinity(), dmax = 0.0;
  for (int c = 0; c < N && ok; ++c) {
    double d = B(c, c);
    for (int k = 0; k < c; ++k) d -= B(c, k) * B(c, k);
    if (!(d > 0.0)) {
      ok = false;
      break;
    }
    d = std::sqrt(d);
    B(c, c) = d;
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
    for (int row = c + 1; row < N; ++row) {
      double e = B(c, row);  // upper triangle holds the sums
      for (int k = 0; k < c; ++k) e -= B(row, k) * B(c, k);
      B(row, c) = e / d;
    }
  }
  if (ok && dmax * dmax * kMinRcond <= dmin * dmin) {
    // A_iᵀ = the first Dim columns of B⁻¹ (B symmetric): solve L Lᵀ X = [I; 0].
    for (int col = 0; col < Dim; ++col) {
      Basis y;
      for (int row = 0; row < N; ++row) {
        double e = row == col ? 1.0 : 0.0;
        for (int k = 0; k < row; ++k) e -= B(row, k) * y[k];
        y[row] = e / B(row, row);
      }
      for (int row = N - 1; row >= 0; --row) {
        double e = y[row];
        for (int k = row + 1; k < N; ++k) e -= B(k, row) * y[k];
        y[row] = e / B(row, row);
      }
      A.row(col) = y.transpose();
    }
  } else {
    A.template leftCols<Dim>() = M.inverse();
  }
  return A;
}

}  // namespace geohaz::sph
