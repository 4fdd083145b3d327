// Unit tests of the runout building blocks: head-pressure shape, friction laws and their implicit
// integration, a single particle on planes (closed-form kinematics), release seeding.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "geohaz/runout/basal_friction.hpp"
#include "geohaz/runout/head_pressure.hpp"
#include "geohaz/runout/release.hpp"
#include "geohaz/runout/solver.hpp"

using namespace geohaz;
using namespace geohaz::runout;

namespace {
constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;
}  // namespace

TEST(HeadPressure, ContinuousAtOneAndTwoAndZeroBeyond) {
  const double eps = 1e-9;
  // The lecture's transcription (+1/8) jumps by 1/4 at x = 1 and x = 2; the continuous reading
  // must not: |f(1−ε) − f(1+ε)| = O(ε).
  EXPECT_NEAR(HeadPressureForce::shape(1.0 - eps), HeadPressureForce::shape(1.0 + eps), 1e-8);
  EXPECT_NEAR(HeadPressureForce::shape(2.0 - eps), HeadPressureForce::shape(2.0 + eps), 1e-8);
  EXPECT_DOUBLE_EQ(HeadPressureForce::shape(1.0), 0.0);
  EXPECT_DOUBLE_EQ(HeadPressureForce::shape(0.0), 1.0);
  EXPECT_DOUBLE_EQ(HeadPressureForce::shape(1.5), 0.125);  // −½(0.5)(−0.5)
  for (double x : {2.0, 2.5, 10.0}) EXPECT_EQ(HeadPressureForce::shape(x), 0.0);
}

TEST(HeadPressure, NormalisationMakesContinuumLimitGGradH) {
  // Midpoint quadrature of I = ∫₀² x² f(x) dx against the closed form used for C.
  const int n = 200000;
  double sum = 0.0;
  for (int k = 0; k < n; ++k) {
    const double x = (k + 0.5) * 2.0 / n;
    sum += x * x * HeadPressureForce::shape(x);
  }
  sum *= 2.0 / n;
  EXPECT_NEAR(sum, HeadPressureForce::second_moment(), 1e-9);
  EXPECT_NEAR(HeadPressureForce::consistent_normalisation() * kPi * sum, 1.0, 1e-8);
}

TEST(Friction, ImplicitStepNeverReverses) {
  const FrictionTerms t{2.0, 0.5};
  for (double s : {0.0, 1e-6, 0.1, 1.0, 10.0, 100.0})
    for (double dt : {1e-4, 0.1, 1.0, 100.0}) {
      const double out = speed_after_friction(s, dt, t);
      EXPECT_GE(out, 0.0);
      EXPECT_LE(out, s);
      // It solves out = s − dt(rest + drag·out²) whenever the particle keeps moving.
      if (out > 0.0) {
        EXPECT_NEAR(out, s - dt * (t.rest + t.drag * out * out), 1e-12 * std::max(1.0, s));
      }
    }
  EXPECT_EQ(speed_after_friction(0.1, 1.0, FrictionTerms{0.2, 0.0}), 0.0);  // stops, does not go to −0.1
}

TEST(Friction, VoellmyEqualsManningWithMuIcrAndXi) {
  // Seed's law with m = 0 is Voellmy with μ = i_cr and ξ = R_h^{1/3}/n².
  const double h = 2.3, n = 0.06, icr = 0.15, gn = kG * std::cos(0.3);
  const ModifiedManningFriction manning{n, icr, 0.0};
  const VoellmyFriction voellmy{icr, std::cbrt(h) / (n * n)};
  const auto a = manning.terms(kG, gn, h, 3.0, 1800.0), b = voellmy.terms(kG, gn, h, 3.0, 1800.0);
  EXPECT_NEAR(a.rest, b.rest, 1e-12);
  EXPECT_NEAR(a.drag, b.drag, 1e-12 * a.drag);
  EXPECT_EQ(friction_name(BasalFriction{CoulombFriction{}}), "coulomb");
}

