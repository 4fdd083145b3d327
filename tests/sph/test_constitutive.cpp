// Unit tests of the constitutive models (constitutive.hpp): Drucker–Prager constants against hand
// values, return mapping onto the yield surface, tension cut-off, Jaumann objectivity, Hooke's law.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "geohaz/sph/constitutive.hpp"

namespace geohaz::sph {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double J2(const Mat3& s) {
  Mat3 d = s;
  d.diagonal().array() -= s.trace() / 3.0;
  return 0.5 * d.squaredNorm();
}

TEST(StrengthReduction, EachModelReducesItsOwnStrength) {
  // The strength reduction's trial material (constitutive.hpp, reduce_strength): Drucker–Prager
  // c/F and tan φ/F, tan ψ/F; the softening model its residual strength as well; von Mises its
  // yield stress (an undrained strength). Elastic and fluid models have none and are refused.
  MaterialParams p;
  p.cohesion = 12e3, p.friction = 35 * kDeg, p.dilatancy = 5 * kDeg, p.yield_stress = 90e3;
  p.residual_cohesion = 3e3, p.residual_friction = 25 * kDeg;
  const double F = 1.6;
  const auto dp = reduced_strength(DruckerPrager{}, {p}, F).front();
  EXPECT_DOUBLE_EQ(dp.cohesion, 12e3 / F);
  EXPECT_NEAR(std::tan(dp.friction), std::tan(35 * kDeg) / F, 1e-15);
  EXPECT_NEAR(std::tan(dp.dilatancy), std::tan(5 * kDeg) / F, 1e-15);
  EXPECT_EQ(dp.residual_cohesion, p.residual_cohesion);  // not a softening model's parameter
  EXPECT_EQ(dp.yield_stress, p.yield_stress);
  const auto soft = reduced_strength(DruckerPragerSoftening{}, {p}, F).front();
  EXPECT_DOUBLE_EQ(soft.cohesion, dp.cohesion);
  EXPECT_DOUBLE_EQ(soft.residual_cohesion, 3e3 / F);
  EXPECT_NEAR(std::tan(soft.residual_friction), std::tan(25 * kDeg) / F, 1e-15);
  const auto vm = reduced_strength(VonMises{}, {p}, F).front();
  EXPECT_DOUBLE_EQ(vm.yield_stress, 90e3 / F);
  EXPECT_EQ(vm.cohesion, p.cohesion);
  EXPECT_EQ(vm.friction, p.friction);
  EXPECT_THROW(reduced_strength(LinearElastic{}, {p}, F), std::invalid_argument);
  EXPECT_THROW(reduced_strength(NewtonianFluid{}, {p}, F), std::invalid_argument);
  EXPECT_EQ(models_with_shear_strength(), "von_mises, drucker_prager, drucker_prager_softening");
}

TEST(StrengthReduction, PlaneStrainStrengthForBishop) {
  // Bishop's (c, φ) of each model: von Mises in plane strain is Tresca with c_u = σ_y/√3, checked
  // here on a stress state at yield: σ_zz = (σ1 + σ3)/2 (plane strain, associated flow) and
  // σ1 − σ3 = 2 c_u puts √J2 exactly on σ_y/√3.
  MaterialParams p;
  p.cohesion = 12e3, p.friction = 35 * kDeg, p.yield_stress = 90e3;
  p.residual_cohesion = 3e3, p.residual_friction = 25 * kDeg;
  const auto [cu, phi_u] = *plane_strain_strength(VonMises{}, p);
  EXPECT_EQ(phi_u, 0.0);
  Mat3 s = Mat3::Zero();
  s(0, 0) = -200e3, s(1, 1) = -200e3 + 2.0 * cu, s(2, 2) = -200e3 + cu;
  EXPECT_NEAR(std::sqrt(J2(s)), p.yield_stress / std::sqrt(3.0), 1e-9);
  EXPECT_EQ(*plane_strain_strength(DruckerPrager{}, p), std::make_pair(12e3, 35 * kDeg));
  EXPECT_EQ(*plane_strain_strength(DruckerPragerSoftening{}, p, true), std::make_pair(3e3, 25 * kDeg));
  EXPECT_FALSE(plane_strain_strength(LinearElastic{}, p).has_value());
  EXPECT_FALSE(has_shear_strength(NewtonianFluid{}));
  EXPECT_TRUE(has_shear_strength(VonMises{}));
}

TEST(DruckerPragerConstants, PlaneStrainHandValues) {
  // φ = 30°, c = 10 kPa: tanφ = 1/√3, √(9 + 12 tan²φ) = √13 (Bui et al. 2010, eqs. 18–19).
  const auto k = drucker_prager_constants(10e3, 30 * kDeg, 0.0, DruckerPragerFit::PlaneStrain);
  EXPECT_NEAR(k.alpha_phi, (1.0 / std::sqrt(3.0)) / std::sqrt(13.0), 1e-12);
  EXPECT_NEAR(k.alpha_phi, 0.160128, 1e-6);
  EXPECT_NEAR(k.kc, 30e3 / std::sqrt(13.0), 1e-9);
  EXPECT_NEAR(k.kc, 8320.50, 1e-2);
  EXPECT_DOUBLE_EQ(k.alpha_psi, 0.0);
}

TEST(DruckerPragerConstants, ThreeDHandValues) {
  // φ = 30°, c = 10 kPa: sinφ = 1/2 → α = 1/(√3·2.5), k = 6c cos30°/(√3·2.5) = 12 kPa (SPH-slope paper 2020, eq. 21).
  const auto k = drucker_prager_constants(10e3, 30 * kDeg, 30 * kDeg, DruckerPragerFit::Compression3D);
  EXPECT_NEAR(k.alpha_phi, 0.2309401, 1e-7);
  EXPECT_NEAR(k.kc, 12000.0, 1e-6);
  EXPECT_NEAR(k.alpha_psi, k.alpha_phi, 1e-15);
}

TEST(DruckerPragerConstants, SeedMasaSoil) {
  // Bui et al. (2010), Table 1: c = 0.78 kPa, φ = 22.56°: tanφ = 0.41544, √(9+12·0.172591) = 3.327325.
  const auto k = drucker_prager_constants(780.0, 22.56 * kDeg, 0.0, DruckerPragerFit::PlaneStrain);
  EXPECT_NEAR(k.alpha_phi, 0.124857, 1e-6);
  EXPECT_NEAR(k.kc, 703.27, 0.01);
}

TEST(DruckerPragerConstants, PlaneStrainFlowRuleHandValues) {
  // ψ = 0: α = sinφ/3, k = c cosφ; φ = 30°, c = 10 kPa → α = 1/6, k = 10 kPa · √3/2.
  const auto k0 = drucker_prager_constants(10e3, 30 * kDeg, 0.0, DruckerPragerFit::PlaneStrainFlowRule);
  EXPECT_NEAR(k0.alpha_phi, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(k0.kc, 5e3 * std::sqrt(3.0), 1e-9);
  EXPECT_DOUBLE_EQ(k0.alpha_psi, 0.0);
  // ψ = φ: the associated plane-strain fit of Bui et al. (2010) (the same constants, round-off).
  for (double phi : {10.0, 19.6, 30.0, 45.0}) {
    const auto a = drucker_prager_constants(3e3, phi * kDeg, phi * kDeg, DruckerPragerFit::PlaneStrainFlowRule);
    const auto b = drucker_prager_constants(3e3, phi * kDeg, phi * kDeg, DruckerPragerFit::PlaneStrain);
    EXPECT_NEAR(a.alpha_phi, b.alpha_phi, 1e-14) << phi;
    EXPECT_NEAR(a.kc, b.kc, 1e-10) << phi;
    EXPECT_DOUBLE_EQ(a.alpha_psi, b.alpha_psi) << phi;
  }
}

/// Steady plastic deviator q = σ_lateral − σ_axial (Pa) of Drucker–Prager in a plane-strain biaxial
/// test at one material point: lateral stress held at −p3 (lateral strain rate iterated with the
/// oedometric stiffness), axial compression in strain steps of 1e-5 to 4 % (far past yield: the
/// elastic state's σ_zz has relaxed to the flow value by then).
double plane_strain_biaxial_strength(const MaterialParams& p, double p3) {
  const double M = p.bulk + 4.0 * p.shear / 3.0;
  Mat3 s = -p3 * Mat3::Identity();
  double kappa = 0.0;
  const double de = 1e-5, dt = 1e-3;
  for (int n = 0; n < 4000; ++n) {
    double exx = 0.0;
    Mat3 trial;
    for (int it = 0; it < 100; ++it) {
      Mat3 L = Mat3::Zero();
      L(0, 0) = exx / dt;
      L(1, 1) = -de / dt;
      trial = s;
      double kap = kappa;
      (void)DruckerPrager::update(trial, L, dt, p.density, p, kap);
      const double err = trial(0, 0) + p3;
      if (std::abs(err) < 1e-10 * p3) break;
      exx -= err / M;
    }
    s = trial;
  }
  return s(0, 0) - s(1, 1);
}

// Plane-strain failure at the Mohr–Coulomb stress: q = 2(c cosφ + p3 sinφ)/(1 − sinφ) with σ3 = −p3
// held. The flow-rule fit must give it for ψ = 0, 10° and φ (tolerance 0.5 %, the brief's; the
// residual comes from the strain steps); the associated fit of Bui et al. (2010) only for ψ = φ:
// with ψ = 0 it is weaker (sin φ_eff = 3α < sin φ), 2.0 % at the ACADS 1(a) soil (docs/validation/sph.md).
TEST(DruckerPragerConstants, FlowRuleFitFailsAtTheMohrCoulombStressInPlaneStrain) {
  const double c = 3e3, phi = 19.6 * kDeg, p3 = 40e3;
  const double q_mc = 2.0 * (c * std::cos(phi) + p3 * std::sin(phi)) / (1.0 - std::sin(phi));
  for (double psi : {0.0, 10.0, 19.6}) {
    MaterialParams p;
    p.young = 20e6;
    p.poisson = 0.3;
    p.cohesion = c;
    p.friction = phi;
    p.dilatancy = psi * kDeg;
    p.fit = DruckerPragerFit::PlaneStrainFlowRule;
    p.finalise();
    const double q = plane_strain_biaxial_strength(p, p3);
    EXPECT_NEAR(q, q_mc, 0.005 * q_mc) << "psi = " << psi;
    RecordProperty("q_flow_rule_psi" + std::to_string(static_cast<int>(psi)), std::to_string(q));
    p.fit = DruckerPragerFit::PlaneStrain;
    p.finalise();
    const double q_bui = plane_strain_biaxial_strength(p, p3);
    if (psi == 0.0) {
      EXPECT_LT(q_bui, 0.985 * q_mc);  // the associated fit under non-associated flow: too weak
    } else if (psi > 19.0) {
      EXPECT_NEAR(q_bui, q_mc, 0.005 * q_mc);
    }
    RecordProperty("q_plane_strain_psi" + std::to_string(static_cast<int>(psi)), std::to_string(q_bui));
  }
  RecordProperty("q_mohr_coulomb", std::to_string(q_mc));
}

TEST(DruckerPragerReturn, LandsOnYieldSurface) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-200e3, 50e3);
  const double K = 5e6, G = 3e6;
  for (double psi : {0.0, 10.0, 30.0}) {
    const auto k = drucker_prager_constants(5e3, 30 * kDeg, psi * kDeg, DruckerPragerFit::PlaneStrain);
    int plastic = 0;
    for (int t = 0; t < 2000; ++t) {
      Mat3 s;
      for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) s(a, b) = s(b, a) = u(rng);
      const double f0 = drucker_prager_yield(s, k.alpha_phi, k.kc);
      const double I1_0 = s.trace();
      Mat3 r = s;
      const double dl = drucker_prager_return(r, k.alpha_phi, k.alpha_psi, k.kc, K, G);
      const double f = drucker_prager_yield(r, k.alpha_phi, k.kc);
      EXPECT_LE(f, 1e-9 * k.kc) << "outside the surface after return";
      EXPECT_LE(r.trace(), k.kc / k.alpha_phi * (1 + 1e-12)) << "tension cut-off violated";
      if (f0 <= 0.0) {
        EXPECT_EQ(dl, 0.0);
        EXPECT_TRUE(r.isApprox(s)) << "elastic state changed";
      } else {
        ++plastic;
        EXPECT_GT(dl, 0.0);
        EXPECT_NEAR(f, 0.0, 1e-8 * std::max(k.kc, 1.0)) << "plastic state not on the surface";
        // Non-dilatant flow (ψ = 0) keeps I1 unless the apex is reached.
        if (psi == 0.0 && J2(r) > 1e-6) {
          EXPECT_NEAR(r.trace(), I1_0, 1e-6 * std::abs(I1_0) + 1e-6);
        }
        // Symmetric stress stays symmetric.
        EXPECT_NEAR((r - r.transpose()).norm(), 0.0, 1e-9);
      }
    }
    EXPECT_GT(plastic, 100);  // the test exercised the plastic branch
  }
}

