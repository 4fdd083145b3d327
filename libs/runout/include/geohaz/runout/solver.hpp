#pragma once
/// \file solver.hpp
/// RunoutSolver: one time step of the depth-averaged particle debris-flow model (seed 000 §3),
/// readable top to bottom in step():
///
///  1. neighbours within 2·d0: by default visited straight from a cell scan rebuilt every step
///     (CellPairScan: the pairs are used once, so no list is written); with numerics.skin > 0 a
///     Verlet list within (2 + skin)·d0 (NeighbourList), rebuilt when a particle has moved more
///     than skin·d0/2 since the last build and after removals. The scan visits exactly the pairs,
///     in the same order, of a list without skin. The particles are reordered by cell every
///     reorder_interval steps;
///  2. pair pass 1: flow depth h_i = Σ_j V_j W(r_ij, d0) (cubic spline, self included);
///     pair pass 2: head-pressure acceleration a_p,i = C g Σ_j (V_j/d0³) f(r_ij/d0) x̂_ij
///     (head_pressure.hpp) and the velocity smoothing Δv_i = ε Σ_j 2V_j/(h_i + h_j) (v_j − v_i) W_ij
///     (the particle velocity correction of seed 000 §2, Monaghan 1994, with a symmetric weight so
///     momentum is conserved). Without it a particle lattice under the seed's force is unstable
///     (f rises with distance on 1 < x < 1.5), and round-off grows into a "thermal" noise;
///  3. adaptive time step Δt = cfl · d0 / max_i(S_i + √(g h_i)) (the maximum taken in the pair
///     pass), capped by dt_max and the end time;
///  4. per particle: driving acceleration in map view for a particle held on the surface z(x, y)
///         a_h = −g ∇z / (1 + |∇z|²) + a_p
///     (exact for a plane: the along-slope acceleration is g sin θ; bed curvature is neglected),
///     predicted velocity v* = v + Δt a_h, then basal friction applied implicitly on the surface
///     speed S = |(v, ∇z·v)| with g_n = g cos θ and h_n = h cos θ (basal_friction.hpp): it may stop
///     a particle, never reverse it; position x += Δt v (symplectic Euler);
///  5. particles whose new position is off the terrain (raster edge, nodata) are removed and their
///     volume is added to the lost volume.
/// All per-particle loops are parallel over i with no order-dependent reduction (only maxima and
/// "any" flags), so 1 and N threads give bit-identical results.

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/kernels.hpp"
#include "geohaz/core/neighbours.hpp"
#include "geohaz/runout/basal_friction.hpp"
#include "geohaz/runout/fields.hpp"
#include "geohaz/runout/head_pressure.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {

/// Model parameters (SI units), filled from the config by the app.
struct RunoutParameters {
  double gravity = 9.81;    ///< g (m/s²)
  double density = 1800.0;  ///< ρ of the mixture (kg/m³), for pressures ρv² in the outputs
  double d0 = 5.0;          ///< reference particle spacing (m); kernel h = d0, support 2·d0
  double h0 = 1.0;          ///< reference depth (m): nominal particle volume V0 = h0·d0²
  double cfl = 0.3;         ///< Courant number on d0 (1)
  double dt_max = 1.0;      ///< largest time step (s)
  double dt_min = 1e-7;     ///< a smaller step is a blow-up (s)
  double duration = 600.0;  ///< simulated time (s)
  double min_depth = 0.01;  ///< floor on the bed-normal depth in the friction law (m)
  double smoothing = 0.0;   ///< ε of the velocity correction per step (1), 0 switches it off
  double pressure_scale = HeadPressureForce::consistent_normalisation();  ///< C (1)
  int reorder_interval = 25;  ///< steps between cell reorderings of the store
  double skin = 0.0;          ///< neighbour-list skin in units of d0 (list cutoff (2 + skin)·d0)
  BasalFriction friction = ModifiedManningFriction{};

  double nominal_volume() const noexcept { return h0 * d0 * d0; }
};

