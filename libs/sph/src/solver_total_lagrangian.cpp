// The total-Lagrangian formulation of the SPH solver (numerics.formulation = total_lagrangian;
// docs/sph.md): elastic bodies with derivatives in the reference configuration.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "geohaz/core/parallel.hpp"
#include "solver_kernels.hpp"

namespace geohaz::sph {

// ---- Total-Lagrangian formulation (settings_.total_lagrangian; docs/sph.md) ----------------------
//
// For elastic bodies in small-to-moderate deformation (beams, piles, retaining structures). All
// spatial derivatives are taken in the reference configuration X, fixed at the first step of the
// main phase as X = x − u (u the Displacement field, zero at the start of a run; after a restart
// the same X again), with the neighbour list of that configuration, built once and never rebuilt
// (Vignjevic, Reveles & Campbell 2006; Ganzenmüller 2015):
//   V⁰_i = m_i/ρ₀, g⁰_ij = A_i b⁰_ij, the corrected reference gradient (linear: C_i ∇W⁰_ij, Bonet & Lok
//          1999; quadratic_correction: the quadratic-complete one of step 2), computed once;
//   F_i = I + Σ_j V⁰_j (u_j − u_i) ⊗ g⁰_ij (exact for an affine u, surfaces included);
//   E_i = ½ (F_iᵀ F_i − I), S_i = λ tr E_i I + 2μ E_i (St Venant–Kirchhoff; plane strain in 2D:
//          E_zz = 0, S_zz = λ tr E), P_i = F_i S_i (first Piola–Kirchhoff);
//   m_i a_i = Σ_j V⁰_i V⁰_j (P_i g⁰_ij − P_j g⁰_ji) + f^HG_i, then ḡ, damping, leap-frog as step 5
//          (the pair term is −∂/∂x_i of Σ_k V⁰_k Ψ(F_k): antisymmetric, linear momentum conserved);
//   f^HG_i = ½ α Σ_j (V⁰_i V⁰_j W⁰_ij/|X_ij|²) E (δ^i_ij + δ^j_ji) x_ij/|x_ij| (Ganzenmüller 2015),
//          x_ij = x_i − x_j, X_ij = X_i − X_j, δ^i_ij = (F_i X_ij − x_ij)·x_ij/|x_ij|: the pair's
//          length error against the one F_i predicts; zero for an affine motion;
//   Cauchy σ_i = J⁻¹ P_i F_iᵀ (J = det F, σ_zz = S_zz/J in 2D) into Stress, ρ_i = ρ₀/J into Density.
// No artificial viscosity, artificial stress or XSPH (the hourglass force is the stabilisation).
// Every particle sums its own row (the reverse slot tl_rev_ gives g⁰_ji): the sums are the same on
// any thread count, and the pair terms of (i, j) and (j, i) are bitwise negatives of each other.
template <int Dim>
template <class Kernel>
void SphSolver<Dim>::tl_step() {
  if (!tl_ready_) tl_setup<Kernel>();
  const Vec<Dim> gbar = body_acceleration();
  tl_stress();
  tl_forces();
  integrate(gbar);
  time_ += dt_;
  ++step_;
  check_state();
  update_dt();
}

template <int Dim>
template <class Kernel>
void SphSolver<Dim>::tl_setup() {
  constexpr int N = kBasis;
  const std::size_t n = store_.size();
  const PairKernel<Kernel> K(h_);
  const Vec<Dim>* x = field<Position<Dim>>();
  const Vec<Dim>* u = field<Displacement<Dim>>();
  const double* m = field<Mass>();
  const std::int32_t* mat = field<MaterialId>();
  tl_X_.resize(n);
  tl_V0_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    tl_X_[i] = x[i] - u[i];
    tl_V0_[i] = m[i] / materials_[mat[i]].density;
  }
  NeighbourList<Dim> list;
  list.build(tl_X_, Kernel::support * h_);
  const auto off = list.offsets();
  const auto idx = list.indices();
  tl_off_.assign(n + 1, 0);
  tl_idx_.clear();
  for (std::size_t i = 0; i < n; ++i) {  // the neighbours within the support, ascending
    const std::size_t row = tl_idx_.size();
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = idx[k];
      const double r2 = (tl_X_[i] - tl_X_[j]).squaredNorm();
      if (j != i && r2 < K.cutoff2 && r2 > 0.0) tl_idx_.push_back(j);
    }
    std::sort(tl_idx_.begin() + static_cast<std::ptrdiff_t>(row), tl_idx_.end());
    tl_off_[i + 1] = static_cast<std::uint32_t>(tl_idx_.size());
  }
  const std::size_t np = tl_idx_.size();
  tl_rev_.resize(np);
  tl_g_.resize(np);
  tl_hg_.resize(np);
  const Vec<Dim>* X = tl_X_.data();
  const double* V0 = tl_V0_.data();
  const bool quadratic = settings_.kernel_correction && settings_.quadratic_correction;
  const bool corrected = settings_.kernel_correction;
  const std::int64_t ni = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static) if (parallel_worth(ni))
  for (std::int64_t ii = 0; ii < ni; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const std::uint32_t b = tl_off_[i], e = tl_off_[i + 1];
    const auto pairs = [&](auto&& f) {
      for (std::uint32_t k = b; k < e; ++k) {
        const std::uint32_t j = tl_idx_[k];
        const Vec<Dim> xij = X[i] - X[j];
        f(V0[j], xij, xij.norm());
      }
    };
    Eigen::Matrix<double, Dim, N> A = Eigen::Matrix<double, Dim, N>::Zero();
    A.template leftCols<Dim>().setIdentity();
    if (corrected) A = correction_matrix<Dim, N, Kernel>(K, quadratic, pairs);
    const double Ei = materials_[mat[i]].young;
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t j = tl_idx_[k];
      const Vec<Dim> xij = X[i] - X[j];
      const double r = xij.norm(), q = r * K.inv_h;
      const double F = -K.sigma_h * Kernel::shape_derivative(q) / r;  // |∇_i W_ij|/r
      const Vec<Dim> gw = -F * xij;                                   // ∇_i W⁰_ij
      tl_g_[k] = A * kernel_basis<Dim, N>(gw, F, xij, K.inv_h);
      const double E = 0.5 * (Ei + materials_[mat[j]].young);  // symmetric in i, j
      tl_hg_[k] = 0.5 * settings_.hourglass * E * (V0[i] * V0[j]) * K.sigma * Kernel::shape(q) / (r * r);
      // the slot of (j, i) in j's sorted row
      const auto* first = tl_idx_.data() + tl_off_[j];
      const auto* last = tl_idx_.data() + tl_off_[j + 1];
      tl_rev_[k] =
          static_cast<std::uint32_t>(std::lower_bound(first, last, static_cast<std::uint32_t>(i)) - tl_idx_.data());
    }
  }
  // The hourglass force's stiffness in the time step: in the mode it resists (i and j moving apart
  // by u each along e_ij, F unchanged) the pair pushes i back with 4 w_ij u (w_ij = tl_hg_), so
  // ω_i² ≤ Σ_j 4 w_ij / m_i. It enters as a wave speed c_hg = ω h/2 added to the P-wave speed in
  // quadrature, c² = c_p² + c_hg², so that Δt = C_cfl h/c ≤ 2 C_cfl/ω (the leap-frog bound 2/ω
  // with the CFL number's margin). α = 0 leaves c_p.
  double w2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    double k = 0.0;
    for (std::uint32_t s = tl_off_[i]; s < tl_off_[i + 1]; ++s) k += 4.0 * tl_hg_[s];
    w2 = std::max(w2, k / m[i]);
  }
  tl_wave_speed_ = std::sqrt(max_wave_speed_ * max_wave_speed_ + 0.25 * w2 * h_ * h_);
  dt_ = std::min(dt_, settings_.cfl * h_ / tl_wave_speed_);
  tl_F_.assign(n, Mat<Dim>::Identity());
  tl_ready_ = true;
}

