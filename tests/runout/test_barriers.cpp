// Regression tests of the barriers of docs/runout.md, "Barriers":
//  - one particle hitting a wall: the reflected velocity (restitution, wall friction) and the
//    impulse the wall takes;
//  - a layer at rest between two walls presses ½ ρ g h² per metre on each (hydrostatic);
//  - a fast sheet against a wall: force per metre against ρ h v² + ½ ρ g h² and against the exact
//    reflected-bore force;
//  - retention: a barrier whose storage exceeds the flow volume holds it all; a lower one holds its
//    storage and passes the rest; retained + passed = released;
//  - an open barrier passes its fraction of the volume;
//  - 1 and 2 threads give identical tallies and positions.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "geohaz/core/kernels.hpp"
#include "geohaz/runout/solver.hpp"

using namespace geohaz;
using namespace geohaz::runout;

namespace {

constexpr double kG = 9.81;
constexpr double kRho = 1800.0;

const int kSerial = [] {
  omp_set_num_threads(1);
  return 1;
}();

/// A straight barrier from a to b; the upstream side is the left of a → b.
Barrier wall(Vec2 a, Vec2 b, double height, double permeability = 0.0, bool upstream_left = true) {
  Barrier w;
  w.name = "wall";
  w.vertices = {a, b};
  w.height = height;
  w.permeability = permeability;
  w.upstream_left = upstream_left;
  return w;
}

/// A block of bed-normal depth H on a flat bed over [x0, x1] × [0, ly] (periodic in y), at map
/// velocity v, on a square lattice of spacing d0 √(h0/H).
void fill_block(RunoutSolver<InclinedPlane>& s, double x0, double x1, double ly, double H, const Vec2& v) {
  const RunoutParameters& p = s.parameters();
  const double d = p.d0 * std::sqrt(p.h0 / H);
  const int nx = static_cast<int>(std::lround((x1 - x0) / d)), ny = static_cast<int>(std::lround(ly / d));
  RunoutStore& st = s.particles();
  const std::size_t first = st.size();
  st.append(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  const double dx = (x1 - x0) / nx, dy = ly / ny;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto k = first + static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
      st.get<Position<2>>()[k] = Vec2(x0 + (i + 0.5) * dx, (j + 0.5) * dy);
      st.get<Velocity<2>>()[k] = v;
      st.get<Volume>()[k] = H * dx * dy;
      st.get<ParticleId>()[k] = static_cast<std::int64_t>(k);
    }
}

Periodicity<2> periodic_y(double ly) {
  Periodicity<2> per;
  per.axis = {false, true};
  per.lo = Vec2(0.0, 0.0);
  per.hi = Vec2(0.0, ly);
  return per;
}

double total_volume(const RunoutStore& st) {
  double v = 0.0;
  for (double x : st.get<Volume>()) v += x;
  return v;
}

}  // namespace

// F(s), the part of the kernel on the particle's side of a wall: ½ on it, 1 beyond 2 d0, and at
// s = 1 the value of an independent 2D quadrature of the cubic spline over the half plane.
TEST(Barriers, KernelFractionOfAHalfPlane) {
  EXPECT_DOUBLE_EQ(BarrierSet::kernel_fraction(0.0), 0.5);
  EXPECT_DOUBLE_EQ(BarrierSet::kernel_fraction(2.0), 1.0);
  double prev = 0.5;
  for (double s = 0.05; s < 2.0; s += 0.05) {
    EXPECT_GT(BarrierSet::kernel_fraction(s), prev);
    prev = BarrierSet::kernel_fraction(s);
  }
  // ∫∫_{x > −1} W dx dy on a 1000 × 1000 grid over the support (h = 1).
  const int n = 1000;
  const double step = 4.0 / n;
  double inside = 0.0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double x = -2.0 + (a + 0.5) * step, y = -2.0 + (b + 0.5) * step;
      if (x > -1.0) inside += CubicSpline<2>::value(std::hypot(x, y), 1.0) * step * step;
    }
  EXPECT_NEAR(BarrierSet::kernel_fraction(1.0), inside, 2e-3);
}

