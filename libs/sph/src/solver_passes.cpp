// One step of the SPH solver (updated Lagrangian), step() and the passes of the numbered list in
// solver.hpp: the boundary particles' mirror terms (1), the kernel-gradient correction and the
// velocity gradient (2), the stress update (3), the pair forces (4) and the loads on the structures
// (4b). The neighbour list (0), the time integration (5) and the clock (6) are in solver.cpp.
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <tuple>
#include <type_traits>
#include <variant>

#include "geohaz/core/parallel.hpp"
#include "solver_kernels.hpp"

namespace geohaz::sph {

namespace {

/// Principal-frame artificial stress (Gray & Monaghan 2001): R = Q diag(r_a) Qᵀ,
/// r_a = −ε σ_a/ρ² for σ_a > 0 (tension), 0 otherwise. σ is the in-plane block.
template <int Dim>
Mat<Dim> artificial_stress(const Mat<Dim>& s, double eps, double rho) {
  const double inv = -eps / (rho * rho);
  if constexpr (Dim == 2) {
    const double a = s(0, 0), b = s(1, 1), c = 0.5 * (s(0, 1) + s(1, 0));
    const double m = 0.5 * (a + b), d = std::sqrt(0.25 * (a - b) * (a - b) + c * c);
    const double s1 = m + d, s2 = m - d;
    if (s1 <= 0.0) return Mat<2>::Zero();
    // Principal direction of s1.
    double ex, ey;
    if (d < 1e-300 * (std::abs(m) + 1.0)) {
      ex = 1.0;
      ey = 0.0;
    } else {
      const double theta = 0.5 * std::atan2(2.0 * c, a - b);
      ex = std::cos(theta);
      ey = std::sin(theta);
    }
    const double r1 = inv * s1, r2 = s2 > 0.0 ? inv * s2 : 0.0;
    Mat<2> R;
    R(0, 0) = r1 * ex * ex + r2 * ey * ey;
    R(1, 1) = r1 * ey * ey + r2 * ex * ex;
    R(0, 1) = R(1, 0) = (r1 - r2) * ex * ey;
    return R;
  } else {
    Eigen::SelfAdjointEigenSolver<Mat3> es;
    es.computeDirect(s);
    const Vec3 ev = es.eigenvalues();
    if (ev.maxCoeff() <= 0.0) return Mat3::Zero();
    Vec3 r;
    for (int k = 0; k < 3; ++k) r[k] = ev[k] > 0.0 ? inv * ev[k] : 0.0;
    const Mat3& Q = es.eigenvectors();
    return Q * r.asDiagonal() * Q.transpose();
  }
}

// The fixed-order reactions of the pair passes (steps 2 and 4; docs/sph.md, "Determinism") use
// the core's PairBlocks (neighbours.hpp): each soil–soil pair is evaluated once, by the particle
// of lower index, which adds the partner's share to the buffer of its block of B particles; the
// reach W is the largest index distance of a soil–soil pair of the list (Neighbours::blocks_for).

/// ρ_i ρ_j Π_ij of Monaghan's artificial viscosity, Π_ij = (−α c̄ μ + β μ²)/ρ̄ with c̄ and ρ̄ the pair's
/// mean sound speed and density, for an approaching pair (μ = h v_ij·x_ij/(r² + 0.01h²) < 0).
inline double viscous_pressure(double alpha, double beta, double ci, double cj, double mu, double rhoi,
                               double rhoj) noexcept {
  return (-alpha * 0.5 * (ci + cj) * mu + beta * mu * mu) * (rhoi * rhoj) / (0.5 * (rhoi + rhoj));
}

/// Velocity of boundary particle b in its pair with soil particle i (step 1): the mirror image of
/// v_i, all components (fixed wall, pile) or only the normal one (roller).
template <int Dim>
inline Vec<Dim> mirror_velocity(const Vec<Dim>& vi, const Vec<Dim>& vb, const Vec<Dim>& nb, bool roller) noexcept {
  if (roller) return vi - 2.0 * (vi - vb).dot(nb) * nb;
  return 2.0 * vb - vi;
}

/// Stress of boundary particle b in its pair with soil particle i (step 1): σ_i extrapolated along
/// the layering normal ν_b with the matrix G_b of prepare_boundary_pairs, d = (x_b − x_i)·ν = −x_ib·ν;
/// shear mirrored through the wall for a roller.
template <int Dim>
inline Mat<Dim> mirror_stress(const Mat<Dim>& si, double rhoi, const Vec<Dim>& xib, const Vec<Dim>& nu_b,
                              const Mat<Dim>& G_b, const Vec<Dim>& nb, bool roller) noexcept {
  Mat<Dim> sb = si + (rhoi * xib.dot(nu_b)) * G_b;
  if (roller) {
    const Mat<Dim> M = Mat<Dim>::Identity() - 2.0 * nb * nb.transpose();
    sb = M * sb * M;
  }
  return sb;
}

/// Step 4's pair term, written once for the momentum pass and for step 4b (structure_forces), which
/// must repeat its soil–boundary part exactly: for soil particle i and neighbour j (soil, or a
/// boundary particle acting as i's mirror image) closer than the cut-off, the force density on i
/// per unit volume of j,
///   T_ij ∇W_ij,  T_ij = σ_i + σ_j − Π_ij ρ_i ρ_j I + f_ij^n ρ_i ρ_j (R_i + R_j),
/// with the stress pair taken with the corrected gradients instead when the kernel correction is
/// on (linear: σ_i C_i ∇W_ij + σ_j C_j ∇W_ij between soil particles, (σ_i + σ_b) C_i ∇W_ib at a
/// wall; quadratic: the same with g_ij = A_i b_ij); and the wall repulsion on i. The arrays are the
/// state before the integration; solver.hpp momentum_pair_term() fills them.
template <int Dim, int Basis, class Kernel, bool Corrected>
struct MomentumPairTerm {
  PairKernel<Kernel> K;
  MinimumImage<Dim> image;
  double w_dx, n_as, alpha, beta, h, eta2, r_rep;
  const double* wave;
  const Vec<Dim>* x;
  const Vec<Dim>* v;
  const double* rho;
  const double* vol;
  const std::int32_t* mat;
  const std::uint8_t* kind;
  const Vec<Dim>* nrm;
  const Vec<Dim>* lnrm;
  const Mat<Dim>* ps;
  const Mat<Dim>* R;
  const std::uint8_t* has_as;
  const Eigen::Matrix<double, Dim, Basis>* A;  // correction (Corrected only)
  bool quadratic;

