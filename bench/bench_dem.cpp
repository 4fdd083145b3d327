// Throughput of the bonded-disc DEM (particle-steps per second), 1 and 2 threads:
//  1. N unbonded discs settling under gravity in a box (contacts only): the problem of LAMMPS's
//     bench/peers/in.discs2d, run beside it by bench/peers/dem_vs_lammps.sh;
//  2. an N-disc bonded sample (parallel bonds on the regular-triangulation edges) compressed
//     between platens.
// Usage: bench_dem [N=100000] [steps=300] [threads=0: both 1 and 2] [case: settling | bonded | both (default)].
// Prints rates; never asserts.
//  3. `bench_dem avalanche [N=100000] [runout_s=300] [threads=2]`: a rock avalanche of about N
//     bonded, jointed discs (the material of data/dem/avalanche.toml) on a 3 km profile (35°
//     slope 1 km high onto a 1.57 km floor), run with the library's run_avalanche to rest or for
//     runout_s seconds after release; prints the wall time of the set-up (packing, tessellation,
//     bonds), of the settling and of the run-out, the run-out rate and, when the run was cut
//     short, the wall time a run to rest would take at that rate.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/dem/experiments.hpp"
#include "geohaz/dem/packing.hpp"
#include "geohaz/dem/solver.hpp"
#include "geohaz/dem/tessellation.hpp"

using namespace geohaz;
using namespace geohaz::dem;

namespace {

/// Discs on a triangular lattice (spacing 2 R_max) with radii in [0.8, 1] R_max, nx per row.
void lattice(DemSolver& s, std::size_t n, double rmax, double fill, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.8, 1.0);
  const auto nx = static_cast<std::size_t>(std::sqrt(static_cast<double>(n)));
  const double dx = 2 * rmax / fill, dy = dx * std::sqrt(3.0) / 2;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t row = k / nx, col = k % nx;
    add_disc(s.discs, Vec2((col + 0.5 * (row % 2) + 0.5) * dx, (row + 0.5) * dy + rmax), rmax * u(rng), 2650,
             static_cast<std::int64_t>(k));
  }
}

void box(DemSolver& s, double w, double h) {
  const Vec2 c[4] = {Vec2(0, 0), Vec2(w, 0), Vec2(w, h), Vec2(0, h)};
  const Vec2 n[4] = {Vec2(0, 1), Vec2(-1, 0), Vec2(0, -1), Vec2(1, 0)};
  for (int k = 0; k < 4; ++k) {
    WallSegment wl;
    const Vec2 d = c[(k + 1) % 4] - c[k];
    wl.a = c[k] - 0.5 * d;
    wl.b = c[(k + 1) % 4] + 0.5 * d;
    wl.servo_normal = n[k];
    s.walls.push_back(wl);
  }
}

/// FNV-1a hash of the positions and rotations in disc-id order (the store is reordered by cell):
/// equal hashes mean the same run to the last bit.
unsigned long long state_hash(const DemSolver& s) {
  const auto& id = s.discs.get<ParticleId>();
  std::vector<std::size_t> at(s.discs.size());
  for (std::size_t i = 0; i < at.size(); ++i) at[static_cast<std::size_t>(id[i])] = i;
  unsigned long long h = 1469598103934665603ull;
  const auto add = [&](const auto& value) {
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    for (std::size_t k = 0; k < sizeof(value); ++k) h = (h ^ p[k]) * 1099511628211ull;
  };
  for (std::size_t i : at) {
    add(s.discs.get<Position<2>>()[i]);
    add(s.discs.get<Rotation>()[i]);
  }
  return h;
}

/// Particle-steps per wall-clock second, and per CPU second of the process (all threads): on a
/// shared machine the second tells the per-core cost even when the wall clock is inflated.
std::pair<double, double> rate(DemSolver& s, int steps) {
  for (int k = 0; k < 20; ++k) s.step();  // warm-up (first list builds, first sort)
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  for (int k = 0; k < steps; ++k) s.step();
  const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  const double ps = static_cast<double>(s.discs.size()) * steps;
  return {ps / dt, ps / cpu};
}