/// Volumes (m³) at a moment of the run; initial = mobile + deposited + lost up to round-off.
struct VolumeBudget {
  double initial = 0.0, mobile = 0.0, deposited = 0.0, lost = 0.0;
  std::size_t lost_particles = 0;
  double balance_error() const noexcept { return mobile + deposited + lost - initial; }
};

/// Below this many particles the per-particle loops run on one thread: the work of a step is then
/// smaller than the cost of waking the team (and, on a loaded machine, of waiting for it).
inline constexpr std::int64_t kParallelMin = 2048;

template <class Surface>
class RunoutSolver {
 public:
  RunoutSolver(Surface surface, RunoutParameters params, Periodicity<2> periodic = {})
      : surface_(std::move(surface)), p_(std::move(params)), periodic_(periodic) {}

  RunoutStore& particles() noexcept { return store_; }
  const RunoutStore& particles() const noexcept { return store_; }
  const Surface& surface() const noexcept { return surface_; }
  const RunoutParameters& parameters() const noexcept { return p_; }
  double time() const noexcept { return time_; }
  std::int64_t step_count() const noexcept { return step_; }
  double last_dt() const noexcept { return dt_; }

  /// Call once the particles (position, velocity, volume, id) are in the store: samples the
  /// terrain, records start elevations and the initial volume, computes depths. Throws
  /// std::invalid_argument when a particle is off the terrain or has a non-positive volume.
  void initialise() {
    auto& x = store_.get<Position<2>>();
    const auto& vol = store_.get<Volume>();
    for (std::size_t i = 0; i < store_.size(); ++i) {
      SurfaceSample s;
      if (!surface_.sample(x[i], s))
        throw std::invalid_argument("particle " + std::to_string(i) + " is off the terrain");
      if (!(vol[i] > 0.0)) throw std::invalid_argument("particle " + std::to_string(i) + " has no volume");
      store_.get<Elevation>()[i] = s.z;
      store_.get<StartElevation>()[i] = s.z;
      store_.get<StartPosition>()[i] = x[i];
      store_.get<SurfaceGradient>()[i] = s.grad;
      store_.get<Moving>()[i] = 1;
    }
    budget_ = {};
    for (double v : vol) budget_.initial += v;
    compute_pair_terms();
    update_budget();
  }

  /// Advance one adaptive step; returns Δt. SimulationError on NaN or time-step collapse.
  double step() {
    // 1-2. Neighbours and the pair pass, which also returns the signal speed of the time step.
    if (step_ % p_.reorder_interval == 0 && store_.size() > 1) reorder_by_cell();
    const double signal = compute_pair_terms();

    // 3. Time step (max is exact in any order: thread-count independent).
    double dt = signal > 0.0 ? p_.cfl * p_.d0 / signal : p_.dt_max;
    dt = std::min(dt, p_.dt_max);
    const double remaining = p_.duration - time_;
    if (remaining > 0.0 && dt > remaining) dt = remaining;
    if (!(dt >= p_.dt_min) && remaining > p_.dt_min) {
      std::ostringstream msg;
      msg << "time step collapsed to " << dt << " s (signal speed " << signal << " m/s) at step " << step_
          << ", t = " << time_ << " s";
      throw SimulationError(msg.str());
    }

    // 4-5. Integrate with the friction law resolved once for the whole loop.
    const IntegrateFlags flags = std::visit([&](const auto& law) { return integrate(law, dt); }, p_.friction);
    if (flags.non_finite) throw_non_finite();
    if (flags.leaving) remove_leaving();
    dt_ = dt;
    time_ += dt;
    ++step_;
    update_budget();
    return dt;
  }

  /// True when friction holds every particle at rest (nothing will move again).
  bool all_stopped() const noexcept {
    for (auto m : store_.get<Moving>())
      if (m) return false;
    return true;
  }
  /// Whether the run is over: duration reached, all stopped, or no particle left.
  bool finished() const noexcept {
    return time_ >= p_.duration - 1e-12 * std::max(1.0, p_.duration) || store_.empty() || (step_ > 0 && all_stopped());
  }

  const VolumeBudget& budget() const noexcept { return budget_; }