TEST(DruckerPragerReturn, TensionCutOffGoesToApex) {
  const auto k = drucker_prager_constants(5e3, 30 * kDeg, 0.0, DruckerPragerFit::PlaneStrain);
  Mat3 s = Mat3::Identity() * 1e5;  // large hydrostatic tension
  s(0, 1) = s(1, 0) = 1e3;
  drucker_prager_return(s, k.alpha_phi, k.alpha_psi, k.kc, 5e6, 3e6);
  EXPECT_NEAR(s.trace(), k.kc / k.alpha_phi, 1e-9 * k.kc / k.alpha_phi);
  EXPECT_NEAR(J2(s), 0.0, 1e-12);
  // Cohesionless: no tension at all.
  const auto k0 = drucker_prager_constants(0.0, 30 * kDeg, 0.0, DruckerPragerFit::PlaneStrain);
  Mat3 t = Mat3::Identity() * 1e4;
  drucker_prager_return(t, k0.alpha_phi, k0.alpha_psi, k0.kc, 5e6, 3e6);
  EXPECT_NEAR(t.norm(), 0.0, 1e-9);
}

// Density floor (parting): ρ0 for a cohesionless DP soil; ρ0/(1 + p_t/K) with the apex tension
// p_t = k_c/(3α_φ) for c > 0; none for the models that carry tension.
TEST(DruckerPrager, MinimumDensityIsTheDilationAtTheApex) {
  MaterialParams p;
  p.density = 1800.0;
  p.young = 1e6;
  p.poisson = 0.3;
  p.friction = 30 * kDeg;
  p.finalise();
  EXPECT_DOUBLE_EQ(DruckerPrager::min_density(p), 1800.0);
  p.cohesion = 10e3;
  p.finalise();
  const double pt = p.dp.kc / (3.0 * p.dp.alpha_phi);
  EXPECT_NEAR(DruckerPrager::min_density(p), 1800.0 / (1.0 + pt / p.bulk), 1e-9);
  EXPECT_LT(DruckerPrager::min_density(p), 1800.0);
  EXPECT_EQ(LinearElastic::min_density(p), 0.0);
  EXPECT_EQ(VonMises::min_density(p), 0.0);
  EXPECT_EQ(NewtonianFluid::min_density(p), 0.0);
}