  /// What particle i brings to each of its pairs, read once.
  struct Self {
    Mat<Dim> s, R;
    bool has_R;
    double c, V, rho;
  };
  Self self(std::size_t i) const { return {ps[i], R[i], has_as[i] != 0, wave[mat[i]], vol[i], rho[i]}; }

  /// T_ij ∇W_ij for the pair at xij = x_i − x_j, r = |xij| below the cut-off.
  [[gnu::always_inline]] inline Vec<Dim> operator()(const Self& I, std::size_t i, std::size_t j, bool soil_j,
                                                    const Vec<Dim>& xij, double r) const {
    const double q = r * K.inv_h;
    const Vec<Dim> gw = xij * (r > 0.0 ? K.sigma_h * Kernel::shape_derivative(q) / r : 0.0);
    const bool roller = kind[j] == kRoller;
    const Mat<Dim> sj = soil_j ? ps[j] : mirror_stress<Dim>(I.s, I.rho, xij, lnrm[j], ps[j], nrm[j], roller);
    Mat<Dim> T;
    if constexpr (Corrected)
      T.setZero();  // the stress pair is added below with the corrected gradients
    else
      T = I.s + sj;
    const Vec<Dim> vij = v[i] - (soil_j ? v[j] : mirror_velocity<Dim>(v[i], v[j], nrm[j], roller));
    const double vr = vij.dot(xij);
    if (vr < 0.0 && alpha + beta > 0.0)
      T.diagonal().array() -= viscous_pressure(alpha, beta, I.c, wave[mat[j]], h * vr / (r * r + eta2), I.rho, rho[j]);
    if (I.has_R || has_as[j]) {
      const double f = K.sigma * Kernel::shape(q) / w_dx;
      T += (std::pow(f, n_as) * I.rho * rho[j]) * (I.R + R[j]);
    }
    Vec<Dim> Tg = T * gw;
    if constexpr (Corrected) {  // σ_i g_ij − σ_j g_ji, g_ij = A_i b_ij (step 2); b_ji: ∇W negated
      if (!quadratic) {         // the linear correction: g_ij = C_i ∇W_ij, g_ji = −C_j ∇W_ij
        const Vec<Dim> cgi = A[i].template leftCols<Dim>() * gw;
        if (soil_j)
          Tg.noalias() += I.s * cgi + sj * (A[j].template leftCols<Dim>() * gw);
        else
          Tg.noalias() += (I.s + sj) * cgi;
      } else {
        auto b =
            kernel_basis<Dim, Basis>(gw, r > 0.0 ? -K.sigma_h * Kernel::shape_derivative(q) / r : 0.0, xij, K.inv_h);
        const Vec<Dim> gij = A[i] * b;
        if (soil_j) {
          b.template head<Dim>() = -gw;
          Tg.noalias() += I.s * gij - sj * (A[j] * b);
        } else {
          Tg.noalias() += (I.s + sj) * gij;
        }
      }
    }
    return Tg;
  }

