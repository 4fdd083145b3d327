#pragma once
/// \file solver.hpp
/// RunoutSolver: one time step of the depth-averaged particle debris-flow model, readable top to
/// bottom in step(). Particles move in map view (x, y) on the terrain z(x, y); p = ∇z, cos²θ =
/// 1/(1 + |p|²), P = I − p pᵀ/(1 + |p|²) (the inverse metric of the surface: it turns a map-view
/// force into the map-view acceleration of a particle held on the bed). docs/runout.md derives it.
///
///  1. neighbours within 2·d0: by default visited straight from a cell scan rebuilt every step
///     (CellPairScan: the pairs are used once, so no list is written); with numerics.skin > 0 a
///     Verlet list within (2 + skin)·d0 (NeighbourList), rebuilt when a particle has moved more
///     than skin·d0/2 since the last build and after removals. The particles are reordered by cell
///     at every reorder_every-th rebuild;
///  2. pair pass (each pair once, the partner's share through fixed-order block reactions, so the
///     sums do not depend on the thread count; with the velocity smoothing or a Verlet list each
///     particle visits all its neighbours): vertical depth h_i = Σ_j V_j W(r_ij, d0) (cubic spline, self included), the
///     neighbours' mean velocity ṽ_i = Σ_j V_j W_ij v_j / h_i, and the head-pressure force
///         F_i = C g Σ_j ½(cos²θ_i + cos²θ_j) (V_j/d0³) f(r_ij/d0) x̂_ij        (head_pressure.hpp)
///     whose continuum limit is −∇(g cos²θ h): the map gradient of the hydrostatic energy
///     ½ g cos θ h_n² per unit bed area (h_n = h cos θ); with the optional velocity smoothing
///     (numerics.smoothing = ε) a second pass adds Δv_i = ε Σ_j 2V_j/(h_i + h_j) (v_j − v_i) W_ij;
///  3. adaptive time step Δt = cfl · d0 / max_i(S_i + √(g h_i)) (the maximum taken in the pair
///     pass), capped by dt_max and the end time;
///  4. per particle:
///     a. lateral mixing (an artificial viscosity, Sampl & Zwinger 2004 as in AvaFrame com1DFA),
///        implicit: v ← (v + kΔt ṽ)/(1 + kΔt), k = C_mix |ṽ − v|_s √(h_n/V);
///     b. driving acceleration along the bed: a = −g cos²θ p + P F_i; within 2 d0 of a barrier
///        whose crest is above the flow surface, plus the push of the mirror layer the wall stands
///        for, P C g cos θ h_w M(s/d0)/d0 away from it (barriers.hpp), which the wall takes;
///     c. basal friction applied implicitly on the surface speed S = |(v, p·v)| with the bed-normal
///        stress of g_n = cos θ (g + vᵀHv)⁺ (gravity plus the centripetal acceleration of the bed
///        curvature along the velocity, H the Hessian of z; zero when the particle would leave the
///        bed) and the depth h_n = h cos θ (basal_friction.hpp): it may stop a particle, never
///        reverse it; position x += Δt v (symplectic Euler);
///     d. barriers (barriers.hpp, set_barriers): a step that would cross a barrier below its crest
///        ends at the wall with the velocity reflected, v_n' = −e v_n, the tangential speed reduced
///        by μ_w (1 + e) v_n, the rest of the step taken with v'; the wall takes ρ V (1 + e) v_n.
///        A particle whose flow surface is above the crest, or that passes an open barrier, crosses;
///     e. the bed constraint: the velocity is turned into the tangent plane at the new position
///        keeping its magnitude S (the normal reaction does no work), as AvaFrame com1DFA
///        reprojects it;
///     With spatial processes (processes.hpp, set_processes) the friction coefficients are those of
///     the particle's cell, forest drag k_f S² joins the law's drag, and a particle in an erodible
///     cell records the volume it asks to entrain;
///  5. entrainment granted in store order, capped by the layer, the mass joining at rest; the wall
///     impulses and crossed volumes added to the barrier tally in store order;
///     particles whose new position is off the terrain (raster edge, nodata) are removed and their
///     volume is added to the lost volume; inflow hydrographs inject the particles now due;
///  6. the volume budget and the kinetic energy Σ ½ ρ V S²; the run ends at the duration, when
///     every particle is at rest, or when the kinetic energy has fallen below
///     stop_energy_fraction of its peak (AvaFrame com1DFA / RAMMS practice) — not before the
///     inflows have delivered their volume.
/// All per-particle loops are parallel over i with no order-dependent reduction (only maxima and
/// "any" flags); entrainment, injection and the barrier tally are serial in store order; so 1 and N threads give
/// bit-identical results.

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/kernels.hpp"
#include "geohaz/core/neighbours.hpp"
#include "geohaz/core/parallel.hpp"
#include "geohaz/runout/barriers.hpp"
#include "geohaz/runout/basal_friction.hpp"
#include "geohaz/runout/fields.hpp"
#include "geohaz/runout/head_pressure.hpp"
#include "geohaz/runout/parameters.hpp"
#include "geohaz/runout/processes.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {

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

  /// Spatial fields (friction zones, forest, erodible layer) and inflow hydrographs (docs/runout.md,
  /// "Processes"). Set before initialise(). The erodible depth is consumed as the bed is eroded.
  void set_processes(SpatialProcesses proc) {
    proc_ = std::move(proc);
    eroded_.assign(proc_.erodible_depth.empty() ? 0 : proc_.grid.cells(), 0.0);
    emitted_.assign(proc_.inflows.size(), 0.0);
    slot_.assign(proc_.inflows.size(), 0);
  }
  const SpatialProcesses& processes() const noexcept { return proc_; }
  /// Depth eroded from the bed per cell of the processes' grid (m, vertical; empty without an
  /// erodible layer).
  const std::vector<double>& eroded_depth() const noexcept { return eroded_; }
  /// Volume each inflow has delivered so far (m³).
  const std::vector<double>& inflow_volumes() const noexcept { return emitted_; }
  /// True while an inflow hydrograph still has volume to deliver.
  bool inflow_pending() const noexcept {
    for (std::size_t m = 0; m < emitted_.size(); ++m)
      if (emitted_[m] < proc_.inflows[m].volume() - 1e-9 * p_.nominal_volume()) return true;
    return false;
  }

  /// Barriers across the flow (barriers.hpp; docs/runout.md, "Barriers"). Set before initialise().
  void set_barriers(BarrierSet b) {
    barriers_ = std::move(b);
    const std::size_t nb = barriers_.size();
    tally_.impulse.assign(nb, 0.0);
    tally_.passed.assign(nb, 0.0);
    tally_.contacts.assign(nb, 0.0);
    tally_.window_depth.assign(nb, 0.0);
    tally_.touched.assign(barriers_.bins(), 0);
  }
  const BarrierSet& barriers() const noexcept { return barriers_; }
  /// What the walls have taken so far (impulses, crossed volumes, the bins touched and the depth at
  /// the wall since the last reset_barrier_window()).
  const BarrierTally& barrier_tally() const noexcept { return tally_; }
  /// Start a new window for the wetted bins and the depth at the wall (the outputs call it per row).
  void reset_barrier_window() {
    std::fill(tally_.touched.begin(), tally_.touched.end(), std::uint8_t{0});
    std::fill(tally_.window_depth.begin(), tally_.window_depth.end(), 0.0);
  }

  /// Call once the particles (position, velocity, volume, id) are in the store: samples the
  /// terrain, records start elevations and the initial volume, computes depths. Throws
  /// std::invalid_argument when a particle is off the terrain or has a non-positive volume.
  void initialise() {
    configure_neighbours();
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
      store_.get<SurfaceCurvature>()[i] = s.hess;
      store_.get<BedCos>()[i] = 1.0 / std::sqrt(1.0 + s.grad.squaredNorm());
      const Vec2 v = store_.get<Velocity<2>>()[i];
      store_.get<Speed>()[i] = std::hypot(v.norm(), s.grad.dot(v));
      store_.get<VerticalVelocity>()[i] = s.grad.dot(v);
      store_.get<Moving>()[i] = 1;
    }
    budget_ = {};
    for (double v : vol) budget_.initial += v;
    next_id_ = 0;
    for (auto id : store_.get<ParticleId>()) next_id_ = std::max(next_id_, id + 1);
    energy_stop_ = false;
    compute_pair_terms();
    update_budget();
  }

  /// Advance one adaptive step; returns Δt. SimulationError on NaN or time-step collapse.
  double step() {
    // 1-2. Neighbours (reordered by cell at every reorder_every-th rebuild) and the pair pass,
    // which also returns the signal speed of the time step.
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
    if (flags.entraining) entrain();
    if (flags.walls) tally_walls();
    if (flags.leaving) remove_leaving();
    dt_ = dt;
    time_ += dt;
    ++step_;
    if (!proc_.inflows.empty()) inject(time_);
    update_budget();
    return dt;
  }

  /// True when friction holds every particle at rest (nothing will move again).
  bool all_stopped() const noexcept {
    for (auto m : store_.get<Moving>())
      if (m) return false;
    return true;
  }
  /// Whether the run is over: duration reached, all stopped, no particle left, or the kinetic
  /// energy below stop_energy_fraction of its peak.
  bool finished() const noexcept {
    if (time_ >= p_.duration - 1e-12 * std::max(1.0, p_.duration)) return true;
    if (inflow_pending()) return false;
    return store_.empty() || (step_ > 0 && all_stopped()) || energy_stop_;
  }
  /// True when the run ended (or would end) by the kinetic-energy criterion.
  bool stopped_by_energy() const noexcept { return energy_stop_; }

  const VolumeBudget& budget() const noexcept { return budget_; }

  /// Recompute the depths and head-pressure accelerations for the current positions (also done
  /// by step(); public for tests and outputs), rebuilding the neighbours (and reordering the store)
  /// when due.
  /// Returns the signal speed of the time step, max_i (S_i + √(g h_i)) (m/s), computed in the same
  /// pass.
  double compute_pair_terms() {
    if (store_.empty()) return 0.0;
    // Neighbours (core Neighbours): with numerics.skin > 0 a Verlet list rebuilt when a particle
    // has moved more than half the skin since the build; without, the pairs are used once per
    // build, so they are visited straight from the cell scan (same pairs in the same order as the
    // list, without writing and re-reading it), and without the velocity smoothing each pair
    // once (half_pair_terms).
    {
      const auto& x = store_.get<Position<2>>();
      auto& xb = store_.get<ListPosition>();
      const auto u = nb_.update(x, p_.skin > 0.0 ? std::span<Vec2>(xb) : std::span<Vec2>());
      if (u.reordered()) store_.reorder(u.permutation);
    }
    const std::span<const Vec2> x = store_.get<Position<2>>();
    if (p_.skin == 0.0 && p_.smoothing == 0.0) return half_pair_terms();
    return pair_terms([&](std::size_t i, auto&& f) { nb_.for_each_neighbour(x, i, f); });
  }

 private:
  /// What a particle gathers from its neighbours in the pair pass: the depth sum Σ V_j W_ij and
  /// the W-weighted velocity sums (per σ), and the head-pressure sums (map and vertical parts).
  struct PairSums {
    double depth, vx, vy, vz, ax, ay, az;
  };
  /// The pair pass of pair_terms (no smoothing) with each pair evaluated once, by the particle of
  /// the lower slot in the scan's cell order, which adds its partner's share to a block buffer
  /// (PairBlocks: fixed-order sums, the same on any thread count). The pair terms are symmetric
  /// (W, f and the pair average of cos²θ); only the neighbour's volume and velocity differ, and
  /// the force changes sign. Returns the signal speed max_i (S_i + √(g h_i)).
  double half_pair_terms() {
    const auto& vol = store_.get<Volume>();
    auto& h = store_.get<FlowDepth>();
    auto& ap = store_.get<HeadAcceleration>();
    const auto& v = store_.get<Velocity<2>>();
    const auto& x = store_.get<Position<2>>();
    const auto& z = store_.get<Elevation>();
    const auto& grad = store_.get<SurfaceGradient>();
    const auto& cb = store_.get<BedCos>();
    const auto& vz = store_.get<VerticalVelocity>();
    auto& vmean = store_.get<MeanVelocity>();
    auto& dv = store_.get<VelocityCorrection>();
    const std::uint32_t* ids = nb_.cell_order().data();
    const double d0 = p_.d0, inv_d0 = 1.0 / d0;
    const double coef = 0.5 * p_.pressure_scale * p_.gravity * inv_d0 * inv_d0 * inv_d0;
    const double g = p_.gravity, support2 = 4.0 * d0 * d0, sigma = CubicSpline<2>::sigma(d0);
    const std::size_t n = store_.size();
    const PairBlocks& blocks = nb_.blocks();
    own_.resize(n);
    reactions_.resize(blocks.slots());
    const auto nblocks = static_cast<std::int64_t>(blocks.count());
    const bool periodic = periodic_.any();
    const auto pass = [&](auto periodic_tag) {
      constexpr bool kPeriodic = decltype(periodic_tag)::value;
#pragma omp parallel for schedule(static) if (parallel_worth(n))
      for (std::int64_t bb = 0; bb < nblocks; ++bb) {
        const auto b = static_cast<std::size_t>(bb);
        PairSums* mine = blocks.buffer(reactions_.data(), b);  // mine[s]: the reactions to slot s
        std::fill(mine + blocks.first(b), mine + blocks.window_end(b), PairSums{});
        for (std::size_t a = blocks.first(b); a < blocks.last(b); ++a) {
          const std::size_t i = ids[a];
          const double Vi = vol[i], ci = cb[i], zi = z[i], vzi = vz[i];
          const Vec2 vi = v[i];
          double depth = Vi * (2.0 / 3.0);
          Vec2 vsum = depth * vi;
          double vzsum = depth * vzi;
          Vec2 acc = Vec2::Zero();
          double accz = 0.0;
          // W/σ (kernels.hpp) and f (head_pressure.hpp) written out per branch of q.
          nb_.for_each_forward_neighbour(a, [&](std::size_t s, const Vec2& xij, double r2) {
            const std::size_t j = ids[s];
            double zij = zi - z[j];
            if constexpr (kPeriodic) zij += grad[i].dot(xij - (x[i] - x[j]));
            const double r3 = r2 + zij * zij;
            if (r3 >= support2) return;  // beyond the support on the bed
            const double r = std::sqrt(r3);
            const double q = r * inv_d0;
            double w, f;
            if (q < 1.0) {
              w = 2.0 / 3.0 - q * q + 0.5 * q * q * q;
              f = r > 0.0 ? coef * (1.0 - q) / ((1.0 + q) * r) : 0.0;
            } else {
              const double t = 2.0 - q;
              w = t * t * t / 6.0;
              f = coef * (-0.5 * (q - 1.0) * (q - 2.0)) / r;
            }
            f *= ci + cb[j];
            const double Vj = vol[j];
            const double wj = Vj * w, fj = Vj * f;
            depth += wj;
            vsum += wj * v[j];
            vzsum += wj * vz[j];
            acc += fj * xij;
            accz += fj * zij;
            const double wi = Vi * w, fi = Vi * f;
            PairSums& r_s = mine[s];
            r_s.depth += wi;
            r_s.vx += wi * vi.x();
            r_s.vy += wi * vi.y();
            r_s.vz += wi * vzi;
            r_s.ax -= fi * xij.x();
            r_s.ay -= fi * xij.y();
            r_s.az -= fi * zij;
          });
          own_[a] = {depth, vsum.x(), vsum.y(), vzsum, acc.x(), acc.y(), accz};
        }
      }
    };
    if (periodic)
      pass(std::true_type{});
    else
      pass(std::false_type{});
    // Every particle: its own sums, then the reactions of the blocks that reach it, in block order.
    const auto add = [](PairSums& t, const PairSums& r) {
      t.depth += r.depth;
      t.vx += r.vx;
      t.vy += r.vy;
      t.vz += r.vz;
      t.ax += r.ax;
      t.ay += r.ay;
      t.az += r.az;
    };
    const auto finish = [&](std::size_t a, const PairSums& t) {
      const std::size_t i = ids[a];
      vmean[i] = tangent_mean(grad[i], Vec2(t.vx, t.vy) / t.depth, t.vz / t.depth);
      h[i] = t.depth * sigma;
      ap[i] = on_bed(grad[i], Vec2(t.ax, t.ay), t.az);
      dv[i] = Vec2::Zero();
      const double vzi = grad[i].dot(v[i]);
      return std::sqrt(v[i].squaredNorm() + vzi * vzi) + std::sqrt(g * h[i]);
    };
    return blocks.gather_max(
        reactions_.data(), [&](std::size_t a) { return own_[a]; }, add, finish);
  }
  /// The head-pressure force F = (F_h, F_z) along the 3D chords, as the map-view acceleration of a
  /// particle held on a bed of gradient p: P (F_h + p F_z) (docs/runout.md).
  static Vec2 on_bed(const Vec2& p, const Vec2& fh, double fz) {
    const Vec2 f = fh + fz * p;
    return Vec2(f - (p.dot(f) / (1.0 + p.squaredNorm())) * p);
  }
  /// A mean 3D velocity (u_h, u_z) with its component normal to a bed of gradient p removed, as a
  /// map velocity: u_h + p (u_z − p·u_h)/(1 + |p|²).
  static Vec2 tangent_mean(const Vec2& p, const Vec2& uh, double uz) {
    return Vec2(uh + ((uz - p.dot(uh)) / (1.0 + p.squaredNorm())) * p);
  }

  /// The pair pass over the neighbours given by `neighbours(i, f)`, which calls f(j, xij, r²) for
  /// every j ≠ i of particle i (possibly including skin pairs beyond the support). Returns the
  /// signal speed max_i (S_i + √(g h_i)).
  template <class Neighbours>
  double pair_terms(Neighbours&& neighbours) {
    const auto& vol = store_.get<Volume>();
    auto& h = store_.get<FlowDepth>();
    auto& ap = store_.get<HeadAcceleration>();
    const auto& v = store_.get<Velocity<2>>();
    const auto& x = store_.get<Position<2>>();
    const auto& z = store_.get<Elevation>();
    const auto& grad = store_.get<SurfaceGradient>();
    const auto& cb = store_.get<BedCos>();
    const auto& vz = store_.get<VerticalVelocity>();
    auto& vmean = store_.get<MeanVelocity>();
    // Height difference of a pair. In a periodic domain (tests on an infinite plane) a neighbour
    // across the boundary is an image: its height is continued with i's bed slope.
    const bool periodic = periodic_.any();
    const auto dz = [&](std::size_t i, std::size_t j, const Vec2& xij) {
      const double d = z[i] - z[j];
      return periodic ? d + grad[i].dot(xij - (x[i] - x[j])) : d;
    };
    auto& dv = store_.get<VelocityCorrection>();
    const double d0 = p_.d0;
    const double inv_d0 = 1.0 / d0;
    const double w0 = CubicSpline<2>::value(0.0, d0);
    // The ½ of the pair average ½(cos θ_i + cos θ_j) is folded into the constant.
    const double coef = 0.5 * p_.pressure_scale * p_.gravity * inv_d0 * inv_d0 * inv_d0;
    const double g = p_.gravity;
    const std::int64_t n = static_cast<std::int64_t>(store_.size());
    const double support2 = 4.0 * d0 * d0, sigma = CubicSpline<2>::sigma(d0);
    // Signal speed of particle i for the CFL condition: surface speed plus gravity-wave speed.
    const auto signal_speed = [&](std::size_t i) {
      const double vz = grad[i].dot(v[i]);
      return std::sqrt(v[i].squaredNorm() + vz * vz) + std::sqrt(g * h[i]);
    };
    // The head-pressure force F = (F_h, F_z) along the 3D chords, as the map-view acceleration of a
    // particle held on the bed: P (F_h + p F_z) (docs/runout.md).
    const auto on_bed_i = [&](std::size_t i, const Vec2& fh, double fz) { return on_bed(grad[i], fh, fz); };
    // The neighbours' mean 3D velocity ū = (ū_h, ū_z), with its normal component at i removed, as a
    // map velocity: ū_h + p (ū_z − p·ū_h)/(1 + |p|²). (Averaging map velocities of particles on
    // beds of different slope would hand a steep particle a larger surface speed than any of them.)
    const auto tangent_mean_i = [&](std::size_t i, const Vec2& uh, double uz) { return tangent_mean(grad[i], uh, uz); };
    const double eps = p_.smoothing;
    double signal = 0.0;
    if (eps == 0.0) {
      // One pass: depth, mean velocity and head pressure (none needs the neighbours' depths). The
      // periodic test of the pair height is hoisted out of the pair loop (two instantiations).
      const auto one_pass = [&](auto periodic_tag) {
        constexpr bool kPeriodic = decltype(periodic_tag)::value;
#pragma omp parallel for reduction(max : signal) schedule(static) if (parallel_worth(n))
        for (std::int64_t ii = 0; ii < n; ++ii) {
          const auto i = static_cast<std::size_t>(ii);
          double depth = vol[i] * (2.0 / 3.0);
          Vec2 vsum = depth * v[i];
          double vzsum = depth * vz[i];
          Vec2 acc = Vec2::Zero();
          double accz = 0.0;
          const double ci = cb[i];
          // W/σ (kernels.hpp) and f (head_pressure.hpp) written out per branch of q; the
          // arithmetic is exactly that of CubicSpline and HeadPressureForce::shape.
          const double zi = z[i];
          neighbours(i, [&](std::size_t j, const Vec2& xij, double r2) {
            double zij = zi - z[j];
            if constexpr (kPeriodic) zij += grad[i].dot(xij - (x[i] - x[j]));
            const double r3 = r2 + zij * zij;
            if (r3 >= support2) return;  // beyond the support on the bed (or in the list's skin)
            const double r = std::sqrt(r3);
            const double q = r * inv_d0;
            const double vj = vol[j];
            double w, fr;
            if (q < 1.0) {
              w = vj * (2.0 / 3.0 - q * q + 0.5 * q * q * q);
              fr = r > 0.0 ? coef * vj * (1.0 - q) / ((1.0 + q) * r) : 0.0;  // one division
            } else {
              const double t = 2.0 - q;
              w = vj * (t * t * t / 6.0);
              fr = coef * vj * (-0.5 * (q - 1.0) * (q - 2.0)) / r;
            }
            depth += w;
            vsum += w * v[j];
            vzsum += w * vz[j];
            fr *= ci + cb[j];
            acc += fr * xij;
            accz += fr * zij;
          });
          vmean[i] = tangent_mean_i(i, vsum / depth, vzsum / depth);
          depth *= sigma;
          h[i] = depth;
          ap[i] = on_bed_i(i, acc, accz);
          dv[i] = Vec2::Zero();
          signal = std::max(signal, signal_speed(i));
        }
      };
      if (periodic)
        one_pass(std::true_type{});
      else
        one_pass(std::false_type{});
      return signal;
    }
    // Pass 1: depths and mean velocities.
#pragma omp parallel for schedule(static) if (parallel_worth(n))
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      double depth = vol[i] * w0;
      Vec2 vsum = depth * v[i];
      double vzsum = depth * vz[i];
      neighbours(i, [&](std::size_t j, const Vec2& xij, double /*r2*/) {
        const double zij = dz(i, j, xij);
        const double w = vol[j] * CubicSpline<2>::value(std::sqrt(xij.squaredNorm() + zij * zij), d0);
        depth += w;
        vsum += w * v[j];
        vzsum += w * vz[j];
      });
      h[i] = depth;
      vmean[i] = tangent_mean_i(i, vsum / depth, vzsum / depth);
    }
    // Pass 2: head pressure and velocity smoothing (needs every depth).
