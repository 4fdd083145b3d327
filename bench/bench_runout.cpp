// Throughput of the debris-runout solver (issue 4 targets, 2-core machine):
//  1. particle-steps per second for a 10^5-particle flow on an inclined plane, 1 and 2 threads
//     (target ≥ 5e6 /s with 2 threads);
//  2. wall time of the lecture's case at the lecture's scale: 10 simulated minutes of a ~5000-particle
//     release (d0 = 5 m, h0 = 1 m, 2 m thick over 300 m × 200 m) on the synthetic 5 km valley DSM of 2000 × 1000 cells
//     at 2.5 m, n = 0.06, i_cr = 0.15 (target < 10 s), with the hazard maps recorded every step as the app does.
// Prints rates; never asserts. Usage: bench_runout [particles=100000] [steps=40]
// [all|plane|seed|processes|barrier|laws|law_steps|law=<name>] [threads] [skin] (the third argument runs one case only,
// the fourth one thread count only, the fifth sets numerics.skin in units of d0: for profiling and for comparing list
// strategies).
#include <omp.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <span>
#include <string>
#include <vector>

#include "geohaz/runout/hazard_maps.hpp"
#include "geohaz/runout/release.hpp"
#include "geohaz/runout/solver.hpp"
#include "geohaz/runout/synthetic_terrain.hpp"

using namespace geohaz;
using namespace geohaz::runout;

