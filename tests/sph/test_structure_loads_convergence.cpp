// Convergence of the wall thrust of a fluid at rest with resolution (label: validation, ~2.5 min on
// one thread): the Newtonian fluid column of test_structure_loads.cpp (H = 0.2 m, c = 20 m/s) at
// Δx = 10, 5 and 2.5 mm. The thrust on a wall approaches ½ ρ g H² from below as the free-surface
// kernel deficiency (a layer ~h thick) shrinks: the error must fall with each halving of Δx and be
// under 1.5 % at 2.5 mm. Numbers in docs/sph.md, "Loads on structures".
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"

namespace geohaz::sph {
namespace {

/// Thrust on the right wall (N/m) of a fluid column W × H at rest (Δx), after the gravity ramp.
double fluid_thrust(double dx) {
  const double W = 0.1, H = 0.2, rho = 1000.0, c = 20.0;
  ProfileDomain d;
  d.surface = {{0.0, H}, {W, H}};
  d.x_left = 0.0;
  d.x_right = W;
  auto sc = build_profile<2>(d, dx, {rho}, 1.2);
  MaterialParams m;
  m.density = rho;
  m.poisson = 0.0;
  m.young = 3.0 * rho * c * c;
  m.viscosity = 0.1;
  SolverSettings<2> s;
  s.spacing = dx;
  s.h_factor = 1.2;
  s.domain_lo = sc.domain_lo;
  s.domain_hi = sc.domain_hi;
  std::vector<Vec2> bases;
  std::size_t right = 0;
  for (std::size_t k = 0; k < sc.structures.size(); ++k) {
    bases.push_back(sc.structures[k].base);
    if (sc.structures[k].name == "right_wall") right = k;
  }
  SphSolver<2> solver(std::move(sc.store), {m}, NewtonianFluid{}, s);
  solver.track_structures(bases);
  solver.apply_gravity_gradually(60.0 * H / c, 0.7, true);
  return solver.structure_loads()[right].force.x();
}

TEST(StructureLoadsConvergence, FluidThrustApproachesHalfRhoGHSquared) {
  omp_set_num_threads(1);
  const double F = 0.5 * 1000.0 * 9.81 * 0.2 * 0.2;
  double last = 1.0;
  for (const double dx : {0.01, 0.005, 0.0025}) {
    const double err = fluid_thrust(dx) / F - 1.0;
    std::printf("fluid column, dx = %.4f m: thrust / (1/2 rho g H^2) - 1 = %+.4f\n", dx, err);
    EXPECT_LT(std::abs(err), std::abs(last));
    last = err;
  }
  EXPECT_LT(std::abs(last), 0.015);
}

}  // namespace
}  // namespace geohaz::sph
