// Unit tests of Bishop's simplified method and the critical-circle search (limit_equilibrium.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/sph/limit_equilibrium.hpp"

namespace geohaz::sph {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// A slope of height H at `gradient`:1 (H:V) on a foundation `base` deep, long crest and front.
SlopeSection slope(double H, double gradient, double base, double crest, double front, LimitEquilibriumSoil soil) {
  SlopeGeometry g;
  g.height = H;
  g.gradient = gradient;
  g.base_thickness = base;
  g.crest_length = crest;
  g.front_length = front;
  return SlopeSection::from_profile(g.profile(), {soil});
}

// Taylor (1937) stability chart, φ = 0: for face angles β ≥ 53° the critical circle passes through
// the toe and the stability number N = c/(γ H F) is 0.261 for a vertical face and 0.191 for β = 60°.
// Read from the chart to about ±1 %; the tolerance is the 3 %.
TEST(Bishop, VerticalCutMatchesTaylorChart) {
  const double H = 10.0, gamma = 20e3, c = 50e3;
  const auto s = slope(H, 0.0, 2.0 * H, 3.0 * H, 3.0 * H, {gamma, c, 0.0});
  const auto r = bishop_critical_circle(s);
  ASSERT_TRUE(r.admissible());
  const double N = c / (gamma * H * r.factor);
  EXPECT_NEAR(N, 0.261, 0.03 * 0.261);
  // The critical circle passes through the toe (x = 30 m, z = 20 m).
  EXPECT_NEAR(r.x_exit, 3.0 * H, 0.05 * H);
}

TEST(Bishop, SixtyDegreeSlopeMatchesTaylorChart) {
  const double H = 10.0, gamma = 20e3, c = 40e3;
  const auto s = slope(H, 1.0 / std::tan(60.0 * kDeg), 2.0 * H, 3.0 * H, 3.0 * H, {gamma, c, 0.0});
  const auto r = bishop_critical_circle(s);
  const double N = c / (gamma * H * r.factor);
  EXPECT_NEAR(N, 0.191, 0.03 * 0.191);
}

// ACADS benchmark 1(a) (Giam & Donald 1989; Donald & Giam 1992): homogeneous dry slope, H = 10 m at
// 2H:1V, c′ = 3 kPa, φ′ = 19.6°, γ = 20 kN/m³; referee factor 1.00, mean of the survey's Bishop
// results 0.993. The issue asks for Bishop within 3 % of the referee.
TEST(Bishop, AcadsOneAMatchesTheRefereeFactor) {
  const auto s = slope(10.0, 2.0, 5.0, 25.0, 20.0, {20e3, 3e3, 19.6 * kDeg});
  const auto r = bishop_critical_circle(s);
  EXPECT_NEAR(r.factor, 1.00, 0.03);
  // A toe circle: it leaves the slope near the toe (x = 45 m) and enters the crest behind the face.
  EXPECT_NEAR(r.x_exit, 45.0, 2.0);
  EXPECT_LT(r.x_entry, 25.0);
  // Its lowest point at the toe level (within 1 cm: the search's last step; a circle dipping a few
  // millimetres under the level ground in front of the toe is admissible since Whitman & Bailey's
  // m_α limit is checked at the converged factor, not at the iterates).
  EXPECT_GT(r.circle.zc - r.circle.radius, 5.0 - 0.01);
  std::printf("ACADS 1(a): F %.4f, circle (%.3f, %.3f, R %.3f)\n", r.factor, r.circle.xc, r.circle.zc, r.circle.radius);
}

// Mirroring the section (the slope falling to the left) gives the same factor: the direction of
// sliding is found from the sign of the driving moment.
TEST(Bishop, MirroredSlopeHasTheSameFactor) {
  const LimitEquilibriumSoil soil{20e3, 3e3, 19.6 * kDeg};
  const auto s = slope(10.0, 2.0, 5.0, 25.0, 20.0, soil);
  SlopeSection m = s;
  m.surface.clear();
  for (auto it = s.surface.rbegin(); it != s.surface.rend(); ++it) m.surface.push_back({-(*it)[0], (*it)[1]});
  m.x_left = -s.x_right;
  m.x_right = -s.x_left;
  const SlipCircle c{35.0, 25.0, 20.0};
  const auto a = bishop_factor(s, c), b = bishop_factor(m, {-35.0, 25.0, 20.0});
  ASSERT_TRUE(a.admissible());
  EXPECT_NEAR(a.factor, b.factor, 1e-9 * a.factor);
}

// For φ = 0 Bishop's factor is the moment balance of the circle, F = c R ℓ / Σ W (x_c − x) with ℓ the
// arc length in soil: checked on a circle through a vertical cut, the weight moment integrated
// independently on a fine grid.
TEST(Bishop, UndrainedFactorIsTheMomentBalanceOfTheCircle) {
  const double gamma = 18e3, c = 30e3;
  const auto s = slope(10.0, 0.0, 10.0, 30.0, 30.0, {gamma, c, 0.0});
  const SlipCircle circ{32.0, 27.0, 13.0};  // enters the crest at x = 21.05 m, leaves through the face
  const auto r = bishop_factor(s, circ, 2000);
  ASSERT_TRUE(r.admissible());
  // Arc in soil between the entry and the exit (the lower arc): angles from the centre.
  const double a0 = std::asin((circ.xc - r.x_entry) / circ.radius), a1 = std::asin((r.x_exit - circ.xc) / circ.radius);
  const double arc = circ.radius * (a0 + a1);
  double moment = 0.0;
  const int n = 4000;
  const double dxm = (r.x_exit - r.x_entry) / n;
  for (int i = 0; i < n; ++i) {
    const double x = r.x_entry + (i + 0.5) * dxm;
    const double za = circ.zc - std::sqrt(circ.radius * circ.radius - (x - circ.xc) * (x - circ.xc));
    const double zs = x < 30.0 ? 20.0 : 10.0;
    if (zs > za) moment += gamma * (zs - za) * dxm * (circ.xc - x);
  }
  EXPECT_NEAR(r.factor, c * circ.radius * arc / moment, 2e-3 * r.factor);  // slice discretisation
}

// A layered section with identical soils gives the homogeneous factor; a weaker lower layer lowers it.
TEST(Bishop, LayersWithEqualSoilsAreOneSoil) {
  const LimitEquilibriumSoil soil{20e3, 3e3, 19.6 * kDeg};
  auto s = slope(10.0, 2.0, 5.0, 25.0, 20.0, soil);
  const SlipCircle c{38.0, 24.0, 17.0};
  const double F = bishop_factor(s, c).factor;
  s.layer_tops = {5.0, 9.0};
  s.layer_materials = {0, 1, 0};
  s.soils = {soil, soil};
  EXPECT_NEAR(bishop_factor(s, c).factor, F, 1e-12 * F);
  s.soils[1].cohesion = 1e3;
  EXPECT_LT(bishop_factor(s, c).factor, F);
}

// Two-layer undrained clay slope of Griffiths & Lane (1999), their slope on a weak foundation
// (data/sph/griffiths_lane_two_layer_srm.toml): 2H:1V, H = 10 m, on a foundation H deep (D = 2) over a
// rigid base, φ_u = 0, γ = 20 kN/m³; slope soil (above the toe level z = 10 m) c_u1 = 0.25 γH = 50 kPa,
// foundation c_u2 = λ c_u1. Materials: 0 foundation, 1 slope soil. Crest and front 20 m.
SlopeSection griffiths_lane_section(double lambda, double base = 10.0) {
  SlopeGeometry g;
  g.height = 10.0;
  g.gradient = 2.0;
  g.base_thickness = base;
  g.crest_length = 20.0;
  g.front_length = 20.0;
  auto s = SlopeSection::from_profile(g.profile(), {{20e3, lambda * 50e3, 0.0}, {20e3, 50e3, 0.0}});
  s.layer_tops = {base};
  s.layer_materials = {0, 1};
  return s;
}

// λ = 1 is the homogeneous slope with a firm base at D = 2: Taylor's (1937) chart gives N = 0.17 at
// β = 26.57°, F = 0.25/0.17 = 1.47, the value Griffiths & Lane quote for it. Chart reading ±2 %; the
// issue's 3 %.
TEST(Bishop, TwoLayerClaySlopeWithEqualLayersMatchesTaylorChart) {
  const auto r = bishop_critical_circle(griffiths_lane_section(1.0));
  ASSERT_TRUE(r.admissible());
  EXPECT_NEAR(r.factor, 1.47, 0.03 * 1.47);
  // Taylor's base circle for β < 53°: the circle touches the firm base.
  EXPECT_NEAR(r.circle.zc - r.circle.radius, 0.0, 0.5);
}

// The slice base takes the strength of the layer it lies in: for φ = 0 and one circle,
// F = R (c_u1 ℓ₁ + c_u2 ℓ₂) / Σ W (x_c − x), so F(λ)/F(1) = (ℓ₁ + λ ℓ₂)/(ℓ₁ + ℓ₂) with ℓ₂ the arc below
// the layer top, 2R acos((z_c − z_top)/R), and ℓ₁ the rest of the arc in soil (angles from the entry
// and exit points). Tolerance: the slices cut the arc at the layer top to within one slice, a slice
// arc ℓ_s of up to ~0.3 m with 200 slices, an error (λ − 1) ℓ_s/ℓ of up to 1e-2 in the ratio at λ = 3;
// with 1000 slices 2e-3, inside the 5e-3 allowed.
TEST(Bishop, UndrainedFactorWeighsTheArcInEachLayer) {
  const SlipCircle circ{30.0, 28.0, 27.5};  // a deep circle: enters the crest, dips 7.5 m into the foundation
  const auto one = bishop_factor(griffiths_lane_section(1.0), circ, 1000);
  ASSERT_TRUE(one.admissible());
  const double a0 = std::asin((circ.xc - one.x_entry) / circ.radius);
  const double a1 = std::asin((one.x_exit - circ.xc) / circ.radius);
  const double arc = circ.radius * (a0 + a1);
  const double below = 2.0 * circ.radius * std::acos((circ.zc - 10.0) / circ.radius);
  // The level ground in front of the toe is the layer top: the circle leaves the soil where it crosses it.
  EXPECT_NEAR(circ.xc + circ.radius * std::sin(std::acos((circ.zc - 10.0) / circ.radius)), one.x_exit, 0.05);
  for (double lambda : {0.4, 0.6, 1.4, 3.0}) {
    const auto r = bishop_factor(griffiths_lane_section(lambda), circ, 1000);
    EXPECT_NEAR(r.factor / one.factor, (arc - below + lambda * below) / arc, 5e-3) << lambda;
  }
}

// Griffiths & Lane (1999; code_aster's reproduction of their example, SSNP507, states it): with a weak
// foundation the critical circle goes deep into it and F grows with λ; from λ ≈ 1.5 on the circle
// stays in the slope layer (a circle tangent to the foundation, leaving through the face just above the
// toe) and F no longer depends on the foundation. That circle is the critical circle of the slope
// layer on a rigid base at the toe level (Taylor's D = 1).
TEST(Bishop, StrongFoundationLeavesTheToeCircleInTheSlopeLayer) {
  const auto weak = bishop_critical_circle(griffiths_lane_section(0.6));
  const auto below_switch = bishop_critical_circle(griffiths_lane_section(1.4));
  const auto strong = bishop_critical_circle(griffiths_lane_section(2.0));
  const auto stronger = bishop_critical_circle(griffiths_lane_section(3.0));
  const auto rigid = bishop_critical_circle(griffiths_lane_section(1.0, 0.0));  // D = 1: no foundation
  // Deep circles, tangent to the rigid base, below the switch.
  EXPECT_LT(weak.circle.zc - weak.circle.radius, 1.0);
  EXPECT_LT(below_switch.circle.zc - below_switch.circle.radius, 1.0);
  EXPECT_LT(weak.factor, below_switch.factor);
  // Above it: the toe circle of the slope layer, the same for every stronger foundation.
  EXPECT_NEAR(strong.circle.zc - strong.circle.radius, 10.0, 0.05);
  EXPECT_NEAR(strong.factor, stronger.factor, 1e-3 * strong.factor);
  EXPECT_NEAR(strong.factor, rigid.factor, 3e-3 * rigid.factor);
  EXPECT_GT(strong.factor, below_switch.factor);
}

// Two-layer undrained clay slope of Table 1 of "Influence of Both Soil Properties and Geometric
// Parameters on Failure Mechanisms and Stability of Two-Layer Undrained Slopes" (Advances in Materials
// Science and Engineering 2020, article 4253026; data/sph/two_layer_d15.toml): cot β = 1.5, H = 10 m,
// firm base D H = 15 m below the crest (a foundation 0.5 H thick below the toe level), φ_u = 0,
// c_u1 above the toe level, c_u2 = λ c_u1 below it. The paper's c_u1/(γH) is not known to us; with
// φ = 0 every factor is proportional to c_u1 at fixed λ, so the ratios F(λ)/F(2) are independent of it
// and of H and γ: those are compared with the paper's limit-equilibrium (LEM) ratios, 3 % (issue #18's
// tolerance for Bishop). From λ = 1.5 on the paper's mechanism is the shallow toe circle in the slope
// layer (F the same for every stronger foundation), and at λ = 1.4 both mechanisms give that F: λ = 1.4,
// 1.5 and 3 within 0.5 % of λ = 2. λ = 0.5 to 1.2 "deep": the critical circle reaches the firm base.
SlopeSection two_layer_d15_section(double lambda) {
  SlopeGeometry g;
  g.height = 10.0;
  g.gradient = 1.5;
  g.base_thickness = 5.0;
  g.crest_length = 20.0;
  g.front_length = 20.0;
  auto s = SlopeSection::from_profile(g.profile(), {{20e3, lambda * 50e3, 0.0}, {20e3, 50e3, 0.0}});
  s.layer_tops = {5.0};
  s.layer_materials = {0, 1};
  return s;
}

TEST(Bishop, TwoLayerSlopeD15MatchesPublishedFactorRatios) {
  constexpr double kLemShallow = 1.185;  // Table 1, LEM, λ = 1.5 to 3
  const auto ref = bishop_critical_circle(two_layer_d15_section(2.0));
  ASSERT_TRUE(ref.admissible());
  for (const auto& [lambda, lem] : {std::pair{0.5, 0.647}, {0.8, 0.851}, {1.1, 1.060}, {1.2, 1.130}}) {
    const auto r = bishop_critical_circle(two_layer_d15_section(lambda));
    ASSERT_TRUE(r.admissible()) << lambda;
    const double ratio = r.factor / ref.factor, published = lem / kLemShallow;
    std::printf("lambda %.2f: F %.4f  F/F(2) %.4f  published %.4f  (%+.2f %%)  circle bottom z = %.2f m\n", lambda,
                r.factor, ratio, published, 100.0 * (ratio / published - 1.0), r.circle.zc - r.circle.radius);
    EXPECT_NEAR(ratio, published, 0.03 * published) << lambda;
    // The paper's "deep" mechanism: the critical circle goes down to the firm base.
    EXPECT_LT(r.circle.zc - r.circle.radius, 0.5) << lambda;
  }
  // λ = 1 (one soil): the published 0.967 lies 2.4 % below the chord of its neighbours 0.851 (λ = 0.8)
  // and 1.130 (1.2), 0.9905, which no factor of safety can: for φ = 0 the factor of every mechanism is
  // linear in λ (F = (a + λ b)/M), so the minimum over mechanisms is concave in λ (true of the
  // limit-equilibrium minimum over circles and of the collapse factor, the minimum over kinematic
  // mechanisms, alike). Ours (+3.3 % from the published λ = 1 ratio) is checked against the chord of
  // the published λ = 0.8 and 1.2 ratios instead, 3 %.
  {
    const auto r = bishop_critical_circle(two_layer_d15_section(1.0));
    const double ratio = r.factor / ref.factor, chord = 0.5 * (0.851 + 1.130) / kLemShallow;
    std::printf("lambda 1.00: F %.4f  F/F(2) %.4f  published %.4f (%+.2f %%), chord of 0.8 and 1.2 %.4f (%+.2f %%)\n",
                r.factor, ratio, 0.967 / kLemShallow, 100.0 * (ratio * kLemShallow / 0.967 - 1.0), chord,
                100.0 * (ratio / chord - 1.0));
    EXPECT_NEAR(ratio, chord, 0.03 * chord);
  }
  std::printf("lambda 2.00: F %.4f  circle bottom z = %.2f m\n", ref.factor, ref.circle.zc - ref.circle.radius);
  for (double lambda : {1.4, 1.5, 3.0}) {
    const auto r = bishop_critical_circle(two_layer_d15_section(lambda));
    std::printf("lambda %.2f: F %.4f  circle bottom z = %.2f m\n", lambda, r.factor, r.circle.zc - r.circle.radius);
    EXPECT_NEAR(r.factor, ref.factor, 5e-3 * ref.factor) << lambda;
  }
  // "Shallow": the circle stays in the slope layer, above the toe level z = 5 m.
  EXPECT_GT(ref.circle.zc - ref.circle.radius, 5.0 - 0.05);
}

TEST(Bishop, CircleBelowTheRigidBottomIsNotAdmissible) {
  const auto s = slope(10.0, 2.0, 5.0, 25.0, 20.0, {20e3, 3e3, 19.6 * kDeg});
  EXPECT_FALSE(bishop_factor(s, {38.0, 24.0, 30.0}).admissible());
}

// A surface layer whose material has no soil, and a terrain across the width (3D), are rejected.
TEST(Bishop, SectionItCannotRepresentIsRejected) {
  ProfileDomain d = SlopeGeometry{}.profile();
  d.surface_layer_depth = 1.0;
  d.surface_material = 1;
  EXPECT_THROW((void)SlopeSection::from_profile(d, {{}}), InputError);
  d.surface_material = 0;
  EXPECT_NO_THROW((void)SlopeSection::from_profile(d, {{}}));
  d.surface_xy = [](double, double) { return 0.0; };
  EXPECT_THROW((void)SlopeSection::from_profile(d, {{}}), InputError);
}

/// A long planar slope at β (rising to the left) with a cover `t` deep (vertical) of `cover` soil over a
/// base layer of `base` soil, on bedrock that follows the surface `bedrock` below it: a DSM section.
SlopeSection cover_on_bedrock(double beta, double t, double bedrock, LimitEquilibriumSoil cover,
                              LimitEquilibriumSoil base) {
  SlopeSection s;
  const double L = 300.0;
  s.surface = {{0.0, L * std::tan(beta)}, {L, 0.0}};
  s.x_left = 0.0;
  s.x_right = L;
  s.z_bottom = -bedrock;
  s.layer_materials = {1};
  s.surface_layer_depth = t;
  s.surface_material = 0;
  s.bedrock_depth = bedrock;
  s.soils = {cover, base};
  return s;
}

// A cohesionless cover on a planar slope: every shallow slip surface approaches the infinite-slope
// factor tan φ / tan β (Taylor 1948; the circle search on bedrock must find the flat circles in the
// cover). The circles have a curvature, so their bases are not all at β: 2 %.
TEST(Bishop, CohesionlessCoverOnBedrockGivesTheInfiniteSlopeFactor) {
  const double beta = 35.0 * kDeg, phi = 30.0 * kDeg;
  const auto s = cover_on_bedrock(beta, 3.0, 5.0, {19e3, 0.0, phi}, {23e3, 500e3, 45.0 * kDeg});
  const auto r = bishop_critical_circle(s);
  ASSERT_TRUE(r.admissible());
  EXPECT_NEAR(r.factor, std::tan(phi) / std::tan(beta), 0.02 * std::tan(phi) / std::tan(beta));
}

// With cohesion a circle cannot follow the base of a thin cover: the critical circle is the long flat
// one that touches it, a lens whose mean depth is about 2t/3 (a parabolic segment of sagitta t), so its
// factor is close to the infinite-slope factor of a slab 2t/3 deep, c / (γ (2t/3) sin β cos β) +
// tan φ / tan β, and above the translational slide along the base of the cover, F∞ at depth t (which
// is why sph-slope reports both on a DSM section). Lens estimate ±3 % (the arc is a circle, not a
// parabola, and its ends are not at β). The arc stays above the bedrock and inside the cover (the
// base layer is far stronger).
TEST(Bishop, CohesiveCoverOnBedrockGivesTheLensFactor) {
  const double beta = 45.0 * kDeg, phi = 35.0 * kDeg, gamma = 19e3, c = 20e3, t = 3.0;
  const auto s = cover_on_bedrock(beta, t, 5.0, {gamma, c, phi}, {23e3, 500e3, 45.0 * kDeg});
  const auto r = bishop_critical_circle(s);
  ASSERT_TRUE(r.admissible());
  const double f_inf = c / (gamma * t * std::sin(beta) * std::cos(beta)) + std::tan(phi) / std::tan(beta);
  const double f_lens =
      c / (gamma * (2.0 / 3.0) * t * std::sin(beta) * std::cos(beta)) + std::tan(phi) / std::tan(beta);
  EXPECT_GT(r.factor, f_inf);
  EXPECT_NEAR(r.factor, f_lens, 0.03 * f_lens);
  for (int k = 0; k <= 20; ++k) {
    const double x = r.x_entry + (r.x_exit - r.x_entry) * k / 20.0;
    const double za =
        r.circle.zc - std::sqrt(r.circle.radius * r.circle.radius - (x - r.circle.xc) * (x - r.circle.xc));
    EXPECT_GE(za, s.bottom_at(x) - 1e-6);
    EXPECT_GE(za, surface_at(s.surface, x) - t - 0.05);
  }
  // The same soil in both layers and no bedrock within reach gives the same circle's factor: the layer
  // by depth weighs and resists like the layers by elevation.
  SlopeSection one = s;
  one.soils[1] = one.soils[0];
  EXPECT_NEAR(bishop_factor(one, r.circle).factor, r.factor, 1e-12 * r.factor);
}

// The infinite-slope factor of the cover is the closed form on a plane, and on a slope that steepens
// halfway down its minimum lies on the steep part, at that part's angle.
TEST(InfiniteSlope, CoverFactorIsTheClosedFormAndFindsTheSteepestReach) {
  const double beta = 40.0 * kDeg, phi = 33.0 * kDeg, gamma = 19e3, c = 10e3, t = 2.0;
  auto s = cover_on_bedrock(beta, t, 4.0, {gamma, c, phi}, {23e3, 500e3, 45.0 * kDeg});
  const double f = c / (gamma * t * std::sin(beta) * std::cos(beta)) + std::tan(phi) / std::tan(beta);
  const auto r = infinite_slope_minimum(s);
  EXPECT_NEAR(r.factor, f, 1e-12 * f);
  EXPECT_DOUBLE_EQ(r.window, 10.0 * t);
  const double steep = 50.0 * kDeg;
  s.surface = {{0.0, 0.0}, {150.0, 0.0}};
  s.surface[0][1] = 150.0 * std::tan(beta) + 150.0 * std::tan(steep);
  s.surface[1][1] = 150.0 * std::tan(steep);
  s.surface.push_back({300.0, 0.0});
  const auto k = infinite_slope_minimum(s);
  EXPECT_NEAR(k.angle, steep, 1e-9);
  EXPECT_GT(k.x, 150.0);
  EXPECT_NEAR(k.factor, c / (gamma * t * std::sin(steep) * std::cos(steep)) + std::tan(phi) / std::tan(steep), 1e-9);
  s.surface_layer_depth = 0.0;
  EXPECT_FALSE(std::isfinite(infinite_slope_minimum(s).factor));
}

}  // namespace
}  // namespace geohaz::sph