template <int Dim>
void SphSolver<Dim>::tl_stress() {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* u = field<Displacement<Dim>>();
  const std::int32_t* mat = field<MaterialId>();
  const MaterialParams* mats = materials_.data();
  const double* V0 = tl_V0_.data();
  const std::uint32_t* off = tl_off_.data();
  const std::uint32_t* idx = tl_idx_.data();
  const Vec<Dim>* g = tl_g_.data();
  Mat<Dim>* Fs = tl_F_.data();
  Mat<Dim>* P = field<PairStress<Dim>>();
  Mat3* sig = field<Stress>();
  double* rho = field<Density>();
  double* vol = field<Volume>();
  Mat<Dim>* L = field<VelocityGradient<Dim>>();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    Mat<Dim> F = Mat<Dim>::Identity();
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k)
      F.noalias() += (V0[idx[k]] * (u[idx[k]] - u[i])) * g[k].transpose();
    Fs[i] = F;
    const MaterialParams& p = mats[mat[i]];
    const double mu = p.shear, lambda = p.bulk - 2.0 * p.shear / 3.0;
    Mat<Dim> Eg = 0.5 * (F.transpose() * F - Mat<Dim>::Identity());
    const double tr = Eg.trace();
    Mat<Dim> S = 2.0 * mu * Eg;
    S.diagonal().array() += lambda * tr;
    P[i].noalias() = F * S;
    const double J = F.determinant();
    Mat3 s3 = Mat3::Zero();
    s3.template topLeftCorner<Dim, Dim>() = (P[i] * F.transpose()) / J;
    if constexpr (Dim == 2) s3(2, 2) = lambda * tr / J;
    sig[i] = s3;
    rho[i] = p.density / J;
    vol[i] = V0[i];
    L[i].setZero();
  }
}

