// Unit tests of the SPH solver's prescribed pore pressure (pore_pressure.hpp; docs/sph.md, "Pore
// pressure and seismic coefficients"): the r_u overburden against hand integrals, the solver's
// pore-pressure field against the formula at every particle, and rain's head and clock.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <utility>
#include <vector>

#include "geohaz/sph/infiltration.hpp"
#include "geohaz/sph/pore_pressure.hpp"
#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"
#include "support.hpp"

namespace geohaz::sph {
namespace {

// A slope profile (crest at 15 m, face down to 5 m between x = 25 and 45) over two layers (ρ 1800
// below z = 8, 2000 above): ∫_z^{z_g} ρ dz by hand at points in each layer, across the interface,
// under the face, and 0 on and above the ground.
TEST(Overburden, MassAboveIntegratesTheLayersUpToTheGround) {
  OverburdenProfile p;
  p.ground = {{0.0, 15.0}, {25.0, 15.0}, {45.0, 5.0}, {65.0, 5.0}};
  p.tops = {8.0};
  p.densities = {1800.0, 2000.0};
  EXPECT_DOUBLE_EQ(p.mass_above(10.0, 12.0), 2000.0 * 3.0);
  EXPECT_DOUBLE_EQ(p.mass_above(10.0, 2.0), 2000.0 * 7.0 + 1800.0 * 6.0);
  // Under the face at x = 35 the ground is at 10 m.
  EXPECT_DOUBLE_EQ(p.mass_above(35.0, 6.0), 2000.0 * 2.0 + 1800.0 * 2.0);
  EXPECT_DOUBLE_EQ(p.mass_above(55.0, 1.0), 1800.0 * 4.0);
  EXPECT_EQ(p.mass_above(35.0, 10.0), 0.0);
  EXPECT_EQ(p.mass_above(35.0, 11.0), 0.0);
  OverburdenProfile one;
  one.ground = p.ground;
  one.densities = {1900.0};
  EXPECT_DOUBLE_EQ(one.mass_above(0.0, 0.0), 1900.0 * 15.0);
}

// u = r_u g_f ∫ρ dz (the gravity of the step, ramped in the geostatic phase) and, with a phreatic
// surface, γ_w times the depth below the table clipped to the ground.
TEST(PoreWaterStep, RuGivesRuTimesTheOverburdenStressAndATableItsHead) {
  PoreWaterSettings ru;
  ru.ru = 0.3;
  ru.overburden.ground = {{0.0, 10.0}, {10.0, 10.0}};
  ru.overburden.densities = {2000.0};
  ASSERT_TRUE(ru.active());
  const PoreWaterStep half(ru, 0.0, 9.81, 0.5);
  EXPECT_NEAR(half.pressure<2>(Vec2(3.0, 4.0)), 0.3 * 9.81 * 0.5 * 2000.0 * 6.0, 1e-9);
  EXPECT_NEAR(half.pressure<3>(Vec3(3.0, 7.0, 4.0)), 0.3 * 9.81 * 0.5 * 2000.0 * 6.0, 1e-9);
  EXPECT_EQ(half.pressure<2>(Vec2(3.0, 11.0)), 0.0);

  PoreWaterSettings table;
  table.phreatic = {{0.0, 12.0}, {10.0, 6.0}};
  table.ground = {{0.0, 10.0}, {10.0, 10.0}};
  table.history_times = {0.0, 10.0};
  table.history_offsets = {0.0, 2.0};
  const PoreWaterStep at5(table, 5.0, 9.81, 1.0);                            // Δz = 1 m
  EXPECT_NEAR(at5.pressure<2>(Vec2(0.0, 4.0)), 1000.0 * 9.81 * 6.0, 1e-9);   // clipped to the ground at 10 m
  EXPECT_NEAR(at5.pressure<2>(Vec2(10.0, 4.0)), 1000.0 * 9.81 * 3.0, 1e-9);  // 6 + 1 − 4
  EXPECT_EQ(at5.pressure<2>(Vec2(10.0, 8.0)), 0.0);
}

// The solver's field: a level deposit 3 m deep at 0.25 m spacing with r_u = 0.4 takes
// u = r_u ρ g (z_g − z) at every soil particle in the first step (to round-off), the particles
// unmoved by then.
TEST(PoreWaterStep, SolverGivesEverySoilParticleItsOverburdenPressure) {
  const double dx = 0.25, rho = 1900.0, g = 9.81, ru = 0.4;
  ProfileDomain d;
  d.surface = {{0.0, 3.0}, {5.0, 3.0}};
  d.x_left = 0.0;
  d.x_right = 5.0;
  auto sc = build_profile<2>(d, dx, {rho}, 1.2);
  MaterialParams m;
  m.density = rho;
  m.young = 1e7;
  m.poisson = 0.3;
  m.friction = 30.0 * std::numbers::pi / 180.0;
  SolverSettings<2> s;
  s.spacing = dx;
  s.gravity = g;
  s.periodic = sc.periodic;
  s.domain_lo = sc.domain_lo;
  s.domain_hi = sc.domain_hi;
  s.pore_water.ru = ru;
  s.pore_water.overburden.ground = d.surface;
  s.pore_water.overburden.densities = {rho};
  std::vector<double> z0(sc.store.size());  // by particle id: the step reorders the store
  for (std::size_t i = 0; i < sc.store.size(); ++i)
    z0[static_cast<std::size_t>(sc.store.get<ParticleId>()[i])] = sc.store.get<Position<2>>()[i][1];
  SphSolver<2> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
  solver.step();
  const auto& S = solver.store();
  int n = 0;
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.get<ParticleKind>()[i] != static_cast<std::uint8_t>(Kind::Soil)) continue;
    const double z = z0[static_cast<std::size_t>(S.get<ParticleId>()[i])];
    EXPECT_NEAR(S.get<PorePressure>()[i], ru * g * rho * (3.0 - z), 1e-9 * ru * g * rho * 3.0) << "particle " << i;
    ++n;
  }
  EXPECT_GT(n, 200);
}

