// Regression tests of the slope-consistent thin-layer physics (docs/runout.md, "Equations as
// implemented"; docs/validation/runout.md, "Steep and curved terrain"):
//  - dam break on planes at 0°, 30° and 45° with Coulomb friction against the analytic solution
//    of the thin-layer system on an incline (Mangeney et al. 2000): in the frame accelerating at
//    m = g (sin θ − cos θ tan δ) down the slope, the Ritter fan with c₀ = √(g cos θ h₀);
//  - a particle in a cylindrical trough with Coulomb friction: the bed constraint and the
//    curvature term of the normal stress against the exact motion on a vertical circle;
//  - the kinetic-energy stop criterion.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

#include "geohaz/runout/solver.hpp"
#include "line_fit.hpp"

using namespace geohaz;
using namespace geohaz::runout;

namespace {

constexpr double kG = 9.81;
constexpr double kDeg = std::numbers::pi / 180.0;

const int kSerial = [] {
  omp_set_num_threads(1);
  return 1;
}();

/// Fan edges of a dam break on an incline, in the accelerating frame, relative to c₀ t.
struct FanEdges {
  double back = 0.0;   ///< (s_back − ½ m t²)/(−c₀ t): 1 for the analytic solution
  double front = 0.0;  ///< (s_front − ½ m t²)/(2 c₀ t): 1 for the analytic solution
};

/// Reservoir of bed-normal depth H = 1 m, 40 m long up the slope from the dam at s = 0, on a plane
/// inclined at θ (falling towards +x), Coulomb friction tan δ, periodic across (4 m); run to t.
/// In the fan √(g cos θ h_n) = (2 c₀ t − s′)/(3 t), s′ = s − ½ m t²: a straight line in s′, fitted
/// by least squares over −0.7 c₀t < s′ < 0.4 c₀t (clear of the kernel-rounded head and the thin
/// tip). The back edge is where the line reaches c₀, the front edge where it reaches 0.
FanEdges dam_break_on_incline(double theta_deg, double tan_delta, double t_end, double mixing = 0.0, double d0 = 1.0) {
  const double th = theta_deg * kDeg, H = 1.0, reservoir = 40.0;  // > 2 c₀ t: the far end stays out
  RunoutParameters p;
  p.d0 = d0;
  p.h0 = H / 16.0;
  p.duration = t_end;
  p.cfl = 0.25;
  p.stop_energy_fraction = 0.0;
  p.friction = CoulombFriction{tan_delta};
  p.lateral_mixing = mixing;
  const double d = p.d0 * std::sqrt(p.h0 / H);  // lattice spacing on the bed for a normal depth H
  const int nx = static_cast<int>(std::lround(reservoir / d)), ny = static_cast<int>(std::lround(4.0 / d));
  Periodicity<2> across;
  across.axis = {false, true};
  across.lo = Vec2(-1e4, 0.0);
  across.hi = Vec2(1e4, ny * d);
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(th), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p, across);
  auto& st = s.particles();
  st.append(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto k = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
      const double along = -nx * d + (i + 0.5) * d;  // bed coordinate s (m)
      st.get<Position<2>>()[k] = Vec2(along * std::cos(th), (j + 0.5) * d);
      st.get<Volume>()[k] = p.nominal_volume();
      st.get<ParticleId>()[k] = static_cast<std::int64_t>(k);
    }
  s.initialise();
  while (!s.finished()) s.step();
  const double t = s.time();
  const double c0 = std::sqrt(kG * std::cos(th) * H);
  const double m = kG * (std::sin(th) - std::cos(th) * tan_delta);
  const double shift = 0.5 * m * t * t;
  geohaz::testing::LineFit fan;
  const auto& x = st.get<Position<2>>();
  const auto& h = st.get<FlowDepth>();
  for (std::size_t i = 0; i < st.size(); ++i) {
    const double sp = x[i].x() / std::cos(th) - shift;
    // √(g cos θ h_n); h is bed-normal.
    if (sp > -0.7 * c0 * t && sp < 0.4 * c0 * t) fan.add(sp, std::sqrt(kG * std::cos(th) * h[i]));
  }
  EXPECT_GT(fan.count(), 300u);
  FanEdges e;
  e.back = fan.x_at(c0) / (-c0 * t);
  e.front = fan.x_at(0.0) / (2.0 * c0 * t);
  std::printf(
      "dam break at %.0f°, tan δ = %.2f, C_mix = %g, d0 = %g m, t = %.2f s: back edge %.4f, front edge %.4f of the "
      "analytic\n",
      theta_deg, tan_delta, mixing, d0, t, e.back, e.front);
  return e;
}

}  // namespace

