// Where the single block's rolling starts (issue #19, validation, ≈ 1 min): the bonded 4 m block of
// SingleBlockOutlineResolution (R = 0.4 m, 10 packings) rests on the 40° slope on a few discs of its
// irregular outline, held by the support wall. A block sliding with friction μ keeps its base on
// the slope only if the normal reaction can sit where it balances the friction moment about the
// centre: N a = μ N h, i.e. a = μ h ≤ the front of its support (a measured downhill from the centre,
// h the centre's height above the slope). A rigid square has front/h = 1 > μ = 0.5 and slides; a
// packing whose support ends short of μ h must tip over while it slides. Reported in
// docs/validation/dem.md ("Where the rolling starts").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "geohaz/dem/experiments.hpp"
#include "rigid_body.hpp"
#include "single_block.hpp"

using namespace geohaz;
using namespace geohaz::dem;
using namespace geohaz::dem::rigid;

TEST(DemBlockSupport, BlocksWhoseSupportEndsShortOfMuHTumbleFromRelease) {
  constexpr double kPi = std::numbers::pi;
  const double mu = 0.5;
  std::vector<double> turns_short, turns_long;
  for (int seed = 1; seed <= 10; ++seed) {
    // The block of SingleBlockOutlineResolution at R = 0.4 m (test_dem_validation.cpp): the example's
    // contact law and terrain, μ_r = 0.1 on discs and terrain, bonds 200 MPa, no joints.
    AvalancheSpec a;
    a.packing.r_min = 0.75 * 0.4;
    a.packing.r_max = 1.25 * 0.4;
    a.packing.porosity = 0.18;
    a.packing.locked_in_stress = 0;
    a.packing.seed = static_cast<std::uint64_t>(seed);
    a.packing.expansion_steps = 2000;
    a.packing.max_relax_steps = 6000;
    a.material.law = LinearSpringCoulomb{4e8, 4e8 / 2.5};
    a.material.contact.friction = mu;
    a.material.contact.rolling_friction = 0.1;
    a.material.contact.restitution = 0.3;
    a.material.bond.modulus = 2e8;
    a.material.bond.tensile_strength = a.material.bond.shear_strength = 200e6;
    a.material.bond.tensile_strength_std = a.material.bond.shear_strength_std = 0;
    a.material.joint_friction = 0.4;
    a.strength_factor = 1.0;
    a.runout_time = 300;
    a.record_interval = 0.25;
    a.terrain_friction = mu;
    a.terrain_restitution = 0.3;
    a.terrain_rolling_friction = 0.1;
    const auto [H0, along, up] = block_scene::place_on_40_degree_slope(a);
    DemSolver s;
    // Support at the end of settling: the discs within 5 cm of the slope, their downhill extent
    // from the block's centre, and the centre's height above the slope.
    double front = -1e9, height = 0;
    int touching = 0;
    const auto observe = [&](const DemSolver& sv, const std::string& phase) {
      if (phase != "settling") return;
      const RigidState g = rigid_state(sv);
      height = (g.centre - Vec2(0, H0)).dot(up);
      front = -1e9;
      touching = 0;
      const auto& x = sv.discs.get<Position<2>>();
      const auto& R = sv.discs.get<Radius>();
      for (std::size_t i = 0; i < sv.discs.size(); ++i)
        if ((x[i] - Vec2(0, H0)).dot(up) < R[i] + 0.05) {
          front = std::max(front, (x[i] - g.centre).dot(along));
          ++touching;
        }
    };
    const AvalancheResult r = run_avalanche(a, s, observe);
    double turns = 0;
    for (const double phi : s.discs.get<Rotation>()) turns += phi;
    turns /= 2 * kPi * static_cast<double>(s.discs.size());
    const double angle = std::atan(r.quantiles.back().h_over_l) * 180 / kPi;
    std::printf(
        "seed %d: %d discs on the slope, support front %.2f m, centre height %.2f m, front/h %.2f (mu %.1f); "
        "Fahrboeschung %.1f deg, centre of mass %.1f deg, %.1f turns\n",
        seed, touching, touching ? front : 0.0, height, touching ? front / height : -1.0, mu, angle,
        std::atan(r.com_h_over_l) * 180 / kPi, turns);
    std::fflush(stdout);
    (touching > 0 && front >= mu * height ? turns_long : turns_short).push_back(std::abs(turns));
  }
  auto mean = [](const std::vector<double>& v) {
    double m = 0;
    for (const double x : v) m += x / static_cast<double>(v.size());
    return m;
  };
  std::printf("support front >= mu h: %zu blocks, mean %.1f turns; shorter: %zu blocks, mean %.1f turns\n",
              turns_long.size(), mean(turns_long), turns_short.size(), mean(turns_short));
  ASSERT_FALSE(turns_long.empty());
  ASSERT_FALSE(turns_short.empty());
  // The blocks that must tip while sliding roll more than those that can slide on their base.
  EXPECT_GT(mean(turns_short), 1.5 * mean(turns_long));
}