TEST(VonMises, RadialReturn) {
  MaterialParams p;
  p.young = 10e6;
  p.poisson = 0.3;
  p.yield_stress = 30e3;
  p.finalise();
  Mat3 s = Mat3::Zero();
  Mat3 L = Mat3::Zero();
  L(0, 1) = 1.0;  // simple shear rate 1/s
  double eps_p = 0.0;
  for (int i = 0; i < 2000; ++i) VonMises::update(s, L, 1e-5, p.density, p, eps_p);
  EXPECT_NEAR(std::sqrt(J2(s)), 30e3 / std::sqrt(3.0), 1e-6 * 30e3);
}

TEST(Jaumann, RigidRotationKeepsInvariants) {
  MaterialParams p;
  p.young = 10e6;
  p.poisson = 0.25;
  p.finalise();
  Mat3 s0;
  s0 << -50e3, 10e3, 0, 10e3, -20e3, 0, 0, 0, -30e3;
  Mat3 s = s0;
  const double omega = 2.0;  // rad/s
  Mat3 L = Mat3::Zero();
  L(0, 1) = -omega;
  L(1, 0) = omega;  // rigid rotation about z: v = ω × x
  const double dt = 1e-4, T = std::numbers::pi / 4.0 / omega;
  const int n = static_cast<int>(std::round(T / dt));
  for (int i = 0; i < n; ++i) LinearElastic::update(s, L, dt, p.density, p);
  EXPECT_NEAR(s.trace(), s0.trace(), 1e-9 * std::abs(s0.trace()));
  EXPECT_NEAR(J2(s), J2(s0), 1e-3 * J2(s0));
  EXPECT_NEAR(s.determinant(), s0.determinant(), 2e-3 * std::abs(s0.determinant()));
  // And the stress is the rotated one: σ = Q σ0 Qᵀ with Q a rotation by ωT = π/4.
  const double c = std::cos(omega * n * dt), sn = std::sin(omega * n * dt);
  Mat3 Q;
  Q << c, -sn, 0, sn, c, 0, 0, 0, 1;
  EXPECT_LT((s - Q * s0 * Q.transpose()).norm(), 2e-3 * s0.norm());
}

