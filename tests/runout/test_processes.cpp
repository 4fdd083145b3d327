// Regression tests of the processes of docs/runout.md, "Processes":
//  - entrainment, growth law dV/ds = E_s V: one particle on a uniform slope grows as V₀ exp(E_s s);
//    erosion never exceeds the erodible depth; a uniform sheet on a frictionless flat bed keeps its
//    momentum Σ V v while it grows;
//  - entrainment, shear law ė = k_e (τ_b − τ_c)⁺: none below τ_c; the rate of a steady uniform
//    Voellmy sheet (τ_b = ρ g h sin θ) as the law says;
//  - friction zones: a particle crossing from one Coulomb zone into another stops where the
//    analytic stopping distance says;
//  - forest drag: the terminal speed of a steady sheet in a forest;
//  - inflow hydrograph: injected volume = ∫Q dt, mass balance to round-off.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "geohaz/runout/solver.hpp"

using namespace geohaz;
using namespace geohaz::runout;

namespace {

constexpr double kG = 9.81;
constexpr double kDeg = std::numbers::pi / 180.0;

const int kSerial = [] {
  omp_set_num_threads(1);
  return 1;
}();

/// A grid of `cells` × `cells` square cells of edge dx with its south-west corner at (x0, y0).
GridGeometry square_grid(double x0, double y0, int cells, double dx) {
  return {cells, cells, x0, y0 + cells * dx, dx, dx};
}

/// A uniform sheet of bed-normal depth H on the plane `plane`, periodic over a box of lx × ly (map),
/// every particle with the map velocity v.
template <class Surface>
void fill_sheet(RunoutSolver<Surface>& s, double lx, double ly, double H, double cos_theta, const Vec2& v) {
  const RunoutParameters& p = s.parameters();
  const double d = p.d0 * std::sqrt(p.h0 / H);  // spacing on the bed for a normal depth H
  const int nx = static_cast<int>(std::lround(lx / cos_theta / d)), ny = static_cast<int>(std::lround(ly / d));
  RunoutStore& st = s.particles();
  st.append(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto k = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
      st.get<Position<2>>()[k] = Vec2((i + 0.5) * lx / nx, (j + 0.5) * ly / ny);
      st.get<Velocity<2>>()[k] = v;
      st.get<Volume>()[k] = p.nominal_volume() * (lx / nx / cos_theta) * (ly / ny) / (d * d);
      st.get<ParticleId>()[k] = static_cast<std::int64_t>(k);
    }
}

Periodicity<2> box(double lx, double ly) {
  Periodicity<2> per;
  per.axis = {true, true};
  per.lo = Vec2(0.0, 0.0);
  per.hi = Vec2(lx, ly);
  return per;
}

Vec2 total_momentum(const RunoutStore& st) {
  Vec2 m = Vec2::Zero();
  for (std::size_t i = 0; i < st.size(); ++i) m += st.get<Volume>()[i] * st.get<Velocity<2>>()[i];
  return m;
}

double total_volume(const RunoutStore& st) {
  double v = 0.0;
  for (double x : st.get<Volume>()) v += x;
  return v;
}

}  // namespace

// One particle sliding down a 30° plane (Coulomb tan δ = 0.2) through an erodible layer deep
// enough never to run out: V = V₀ exp(E_s s), s the path length along the bed (map path / cos θ).
TEST(Entrainment, GrowthLawFollowsExponentialOfPathLength) {
  const double th = 30.0 * kDeg, Es = 0.03;
  RunoutParameters p;
  p.d0 = 2.0;
  p.h0 = 0.5;
  p.duration = 8.0;
  p.stop_energy_fraction = 0.0;
  p.friction = CoulombFriction{0.2};
  p.entrainment = {EntrainmentLaw::GrowthRate, Es, 0.0, 0.0};
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(th), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p);
  SpatialProcesses proc;
  proc.grid = square_grid(-10.0, -500.0, 1000, 1.0);
  proc.erodible_depth.assign(proc.grid.cells(), 50.0);
  s.set_processes(proc);
  auto& st = s.particles();
  st.append(1);
  st.get<Position<2>>()[0] = Vec2(0.0, 0.0);
  st.get<Volume>()[0] = p.nominal_volume();
  s.initialise();
  while (!s.finished()) s.step();
  const double path = (st.get<Position<2>>()[0].x() - 0.0) / std::cos(th);
  const double expected = p.nominal_volume() * std::exp(Es * path);
  std::printf("growth law: path %.2f m, V/V0 %.4f, V/(V0 exp(Es s)) %.6f\n", path,
              st.get<Volume>()[0] / p.nominal_volume(), st.get<Volume>()[0] / expected);
  EXPECT_GT(Es * path, 1.5);  // a real growth (× 4.5 or more), not a first-order check
  EXPECT_NEAR(st.get<Volume>()[0] / expected, 1.0, 0.02) << "path " << path << " m";
  // The budget holds what was entrained.
  EXPECT_NEAR(s.budget().entrained, st.get<Volume>()[0] - p.nominal_volume(), 1e-9 * expected);
  EXPECT_NEAR(s.budget().balance_error(), 0.0, 1e-10 * expected);
}

