#pragma once
// The pair passes of the SPH step shared by the one-process step (solver_passes.cpp) and the
// passes over several ranks (solver_distributed.cpp): the momentum pair term, the reaction gather,
// the velocity gradient (2) and the momentum (4). Private to the library. Each translation unit
// instantiates its own form (Ghosts false there, true here), so that the one-process loops are
// compiled as before, unaffected by the inlining budget the other form would take.
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
namespace pass_detail {

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

}  // namespace pass_detail

using namespace pass_detail;

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
template <class T, class Add, class Finish>
void SphSolver<Dim>::gather_reactions(const std::vector<T>& buffer, Add&& add, Finish&& finish) {
  const PairBlocks blocks{block_size_, block_reach_, owned_count()};  // the ghosts' sums are their owners'
  const std::uint8_t* kind = field<ParticleKind>();
  blocks.gather(
      buffer.data(), [kind](std::size_t i) { return kind[i] == kSoil; }, add, finish);
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
template <class Kernel, bool Corrected, bool Ghosts>
void SphSolver<Dim>::velocity_gradient() {
  constexpr int Cols = Corrected ? kBasis : Dim;
  using Reaction = GradientReactionT<Cols>;
  using Sum = Eigen::Matrix<double, Dim, Cols>;
  const PairKernel<Kernel> K(h_);
  const MinimumImage<Dim> image(settings_.periodic);
  const std::int64_t n = static_cast<std::int64_t>(owned_count());
  const std::uint32_t nown = static_cast<std::uint32_t>(n);  // a ghost's reaction is its owner's
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
        if (soil_j && (!Ghosts || j < nown)) {
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
template <class Kernel, bool Corrected, bool Ghosts>
void SphSolver<Dim>::momentum() {
  const auto P = momentum_pair_term<Kernel, Corrected>();
  const std::int64_t n = static_cast<std::int64_t>(owned_count());
  const std::uint32_t nown = static_cast<std::uint32_t>(n);  // a ghost's reaction is its owner's
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
        if constexpr (Ghosts) {  // (the one-process branch below as it was: any change to it cost 13 %)
          if (soil_j) {
            if (j < nown) mine[j].noalias() -= I.V * Tg;
          } else if (r < P.r_rep) {
            ai.noalias() += P.repulsion(I, xij, r2);
          }
        } else {
          if (soil_j)
            mine[j].noalias() -= I.V * Tg;
          else if (r < P.r_rep)
            ai.noalias() += P.repulsion(I, xij, r2);
        }
      }
      acc[i] = ai;
    }
  }
  gather_reactions(
      pair_acc_, [&](std::size_t i, const Vec<Dim>& r) { acc[i] += r; }, [&](std::size_t i) { acc[i] /= rho[i]; });
}

}  // namespace geohaz::sph