TEST(LinearElastic, UniaxialStrainAndPlaneStrainSigmaZZ) {
  MaterialParams p;
  p.young = 10e6;
  p.poisson = 0.3;
  p.finalise();
  Mat3 s = Mat3::Zero();
  Mat<2> L2 = Mat<2>::Zero();
  L2(1, 1) = -1.0;  // plane-strain compression rate along y
  const double dt = 1e-5;
  for (int i = 0; i < 100; ++i) LinearElastic::update(s, embed3<2>(L2), dt, p.density, p);
  const double eps = -1e-3;
  const double lambda = p.bulk - 2.0 * p.shear / 3.0;
  EXPECT_NEAR(s(1, 1), (p.bulk + 4.0 * p.shear / 3.0) * eps, 1e-9 * p.young);
  EXPECT_NEAR(s(0, 0), lambda * eps, 1e-9 * p.young);
  EXPECT_NEAR(s(2, 2), lambda * eps, 1e-9 * p.young) << "plane strain must carry sigma_zz";
}

TEST(NewtonianFluid, StressFromRate) {
  MaterialParams p;
  p.density = 1000;
  p.young = 3e6;
  p.poisson = 0.0;
  p.viscosity = 2.0;
  p.finalise();
  Mat3 s = Mat3::Zero();
  Mat3 L = Mat3::Zero();
  L(0, 1) = 3.0;
  NewtonianFluid::update(s, L, 1e-3, 1000.0, p);
  EXPECT_NEAR(s(0, 1), 2.0 * 3.0, 1e-12);  // μ du/dy
  NewtonianFluid::update(s, Mat3::Zero(), 1e-3, 1010.0, p);
  EXPECT_NEAR(s.trace() / 3.0, -p.bulk * 0.01, 1e-9);
}