// A sheet runs over a thin erodible strip with a large E_s: the strip is eroded down to its depth
// and no further, and the entrained volume is what left the bed.
TEST(Entrainment, ErosionStopsAtTheErodibleDepth) {
  const double th = 20.0 * kDeg, depth = 0.05;
  RunoutParameters p;
  p.d0 = 1.0;
  p.h0 = 1.0 / 16.0;
  p.duration = 6.0;
  p.stop_energy_fraction = 0.0;
  p.friction = CoulombFriction{0.1};
  p.entrainment = {EntrainmentLaw::GrowthRate, 0.5, 0.0, 0.0};
  const double lx = 12.0 * std::cos(th), ly = 4.0;
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(th), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p, box(lx, ly));
  SpatialProcesses proc;
  proc.grid = square_grid(0.0, 0.0, 16, 1.0);
  proc.erodible_depth.assign(proc.grid.cells(), 0.0);
  for (int r = 0; r < 16; ++r)
    for (int c = 4; c < 7; ++c) proc.erodible_depth[proc.grid.index(c, r)] = depth;  // x in [4, 7) m
  s.set_processes(proc);
  fill_sheet(s, lx, ly, 1.0, std::cos(th), Vec2(3.0, 0.0));
  s.initialise();
  const double v0 = total_volume(s.particles());
  while (!s.finished()) s.step();
  double eroded = 0.0, deepest = 0.0;
  int exhausted = 0;
  for (int r = 0; r < 16; ++r)
    for (int c = 0; c < 16; ++c) {
      const double e = s.eroded_depth()[proc.grid.index(c, r)];
      eroded += e;
      deepest = std::max(deepest, e);
      if (c < 4 || c >= 7 || r < 12) {  // rows 12–15 are y in [0, 4): under the sheet
        EXPECT_EQ(e, 0.0) << "cell " << c << ", " << r << " outside the strip";
      }
      if (e > depth * (1.0 - 1e-12)) ++exhausted;
    }
  EXPECT_LE(deepest, depth * (1.0 + 1e-12));
  EXPECT_EQ(exhausted, 12);  // the strip under the periodic sheet (3 × 4 cells) is eroded to its depth
  EXPECT_NEAR(s.budget().entrained, eroded * 1.0, 1e-12 * v0);
  EXPECT_NEAR(total_volume(s.particles()), v0 + s.budget().entrained, 1e-12 * v0);
}

// A uniform sheet moving at v₀ on a flat frictionless periodic bed entrains everywhere: no force
// acts, so Σ V v is conserved and every particle slows to v₀ V₀/V.
TEST(Entrainment, EntrainedMassJoinsAtRestConservingMomentum) {
  RunoutParameters p;
  p.d0 = 1.0;
  p.h0 = 1.0 / 16.0;
  p.duration = 3.0;
  p.stop_energy_fraction = 0.0;
  p.friction = CoulombFriction{0.0};
  p.entrainment = {EntrainmentLaw::GrowthRate, 0.05, 0.0, 0.0};
  InclinedPlane flat;
  RunoutSolver<InclinedPlane> s(flat, p, box(6.0, 6.0));
  SpatialProcesses proc;
  proc.grid = square_grid(0.0, 0.0, 6, 1.0);
  proc.erodible_depth.assign(proc.grid.cells(), 10.0);
  s.set_processes(proc);
  fill_sheet(s, 6.0, 6.0, 1.0, 1.0, Vec2(4.0, 0.0));
  s.initialise();
  const Vec2 m0 = total_momentum(s.particles());
  const double v0 = total_volume(s.particles());
  while (!s.finished()) s.step();
  const double grown = total_volume(s.particles()) / v0;
  EXPECT_GT(grown, 1.5);
  const Vec2 m = total_momentum(s.particles());
  std::printf("momentum: volume x %.4f, |ΔP|/P %.2e\n", grown, (m - m0).norm() / m0.norm());
  EXPECT_NEAR((m - m0).norm() / m0.norm(), 0.0, 0.01);
  EXPECT_NEAR(m.x() / total_volume(s.particles()), 4.0 / grown, 0.01 * 4.0 / grown);
}

