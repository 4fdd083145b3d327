// Unit tests of the parallel bond (Potyondy & Cundall 2004): elastic response and breaking.
#include <gtest/gtest.h>

#include <cmath>

#include "geohaz/dem/solver.hpp"

using namespace geohaz;
using namespace geohaz::dem;

namespace {

/// Two touching discs joined by one bond; disc 1 is held, disc 0 is moved kinematically at v.
DemSolver bonded_pair(const Vec2& v, double sigma_c, double tau_c) {
  DemSolver s;
  s.settings.gravity = Vec2::Zero();
  s.law = LinearSpringCoulomb{1e9, 1e9};
  const double R = 0.01;
  add_disc(s.discs, Vec2(R, 0), R, 2650);
  add_disc(s.discs, Vec2(-R, 0), R, 2650);
  s.discs.get<Kinematic>()[0] = 1;
  s.discs.get<Kinematic>()[1] = 2;
  s.discs.get<Velocity<2>>()[0] = v;
  s.bonds.add(0, 1, R, 2 * R, 2e13, 1e13, sigma_c, tau_c);  // k̄n = 2e13, k̄s = 1e13 Pa/m
  s.initialise();
  return s;
}

}  // namespace

TEST(DemBonds, NormalForceIsStiffnessTimesAreaTimesStretch) {
  DemSolver s = bonded_pair(Vec2(1e-3, 0), 1e12, 1e12);
  const double A = 2 * 0.01, kn = 2e13;
  for (int k = 0; k < 200; ++k) {
    s.step();
    const double stretch = (s.discs.get<Position<2>>()[0] - s.discs.get<Position<2>>()[1]).norm() - 0.02;
    // Force on the held disc (group 2) from the bond: +k̄n A δ towards disc 0 (tension).
    const Vec2 f = s.kinematic_group_force(2);
    ASSERT_NEAR(f.x(), kn * A * stretch, 1e-9 * kn * A * stretch);
    ASSERT_NEAR(f.y(), 0.0, 1e-6);
  }
}

TEST(DemBonds, BreaksInTensionAtTheTensileStrength) {
  const double sigma_c = 5e6, kn = 2e13;
  DemSolver s = bonded_pair(Vec2(1e-3, 0), sigma_c, 1e12);
  const double stretch_c = sigma_c / kn;  // σ = k̄n δ (no moment)
  double stretch_at_break = -1;
  for (int k = 0; k < 100000 && s.events.empty(); ++k) {
    s.step();
    stretch_at_break = (s.discs.get<Position<2>>()[0] - s.discs.get<Position<2>>()[1]).norm() - 0.02;
  }
  ASSERT_EQ(s.events.size(), 1u);
  EXPECT_EQ(s.events[0].mode, FailureMode::Tensile);
  const double step_stretch = 1e-3 * s.time_step();
  EXPECT_NEAR(stretch_at_break, stretch_c, 1.01 * step_stretch);
  EXPECT_EQ(s.bonds.state[0], BondState::BrokenTension);
  // Released energy: F²/(2 k̄n A) with F = σ_c A (± one step of load).
  const double A = 0.02, F = sigma_c * A;
  EXPECT_NEAR(s.events[0].energy, F * F / (2 * kn * A), 0.02 * F * F / (2 * kn * A));
  // Removed with its load: no force afterwards.
  s.step();
  EXPECT_NEAR(s.kinematic_group_force(2).norm(), 0.0, 1e-12);
  EXPECT_EQ(s.discs.get<BrokenBonds>()[0], 1);
}

TEST(DemBonds, BreaksInShearAtTheShearStrength) {
  const double tau_c = 4e6, ks = 1e13;
  DemSolver s = bonded_pair(Vec2(0, 1e-3), 1e12, tau_c);
  double shear_at_break = -1;
  for (int k = 0; k < 100000 && s.events.empty(); ++k) {
    shear_at_break = std::abs(s.bonds.shear_force[0]) / 0.02;
    s.step();
  }
  ASSERT_EQ(s.events.size(), 1u);
  EXPECT_EQ(s.events[0].mode, FailureMode::Shear);
  // Pure tangential translation: τ = k̄s u_s, broken at the first step with τ ≥ τ_c.
  EXPECT_LT(shear_at_break, tau_c);
  EXPECT_GT(shear_at_break, tau_c - 1.01 * ks * 1e-3 * s.time_step());
  EXPECT_EQ(s.bonds.state[0], BondState::BrokenShear);
}

TEST(DemBonds, BendingMomentAddsToTensileStress) {
  // Rotating one disc bends the bond: σ = |M| R̄/I with M = k̄n I Δθ, so it breaks in tension at
  // Δθ = σ_c/(k̄n R̄) without any stretch.
  const double sigma_c = 5e6, kn = 2e13, Rb = 0.01;
  DemSolver s = bonded_pair(Vec2::Zero(), sigma_c, 1e12);
  s.discs.get<AngularVelocity>()[0] = 0.1;
  // Keep the contact point fixed: translate disc 0 so it rolls about the bond centre without slip.
  s.discs.get<Velocity<2>>()[0] = Vec2(0, 0.1 * 0.01);
  double theta = 0;
  for (int k = 0; k < 200000 && s.events.empty(); ++k) {
    theta = s.discs.get<Rotation>()[0];
    s.step();
  }
  ASSERT_EQ(s.events.size(), 1u);
  EXPECT_EQ(s.events[0].mode, FailureMode::Tensile);
  const double theta_c = sigma_c / (kn * Rb);
  EXPECT_NEAR(theta, theta_c, 0.02 * theta_c);
}