  /// Wall repulsion on soil particle i from a boundary particle at xij (r² = |xij|², r < r_rep):
  /// ρ_i c_i² ((r0/r)⁴ − (r0/r)²) x_ij/r².
  Vec<Dim> repulsion(const Self& I, const Vec<Dim>& xij, double r2) const {
    const double q2 = (r_rep * r_rep) / r2;
    return (I.rho * I.c * I.c * (q2 * q2 - q2) / r2) * xij;
  }
};

}  // namespace

template <int Dim>
template <class Kernel, bool Corrected>
auto SphSolver<Dim>::momentum_pair_term() {
  const PairKernel<Kernel> K(h_);
  const double w_dx = Kernel::value(settings_.spacing, h_);
  return MomentumPairTerm<Dim, kBasis, Kernel, Corrected>{
      .K = K,
      .image = MinimumImage<Dim>(settings_.periodic),
      .w_dx = w_dx,
      .n_as = settings_.artificial_stress_n > 0.0 ? settings_.artificial_stress_n : K.w_self / w_dx,
      .alpha = settings_.viscosity_alpha,
      .beta = settings_.viscosity_beta,
      .h = h_,
      .eta2 = 0.01 * h_ * h_,
      .r_rep = settings_.wall_repulsion * settings_.spacing,
      .wave = wave_speed_.data(),
      .x = field<Position<Dim>>(),
      .v = field<Velocity<Dim>>(),
      .rho = field<Density>(),
      .vol = field<Volume>(),
      .mat = field<MaterialId>(),
      .kind = field<ParticleKind>(),
      .nrm = field<WallNormal<Dim>>(),
      .lnrm = field<LayerNormal<Dim>>(),
      .ps = field<PairStress<Dim>>(),
      .R = field<ArtificialStress<Dim>>(),
      .has_as = has_as_.data(),
      .A = Corrected ? correction_.data() : nullptr,
      .quadratic = settings_.quadratic_correction};
}

template <int Dim>
void SphSolver<Dim>::step() {
  if (settings_.total_lagrangian) {  // linear_elastic only (constructor): no model dispatch
    switch (settings_.kernel) {
      case KernelChoice::CubicSpline:
        return tl_step<CubicSpline<Dim>>();
      case KernelChoice::WendlandC2:
        return tl_step<WendlandC2<Dim>>();
    }
  }
  std::visit(
      [&](const auto& model) {
        switch (settings_.kernel) {  // no default: a kernel added to KernelChoice must be handled (-Wswitch)
          case KernelChoice::CubicSpline:
            return step_impl<CubicSpline<Dim>>(model);
          case KernelChoice::WendlandC2:
            return step_impl<WendlandC2<Dim>>(model);
        }
      },
      model_);
}

// ---- One step: the passes of the numbered list in solver.hpp -------------------------------------

template <int Dim>
template <class Kernel, class Model>
void SphSolver<Dim>::step_impl(const Model& model) {
  update_neighbours(Kernel::support * h_);    // 0. neighbour list (and cell reordering)
  const Vec<Dim> gbar = body_acceleration();  //    ḡ = g + a_earthquake of this step
  prepare_boundary_pairs(gbar);               // 1. volumes; the walls' stress extrapolation
  const bool corrected = settings_.kernel_correction;
  if (corrected) {                  // 2. A_i (consistent kernel gradients)
    gradient_correction<Kernel>();  //    L, dρ/dt, ρ̃, XSPH
    if (settings_.quadratic_correction)
      velocity_gradient<Kernel, true>();
    else
      velocity_gradient<Kernel, false>();  // with L_i ← L_i C_iᵀ at the end
  } else {
    velocity_gradient<Kernel, false>();
  }
  update_stress(model);  // 3. density, constitutive model, artificial stress
  if (corrected) {       // 4. pair forces → acceleration
    momentum<Kernel, true>();
    structure_forces<Kernel, true>();  // 4b. loads on tracked walls and piles (read only)
  } else {
    momentum<Kernel, false>();
    structure_forces<Kernel, false>();
  }
  integrate(gbar);  // 5. body force, damping, leap-frog
  time_ += dt_;     // 6. clock, state check, next Δt
  ++step_;
  check_state();
  update_dt();
}

// 1. Particle volumes for the pair sums; boundary particles: the extrapolation matrix of their
//    stress (below) in the pair-stress slot.
//
// Boundary particles (Bui et al. 2008) act on each soil particle i as its mirror image: in the
// pair (i, b) the wall particle b takes
//   velocity  2 v_b − v_i (no slip: zero relative velocity halfway between i and b), or
//             v_i − 2 ((v_i − v_b)·n) n (free slip: only the normal component mirrored);
//   stress    σ_b = σ_i − ρ_i d [ḡ_n I + ḡ_t ⊗ ν + ν ⊗ ḡ_t], d = (x_b − x_i)·ν,
//             shear mirrored through the wall (M σ_b M, M = I − 2nn) for free slip.
// (mirror_velocity and mirror_stress above; the pair passes 2 and 4 call them.)
// The stress extrapolation lets the wall carry the stress gradient equilibrium demands,
// ∂σ_ik/∂x_k = −ρ ḡ_i, assuming the stress varies only along the layering normal ν (flat
// ground, an infinite slope): its traction on the layering plane changes by −ρ_i ḡ d (normal and
// shear), the in-plane normal components take the isotropic part. On flat ground under gravity
// this is the hydrostatic term of Adami et al. (2012); on a slope or under horizontal shaking it
// also supplies the shear the base must carry.
// Why per pair and not a Shepard average over the wall particle's soil neighbours (Adami's
// form, used before 2026-11-22): the average couples a soil particle to every soil particle
// within 2h of the wall, one-way (no reaction), and with a stiffness or density contrast within
// that distance — a thin stiff base under a soft cover, or any layering near an inclined wall —
// the coupling made an oscillation grow until the soil failed, at any Δt. The mirror pair is
// local and, with the pair forms of steps 2 and 4, conserves energy (docs/sph.md, "Boundary
// particles and material interfaces").
template <int Dim>
void SphSolver<Dim>::prepare_boundary_pairs(const Vec<Dim>& gbar) {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const double* rho = field<Density>();
  const double* m = field<Mass>();
  const std::uint8_t* kind = field<ParticleKind>();
  const Vec<Dim>* lnrm = field<LayerNormal<Dim>>();
  Mat<Dim>* ps = field<PairStress<Dim>>();
  double* vol = field<Volume>();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    vol[i] = m[i] / rho[i];
    if (kind[i] == kSoil) continue;
    const Vec<Dim>& nu = lnrm[i];
    const double g_n = gbar.dot(nu);
    const Vec<Dim> g_t = gbar - g_n * nu;
    Mat<Dim> G = g_t * nu.transpose();
    G += G.transpose().eval();
    G.diagonal().array() += g_n;
    ps[i] = G;
  }
}

