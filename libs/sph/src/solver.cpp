#include "geohaz/sph/solver.hpp"

// The SPH solver's construction, neighbour list, time integration (step 5), state check, time step
// and geostatic phase. The passes of a step are in solver_passes.cpp, the total-Lagrangian
// formulation in solver_total_lagrangian.cpp, what they share in solver_kernels.hpp.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>
#include <variant>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/parallel.hpp"
#include "solver_kernels.hpp"

namespace geohaz::sph {

namespace {

/// Whether a store has every field of a list (compile time).
template <class Store, class... Tags>
constexpr bool has_fields(FieldList<Tags...>) {
  return (Store::template has<Tags>() && ...);
}

/// Zero every internal variable of every model (fields.hpp FieldList, constitutive.hpp).
template <class Store, class... Tags>
void zero_fields(Store& s, FieldList<Tags...>) {
  [[maybe_unused]] auto zero = [&](auto& v) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    if constexpr (std::is_arithmetic_v<T>)
      std::fill(v.begin(), v.end(), T{});
    else
      std::fill(v.begin(), v.end(), T::Zero());
  };
  (zero(s.template get<Tags>()), ...);
}
template <class Store, class... Models>
void reset_internal_variables(Store& s, std::type_identity<std::variant<Models...>>) {
  (zero_fields(s, typename Models::InternalVariables{}), ...);
}

}  // namespace

template <int Dim>
SphSolver<Dim>::SphSolver(SphStore<Dim> store, std::vector<MaterialParams> materials, ConstitutiveModel model,
                          SolverSettings<Dim> settings)
    : store_(std::move(store)), materials_(std::move(materials)), model_(model), settings_(std::move(settings)) {
  if (materials_.empty()) throw InputError("the SPH model needs at least one material");
  if (!(settings_.spacing > 0.0)) throw InputError("particle spacing must be > 0", "", "spacing");
  if (!(settings_.h_factor >= 1.0 && settings_.h_factor <= 2.0))
    throw InputError("h_factor must be in [1, 2]", "", "h_factor");
  for (auto& m : materials_) m.finalise();
  const auto& mat = store_.template get<MaterialId>();
  for (std::size_t i = 0; i < store_.size(); ++i)
    if (mat[i] < 0 || static_cast<std::size_t>(mat[i]) >= materials_.size())
      throw InputError("particle " + std::to_string(i) + " names material " + std::to_string(mat[i]) + " but only " +
                       std::to_string(materials_.size()) + " are defined");
  fill_missing_layer_normals(store_);
  if (settings_.total_lagrangian) {
    if (!std::holds_alternative<LinearElastic>(model_))
      throw InputError(
          "the total-Lagrangian formulation is for elastic bodies: it needs model.constitutive = "
          "linear_elastic, not " +
              std::visit([](const auto& m) { return std::string(std::decay_t<decltype(m)>::name); }, model_),
          "", "numerics.formulation", "total_lagrangian");
    const auto& kind = store_.template get<ParticleKind>();
    if (std::any_of(kind.begin(), kind.end(), [](std::uint8_t k) { return k != kSoil; }))
      throw InputError(
          "the total-Lagrangian formulation takes no boundary (wall, pile) particles: support the "
          "body with clamp.boxes",
          "", "numerics.formulation", "total_lagrangian");
    if (settings_.periodic.any())
      throw InputError("the total-Lagrangian formulation takes no periodic axes", "", "numerics.formulation",
                       "total_lagrangian");
    if (!(settings_.hourglass >= 0.0 && settings_.hourglass <= 100.0))
      throw InputError("must be in [0, 100]", "", "numerics.hourglass", std::to_string(settings_.hourglass));
    if (settings_.kernel_correction && settings_.quadratic_correction && settings_.hourglass > 1.0)
      throw InputError(
          "must be at most 1 with the quadratic-complete gradient (kernel_correction = quadratic): a larger "
          "hourglass force drives a growing mode with it",
          "", "numerics.hourglass", std::to_string(settings_.hourglass));
  }
  h_ = settings_.h_factor * settings_.spacing;
  damping_ = settings_.damping;
  set_model(model_);
  dt_ = std::min(settings_.dt_max, settings_.cfl * h_ / max_wave_speed_);
  dt_ = std::min(dt_, model_dt_limit_);
}