// The analytic solution is of the inviscid system, so these runs have no lateral mixing (as
// AvaFrame's own dam-break test, viscOption = 0); MixingDragAtTheFrontConvergesWithD0 checks what
// the mixing does. Tolerance 5 %; measured at h₀ = H/16, d₀ = 1 m: 0° back 1.3 %, front 1.7 %;
// 30° 1.5 %, 4.1 %; 45° 2.2 %, 4.7 % (the front error grows with the slope because the tip of the
// fan is thinner: the depth resolution h₀ is the same while c₀ t shrinks as √cos θ).
TEST(DamBreakOnIncline, FlatBedFollowsRitter) {
  const FanEdges e = dam_break_on_incline(0.0, 0.0, 5.0);
  EXPECT_NEAR(e.back, 1.0, 0.05);
  EXPECT_NEAR(e.front, 1.0, 0.05);
}

TEST(DamBreakOnIncline, ThirtyDegreesTravelsAtSqrtGCosThetaH) {
  const FanEdges e = dam_break_on_incline(30.0, 0.3, 5.0);
  EXPECT_NEAR(e.back, 1.0, 0.05);
  EXPECT_NEAR(e.front, 1.0, 0.05);
}

TEST(DamBreakOnIncline, FortyFiveDegreesTravelsAtSqrtGCosThetaH) {
  const FanEdges e = dam_break_on_incline(45.0, 0.5, 5.0);
  EXPECT_NEAR(e.back, 1.0, 0.05);
  EXPECT_NEAR(e.front, 1.0, 0.05);
}

TEST(DamBreakOnIncline, MixingDragAtTheFrontConvergesWithD0) {
  // The lateral mixing relaxes each particle towards the kernel mean of its neighbours' velocities;
  // at the thin tip of the fan the mean lags (it reaches back into slower flow), so the mixing
  // holds the tip back: an O(d₀) drag that must vanish as d₀ shrinks (h₀/H fixed). Measured:
  // front edge +13.1 % at d₀ = 1 m, +5.1 % at 0.5 m (without mixing +1.7 %, +0.8 %).
  const FanEdges coarse = dam_break_on_incline(0.0, 0.0, 5.0, RunoutParameters{}.lateral_mixing, 1.0);
  const FanEdges fine = dam_break_on_incline(0.0, 0.0, 5.0, RunoutParameters{}.lateral_mixing, 0.5);
  EXPECT_LT(std::abs(fine.front - 1.0), 0.6 * std::abs(coarse.front - 1.0));
  EXPECT_NEAR(fine.front, 1.0, 0.07);
  EXPECT_NEAR(fine.back, 1.0, 0.05);
}

namespace {

/// First turning point (angle from the bottom, degrees, negative on the far side) of a point mass
/// released at rest at φ₀ on a vertical circle of radius R with Coulomb friction μ, the normal
/// force including the centripetal term: along the path E = S² obeys
///     dE/dφ = 2 μ E − 2 R g (sin φ − μ cos φ)     (φ decreasing)
/// until E = 0 again. Classical RK4 in φ.
double exact_turning_angle(double R, double phi0_deg, double mu) {
  const auto rhs = [&](double phi, double E) {
    return 2.0 * mu * E - 2.0 * R * kG * (std::sin(phi) - mu * std::cos(phi));
  };
  double phi = phi0_deg * kDeg, E = 0.0;
  const double dphi = -1e-5;
  for (;;) {
    const double k1 = rhs(phi, E), k2 = rhs(phi + 0.5 * dphi, E + 0.5 * dphi * k1),
                 k3 = rhs(phi + 0.5 * dphi, E + 0.5 * dphi * k2), k4 = rhs(phi + dphi, E + dphi * k3);
    const double En = E + dphi / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    if (En <= 0.0 && phi < phi0_deg * kDeg - 0.01) return (phi + dphi * E / (E - En)) / kDeg;
    E = std::max(En, 0.0);
    phi += dphi;
  }
}

/// Release one particle at rest at φ₀ on the surface and return the angle of its first turning
/// point (where it stops or starts back).
template <class Surface>
double simulated_turning_angle(const Surface& surface, double R, double phi0_deg, double mu, bool curvature) {
  RunoutParameters p;
  p.d0 = 2.0;
  p.dt_max = 2e-3;
  p.duration = 200.0;
  p.stop_energy_fraction = 0.0;
  p.curvature = curvature;
  p.friction = CoulombFriction{mu};
  RunoutSolver<Surface> s(surface, p);
  RunoutStore& st = s.particles();
  st.append(1);
  st.get<Position<2>>()[0] = Vec2(R * std::sin(phi0_deg * kDeg), 0.0);
  st.get<Volume>()[0] = 1.0;
  s.initialise();
  double x_prev = st.get<Position<2>>()[0].x();
  for (;;) {
    s.step();
    const double x = st.get<Position<2>>()[0].x();
    const double vx = st.get<Velocity<2>>()[0].x();
    if (s.time() > 0.5 && (vx >= 0.0 || s.all_stopped())) return std::asin(x / R) / kDeg;
    EXPECT_LE(x, x_prev + 1e-12);
    x_prev = x;
    if (s.finished()) return 90.0;
  }
}

}  // namespace

