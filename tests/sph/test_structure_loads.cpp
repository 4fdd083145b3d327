// Loads on structures (walls, piles) in the SPH solver (label: regression): the force the soil
// exerts on each structure, summed from the soil–boundary pair terms of the momentum equation
// (solver.hpp, pass 4b). Checked against the lateral thrust of a fluid at rest (½ ρ g H²) and of an
// elastic soil at rest (K0 ½ γ H², K0 = ν/(1 − ν)), against the momentum balance of the soil (the
// loads must be exactly the reaction of what the momentum pass applies), and for thread-count
// independence. Each case is a few hundred particles and runs in a few seconds on one thread.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "geohaz/core/parallel.hpp"
#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"
#include "support.hpp"

namespace geohaz::sph {
namespace {

/// A 2D box of soil W wide and H high between two side walls on a fixed bottom. The soil particles
/// sit at (i + ½)Δx, (k + ½)Δx: the column represents the height H = nz Δx, and each wall face lies
/// half a spacing outside the last soil particle (scenario.cpp).
Scenario<2> box(double W, double H, double dx, double rho, WallType sides) {
  ProfileDomain d;
  d.surface = {{0.0, H}, {W, H}};
  d.x_left = 0.0;
  d.x_right = W;
  d.left = d.right = sides;
  d.bottom = WallType::Fixed;
  return build_profile<2>(d, dx, {rho}, 1.2);
}

SolverSettings<2> settings_for(const Scenario<2>& sc) {
  SolverSettings<2> s;
  s.spacing = sc.spacing;
  s.h_factor = 1.2;
  s.domain_lo = sc.domain_lo;
  s.domain_hi = sc.domain_hi;
  return s;
}

std::size_t index_of(const Scenario<2>& sc, const std::string& name) {
  for (std::size_t k = 0; k < sc.structures.size(); ++k)
    if (sc.structures[k].name == name) return k;
  ADD_FAILURE() << "no structure " << name;
  return 0;
}

std::vector<Vec2> bases(const Scenario<2>& sc) {
  std::vector<Vec2> b;
  for (const auto& s : sc.structures) b.push_back(s.base);
  return b;
}

TEST(StructureLoads, BoxScenarioNamesItsWallsAndTagsTheirParticles) {
  auto sc = box(0.1, 0.2, 0.01, 1000.0, WallType::Fixed);
  ASSERT_EQ(sc.structures.size(), 3u);
  EXPECT_EQ(sc.structures[0].name, "bottom");
  EXPECT_EQ(sc.structures[1].name, "left_wall");
  EXPECT_EQ(sc.structures[2].name, "right_wall");
  EXPECT_NEAR(sc.structures[2].base.x(), 0.1, 1e-15);
  EXPECT_NEAR(sc.structures[2].base.y(), 0.0, 1e-15);
  EXPECT_EQ(sc.structures[2].normal, Vec2(1.0, 0.0));
  const auto& x = sc.store.get<Position<2>>();
  const auto& kind = sc.store.get<ParticleKind>();
  const auto& sid = sc.store.get<StructureId>();
  for (std::size_t i = 0; i < sc.store.size(); ++i) {
    if (kind[i] == 0) continue;
    const int expect = x[i].y() < 0.0 ? 0 : (x[i].x() < 0.0 ? 1 : 2);
    EXPECT_EQ(sid[i], expect) << "particle " << i;
  }
}

// A Newtonian fluid column of height H at rest between two vertical walls (after the gravity ramp
// under local damping, Bui et al. 2010): the hydrostatic pressure ρ g (H − z) on the wall face integrates
// to F = ½ ρ g H² per metre of wall, acting at H/3 above the base (moment ρ g H³/6 about it).
// Tolerance 2 % on F: the SPH wall sum has a free-surface kernel deficiency over the top h, and the
// weakly compressible fluid (c = 20 m/s, ρgH/K = 0.5 %) lowers the centre of mass by ~0.1 %. The
// moment within 4 % (the free-surface deficiency weighs with the lever arm).
TEST(StructureLoads, FluidColumnAtRestPushesTheWallWithHalfRhoGHSquared) {
  const double W = 0.1, H = 0.2, dx = 0.005, rho = 1000.0, g = 9.81, c = 20.0;
  auto sc = box(W, H, dx, rho, WallType::Fixed);
  MaterialParams m;
  m.density = rho;
  m.poisson = 0.0;
  m.young = 3.0 * rho * c * c;  // K = E/(3(1 − 2ν)) = ρ c²
  m.viscosity = 0.1;
  auto s = settings_for(sc);
  const std::size_t right = index_of(sc, "right_wall"), left = index_of(sc, "left_wall");
  const std::size_t bottom = index_of(sc, "bottom");
  SphSolver<2> solver(std::move(sc.store), {m}, NewtonianFluid{}, s);
  solver.track_structures(bases(sc));
  const auto rep = solver.apply_gravity_gradually(40.0 * H / c, 0.7, true);
  const auto& L = solver.structure_loads();
  const double F = 0.5 * rho * g * H * H, M = rho * g * H * H * H / 6.0;
  std::printf(
      "fluid column (%lld steps, max speed %.2e m/s): right wall Fx = %.5g N/m (1/2 rho g H^2 = %.5g), "
      "Fz = %.3g, My = %.5g N m/m (rho g H^3/6 = %.5g); left Fx = %.5g; bottom Fz = %.5g (weight %.5g)\n",
      static_cast<long long>(rep.steps), rep.max_speed, L[right].force.x(), F, L[right].force.y(), L[right].moment[1],
      M, L[left].force.x(), L[bottom].force.y(), rho * g * H * W);
  EXPECT_LT(rep.max_speed, 1e-2 * std::sqrt(g * H));
  EXPECT_NEAR(L[right].force.x(), F, 0.02 * F);
  EXPECT_NEAR(-L[left].force.x(), F, 0.02 * F);
  // Moment about the foot of the face: the thrust at H/3 tips the right wall outwards (+y, the
  // out-of-plane axis of the (x, z) section).
  EXPECT_NEAR(L[right].moment[1], M, 0.04 * M);
  // The bottom carries the weight (the walls take no shear from a fluid at rest): within 1 %.
  EXPECT_NEAR(-L[bottom].force.y(), rho * g * H * W, 0.01 * rho * g * H * W);
}

// An elastic soil at rest between smooth rigid walls (roller: no wall friction, so the soil is in
// uniaxial strain, plane strain ε_xx = ε_yy = 0): σ_xx = K0 σ_zz with K0 = ν/(1 − ν), and the
// horizontal force on a wall K0 ½ γ H² per metre. Within 5 % (the bar; the geostatic
// column of test_physics gives σ_v within 3 % and K0 within 10 % in the interior, the wall sum
// averages over all depths).
TEST(StructureLoads, ElasticSoilAtRestGivesTheAtRestEarthPressure) {
  const double W = 0.1, H = 0.4, dx = 0.01, rho = 2000.0, g = 9.81, nu = 0.3;
  auto sc = box(W, H, dx, rho, WallType::Roller);
  MaterialParams m;
  m.density = rho;
  m.young = 5e6;
  m.poisson = nu;
  auto s = settings_for(sc);
  const std::size_t right = index_of(sc, "right_wall"), left = index_of(sc, "left_wall");
  SphSolver<2> solver(std::move(sc.store), {m}, LinearElastic{}, s);
  solver.track_structures(bases(sc));
  const double cp = std::sqrt((m.young / (3 * (1 - 2 * nu)) + 4.0 / 3.0 * m.young / (2 * (1 + nu))) / rho);
  const auto rep = solver.apply_gravity_gradually(30.0 * H / cp, 0.7, true);
  const auto& L = solver.structure_loads();
  const double K0 = nu / (1 - nu), F = K0 * 0.5 * rho * g * H * H;
  std::printf(
      "elastic soil at rest (%lld steps): right wall Fx = %.5g N/m, left %.5g, K0 1/2 gamma H^2 = %.5g "
      "(ratio %.4f); Fz = %.3g N/m\n",
      static_cast<long long>(rep.steps), L[right].force.x(), -L[left].force.x(), F, L[right].force.x() / F,
      L[right].force.y());
  EXPECT_NEAR(L[right].force.x(), F, 0.05 * F);
  EXPECT_NEAR(-L[left].force.x(), F, 0.05 * F);
  // A smooth wall carries no shear: |Fz| below 1 % of the thrust.
  EXPECT_LT(std::abs(L[right].force.y()), 0.01 * F);
}

// The loads are the reaction of what the momentum pass applies to the soil: with no damping, the
// soil's acceleration after a step is a_i = (f_i^soil + f_i^boundary)/m_i + ḡ and the soil–soil
// pair forces cancel in the sum, so Σ_i m_i (a_i − ḡ) = −Σ_s F_s up to round-off. A soil block
// sliding against a fixed and a roller wall under gravity exercises the stress, artificial
// viscosity and artificial stress terms. Tolerance 1e-9 of the weight (round-off of a few thousand
// pair sums ~1e-13). This fails if pass 4b and step 4 treat a soil–boundary pair differently.
TEST(StructureLoads, BalanceTheSoilsMomentumChangeFromItsBoundaryPairs) {
  const double dx = 0.01, rho = 1800.0;
  ProfileDomain d;
  d.surface = {{0.0, 0.2}, {0.1, 0.2}, {0.1, 0.0}, {0.3, 0.0}};  // a column against the left wall
  d.x_left = 0.0;
  d.x_right = 0.3;
  d.left = WallType::Fixed;
  d.right = WallType::Roller;
  d.bottom = WallType::Roller;
  auto sc = build_profile<2>(d, dx, {rho}, 1.2);
  MaterialParams m;
  m.density = rho;
  m.young = 2e6;
  m.poisson = 0.3;
  m.friction = 0.5;
  auto s = settings_for(sc);
  SphSolver<2> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
  solver.track_structures(bases(sc));
  double weight = 0.0;
  for (std::size_t i = 0; i < solver.store().size(); ++i)
    if (solver.store().get<ParticleKind>()[i] == 0) weight += solver.store().get<Mass>()[i] * s.gravity;
  double worst = 0.0;
  for (int k = 0; k < 400; ++k) {
    solver.step();
    if (k % 50 != 49) continue;
    const auto& S = solver.store();
    Vec2 soil = Vec2::Zero(), walls = Vec2::Zero();
    for (std::size_t i = 0; i < S.size(); ++i)
      if (S.get<ParticleKind>()[i] == 0)
        soil += S.get<Mass>()[i] * (S.get<Acceleration<2>>()[i] - Vec2(0.0, -s.gravity));
    for (const auto& l : solver.structure_loads()) walls += l.force;
    worst = std::max(worst, (soil + walls).norm() / weight);
    EXPECT_GT(walls.norm(), 0.1 * weight);  // the walls do carry the column
  }
  std::printf("momentum balance: max |sum m (a - g) + sum F_walls| = %.3g weight\n", worst);
  EXPECT_LT(worst, 1e-9);
}

// One and two threads give bit-identical loads (per-block sums added in block order), on a box
// larger than the small-problem threshold (core parallel.hpp: smaller ones run on one thread).
TEST(StructureLoads, OneAndTwoThreadsGiveIdenticalLoads) {
  auto run = [](int threads) {
    omp_set_num_threads(threads);
    auto sc = box(0.4, 0.2, 0.005, 1800.0, WallType::Fixed);
    EXPECT_GE(static_cast<std::int64_t>(sc.store.size()), kParallelMin);
    MaterialParams m;
    m.density = 1800.0;
    m.young = 2e6;
    m.poisson = 0.3;
    auto s = settings_for(sc);
    s.earthquake = EarthquakeLoading::sine(3.0, 5.0, 0.0, 1.0, 0.0);
    SphSolver<2> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
    solver.track_structures(bases(sc));
    for (int k = 0; k < 100; ++k) solver.step();
    omp_set_num_threads(1);
    return solver.structure_loads();
  };
  const auto a = run(1), b = run(2);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].force, b[k].force) << "structure " << k;
    EXPECT_EQ(a[k].moment, b[k].moment) << "structure " << k;
  }
}

}  // namespace
}  // namespace geohaz::sph
