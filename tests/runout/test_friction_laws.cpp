// The basal laws own their coefficients (issue #30; friction/*.hpp, core/law_parameters.hpp): the
// reader, the refusal of another law's key, the friction zones and the report's labels follow each
// law's `parameters`, and the struct defaults are the declared ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <variant>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/runout/config.hpp"
#include "geohaz/runout/processes.hpp"

using namespace geohaz;
using namespace geohaz::runout;

namespace {

/// The law a config with only model.friction = name reads.
BasalFriction read_law(const std::string& name, const std::string& extra = "") {
  ConfigReader cfg = ConfigReader::from_string("[model]\nfriction = \"" + name + "\"\n" + extra, "case.toml");
  return read_config(cfg).params.friction;
}

TEST(FrictionLaws, TheStructDefaultsAreTheDeclaredOnes) {
  const auto manning = std::get<ModifiedManningFriction>(read_law("manning"));
  EXPECT_EQ(manning.n, ModifiedManningFriction{}.n);
  EXPECT_EQ(manning.i_cr, ModifiedManningFriction{}.i_cr);
  EXPECT_EQ(manning.m, ModifiedManningFriction{}.m);
  const auto vc = std::get<VoellmyCohesionFriction>(read_law("voellmy_cohesion"));
  EXPECT_EQ(vc.mu, VoellmyCohesionFriction{}.mu);
  EXPECT_EQ(vc.xi, VoellmyCohesionFriction{}.xi);
  EXPECT_EQ(vc.cohesion, VoellmyCohesionFriction{}.cohesion);
  const auto hb = std::get<HerschelBulkleyFriction>(read_law("herschel_bulkley"));
  EXPECT_EQ(hb.consistency, HerschelBulkleyFriction{}.consistency);
  EXPECT_EQ(hb.flow_index, HerschelBulkleyFriction{}.flow_index);
  const auto oj = std::get<OBrienJulienFriction>(read_law("obrien_julien"));
  EXPECT_EQ(oj.tau_y, OBrienJulienFriction{}.tau_y);
  EXPECT_EQ(oj.viscosity, OBrienJulienFriction{}.viscosity);
  EXPECT_EQ(oj.laminar_k, OBrienJulienFriction{}.laminar_k);
  EXPECT_EQ(oj.n_td, OBrienJulienFriction{}.n_td);
  // Pouliquen's angles are declared in degrees (to 0.01°) and held as tangents: the struct's
  // published tangents and the declared degrees agree to that rounding (5e-3° ≈ 1e-4 in tan).
  const auto pf = std::get<PouliquenForterreFriction>(read_law("pouliquen"));
  EXPECT_NEAR(pf.tan_delta1, PouliquenForterreFriction{}.tan_delta1, 1e-4);
  EXPECT_NEAR(pf.tan_delta2, PouliquenForterreFriction{}.tan_delta2, 1e-4);
  EXPECT_EQ(pf.length, PouliquenForterreFriction{}.length);
  EXPECT_EQ(pf.beta, PouliquenForterreFriction{}.beta);
}

TEST(FrictionLaws, EveryKeyOfAnotherLawIsRefusedNamingIt) {
  for (const auto& key : BasalFrictionParameters::keys())
    for (const std::string& law : BasalFrictionNames::choices()) {
      if (std::find(key.laws.begin(), key.laws.end(), law) != key.laws.end()) continue;
      const std::string k = "model." + std::string(key.spec.key);
      try {
        (void)read_law(law, std::string(key.spec.key) + " = " + std::to_string(key.spec.def) + "\n");
        ADD_FAILURE() << k << " accepted for " << law;
      } catch (const InputError& e) {
        EXPECT_EQ(e.key(), k);
        EXPECT_NE(e.reason().find("does not use it"), std::string::npos) << e.reason();
      }
    }
}

TEST(FrictionLaws, TheReportLabelsAreTheDeclaredMeanings) {
  const auto keys = friction_keys("herschel_bulkley");
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[0].key, "model.tau_y");
  EXPECT_EQ(keys[0].label, "yield stress τ_y");
  EXPECT_EQ(keys[0].unit, "Pa");
  EXPECT_EQ(keys[2].label, "flow index n of τ = τ_y + K γ̇^n");
  EXPECT_TRUE(friction_keys("no_such_law").empty());
  const auto mu = case_key("model.mu");
  ASSERT_TRUE(mu.has_value());
  EXPECT_EQ(mu->label, "Coulomb friction coefficient μ");
}

TEST(FrictionLaws, EveryZoneSlotIsACoefficientOfALawWithItsDeclaredRange) {
  for (int k = 0; k < kFrictionParameters; ++k) {
    const ParamSpec& s = zone_parameter(k);
    EXPECT_EQ(s.key, kFrictionParameterNames[static_cast<std::size_t>(k)]);
    bool some = false;
    for (const std::string& law : BasalFrictionNames::choices())
      some = some || has_parameter(*BasalFrictionNames::from_name(law), k);
    EXPECT_TRUE(some) << s.key;
  }
  EXPECT_EQ(zone_parameter(kDelta1).unit, "deg");
  EXPECT_FALSE(zone_parameter(kVoellmyXi).range.contains(0.0));
  // A zone's δ₁ in degrees lands as its tangent, as model.delta1 does.
  PouliquenForterreFriction pf;
  ASSERT_TRUE(set_parameter(pf, kDelta1, 30.0));
  EXPECT_DOUBLE_EQ(pf.tan_delta1, std::tan(std::numbers::pi / 6.0));
  OBrienJulienFriction oj;
  EXPECT_FALSE(set_parameter(oj, kCohesion, 1.0));
}

}  // namespace
