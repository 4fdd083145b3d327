// Regression tests of the SPH solver on small problems with known answers (label: regression).
// Each runs in seconds on two cores.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "geohaz/sph/diagnostics.hpp"
#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"
#include "support.hpp"

namespace geohaz::sph {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// A 2D soil column of width W and height H between roller side walls on a fixed base.
Scenario<2> column(double W, double H, double dx, double rho, WallType sides, double hf = 1.2) {
  ProfileDomain d;
  d.surface = {{0.0, H}, {W, H}};
  d.x_left = 0.0;
  d.x_right = W;
  d.left = d.right = sides;
  d.bottom = WallType::Fixed;
  return build_profile<2>(d, dx, {rho}, hf);
}

SolverSettings<2> settings_for(const Scenario<2>& sc, double hf = 1.2) {
  SolverSettings<2> s;
  s.spacing = sc.spacing;
  s.h_factor = hf;
  s.domain_lo = sc.domain_lo;
  s.domain_hi = sc.domain_hi;
  return s;
}

double min_soil_distance(const SphStore<2>& S) {
  const auto& x = S.get<Position<2>>();
  const auto& k = S.get<ParticleKind>();
  double dmin = 1e300;
  for (std::size_t i = 0; i < S.size(); ++i)
    for (std::size_t j = i + 1; j < S.size(); ++j)
      if (k[i] == 0 && k[j] == 0) dmin = std::min(dmin, (x[i] - x[j]).norm());
  return dmin;
}

// Compression-wave arrival in a laterally confined elastic column (periodic across its width, i.e.
// an infinitely wide layer: uniaxial strain without side-wall effects, see docs/sph.md): the whole
// column moves down at v0 onto a fixed base at t = 0; the front of the wave that brings it to rest
// travels up at the P-wave speed c_p = √((K + 4G/3)/ρ) (uniaxial strain), and behind it the stress
// is σ_zz = −ρ c_p v0 (impedance). The front's travel time between two probe heights (which leaves
// out the start-up at the wall, about one particle row) within 5 % of Δz/c_p, the arrival at the
// upper probe within 10 % of z/c_p, the stress within 5 %.
TEST(ElasticWave, CompressionArrivalMatchesPWaveSpeed) {
  const double W = 0.05, H = 0.6, dx = 0.01, rho = 2000.0, v0 = 0.05;
  auto sc = column(W, H, dx, rho, WallType::None);
  MaterialParams m;
  m.density = rho;
  m.young = 5e6;
  m.poisson = 0.25;
  m.finalise();
  const double cp = m.p_wave_speed;
  auto s = settings_for(sc);
  s.gravity = 0.0;
  s.periodic.axis[0] = true;
  s.periodic.lo[0] = 0.0;
  s.periodic.hi[0] = W;
  s.neighbour_skin = 0.0;  // the 5-particle period must be ≥ 2 × the list's cut-off, (2 + skin) h
  auto& v = sc.store.get<Velocity<2>>();
  const auto& kind = sc.store.get<ParticleKind>();
  for (std::size_t i = 0; i < v.size(); ++i)
    if (kind[i] == 0) v[i] = Vec2(0.0, -v0);
  SphSolver<2> solver(std::move(sc.store), {m}, LinearElastic{}, s);
  const double z_probe[2] = {0.2, 0.4};
  double t_arrival[2] = {-1.0, -1.0}, stress_behind = 0.0;
  while (solver.time() < 1.5 * z_probe[1] / cp) {
    solver.step();
    const auto& S = solver.store();
    const auto& x = S.get<Position<2>>();
    const auto& vv = S.get<Velocity<2>>();
    const auto& k = S.get<ParticleKind>();
    for (int p = 0; p < 2; ++p) {
      double sum = 0;
      int cnt = 0;
      for (std::size_t i = 0; i < S.size(); ++i)
        if (k[i] == 0 && std::abs(x[i][1] - z_probe[p]) < 0.5 * dx + 1e-3) {
          sum += vv[i][1];
          ++cnt;
        }
      if (t_arrival[p] < 0 && cnt > 0 && sum / cnt > -0.5 * v0) t_arrival[p] = solver.time();
    }
  }
  {
    const auto& S = solver.store();
    const auto& x = S.get<Position<2>>();
    const auto& sig = S.get<Stress>();
    const auto& k = S.get<ParticleKind>();
    double sum = 0;
    int cnt = 0;
    for (std::size_t i = 0; i < S.size(); ++i)
      if (k[i] == 0 && x[i][1] > 0.1 && x[i][1] < 0.3) {
        sum += sig[i](1, 1);
        ++cnt;
      }
    stress_behind = sum / cnt;
  }
  const double t_theory = z_probe[1] / cp, dt_theory = (z_probe[1] - z_probe[0]) / cp;
  std::printf(
      "P-wave: c_p = %.2f m/s, arrival at %.1f / %.1f m: %.5f / %.5f s (theory %.5f / %.5f s), travel time "
      "%.5f s (theory %.5f s), stress %.1f Pa (theory %.1f Pa)\n",
      cp, z_probe[0], z_probe[1], t_arrival[0], t_arrival[1], z_probe[0] / cp, t_theory, t_arrival[1] - t_arrival[0],
      dt_theory, stress_behind, -rho * cp * v0);
  ASSERT_GT(t_arrival[0], 0.0);
  ASSERT_GT(t_arrival[1], 0.0);
  EXPECT_NEAR((t_arrival[1] - t_arrival[0]) / dt_theory, 1.0, 0.05);
  EXPECT_NEAR(t_arrival[1] / t_theory, 1.0, 0.10);
  EXPECT_NEAR(stress_behind / (-rho * cp * v0), 1.0, 0.05);
}

// Couette start-up (SWJTU lecture 2010 "simple shear of viscous fluid"): fluid at rest between a fixed wall
// (y = 0) and a wall moving at U (y = H), periodic along x. Analytical profile
//   u(y,t) = U y/H + Σ_n 2U(−1)^n/(nπ) sin(nπy/H) exp(−n²π²νt/H²).
// Layer-averaged velocities within 4 % of U at t = 0.1 s (profile still developing) and 0.4 s.
TEST(ViscousShear, CouetteStartUpMatchesSeries) {
  const double dx = 0.001, W = 0.01, H = 0.02, rho = 1000.0, mu = 1.0, U = 0.01;
  SphStore<2> S;
  auto add = [&](double x, double y, Kind kind, Vec2 vel) {
    const std::size_t i = S.append(1);
    S.get<Position<2>>()[i] = Vec2(x, y);
    S.get<Velocity<2>>()[i] = vel;
    S.get<Density>()[i] = rho;
    S.get<Mass>()[i] = rho * dx * dx;
    S.get<ParticleKind>()[i] = static_cast<std::uint8_t>(kind);
    S.get<WallNormal<2>>()[i] = Vec2(0, 1);
    S.get<ParticleId>()[i] = static_cast<std::int64_t>(i);
  };
  const int nx = 10, ny = 20;
  for (int i = 0; i < nx; ++i) {
    for (int k = 0; k < ny; ++k) add((i + 0.5) * dx, (k + 0.5) * dx, Kind::Soil, Vec2::Zero());
    for (int l = 0; l < 3; ++l) {
      add((i + 0.5) * dx, -(l + 0.5) * dx, Kind::FixedWall, Vec2::Zero());
      add((i + 0.5) * dx, H + (l + 0.5) * dx, Kind::FixedWall, Vec2(U, 0.0));
    }
  }
  MaterialParams m;
  m.density = rho;
  m.young = 3.0 * 1000.0;  // K = 1000 Pa → c = 1 m/s = 100 U (weakly compressible)
  m.poisson = 0.0;
  m.viscosity = mu;
  SolverSettings<2> s;
  s.spacing = dx;
  s.h_factor = 1.2;
  s.gravity = 0.0;
  s.viscosity_alpha = 0.0;
  s.artificial_stress = 0.0;
  s.periodic.axis = {true, false};
  s.periodic.lo = Vec2(0.0, -1.0);
  s.periodic.hi = Vec2(W, 1.0);
  SphSolver<2> solver(std::move(S), {m}, NewtonianFluid{}, s);
  const double nu = mu / rho;
  auto exact = [&](double y, double t) {
    double u = U * y / H;
    for (int n = 1; n < 200; ++n)
      u += 2.0 * U * (n % 2 ? -1.0 : 1.0) / (n * std::numbers::pi) * std::sin(n * std::numbers::pi * y / H) *
           std::exp(-n * n * std::numbers::pi * std::numbers::pi * nu * t / (H * H));
    return u;
  };
  for (double t_check : {0.1, 0.4}) {
    while (solver.time() < t_check) solver.step();
    const auto& St = solver.store();
    std::vector<double> sum(ny, 0.0);
    std::vector<int> cnt(ny, 0);
    for (std::size_t i = 0; i < St.size(); ++i) {
      if (St.get<ParticleKind>()[i] != 0) continue;
      const int b = static_cast<int>(std::floor(St.get<Position<2>>()[i][1] / dx));
      if (b < 0 || b >= ny) continue;
      sum[b] += St.get<Velocity<2>>()[i][0];
      ++cnt[b];
    }
    double worst = 0.0;
    for (int b = 0; b < ny; ++b) {
      ASSERT_GT(cnt[b], 0);
      worst = std::max(worst, std::abs(sum[b] / cnt[b] - exact((b + 0.5) * dx, solver.time())));
    }
    std::printf("Couette t = %.3f s: max |u - u_exact| = %.3g U\n", solver.time(), worst / U);
    EXPECT_LT(worst, 0.04 * U);
  }
}

// Parting (SWJTU lecture 2010 "meeting and parting"): a free cohesionless block without gravity, given a
// uniform expansion v = ε̇ (x − x_c), comes apart. Its particles carry no stress (nothing holds
// them together) and their density stays at ρ0 (constitutive.hpp, `min_density`); without the floor
// the continuity density follows ρ0/(1 + ε̇t)² (0.25ρ0 here) and m/ρ grows without bound, which is
// how the fine column collapses blew up. Checks: min ρ ≥ ρ0 (1e-12), |σ| ≤ 1e-9 Pa once apart,
// velocities unchanged (no spurious forces between parting particles, 1e-6 relative).
TEST(Parting, CohesionlessParticlesKeepRestDensityAndCarryNoStress) {
  const double dx = 0.005, rho = 1800.0, rate = 10.0;
  ProfileDomain d;
  d.surface = {{0.0, 0.05}, {0.05, 0.05}};
  d.x_left = 0.0;
  d.x_right = 0.05;
  d.left = d.right = d.bottom = WallType::None;
  auto sc = build_profile<2>(d, dx, {rho}, 1.2);
  auto& v = sc.store.get<Velocity<2>>();
  const auto& x0 = sc.store.get<Position<2>>();
  const Vec2 centre(0.025, 0.025);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = rate * (x0[i] - centre);
  const std::vector<Vec2> v_start = v;
  MaterialParams m;
  m.density = rho;
  m.young = 1e6;
  m.poisson = 0.3;
  m.friction = 30 * kDeg;
  auto s = settings_for(sc);
  s.gravity = 0.0;
  s.domain_lo = Vec2(-1.0, -1.0);
  s.domain_hi = Vec2(1.0, 1.0);
  SphSolver<2> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
  while (solver.time() < 0.1) solver.step();  // (1 + ε̇t)² = 4: particles 2Δx apart
  const auto& S = solver.store();
  double rho_min = 1e300, sig_max = 0.0, dv_max = 0.0;
  for (std::size_t i = 0; i < S.size(); ++i) {
    rho_min = std::min(rho_min, S.get<Density>()[i]);
    sig_max = std::max(sig_max, S.get<Stress>()[i].cwiseAbs().maxCoeff());
    const auto id = static_cast<std::size_t>(S.get<ParticleId>()[i]);
    dv_max = std::max(dv_max, (S.get<Velocity<2>>()[i] - v_start[id]).norm() / (rate * 0.025));
  }
  std::printf("parting block: min density %.6g kg/m3 (rho0 %.0f), max |sigma| %.3g Pa, max |dv|/v %.3g\n", rho_min, rho,
              sig_max, dv_max);
  EXPECT_GE(rho_min, rho * (1.0 - 1e-12));
  EXPECT_LE(sig_max, 1e-9);
  EXPECT_LT(dv_max, 1e-6);
}

// Cohesionless Drucker–Prager column collapse (a = H/L0 = 1) against a wall: the flow stops with a
// finite run-out. Quasi-2D experiments give (L∞ − L0)/L0 ≈ 1.2 a for a ≲ 2–3 (Lube et al. 2005;
// Lajeunesse et al. 2005); this coarse run (Δx = L0/20; front = last bin ≥ 2Δx thick) must land within ±25 % of it,
// with the mass at rest (max speed < 1 % of √(gH)), final height ≤ H and no particle behind the wall.
TEST(GranularCollapse, FiniteRunoutNearExperimentalScaling) {
  const double L0 = 0.1, Hc = 0.1, rho = 1800.0, g = 9.81;
  const double dx = std::getenv("SPH_DX") ? std::atof(std::getenv("SPH_DX")) : 0.005;
  ProfileDomain d;
  d.surface = {{0.0, Hc}, {L0, Hc}, {L0, 0.0}, {0.5, 0.0}};
  d.x_left = 0.0;
  d.x_right = 0.5;
  d.right = WallType::None;
  auto sc = build_profile<2>(d, dx, {rho}, 1.2);
  MaterialParams m;
  m.density = rho;
  m.young = 1e6;
  m.poisson = 0.3;
  m.friction = (std::getenv("SPH_PHI") ? std::atof(std::getenv("SPH_PHI")) : 30.0) * kDeg;
  auto s = settings_for(sc);
  s.stress_free_fraction = std::getenv("SPH_SF") ? std::atof(std::getenv("SPH_SF")) : 0.0;
  if (std::getenv("SPH_AS")) s.artificial_stress = std::atof(std::getenv("SPH_AS"));
  if (std::getenv("SPH_AV")) s.viscosity_alpha = std::atof(std::getenv("SPH_AV"));
  SphSolver<2> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
  DiagnosticFrame f;
  f.toe_x = L0;
  f.base_length = L0;
  f.base_top = 0.0;
  f.spacing = dx;
  SeriesRow r;
  while (solver.time() < 1.0) {
    solver.step();
    if (solver.step_count() % 200 == 0) {
      r = series_row(solver.store(), f);
      if (solver.time() > 0.3 && r.max_speed < 0.01 * std::sqrt(g * Hc)) break;
    }
  }
  r = series_row(solver.store(), f);
  double hmax = 0.0, xmin = 1e9;
  const auto& S = solver.store();
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.get<ParticleKind>()[i] != 0) continue;
    hmax = std::max(hmax, S.get<Position<2>>()[i][1] + 0.5 * dx);
    xmin = std::min(xmin, S.get<Position<2>>()[i][0]);
  }
  if (std::getenv("SPH_DEBUG"))
    for (auto& p : free_surface(solver.store(), dx)) std::printf("  %.4f %.4f\n", p[0], p[1]);
  std::printf(
      "collapse a=1: t = %.3f s, (L-L0)/L0 = %.3f (experiments 1.2; tip %.3f), H/H0 = %.3f, max speed %.3g m/s\n",
      solver.time(), r.normalised_runout, (r.tip - L0) / L0, hmax / Hc, r.max_speed);
  EXPECT_LT(r.max_speed, 0.01 * std::sqrt(g * Hc)) << "not at rest after 1 s";
  EXPECT_NEAR(r.normalised_runout, 1.2, 0.25 * 1.2);
  EXPECT_LE(hmax, Hc + 0.5 * dx);
  EXPECT_GT(xmin, 0.0);
}

