// Regression tests of the dam break against the parts of Ritter's solution (1892) that the
// particle model resolves (docs/validation/runout.md, "The dam break"). Flat frictionless bed,
// reservoir depth H for x < 0, c = √(g H); for −c t < x < 2c t
//     u = (2/3)(x/t + c),   h = (2c − x/t)²/(9g),   i.e. √(g h) = (2c − x/t)/3,
// so the depth at the dam section is 4H/9 (flow critical there, u = √(g h) = 2c/3) and the
// rarefaction head travels back into the reservoir at −c.
//
// Run: H = 1 m, h0 = H/16, d0 = 1 m, t = 5 s (c t/d0 = 16), a 50 m reservoir (the rarefaction
// from its far end does not reach the fan by then), a square lattice 4 m wide, periodic across.
// The wet front is not asserted here: it lags Ritter's 2c t because the lecture's force vanishes
// beyond 2 d0 (measured and explained in docs/validation/runout.md; the bound is in test_flows).
//
// Tolerances: the errors measured at this resolution are, for this square packing and for a
// hexagonal one of the same density, 6.1 % / 4.8 % on the dam depth, 6.2 % / 4.4 % on the dam
// velocity, 1.3 % / 0.6 % on the rarefaction head, 0.7 % / 3.1 % on the fan slope and
// 8.4 % / 5.8 % on the 2 m bins of the interior profile. They are discretisation errors of the
// depth resolution (at h0 = H/36: 4.6 %, 4.3 %, 0.4 %, 3.0 %, 5.1 %; at h0 = H/4 the interior is
// not Ritter's: slope 0.61, bins off by 49 %). The tolerances are about 1.5 × the larger error,
// because the particle-scale noise depends on round-off (another compiler or -march gives another
// realisation of it).
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "geohaz/runout/solver.hpp"
#include "line_fit.hpp"

using namespace geohaz;
using namespace geohaz::runout;

namespace {

constexpr double kG = 9.81, kH = 1.0, kT = 5.0;

struct DamBreakState {
  std::vector<Vec2> x, v;
  std::vector<double> h;
  double t = 0.0;
};

// The flow at t = 5 s, computed once for all the tests of this file (about 2 s on one thread).
const DamBreakState& dam_break() {
  static const DamBreakState state = [] {
    omp_set_num_threads(1);
    RunoutParameters p;
    p.d0 = 1.0;
    p.h0 = kH / 16.0;
    p.duration = kT;
    p.cfl = 0.25;
    p.friction = CoulombFriction{0.0};
    // Ritter's solution is of the inviscid system: no artificial viscosity (as AvaFrame's own
    // dam-break test, viscOption = 0); its effect and convergence: test_terrain.cpp.
    p.lateral_mixing = 0.0;
    const double d = p.d0 * std::sqrt(p.h0 / kH);  // lattice spacing of depth H
    const int nx = static_cast<int>(std::lround(50.0 / d)), ny = static_cast<int>(std::lround(4.0 / d));
    Periodicity<2> across;
    across.axis = {false, true};
    across.lo = Vec2(-1e3, 0.0);
    across.hi = Vec2(1e3, ny * d);
    RunoutSolver<InclinedPlane> s(InclinedPlane{}, p, across);
    auto& st = s.particles();
    st.append(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const auto k = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
        st.get<Position<2>>()[k] = Vec2(-nx * d + (i + 0.5) * d, (j + 0.5) * d);
        st.get<Volume>()[k] = p.nominal_volume();
        st.get<ParticleId>()[k] = static_cast<std::int64_t>(k);
      }
    s.initialise();
    while (!s.finished()) s.step();
    return DamBreakState{st.get<Position<2>>(), st.get<Velocity<2>>(), st.get<FlowDepth>(), s.time()};
  }();
  return state;
}

double ritter_depth(double x, double t) {
  const double c = std::sqrt(kG * kH), xi = x / t;
  if (xi <= -c) return kH;
  if (xi >= 2.0 * c) return 0.0;
  return (2.0 * c - xi) * (2.0 * c - xi) / (9.0 * kG);
}

// Mean depth and velocity of the particles with |x − xc| < half.
struct Bin {
  double h = 0.0, u = 0.0;
  int n = 0;
};
Bin bin(const DamBreakState& s, double xc, double half) {
  Bin b;
  for (std::size_t i = 0; i < s.x.size(); ++i)
    if (std::abs(s.x[i].x() - xc) < half) {
      b.h += s.h[i];
      b.u += s.v[i].x();
      ++b.n;
    }
  if (b.n > 0) {
    b.h /= b.n;
    b.u /= b.n;
  }
  return b;
}

}  // namespace

TEST(DamBreakRitter, DepthAndVelocityAtTheDamSection) {
  // Mean over |x| < 2 m (the kernel support): Ritter's depth varies by 0.01 % over it.
  const auto& s = dam_break();
  const double c = std::sqrt(kG * kH);
  const Bin b = bin(s, 0.0, 2.0);
  ASSERT_GT(b.n, 100);
  std::printf("dam section: h = %.4f m (4H/9 = %.4f), u = %.4f m/s (2c/3 = %.4f), Froude %.3f\n", b.h, 4.0 * kH / 9.0,
              b.u, 2.0 * c / 3.0, b.u / std::sqrt(kG * b.h));
  EXPECT_NEAR(b.h / (4.0 * kH / 9.0), 1.0, 0.10);
  EXPECT_NEAR(b.u / (2.0 * c / 3.0), 1.0, 0.10);
}

TEST(DamBreakRitter, RarefactionTravelsBackAtSqrtGH) {
  // In the fan √(g h) is linear in x: fit it by least squares over −0.7 c t < x < 0.4 c t (clear
  // of the kernel-rounded head and of the tip) and extrapolate to √(g H): the head, at −c t. The
  // slope, −1/(3t), checks the whole fan.
  const auto& s = dam_break();
  const double c = std::sqrt(kG * kH), t = s.t;
  geohaz::testing::LineFit fan;
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    const double x = s.x[i].x();
    if (x > -0.7 * c * t && x < 0.4 * c * t) fan.add(x, std::sqrt(kG * s.h[i]));
  }
  ASSERT_GT(fan.count(), 300u);
  const double slope = fan.slope(), head = fan.x_at(c);
  std::printf("fan: head at %.3f m = %.4f (-c t), slope %.5f 1/s = %.4f (-1/(3t))\n", head, head / (-c * t), slope,
              slope / (-1.0 / (3.0 * t)));
  EXPECT_NEAR(head / (-c * t), 1.0, 0.05);
  EXPECT_NEAR(slope / (-1.0 / (3.0 * t)), 1.0, 0.05);
}

TEST(DamBreakRitter, InteriorDepthProfile) {
  // 2 m bins from behind the head to before the tip (−0.8 c t < x < 0.45 c t): each within 13 %
  // of Ritter's depth (the tip beyond, thicker than Ritter's because the front lags, is excluded).
  const auto& s = dam_break();
  const double c = std::sqrt(kG * kH), t = s.t;
  double worst = 0.0, at = 0.0;
  int bins = 0;
  for (double xc = -0.8 * c * t + 1.0; xc < 0.45 * c * t; xc += 2.0) {
    const Bin b = bin(s, xc, 1.0);
    ASSERT_GT(b.n, 10) << "x = " << xc;
    const double e = std::abs(b.h / ritter_depth(xc, t) - 1.0);
    if (e > worst) worst = e, at = xc;
    ++bins;
  }
  std::printf("interior profile: %d bins, largest relative depth error %.3f at x = %.1f m\n", bins, worst, at);
  EXPECT_LT(worst, 0.13);
}