// One particle at 10 m/s hitting a wall at 30° from its normal, frictionless flat bed: the normal
// velocity is reversed times e, the tangential one reduced by μ_w (1 + e) v_n, and the wall takes
// ρ V (1 + e) v_n. The particle is 10⁻⁶ V0, so that the mirror push ∝ its depth is negligible.
TEST(Barriers, SingleParticleReflectsWithRestitutionAndWallFriction) {
  RunoutParameters p;
  p.d0 = 1.0;
  p.h0 = 0.5;
  p.density = kRho;
  p.duration = 0.5;
  p.stop_energy_fraction = 0.0;
  p.lateral_mixing = 0.0;
  p.friction = CoulombFriction{0.0};
  p.dt_max = 0.01;
  const double e = 0.5, mu_w = 0.2, speed = 10.0, ang = 30.0 * std::numbers::pi / 180.0;
  RunoutSolver<InclinedPlane> s(InclinedPlane{}, p);
  s.set_barriers(BarrierSet({wall(Vec2(1.0, -50.0), Vec2(1.0, 50.0), 5.0, 0.0, false)}, {e, mu_w, 100.0}, p.d0));
  auto& st = s.particles();
  st.append(1);
  st.get<Velocity<2>>()[0] = speed * Vec2(std::cos(ang), std::sin(ang));
  st.get<Volume>()[0] = 1e-6 * p.nominal_volume();
  s.initialise();
  while (!s.finished()) s.step();
  const Vec2 v = st.get<Velocity<2>>()[0];
  const double vn = speed * std::cos(ang), vt = speed * std::sin(ang);
  std::printf("reflection: v = (%.6f, %.6f) m/s, expected (%.6f, %.6f); impulse %.4f N s\n", v.x(), v.y(), -e * vn,
              vt - mu_w * (1.0 + e) * vn, s.barrier_tally().impulse[0]);
  EXPECT_NEAR(v.x(), -e * vn, 1e-6);
  EXPECT_NEAR(v.y(), vt - mu_w * (1.0 + e) * vn, 1e-6);
  EXPECT_LT(st.get<Position<2>>()[0].x(), 1.0);
  const double impulse = kRho * 1e-6 * p.nominal_volume() * (1.0 + e) * vn;
  EXPECT_NEAR(s.barrier_tally().impulse[0], impulse, 1e-6 * impulse);
  EXPECT_EQ(s.barrier_tally().passed[0], 0.0);
}

// A layer of depth h = 1 m at rest between walls 8 m apart (flat frictionless bed, periodic
// across): each wall takes ½ ρ g h² per metre, from the head-pressure push of the particles held
// against it and the mirror-layer push (no formula for the force in the model). Mean over the
// last 4 s of 12.
TEST(Barriers, LayerAtRestPressesHydrostaticLoadOnTheWalls) {
  const double h = 1.0, L = 8.0, W = 3.0;
  RunoutParameters p;
  p.d0 = 0.5;
  p.h0 = h / 16.0;
  p.density = kRho;
  p.duration = 12.0;
  p.stop_energy_fraction = 0.0;
  p.friction = VoellmyFriction{0.0, 200.0};
  RunoutSolver<InclinedPlane> s(InclinedPlane{}, p, periodic_y(W));
  s.set_barriers(BarrierSet({wall(Vec2(0.0, -2.0), Vec2(0.0, W + 2.0), 50.0, 0.0, false),
                             wall(Vec2(L, -2.0), Vec2(L, W + 2.0), 50.0, 0.0, true)},
                            {}, p.d0));
  fill_block(s, 0.0, L, W, h, Vec2::Zero());
  s.initialise();
  const double volume = total_volume(s.particles());
  std::vector<double> i15;
  while (!s.finished()) {
    s.step();
    if (i15.empty() && s.time() >= 8.0) i15 = s.barrier_tally().impulse;
  }
  const double span = s.time() - 8.0;
  const double h_mean = volume / (L * W);
  const double expected = 0.5 * kRho * kG * h_mean * h_mean;
  for (int b = 0; b < 2; ++b) {
    const double f = (s.barrier_tally().impulse[b] - i15[b]) / span / W;
    std::printf("hydrostatic: wall %d %.1f N/m, 1/2 rho g h^2 = %.1f N/m, ratio %.4f\n", b, f, expected, f / expected);
    EXPECT_NEAR(f / expected, 1.0, 0.05);
  }
  EXPECT_EQ(s.barrier_tally().passed[0] + s.barrier_tally().passed[1], 0.0);
}