// The Verlet skin (numerics.neighbour_skin) only changes when the list is rebuilt, not which pairs
// interact (pairs beyond 2h are skipped): a run with skin 0.3h must reproduce the run without it to
// round-off of the summation order (1e-9 relative after 500 steps of a collapsing column).
TEST(NeighbourSkin, SameResultAsRebuildEveryStep) {
  auto run = [](double skin, std::int64_t& builds) {
    ProfileDomain d;
    d.surface = {{0.0, 0.1}, {0.1, 0.1}, {0.1, 0.0}, {0.4, 0.0}};
    d.x_right = 0.4;
    d.right = WallType::None;
    auto sc = build_profile<2>(d, 0.005, {1800.0}, 1.2);
    MaterialParams m;
    m.density = 1800;
    m.young = 1e6;
    m.friction = 30 * kDeg;
    auto s = settings_for(sc);
    s.neighbour_skin = skin;
    SphSolver<2> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
    for (int k = 0; k < 500; ++k) solver.step();
    builds = solver.neighbour_builds();
    std::vector<Vec2> x(solver.store().size());
    for (std::size_t i = 0; i < x.size(); ++i)
      x[static_cast<std::size_t>(solver.store().get<ParticleId>()[i])] = solver.store().get<Position<2>>()[i];
    return x;
  };
  std::int64_t b0 = 0, b1 = 0;
  const auto x0 = run(0.0, b0), x1 = run(0.3, b1);
  double worst = 0.0;
  for (std::size_t i = 0; i < x0.size(); ++i) worst = std::max(worst, (x0[i] - x1[i]).norm());
  std::printf("skin: %lld vs %lld list builds, max position difference %.3g m\n", static_cast<long long>(b0),
              static_cast<long long>(b1), worst);
  EXPECT_EQ(b0, 500);
  EXPECT_LT(b1, 100);
  EXPECT_LT(worst, 1e-9);
}