// After a pair pass (steps 2 and 4): every soil particle adds its reactions from the block buffers
// in the fixed order of PairBlocks::gather, then `finish` completes it.
template <int Dim>
template <class T, class Add, class Finish>
void SphSolver<Dim>::gather_reactions(const std::vector<T>& buffer, Add&& add, Finish&& finish) {
  const PairBlocks blocks{block_size_, block_reach_, store_.size()};
  const std::uint8_t* kind = field<ParticleKind>();
  blocks.gather(
      buffer.data(), [kind](std::size_t i) { return kind[i] == kSoil; }, add, finish);
}

// (The pair loops of steps 2 and 4 repeat the same ten-line neighbour header on purpose: folded
//  into a shared lambda it cost 20 % of the 2D speed, the captures defeating register reuse.)

// 2. Kernel-gradient correction, only with `kernel_correction`. Linear (the default, Bonet & Lok
//    1999, Randles & Libersky 1996): A_i = [C_i 0], C_i = M_i⁻¹, g_ij = C_i ∇_i W_ij, exact for linear
//    fields. With `quadratic_correction`: a gradient exact for any quadratic field, at the free
//    surface too (the idea of Zhang & Batra 2004's modified SPH, with the SPH gradient's weight). For a field
//    u_j − u_i = ∇u·r + Σ_{a≤b} c_ab r_a r_b (r = x_j − x_i) the Dim + Dim(Dim+1)/2 kernel moments
//    Σ_j V_j (u_j − u_i) b_ij, b_ij = F_ij p_ij = [∇_i W_ij; F_ij h m(r/h)] (kernel_basis; F_ij =
//    |∇_i W_ij|/r, so ∇_i W_ij = F_ij r), are B_i z with
//    z = [∇u; h c], B_i = Σ_j V_j b_ij ⊗ p_ij, p_ij = [r; h m(r/h)]. So z = B_i⁻¹ Σ_j V_j (u_j − u_i) b_ij and
//    the corrected gradient is ∇u_i = Σ_j V_j (u_j − u_i) g_ij with g_ij = A_i b_ij, A_i the first Dim
//    rows of B_i⁻¹. Why quadratic and not only linear (C_i = M_i⁻¹, M_i = Σ_j V_j ∇_i W_ij ⊗ r, the
//    top-left block of B_i; used before 2026-12-02): a bending beam's displacement is quadratic, and
//    at a free surface, where all neighbours lie on one side, the linear correction evaluates the
//    gradient at the centroid of the one-sided neighbourhood, 0.27Δx inside the outer row (cubic
//    spline, h = 1.2Δx): the outer fibres' strain is 6 % low at 10 particles through a beam, its
//    bending stiffness 6.7 % low and its period 3.5 % long (docs/validation/sph.md, "Clamped elastic
//    cantilever"). Inside a regular lattice the odd moments vanish, B_i is block diagonal and
//    g_ij = M_i⁻¹ ∇W_ij: the two corrections agree there. Not the default because a bent beam then
//    goes unstable earlier at fine resolution (docs/validation/sph.md, cantilever, second round).
//    The sums run over every neighbour the velocity-gradient sum uses, boundary particles included
//    (they stand in for the missing support at a wall). Guards: where det M_i < 0.2^Dim (the
//    geometric mean of M_i's eigenvalues below 0.2) the particle keeps the plain gradient
//    (A_i = [I 0]): a particle with few neighbours or all of them near one line (a detached grain, a
//    thin tongue after failure) has a near-singular M_i whose inverse would amplify noise into the
//    stress. Where B_i is ill-conditioned (B_i = Σ_j V_j F_ij p_ij ⊗ p_ij is symmetric positive
//    semi-definite: its Cholesky factor fails, or (max/min of the factor's diagonal)² > 10⁴, e.g.
//    neighbours on two lines only) it keeps the linear correction (A_i = [M_i⁻¹ 0]). The surfaces, edges and
//    corners of an intact lattice are fully corrected: det M_i (cubic spline, h = 1.2–1.5Δx, lattice
//    sums) is 0.95–1.03 inside, 0.37–0.39 on a face (2D) and 0.12–0.14 at a corner; in 3D 0.28–0.30
//    on a face, 0.07–0.09 on an edge, 0.014–0.025 at a corner (threshold 0.008). Boundary particles
//    keep A = [I 0]. Each particle sums its own row (no reactions): the sum is then the same on any
//    thread count.
template <int Dim>
template <class Kernel>
void SphSolver<Dim>::gradient_correction() {
  constexpr int N = kBasis;
  const PairKernel<Kernel> K(h_);
  const MinimumImage<Dim> image(settings_.periodic);
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* x = field<Position<Dim>>();
  const double* vol = field<Volume>();
  const std::uint8_t* kind = field<ParticleKind>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  correction_.resize(static_cast<std::size_t>(n));
  auto* A = correction_.data();
  const bool quadratic = settings_.quadratic_correction;
  // f(j, x_ij, r) for every neighbour j of i within the support, i itself excluded.
  const auto support_pairs = [&](std::size_t i, auto&& f) {
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = idx[k];
      const Vec<Dim> xij = image(x[i], x[j]);
      const double r2 = xij.squaredNorm();
      if (r2 >= K.cutoff2 || r2 == 0.0) continue;
      f(vol[j], xij, std::sqrt(r2));
    }
  };
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    if (kind[i] != kSoil) {
      A[i].setZero();
      A[i].template leftCols<Dim>().setIdentity();
      continue;
    }
    A[i] = correction_matrix<Dim, N, Kernel>(K, quadratic, [&](auto&& f) { support_pairs(i, f); });
  }
}