namespace {
// One particle released at rest at the origin of a plane falling towards +x at angle θ.
RunoutSolver<InclinedPlane> single_particle(double theta, BasalFriction law, double dt_max = 0.01) {
  RunoutParameters p;
  p.d0 = 1.0;
  p.duration = 2.0;
  p.dt_max = dt_max;
  p.friction = law;
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(theta), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p);
  s.particles().append(1);
  s.particles().get<Volume>()[0] = 1.0;
  s.initialise();
  return s;
}
}  // namespace

TEST(SingleParticle, FrictionlessPlaneAcceleratesAtGSinTheta) {
  for (double deg : {5.0, 20.0, 45.0, 60.0}) {
    const double th = deg * kPi / 180.0;
    auto s = single_particle(th, CoulombFriction{0.0});
    while (!s.finished()) s.step();
    const double t = s.time();
    // Surface speed grows as g sin θ t exactly (constant acceleration, symplectic Euler).
    EXPECT_NEAR(s.particles().get<Speed>()[0], kG * std::sin(th) * t, 1e-9) << deg << "°";
    // Map velocity is the along-slope velocity times cos θ.
    EXPECT_NEAR(s.particles().get<Velocity<2>>()[0].x(), kG * std::sin(th) * std::cos(th) * t, 1e-9);
    EXPECT_NEAR(s.particles().get<Velocity<2>>()[0].y(), 0.0, 1e-15);
  }
}

TEST(SingleParticle, CoulombPlaneAcceleratesAtGSinMinusIcrCos) {
  const double mu = 0.3;
  for (double deg : {20.0, 30.0, 45.0, 70.0}) {
    const double th = deg * kPi / 180.0;
    auto s = single_particle(th, CoulombFriction{mu});
    while (!s.finished()) s.step();
    const double expected = kG * (std::sin(th) - mu * std::cos(th)) * s.time();
    EXPECT_NEAR(s.particles().get<Speed>()[0], expected, 1e-9) << deg << "°";
  }
}

TEST(SingleParticle, ManningIcrHoldsAtRestBelowCriticalSlope) {
  for (double grad : {0.0, 0.05, 0.149}) {
    auto s = single_particle(std::atan(grad), ModifiedManningFriction{0.06, 0.15, 0.0});
    s.step();
    EXPECT_EQ(s.particles().get<Speed>()[0], 0.0) << grad;
    EXPECT_TRUE(s.all_stopped());
    EXPECT_TRUE(s.finished());
  }
  auto moving = single_particle(std::atan(0.151), ModifiedManningFriction{0.06, 0.15, 0.0});
  moving.step();
  EXPECT_GT(moving.particles().get<Speed>()[0], 0.0);
}

TEST(SingleParticle, StopsOnRunoutWhereSlopeFallsBelowIcr) {
  // Slide from x = −20 m down tan θ = 0.5 onto a flat run-out with Coulomb μ = 0.2. On the slope
  // S² = 2 g L (tan θ − μ) (L horizontal length); at the break the bed constraint turns the
  // velocity into the flat keeping its magnitude (the normal reaction does no work), so the
  // stopping distance is S²/(2 μ g). (This analytical break is a true kink without curvature, so
  // no centripetal friction acts there; on a DSM the curvature smoothed over d0 adds it.)
  const double mu = 0.2, tn = 0.5, L = 20.0;
  RunoutParameters p;
  p.d0 = 1.0;
  p.duration = 100.0;
  p.stop_energy_fraction = 0.0;  // stop by friction alone
  p.dt_max = 1e-3;
  p.friction = CoulombFriction{mu};
  RunoutSolver<SlopeToRunout> s(SlopeToRunout{0.0, -tn, 0.0}, p);
  s.particles().append(1);
  s.particles().get<Position<2>>()[0] = Vec2(-L, 0.0);
  s.particles().get<Volume>()[0] = 1.0;
  s.initialise();
  while (!s.finished()) s.step();
  EXPECT_TRUE(s.all_stopped());
  const double s2 = 2.0 * kG * L * (tn - mu);
  const double expected = s2 / (2.0 * mu * kG);
  // Tolerance: the step that crosses the break mixes the two slopes over ≤ S·dt ≈ 0.01 m.
  EXPECT_NEAR(s.particles().get<Position<2>>()[0].x(), expected, 0.05);
  EXPECT_LT(s.time(), 100.0);
}

