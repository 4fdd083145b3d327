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
#include "solver_pair_passes.hpp"

namespace geohaz::sph {

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
  // The pair passes on one process here; over several ranks (with ghosts) in solver_distributed.cpp,
  // so that this translation unit compiles the one-process loops alone (solver_pair_passes.hpp).
  if (corrected) gradient_correction<Kernel>();  // 2. A_i (consistent kernel gradients)
  if (domain_)                                   //    L, dρ/dt, ρ̃, XSPH
    distributed_velocity_gradient<Kernel>();
  else if (corrected && settings_.quadratic_correction)
    velocity_gradient<Kernel, true, false>();
  else
    velocity_gradient<Kernel, false, false>();  // with L_i ← L_i C_iᵀ at the end if corrected
  update_stress(model);                         // 3. density, constitutive model, artificial stress
  if (domain_)                                  // 4. pair forces → acceleration
    distributed_momentum<Kernel>();
  else if (corrected)
    momentum<Kernel, true, false>();
  else
    momentum<Kernel, false, false>();
  if (corrected)  // 4b. loads on tracked walls and piles (read only)
    structure_forces<Kernel, true>();
  else
    structure_forces<Kernel, false>();
  integrate(gbar);  // 5. body force, damping, leap-frog
  if (domain_) domain_->template update_ghosts<Position<Dim>, Velocity<Dim>>(store_);
  time_ += dt_;  // 6. clock, state check, next Δt
  ++step_;
  if (domain_)
    reduce_over_ranks();  // the maxima and sums of every rank, the state check of all
  else
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
  const std::int64_t n = static_cast<std::int64_t>(owned_count());  // ghosts: from their owners, below
  const Vec<Dim>* x = field<Position<Dim>>();
  const double* vol = field<Volume>();
  const std::uint8_t* kind = field<ParticleKind>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  correction_.resize(store_.size());
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
  if (domain_) domain_->update_ghost_array(correction_);
}

// 3. Density, stress (constitutive model), stress vanishing, artificial stress.
template <int Dim>
template <class Model>
void SphSolver<Dim>::update_stress(const Model& /*model*/) {
  const std::int64_t n = static_cast<std::int64_t>(owned_count());
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
  has_as_.resize(store_.size());
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
  if (domain_) update_stress_ghosts();
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
  const std::int64_t n = static_cast<std::int64_t>(owned_count());
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