namespace {

/// A steady uniform Voellmy sheet (μ, ξ) of bed-normal depth H on a plane at θ, periodic, started
/// at its steady speed U = √(ξ H (sin θ − μ cos θ)), with the shear-stress entrainment law; run for
/// `t` and return the mean erosion rate (m/s of bed depth) = entrained / (bed area × t).
double shear_erosion_rate(double tau_c, double k_e, double t, double* tau_b_expected) {
  const double th = 20.0 * kDeg, mu = 0.1, xi = 1000.0, H = 1.0, rho = 2000.0;
  RunoutParameters p;
  p.d0 = 1.0;
  p.h0 = H / 16.0;
  p.density = rho;
  p.duration = t;
  p.stop_energy_fraction = 0.0;
  p.friction = VoellmyFriction{mu, xi};
  p.entrainment = {EntrainmentLaw::ShearStress, 0.0, tau_c, k_e};
  const double lx = 8.0 * std::cos(th), ly = 4.0;
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(th), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p, box(lx, ly));
  SpatialProcesses proc;
  proc.grid = square_grid(0.0, 0.0, 8, 1.0);
  proc.erodible_depth.assign(proc.grid.cells(), 10.0);
  s.set_processes(proc);
  const double U = std::sqrt(xi * H * (std::sin(th) - mu * std::cos(th)));
  fill_sheet(s, lx, ly, H, std::cos(th), Vec2(U * std::cos(th), 0.0));
  s.initialise();
  while (!s.finished()) s.step();
  *tau_b_expected = rho * kG * H * std::sin(th);
  const double bed_area = lx * ly / std::cos(th);
  return s.budget().entrained / (bed_area * s.time());
}

}  // namespace

TEST(Entrainment, ShearLawRateOfSteadyUniformFlow) {
  double tau_b = 0.0;
  const double k_e = 1e-8;  // small: the flow stays steady while the rate is measured
  shear_erosion_rate(0.0, k_e, 0.1, &tau_b);
  const double tau_c = 0.25 * tau_b;
  const double rate = shear_erosion_rate(tau_c, k_e, 2.0, &tau_b);
  const double law = k_e * (tau_b - tau_c);
  std::printf("shear law: rate %.6e m/s, law %.6e m/s, ratio %.5f\n", rate, law, rate / law);
  EXPECT_NEAR(rate / law, 1.0, 0.02) << "rate " << rate << " m/s, law " << law << " m/s, τ_b " << tau_b << " Pa";
  // Below τ_c nothing is eroded.
  EXPECT_EQ(shear_erosion_rate(1.1 * tau_b, k_e, 2.0, &tau_b), 0.0);
}