template <int Dim>
void SphSolver<Dim>::tl_forces() {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* x = field<Position<Dim>>();
  const double* m = field<Mass>();
  const double* V0 = tl_V0_.data();
  const Vec<Dim>* X = tl_X_.data();
  const std::uint32_t* off = tl_off_.data();
  const std::uint32_t* idx = tl_idx_.data();
  const std::uint32_t* rev = tl_rev_.data();
  const Vec<Dim>* g = tl_g_.data();
  const double* hg = tl_hg_.data();
  const Mat<Dim>* Fs = tl_F_.data();
  const Mat<Dim>* P = field<PairStress<Dim>>();
  Vec<Dim>* acc = field<Acceleration<Dim>>();
  const bool hourglass = settings_.hourglass > 0.0;
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    Vec<Dim> f = Vec<Dim>::Zero();
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = idx[k];
      const Vec<Dim> t = P[i] * g[k] - P[j] * g[rev[k]];
      f.noalias() += (V0[i] * V0[j]) * t;
      if (hourglass) {
        const Vec<Dim> xij = x[i] - x[j];
        const Vec<Dim> Xij = X[i] - X[j];
        const double r = xij.norm();
        const Vec<Dim> e = xij / r;
        // δ^i_ij + δ^j_ji: (F_i X_ij − x_ij)·e + (F_j X_ji − x_ji)·(−e)
        const double delta = (Fs[i] * Xij - xij).dot(e) + (Fs[j] * Xij - xij).dot(e);
        f.noalias() += (hg[k] * delta) * e;
      }
    }
    acc[i] = f / m[i];
  }
}

template void SphSolver<2>::tl_step<CubicSpline<2>>();
template void SphSolver<2>::tl_step<WendlandC2<2>>();
template void SphSolver<3>::tl_step<CubicSpline<3>>();
template void SphSolver<3>::tl_step<WendlandC2<3>>();
template void SphSolver<2>::tl_stress();
template void SphSolver<3>::tl_stress();
template void SphSolver<2>::tl_forces();
template void SphSolver<3>::tl_forces();

}  // namespace geohaz::sph