TEST(ConstitutiveModel, NamesRoundTrip) {
  EXPECT_EQ(constitutive_model_names.size(), std::variant_size_v<ConstitutiveModel>);
  for (const char* n : {"linear_elastic", "von_mises", "drucker_prager", "newtonian_fluid"}) {
    const auto m = constitutive_model_from_name(n);
    ASSERT_TRUE(m.has_value()) << n;
    EXPECT_EQ(std::visit([](auto& x) { return std::string(std::decay_t<decltype(x)>::name); }, *m), n);
    EXPECT_EQ(constitutive_model_name(*m), n);
  }
  EXPECT_FALSE(constitutive_model_from_name("mohr").has_value());
}

// What the models declare instead of special cases in the solver: a fluid's wave speed is the
// sound speed √(K/ρ0) and it bounds Δt by viscous diffusion, 0.125 h²ρ0/μ (Morris et al. 1997);
// a solid's is the P-wave speed and it sets no bound of its own; only the solids may be loaded
// elastically in the geostatic phase; the plastic models accumulate Δλ in their internal variable.
TEST(ConstitutiveModel, ModelsDeclareWaveSpeedTimeStepLimitAndInternalVariables) {
  MaterialParams p;
  p.density = 1000.0;
  p.young = 3e4;
  p.poisson = 0.0;
  p.viscosity = 2.0;
  p.finalise();
  EXPECT_DOUBLE_EQ(NewtonianFluid::wave_speed(p), std::sqrt(1e4 / 1000.0));
  EXPECT_DOUBLE_EQ(NewtonianFluid::time_step_limit(p, 0.01), 0.125 * 1e-4 / 2e-3);
  p.viscosity = 0.0;
  EXPECT_EQ(NewtonianFluid::time_step_limit(p, 0.01), std::numeric_limits<double>::infinity());
  EXPECT_DOUBLE_EQ(DruckerPrager::wave_speed(p), p.p_wave_speed);
  EXPECT_EQ(DruckerPrager::time_step_limit(p, 0.01), std::numeric_limits<double>::infinity());
  EXPECT_FALSE(NewtonianFluid::elastic_loading);
  EXPECT_TRUE(DruckerPrager::elastic_loading && VonMises::elastic_loading && LinearElastic::elastic_loading);
  static_assert(std::is_same_v<DruckerPrager::InternalVariables, FieldList<PlasticStrain>>);
  static_assert(std::is_same_v<NewtonianFluid::InternalVariables, FieldList<>>);
  // Δλ returned and accumulated: a shear beyond the cone.
  p.young = 1e6;
  p.poisson = 0.3;
  p.friction = 0.5;
  p.finalise();
  Mat3 s = -1000.0 * Mat3::Identity(), L = Mat3::Zero();
  L(0, 1) = 10.0;
  double eps_p = 0.25;
  const double dl = DruckerPrager::update(s, L, 1e-3, p.density, p, eps_p);
  EXPECT_GT(dl, 0.0);
  EXPECT_DOUBLE_EQ(eps_p, 0.25 + dl);
}