namespace {
double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Process CPU time (s): with the machine shared, CPU time per particle-step is the load-independent figure.
double cpu() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

struct Rate {
  double wall, cpu;
  unsigned long long state = 0;  ///< hash of the final state (to compare variants bit for bit)
};

/// FNV-1a hash of the positions, velocities and depths in particle-id order (the store is
/// reordered by cell, so store order depends on the reordering schedule): equal hashes mean the
/// same run to the last bit.
unsigned long long state_hash(const RunoutStore& st) {
  std::vector<std::size_t> at(st.size());
  for (std::size_t i = 0; i < st.size(); ++i) at[static_cast<std::size_t>(st.get<ParticleId>()[i])] = i;
  unsigned long long h = 1469598103934665603ull;
  const auto add = [&](const auto& value) {
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    for (std::size_t k = 0; k < sizeof(value); ++k) h = (h ^ p[k]) * 1099511628211ull;
  };
  for (std::size_t i : at) {
    add(st.get<Position<2>>()[i]);
    add(st.get<Velocity<2>>()[i]);
    add(st.get<FlowDepth>()[i]);
  }
  return h;
}

/// `processes`: an erodible layer under the whole plane (growth law), a friction-zone field and a
/// forest field, so every particle looks up three cells per step and erodes. `barrier`: a wall with
/// a 1 m crest across the middle of the 2 m deep block, so that the front half of the particles is
/// within its reach or held by it, and the deeper ones overtop.
Rate plane_rate(std::size_t target, int steps, int threads, double skin, bool processes = false, bool barrier = false,
                BasalFriction friction = ModifiedManningFriction{0.06, 0.15, 0.0}) {
  omp_set_num_threads(threads);
  RunoutParameters p;
  p.d0 = 5.0;
  p.h0 = 1.0;
  p.duration = 1e9;
  p.skin = skin;
  p.friction = friction;
  InclinedPlane plane;
  plane.slope = Vec2(-0.3, 0.0);
  const int n = static_cast<int>(std::sqrt(static_cast<double>(target)));
  const double d = p.d0 / std::sqrt(2.0);  // 2 m thick layer
  if (processes) p.entrainment = {EntrainmentLaw::GrowthRate, 1e-4, 0.0, 0.0};
  RunoutSolver<InclinedPlane> s(plane, p);
  if (processes) {
    SpatialProcesses proc;
    const int cells = static_cast<int>(std::ceil((n * d + 400.0) / 5.0));
    proc.grid = {cells, cells, -200.0, n * d + 200.0, 5.0, 5.0};
    proc.erodible_depth.assign(proc.grid.cells(), 10.0);
    proc.forest_drag.assign(proc.grid.cells(), 1e-3);
    proc.friction[kManningN].assign(proc.grid.cells(), 0.07);
    s.set_processes(std::move(proc));
  }
  if (barrier) {
    Barrier b;
    b.name = "bench";
    b.vertices = {Vec2(0.5 * n * d, -50.0), Vec2(0.5 * n * d, n * d + 50.0)};
    b.height = 1.0;
    b.upstream_left = true;
    s.set_barriers(BarrierSet({b}, {}, p.d0));
  }
  auto& st = s.particles();
  st.append(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * n + i;
      st.get<Position<2>>()[k] = Vec2(i * d, j * d);
      st.get<Volume>()[k] = p.nominal_volume();
      st.get<ParticleId>()[k] = static_cast<std::int64_t>(k);
    }
  s.initialise();
  for (int k = 0; k < 5; ++k) s.step();  // warm-up: moving, reordered
  const double t0 = now(), c0 = cpu();
  for (int k = 0; k < steps; ++k) s.step();
  const double wall = now() - t0, c = cpu() - c0;
  const double ps = static_cast<double>(st.size()) * steps;
  return {ps / wall, ps / c, state_hash(st)};
}
/// The laws compared by `laws` and `law=<name>`, Voellmy first. Parameters that keep the 2 m layer
/// on tan θ = 0.3 moving (τ_b = 10 kPa), so every particle takes the law's moving branch.
const std::vector<BasalFriction>& bench_laws() {
  static const std::vector<BasalFriction> laws{VoellmyFriction{0.15, 500.0},
                                               VoellmyCohesionFriction{0.15, 500.0, 1000.0},
                                               BinghamFriction{1000.0, 100.0},
                                               HerschelBulkleyFriction{1000.0, 100.0, 0.4},
                                               OBrienJulienFriction{1000.0, 100.0, 24.0, 0.06},
                                               PouliquenForterreFriction{0.176, 0.466, 0.5, 0.65, 0.136},
                                               ModifiedManningFriction{0.06, 0.15, 0.0},
                                               CoulombFriction{0.15}};
  return laws;
}
/// The cost of one law's friction step alone (terms + step), ns per step, best of 5 runs of 2e6
/// steps, CPU time: an accelerating 2 m layer (tan θ ≈ 0.3, Δt = 0.01 s) restarted every 200 steps;
/// an iterative law keeps its memory. Two ways: `chained`, one particle whose next step waits for
/// this one (the latency: what a step cost when each particle's step sat inside its own update),
/// and in blocks of kFrictionBlock independent particles through speed_after_friction_block, as
/// the solver now steps them (the throughput). Small working set: far less sensitive to a shared
/// machine than the plane's rates.
double law_step_ns(const BasalFriction& friction, bool chained) {
  return std::visit(
      [chained](const auto& law) {
        using Terms = decltype(law.terms(0.0, 0.0, 1.0, 0.0, 1.0));
        const std::size_t block = chained ? 1 : kFrictionBlock;
        const int n = 2000000 / static_cast<int>(block);
        const double dt = 0.01, h = 2.0, g = 9.81;
        std::array<double, kFrictionBlock> zeta{}, rate{}, s, s_star;
        std::array<Terms, kFrictionBlock> t;
        s.fill(1.0);
        double sum = 0.0, best = HUGE_VAL;
        for (int rep = 0; rep < 5; ++rep) {
          const double c0 = cpu();
          for (int k = 0; k < n; ++k) {
            for (std::size_t p = 0; p < block; ++p) {
              s_star[p] = (k % 200 == 0 ? 0.5 + 0.01 * static_cast<double>(p) : s[p]) + dt * g * 0.287;
              t[p] = law.terms(g, g * 0.958, h + 1e-3 * static_cast<double>((k + static_cast<int>(p)) & 7), s_star[p],
                               2000.0);
              if constexpr (requires { t[p].memory; }) t[p].memory = {&zeta[p], &rate[p]};
            }
            speed_after_friction_block(std::span<const double>(s_star.data(), block), dt,
                                       std::span<const Terms>(t.data(), block), std::span<double>(s.data(), block));
          }
          best = std::min(best, (cpu() - c0) / (static_cast<double>(n) * static_cast<double>(block)) * 1e9);
          for (std::size_t p = 0; p < block; ++p) sum += s[p];
        }
        return sum > 0.0 ? best : -best;  // keeps the chain
      },
      friction);
}
}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 100000;
  const int steps = argc > 2 ? std::atoi(argv[2]) : 40;
  const std::string which = argc > 3 ? argv[3] : "all";
  const int only_threads = argc > 4 ? std::atoi(argv[4]) : 0;
  const double skin = argc > 5 ? std::atof(argv[5]) : RunoutParameters{}.skin;
  if (which == "processes") {
    // The plane with entrainment, a friction zone and a forest everywhere, back to back with the plain plane.
    std::printf("bench_runout: %zu particles on a plane, %d steps, plain vs with processes\n", n, steps);
    for (int t : {1, 2}) {
      if (only_threads > 0 && t != only_threads) continue;
      const Rate a = plane_rate(n, steps, t, skin), b = plane_rate(n, steps, t, skin, true);
      std::printf("  %d thread(s): plain %.3g, with processes %.3g particle-steps/s (wall); ratio %.3f (CPU %.3f)\n", t,
                  a.wall, b.wall, b.wall / a.wall, b.cpu / a.cpu);
      std::fflush(stdout);
    }
    return 0;
  }
  if (which.rfind("law=", 0) == 0) {
    // One law only (for instruction counts under callgrind: --toggle-collect on RunoutSolver::step).
    for (const BasalFriction& law : bench_laws())
      if (friction_name(law) == which.substr(4)) {
        const Rate r = plane_rate(n, steps, only_threads > 0 ? only_threads : 1, skin, false, false, law);
        std::printf("%s: %.3g particle-steps/s (CPU); state %016llx\n", which.c_str() + 4, r.cpu, r.state);
        return 0;
      }
    std::fprintf(stderr, "bench_runout: unknown law %s\n", which.c_str() + 4);
    return 2;
  }
  if (which == "law_steps") {
    std::printf(
        "bench_runout: one friction step of each law alone (ns, CPU, best of 5): one particle in a dependent\n"
        "  chain, and blocks of %zu independent particles as the solver steps them\n",
        kFrictionBlock);
    for (const BasalFriction& law : bench_laws())
      std::printf("  %-17s chained %5.1f ns, in blocks %5.1f ns\n", friction_name(law).c_str(), law_step_ns(law, true),
                  law_step_ns(law, false));
    return 0;
  }
  if (which == "laws") {
    // Each basal law against Voellmy on the plane, back to back, best of 3 each (issue 34: no law
    // more than 10 % slower per particle-step).
    const BasalFriction voellmy = bench_laws().front();
    const std::vector<BasalFriction> laws(bench_laws().begin() + 1, bench_laws().end());
    const int t = only_threads > 0 ? only_threads : 1;
    std::printf("bench_runout: %zu particles on a plane, %d steps, %d thread(s), each law vs voellmy (best of 3)\n", n,
                steps, t);
    for (const BasalFriction& law : laws) {
      Rate a{0.0, 0.0}, b{0.0, 0.0};
      for (int k = 0; k < 3; ++k) {
        const Rate ra = plane_rate(n, steps, t, skin, false, false, voellmy);
        const Rate rb = plane_rate(n, steps, t, skin, false, false, law);
        a = {std::max(a.wall, ra.wall), std::max(a.cpu, ra.cpu)};
        b = {std::max(b.wall, rb.wall), std::max(b.cpu, rb.cpu)};
      }
      std::printf(
          "  %-17s %.3g vs voellmy %.3g particle-steps/s (CPU); time per particle-step %+.1f %% (wall %+.1f %%)\n",
          friction_name(law).c_str(), b.cpu, a.cpu, 100.0 * (a.cpu / b.cpu - 1.0), 100.0 * (a.wall / b.wall - 1.0));
      std::fflush(stdout);
    }
    return 0;
  }
  if (which == "barrier") {
    // The plane with a barrier across the block, back to back with the plain plane, best of 5 each
    // (the machine is shared: the best run is the least disturbed one).
    std::printf("bench_runout: %zu particles on a plane, %d steps, plain vs with a barrier (best of 5)\n", n, steps);
    for (int t : {1, 2}) {
      if (only_threads > 0 && t != only_threads) continue;
      Rate a{0.0, 0.0}, b{0.0, 0.0};
      for (int k = 0; k < 5; ++k) {
        const Rate ra = plane_rate(n, steps, t, skin), rb = plane_rate(n, steps, t, skin, false, true);
        std::printf("    run %d: plain %.3g, barrier %.3g particle-steps/s (wall); CPU %.3g, %.3g\n", k, ra.wall,
                    rb.wall, ra.cpu, rb.cpu);
        a = {std::max(a.wall, ra.wall), std::max(a.cpu, ra.cpu)};
        b = {std::max(b.wall, rb.wall), std::max(b.cpu, rb.cpu)};
      }
      std::printf(
          "  %d thread(s): best plain %.3g, with a barrier %.3g particle-steps/s (wall); ratio %.3f (CPU %.3f)\n", t,
          a.wall, b.wall, b.wall / a.wall, b.cpu / a.cpu);
      std::fflush(stdout);
    }
    return 0;
  }
  if (which == "all" || which == "plane") {
    std::printf("bench_runout: %zu particles on a plane, %d steps\n", n, steps);
    std::fflush(stdout);
    for (int t : {1, 2}) {
      if (only_threads > 0 && t != only_threads) continue;
      const Rate r = plane_rate(n, steps, t, skin);
      std::printf("  %d thread(s): %.3g particle-steps/s (wall), %.3g per CPU-second; state %016llx\n", t, r.wall,
                  r.cpu, r.state);
      std::fflush(stdout);
    }
  }
  if (which != "all" && which != "seed") return 0;

  // The lecture's case.
  const int seed_threads = only_threads > 0 ? only_threads : 2;
  omp_set_num_threads(seed_threads);
  const SyntheticValley v;
  const GridSurface surface = v.surface();
  const GridGeometry g = v.geometry();
  std::vector<double> thick(g.cells(), 0.0);
  const double L = v.length();
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      const Vec2 p = g.centre(c, r);
      const double s = p.x() - g.x0;
      if (s > 0.06 * L && s < 0.12 * L && std::abs(p.y() - v.thalweg_y(p.x())) < 0.02 * L) thick[g.index(c, r)] = 2.0;
    }
  RunoutParameters p;
  p.d0 = 5.0;
  p.h0 = 1.0;
  p.duration = 600.0;
  p.skin = skin;
  p.friction = ModifiedManningFriction{0.06, 0.15, 0.0};
  RunoutSolver<GridSurface> s(surface, p);
  const SeedReport rep = seed_release(g, thick, p.d0, p.h0, s.particles());
  s.initialise();
  HazardMaps maps(g, p.d0, p.density);
  const double t0 = now(), c0 = cpu();
  std::size_t particle_steps = 0;
  while (!s.finished()) {
    s.step();
    maps.record(s.particles(), s.time());
    particle_steps += s.particles().size();
  }
  const double wall = now() - t0, cpu_s = cpu() - c0;
  const auto row = series_row(s.particles(), s.budget(), s.time(), s.step_count());
  std::printf(
      "lecture case: %zu particles (%.0f m^3), 2000 x 1000 DSM at 2.5 m, %.0f s simulated in %lld steps: "
      "%.2f s wall, %.2f s CPU (%d thread(s), %.3g particle-steps/s); front travelled %.0f m (lecture: 4800 m in 600 "
      "s)\n",
      rep.particles, rep.volume_seeded, s.time(), static_cast<long long>(s.step_count()), wall, cpu_s, seed_threads,
      static_cast<double>(particle_steps) / wall, row.front_travel);
  // Sum of the final positions in id order: equal sums mean the same run (to compare variants).
  std::vector<Vec2> by_id(rep.particles, Vec2::Zero());
  for (std::size_t i = 0; i < s.particles().size(); ++i)
    by_id[static_cast<std::size_t>(s.particles().get<ParticleId>()[i])] = s.particles().get<Position<2>>()[i];
  Vec2 sum = Vec2::Zero();
  for (const Vec2& x : by_id) sum += x;
  std::printf("final positions: sum %.17g %.17g\n", sum.x(), sum.y());
  std::printf("memory: %zu bytes per particle; DSM %zu MB\n", RunoutStore::bytes_per_particle(),
              g.cells() * sizeof(double) / (1024 * 1024));
  return 0;
}
