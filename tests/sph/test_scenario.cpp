// Unit tests of the scenario builders (scenario.hpp) and diagnostics (diagnostics.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "geohaz/core/errors.hpp"
#include "geohaz/sph/diagnostics.hpp"
#include "geohaz/sph/scenario.hpp"

namespace geohaz::sph {
namespace {

TEST(Scenario, SlopeParticleCountAndMass) {
  SlopeGeometry g;
  g.height = 0.2;
  g.gradient = 1.0;
  g.crest_length = 0.2;
  g.front_length = 0.2;
  g.base_thickness = 0.04;
  const double dx = 0.01;
  auto sc = build_profile<2>(g.profile(), dx, {2000.0}, 1.2);
  // Area: base 0.6·0.04 + crest 0.2·0.2 + face ½·0.2·0.2 = 0.084 m² → 840 particles (staircase face
  // makes the count exact only to within the face's row count, 20).
  EXPECT_NEAR(static_cast<double>(sc.soil_count), 840.0, 20.0);
  double mass = 0.0;
  const auto& k = sc.store.get<ParticleKind>();
  for (std::size_t i = 0; i < sc.store.size(); ++i)
    if (k[i] == 0) mass += sc.store.get<Mass>()[i];
  EXPECT_NEAR(mass, 2000.0 * dx * dx * static_cast<double>(sc.soil_count), 1e-9);
  EXPECT_GT(sc.boundary_count, 0u);
  EXPECT_DOUBLE_EQ(g.toe_x(), 0.4);
}

TEST(Scenario, LayersByElevation) {
  ProfileDomain d;
  d.surface = {{0.0, 0.3}, {0.2, 0.3}};
  d.x_right = 0.2;
  d.layer_tops = {0.1, 0.2};
  d.layer_materials = {0, 2, 1};
  auto sc = build_profile<2>(d, 0.01, {1000.0, 1500.0, 2000.0}, 1.2);
  const auto& x = sc.store.get<Position<2>>();
  const auto& m = sc.store.get<MaterialId>();
  const auto& k = sc.store.get<ParticleKind>();
  for (std::size_t i = 0; i < sc.store.size(); ++i) {
    if (k[i] != 0) continue;
    const int expect = x[i][1] < 0.1 ? 0 : (x[i][1] < 0.2 ? 2 : 1);
    EXPECT_EQ(m[i], expect);
    EXPECT_DOUBLE_EQ(sc.store.get<Density>()[i], expect == 0 ? 1000.0 : (expect == 2 ? 2000.0 : 1500.0));
  }
  d.layer_materials = {0, 5, 1};
  EXPECT_THROW(build_profile<2>(d, 0.01, {1000.0, 1500.0, 2000.0}, 1.2), InputError);
}

// DSM sections on a mountainside: with bedrock_depth the soil is a cover of that depth resting on
// boundary particles that follow the surface, so the particle count scales with length × depth,
// not with the relief, and the geostatic loading height is the cover depth.
TEST(Scenario, BedrockCoverFollowsTheSurface) {
  ProfileDomain d;
  d.surface = {{0.0, 60.0}, {100.0, 0.0}};  // a 31° slope, 60 m of relief
  d.x_left = 0.0;
  d.x_right = 100.0;
  d.z_bottom = -10.0;
  d.layer_materials = {0};
  d.surface_layer_depth = 2.0;
  d.surface_material = 1;
  d.bedrock_depth = 4.0;
  const double dx = 0.5;
  auto sc = build_profile<2>(d, dx, {2200.0, 1800.0}, 1.2);
  const auto& x = sc.store.get<Position<2>>();
  const auto& m = sc.store.get<MaterialId>();
  const auto& k = sc.store.get<ParticleKind>();
  std::size_t soil = 0;
  for (std::size_t i = 0; i < sc.store.size(); ++i) {
    const double zs = 60.0 - 0.6 * x[i][0];
    if (k[i] != 0) {
      if (x[i][0] > 0.0 && x[i][0] < 100.0) {
        EXPECT_LT(x[i][1], zs - 4.0 + 1e-9);  // bedrock below the cover
      }
      continue;
    }
    ++soil;
    EXPECT_GT(x[i][1], zs - 4.0 - 1e-9);
    EXPECT_LT(x[i][1], zs);
    EXPECT_EQ(m[i], x[i][1] > zs - 2.0 ? 1 : 0);  // 2 m soil over 2 m base
  }
  EXPECT_EQ(soil, sc.soil_count);
  EXPECT_NEAR(static_cast<double>(soil), 100.0 * 4.0 / (dx * dx), 0.02 * 100.0 * 4.0 / (dx * dx));
  EXPECT_DOUBLE_EQ(sc.reference_height, 4.0);
}

TEST(Scenario, UpperCutRemovesSoil) {
  SlopeGeometry g;
  const auto full = build_profile<2>(g.profile(), 0.01, {1800.0}, 1.2);
  g.cut_depth = 0.05;
  g.cut_gradient = 2.0;
  const auto cut = build_profile<2>(g.profile(), 0.01, {1800.0}, 1.2);
  // Removed wedge: between the 1.5:1 face and the 2:1 cut over 0.05 m depth: ½·0.05·(2 − 1.5)·0.05 m².
  const double removed = 0.5 * 0.05 * 0.05 * 0.5;
  EXPECT_NEAR(static_cast<double>(full.soil_count - cut.soil_count), removed / 1e-4, 4.0);
  g.cut_depth = 0.3;
  EXPECT_THROW(g.profile(), InputError);
}

TEST(Scenario, PilesIn3DAndRejectedIn2D) {
  SlopeGeometry g;
  auto d = g.profile();
  d.width = 0.1;
  d.piles = {{0.5, 0.05, 0.04}};
  auto sc = build_profile<3>(d, 0.01, {1800.0}, 1.2);
  std::size_t piles = 0;
  for (auto k : sc.store.get<ParticleKind>()) piles += k == static_cast<std::uint8_t>(Kind::Pile);
  EXPECT_GT(piles, 10u);
  EXPECT_TRUE(sc.periodic.axis[1]);
  EXPECT_NEAR(sc.periodic.hi[1] - sc.periodic.lo[1], 0.1, 1e-12);
  EXPECT_THROW(build_profile<2>(d, 0.01, {1800.0}, 1.2), InputError);
  d.piles.clear();
  d.width = 0.03;  // narrower than 4h
  EXPECT_THROW(build_profile<3>(d, 0.01, {1800.0}, 1.2), InputError);
}

/// The blocks a scenario built by shares keeps (BuildShare, a rank's share of a distributed run)
/// are the consecutive blocks of the whole scenario, field for field (the block the decomposition's
/// scatter keeps), with the whole scenario's counts; count_only keeps none; visit sees every particle.
template <int Dim>
void expect_shares_join_to_whole(const ProfileDomain& d, int parts) {
  const auto whole = build_profile<Dim>(d, 0.01, {1800.0}, 1.2);
  std::size_t at = 0;
  for (int p = 0; p < parts; ++p) {
    const auto part = build_profile<Dim>(d, 0.01, {1800.0}, 1.2, BuildShare<Dim>{p, parts, false, {}});
    EXPECT_EQ(part.soil_count, whole.soil_count);
    EXPECT_EQ(part.boundary_count, whole.boundary_count);
    EXPECT_EQ(part.structures.size(), whole.structures.size());
    const std::size_t n = whole.store.size();
    EXPECT_EQ(part.store.size(), n * (p + 1) / parts - n * p / parts);
    for (std::size_t i = 0; i < part.store.size(); ++i, ++at) {
      ASSERT_EQ(part.store.template get<ParticleId>()[i], whole.store.template get<ParticleId>()[at]);
      ASSERT_EQ(part.store.template get<Position<Dim>>()[i], whole.store.template get<Position<Dim>>()[at]);
      ASSERT_EQ(part.store.template get<Mass>()[i], whole.store.template get<Mass>()[at]);
      ASSERT_EQ(part.store.template get<ParticleKind>()[i], whole.store.template get<ParticleKind>()[at]);
      ASSERT_EQ(part.store.template get<StructureId>()[i], whole.store.template get<StructureId>()[at]);
      ASSERT_EQ(part.store.template get<LayerNormal<Dim>>()[i], whole.store.template get<LayerNormal<Dim>>()[at]);
    }
  }
  EXPECT_EQ(at, whole.store.size());
  std::size_t seen = 0, soil = 0;
  const auto none =
      build_profile<Dim>(d, 0.01, {1800.0}, 1.2, BuildShare<Dim>{0, 1, true, [&](const Vec<Dim>&, Kind k) {
                                                                   ++seen;
                                                                   soil += k == Kind::Soil;
                                                                 }});
  EXPECT_EQ(none.store.size(), 0u);
  EXPECT_EQ(seen, whole.store.size());
  std::size_t whole_soil = 0;  // soil_count also counts the piles' particles (made with the soil columns)
  for (const auto k : whole.store.template get<ParticleKind>())
    whole_soil += k == static_cast<std::uint8_t>(Kind::Soil);
  EXPECT_EQ(soil, whole_soil);
}

TEST(Scenario, SharesOfAScenarioAreTheBlocksOfTheWhole) {
  SlopeGeometry g;
  auto d = g.profile();
  expect_shares_join_to_whole<2>(d, 3);
  d.width = 0.06;
  d.piles = {{0.5, 0.03, 0.03}};
  expect_shares_join_to_whole<3>(d, 4);
  const auto biax = build_biaxial<2>({}, 0.005, 1800.0, 1.2);
  const auto half = build_biaxial<2>({}, 0.005, 1800.0, 1.2, BuildShare<2>{1, 2, false, {}});
  EXPECT_EQ(half.soil_count, biax.soil_count);
  ASSERT_EQ(half.store.size(), biax.store.size() - biax.store.size() / 2);
  EXPECT_EQ(half.store.get<Position<2>>()[0], biax.store.get<Position<2>>()[biax.store.size() / 2]);
}

TEST(Diagnostics, FrontSurfaceSlipAndFailedMass) {
  ProfileDomain d;
  d.surface = {{0.0, 0.1}, {0.1, 0.1}, {0.1, 0.0}, {0.5, 0.0}};
  d.x_right = 0.5;
  d.right = WallType::None;
  auto sc = build_profile<2>(d, 0.01, {2000.0}, 1.2);
  auto& S = sc.store;
  DiagnosticFrame f;
  f.toe_x = 0.1;
  f.base_length = 0.1;
  f.base_top = 0.0;
  f.spacing = 0.01;
  auto r = series_row(S, f);
  EXPECT_NEAR(r.front, 0.1, 1e-12);
  EXPECT_NEAR(r.runout, 0.0, 1e-12);
  // Move the top-right 3×3 block of particles 0.05 m to the right and 0.07 m down (still ≥ 2 layers).
  auto& x = S.get<Position<2>>();
  auto& u = S.get<Displacement<2>>();
  for (std::size_t i = 0; i < S.size(); ++i)
    if (S.get<ParticleKind>()[i] == 0 && x[i][0] > 0.07 && x[i][1] > 0.07) {
      const Vec2 du(0.05, -0.07);
      x[i] += du;
      u[i] = du;
    }
  r = series_row(S, f);
  EXPECT_NEAR(r.front, 0.15, 1e-9);
  EXPECT_NEAR(r.normalised_runout, 0.5, 1e-9);
  // A fixed physical front thickness replaces 2Δx: the moved block is 0.03 m thick.
  f.front_thickness = 0.025;
  EXPECT_NEAR(series_row(S, f).front, 0.15, 1e-9);
  f.front_thickness = 0.035;
  EXPECT_NEAR(series_row(S, f).front, 0.1, 1e-9);
  f.front_thickness = 0.0;
  const auto fm = failed_mass(S, {2000.0}, 0.01);
  EXPECT_EQ(fm.count, 9u);
  EXPECT_NEAR(fm.volume, 9e-4, 1e-12);
  const auto slip = slip_surface(S, 0.01, 0.01);
  ASSERT_EQ(slip.size(), 3u);
  for (const auto& p : slip) EXPECT_NEAR(p[1], 0.07, 1e-9);
  const auto surf = free_surface(S, 0.01);
  EXPECT_NEAR(surf.front()[1], 0.1, 1e-9);
}

}  // namespace
}  // namespace geohaz::sph