template <int Dim>
void SphSolver<Dim>::set_model(const ConstitutiveModel& model) {
  model_ = model;
  std::visit(
      [&](const auto& m) {
        using Model = std::decay_t<decltype(m)>;
        static_assert(has_fields<SphStore<Dim>>(typename Model::InternalVariables{}),
                      "a model's internal variables must be fields of SphStore (fields.hpp)");
        wave_speed_.clear();
        max_wave_speed_ = 0.0;
        model_dt_limit_ = std::numeric_limits<double>::infinity();
        for (const auto& p : materials_) {
          wave_speed_.push_back(Model::wave_speed(p));
          max_wave_speed_ = std::max(max_wave_speed_, wave_speed_.back());
          model_dt_limit_ = std::min(model_dt_limit_, Model::time_step_limit(p, h_));
        }
      },
      model_);
}

template <int Dim>
std::string SphSolver<Dim>::model_name() const {
  return std::visit([](const auto& m) { return std::string(std::decay_t<decltype(m)>::name); }, model_);
}

template <int Dim>
double SphSolver<Dim>::bytes_per_particle() const {
  const double n = std::max<double>(1.0, static_cast<double>(store_.size()));
  return static_cast<double>(SphStore<Dim>::bytes_per_particle()) +
         4.0 * static_cast<double>(nb_.list().pair_count()) / n + 4.0 + 3.0 * 4.0 +
         1.0 +  // CSR indices + offsets + cell data + artificial-stress flag
         static_cast<double>(pair_acc_.size() * sizeof(Vec<Dim>) + pair_grad_.size() * sizeof(GradientReaction) +
                             pair_grad_corrected_.size() * sizeof(CorrectedGradientReaction)) /
             n +  // block buffers of the pair reactions (n (1 + W/B) slots each)
         static_cast<double>(correction_.size() * sizeof(correction_[0])) / n +  // A_i (kernel_correction)
         static_cast<double>(tl_X_.size() * sizeof(Vec<Dim>) + tl_V0_.size() * sizeof(double) +
                             tl_F_.size() * sizeof(Mat<Dim>) + tl_off_.size() * 4 +
                             tl_idx_.size() * (4 + 4 + sizeof(Vec<Dim>) + sizeof(double))) /
             n;  // total-Lagrangian reference data (per pair: index, reverse slot, g⁰, hourglass weight)
}

namespace {

/// z of a polyline (x, z) at x, held constant beyond its ends (x non-decreasing).
double polyline_at(const std::vector<std::array<double, 2>>& p, double x) noexcept {
  if (x <= p.front()[0]) return p.front()[1];
  if (x >= p.back()[0]) return p.back()[1];
  const auto it =
      std::upper_bound(p.begin(), p.end(), x, [](double v, const std::array<double, 2>& q) { return v < q[0]; });
  const auto& a = *(it - 1);
  const auto& b = *it;
  return b[0] > a[0] ? a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]) : b[1];
}

}  // namespace

double PoreWaterSettings::offset(double t) const noexcept {
  if (history_times.empty()) return 0.0;
  if (t <= history_times.front()) return history_offsets.front();
  if (t >= history_times.back()) return history_offsets.back();
  const auto it = std::upper_bound(history_times.begin(), history_times.end(), t);
  const auto k = static_cast<std::size_t>(it - history_times.begin());
  const double w = (t - history_times[k - 1]) / (history_times[k] - history_times[k - 1]);
  return (1.0 - w) * history_offsets[k - 1] + w * history_offsets[k];
}