// A particle slides on a flat bed at v₀ through a Coulomb zone μ₁ (x < L₁) into a zone μ₂ (global
// μ elsewhere): it stops at L₁ + (v₀² − 2 g μ₁ L₁)/(2 g μ₂).
TEST(FrictionZones, ParticleStopsWhereTheSecondZoneSays) {
  const double mu1 = 0.05, mu2 = 0.3, L1 = 40.0, v0 = 12.0;
  RunoutParameters p;
  p.d0 = 1.0;
  p.h0 = 0.5;
  p.duration = 60.0;
  p.dt_max = 0.01;
  p.stop_energy_fraction = 0.0;
  p.friction = CoulombFriction{0.9};  // the global value: not used inside the zones
  InclinedPlane flat;
  RunoutSolver<InclinedPlane> s(flat, p);
  SpatialProcesses proc;
  proc.grid = square_grid(-10.0, -50.0, 100, 1.0);
  auto& mu = proc.friction[kCoulombMu];
  mu.assign(proc.grid.cells(), 0.0);
  for (int r = 0; r < 100; ++r)
    for (int c = 0; c < 100; ++c) mu[proc.grid.index(c, r)] = (-10.0 + c < L1) ? mu1 : mu2;
  s.set_processes(proc);
  auto& st = s.particles();
  st.append(1);
  st.get<Position<2>>()[0] = Vec2(0.0, 0.0);
  st.get<Velocity<2>>()[0] = Vec2(v0, 0.0);
  st.get<Volume>()[0] = p.nominal_volume();
  s.initialise();
  while (!s.finished()) s.step();
  const double expected = L1 + (v0 * v0 - 2.0 * kG * mu1 * L1) / (2.0 * kG * mu2);
  std::printf("friction zones: stopped at %.3f m, analytic %.3f m\n", st.get<Position<2>>()[0].x(), expected);
  EXPECT_TRUE(s.all_stopped());
  EXPECT_NEAR(st.get<Position<2>>()[0].x(), expected, p.d0) << "expected " << expected << " m";
  // Without the zones the global μ = 0.9 would stop it within v₀²/(2 g 0.9) = 8.2 m.
  EXPECT_GT(st.get<Position<2>>()[0].x(), 3.0 * v0 * v0 / (2.0 * kG * 0.9));
}

// A periodic Voellmy sheet in a forest on a 30° plane, started 20 % below it, settles at the
// terminal speed where gravity
// balances basal friction plus the stems' drag: g (sin θ − μ cos θ) = (g/(ξ H) + k_f) U².
TEST(Forest, TerminalSpeedOfSteadySheet) {
  const double th = 30.0 * kDeg, mu = 0.2, xi = 2000.0, H = 1.0;
  const double n = 0.05, d = 0.3, cd = 1.0, kf = 0.5 * cd * n * d;  // 500 stems/ha of 30 cm
  RunoutParameters p;
  p.d0 = 1.0;
  p.h0 = H / 16.0;
  p.duration = 15.0;  // six relaxation times 1/(2 (g/(ξH) + k_f) U) = 2.5 s
  p.stop_energy_fraction = 0.0;
  p.friction = VoellmyFriction{mu, xi};
  const double lx = 6.0 * std::cos(th), ly = 4.0;
  const double U = std::sqrt(kG * (std::sin(th) - mu * std::cos(th)) / (kG / (xi * H) + kf));
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(th), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p, box(lx, ly));
  SpatialProcesses proc;
  proc.grid = square_grid(0.0, 0.0, 6, 1.0);
  proc.forest_drag.assign(proc.grid.cells(), kf);
  s.set_processes(proc);
  fill_sheet(s, lx, ly, H, std::cos(th), Vec2(0.8 * U * std::cos(th), 0.0));  // started 20 % slow
  s.initialise();
  while (!s.finished()) s.step();
  double speed = 0.0;
  for (double v : s.particles().get<Speed>()) speed += v;
  speed /= static_cast<double>(s.particles().size());
  std::printf("forest: mean speed %.4f m/s, terminal %.4f m/s, ratio %.5f\n", speed, U, speed / U);
  EXPECT_NEAR(speed / U, 1.0, 0.02) << "speed " << speed << " m/s, law " << U << " m/s";
  // Without the forest the sheet would go 1.6× faster: the drag is what holds it.
  EXPECT_LT(U, 0.7 * std::sqrt(xi * H * (std::sin(th) - mu * std::cos(th))));
}