// Geostatic column (Bui et al. 2010: gravity applied gradually): σ_v = −ρ g depth within a few per cent,
// K0 = ν/(1−ν) for the laterally confined elastic column, particles at rest and no clumping.
TEST(Geostatic, ElasticColumnAtRest) {
  const double W = 0.1, H = 0.4, dx = 0.01, rho = 2000.0, g = 9.81, nu = 0.3;
  auto sc = column(W, H, dx, rho, WallType::Roller);
  MaterialParams m;
  m.density = rho;
  m.young = 5e6;
  m.poisson = nu;
  auto s = settings_for(sc);
  SphSolver<2> solver(std::move(sc.store), {m}, LinearElastic{}, s);
  const double cp = std::sqrt((m.young / (3 * (1 - 2 * nu)) + 4.0 / 3.0 * m.young / (2 * (1 + nu))) / rho);
  const auto rep = solver.apply_gravity_gradually(30.0 * H / cp, 0.7, true);
  const auto& S = solver.store();
  const auto& x = S.get<Position<2>>();
  const auto& sig = S.get<Stress>();
  const auto& k = S.get<ParticleKind>();
  double num = 0, den = 0, sxx = 0;
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (k[i] != 0) continue;
    const double depth = H - x[i][1];
    if (depth < 0.2 * H || depth > 0.9 * H) continue;
    num += sig[i](1, 1);
    den += -rho * g * depth;
    sxx += sig[i](0, 0);
  }
  const double ratio = num / den;
  std::printf("geostatic: %lld steps, sigma_v / (rho g z) = %.4f, K0 = %.3f (theory %.3f), max speed %.2e m/s\n",
              static_cast<long long>(rep.steps), ratio, sxx / num, nu / (1 - nu), rep.max_speed);
  EXPECT_NEAR(ratio, 1.0, 0.03);
  EXPECT_NEAR(sxx / num, nu / (1 - nu), 0.1 * nu / (1 - nu));
  EXPECT_LT(rep.max_speed, 1e-3 * std::sqrt(g * H));
  EXPECT_GT(min_soil_distance(S), 0.7 * dx) << "tensile-instability clumping";
}

