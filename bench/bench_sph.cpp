// Throughput of the SPH slope model: particle-steps per second for a 2D Drucker–Prager column
// collapse (~1e5 particles) and a 3D slope (~4e4 particles, SPH-slope paper (2020)'s size), on 1 and 2 threads,
// and the memory per particle. Prints figures; never asserts (docs/performance.md). The state hash
// after the steps is the same on 1 and 2 threads (results independent of the thread count).
//   bench_sph [steps] [scale] [2d|3d|all] [threads] [skin] [structures] [correction]   (scale < 1
//   shrinks the problems for a quick look; the others select runs, e.g. `bench_sph 50 1 2d 2 0.3` for
//   one figure; structures = 1 sums the loads on the walls every step, pass 4b, as sph-slope does;
//   correction 1 turns numerics.kernel_correction on, 2 quadratic, 0 off, default: the solver's default)
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"

using namespace geohaz;
using namespace geohaz::sph;

/// FNV-1a hash of the positions and stresses in store order: equal on 1 and 2 threads when the
/// results are bit-identical (docs/sph.md, "Determinism").
template <int Dim>
unsigned long long state_hash(const SphStore<Dim>& S) {
  unsigned long long h = 1469598103934665603ull;
  auto add = [&](const auto& v) {
    const auto* p = reinterpret_cast<const unsigned char*>(v.data());
    for (std::size_t k = 0; k < v.size() * sizeof(v[0]); ++k) h = (h ^ p[k]) * 1099511628211ull;
  };
  add(S.template get<Position<Dim>>());
  add(S.template get<Stress>());
  return h;
}

/// Which runs (all by default): `bench_sph [steps] [scale] [2d|3d|all] [threads] [skin]`.
struct Selection {
  int dim = 0;              ///< 0: both
  int threads = 0;          ///< 0: 1 and 2
  double skin = -1;         ///< < 0: 0 and 0.3
  bool structures = false;  ///< track the loads on the scenario's structures (pass 4b)
  int correction = -1;      ///< kernel-gradient correction: 1 on, 2 quadratic, 0 off, < 0 the solver's default
};
Selection selection;

template <int Dim>
void run(const char* name, Scenario<Dim> sc, const MaterialParams& m, int steps) {
  for (double skin : {0.0, 0.3})
    for (int threads : {1, 2}) {
      if ((selection.threads > 0 && threads != selection.threads) ||
          (selection.skin >= 0.0 && std::abs(skin - selection.skin) > 1e-9))
        continue;
      omp_set_num_threads(threads);
      SolverSettings<Dim> s;
      s.spacing = sc.spacing;
      s.h_factor = 1.2;
      s.periodic = sc.periodic;
      s.domain_lo = sc.domain_lo;
      s.domain_hi = sc.domain_hi;
      s.neighbour_skin = skin;
      if (selection.correction >= 0) {
        s.kernel_correction = selection.correction >= 1;
        s.quadratic_correction = selection.correction == 2;
      }
      SphSolver<Dim> solver(sc.store, {m}, DruckerPrager{}, s);
      if (selection.structures) {
        std::vector<Vec<Dim>> bases;
        for (const auto& st : sc.structures) bases.push_back(st.base);
        solver.track_structures(std::move(bases));
      }
      solver.step();  // warm-up (first reorder)
      const auto t0 = std::chrono::steady_clock::now();
      for (int i = 0; i < steps; ++i) solver.step();
      const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double rate = static_cast<double>(solver.store().size()) * steps / sec;
      std::printf(
          "%-26s%s skin %.1fh threads %d  particles %7zu  steps %4d  %7.3f s  %.3e particle-steps/s  "
          "%.0f B/particle  %lld list builds  correction %d  state %016llx\n",
          name, selection.structures ? " +loads" : "", skin, threads, solver.store().size(), steps, sec, rate,
          solver.bytes_per_particle(), static_cast<long long>(solver.neighbour_builds()),
          s.kernel_correction ? (s.quadratic_correction ? 2 : 1) : 0, state_hash(solver.store()));
    }
}

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 50;
  const double scale = argc > 2 ? std::atof(argv[2]) : 1.0;
  if (argc > 3) selection.dim = std::string(argv[3]) == "2d" ? 2 : (std::string(argv[3]) == "3d" ? 3 : 0);
  if (argc > 4) selection.threads = std::atoi(argv[4]);
  if (argc > 5) selection.skin = std::atof(argv[5]);
  if (argc > 6) selection.structures = std::atoi(argv[6]) != 0;
  if (argc > 7) selection.correction = std::atoi(argv[7]);
  MaterialParams m;
  m.density = 1800;
  m.young = 1e6;
  m.poisson = 0.3;
  m.friction = 30 * std::numbers::pi / 180;
  if (selection.dim != 3) {
    // 2D column: 1e5 particles ≈ 316 × 316 at Δx = 1 mm... use a 2:1 column of 0.45 m × 0.225 m at 1 mm.
    const double dx = 0.001 / std::sqrt(scale);
    ProfileDomain d;
    d.surface = {{0.0, 0.45}, {0.225, 0.45}, {0.225, 0.0}, {0.6, 0.0}};
    d.x_left = 0.0;
    d.x_right = 0.6;
    d.right = WallType::None;
    run<2>("2D DP column collapse", build_profile<2>(d, dx, {m.density}, 1.2), m, steps);
  }
  if (selection.dim != 2) {
    m.fit = DruckerPragerFit::Compression3D;
    SlopeGeometry g;  // SPH-slope paper (2020), Fig. 3: 0.25 m high, 1.5H:1V, crest 0.3 m, front 0.6 m
    g.height = 0.25;
    g.crest_length = 0.3;
    g.front_length = 0.6;
    g.base_thickness = 0.05;
    auto d = g.profile();
    const double dx = 0.01 / std::cbrt(scale);
    d.width = std::max(0.15, 5.0 * dx);  // ~4e4 particles at dx = 10 mm; periodic width ≥ 4h
    run<3>("3D DP slope (SPH-slope paper 2020)", build_profile<3>(d, dx, {m.density}, 1.2), m, steps / 2 + 1);
  }
  return 0;
}
