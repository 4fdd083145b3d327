// Strong scaling of the SPH domain decomposition (issue #36; docs/performance.md): the 3D slope of
// bench_sph (SPH-slope paper 2020, Fig. 3, periodic across its width) on the ranks of mpirun, with
// the threads each rank gets (OMP_NUM_THREADS). Prints, on rank 0, particle-steps per second, the
// ghosts per owned particle (halo fraction) and the memory per owned particle (store with the
// ghosts, neighbour list and pair buffers of the rank holding most). Never asserts.
//   mpirun -np P bench_sph_mpi [steps] [scale] [width_m]   (scale 1: Δx = 10 mm, ~4e4 particles at
//   0.15 m width; scale 2.5 with width 0.375: ~1e5 particles)
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "geohaz/mpi/mpi_communicator.hpp"
#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"

using namespace geohaz;
using namespace geohaz::sph;

int main(int argc, char** argv) {
  geohaz::mpi::Session session(argc, argv);
  const auto world = geohaz::mpi::world_communicator(session);
  const int steps = argc > 1 ? std::atoi(argv[1]) : 20;
  const double scale = argc > 2 ? std::atof(argv[2]) : 1.0;
  MaterialParams m;
  m.density = 1800;
  m.young = 1e6;
  m.poisson = 0.3;
  m.friction = 30 * std::numbers::pi / 180;
  m.fit = DruckerPragerFit::Compression3D;
  SlopeGeometry g;
  g.height = 0.25;
  g.crest_length = 0.3;
  g.front_length = 0.6;
  g.base_thickness = 0.05;
  auto d = g.profile();
  const double dx = 0.01 / std::cbrt(scale);
  d.width = argc > 3 ? std::atof(argv[3]) : std::max(0.15, 5.0 * dx);
  auto sc = build_profile<3>(d, dx, {m.density}, 1.2);
  SolverSettings<3> s;
  s.spacing = sc.spacing;
  s.h_factor = 1.2;
  s.periodic = sc.periodic;
  s.domain_lo = sc.domain_lo;
  s.domain_hi = sc.domain_hi;
  const std::size_t total = sc.store.size();
  SphSolver<3> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
  if (world) solver.distribute(world);
  solver.step();  // warm-up: the partition, the first list and sort
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) solver.step();
  const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto* dom = solver.domain();
  const double owned = static_cast<double>(solver.owned_count());
  const double ghosts = dom ? static_cast<double>(dom->stats().ghosts) : 0.0;
  const double bytes = solver.bytes_per_particle() * static_cast<double>(solver.store().size()) / std::max(owned, 1.0);
  std::vector<double> mine{sec, ghosts / std::max(owned, 1.0), bytes};
  std::vector<double> all = world ? world->all_gather(mine) : mine;
  double tmax = 0.0, halo = 0.0, bmax = 0.0;
  for (std::size_t r = 0; r < all.size() / 3; ++r) {
    tmax = std::max(tmax, all[3 * r]);
    halo = std::max(halo, all[3 * r + 1]);
    bmax = std::max(bmax, all[3 * r + 2]);
  }
  if (session.rank() == 0)
    std::printf(
        "3D DP slope ranks %d threads %d particles %zu steps %d  %.3f s  %.3e particle-steps/s  ghosts/owned %.3f "
        "(largest)  %.0f B per owned particle (largest)  %lld list builds\n",
        session.size(), omp_get_max_threads(), total, steps, tmax, static_cast<double>(total) * steps / tmax, halo,
        bmax, static_cast<long long>(solver.neighbour_builds()));
  return 0;
}