// 2. Velocity gradient, continuity, summation density, XSPH (soil particles):
//    L_i = Σ_j V_j (v_j − v_i) ⊗ ∇W_ij, dρ_i/dt = −Σ_j m_j (v_j − v_i)·∇W_ij,
//    ρ̃_i = Σ_j m_j W_ij, ξ_i = Σ_j V_j W_ij (v_j − v_i), v_j the mirror velocity of a boundary j.
//    As in step 4, each soil–soil pair is evaluated once; j's share (V_i dv ⊗ ∇W_ij,
//    −m_i dv·∇W_ij, m_i W_ij, −V_i W_ij dv with dv = v_j − v_i) goes to a block buffer (PairBlocks).
//    With the kernel-gradient correction (Corrected) L_i = Σ_j V_j dv ⊗ A_i b_ij = S_i A_iᵀ with
//    S_i = Σ_j V_j dv ⊗ b_ij (Dim × (Dim + Dim(Dim+1)/2)): S_i is summed like the plain L (j's share
//    V_i (−dv) ⊗ b_ji = V_i [dv ⊗ ∇W_ij, −dv ⊗ F_ij h m]), the particle's own part in its own slot
//    of its block's buffer, and multiplied by A_iᵀ once complete (the gather's finish). Continuity,
//    ρ̃ and XSPH keep the plain kernel.
template <int Dim>
template <class Kernel, bool Corrected>
void SphSolver<Dim>::velocity_gradient() {
  constexpr int Cols = Corrected ? kBasis : Dim;
  using Reaction = GradientReactionT<Cols>;
  using Sum = Eigen::Matrix<double, Dim, Cols>;
  const PairKernel<Kernel> K(h_);
  const MinimumImage<Dim> image(settings_.periodic);
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* x = field<Position<Dim>>();
  const Vec<Dim>* v = field<Velocity<Dim>>();
  const double* m = field<Mass>();
  const double* vol = field<Volume>();
  const std::uint8_t* kind = field<ParticleKind>();
  const Vec<Dim>* nrm = field<WallNormal<Dim>>();
  Mat<Dim>* L = field<VelocityGradient<Dim>>();
  double* drho = field<DensityRate>();
  double* rsum = field<SummationDensity>();
  Vec<Dim>* xs = field<XsphCorrection<Dim>>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  const std::int64_t nblocks = static_cast<std::int64_t>(blocks.count());
  std::vector<Reaction>* buffer;
  if constexpr (Corrected)
    buffer = &pair_grad_corrected_;
  else
    buffer = &pair_grad_;
  buffer->resize(blocks.slots());
  Reaction* all = buffer->data();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    const std::size_t first = b * blocks.size, last = std::min(blocks.n, first + blocks.size);
    Reaction* mine = blocks.buffer(all, b);  // mine[j]: the reaction to j
    std::fill(mine + first, mine + first + blocks.window(), Reaction{Sum::Zero(), Vec<Dim>::Zero(), 0.0, 0.0});
    for (std::size_t i = first; i < last; ++i) {
      if (kind[i] != kSoil) continue;
      Sum Li = Sum::Zero();
      Vec<Dim> xi_sum = Vec<Dim>::Zero();
      double dr = 0.0, rs = m[i] * K.w_self;
      const Vec<Dim> vi = v[i];
      const double Vi = vol[i], mi = m[i];
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
        const std::uint32_t j = idx[k];
        const bool soil_j = kind[j] == kSoil;
        if (soil_j && j < i) continue;  // evaluated from j's side
        const Vec<Dim> xij = image(x[i], x[j]);
        const double r2 = xij.squaredNorm();
        if (r2 >= K.cutoff2) continue;
        const double r = std::sqrt(r2);
        const double q = r * K.inv_h;
        const Vec<Dim> gw = xij * (r > 0.0 ? K.sigma_h * Kernel::shape_derivative(q) / r : 0.0);
        const double w = K.sigma * Kernel::shape(q);
        const Vec<Dim> dv = (soil_j ? v[j] : mirror_velocity<Dim>(v[i], v[j], nrm[j], kind[j] == kRoller)) - vi;
        Sum dvg;
        if constexpr (Corrected)
          dvg.noalias() = dv * kernel_basis<Dim, Cols>(gw, r > 0.0 ? -K.sigma_h * Kernel::shape_derivative(q) / r : 0.0,
                                                       xij, K.inv_h)
                                   .transpose();
        else
          dvg.noalias() = dv * gw.transpose();
        const double dvgw = dv.dot(gw);
        const double Vj = vol[j];
        Li.noalias() += Vj * dvg;
        dr -= m[j] * dvgw;
        rs += m[j] * w;
        xi_sum += (Vj * w) * dv;
        if (soil_j) {
          Reaction& g = mine[j];
          if constexpr (Corrected) {
            g.L.template leftCols<Dim>().noalias() += Vi * dvg.template leftCols<Dim>();
            g.L.template rightCols<Cols - Dim>().noalias() -= Vi * dvg.template rightCols<Cols - Dim>();
          } else {
            g.L.noalias() += Vi * dvg;
          }
          g.drho -= mi * dvgw;
          g.rsum += mi * w;
          g.xs -= (Vi * w) * dv;
        }
      }
      if constexpr (Corrected) {  // the own sums in the own slot, completed by the gather below
        Reaction& g = mine[i];
        g.L += Li;
        g.drho += dr;
        g.rsum += rs;
        g.xs += xi_sum;
      } else {
        L[i] = Li;
        drho[i] = dr;
        rsum[i] = rs;
        xs[i] = xi_sum;
      }
    }
  }
  if constexpr (Corrected) {
    const auto* A = correction_.data();
    blocks.gather_max(
        all,
        [](std::size_t) {
          return Reaction{Sum::Zero(), Vec<Dim>::Zero(), 0.0, 0.0};
        },
        [](Reaction& t, const Reaction& g) {
          t.L += g.L;
          t.drho += g.drho;
          t.rsum += g.rsum;
          t.xs += g.xs;
        },
        [&](std::size_t i, const Reaction& t) {
          if (kind[i] != kSoil) return 0.0;
          L[i].noalias() = t.L * A[i].transpose();
          drho[i] = t.drho;
          rsum[i] = t.rsum;
          xs[i] = t.xs;
          return 0.0;
        });
  } else {
    const auto add = [&](std::size_t i, const Reaction& g) {
      L[i] += g.L;
      drho[i] += g.drho;
      rsum[i] += g.rsum;
      xs[i] += g.xs;
    };
    if (settings_.kernel_correction) {  // the linear correction: L_i ← L_i C_iᵀ, C_i = A_i's first Dim columns
      const auto* A = correction_.data();
      gather_reactions(pair_grad_, add, [&](std::size_t i) {
        const Mat<Dim> C = A[i].template leftCols<Dim>();
        L[i] = (L[i] * C.transpose()).eval();
      });
    } else {
      gather_reactions(pair_grad_, add, [](std::size_t) {});
    }
  }
}