namespace {

/// The reflected bore of a stream (h, v) against a wall: depth h_b at rest behind it from mass
/// h v = (h_b − h) c and momentum ½ g (h_b² − h²) = h v² + h v c (c: bore speed upstream).
double bore_depth(double h, double v) {
  double lo = h, hi = 100.0 * h;
  for (int it = 0; it < 200; ++it) {
    const double hb = 0.5 * (lo + hi);
    const double c = h * v / (hb - h);
    (0.5 * kG * (hb * hb - h * h) < h * v * v + h * v * c ? lo : hi) = hb;
  }
  return 0.5 * (lo + hi);
}

struct SheetRun {
  double force_per_m = 0.0;
  std::vector<double> impulse;
  std::vector<Vec2> x;
};

/// A sheet h = 1 m at Froude number 6 running into a wall on a frictionless flat bed; the mean force
/// per metre from t0 to t1. The lateral mixing is off: its relaxation towards a Shepard-weighted
/// mean velocity does not conserve momentum where the velocity jumps (at the bore it discards about
/// half of the momentum flux before it reaches the wall); the momentum-conserving XSPH smoothing
/// (ε = 0.1) dissipates the bore's energy instead (without any, the stopped particles keep it as
/// random motion and press 1.3 × the bore force on the wall).
SheetRun sheet_against_wall(double t0, double t1, int threads) {
  omp_set_num_threads(threads);
  const double h = 1.0, W = 2.0, v = 6.0 * std::sqrt(kG * h);
  RunoutParameters p;
  p.d0 = 0.5;
  p.h0 = h / 8.0;
  p.density = kRho;
  p.duration = t1;
  p.stop_energy_fraction = 0.0;
  p.friction = CoulombFriction{0.0};
  p.lateral_mixing = 0.0;
  p.smoothing = 0.1;
  RunoutSolver<InclinedPlane> s(InclinedPlane{}, p, periodic_y(W));
  s.set_barriers(BarrierSet({wall(Vec2(1.0, -2.0), Vec2(1.0, W + 2.0), 50.0, 0.0, false)}, {}, p.d0));
  fill_block(s, -36.0, 0.0, W, h, Vec2(v, 0.0));  // 2304 particles: enough for 2 threads
  s.initialise();
  double i0 = 0.0, ta = 0.0;
  while (!s.finished()) {
    s.step();
    if (ta == 0.0 && s.time() >= t0) {
      ta = s.time();
      i0 = s.barrier_tally().impulse[0];
    }
  }
  omp_set_num_threads(1);
  SheetRun r;
  r.force_per_m = (s.barrier_tally().impulse[0] - i0) / (s.time() - ta) / W;
  r.impulse = s.barrier_tally().impulse;
  const auto& x = s.particles().get<Position<2>>();
  r.x.assign(x.begin(), x.end());
  return r;
}

}  // namespace