  /// Recompute the depths and head-pressure accelerations for the current positions (also done
  /// by step(); public for tests and outputs). Returns the signal speed of the time step,
  /// max_i (S_i + √(g h_i)) (m/s), computed in the same pass.
  double compute_pair_terms() {
    if (store_.empty()) return 0.0;
    if (p_.skin > 0.0) {
      // Verlet list: rebuilt when a particle has moved more than half the skin since the build.
      if (!list_valid_ || max_displacement() > 0.5 * p_.skin * p_.d0) {
        build_list();
        list_valid_ = true;
      }
      const auto& x = store_.get<Position<2>>();
      const auto offsets = list_.offsets();
      const auto indices = list_.indices();
      const bool periodic = periodic_.any();
      return pair_terms([&](std::size_t i, auto&& f) {
        const Vec2 xi = x[i];
        for (std::uint32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
          const std::uint32_t j = indices[k];
          const Vec2 xij = periodic ? periodic_.min_image(xi - x[j]) : Vec2(xi - x[j]);
          f(static_cast<std::size_t>(j), xij, xij.squaredNorm());
        }
      });
    }
    // No skin: the pairs are used once per build, so they are visited straight from the cell scan
    // (same pairs in the same order as the list, without writing and re-reading it).
    const auto& x = store_.get<Position<2>>();
    scan_.build(std::span<const Vec2>(x.data(), x.size()), HeadPressureForce::support * p_.d0, periodic_);
    return pair_terms([&](std::size_t i, auto&& f) { scan_.for_each_neighbour(i, f); });
  }