double PoreWaterSettings::level(double x, double dz) const noexcept {
  const double zw = polyline_at(phreatic, x) + dz;
  return ground.empty() ? zw : std::min(zw, polyline_at(ground, x));
}

template <int Dim>
void SphSolver<Dim>::update_neighbours(double cutoff) {
  // The core Neighbours object: an optional Verlet skin lets the list be reused while no particle
  // has moved more than half the skin (max_drift_, from step 5); cell reordering keeps neighbours
  // close in memory, at every reorder_every-th rebuild (the object's schedule).
  auto& S = store_;
  if (nb_.settings().cutoff != cutoff) configure_neighbours(cutoff);
  if (domain_) return rebuild_distributed();
  const auto u = nb_.update(S.template get<Position<Dim>>(), S.template get<PositionAtBuild<Dim>>(), max_drift_);
  if (!u.rebuilt) return;
  if (u.reordered()) S.reorder(u.permutation);
  choose_pair_blocks();
  max_drift_ = 0.0;
}

template <int Dim>
void SphSolver<Dim>::configure_neighbours(double cutoff) {
  NeighbourSettings<Dim> ns;
  ns.cutoff = cutoff;
  ns.skin = settings_.neighbour_skin * h_;
  ns.reorder_every = domain_ ? 0 : settings_.reorder_every;  // distributed: the decomposition sorts
  ns.periodic = settings_.periodic;
  nb_.configure(ns);
}

template <int Dim>
void SphSolver<Dim>::choose_pair_blocks() {
  // The reach W of the list: the largest index distance of a soil–soil pair (the others are
  // evaluated from both sides). B = n/8: eight blocks for the threads (a static share of blocks is
  // then the contiguous share of particles the threads had before), and few slots beyond n,
  // n (1 + W/B) in all (1.08n in the 2D benchmark, 2.6n in 3D); but at least W/3 and 64.
  // Distributed: a pair with a ghost is evaluated from the owned side only (no reaction).
  const std::uint8_t* kind = field<ParticleKind>();
  const auto nown = static_cast<std::uint32_t>(owned_count());
  const PairBlocks blocks = nb_.blocks_for(
      [kind, nown](std::uint32_t i, std::uint32_t j) { return kind[i] == kSoil && kind[j] == kSoil && j < nown; });
  block_size_ = blocks.size;
  block_reach_ = blocks.reach;
}

template <int Dim>
void SphSolver<Dim>::resume(const SolverState& st) {
  tl_ready_ = false;  // total-Lagrangian: the reference X = x − u is rebuilt at the next step
  time_ = st.time;
  step_ = st.step;
  dt_ = st.dt;
  // Over several ranks (a file of any rank count): the first step partitions, migrates and builds
  // the lists afresh (distribute() invalidated them). The pairs are the same, their sums in another
  // order, and the build count starts again: the same state within round-off.
  if (domain_) return;
  double support = 0.0;
  switch (settings_.kernel) {
    case KernelChoice::CubicSpline:
      support = CubicSpline<Dim>::support;
      break;
    case KernelChoice::WendlandC2:
      support = WendlandC2<Dim>::support;
      break;
  }
  const auto& xb = store_.template get<PositionAtBuild<Dim>>();
  configure_neighbours(support * h_);
  nb_.restore(xb, st.neighbour_builds);
  choose_pair_blocks();
  // The drift since that build, as step 5 computes it.
  const MinimumImage<Dim> image(settings_.periodic);
  const auto& x = store_.template get<Position<Dim>>();
  double drift = 0.0;
  for (std::size_t i = 0; i < store_.size(); ++i) drift = std::max(drift, image(x[i], xb[i]).squaredNorm());
  max_drift_ = std::sqrt(drift);
}

template <int Dim>
Vec<Dim> SphSolver<Dim>::body_acceleration() const {
  // Effective body acceleration ḡ = g + a_eq (Bui et al. 2010, eq. 26); gravity along −axis Dim−1.
  Vec<Dim> gbar = Vec<Dim>::Zero();
  gbar[Dim - 1] = -settings_.gravity * gravity_factor_;
  if (earthquake_on_ && settings_.earthquake.active()) {
    gbar[0] += settings_.earthquake.horizontal(time_);
    gbar[Dim - 1] += settings_.earthquake.vertical(time_);
  }
  return gbar;
}