// Force per metre of a sheet (h = 1 m, v = 18.8 m/s, Fr = 6) against a wall, mean over 0.4–1.2 s
// (after the first impact, before the rarefaction from the sheet's tail arrives): within 15 % of
// α ρ h v² + k ½ ρ g h² with α = 1 (the momentum flux stopped completely, e = 0) and k = 1
// (hydrostatic load of the arriving depth). The exact shallow-water force of the reflected bore,
// ½ ρ g h_b² = ρ h v² + ½ ρ g h² + ρ h v c, is 11.5 % above that formula at Fr = 6; the model is
// checked against it too (10 %: the force fluctuates by ±6 % over 0.2 s windows as the pile settles).
// The sheet's tail (36 m behind the front) sends its rarefaction to the wall after ≈ 1.6 s.
TEST(Barriers, SheetAgainstWallGivesMomentumFluxPlusHydrostaticLoad) {
  const double h = 1.0, v = 6.0 * std::sqrt(kG * h);
  const SheetRun r = sheet_against_wall(0.4, 1.2, 1);
  const double formula = kRho * h * v * v + 0.5 * kRho * kG * h * h;
  const double hb = bore_depth(h, v);
  const double bore = 0.5 * kRho * kG * hb * hb;
  std::printf(
      "sheet impact: %.0f N/m; rho h v^2 + 1/2 rho g h^2 = %.0f (ratio %.3f); bore h_b = %.3f m, "
      "1/2 rho g h_b^2 = %.0f (ratio %.3f)\n",
      r.force_per_m, formula, r.force_per_m / formula, hb, bore, r.force_per_m / bore);
  EXPECT_NEAR(r.force_per_m / formula, 1.0, 0.15);
  EXPECT_NEAR(r.force_per_m / bore, 1.0, 0.10);
}

// The same impact on 1 and 2 threads: the tally is added in store order, so identical.
TEST(Barriers, OneAndTwoThreadsGiveIdenticalResults) {
  const SheetRun a = sheet_against_wall(0.1, 0.3, 1), b = sheet_against_wall(0.1, 0.3, 2);
  ASSERT_EQ(a.x.size(), b.x.size());
  EXPECT_GT(a.impulse[0], 0.0);
  EXPECT_EQ(a.impulse[0], b.impulse[0]);
  for (std::size_t i = 0; i < a.x.size(); ++i) ASSERT_EQ(a.x[i], b.x[i]) << "particle " << i;
}

namespace {

struct Retention {
  double released = 0.0, retained = 0.0, passed = 0.0, storage = 0.0, arrived = 0.0;
};

/// A channel (flat bed, 3 m wide, periodic across) closed upstream at x = 0; a barrier of crest
/// height H at x = 10 m; released at rest: a block of depth `depth` over x ∈ [0, length];
/// Voellmy μ = 0 (no yield, so the pool behind the barrier levels out), ξ = 100 m/s². After 20 s:
/// the volume upstream of the barrier, the volume that crossed it, and the volume of the particles
/// that came within d0 of it.
Retention retention(double H, double depth, double length, double permeability = 0.0, double xi = 100.0,
                    double duration = 20.0) {
  const double W = 3.0, Lr = 10.0;
  RunoutParameters p;
  p.d0 = 0.5;
  p.h0 = 1.0 / 16.0;
  p.density = kRho;
  p.duration = duration;
  p.stop_energy_fraction = 0.0;
  p.friction = VoellmyFriction{0.0, xi};
  RunoutSolver<InclinedPlane> s(InclinedPlane{}, p, periodic_y(W));
  s.set_barriers(BarrierSet({wall(Vec2(0.0, -2.0), Vec2(0.0, W + 2.0), 50.0, 0.0, false),
                             wall(Vec2(Lr, -2.0), Vec2(Lr, W + 2.0), H, permeability, true)},
                            {}, p.d0));
  fill_block(s, 0.0, length, W, depth, Vec2::Zero());
  s.initialise();
  Retention r;
  r.released = total_volume(s.particles());
  r.storage = H * Lr * W;
  std::vector<std::uint8_t> arrived(s.particles().size(), 0);
  const auto& x = s.particles().get<Position<2>>();
  const auto& id = s.particles().get<ParticleId>();
  const auto& vol = s.particles().get<Volume>();
  while (!s.finished()) {
    s.step();
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x[i].x() > Lr - p.d0) arrived[static_cast<std::size_t>(id[i])] = 1;
  }
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (x[i].x() < Lr) r.retained += vol[i];
    if (arrived[static_cast<std::size_t>(id[i])]) r.arrived += vol[i];
  }
  r.passed = s.barrier_tally().passed[1];
  EXPECT_EQ(s.barrier_tally().passed[0], 0.0);  // the closed end holds
  return r;
}

}  // namespace