#pragma omp parallel for reduction(max : signal) schedule(static) if (parallel_worth(n))
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      Vec2 acc = Vec2::Zero(), corr = Vec2::Zero();
      double accz = 0.0;
      const Vec2 vi = v[i];
      const double hi = h[i], ci = cb[i];
      neighbours(i, [&](std::size_t j, const Vec2& xij, double /*r2*/) {
        const double zij = dz(i, j, xij);
        const double r = std::sqrt(xij.squaredNorm() + zij * zij);
        if (r > 0.0) {
          const double fr = (ci + cb[j]) * coef * vol[j] * HeadPressureForce::shape(r * inv_d0) / r;
          acc += fr * xij;
          accz += fr * zij;
        }
        corr += (2.0 * vol[j] / (hi + h[j]) * CubicSpline<2>::value(r, d0)) * (v[j] - vi);
      });
      ap[i] = on_bed_i(i, acc, accz);
      dv[i] = eps * corr;
      signal = std::max(signal, signal_speed(i));
    }
    return signal;
  }

  /// The neighbour object's settings: cut-off 2·d0 (the support), skin numerics.skin·d0 (list
  /// cut-off (2 + skin)·d0), the store sorted by cell at every reorder_every-th rebuild.
  void configure_neighbours() {
    NeighbourSettings<2> s;
    s.cutoff = HeadPressureForce::support * p_.d0;
    s.skin = p_.skin * p_.d0;
    s.storage = p_.skin > 0.0 ? PairStorage::list : PairStorage::scan;
    s.reorder_every = p_.reorder_every;
    s.periodic = periodic_;
    nb_.configure(s);
  }

  /// What the integration found, so the serial checks run only when needed.
  struct IntegrateFlags {
    bool leaving = false;     ///< a particle left the terrain
    bool non_finite = false;  ///< a position or velocity is not finite
    bool entraining = false;  ///< a particle asks to erode the bed (demand_)
    bool walls = false;       ///< a particle met a barrier (wall_barrier_)
  };

  template <class Law>
  IntegrateFlags integrate(const Law& law, double dt) {
    auto& x = store_.get<Position<2>>();
    auto& v = store_.get<Velocity<2>>();
    auto& grad = store_.get<SurfaceGradient>();
    auto& hess = store_.get<SurfaceCurvature>();
    auto& cb = store_.get<BedCos>();
    auto& vzf = store_.get<VerticalVelocity>();
    auto& z = store_.get<Elevation>();
    auto& speed = store_.get<Speed>();
    auto& path = store_.get<PathLength>();
    auto& moving = store_.get<Moving>();
    auto& leaving = store_.get<Leaving>();
    const auto& vol = store_.get<Volume>();
    const auto& h = store_.get<FlowDepth>();
    const auto& ap = store_.get<HeadAcceleration>();
    const auto& dv = store_.get<VelocityCorrection>();
    const auto& vmean = store_.get<MeanVelocity>();
    auto& memory_stress = store_.get<BasalExcessStress>();
    auto& memory_rate = store_.get<BasalShearRate>();
    // An iterative law starts from the particle's last state unless the fields change what it means.
    const bool memory = step_memory_valid(law, proc_.friction);
    const double g = p_.gravity, mix = p_.lateral_mixing;
    const bool curvature = p_.curvature;
    const bool periodic = periodic_.any();
    const std::int64_t n = static_cast<std::int64_t>(store_.size());
    // Spatial processes: one cell look-up per particle, at its position during the step.
    const bool cells = proc_.has_cell_fields(), zones = proc_.has_friction_fields();
    const bool forest = !proc_.forest_drag.empty();
    const EntrainmentParameters& ent = p_.entrainment;
    const bool erode = ent.law != EntrainmentLaw::None && !proc_.erodible_depth.empty();
    if (erode) {
      demand_.assign(store_.size(), 0.0);
      demand_cell_.resize(store_.size());
    }
    const bool walls = !barriers_.empty();
    if (walls) {
      wall_barrier_.assign(store_.size(), -1);
      wall_value_.resize(store_.size());
      wall_depth_.resize(store_.size());
      wall_bin_.resize(store_.size());
      wall_cross_.resize(store_.size());
      push_barrier_.assign(store_.size(), -1);
      push_value_.resize(store_.size());
      push_bin_.resize(store_.size());
      push_depth_.resize(store_.size());
    }
    // The particles go in blocks of kFrictionBlock: a. and b. for the block, the friction steps of
    // the block together (c.), then the rest for the block. The friction steps of a block are
    // independent, so the processor overlaps them (one particle's step is a chain of dependent
    // divisions that the rest of its own update cannot hide), and a law may step several
    // particles in one vector instruction (speed_after_friction_block).
    using Terms = decltype(law.terms(0.0, 0.0, 1.0, 0.0, 1.0));
    const std::int64_t blocks = (n + kFrictionBlock - 1) / kFrictionBlock;
    int any_leaving = 0, any_non_finite = 0, any_entraining = 0, any_wall = 0;
#pragma omp parallel for reduction(max                                                      \
                                   : any_leaving, any_non_finite, any_entraining, any_wall) \
    schedule(static) if (parallel_worth(n))
    for (std::int64_t blk = 0; blk < blocks; ++blk) {
      const auto first = static_cast<std::size_t>(blk) * kFrictionBlock;
      const std::size_t count = std::min<std::size_t>(kFrictionBlock, static_cast<std::size_t>(n) - first);
      std::array<Terms, kFrictionBlock> terms;
      std::array<Vec2, kFrictionBlock> v_stars;
      std::array<double, kFrictionBlock> s_stars, speeds;
      std::array<std::size_t, kFrictionBlock> block_cells;
      for (std::size_t k = 0; k < count; ++k) {
        const std::size_t i = first + k;
        const std::size_t cell = cells ? proc_.cell(x[i]) : SpatialProcesses::npos;
        const Vec2 gz = grad[i];
        const double cos_theta = cb[i];
        const double h_n = std::max(h[i], p_.min_depth);
        // a. Lateral mixing: implicit relaxation towards the neighbours' mean velocity at the rate
        //    k = C_mix |ṽ − v|_s √(h_n/V) (com1DFA: C·½ρ|Δv|A_lat/m with A_lat = 2√(V h_n)).
        Vec2 vi = v[i] + dv[i];
        if (mix > 0.0) {
          const Vec2 dm = vmean[i] - vi;
          const double dmz = gz.dot(dm);
          const double kdt = mix * std::sqrt(dm.squaredNorm() + dmz * dmz) * std::sqrt(h_n / vol[i]) * dt;
          vi = (vi + kdt * vmean[i]) / (1.0 + kdt);
        }
        // b. Gravity along the bed and the head pressure: a = −g cos²θ p + a_p.
        Vec2 a = (-g * cos_theta * cos_theta) * gz + ap[i];
        //    Near a barrier whose crest is above the flow surface: the push of the mirror layer the
        //    wall stands for, C g cos θ h_w M(s/d0)/d0 away from it (barriers.hpp); the wall takes it.
        if (walls && barriers_.near(x[i])) {
          wall_push(i, dt, a);
          if (push_barrier_[i] >= 0) any_wall = 1;
        }
        const Vec2 v_star = vi + dt * a;
        // c. Basal friction on the surface speed with the bed-normal stress ρ g_n h_n,
        //    g_n = cos θ (g + vᵀHv)⁺: gravity plus the centripetal acceleration of the bed curvature
        //    along the velocity, zero when the particle would leave the bed.
        const Vec3& H = hess[i];
        const double kv =
            curvature ? H[0] * vi.x() * vi.x() + 2.0 * H[1] * vi.x() * vi.y() + H[2] * vi.y() * vi.y() : 0.0;
        const double vz = gz.dot(v_star);
        const double s_star = std::sqrt(v_star.squaredNorm() + vz * vz);
        //    The law's coefficients of the particle's friction zone; forest drag k_f |v|² on top.
        Law local = law;
        if (zones) local = proc_.law_at(law, cell);
        auto t = local.terms(g, std::max(g + kv, 0.0) * cos_theta, h_n, s_star, p_.density);
        if (forest && cell != SpatialProcesses::npos && proc_.forest_drag[cell] > 0.0)
          t.extra_drag = proc_.forest_drag[cell];
        if constexpr (requires { t.memory; })
          if (memory) t.memory = {&memory_stress[i], &memory_rate[i]};
        terms[k] = t;
        v_stars[k] = v_star;
        s_stars[k] = s_star;
        block_cells[k] = cell;
      }
      speed_after_friction_block(std::span<const double>(s_stars.data(), count), dt,
                                 std::span<const Terms>(terms.data(), count), std::span<double>(speeds.data(), count));
      for (std::size_t k = 0; k < count; ++k) {
        const std::size_t i = first + k;
        const std::size_t cell = block_cells[k];
        const Vec2 gz = grad[i];
        const double cos_theta = cb[i];
        const double h_n = std::max(h[i], p_.min_depth);
        const Vec2 v_star = v_stars[k];
        const double s_star = s_stars[k];
        const Terms& t = terms[k];
        double s = speeds[k];
        //    Erosion the particle asks for over the step (granted in entrain(), capped by the layer).
        if (erode && s > 0.0 && cell != SpatialProcesses::npos && proc_.erodible_depth[cell] > 0.0) {
          double want = 0.0;
          if (ent.law == EntrainmentLaw::GrowthRate) {
            want = vol[i] * std::expm1(ent.growth_rate * s * dt);  // V (exp(E_s Δs) − 1), Δs = S Δt
          } else {
            const double tau_b = p_.density * h_n * t.acceleration(s);  // basal shear (Pa)
            const double rate = ent.erosion_coefficient * std::max(tau_b - ent.critical_shear, 0.0);
            want = rate * dt * vol[i] / h_n;  // ė Δt × bed area V/h_n
          }
          if (want > 0.0) {
            demand_[i] = want;
            demand_cell_[i] = cell;
            any_entraining = 1;
          }
        }
        Vec2 v_new = s > 0.0 ? Vec2(v_star * (s / s_star)) : Vec2::Zero();
        Vec2 x_new = x[i] + dt * v_new;
        // d. Barriers: held at the wall unless the flow surface is above the crest or the particle
        //    passes an open barrier.
        BarrierCrossing hit;
        bool held = false;
        if (walls && barriers_.first_crossing(x[i], x_new, hit)) {
          any_wall = 1;
          held = meet_wall(i, hit, dt, gz, cos_theta, v_new, x_new, s);
        }
        const double moved = held ? (x_new - x[i]).norm() : dt * v_new.norm();
        if (periodic) x_new = periodic_.wrap(x_new);
        SurfaceSample smp;
        if (!surface_.sample(x_new, smp)) {
          leaving[i] = 1;
          v[i] = v_new;
          any_leaving = 1;
          if (!(x[i].allFinite() && v_new.allFinite())) any_non_finite = 1;
          continue;
        }
        // e. The bed constraint: the velocity, tangent to the bed at the old position, is turned into
        //    the tangent plane at the new one keeping its magnitude S (the normal reaction does no
        //    work; AvaFrame com1DFA's reprojection). In map view, with p' the new gradient:
        //        v' ∝ v + p' ((p − p')·v)/(1 + |p'|²),   scaled so that |(v', p'·v')| = S.
        if (s > 0.0) {
          const Vec2 pn = smp.grad;
          const Vec2 vt = v_new + (((gz - pn).dot(v_new)) / (1.0 + pn.squaredNorm())) * pn;
          const double vtz = pn.dot(vt);
          const double st = std::sqrt(vt.squaredNorm() + vtz * vtz);
          if (st > 1e-12 * s) v_new = vt * (s / st);
        }
        leaving[i] = 0;
        path[i] += moved;
        x[i] = x_new;
        v[i] = v_new;
        z[i] = smp.z;
        grad[i] = smp.grad;
        hess[i] = smp.hess;
        cb[i] = 1.0 / std::sqrt(1.0 + smp.grad.squaredNorm());
        vzf[i] = smp.grad.dot(v_new);
        speed[i] = s;
        moving[i] = s > 0.0 ? 1 : 0;
        if (!(x_new.allFinite() && v_new.allFinite())) any_non_finite = 1;
      }
    }
    return {any_leaving != 0, any_non_finite != 0, any_entraining != 0, any_wall != 0};
  }

  /// d. Particle i, moving from x[i] to x_new at v_new, crosses a barrier (hit): recorded for the
  /// tally. It is held at the wall (v_new reflected by the wall law, x_new just before the wall,
  /// then the rest of the step, s its new speed; true) unless the flow surface is above the crest
  /// or the particle passes an open barrier (false: nothing changed).
  bool meet_wall(std::size_t i, const BarrierCrossing& hit, double dt, const Vec2& gz, double cos_theta, Vec2& v_new,
                 Vec2& x_new, double& s) {
    const auto& x = store_.get<Position<2>>();
    const auto& h = store_.get<FlowDepth>();
    const auto& z = store_.get<Elevation>();
    const auto& vol = store_.get<Volume>();
    const auto& ids = store_.get<ParticleId>();
    const auto b = static_cast<std::size_t>(hit.barrier);
    const Barrier& bar = barriers_[b];
    // Depth at the wall: the kernel sum misses the part of the support beyond the wall.
    const double h_wall =
        h[i] / BarrierSet::kernel_fraction(barriers_.distance_to_segment(b, hit.segment, x[i]) / p_.d0);
    SurfaceSample at;
    const double z_crest = (surface_.sample(hit.point, at) ? at.z : z[i]) + bar.height;
    const bool over = z[i] + h_wall / cos_theta > z_crest;
    wall_barrier_[i] = hit.barrier;
    wall_bin_[i] = barriers_.bin_of(hit);
    wall_depth_[i] = h_wall;
    wall_cross_[i] = over || barriers_.passes(ids[i], b) ? 1 : 0;
    if (wall_cross_[i]) {
      wall_value_[i] = hit.from_upstream ? vol[i] : -vol[i];  // crosses: signed volume
    } else {
      const WallLaw& wl = barriers_.law();
      const Vec2 nrm = hit.normal;
      const double vn = std::max(v_new.dot(nrm), 0.0);
      Vec2 vt = v_new - v_new.dot(nrm) * nrm;
      const double vt_norm = vt.norm(), dvn = (1.0 + wl.restitution) * vn;
      if (vt_norm > 0.0) vt *= std::max(0.0, 1.0 - wl.friction * dvn / vt_norm);
      v_new = vt - wl.restitution * vn * nrm;
      wall_value_[i] = vol[i] * dvn;  // held: the impulse per unit density (m⁴/s)
      // Stop at the wall (a hair before it), then the rest of the step with v'.
      const double backoff = 1e-6 * p_.d0;
      const double to_wall = hit.t * (x_new - x[i]).dot(nrm);
      const Vec2 xc = to_wall > 2.0 * backoff ? Vec2(x[i] + hit.t * (x_new - x[i]) - backoff * nrm) : x[i];
      x_new = xc + ((1.0 - hit.t) * dt) * v_new;
      BarrierCrossing again;
      if (barriers_.first_crossing(xc, x_new, again)) x_new = xc;  // a corner: the next step resolves it
      const double vzn = gz.dot(v_new);
      s = std::sqrt(v_new.squaredNorm() + vzn * vzn);
      return true;
    }
    return false;
  }

  /// The mirror push of the nearest barrier on particle i (added to its acceleration a), recorded
  /// for the tally. None when the flow surface is above the crest or the particle passes the
  /// barrier (open barriers), or beyond 2 d0 of the wall.
  void wall_push(std::size_t i, double dt, Vec2& a) {
    WallProximity w;
    if (!barriers_.nearest_wall(store_.get<Position<2>>()[i], w)) return;
    const auto b = static_cast<std::size_t>(w.barrier);
    if (barriers_.passes(store_.get<ParticleId>()[i], b)) return;
    const double sd = w.distance / p_.d0;
    const double push_shape = BarrierSet::mirror_push(sd);
    if (!(push_shape > 0.0)) return;
    const double cos_theta = store_.get<BedCos>()[i], zi = store_.get<Elevation>()[i];
    const double h_wall = store_.get<FlowDepth>()[i] / BarrierSet::kernel_fraction(sd);
    SurfaceSample at;
    const double z_crest = (surface_.sample(w.point, at) ? at.z : zi) + barriers_[b].height;
    if (zi + h_wall / cos_theta > z_crest) return;  // overtopping: the wall does not hold it
    const double push = p_.pressure_scale * p_.gravity * cos_theta * h_wall * push_shape / p_.d0;
    const Vec2 gz = store_.get<SurfaceGradient>()[i];
    const Vec2 f = push * w.away;
    a += f - (gz.dot(f) / (1.0 + gz.squaredNorm())) * gz;  // P f: held on the bed
    push_barrier_[i] = w.barrier;
    push_value_[i] = store_.get<Volume>()[i] * push * dt;  // impulse per unit density (m⁴/s)
    push_bin_[i] = barriers_.bin_at(b, w.arclength);
    push_depth_[i] = w.distance <= p_.d0 ? h_wall : 0.0;
  }

  /// Add the wall events of the step to the barrier tally, in store order (deterministic). A held
  /// particle gave the wall ρ V (1 + e) v_n; a crossing one moved its volume across (signed: + from
  /// the upstream side).
  void tally_walls() {
    for (std::size_t i = 0; i < store_.size(); ++i) {
      if (const int pb = push_barrier_[i]; pb >= 0) {
        const auto k = static_cast<std::size_t>(pb);
        tally_.impulse[k] += push_value_[i] * p_.density;
        tally_.touched[push_bin_[i]] = 1;
        tally_.window_depth[k] = std::max(tally_.window_depth[k], push_depth_[i]);
      }
      const int b = wall_barrier_[i];
      if (b < 0) continue;
      const auto k = static_cast<std::size_t>(b);
      tally_.touched[wall_bin_[i]] = 1;
      tally_.window_depth[k] = std::max(tally_.window_depth[k], wall_depth_[i]);
      if (!wall_cross_[i]) {
        tally_.impulse[k] += wall_value_[i] * p_.density;
        tally_.contacts[k] += 1.0;
      } else {
        tally_.passed[k] += wall_value_[i];
      }
    }
  }

  /// Grant the erosion asked for in integrate(), in store order (deterministic), capped by the depth
  /// left in each cell. The eroded mass joins its particle at rest: V v is conserved, so the
  /// particle slows by V/(V + ΔV).
  void entrain() {
    auto& vol = store_.get<Volume>();
    auto& v = store_.get<Velocity<2>>();
    auto& speed = store_.get<Speed>();
    auto& vz = store_.get<VerticalVelocity>();
    auto& layer = proc_.erodible_depth;
    const double area = proc_.grid.cell_area();
    for (std::size_t i = 0; i < store_.size(); ++i) {
      if (!(demand_[i] > 0.0)) continue;
      const std::size_t k = demand_cell_[i];
      const double dV = std::min(demand_[i], layer[k] * area);
      if (!(dV > 0.0)) continue;
      layer[k] = std::max(layer[k] - dV / area, 0.0);
      eroded_[k] += dV / area;
      const double f = vol[i] / (vol[i] + dV);
      v[i] *= f;
      speed[i] *= f;
      vz[i] *= f;
      vol[i] += dV;
      budget_.entrained += dV;
    }
  }

  /// Particles of the inflow hydrographs due by time t: one of volume V0 each time ∫Q has grown by
  /// V0, and the remainder when the hydrograph ends, so the injected volume is ∫Q dt exactly. Each
  /// enters at the next slot across the inflow line (slots d0 apart) and is placed where it would
  /// be at t had it entered when the middle of its volume did.
  void inject(double t) {
    const double v0 = p_.nominal_volume();
    for (std::size_t m = 0; m < proc_.inflows.size(); ++m) {
      const Hydrograph& q = proc_.inflows[m];
      const bool ended = t >= q.end_time();
      double due = (ended ? q.volume() : q.volume_until(t)) - emitted_[m];
      while (due >= v0 || (ended && due > 1e-9 * v0)) {
        const double dv = std::min(v0, due);
        const double entered = q.time_of_volume(emitted_[m] + 0.5 * dv);
        emitted_[m] += dv;
        due -= dv;
        add_inflow_particle(q, slot_[m]++, dv, std::max(t - entered, 0.0));
        budget_.injected += dv;
      }
    }
  }
  void add_inflow_particle(const Hydrograph& q, std::int64_t slot, double volume, double age) {
    const int slots = std::max(1, static_cast<int>(std::lround((q.b - q.a).norm() / p_.d0)));
    const Vec2 base = q.a + (q.b - q.a) * ((static_cast<double>(slot % slots) + 0.5) / slots);
    SurfaceSample s0, s;
    if (!surface_.sample(base, s0))
      throw SimulationError("the inflow of " + q.source + " is off the terrain at (" + std::to_string(base.x()) + ", " +
                            std::to_string(base.y()) + ")");
    // Map velocity of surface speed q.speed along the map direction of the inflow.
    const auto map_velocity = [&](const Vec2& grad) {
      const double pz = grad.dot(q.direction);
      return Vec2(q.direction * (q.speed / std::sqrt(1.0 + pz * pz)));
    };
    Vec2 xp = base + age * map_velocity(s0.grad);
    if (!surface_.sample(xp, s)) {
      xp = base;
      s = s0;
    }
    const Vec2 vp = map_velocity(s.grad);
    const std::size_t i = store_.append(1);
    store_.get<Position<2>>()[i] = xp;
    store_.get<Velocity<2>>()[i] = vp;
    store_.get<Volume>()[i] = volume;
    store_.get<ParticleId>()[i] = next_id_++;
    store_.get<Elevation>()[i] = s.z;
    store_.get<StartElevation>()[i] = s0.z;
    store_.get<StartPosition>()[i] = base;
    store_.get<PathLength>()[i] = (xp - base).norm();
    store_.get<SurfaceGradient>()[i] = s.grad;
    store_.get<SurfaceCurvature>()[i] = s.hess;
    store_.get<BedCos>()[i] = 1.0 / std::sqrt(1.0 + s.grad.squaredNorm());
    store_.get<Speed>()[i] = q.speed;
    store_.get<VerticalVelocity>()[i] = s.grad.dot(vp);
    store_.get<Moving>()[i] = 1;
    nb_.invalidate();
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
      nb_.invalidate();
    }
  }

  void update_budget() {
    const auto& vol = store_.get<Volume>();
    const auto& moving = store_.get<Moving>();
    const auto& speed = store_.get<Speed>();
    budget_.mobile = budget_.deposited = 0.0;
    double ke = 0.0;
    for (std::size_t i = 0; i < store_.size(); ++i) {
      (moving[i] ? budget_.mobile : budget_.deposited) += vol[i];
      ke += vol[i] * speed[i] * speed[i];
    }
    budget_.kinetic_energy = 0.5 * p_.density * ke;
    budget_.peak_kinetic_energy = std::max(budget_.peak_kinetic_energy, budget_.kinetic_energy);
    energy_stop_ = p_.stop_energy_fraction > 0.0 && budget_.peak_kinetic_energy > 0.0 &&
                   budget_.kinetic_energy < p_.stop_energy_fraction * budget_.peak_kinetic_energy;
  }

  Surface surface_;
  RunoutParameters p_;
  Periodicity<2> periodic_;
  RunoutStore store_;
  Neighbours<2> nb_;                 // a list with a skin (numerics.skin > 0), a cell scan without
  std::vector<PairSums> own_;        // half_pair_terms: each slot's own sums
  std::vector<PairSums> reactions_;  // half_pair_terms: the blocks' reaction buffers
  VolumeBudget budget_;
  SpatialProcesses proc_;
  std::vector<double> eroded_;            // per cell of proc_.grid (m)
  std::vector<double> demand_;            // per particle, this step (m³)
  std::vector<std::size_t> demand_cell_;  // the cell it erodes
  std::vector<double> emitted_;           // per inflow (m³)
  BarrierSet barriers_;
  BarrierTally tally_;
  std::vector<int> wall_barrier_;         // per particle, this step: the barrier met (−1: none)
  std::vector<std::size_t> wall_bin_;     // its bin
  std::vector<double> wall_value_;        // V (1+e) v_n when held; ± V when crossing
  std::vector<double> wall_depth_;        // depth at the wall h_w (m)
  std::vector<std::uint8_t> wall_cross_;  // 1 when it crossed
  std::vector<int> push_barrier_;         // per particle, this step: the barrier pushing it (−1: none)
  std::vector<double> push_value_;        // its impulse per unit density (m⁴/s)
  std::vector<std::size_t> push_bin_;     // the bin of the nearest wall point
  std::vector<double> push_depth_;        // h_w within d0 of the wall (m), else 0
  std::vector<std::int64_t> slot_;        // per inflow: particles emitted
  std::int64_t next_id_ = 0;
  bool energy_stop_ = false;
  double time_ = 0.0, dt_ = 0.0;
  std::int64_t step_ = 0;
};

}  // namespace geohaz::runout