template <int Dim>
void SphSolver<Dim>::track_structures(std::vector<Vec<Dim>> base_points) {
  structure_base_ = std::move(base_points);
  structure_loads_.assign(structure_base_.size(), StructureLoad<Dim>{});
}

// 5. Body force ḡ, Cundall local damping (Bui et al. 2010, eq. 14), leap-frog update (kick–drift, with
//    the XSPH correction in the drift); boundary particles move with their prescribed velocity, clamped
//    soil particles stay at rest.
//    The step statistics (max speed, max acceleration) and the drift since the last neighbour
//    build (Verlet skin) are gathered here.
template <int Dim>
void SphSolver<Dim>::integrate(const Vec<Dim>& gbar) {
  const std::int64_t n = static_cast<std::int64_t>(owned_count());  // ghosts: from their owners
  const double dt = dt_;
  const double zeta = damping_;
  const double eps_x = settings_.xsph;
  const auto& per = settings_.periodic;
  const bool periodic_any = per.any();
  const MinimumImage<Dim> image(per);
  const std::uint8_t* kind = field<ParticleKind>();
  const Vec<Dim>* xs = field<XsphCorrection<Dim>>();
  const Vec<Dim>* xb = field<PositionAtBuild<Dim>>();
  Vec<Dim>* x = field<Position<Dim>>();
  Vec<Dim>* v = field<Velocity<Dim>>();
  Vec<Dim>* acc = field<Acceleration<Dim>>();
  Vec<Dim>* disp = field<Displacement<Dim>>();
  const std::uint8_t* clamped = field<Clamped>();
  double vmax = 0.0, amax = 0.0, drift = 0.0;
#pragma omp parallel for schedule(static) reduction(max : vmax, amax, drift) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    if (kind[i] != kSoil) {
      const Vec<Dim> dx = dt * v[i];
      x[i] += dx;
      disp[i] += dx;
      if (periodic_any) x[i] = per.wrap(x[i]);
      drift = std::max(drift, image(x[i], xb[i]).squaredNorm());
      continue;
    }
    Vec<Dim> a = acc[i] + gbar;
    if (zeta > 0.0) {
      for (int d = 0; d < Dim; ++d) {
        const double sgn = v[i][d] > 0.0 ? 1.0 : (v[i][d] < 0.0 ? -1.0 : 0.0);
        a[d] -= zeta * std::abs(a[d]) * sgn;
      }
    }
    acc[i] = a;
    if (clamped[i]) {  // held at rest in place (a clamped region); acc keeps the force that holds it
      v[i].setZero();
      continue;
    }
    v[i] += dt * a;
    const Vec<Dim> dx = dt * (v[i] + eps_x * xs[i]);
    x[i] += dx;
    disp[i] += dx;
    if (periodic_any) x[i] = per.wrap(x[i]);
    vmax = std::max(vmax, v[i].norm());
    amax = std::max(amax, a.norm());
    drift = std::max(drift, image(x[i], xb[i]).squaredNorm());
  }
  max_drift_ = std::sqrt(drift);
  stats_.max_speed = vmax;
  stats_.max_acceleration = amax;
}