// 3. Density, stress (constitutive model), stress vanishing, artificial stress.
template <int Dim>
template <class Model>
void SphSolver<Dim>::update_stress(const Model& /*model*/) {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const double dt = dt_;
  const double eps_as = settings_.artificial_stress;
  const double sf_frac = settings_.stress_free_fraction;
  const double* m = field<Mass>();
  const std::int32_t* mat = field<MaterialId>();
  const std::uint8_t* kind = field<ParticleKind>();
  const double* drho = field<DensityRate>();
  const double* rsum = field<SummationDensity>();
  const Mat<Dim>* L = field<VelocityGradient<Dim>>();
  double* rho = field<Density>();
  double* vol = field<Volume>();
  Mat3* sig = field<Stress>();
  std::uint8_t* sfree = field<StressFree>();
  Mat<Dim>* R = field<ArtificialStress<Dim>>();
  Mat<Dim>* ps = field<PairStress<Dim>>();
  const MaterialParams* mats = materials_.data();
  // Prescribed pore water (pore_pressure.hpp): u of this step at the particle's position; the pair stress
  // of step 4 is the total stress σ′ − u I.
  const PoreWaterSettings& pw = settings_.pore_water;
  const bool water = pw.active();
  const PoreWaterStep pws =
      water ? PoreWaterStep(pw, earthquake_on_ ? time_ : 0.0, settings_.gravity, gravity_factor_) : PoreWaterStep();
  const Vec<Dim>* xpos = field<Position<Dim>>();
  double* upore = field<PorePressure>();
  // The model's internal variables (fields of the store), passed per particle to its update.
  const auto iv = field_arrays(typename Model::InternalVariables{});
  has_as_.resize(static_cast<std::size_t>(n));
  std::uint8_t* has_as = has_as_.data();
  // Σ Δλ by blocks of particles, then over the blocks in order: the same sum on any thread count.
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  block_sums_.assign(blocks.count(), 0.0);
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < static_cast<std::int64_t>(blocks.count()); ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    double plastic = 0.0;
    const std::size_t last = std::min(blocks.n, (b + 1) * blocks.size);
    for (std::size_t i = b * blocks.size; i < last; ++i) {
      has_as[i] = 0;
      if (kind[i] != kSoil) {
        R[i].setZero();
        continue;
      }
      const MaterialParams& p = mats[mat[i]];
      // Continuity, floored at the model's parting density (constitutive.hpp, `min_density`).
      rho[i] = std::max(rho[i] + dt * drho[i], Model::min_density(p));
      vol[i] = m[i] / rho[i];
      if (sf_frac > 0.0 && rsum[i] < sf_frac * p.density) {
        sfree[i] = 1;
        sig[i].setZero();
        R[i].setZero();
        ps[i].setZero();
        continue;
      }
      sfree[i] = 0;
      plastic +=
          std::apply([&](auto*... a) { return Model::update(sig[i], embed3<Dim>(L[i]), dt, rho[i], p, a[i]...); }, iv);
      if (eps_as > 0.0) {
        const Mat<Dim> s2 = sig[i].template topLeftCorner<Dim, Dim>();
        R[i] = artificial_stress<Dim>(s2, eps_as, rho[i]);
        has_as[i] = R[i].squaredNorm() > 0.0;
      }
      ps[i] = sig[i].template topLeftCorner<Dim, Dim>();
      if (water) {
        const double u = pws.pressure<Dim>(xpos[i]);
        upore[i] = u;
        ps[i].diagonal().array() -= u;
      }
    }
    block_sums_[b] = plastic;
  }
  stats_.plastic_increment = 0.0;
  for (const double p : block_sums_) stats_.plastic_increment += p;
}