// Rain on a section: the head at a point is Iverson's ψ(Z, t_r, δ, d) (InfiltrationHistory, tested
// against the analytic solution in stability_map's tests) of its column, Z the depth below the
// ground, δ the inclination of the ground segment above the point (0 beyond the ends), and the clock
// maps the run's time to the rain's, linear between its pairs and held beyond them.
TEST(RainPorePressure, HeadIsIversonsOfTheColumnAndTheClockMapsTheRunsTime) {
  InfiltrationParameters p;
  p.conductivity = 1e-5;
  p.diffusivity = 1e-3;
  p.steady_flux = 1e-6;
  const auto rain_history = RainfallHistory::uniform_steps(3600.0, {2e-5, 5e-6});  // the first beyond K_s
  const std::vector<std::array<double, 2>> ground = {{0.0, 15.0}, {25.0, 15.0}, {45.0, 5.0}, {65.0, 5.0}};
  const RainPorePressure rain(p, rain_history, ground, 4.0, {{0.0, 0.0}, {10.0, 7200.0}});
  const InfiltrationHistory h(p, rain_history);
  const double face = std::atan(0.5);
  EXPECT_EQ(rain.slope_at(10.0), 0.0);
  EXPECT_DOUBLE_EQ(rain.slope_at(30.0), face);
  EXPECT_EQ(rain.slope_at(50.0), 0.0);
  EXPECT_EQ(rain.slope_at(-5.0), 0.0);
  EXPECT_EQ(rain.slope_at(70.0), 0.0);
  for (const double t : {0.0, 1800.0, 5400.0, 20000.0})
    for (const auto& [x, z] : {std::pair{10.0, 12.0}, {10.0, 3.0}, {30.0, 9.0}, {40.0, 2.0}, {55.0, 1.0}}) {
      const double Z = (x < 25.0 ? 15.0 : (x < 45.0 ? 15.0 - (x - 25.0) / 2.0 : 5.0)) - z;
      const double delta = x > 25.0 && x < 45.0 ? face : 0.0;
      EXPECT_NEAR(rain.head(x, z, t), h.pressure_head(Z, t, delta, 4.0), 1e-12) << x << " " << z << " " << t;
    }
  EXPECT_EQ(rain.head(30.0, 13.0, 100.0), -std::numeric_limits<double>::infinity());  // above the ground
  EXPECT_DOUBLE_EQ(rain.initial_level(35.0), 6.0);
  EXPECT_EQ(rain.rain_time(-1.0), 0.0);
  EXPECT_DOUBLE_EQ(rain.rain_time(2.5), 1800.0);
  EXPECT_EQ(rain.rain_time(12.0), 7200.0);  // held beyond the last pair
  const RainPorePressure identity(p, rain_history, ground, 4.0, {});
  EXPECT_EQ(identity.rain_time(123.0), 123.0);

  // The solver's u: γ_w max(ψ, 0) at the rain's time of the step.
  PoreWaterSettings pw;
  pw.rain = std::make_shared<const RainPorePressure>(rain);
  ASSERT_TRUE(pw.active());
  const PoreWaterStep step(pw, 5.0, 9.81, 1.0);  // rain time 3600 s
  EXPECT_DOUBLE_EQ(step.t_rain, 3600.0);
  EXPECT_NEAR(step.pressure<2>(Vec2(30.0, 9.0)), 1000.0 * 9.81 * std::max(rain.head(30.0, 9.0, 3600.0), 0.0), 1e-9);
  EXPECT_GT(step.pressure<2>(Vec2(10.0, 3.0)), 0.0);   // below the table
  EXPECT_EQ(step.pressure<2>(Vec2(10.0, 14.0)), 0.0);  // suction is not counted
}