template <int Dim>
void SphSolver<Dim>::check_state() const {
  const auto& x = store_.template get<Position<Dim>>();
  const auto& v = store_.template get<Velocity<Dim>>();
  const auto& sig = store_.template get<Stress>();
  const auto& id = store_.template get<ParticleId>();
  const std::size_t n = owned_count();
  const bool ok_stats = std::isfinite(stats_.max_speed) && std::isfinite(stats_.max_acceleration);
  std::size_t bad = n;
  std::string what;
  // Cheap global test first; locate the culprit only when something is wrong.
  bool box_ok = true;
  for (std::size_t i = 0; i < n && box_ok; ++i)
    for (int d = 0; d < Dim; ++d)
      if (!(x[i][d] >= settings_.domain_lo[d] && x[i][d] <= settings_.domain_hi[d])) {
        box_ok = false;
        bad = i;
        what = std::isfinite(x[i][d]) ? "left the domain" : "has a non-finite position";
      }
  if (ok_stats && box_ok) return;
  if (bad == n) {
    for (std::size_t i = 0; i < n; ++i)
      if (!v[i].allFinite() || !sig[i].allFinite()) {
        bad = i;
        what = "has a non-finite velocity or stress";
        break;
      }
  }
  std::ostringstream os;
  if (bad < n) {
    os << "particle id " << id[bad] << " " << what << " at position (";
    for (int d = 0; d < Dim; ++d) os << (d ? ", " : "") << x[bad][d];
    os << ") m";
  } else {
    os << "non-finite speed or acceleration";
  }
  os << " at step " << step_ << ", t = " << time_ << " s (dt = " << dt_ << " s)";
  throw SimulationError(os.str());
}

template <int Dim>
void SphSolver<Dim>::update_dt() {
  const double c = settings_.total_lagrangian ? tl_wave_speed_ : max_wave_speed_;  // TL: hourglass included
  double dt = settings_.cfl * h_ / (c + stats_.max_speed);
  if (stats_.max_acceleration > 0.0)
    dt = std::min(dt, settings_.force_factor * std::sqrt(h_ / stats_.max_acceleration));
  dt = std::min(dt, model_dt_limit_);
  dt = std::min(dt, settings_.dt_max);
  if (!(dt >= settings_.dt_min)) {
    std::ostringstream os;
    os << "time step collapsed to " << dt << " s (< dt_min " << settings_.dt_min << " s) at step " << step_
       << ", t = " << time_ << " s: max speed " << stats_.max_speed << " m/s, max acceleration "
       << stats_.max_acceleration << " m/s^2";
    throw SimulationError(os.str());
  }
  dt_ = dt;
}

template <int Dim>
GeostaticReport SphSolver<Dim>::apply_gravity_gradually(double duration, double damping, bool elastic,
                                                        const std::function<void()>& on_step) {
  if (settings_.total_lagrangian)  // its reference is the start of the main phase (docs/sph.md)
    throw InputError("the total-Lagrangian formulation takes no geostatic phase", "", "numerics.formulation",
                     "total_lagrangian");
  GeostaticReport rep;
  rep.duration = duration;
  const ConstitutiveModel saved = model_;
  const double saved_damping = damping_;
  // A solid is loaded as linear elastic if asked; a model without an elastic range (a fluid) keeps its law.
  if (elastic && std::visit([](const auto& m) { return std::decay_t<decltype(m)>::elastic_loading; }, model_))
    set_model(LinearElastic{});
  damping_ = damping;
  earthquake_on_ = false;
  const double t0 = time_;
  const std::int64_t s0 = step_;
  while (time_ - t0 < duration) {
    const double s = (time_ - t0) / (0.5 * duration);
    gravity_factor_ = std::min(1.0, s);
    step();
    if (on_step) on_step();
  }
  set_model(saved);
  damping_ = saved_damping;
  gravity_factor_ = 1.0;
  earthquake_on_ = true;
  rep.steps = step_ - s0;
  rep.max_speed = stats_.max_speed;
  for (auto& v : store_.template get<Velocity<Dim>>()) v.setZero();
  // Boundary particles keep their prescribed wall velocity only in the main phase: none here.
  for (auto& d : store_.template get<Displacement<Dim>>()) d.setZero();
  reset_internal_variables(store_, std::type_identity<ConstitutiveModel>{});  // Σ Δλ of the loading is not failure
  time_ = 0.0;
  return rep;
}

template class SphSolver<2>;
template class SphSolver<3>;

}  // namespace geohaz::sph