// A triangular hydrograph (0 → 8 m³/s at 10 s → 0 at 35 s: 140 m³) enters across a 6 m line on a
// 25° plane: the injected volume is ∫Q dt and the budget closes to round-off throughout.
TEST(Hydrograph, InjectedVolumeIsTheIntegralOfDischarge) {
  const double th = 25.0 * kDeg;
  RunoutParameters p;
  p.d0 = 1.5;
  p.h0 = 0.4;
  p.duration = 40.0;
  p.stop_energy_fraction = 0.0;
  p.friction = CoulombFriction{0.2};
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(th), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p);
  SpatialProcesses proc;
  Hydrograph q;
  q.source = "test";
  q.a = Vec2(0.0, -3.0);
  q.b = Vec2(0.0, 3.0);
  q.direction = Vec2(1.0, 0.0);
  q.speed = 4.0;
  q.time = {0.0, 10.0, 35.0};
  q.discharge = {0.0, 8.0, 0.0};
  proc.inflows.push_back(q);
  s.set_processes(proc);
  s.initialise();
  EXPECT_FALSE(s.finished());  // nothing released yet, but the inflow is to come
  double worst = 0.0;
  bool checked_half = false;
  while (!s.finished()) {
    s.step();
    worst = std::max(worst, std::abs(s.budget().balance_error()));
    if (!checked_half && s.time() >= 10.0) {
      // By t the injected volume lags ∫₀ᵗ Q by less than one particle.
      const double due = q.volume_until(s.time());
      EXPECT_LE(s.budget().injected, due + 1e-9);
      EXPECT_GT(s.budget().injected, due - p.nominal_volume());
      checked_half = true;
    }
  }
  EXPECT_TRUE(checked_half);
  EXPECT_NEAR(q.volume(), 140.0, 1e-12);
  std::printf("hydrograph: injected %.10g m^3 of %.10g, worst balance %.2e m^3\n", s.budget().injected, q.volume(),
              worst);
  EXPECT_NEAR(s.budget().injected / q.volume(), 1.0, 0.005);
  EXPECT_NEAR(total_volume(s.particles()) + s.budget().lost, q.volume(), 1e-9 * q.volume());
  EXPECT_LT(worst, 1e-10 * q.volume());
  // Particles entered moving down the slope: all of them are below the line now.
  for (const Vec2& x : s.particles().get<Position<2>>()) EXPECT_GT(x.x(), 0.0);
}

// Entrainment, zones and forest on a sheet large enough for the parallel loops (≥ kParallelMin
// particles): 1 and 2 threads give bit-identical states (erosion is granted serially in store order).
TEST(Processes, OneAndTwoThreadsGiveIdenticalResults) {
  const auto run = [](int threads) {
    omp_set_num_threads(threads);
    const double th = 25.0 * kDeg;
    RunoutParameters p;
    p.d0 = 1.0;
    p.h0 = 1.0 / 64.0;
    p.duration = 0.5;
    p.stop_energy_fraction = 0.0;
    p.friction = VoellmyFriction{0.2, 1000.0};
    p.entrainment = {EntrainmentLaw::ShearStress, 0.0, 500.0, 1e-6};
    const double lx = 6.0 * std::cos(th), ly = 6.0;
    InclinedPlane plane;
    plane.slope = Vec2(-std::tan(th), 0.0);
    RunoutSolver<InclinedPlane> s(plane, p, box(lx, ly));
    SpatialProcesses proc;
    proc.grid = square_grid(0.0, 0.0, 6, 1.0);
    proc.erodible_depth.assign(proc.grid.cells(), 0.02);
    proc.forest_drag.assign(proc.grid.cells(), 0.0);
    proc.friction[kCoulombMu].assign(proc.grid.cells(), std::numeric_limits<double>::quiet_NaN());
    for (int r = 0; r < 6; ++r) {
      proc.forest_drag[proc.grid.index(2, r)] = 0.02;
      proc.friction[kCoulombMu][proc.grid.index(4, r)] = 0.35;
    }
    s.set_processes(proc);
    fill_sheet(s, lx, ly, 1.0, std::cos(th), Vec2(2.0, 0.5));
    EXPECT_GE(s.particles().size(), static_cast<std::size_t>(kParallelMin));
    s.initialise();
    while (!s.finished()) s.step();
    omp_set_num_threads(1);
    return std::make_pair(s.particles(), s.budget().entrained);
  };
  const auto [a, ea] = run(1);
  const auto [b, eb] = run(2);
  EXPECT_GT(ea, 0.0);
  EXPECT_EQ(ea, eb);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.get<Position<2>>()[i], b.get<Position<2>>()[i]) << i;
    ASSERT_EQ(a.get<Volume>()[i], b.get<Volume>()[i]) << i;
  }
}