 private:
  /// The pair pass over the neighbours given by `neighbours(i, f)`, which calls f(j, xij, r²) for
  /// every j ≠ i of particle i (possibly including skin pairs beyond the support). Returns the
  /// signal speed max_i (S_i + √(g h_i)).
  template <class Neighbours>
  double pair_terms(Neighbours&& neighbours) {
    const auto& vol = store_.get<Volume>();
    auto& h = store_.get<FlowDepth>();
    auto& ap = store_.get<HeadAcceleration>();
    const auto& v = store_.get<Velocity<2>>();
    const auto& grad = store_.get<SurfaceGradient>();
    auto& dv = store_.get<VelocityCorrection>();
    const double d0 = p_.d0;
    const double inv_d0 = 1.0 / d0;
    const double w0 = CubicSpline<2>::value(0.0, d0);
    const double coef = p_.pressure_scale * p_.gravity * inv_d0 * inv_d0 * inv_d0;
    const double g = p_.gravity;
    const std::int64_t n = static_cast<std::int64_t>(store_.size());
    const double support2 = 4.0 * d0 * d0, sigma = CubicSpline<2>::sigma(d0);
    // Signal speed of particle i for the CFL condition: surface speed plus gravity-wave speed.
    const auto signal_speed = [&](std::size_t i) {
      const double vz = grad[i].dot(v[i]);
      return std::sqrt(v[i].squaredNorm() + vz * vz) + std::sqrt(g * h[i]);
    };
    const double eps = p_.smoothing;
    double signal = 0.0;
    if (eps == 0.0) {
      // One pass: depth and head pressure (the pressure does not need the neighbours' depths).
#pragma omp parallel for reduction(max : signal) schedule(static) if (n >= kParallelMin)
      for (std::int64_t ii = 0; ii < n; ++ii) {
        const auto i = static_cast<std::size_t>(ii);
        double depth = vol[i] * (2.0 / 3.0);
        Vec2 acc = Vec2::Zero();
        // W/σ (kernels.hpp) and f (head_pressure.hpp) written out per branch of q; the
        // arithmetic is exactly that of CubicSpline and HeadPressureForce::shape (the steady-flow
        // test's particle-scale fluctuation grows from round-off, so its order is kept).
        neighbours(i, [&](std::size_t j, const Vec2& xij, double r2) {
          if (r2 >= support2) return;  // in the list's skin: no contribution
          const double r = std::sqrt(r2);
          const double q = r * inv_d0;
          const double vj = vol[j];
          if (q < 1.0) {
            depth += vj * (2.0 / 3.0 - q * q + 0.5 * q * q * q);
            if (r > 0.0) acc += (coef * vj * ((1.0 - q) / (1.0 + q)) / r) * xij;
          } else if (q < 2.0) {
            const double t = 2.0 - q;
            depth += vj * (t * t * t / 6.0);
            acc += (coef * vj * (-0.5 * (q - 1.0) * (q - 2.0)) / r) * xij;
          }
        });
        depth *= sigma;
        h[i] = depth;
        ap[i] = acc;
        dv[i] = Vec2::Zero();
        signal = std::max(signal, signal_speed(i));
      }
      return signal;
    }
    // Pass 1: depths.
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      double depth = vol[i] * w0;
      neighbours(i, [&](std::size_t j, const Vec2& xij, double /*r2*/) {
        depth += vol[j] * CubicSpline<2>::value(xij.norm(), d0);
      });
      h[i] = depth;
    }
    // Pass 2: head pressure and velocity smoothing (needs every depth).
#pragma omp parallel for reduction(max : signal) schedule(static) if (n >= kParallelMin)
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      Vec2 acc = Vec2::Zero(), corr = Vec2::Zero();
      const Vec2 vi = v[i];
      const double hi = h[i];
      neighbours(i, [&](std::size_t j, const Vec2& xij, double /*r2*/) {
        const double r = xij.norm();
        if (r > 0.0) acc += (coef * vol[j] * HeadPressureForce::shape(r * inv_d0) / r) * xij;
        corr += (2.0 * vol[j] / (hi + h[j]) * CubicSpline<2>::value(r, d0)) * (v[j] - vi);
      });
      ap[i] = acc;
      dv[i] = eps * corr;
      signal = std::max(signal, signal_speed(i));
    }
    return signal;
  }

  /// Sort the store by cell for memory locality (every reorder_interval steps); the pairs are
  /// then rebuilt for the new order.
  void reorder_by_cell() {
    const auto& x = store_.get<Position<2>>();
    if (p_.skin > 0.0) {
      build_list();
      store_.reorder(list_.cell_order());
    } else {
      scan_.build(std::span<const Vec2>(x.data(), x.size()), HeadPressureForce::support * p_.d0, periodic_);
      store_.reorder(scan_.cell_order());
    }
    list_valid_ = false;
  }
  void build_list() {
    const auto& x = store_.get<Position<2>>();
    list_.build(std::span<const Vec2>(x.data(), x.size()), (HeadPressureForce::support + p_.skin) * p_.d0, periodic_);
    store_.get<ListPosition>() = x;
  }
  /// Largest distance moved since the list was built (max: order-independent, exact).
  double max_displacement() const {
    const auto& x = store_.get<Position<2>>();
    const auto& x0 = store_.get<ListPosition>();
    const std::int64_t n = static_cast<std::int64_t>(store_.size());
    double m2 = 0.0;
#pragma omp parallel for reduction(max : m2) schedule(static) if (n >= kParallelMin)
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const Vec2 d = periodic_.any() ? periodic_.min_image(x[i] - x0[i]) : Vec2(x[i] - x0[i]);
      m2 = std::max(m2, d.squaredNorm());
    }
    return std::sqrt(m2);
  }

  /// What the integration found, so the serial checks run only when needed.
  struct IntegrateFlags {
    bool leaving = false;     ///< a particle left the terrain
    bool non_finite = false;  ///< a position or velocity is not finite
  };

  template <class Law>
  IntegrateFlags integrate(const Law& law, double dt) {
    auto& x = store_.get<Position<2>>();
    auto& v = store_.get<Velocity<2>>();
    auto& grad = store_.get<SurfaceGradient>();
    auto& z = store_.get<Elevation>();
    auto& speed = store_.get<Speed>();
    auto& path = store_.get<PathLength>();
    auto& moving = store_.get<Moving>();
    auto& leaving = store_.get<Leaving>();
    const auto& h = store_.get<FlowDepth>();
    const auto& ap = store_.get<HeadAcceleration>();
    const auto& dv = store_.get<VelocityCorrection>();
    const double g = p_.gravity;
    const bool periodic = periodic_.any();
    const std::int64_t n = static_cast<std::int64_t>(store_.size());
    int any_leaving = 0, any_non_finite = 0;
#pragma omp parallel for reduction(max : any_leaving, any_non_finite) schedule(static) if (n >= kParallelMin)
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const Vec2 gz = grad[i];
      const double p2 = gz.squaredNorm();
      const double cos_theta = 1.0 / std::sqrt(1.0 + p2);
      // Gravity's component along the surface, projected on the map: −g∇z/(1+|∇z|²).
      const Vec2 a = (-g / (1.0 + p2)) * gz + ap[i];
      const Vec2 v_star = v[i] + dv[i] + dt * a;
      const double vz = gz.dot(v_star);
      const double s_star = std::sqrt(v_star.squaredNorm() + vz * vz);
      const double h_n = std::max(h[i] * cos_theta, p_.min_depth);
      const FrictionTerms t = law.terms(g, g * cos_theta, h_n, s_star);
      const double s = speed_after_friction(s_star, dt, t);
      const Vec2 v_new = s > 0.0 ? Vec2(v_star * (s / s_star)) : Vec2::Zero();
      Vec2 x_new = x[i] + dt * v_new;
      if (periodic) x_new = periodic_.wrap(x_new);
      SurfaceSample smp;
      if (!surface_.sample(x_new, smp)) {
        leaving[i] = 1;
        v[i] = v_new;
        any_leaving = 1;
        if (!(x[i].allFinite() && v_new.allFinite())) any_non_finite = 1;
        continue;
      }
      leaving[i] = 0;
      path[i] += dt * v_new.norm();
      x[i] = x_new;
      v[i] = v_new;
      z[i] = smp.z;
      grad[i] = smp.grad;
      speed[i] = s;
      moving[i] = s > 0.0 ? 1 : 0;
      if (!(x_new.allFinite() && v_new.allFinite())) any_non_finite = 1;
    }
    return {any_leaving != 0, any_non_finite != 0};
  }

  /// Name the first particle with a non-finite state (integrate() found one).
  void throw_non_finite() const {
    const auto& x = store_.get<Position<2>>();
    const auto& v = store_.get<Velocity<2>>();
    for (std::size_t i = 0; i < store_.size(); ++i) {
      if (x[i].allFinite() && v[i].allFinite()) continue;
      std::ostringstream msg;
      msg << "particle " << store_.get<ParticleId>()[i] << " has a non-finite state at step " << step_
          << " (t = " << time_ << " s): position (" << x[i].x() << ", " << x[i].y() << ") m, velocity (" << v[i].x()
          << ", " << v[i].y() << ") m/s; reduce cfl or check the DSM for spikes";
      throw SimulationError(msg.str());
    }
    throw std::logic_error("throw_non_finite: no particle has a non-finite state");
  }

  void remove_leaving() {
    auto& leaving = store_.get<Leaving>();
    const auto& vol = store_.get<Volume>();
    bool any = false;
    for (std::size_t i = 0; i < store_.size(); ++i)
      if (leaving[i]) {
        budget_.lost += vol[i];
        ++budget_.lost_particles;
        any = true;
      }
    if (any) {
      store_.remove_if(std::span<const std::uint8_t>(leaving.data(), leaving.size()));
      list_valid_ = false;
    }
  }

  void update_budget() {
    const auto& vol = store_.get<Volume>();
    const auto& moving = store_.get<Moving>();
    budget_.mobile = budget_.deposited = 0.0;
    for (std::size_t i = 0; i < store_.size(); ++i) (moving[i] ? budget_.mobile : budget_.deposited) += vol[i];
  }

  Surface surface_;
  RunoutParameters p_;
  Periodicity<2> periodic_;
  RunoutStore store_;
  NeighbourList<2> list_;  // with a skin (numerics.skin > 0)
  CellPairScan<2> scan_;   // without (the default)
  VolumeBudget budget_;
  bool list_valid_ = false;
  double time_ = 0.0, dt_ = 0.0;
  std::int64_t step_ = 0;
};

}  // namespace geohaz::runout