// A DSM section's cover (3 m of 1900 kg/m³ by depth) over its base (2200 kg/m³): ∫ρ dz by hand above a
// point in the cover, at its base and in the base, under a 2D profile and under a 3D strip's grid.
TEST(Overburden, CoverByDepthOverTheBaseUnderAProfileAndAGrid) {
  OverburdenProfile p;
  p.ground = {{0.0, 20.0}, {10.0, 15.0}};
  p.densities = {2200.0};
  p.surface_layer_depth = 3.0;
  p.surface_density = 1900.0;
  EXPECT_DOUBLE_EQ(p.mass_above(4.0, 16.0), 1900.0 * 2.0);  // ground 18 m
  EXPECT_DOUBLE_EQ(p.mass_above(4.0, 15.0), 1900.0 * 3.0);
  EXPECT_DOUBLE_EQ(p.mass_above(4.0, 13.5), 1900.0 * 3.0 + 2200.0 * 1.5);
  EXPECT_EQ(p.mass_above(4.0, 18.5), 0.0);
  auto g = std::make_shared<StripGrid>();
  g->nx = 3;
  g->ny = 2;
  g->dx = 5.0;
  g->dy = 4.0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 3; ++i) g->ground.push_back(20.0 - 0.5 * (5.0 * i) + 0.25 * (4.0 * j));
  p.grid = g;
  // z_g(4, 2) = 20 − 2 + 0.5 = 18.5 m.
  EXPECT_DOUBLE_EQ(p.mass_above(4.0, 2.0, 14.0), 1900.0 * 3.0 + 2200.0 * 1.5);
}

// Rain under a 3D strip's grid of a plane whose gradient (0.3, 0.4) is oblique to the strip: the cell's
// δ is the plane's true slope atan 0.5, so every point's head equals Iverson's at its vertical depth
// below the plane with that δ (to round-off), and the initial level lies d below the plane.
TEST(RainPorePressure, UnderAStripGridTheHeadTakesTheTrueSlopeOfTheCell) {
  auto g = std::make_shared<StripGrid>();
  g->nx = 5;
  g->ny = 4;
  g->x0 = 1.0;
  g->dx = 2.0;
  g->dy = 1.5;
  auto plane = [](double x, double y) { return 30.0 - 0.3 * x + 0.4 * y; };
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) g->ground.push_back(plane(g->x0 + g->dx * i, g->y0 + g->dy * j));
  InfiltrationParameters h;
  h.conductivity = 1e-5;
  h.diffusivity = 2e-4;
  const auto rain = RainfallHistory::uniform_steps(1800.0, {8e-6, 2e-5});
  const RainPorePressure r(h, rain, g, 1.2, {});
  const InfiltrationHistory ref(h, rain);
  const double delta = std::atan(0.5);
  EXPECT_NEAR(r.smallest_beta(), std::cos(delta) * std::cos(delta), 1e-15);
  for (const double x : {1.3, 4.0, 8.9})
    for (const double y : {0.2, 2.5, 4.4})
      for (const double Z : {0.3, 1.0, 2.5}) {
        const double z = plane(x, y) - Z;
        EXPECT_NEAR(r.head(x, y, z, 2700.0), ref.pressure_head(Z, 2700.0, delta, 1.2), 1e-12) << x << " " << y;
      }
  EXPECT_NEAR(r.initial_level(4.0, 2.5), plane(4.0, 2.5) - 1.2, 1e-12);
  EXPECT_EQ(r.head(4.0, 2.5, plane(4.0, 2.5) + 0.1, 2700.0), -std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace geohaz::sph