// Storage 60 m³ behind a 2 m barrier; 22.5 m³ released as a 1.5 m deep block 5 m long that
// collapses and surges against it: nothing passes.
TEST(Barriers, BarrierWithStorageAboveTheVolumeRetainsAll) {
  const Retention r = retention(2.0, 1.5, 5.0);
  std::printf("high barrier: released %.4f, retained %.4f, passed %.4f m3\n", r.released, r.retained, r.passed);
  EXPECT_EQ(r.passed, 0.0);
  EXPECT_NEAR(r.retained, r.released, 1e-12 * r.released);
}

// Storage 15 m³ behind a 0.5 m barrier; 22.5 m³ released as a pool 0.75 m deep filling the
// reach (ξ = 20 m/s² damps the seiche): the part above the crest spills over it, the pool keeps its
// storage and retained + passed = released to round-off. The pool ends 11 % low (0.89 of the
// storage; 0.93 with ξ = 5, 0.78 with ξ = 100): a particle passes whenever its own depth at the
// wall exceeds the crest, so the particle-scale noise of h_w (a few %) and the seiche draw the
// pool below the crest. Tolerance: 15 % below, 2 % above.
TEST(Barriers, LowBarrierRetainsItsStorageAndPassesTheRest) {
  const Retention r = retention(0.5, 0.75, 10.0, 0.0, 20.0);
  std::printf("low barrier: released %.4f, storage %.4f, retained %.4f (%.3f of storage), passed %.4f m3\n", r.released,
              r.storage, r.retained, r.retained / r.storage, r.passed);
  EXPECT_GT(r.retained / r.storage, 0.85);
  EXPECT_LT(r.retained / r.storage, 1.02);
  EXPECT_GT(r.passed, 0.0);
  EXPECT_NEAR(r.retained + r.passed, r.released, 1e-12 * r.released);
}

// An open barrier (p = 0.3) far higher than the flow, hit by the collapsing block: the volume
// passed is p × the volume that arrived within the sampling of whole particles: binomial
// σ = √(p(1 − p)/N) for N arriving particles; tolerance 3 σ. "Arrived" is not sharp: a passing
// particle ignores the wall, the held ones stay in front of it, and whether a passing particle
// behind them reaches the line depends on the pile; counted within d0 of the line the ratio is
// 0.35 (165 particles), within 2 d0 0.22 (264).
TEST(Barriers, OpenBarrierPassesItsFraction) {
  const double perm = 0.3;
  const Retention r = retention(20.0, 1.5, 5.0, perm);
  const double n_arrived = r.arrived / (22.5 / 1440.0);
  std::printf("open barrier: passed %.4f of %.4f m3 arrived (%.0f particles) = %.4f (p = %.2f)\n", r.passed, r.arrived,
              n_arrived, r.passed / r.arrived, perm);
  ASSERT_GT(n_arrived, 100.0);
  EXPECT_NEAR(r.passed / r.arrived, perm, 3.0 * std::sqrt(perm * (1.0 - perm) / n_arrived));
  EXPECT_NEAR(r.retained + r.passed, r.released, 1e-12 * r.released);
}