/// The avalanche case (usage above).
int avalanche(std::size_t n, double runout_s, int threads) {
  omp_set_num_threads(threads);
  AvalancheSpec a;
  // Material, radii and release of data/dem/avalanche.toml.
  a.packing.r_min = 0.6;
  a.packing.r_max = 1.0;
  a.packing.porosity = 0.18;
  a.packing.locked_in_stress = 0;
  a.packing.seed = 3;
  a.packing.expansion_steps = 2000;
  a.packing.max_relax_steps = 6000;
  a.material.law = LinearSpringCoulomb{4e8, 4e8 / 2.5};
  a.material.contact.friction = 0.5;
  a.material.contact.rolling_friction = 0.1;
  a.material.contact.restitution = 0.3;
  a.material.bond.modulus = 2e8;
  a.material.bond.tensile_strength = a.material.bond.shear_strength = 2e6;
  a.material.bond.tensile_strength_std = a.material.bond.shear_strength_std = 0.4e6;
  a.material.joint_friction = 0.4;
  a.material.joint_sets = {JointSet{35, 5, 0.7, 8}, JointSet{-60, 8, 0.5, 6}};
  a.settle_time = 1.0;
  a.strength_factor = 0.5;
  a.record_interval = 0.5;
  a.terrain_friction = 0.5;
  a.terrain_restitution = 0.35;
  a.terrain_rolling_friction = 0.65;
  a.material.contact.fragment_rolling = true;  // material.terrain_rolling = "fragment"
  a.runout_time = runout_s;
  // 3 km profile: 35° slope from (0, 1000) to (1428, 0), floor to x = 3000 m.
  const double t = std::tan(35.0 * std::acos(-1.0) / 180.0), top = 1000.0;
  a.terrain = {Vec2(0, top), Vec2(top / t, 0), Vec2(3000, 0)};
  // Source: a parallelogram on the slope, as long (horizontally) as it is thick (vertically), of
  // area ≈ N × (mean disc area)/(1 − porosity) (mean R² of R uniform in [0.6, 1] is 0.653 m²).
  const double per_disc = std::acos(-1.0) * 0.653 / (1.0 - a.packing.porosity);
  const double side = std::sqrt(static_cast<double>(n) * per_disc);
  const double x0 = 60.0, z0 = top - x0 * t + 2.0;
  a.source = {Vec2(x0, z0), Vec2(x0 + side, z0 - side * t), Vec2(x0 + side, z0 - side * t + side), Vec2(x0, z0 + side)};
  a.support = {Vec2(x0 + side + 0.5, z0 - side * t - 10), Vec2(x0 + side + 0.5, z0 - side * t + side + 10)};
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  auto t_setup = t0, t_release = t0;
  bool settling = false, released = false;
  std::int64_t steps_at_release = 0, rebuilds_at_release = 0;
  std::clock_t c_release = 0;
  DemSolver s;
  const auto r = run_avalanche(a, s, [&](const DemSolver& sv, const std::string& phase) {
    if (!settling) {
      settling = true;
      t_setup = clock::now();
    }
    if (phase == "runout" && !released) {
      released = true;
      t_release = clock::now();
      c_release = std::clock();
      steps_at_release = sv.step_count();
      rebuilds_at_release = sv.rebuild_count();
    }
  });
  const auto t1 = clock::now();
  const double run_cpu = static_cast<double>(std::clock() - c_release) / CLOCKS_PER_SEC;
  auto secs = [](auto d) { return std::chrono::duration<double>(d).count(); };
  const double run_wall = secs(t1 - t_release);
  const auto steps = s.step_count() - steps_at_release;
  const double rate = static_cast<double>(r.discs) * static_cast<double>(steps) / run_wall;
  std::printf("bench_dem avalanche: %zu discs, %zu bonds, %d thread(s); 3 km profile, source side %.0f m\n", r.discs,
              r.bonds, threads, side);
  std::printf("  set-up (packing, tessellation, bonds, joints) + first settling steps: %.1f s wall\n",
              secs(t_setup - t0));
  std::printf("  settling %.1f s simulated: %.1f s wall\n", a.settle_time, secs(t_release - t_setup));
  std::printf(
      "  run-out %.1f s simulated, %lld steps (dt = %.3g s): %.1f s wall, %.3g particle-steps/s (%.3g per "
      "CPU-second); %s\n",
      r.duration, static_cast<long long>(steps), s.time_step(), run_wall, rate,
      static_cast<double>(r.discs) * static_cast<double>(steps) / run_cpu,
      r.at_rest ? "at rest" : "cut short (still moving)");
  std::printf("  neighbour-list rebuilds in the run-out: %lld (one per %.1f steps)\n",
              static_cast<long long>(s.rebuild_count() - rebuilds_at_release),
              static_cast<double>(steps) /
                  static_cast<double>(std::max<std::int64_t>(1, s.rebuild_count() - rebuilds_at_release)));
  std::printf("  L = %.0f m, H = %.0f m, H/L = %.3f at 99 %% of the mass, %zu fragments\n", r.runout, r.fall_height,
              r.h_over_l, r.fragment_sizes.size());
  if (!r.at_rest && r.duration > 0) {
    // At this rate, a run to rest of T seconds takes T/duration times as long.
    for (double T : {60.0, 120.0, 200.0})
      std::printf("  a run-out of %.0f s at this rate: %.0f s wall\n", T, run_wall * T / r.duration);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "avalanche")
    return avalanche(argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 100000, argc > 3 ? std::atof(argv[3]) : 300.0,
                     argc > 4 ? std::atoi(argv[4]) : 2);
  const std::size_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 100000;
  const int steps = argc > 2 ? std::atoi(argv[2]) : 300;
  const int only_threads = argc > 3 ? std::atoi(argv[3]) : 0;  // 0: 1 and 2 threads
  const std::string only_case = argc > 4 ? argv[4] : "both";
  const double rmax = 1e-3;
  const auto nx = static_cast<std::size_t>(std::sqrt(static_cast<double>(n)));
  std::printf("bench_dem: %zu discs, %d timed steps\n", n, steps);
  for (int threads : {1, 2}) {
    if (only_threads > 0 && threads != only_threads) continue;
    omp_set_num_threads(threads);
    if (only_case != "bonded") {
      DemSolver s;
      // LAMMPS's problem (bench/peers/in.discs2d, gran/hooke/history): kn 1e8, kt 4e7 N/m, μ 0.5,
      // e 0.5; its γ_t = γ_n/2 tangential dashpot is c_t = ½ c_n = f_t c_n √(k_t/k_n), so
      // f_t = ½/√0.4; its skin 0.2 mm and fixed Δt 2 µs (docs/performance.md, "DEM beside LAMMPS").
      s.law = LinearSpringCoulomb{1e8, 4e7};
      s.contact.friction = 0.5;
      s.contact.restitution = 0.5;
      s.contact.tangential_damping = 0.5 / std::sqrt(0.4);
      s.settings.skin = 0.2e-3;
      s.settings.fixed_time_step = 2e-6;
      // Lattice spacing = mean diameter (radii 0.8–1 R_max): about half the neighbours touch, the rest
      // close up as the pile settles under gravity.
      lattice(s, n, rmax, 1.0 / 0.9, 1);
      const double w = (nx + 1) * 2 * rmax * 0.9;
      box(s, w, 2 * w);
      s.initialise();
      // Let the pile form so contacts exist, then time (LAMMPS: `run 220`, then the timed run).
      for (int k = 0; k < 200; ++k) s.step();
      const auto [r, rc] = rate(s, steps);
      std::printf(
          "  unbonded settling, %d thread(s): %.3g particle-steps/s (%.3g per CPU-second; %zu contacts, dt = %.3g s; "
          "%lld list builds; state %016llx)\n",
          threads, r, rc, s.contact_count(), s.time_step(), static_cast<long long>(s.rebuild_count()), state_hash(s));
    }
    if (only_case != "settling") {
      DemSolver s;
      s.settings.gravity = Vec2::Zero();
      s.settings.local_damping = 0.7;
      const double Ec = 20e9;
      s.law = LinearSpringCoulomb{2 * Ec, 2 * Ec / 2.5};
      s.contact.friction = 0.5;
      lattice(s, n, rmax, 1.0, 2);
      const auto& x = s.discs.get<Position<2>>();
      Vec2 lo = x[0], hi = x[0];
      for (const auto& p : x) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      const auto t = tessellate(x, s.discs.get<Radius>(), lo - Vec2::Constant(rmax), hi + Vec2::Constant(rmax));
      ParallelBondProperties pb;
      pb.modulus = Ec;
      pb.tensile_strength = pb.shear_strength = 50e6;
      pb.tensile_strength_std = pb.shear_strength_std = 10e6;
      install_parallel_bonds(s.discs, t.edges, pb, 0.5, 3, s.bonds);
      box(s, hi.x() + rmax, hi.y() + rmax);
      s.walls[0].velocity = Vec2(0, 0.2);   // bottom platen up
      s.walls[2].velocity = Vec2(0, -0.2);  // top platen down
      s.initialise();
      const auto [r, rc] = rate(s, steps);
      std::printf(
          "  bonded compression, %d thread(s): %.3g particle-steps/s (%.3g per CPU-second; %zu bonds, %zu broken; "
          "state %016llx)\n",
          threads, r, rc, s.bonds.size(), s.events.size(), state_hash(s));
    }
  }
  return 0;
}