// A point mass in a trough whose cross-section is a circle of R = 100 m, released at 60°. Exact
// first turning points: −42.17° (μ = 0.1), −16.26° (μ = 0.3). The bed constraint (velocity turned
// into the new tangent plane, magnitude kept) makes the map-view motion that on the circle; the
// curvature term g_n = cos θ (g + vᵀHv) adds the friction of the centripetal load. Without it the
// particle climbs 6.4° (μ = 0.1) and 10.4° (μ = 0.3) higher. Tolerance 0.5°: the time step (≤ 2 ms,
// a 0.1 m path step) shifts the turning point by < 0.05°.
TEST(BedCurvature, PointMassInACircularTroughTurnsWhereTheExactMotionDoes) {
  const double R = 100.0;
  const CylindricalTrough trough{R, 0.0};
  for (const double mu : {0.1, 0.3}) {
    const double exact = exact_turning_angle(R, 60.0, mu);
    const double model = simulated_turning_angle(trough, R, 60.0, mu, true);
    const double flat = simulated_turning_angle(trough, R, 60.0, mu, false);
    std::printf("trough μ = %.1f: exact %.2f°, model %.2f°, without the curvature term %.2f°\n", mu, exact, model,
                flat);
    EXPECT_NEAR(model, exact, 0.5) << "mu " << mu;
    EXPECT_GT(std::abs(flat - exact), 5.0) << "mu " << mu;  // the term matters: the test can fail
  }
}

// The same trough as a DSM of 1 m cells: bilinear elevation, Hessian from second differences over
// d₀ = 2 m. Tolerance 1°: the piecewise-constant bilinear gradient turns the velocity in 1 m kinks.
TEST(BedCurvature, TroughOnADsmTurnsWhereTheExactMotionDoes) {
  const double R = 100.0;
  const GridGeometry g{200, 20, -100.0, 10.0, 1.0, 1.0};
  const GridSurface dsm = GridSurface::from_function(
      g,
      [&](double x, double) {
        return std::abs(x) < 0.99 * R ? R - std::sqrt(R * R - x * x) : std::numeric_limits<double>::quiet_NaN();
      },
      2.0);
  EXPECT_EQ(dsm.curvature_cells(), 2);
  for (const double mu : {0.1, 0.3}) {
    const double exact = exact_turning_angle(R, 60.0, mu);
    const double model = simulated_turning_angle(dsm, R, 60.0, mu, true);
    std::printf("trough on a 1 m DSM, μ = %.1f: exact %.2f°, model %.2f°\n", mu, exact, model);
    EXPECT_NEAR(model, exact, 1.0) << "mu " << mu;
  }
}

namespace {

// GridSurface is the core sampler plus curvature: its elevation and gradient are BilinearGrid's bit
// for bit, it is defined exactly where the sampler is (the closed hull of the centres, east and
// south border lines included since the samplers were merged; not the half-cell band), and a
// quadratic surface's Hessian comes back from the second differences with the sampler's weights.
TEST(GridSurface, IsTheCoreSamplerPlusCurvature) {
  const GridGeometry g{12, 9, 100.0, 500.0, 2.0, 2.0};
  // z = 0.01 x'² − 0.02 x'y' + 0.03 y'²: second differences are exact, z_xx = 0.02, z_xy = −0.02,
  // z_yy = 0.06 at every centre whose stencil fits (k = 1 here); float storage: 1e-7 relative.
  const GridSurface s = GridSurface::from_function(g, [](double x, double y) {
    const double u = x - 110.0, v = y - 490.0;
    return 0.01 * u * u - 0.02 * u * v + 0.03 * v * v;
  });
  const BilinearGrid& grid = s.grid();
  const Vec2 lo = g.centre(0, g.ny - 1), hi = g.centre(g.nx - 1, 0);
  int checked = 0;
  for (double x = lo.x() - 1.5; x <= hi.x() + 1.5; x += 0.25)
    for (double y = lo.y() - 1.5; y <= hi.y() + 1.5; y += 0.25) {
      SurfaceSample a{};
      TerrainSample b{};
      const bool ok = s.sample(Vec2(x, y), a);
      ASSERT_EQ(ok, grid.sample(Vec2(x, y), b)) << x << " " << y;
      ASSERT_EQ(ok, x >= lo.x() && x <= hi.x() && y >= lo.y() && y <= hi.y()) << x << " " << y;
      if (!ok) continue;
      EXPECT_EQ(a.z, b.z);
      EXPECT_EQ(a.grad, b.gradient);
      // Away from the border cells (where the stencil shrinks to nothing) the Hessian is exact.
      if (x >= lo.x() + 2.0 && x <= hi.x() - 2.0 && y >= lo.y() + 2.0 && y <= hi.y() - 2.0) {
        EXPECT_NEAR(a.hess[0], 0.02, 1e-8);
        EXPECT_NEAR(a.hess[1], -0.02, 1e-8);
        EXPECT_NEAR(a.hess[2], 0.06, 1e-8);
        ++checked;
      }
    }
  EXPECT_GT(checked, 500);
  // The south-east corner centre, off the terrain for the old half-open rule, is on it.
  SurfaceSample c{};
  EXPECT_TRUE(s.sample(g.centre(g.nx - 1, g.ny - 1), c));
}

}  // namespace