TEST(SingleParticle, LeavingTheTerrainCountsLostVolume) {
  RunoutParameters p;
  p.d0 = 1.0;
  p.duration = 10.0;
  p.friction = CoulombFriction{0.0};
  InclinedPlane plane;
  plane.slope = Vec2(-1.0, 0.0);
  plane.lo = Vec2(-5.0, -5.0);
  plane.hi = Vec2(5.0, 5.0);
  RunoutSolver<InclinedPlane> s(plane, p);
  s.particles().append(2);
  s.particles().get<Position<2>>()[1] = Vec2(0.0, 4.0);
  s.particles().get<Volume>()[0] = 0.7;
  s.particles().get<Volume>()[1] = 0.3;
  s.initialise();
  while (!s.finished()) s.step();
  EXPECT_TRUE(s.particles().empty());
  EXPECT_EQ(s.budget().lost_particles, 2u);
  EXPECT_DOUBLE_EQ(s.budget().lost, 1.0);
  EXPECT_NEAR(s.budget().balance_error(), 0.0, 1e-15);
}

TEST(Release, SeedingMatchesTheVolumeGivenAndSpacing) {
  GridGeometry g{40, 30, 1000.0, 2000.0, 2.5, 2.5};
  std::vector<double> t(g.cells(), 0.0);
  for (int r = 5; r < 25; ++r)
    for (int c = 3; c < 37; ++c) t[g.index(c, r)] = 0.5 + 0.1 * ((c * 7 + r * 3) % 11);  // 0.5–1.5 m
  RunoutStore store;
  const auto rep = seed_release(g, t, 5.0, 0.5, store);
  double given = 0.0;
  for (double v : t) given += v * g.cell_area();
  EXPECT_NEAR(rep.volume_given, given, 1e-12 * given);
  EXPECT_NEAR(rep.volume_seeded, given, 1e-12 * given);
  EXPECT_EQ(rep.particles, store.size());
  // Mean thickness ~1 m with h0 = 0.5 m: about two particles per d0² block.
  const double v0 = 0.5 * 25.0;
  EXPECT_NEAR(static_cast<double>(store.size()), given / v0, 0.1 * given / v0);
  for (const auto& x : store.get<Position<2>>()) {
    int c, r;
    ASSERT_TRUE(g.cell_of(x, c, r));
    EXPECT_GT(t[g.index(c, r)], 0.0);  // every particle sits on a release cell
  }
}

TEST(Release, BinningPointsKeepsVolumeAndFlagsOutside) {
  GridGeometry g{10, 10, 0.0, 100.0, 10.0, 10.0};
  std::size_t outside;
  auto t = bin_point_volumes(g, {Vec2(5, 95), Vec2(6, 94), Vec2(55, 45)}, {1.0, 2.0, 4.0}, outside);
  EXPECT_EQ(outside, std::numeric_limits<std::size_t>::max());
  EXPECT_DOUBLE_EQ(t[g.index(0, 0)], 3.0 / 100.0);
  EXPECT_DOUBLE_EQ(t[g.index(5, 5)], 4.0 / 100.0);
  bin_point_volumes(g, {Vec2(5, 95), Vec2(-1, 50)}, {1.0, 1.0}, outside);
  EXPECT_EQ(outside, 1u);
}

TEST(SingleParticle, TimeStepCollapseIsASimulationErrorNamingTheStep) {
  // A time step below dt_min (here forced by an absurd dt_min) stops the run with a diagnosis.
  RunoutParameters p;
  p.d0 = 1.0;
  p.dt_min = 10.0;
  p.duration = 100.0;
  RunoutSolver<InclinedPlane> s(InclinedPlane{}, p);
  s.particles().append(1);
  s.particles().get<Volume>()[0] = 1.0;
  s.initialise();
  try {
    s.step();
    FAIL() << "expected a SimulationError";
  } catch (const SimulationError& e) {
    EXPECT_NE(std::string(e.what()).find("step 0"), std::string::npos) << e.what();
  }
}
