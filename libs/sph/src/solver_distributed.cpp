// The SPH solver over several ranks (domain decomposition; decomposition.hpp, docs/sph.md "Domain
// decomposition"): the switch to distributed mode, step 0's rebuild with migration and ghosts, and
// the reductions of step 6. The passes themselves (solver_passes.cpp) only loop over the owned
// particles and refresh the ghosts' fields.
#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "geohaz/core/errors.hpp"
#include "geohaz/sph/solver.hpp"
#include "solver_kernels.hpp"
#include "solver_pair_passes.hpp"

namespace geohaz::sph {

template <int Dim>
void SphSolver<Dim>::distribute(std::shared_ptr<const Communicator> comm, bool store_is_share) {
  if (nb_.builds() > 0 || domain_) throw std::logic_error("SphSolver::distribute: call it once, before the first step");
  if (settings_.total_lagrangian)
    throw InputError("the total-Lagrangian formulation does not run on several ranks yet (issue #36)", "",
                     "numerics.formulation", "total_lagrangian");
  domain_ = std::make_unique<DomainDecomposition<Dim>>(std::move(comm), settings_.periodic);
  if (store_is_share)
    domain_->adopt(store_);
  else
    domain_->scatter(store_);
  nb_.invalidate();
  max_drift_ = 0.0;
}

// 0 (distributed). The rebuild decision is the one-rank rule with the drift of every rank
// (reduce_over_ranks), so every rank rebuilds at the same step. The partition is recomputed at the
// first rebuild and then with the reordering schedule of one rank (every reorder_every-th rebuild),
// when the owned particles are also sorted by cell; in between, particles that left their box
// migrate to its owner.
template <int Dim>
void SphSolver<Dim>::rebuild_distributed() {
  auto& S = store_;
  if (!nb_.rebuild_due(S.size(), max_drift_)) return;
  const std::int64_t builds = nb_.builds();
  const bool scheduled = settings_.reorder_every > 0 && builds % settings_.reorder_every == 0;
  // The cost of a particle: a soil particle 1 + its neighbours in the last list (3 before the first
  // list: a guess, the next partition measures), a boundary particle 1 (it is only ever a partner).
  const std::size_t n = domain_->owned();
  const std::uint8_t* kind = field<ParticleKind>();
  const bool have_list = nb_.list().size() == S.size() && builds > 0;
  const auto off = nb_.list().offsets();
  std::vector<std::int64_t> w(n, 1);
  for (std::size_t i = 0; i < n; ++i)
    if (kind[i] == kSoil) w[i] = 1 + (have_list ? static_cast<std::int64_t>(off[i + 1] - off[i]) : 3);
  const double halo = nb_.list_cutoff();
  domain_->rebuild(S, halo, scheduled || builds == 0, w, scheduled ? halo : 0.0);
  nb_.invalidate();
  nb_.update(S.template get<Position<Dim>>(), S.template get<PositionAtBuild<Dim>>(), 0.0);
  choose_pair_blocks();
  max_drift_ = 0.0;
}

// 3 (distributed): what the momentum pass reads of a neighbour, for the ghosts; the flag "has
// artificial stress" from the artificial stress as the owner set it.
template <int Dim>
void SphSolver<Dim>::update_stress_ghosts() {
  domain_->template update_ghosts<Density, Volume, PairStress<Dim>, ArtificialStress<Dim>>(store_);
  const bool as = settings_.artificial_stress > 0.0;
  const Mat<Dim>* R = field<ArtificialStress<Dim>>();
  for (std::size_t i = domain_->owned(); i < store_.size(); ++i) has_as_[i] = as && R[i].squaredNorm() > 0.0;
}

// 6 (distributed). One collective per step: every rank's maxima (speed, acceleration, drift), the
// flag of its state check, Σ Δλ and the structure loads, gathered and reduced in rank order: the
// maxima are exact, the sums the same on every rank and in every repetition on as many ranks.
template <int Dim>
void SphSolver<Dim>::reduce_over_ranks() {
  std::string error;
  try {  // the check of this rank's particles; every rank must learn of a failure before throwing
    check_state();
  } catch (const SimulationError& e) {
    error = e.what();
  }
  std::vector<double> mine{stats_.max_speed, stats_.max_acceleration, max_drift_, error.empty() ? 0.0 : 1.0,
                           stats_.plastic_increment};
  for (const auto& l : structure_loads_) {
    for (int d = 0; d < Dim; ++d) mine.push_back(l.force[d]);
    for (int d = 0; d < 3; ++d) mine.push_back(l.moment[d]);
  }
  const std::size_t width = mine.size();
  const std::vector<double> all = domain_->comm().all_gather(mine);
  StepStats st;
  double drift = 0.0, failed = 0.0;
  for (auto& l : structure_loads_) l = StructureLoad<Dim>{};
  for (std::size_t r = 0; r < all.size() / width; ++r) {
    const double* a = all.data() + r * width;
    st.max_speed = std::max(st.max_speed, a[0]);
    st.max_acceleration = std::max(st.max_acceleration, a[1]);
    drift = std::max(drift, a[2]);
    failed = std::max(failed, a[3]);
    st.plastic_increment += a[4];
    const double* f = a + 5;
    for (auto& l : structure_loads_) {
      for (int d = 0; d < Dim; ++d) l.force[d] += *f++;
      for (int d = 0; d < 3; ++d) l.moment[d] += *f++;
    }
  }
  if (failed > 0.0)
    throw SimulationError(error.empty() ? "the state check failed on another rank at step " + std::to_string(step_) +
                                              " (its message names the particle)"
                                        : error);
  stats_ = st;
  max_drift_ = drift;
}

template <int Dim>
SphStore<Dim> SphSolver<Dim>::gathered_store(bool root_only) const {
  if (domain_) return domain_->gather(store_, root_only);
  SphStore<Dim> out = store_;
  const auto& id = out.template get<ParticleId>();
  std::vector<std::uint32_t> perm(out.size());
  std::iota(perm.begin(), perm.end(), 0u);
  std::stable_sort(perm.begin(), perm.end(), [&](std::uint32_t p, std::uint32_t q) { return id[p] < id[q]; });
  out.reorder(perm);
  return out;
}

template void SphSolver<2>::distribute(std::shared_ptr<const Communicator>, bool);
template void SphSolver<3>::distribute(std::shared_ptr<const Communicator>, bool);
template void SphSolver<2>::rebuild_distributed();
template void SphSolver<3>::rebuild_distributed();
template void SphSolver<2>::update_stress_ghosts();
template void SphSolver<3>::update_stress_ghosts();
template void SphSolver<2>::reduce_over_ranks();
template void SphSolver<3>::reduce_over_ranks();
template SphStore<2> SphSolver<2>::gathered_store(bool) const;
template SphStore<3> SphSolver<3>::gathered_store(bool) const;

// Passes 2 and 4 with ghosts (a soil pair with a ghost has no reaction: its owner sums it).
template <int Dim>
template <class Kernel>
void SphSolver<Dim>::distributed_velocity_gradient() {
  if (settings_.kernel_correction && settings_.quadratic_correction)
    velocity_gradient<Kernel, true, true>();
  else
    velocity_gradient<Kernel, false, true>();
}

template <int Dim>
template <class Kernel>
void SphSolver<Dim>::distributed_momentum() {
  if (settings_.kernel_correction)
    momentum<Kernel, true, true>();
  else
    momentum<Kernel, false, true>();
}

template void SphSolver<2>::distributed_velocity_gradient<CubicSpline<2>>();
template void SphSolver<2>::distributed_velocity_gradient<WendlandC2<2>>();
template void SphSolver<3>::distributed_velocity_gradient<CubicSpline<3>>();
template void SphSolver<3>::distributed_velocity_gradient<WendlandC2<3>>();
template void SphSolver<2>::distributed_momentum<CubicSpline<2>>();
template void SphSolver<2>::distributed_momentum<WendlandC2<2>>();
template void SphSolver<3>::distributed_momentum<CubicSpline<3>>();
template void SphSolver<3>::distributed_momentum<WendlandC2<3>>();

}  // namespace geohaz::sph