// 4. Momentum: a_i = Σ_j m_j [(σ_i + σ_j)/(ρ_i ρ_j) − Π_ij I + f_ij^n (R_i + R_j)] ∇W_ij + ḡ
//    (Bui et al. 2010, eq. 12 with the stress pair in the form that pairs with the velocity gradient of
//    step 2, L_i = Σ_j V_j (v_j − v_i) ⊗ ∇W_ij: together they conserve energy also where the
//    density jumps between materials; the paper's σ_i/ρ_i² + σ_j/ρ_j² does not, and a layered
//    slope then oscillates at its interfaces, docs/sph.md). Summed as a force density
//    f_i = Σ_j V_j [σ_i + σ_j + ρ_i ρ_j (f^n (R_i + R_j) − Π_ij I)] ∇W_ij, a_i = f_i/ρ_i (ḡ: step 5).
//    Each soil–soil pair is evaluated once, by the particle of lower index: the pair term is
//    symmetric (T_ij = T_ji, ∇W_ji = −∇W_ij), so j receives −V_i T ∇W_ij. Those reactions go to a
//    block buffer (PairBlocks: no two threads write the same slot, and the sums are grouped alike
//    on any number of threads) gathered after the pass; soil–boundary pairs act on the soil
//    particle only.
//    With the kernel-gradient correction (Corrected, step 2) the stress pair becomes
//    V_j (σ_i g_ij − σ_j g_ji), g_ij = A_i b_ij the corrected gradient vector of step 2 (the form
//    whose work rate is Σ_i V_i σ_i : L̃_i with the corrected L̃ of step 2, as Bonet & Lok 1999 wrote
//    it for the linear correction, g_ij = C_i ∇W_ij, g_ji = −C_j ∇W_ij); it is still antisymmetric
//    under i ↔ j, so the reactions and linear momentum are as before. A boundary particle, the
//    mirror image of i, takes g_ib: (σ_i + σ_b) g_ib. Viscosity and artificial stress keep the plain
//    gradient (they are stabilisation terms, not the continuum).
//    Last-resort wall repulsion (Monaghan 1994 form, exponents 4 and 2): only a soil particle closer
//    than r0 = wall_repulsion·Δx to a boundary particle feels it — nothing in a normal configuration
//    (spacing ≈ Δx) — and it stops particles from being squeezed through walls.
template <int Dim>
template <class Kernel, bool Corrected>
void SphSolver<Dim>::momentum() {
  const auto P = momentum_pair_term<Kernel, Corrected>();
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const double* rho = P.rho;
  const std::uint8_t* kind = P.kind;
  Vec<Dim>* acc = field<Acceleration<Dim>>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  const std::int64_t nblocks = static_cast<std::int64_t>(blocks.count());
  pair_acc_.resize(blocks.slots());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    const std::size_t first = b * blocks.size, last = std::min(blocks.n, first + blocks.size);
    Vec<Dim>* mine = blocks.buffer(pair_acc_.data(), b);  // mine[j]: the reaction to j
    std::fill(mine + first, mine + first + blocks.window(), Vec<Dim>::Zero());
    for (std::size_t i = first; i < last; ++i) {
      if (kind[i] != kSoil) continue;
      const auto I = P.self(i);
      Vec<Dim> ai = Vec<Dim>::Zero();
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
        const std::uint32_t j = idx[k];
        const bool soil_j = kind[j] == kSoil;
        if (soil_j && j < i) continue;  // evaluated from j's side
        const Vec<Dim> xij = P.image(P.x[i], P.x[j]);
        const double r2 = xij.squaredNorm();
        if (r2 >= P.K.cutoff2) continue;
        const double r = std::sqrt(r2);
        const Vec<Dim> Tg = P(I, i, j, soil_j, xij, r);
        ai.noalias() += P.vol[j] * Tg;
        if (soil_j)
          mine[j].noalias() -= I.V * Tg;
        else if (r < P.r_rep)
          ai.noalias() += P.repulsion(I, xij, r2);
      }
      acc[i] = ai;
    }
  }
  gather_reactions(
      pair_acc_, [&](std::size_t i, const Vec<Dim>& r) { acc[i] += r; }, [&](std::size_t i) { acc[i] /= rho[i]; });
}

