// Unit tests of the total-Lagrangian formulation (solver.cpp, "Total-Lagrangian formulation";
// docs/sph.md): the deformation gradient is exact for an affine displacement at every particle,
// surfaces and corners included (linear and quadratic-complete reference gradients, 2D and 3D); a
// large rigid rotation gives no stress and no force (objectivity of St Venant–Kirchhoff); the
// hourglass force vanishes for an affine motion and not for a zigzag; a free stressed body keeps
// its linear momentum; one and two threads give the same bits.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <numbers>
#include <utility>

#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"
#include "support.hpp"

namespace geohaz::sph {
namespace {

/// A free block of soil (no walls), side W, spacing dx, at reference positions X; then displaced by
/// u(X) (positions X + u, Displacement u) and moving with v(X). The total-Lagrangian reference is
/// X = x − u at the first step.
template <int Dim>
SphSolver<Dim> tl_block(const std::function<Vec<Dim>(const Vec<Dim>&)>& u,
                        const std::function<Vec<Dim>(const Vec<Dim>&)>& v, bool quadratic, double hourglass = 0.1,
                        double dx = 0.01, double dt_max = 1e-9) {
  SphStore<Dim> store = test_support::free_block<Dim>(Dim == 2 ? 0.1 : 0.06, dx, 1.2);
  auto& x = store.template get<Position<Dim>>();
  auto& vel = store.template get<Velocity<Dim>>();
  auto& disp = store.template get<Displacement<Dim>>();
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Vec<Dim> X = x[i];
    disp[i] = u ? u(X) : Vec<Dim>::Zero();
    x[i] = X + disp[i];
    vel[i] = v ? v(X) : Vec<Dim>::Zero();
  }
  MaterialParams m;
  m.density = 2000;
  m.young = 1e7;
  m.poisson = 0.3;
  SolverSettings<Dim> s;
  s.spacing = dx;
  s.h_factor = 1.2;
  s.gravity = 0.0;
  s.dt_max = dt_max;
  s.kernel_correction = true;
  s.quadratic_correction = quadratic;
  s.total_lagrangian = true;
  s.hourglass = hourglass;
  return SphSolver<Dim>(std::move(store), {m}, LinearElastic{}, s);
}

template <int Dim>
Mat<Dim> test_matrix() {
  Mat<Dim> A;
  if constexpr (Dim == 2)
    A << 0.03, -0.02, 0.05, -0.01;
  else
    A << 0.03, -0.02, 0.01, 0.05, -0.01, 0.02, -0.04, 0.015, 0.025;
  return A;
}

// F_i = I + A to round-off at every particle for u = A X + c: the corrected reference gradients
// reproduce linear fields exactly, one-sided neighbourhoods included (the plain kernel gradient
// would be 40 % off at a corner).
template <int Dim>
void check_affine_F(bool quadratic) {
  const Mat<Dim> A = test_matrix<Dim>();
  const Vec<Dim> c = Vec<Dim>::Constant(0.004);
  auto solver = tl_block<Dim>([&](const Vec<Dim>& X) { return Vec<Dim>(A * X + c); }, {}, quadratic);
  solver.step();
  const auto& F = solver.deformation_gradient();
  ASSERT_EQ(F.size(), solver.store().size());
  const Mat<Dim> expect = Mat<Dim>::Identity() + A;
  double worst = 0.0;
  for (const auto& f : F) worst = std::max(worst, (f - expect).cwiseAbs().maxCoeff());
  std::printf("%zu particles, max |F - (I + A)| = %.3g\n", F.size(), worst);
  EXPECT_LT(worst, 1e-12);
}
TEST(TotalLagrangian, AffineDeformationGradientExactEverywhere2D) {
  check_affine_F<2>(false);
}
TEST(TotalLagrangian, AffineDeformationGradientExactEverywhere2DQuadratic) {
  check_affine_F<2>(true);
}
TEST(TotalLagrangian, AffineDeformationGradientExactEverywhere3D) {
  check_affine_F<3>(false);
}

// A rigid rotation by 60° (u = (R − I) X) is a large displacement with no strain: F = R, the
// Green–Lagrange strain and so the stress vanish to round-off, and so do the forces (the stress
// term and the hourglass term, the latter since the motion is affine). A small-strain (linear)
// stress of the same displacement field would be ~E·0.5 = 5 MPa. Control: a 0.1 % plane-strain
// stretch gives the St Venant–Kirchhoff Cauchy stress at every particle (≈ 1.3e4 Pa).
TEST(TotalLagrangian, LargeRigidRotationIsStressFree) {
  const double th = std::numbers::pi / 3.0;
  Mat<2> R;
  R << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
  for (const bool quadratic : {false, true}) {
    auto solver = tl_block<2>([&](const Vec<2>& X) { return Vec<2>((R - Mat<2>::Identity()) * X); }, {}, quadratic);
    solver.step();
    double smax = 0.0, amax = 0.0;
    for (const auto& s : solver.store().get<Stress>()) smax = std::max(smax, s.cwiseAbs().maxCoeff());
    for (const auto& a : solver.store().get<Acceleration<2>>()) amax = std::max(amax, a.norm());
    std::printf("rotation 60 deg (%s): max |sigma| %.3g Pa, max |a| %.3g m/s^2\n", quadratic ? "quadratic" : "linear",
                smax, amax);
    EXPECT_LT(smax, 1e-6);
    EXPECT_LT(amax, 1e-6);
  }
  auto stretched = tl_block<2>([](const Vec<2>& X) { return Vec<2>(1e-3 * X[0], 0.0); }, {}, false);
  stretched.step();
  // F = diag(1.001, 1): E_xx = ½(1.001² − 1), S_xx = (λ + 2μ) E_xx, σ_xx = F_xx S_xx F_xx / J = 1.001 S_xx.
  const double E = 1e7, nu = 0.3, lam2mu = E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double expect = 1.001 * lam2mu * 0.5 * (1.001 * 1.001 - 1.0);
  for (const auto& s : stretched.store().get<Stress>()) ASSERT_NEAR(s(0, 0), expect, 1e-9 * expect);
}

/// Accelerations after one step with hourglass coefficient alpha.
std::vector<Vec<2>> accelerations(const std::function<Vec<2>(const Vec<2>&)>& u, double alpha) {
  auto solver = tl_block<2>(u, {}, false, alpha);
  solver.step();
  return solver.store().get<Acceleration<2>>();
}

// The hourglass force is zero for an affine motion (every pair's length is the one F predicts) and
// not for a zigzag (alternate rows displaced ±δ: a zero-energy-like mode the collocation sums barely
// see). Measured as the difference of the accelerations with α = 0.1 and α = 0.
TEST(TotalLagrangian, HourglassForceZeroForAffineMotion) {
  const Mat<2> A = test_matrix<2>();
  auto affine = [&](const Vec<2>& X) { return Vec<2>(A * X); };
  auto zigzag = [&](const Vec<2>& X) {
    const int row = static_cast<int>(std::lround(X[1] / 0.01 - 0.5)),
              col = static_cast<int>(std::lround(X[0] / 0.01 - 0.5));
    return Vec<2>(A * X + Vec<2>(0.0, ((row + col) % 2 ? 1e-4 : -1e-4)));
  };
  double d_affine = 0.0, d_zigzag = 0.0, scale = 0.0;
  {
    const auto a1 = accelerations(affine, 0.1), a0 = accelerations(affine, 0.0);
    for (std::size_t i = 0; i < a1.size(); ++i) {
      d_affine = std::max(d_affine, (a1[i] - a0[i]).norm());
      scale = std::max(scale, a0[i].norm());
    }
  }
  {
    const auto a1 = accelerations(zigzag, 0.1), a0 = accelerations(zigzag, 0.0);
    for (std::size_t i = 0; i < a1.size(); ++i) d_zigzag = std::max(d_zigzag, (a1[i] - a0[i]).norm());
  }
  std::printf("hourglass acceleration: affine %.3g, zigzag %.3g m/s^2 (stress term up to %.3g)\n", d_affine, d_zigzag,
              scale);
  EXPECT_GT(scale, 1.0) << "the affine field must stress the block for the test to mean anything";
  EXPECT_LT(d_affine, 1e-9 * scale);
  EXPECT_GT(d_zigzag, 1.0);
}

// The hourglass stiffness is in the time step (solver.cpp, tl_setup). A free block started in a
// zigzag (alternate particles displaced ±0.1 mm, the mode the hourglass force resists) swings about
// the reference without growing over 3000 steps: with the linear gradient even at α = 50, where the
// step is a quarter of the P-wave one (with the P-wave step alone, α = 10 blew the cantilever up
// within 0.03 s), and with the quadratic-complete gradient at the largest accepted α = 1. (With the
// quadratic-complete gradient α = 10 and 50 grow — ×10 in 3000 steps, and out of bounds after 2130
// — whatever the step: the hourglass force is not derived from a potential, and this is why
// numerics.hourglass stops at 1; docs/sph.md.)
TEST(TotalLagrangian, HourglassControlStaysBoundedWithItsTimeStep) {
  auto zigzag = [](const Vec<2>& X) {
    const int row = static_cast<int>(std::lround(X[1] / 0.01 - 0.5)),
              col = static_cast<int>(std::lround(X[0] / 0.01 - 0.5));
    return Vec<2>(0.0, (row + col) % 2 ? 1e-4 : -1e-4);
  };
  for (const auto& [quadratic, alpha] : {std::pair{false, 50.0}, std::pair{true, 1.0}}) {
    auto weak = tl_block<2>(zigzag, {}, quadratic, 0.0, 0.01, 1.0);
    auto strong = tl_block<2>(zigzag, {}, quadratic, alpha, 0.01, 1.0);
    weak.step();
    strong.step();
    const double c_p = weak.max_wave_speed(), h = weak.smoothing_length();
    std::printf("quadratic %d: time step P-wave %.3g s, alpha 0 %.3g s, alpha %g %.3g s\n", quadratic, 0.2 * h / c_p,
                weak.dt(), alpha, strong.dt());
    EXPECT_LT(strong.dt(), (quadratic ? 0.95 : 0.5) * weak.dt()) << "the hourglass stiffness must shorten the step";
    double umax = 0.0;
    for (int k = 0; k < 3000; ++k) {
      strong.step();
      for (const auto& u : strong.store().get<Displacement<2>>()) umax = std::max(umax, u.norm());
    }
    std::printf("largest displacement over 3000 steps: %.3g m (started at 1e-4 m)\n", umax);
    EXPECT_TRUE(std::isfinite(umax));
    EXPECT_LT(umax, 4e-4) << "quadratic " << quadratic;
  }
}

// A free block (no clamp, no gravity) with a non-uniform velocity field and a non-affine initial
// displacement: stressed at once, yet Σ m v stays at its initial value to round-off over 50 steps
// (the pair terms of (i, j) and (j, i) are bitwise negatives; hourglass on).
TEST(TotalLagrangian, FreeStressedBlockConservesLinearMomentum) {
  Mat<2> A;
  A << 0.3, -0.7, 1.1, -0.2;
  for (const bool quadratic : {false, true}) {
    auto solver =
        tl_block<2>([](const Vec<2>& X) { return Vec<2>(1e-3 * X[0] * X[1] / 0.1, 2e-3 * X[0] * X[0] / 0.1); },
                    [&](const Vec<2>& X) { return Vec<2>(Vec<2>(0.5, -0.2) + A * X); }, quadratic, 0.1, 0.01, 1e-5);
    test_support::expect_fifty_steps_conserve_momentum(solver, 1e3);
  }
}

// Above kParallelMin (2048) particles the passes run on the threads; every particle sums its own
// row, so 1 and 2 threads give the same bits (3600 particles, 20 steps).
TEST(TotalLagrangian, OneAndTwoThreadsBitIdentical) {
  std::vector<Vec<2>> x[2];
  for (int t = 1; t <= 2; ++t) {
    omp_set_num_threads(t);
    auto solver =
        tl_block<2>([](const Vec<2>& X) { return Vec<2>(1e-3 * X[0] * X[1] / 0.1, 2e-3 * X[0] * X[0] / 0.1); },
                    [](const Vec<2>& X) { return Vec<2>(0.1 * X[1], -0.2 * X[0]); }, true, 0.1, 0.1 / 60.0, 1e-5);
    ASSERT_GT(solver.store().size(), 2048u);
    for (int k = 0; k < 20; ++k) solver.step();
    x[t - 1] = solver.store().get<Position<2>>();
  }
  omp_set_num_threads(1);
  ASSERT_EQ(x[0].size(), x[1].size());
  EXPECT_EQ(std::memcmp(x[0].data(), x[1].data(), x[0].size() * sizeof(Vec<2>)), 0);
}

}  // namespace
}  // namespace geohaz::sph