// A cover on inclined bedrock (the DSM-section layout of the demo): 3 m of Drucker–Prager soil,
// three particles deep, on a 50° slope; infinite-slope factor of safety ≈ 1.5. After the geostatic phase it must stay
// where it is. The boundary particles carry the stress extrapolated along the layering normal (solver step 1); with the
// extrapolation along the vertical instead — the flat-ground (Adami) form, which drops the shear-stress gradient ρ g
// sin θ at the wall — the same cover creeps down the bedrock, the defect that made the real-terrain section of the demo
// move without shaking.
double cover_creep(bool vertical_layering) {
  const double dx = 1.0, depth = 3.0, L = 30.0, slope = std::tan(50.0 * kDeg), rho = 1900.0;
  ProfileDomain d;
  d.surface = {{0.0, L * slope}, {L, 0.0}};
  d.x_left = 0.0;
  d.x_right = L;
  d.z_bottom = -depth;
  d.bedrock_depth = depth;
  auto sc = build_profile<2>(d, dx, {rho}, 1.2);
  if (vertical_layering)
    for (auto& nu : sc.store.get<LayerNormal<2>>())
      if (nu.squaredNorm() > 0.0) nu = Vec2(0.0, 1.0);
  MaterialParams m;
  m.density = rho;
  m.young = 20e6;
  m.poisson = 0.3;
  m.friction = 35.0 * kDeg;
  m.cohesion = 25e3;  // at 3 m: τ = ρ g z sinθ cosθ ≈ 27.5 kPa, strength c + ρ g z cos²θ tanφ ≈ 41 kPa
  auto s = settings_for(sc);
  SphSolver<2> solver(std::move(sc.store), {m}, DruckerPrager{}, s);
  solver.apply_gravity_gradually(20.0 * depth / 120.0, 0.7, true);
  while (solver.time() < 2.0) solver.step();
  // Largest displacement of the soil away from the end walls (which hold the slope's ends).
  const auto& S = solver.store();
  double umax = 0.0;
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.get<ParticleKind>()[i] != 0) continue;
    const double x = S.get<Position<2>>()[i][0];
    if (x < 5.0 || x > L - 5.0) continue;
    umax = std::max(umax, S.get<Displacement<2>>()[i].norm());
  }
  return umax;
}