// 4b. Loads on the tracked structures: step 4's soil–boundary pair terms once more, with the state
//     step 4 used (positions, velocities, stress, volumes before the integration), each summed with
//     the opposite sign onto the structure of the boundary particle. The force step 4 gives soil
//     particle i from boundary particle b is m_i/ρ_i times its force-density term,
//       F_ib = V_i {V_b [σ_i + σ_b + ρ_i ρ_b (f^n (R_i + R_b) − Π_ib I)] ∇W_ib + ρ_i c_i² ((r0/r)⁴ − (r0/r)²) x_ib/r²},
//     the wall-repulsion part only for r < r0 (with the kernel-gradient correction the stress pair
//     is (σ_i + σ_b) g_ib, g_ib = A_i b_ib, as in step 4); the structure receives −F_ib at x_b. The
//     term is step 4's own (MomentumPairTerm), so the two cannot drift apart; test_physics
//     "StructureLoads" checks that the loads on all structures balance the soil's momentum change
//     from its boundary pairs.
//     Summed per block of particles (PairBlocks) and then over the blocks in order: the same sums
//     on any number of threads.
template <int Dim>
template <class Kernel, bool Corrected>
void SphSolver<Dim>::structure_forces() {
  if (structure_base_.empty()) return;
  const auto P = momentum_pair_term<Kernel, Corrected>();
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const std::uint8_t* kind = P.kind;
  const std::int32_t* sid = field<StructureId>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  const Vec<Dim>* base = structure_base_.data();
  const auto ns = static_cast<std::int32_t>(structure_base_.size());
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  const std::int64_t nblocks = static_cast<std::int64_t>(blocks.count());
  structure_block_loads_.assign(blocks.count() * structure_base_.size(), StructureLoad<Dim>{});
  StructureLoad<Dim>* all = structure_block_loads_.data();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    const std::size_t first = b * blocks.size, last = std::min(blocks.n, first + blocks.size);
    StructureLoad<Dim>* mine = all + b * structure_base_.size();
    for (std::size_t i = first; i < last; ++i) {
      if (kind[i] != kSoil) continue;
      const auto I = P.self(i);
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
        const std::uint32_t j = idx[k];
        if (kind[j] == kSoil || sid[j] < 0 || sid[j] >= ns) continue;
        const Vec<Dim> xij = P.image(P.x[i], P.x[j]);
        const double r2 = xij.squaredNorm();
        if (r2 >= P.K.cutoff2) continue;
        const double r = std::sqrt(r2);
        Vec<Dim> fi = P.vol[j] * P(I, i, j, false, xij, r);  // force density on i from j
        if (r < P.r_rep) fi.noalias() += P.repulsion(I, xij, r2);
        const Vec<Dim> F = -I.V * fi;  // on the structure
        const Vec<Dim> arm = P.image(P.x[j], base[sid[j]]);
        StructureLoad<Dim>& load = mine[sid[j]];
        load.force += F;
        if constexpr (Dim == 3)
          load.moment += arm.cross(F);
        else
          load.moment[1] += arm[1] * F[0] - arm[0] * F[1];
      }
    }
  }
  for (auto& l : structure_loads_) l = StructureLoad<Dim>{};
  for (std::size_t b = 0; b < blocks.count(); ++b)
    for (std::size_t k = 0; k < structure_base_.size(); ++k) {
      structure_loads_[k].force += all[b * structure_base_.size() + k].force;
      structure_loads_[k].moment += all[b * structure_base_.size() + k].moment;
    }
}

template void SphSolver<2>::step();
template void SphSolver<3>::step();
template void SphSolver<2>::prepare_boundary_pairs(const Vec<2>&);
template void SphSolver<3>::prepare_boundary_pairs(const Vec<3>&);

}  // namespace geohaz::sph