namespace geohaz::sph {
namespace {

// ---- Pore pressure and seismic coefficients (docs/sph.md, "Pore pressure and seismic coefficients").

// The layered slope of pySlope's validation examples (Bonanno 2022, pyslope/tests/
// test_validation_examples.py), whose reference factors were computed with Rocscience Slide
// (Bishop simplified; 500 slices for the water-table case): a 1 m high 1:1 slope, crest z = 6 m for
// x < 4.5 m, toe z = 5 m from x = 5.5 m, section x ∈ [0, 10] m over a base at z = 0; layers from the
// crest down: 0.5 m of γ = 20 kN/m³, φ′ = 35°, c′ = 0; 0.5 m of 20 kN/m³, 35°, c′ = 2 kPa; below
// z = 5 m, 18 kN/m³, 30°, c′ = 0. Circles centred 2.5 m above the toe (5.5, 7.5) with R = 2 to 5 m.
SlopeSection pyslope_section() {
  SlopeSection s;
  s.surface = {{0.0, 6.0}, {4.5, 6.0}, {5.5, 5.0}, {10.0, 5.0}};
  s.x_left = 0.0;
  s.x_right = 10.0;
  s.z_bottom = 0.0;
  s.layer_tops = {5.0, 5.5};
  s.layer_materials = {2, 1, 0};
  s.soils = {{20e3, 0.0, 35.0 * kDeg}, {20e3, 2e3, 35.0 * kDeg}, {18e3, 0.0, 30.0 * kDeg}};
  return s;
}

// Dry: Slide gives 1.272, 2.266, 3.941, 5.759 for R = 2, 3, 4, 5 m. The tolerance, 5 %.
TEST(BishopWater, DryLayeredSlopeMatchesSlide) {
  const auto s = pyslope_section();
  for (const auto& [R, slide] : {std::pair{2.0, 1.272}, {3.0, 2.266}, {4.0, 3.941}, {5.0, 5.759}}) {
    const auto r = bishop_factor(s, {5.5, 7.5, R}, 2000);
    ASSERT_TRUE(r.admissible()) << R;
    std::printf("dry R = %.0f m: F %.4f  Slide %.3f  (%+.2f %%)\n", R, r.factor, slide, 100.0 * (r.factor / slide - 1));
    EXPECT_NEAR(r.factor, slide, 0.05 * slide) << R;
  }
}

// A water table 0.7 m below the crest, z = 5.3 m, drawn down the face to the toe and along the ground
// in front of it (no ponded water), the same unit weights above and below it (γ_w = 9.81 kN/m³):
// Slide gives 1.602, 2.330, 3.174 for R = 3, 4, 5 m. Slide's default pore pressure below a water
// table is u = γ_w h_w cos²θ ("Hu automatically calculated"), which head_loss_correction implements:
// it matches to 0.1 %; the vertical head γ_w h_w (θ = 45° along the face) gives 2 to 2.5 % less.
// Both against the 5 %.
TEST(BishopWater, WaterTableMatchesSlide) {
  auto s = pyslope_section();
  s.water.phreatic = {{0.0, 5.3}, {5.2, 5.3}, {5.5, 5.0}, {10.0, 5.0}};
  for (bool corrected : {true, false}) {
    s.water.head_loss_correction = corrected;
    for (const auto& [R, slide] : {std::pair{3.0, 1.602}, {4.0, 2.330}, {5.0, 3.174}}) {
      const auto r = bishop_factor(s, {5.5, 7.5, R}, 2000);
      ASSERT_TRUE(r.admissible()) << R;
      std::printf("water table (%s) R = %.0f m: F %.4f  Slide %.3f  (%+.2f %%)\n",
                  corrected ? "u = gw hw cos^2" : "u = gw hw", R, r.factor, slide, 100.0 * (r.factor / slide - 1));
      EXPECT_NEAR(r.factor, slide, (corrected ? 0.01 : 0.05) * slide) << R;
    }
  }
}

// A horizontal water table: θ = 0, the head-loss correction changes nothing.
TEST(BishopWater, HorizontalWaterTableNeedsNoHeadLossCorrection) {
  auto s = pyslope_section();
  s.water.phreatic = {{0.0, 5.2}, {10.0, 5.2}};
  auto t = s;
  t.water.head_loss_correction = true;
  EXPECT_EQ(bishop_factor(t, {5.5, 7.5, 4.0}, 500).factor, bishop_factor(s, {5.5, 7.5, 4.0}, 500).factor);
}

// A slope under still water higher than its crest: the pore pressure on the base, the water's
// weight on the slices and the thrusts at the ends of the ponded water together act as buoyancy, so
// the factor equals the dry factor with the buoyant unit weight γ_sat − γ_w (exact for Bishop's
// method: the hydrostatic pressure on the circle passes through its centre). 1e-3: the slices'
// quadrature of the water's moment against the exact end thrusts.
TEST(BishopWater, SubmergedSlopeIsTheDrySlopeWithBuoyantWeight) {
  const LimitEquilibriumSoil soil{18e3, 5e3, 25.0 * kDeg, 20e3};
  auto wet = slope(10.0, 2.0, 5.0, 25.0, 20.0, soil);
  wet.water.phreatic = {{0.0, 18.0}, {65.0, 18.0}};  // 3 m above the crest
  auto dry = slope(10.0, 2.0, 5.0, 25.0, 20.0, {20e3 - 9.81e3, 5e3, 25.0 * kDeg});
  const SlipCircle c{40.0, 25.0, 20.0};
  const auto a = bishop_factor(wet, c, 2000), b = bishop_factor(dry, c, 2000);
  ASSERT_TRUE(b.admissible());
  EXPECT_NEAR(a.factor, b.factor, 1e-3 * b.factor);
}

// r_u = 0 is dry; r_u raises u on every base in proportion to the overburden, so F falls linearly
// in r_u for φ′ > 0 once the circle is fixed, F(r_u) ≈ m − n r_u (Bishop & Morgenstern 1960): the
// three values are collinear to the fixed-point's tolerance when m_α changes little.
TEST(BishopWater, PorePressureRatioLowersTheFactor) {
  const auto dry = slope(10.0, 2.0, 5.0, 25.0, 20.0, {20e3, 3e3, 19.6 * kDeg});
  const SlipCircle c{38.0, 24.0, 17.0};
  const double F0 = bishop_factor(dry, c).factor;
  auto wet = dry;
  wet.water.ru = 0.0;
  EXPECT_EQ(bishop_factor(wet, c).factor, F0);
  wet.water.ru = 0.25;
  const double F25 = bishop_factor(wet, c).factor;
  wet.water.ru = 0.5;
  const double F50 = bishop_factor(wet, c).factor;
  EXPECT_LT(F25, F0);
  EXPECT_LT(F50, F25);
  EXPECT_NEAR(F25, 0.5 * (F0 + F50), 0.03 * F25);
}

/// Elevation of the slope(10, 2, 5, 25, 20) surface at x, written out for the hand calculation.
double acads_surface(double x) {
  return x <= 25.0 ? 15.0 : (x >= 45.0 ? 5.0 : 15.0 - 0.5 * (x - 25.0));
}

/// A sloping water table (m): 12 m at x = 0, 11 m at the crest edge, down to the toe, then level.
double sloping_water(double x) {
  if (x <= 25.0) return 12.0 - x / 25.0;
  if (x >= 45.0) return 5.0;
  return 11.0 - 6.0 * (x - 25.0) / 20.0;
}

// A hand calculation of one circle with a sloping water table, γ_sat > γ, k_h and k_v, written out
// here independently of the library: 20 000 vertical columns between the circle's entry and exit
// (found by bisection), the column weight split at the water table, u = γ_w h_w, the centroid of the
// weight, and Bishop's fixed point F = Σ [c′b + (V − ub) tan φ′]/m_α / Σ [V sin α + k_h W (z_c − z_g)/R].
// Tolerance 2e-3: the library's 2000 slices against the 20 000 columns.
TEST(BishopWater, PseudoStaticFactorWithWaterTableMatchesAHandCalculation) {
  const double gamma = 18e3, gsat = 20e3, gw = 9.81e3, c = 5e3, phi = 25.0 * kDeg, kh = 0.12, kv = 0.05;
  auto s = slope(10.0, 2.0, 5.0, 25.0, 20.0, {gamma, c, phi, gsat});
  for (double x : {10.0, 30.0, 44.0, 50.0}) ASSERT_DOUBLE_EQ(surface_at(s.surface, x), acads_surface(x));
  s.water.phreatic = {{0.0, 12.0}, {25.0, 11.0}, {45.0, 5.0}, {65.0, 5.0}};
  s.seismic = {kh, kv};
  const double xc = 40.0, zc = 25.0, R = 20.0;
  auto arc = [&](double x) { return zc - std::sqrt(std::max(R * R - (x - xc) * (x - xc), 0.0)); };
  auto depth = [&](double x) { return acads_surface(x) - arc(x); };
  auto root = [&](double out, double in) {
    for (int i = 0; i < 200; ++i) {
      const double m = 0.5 * (out + in);
      (depth(m) > 0.0 ? in : out) = m;
    }
    return 0.5 * (out + in);
  };
  const double x0 = root(xc - R, 30.0), x1 = root(xc + R - 1e-9, 40.0);
  const int n = 20000;
  const double b = (x1 - x0) / n;
  std::vector<double> V(n), W(n), sa(n), ca(n), u(n), arm(n);
  for (int i = 0; i < n; ++i) {
    const double x = x0 + (i + 0.5) * b, zb = arc(x), zt = acads_surface(x), zw = sloping_water(x);
    const double zm = std::clamp(zw, zb, zt);  // saturated below zm, moist above
    const double wsat = gsat * (zm - zb), wm = gamma * (zt - zm);
    W[i] = b * (wsat + wm);
    const double zg = (wsat * 0.5 * (zb + zm) + wm * 0.5 * (zm + zt)) / (wsat + wm);
    V[i] = (1.0 - kv) * W[i];
    sa[i] = (xc - x) / R;
    ca[i] = std::sqrt(1.0 - sa[i] * sa[i]);
    u[i] = gw * std::max(zw - zb, 0.0);
    arm[i] = (zc - zg) / R;
  }
  double drive = 0.0;
  for (int i = 0; i < n; ++i) drive += V[i] * sa[i] + kh * W[i] * arm[i];
  double F = 1.0;
  for (int it = 0; it < 500; ++it) {
    double res = 0.0;
    for (int i = 0; i < n; ++i)
      res += (c * b + (V[i] - u[i] * b) * std::tan(phi)) / (ca[i] + sa[i] * std::tan(phi) / F);
    F = res / drive;
  }
  const auto r = bishop_factor(s, {xc, zc, R}, 2000);
  ASSERT_TRUE(r.admissible());
  EXPECT_NEAR(r.x_entry, x0, 1e-6);
  EXPECT_NEAR(r.factor, F, 2e-3 * F);
  // The same circle dry and without the seismic coefficients is stronger.
  auto d = s;
  d.water = {};
  d.seismic = {};
  EXPECT_GT(bishop_factor(d, {xc, zc, R}, 2000).factor, r.factor);
}

// k_h = 0 (and k_v = 0) is the static analysis, bit for bit; a larger k_h lowers F; F = 1 exactly at
// the yield coefficient k_y the analysis reports, and k_y does not depend on the k_h configured.
TEST(BishopWater, YieldCoefficientMakesTheFactorOne) {
  auto s = slope(10.0, 2.0, 5.0, 25.0, 20.0, {20e3, 10e3, 25.0 * kDeg});
  const SlipCircle c{40.0, 25.0, 20.0};
  const auto base = bishop_factor(s, c);
  s.seismic = {0.0, 0.0};
  EXPECT_EQ(bishop_factor(s, c).factor, base.factor);
  ASSERT_GT(base.factor, 1.0);
  const double ky = base.yield_coefficient;
  ASSERT_GT(ky, 0.0);
  ASSERT_LT(ky, 1.0);
  s.seismic.kh = 0.5 * ky;
  const auto half = bishop_factor(s, c);
  EXPECT_LT(half.factor, base.factor);
  EXPECT_GT(half.factor, 1.0);
  EXPECT_NEAR(half.yield_coefficient, ky, 1e-12);
  s.seismic.kh = ky;
  EXPECT_NEAR(bishop_factor(s, c).factor, 1.0, 1e-6);
  // The critical circle's k_y, and the search for the circle of the smallest k_y: no larger.
  s.seismic = {};
  const auto crit = bishop_critical_circle(s);
  BishopSearchSettings set;
  set.minimise_yield_coefficient = true;
  const auto yc = bishop_critical_circle(s, set);
  EXPECT_LE(yc.yield_coefficient, crit.yield_coefficient + 1e-9);
  s.seismic.kh = yc.yield_coefficient;
  EXPECT_NEAR(bishop_factor(s, yc.circle).factor, 1.0, 1e-6);
}

// Bad water input: r_u outside [0, 1), r_u with a phreatic surface, a water table above the ground
// everywhere, a saturated unit weight below the moist one. Each names its key.
TEST(BishopWater, BadWaterInputNamesTheKey) {
  auto s = slope(10.0, 2.0, 5.0, 25.0, 20.0, {20e3, 3e3, 19.6 * kDeg});
  auto expect_key = [&](const SlopeSection& t, const std::string& key) {
    try {
      t.validate_water("water.");
      ADD_FAILURE() << "no error for " << key;
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), key);
    }
  };
  s.validate_water("water.");
  auto t = s;
  t.water.ru = 1.0;
  expect_key(t, "water.ru");
  t.water.ru = -0.1;
  expect_key(t, "water.ru");
  t = s;
  t.water.phreatic = {{0.0, 20.0}, {65.0, 20.0}};
  expect_key(t, "water.phreatic");
  t.water.phreatic = {{0.0, 10.0}, {65.0, 5.0}};
  t.validate_water("water.");
  t.water.ru = 0.2;
  expect_key(t, "water.ru");
  t = s;
  t.soils[0].saturated_unit_weight = 15e3;
  expect_key(t, "water.saturated_unit_weight");
}

}  // namespace
}  // namespace geohaz::sph