TEST(Geostatic, CoverOnInclinedBedrockStaysPut) {
  const double u_layered = cover_creep(false), u_vertical = cover_creep(true);
  std::printf(
      "cover on 50 deg bedrock, 2 s after the geostatic phase: max displacement %.2e m (layer-normal "
      "extrapolation), %.2e m (vertical extrapolation)\n",
      u_layered, u_vertical);
  EXPECT_LT(u_layered, 0.01);  // 1 cm: elastic adjustment only
  EXPECT_GT(u_vertical, 10.0 * u_layered) << "the test no longer distinguishes the two extrapolations";
}

// A thin stiff layer between the bedrock boundary and a softer cover, elastic: two particles of
// base (E_b, ρ_b) under three of cover (E = 20 MPa, ρ = 1900 kg/m³), Δx = 1 m, the default Δt
// (CFL 0.2), on flat ground or a plane inclined at `slope_deg`. After the geostatic phase it must
// stay at rest. It did not with walls that take the Shepard average of their soil neighbours
// (from the previous step's stress, with the paper's momentum pair σ_i/ρ_i² + σ_j/ρ_j²): an
// oscillation of the base rows grew to > 1 m/s within seconds on flat ground, and on the 45° plane
// also once the lag and the pair were fixed (docs/sph.md, "Boundary particles and material
// interfaces"). Returns the largest soil speed over the first and over the last second after the
// geostatic phase.
std::pair<double, double> interface_speeds(double young_base, double rho_base, double t_end, double slope_deg = 0.0) {
  const double dx = 1.0, L = 30.0, z_top = 5.0, drop = L * std::tan(slope_deg * kDeg);
  ProfileDomain d;
  d.surface = {{0.0, z_top + drop}, {L, z_top}};
  d.x_left = 0.0;
  d.x_right = L;
  d.z_bottom = 0.0;
  d.bedrock_depth = z_top;
  d.surface_layer_depth = 3.0;
  d.surface_material = 1;
  auto sc = build_profile<2>(d, dx, {rho_base, 1900.0}, 1.2);
  MaterialParams base, cover;
  base.density = rho_base;
  base.young = young_base;
  base.poisson = 0.25;
  cover.density = 1900.0;
  cover.young = 20e6;
  cover.poisson = 0.3;
  auto s = settings_for(sc);
  SphSolver<2> solver(std::move(sc.store), {base, cover}, LinearElastic{}, s);
  solver.apply_gravity_gradually(0.3, 0.7, true);
  const double t0 = solver.time();
  double first = 0.0, last = 0.0;
  while (solver.time() < t0 + t_end) {
    solver.step();
    const double v = solver.last_stats().max_speed;
    if (solver.time() < t0 + 1.0) first = std::max(first, v);
    if (solver.time() > t0 + t_end - 1.0) last = std::max(last, v);
  }
  return {first, last};
}

TEST(Interface, ThinStiffBaseUnderSoftCoverStaysAtRest) {
  const char* what[] = {"E and density contrast", "density only", "E only", "E and density contrast, 45 deg plane"};
  const double young[] = {200e6, 20e6, 200e6, 200e6}, rho[] = {2300.0, 2300.0, 1900.0, 2300.0},
               slope[] = {0.0, 0.0, 0.0, 45.0};
  for (int k = 0; k < 4; ++k) {
    const auto [first, last] = interface_speeds(young[k], rho[k], 8.0, slope[k]);
    std::printf("thin base under a soft cover (%s): max speed %.2e m/s in the first second, %.2e m/s in the 8th\n",
                what[k], first, last);
    // The ringing left by the geostatic ramp decays; the instability grew to 1-100 m/s.
    EXPECT_LT(last, 0.5 * first) << what[k];
    EXPECT_LT(last, 1e-2) << what[k];
  }
}

}  // namespace
}  // namespace geohaz::sph