// Strain softening in a plane-strain biaxial test at one material point: lateral stress held at
// −p3 (iterating the lateral strain rate with the elastic stiffness), axial compression in
// strain steps of 1e-5. The peak deviator is the first yield of the elastic state (σ_zz =
// −p3 − ν q) on the peak surface (c, φ); the residual one the steady plastic flow on the residual
// surface (c_r, φ_r): with ψ = 0 and ε̇_zz = 0 the flow keeps s_zz = 0, so σ_zz is the mean of the
// in-plane stresses and α·1.5(σ1 + σ3) + q/2 = k gives q = (k + 3α p3)/(½ − 3α/2). Tolerance 5 %
// (the issue's); both come out well within 1 %.
TEST(DruckerPragerSoftening, BiaxialPeakAndResidualMatchTheLaw) {
  MaterialParams p;
  p.young = 10e6;
  p.poisson = 0.3;
  p.cohesion = 20e3;
  p.friction = 30 * kDeg;
  p.dilatancy = 0.0;
  p.residual_cohesion = 2e3;
  p.residual_friction = 20 * kDeg;
  p.softening_strain = 0.02;
  p.finalise();
  const double p3 = 50e3;
  const double M = p.bulk + 4.0 * p.shear / 3.0;
  Mat3 s = -p3 * Mat3::Identity();
  double kappa = 0.0, qmax = 0.0, q = 0.0;
  std::vector<double> qs;
  const double de = 1e-5, dt = 1e-3;
  for (int n = 0; n < 12000; ++n) {
    // L = diag(ė_xx, ė_yy) with ė_yy = −de/dt; ė_xx found so that σ_xx stays −p3.
    double exx = 0.0;
    Mat3 trial;
    double kap = kappa;
    for (int it = 0; it < 100; ++it) {
      Mat3 L = Mat3::Zero();
      L(0, 0) = exx / dt;
      L(1, 1) = -de / dt;
      trial = s;
      kap = kappa;
      (void)DruckerPragerSoftening::update(trial, L, dt, p.density, p, kap);
      const double err = trial(0, 0) + p3;
      if (std::abs(err) < 1e-9 * p3) break;
      exx -= err / M;
    }
    s = trial;
    kappa = kap;
    q = s(0, 0) - s(1, 1);
    qmax = std::max(qmax, q);
    qs.push_back(q);
  }
  auto f_at = [&](double qq, double c, double phi, double zz) {
    Mat3 t = Mat3::Zero();
    t(0, 0) = -p3;
    t(1, 1) = -p3 - qq;
    t(2, 2) = zz;
    const auto k = drucker_prager_constants(c, phi, 0.0, p.fit);
    return drucker_prager_yield(t, k.alpha_phi, k.kc);
  };
  double lo = 0.0, hi = 1e7;  // first yield of the elastic state on the peak surface
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (f_at(mid, p.cohesion, p.friction, -p3 - p.poisson * mid) > 0.0 ? hi : lo) = mid;
  }
  const double q_peak = lo;
  const auto kr = drucker_prager_constants(p.residual_cohesion, p.residual_friction, 0.0, p.fit);
  const double q_res = (kr.kc + 3.0 * kr.alpha_phi * p3) / (0.5 - 1.5 * kr.alpha_phi);
  EXPECT_NEAR(qmax, q_peak, 0.05 * q_peak);
  EXPECT_NEAR(q, q_res, 0.05 * q_res);
  EXPECT_GT(kappa, p.softening_strain);
  EXPECT_LT(q, 0.7 * qmax);  // the post-peak drop
  // The deviator falls monotonically after the peak (to within round-off of the lateral iteration).
  const auto ipk = std::max_element(qs.begin(), qs.end()) - qs.begin();
  for (std::size_t k = static_cast<std::size_t>(ipk) + 1; k < qs.size(); ++k) EXPECT_LE(qs[k], qs[k - 1] + 1e-6 * qmax);
  RecordProperty("q_peak_model", std::to_string(qmax));
  RecordProperty("q_peak_law", std::to_string(q_peak));
  RecordProperty("q_residual_model", std::to_string(q));
  RecordProperty("q_residual_law", std::to_string(q_res));
}

// Strength along the softening law: peak at κ = 0, linear, residual from κ_r on.
TEST(DruckerPragerSoftening, StrengthFallsLinearlyToResidual) {
  MaterialParams p;
  p.cohesion = 10e3;
  p.friction = 30 * kDeg;
  p.residual_cohesion = 0.0;
  p.residual_friction = 20 * kDeg;
  p.softening_strain = 0.1;
  auto [c0, f0] = DruckerPragerSoftening::strength(p, 0.0);
  EXPECT_DOUBLE_EQ(c0, 10e3);
  EXPECT_DOUBLE_EQ(f0, 30 * kDeg);
  auto [c1, f1] = DruckerPragerSoftening::strength(p, 0.05);
  EXPECT_NEAR(c1, 5e3, 1e-9);
  EXPECT_NEAR(f1, 25 * kDeg, 1e-12);
  auto [c2, f2] = DruckerPragerSoftening::strength(p, 0.3);
  EXPECT_DOUBLE_EQ(c2, 0.0);
  EXPECT_NEAR(f2, 20 * kDeg, 1e-12);
}

}  // namespace
}  // namespace geohaz::sph
