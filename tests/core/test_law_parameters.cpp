// The parameters a law owns (law_parameters.hpp): the keys of a family of laws, their help text,
// the reading of the chosen law's values and the refusal of another law's key follow each law's
// own declaration, with no table elsewhere.
#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <variant>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/law_parameters.hpp"

namespace {

using geohaz::ConfigReader;
using geohaz::InputError;
using geohaz::ParamProblem;
using geohaz::ParamSpec;
using geohaz::ParamValues;
using geohaz::Range;

constexpr ParamSpec kShared{"mu", 0.2, Range::closed(0.0, 2.0), "1", "friction coefficient μ"};

/// A law whose struct is its parameters (the generic landing through set()).
struct Dry {
  static constexpr const char* name = "dry";
  static constexpr const char* summary = "dry friction";
  static constexpr std::array<ParamSpec, 1> parameters{{kShared}};
  double mu = kShared.def;
  bool set(std::size_t /*j*/, double v) noexcept { return mu = v, true; }
};

/// A law with a derived member (from_parameters) and a rule between its parameters (check).
struct Wet {
  static constexpr const char* name = "wet";
  static constexpr const char* summary = "wet friction";
  static constexpr std::array<ParamSpec, 3> parameters{
      {kShared,
       {"pore", 0.0, Range::closed_open(0.0, 1.0), "1", "pore pressure ratio r_u", "0: dry"},
       {"scale", 1.0, Range::positive(), "m", "length scale L"}}};
  double mu_eff = kShared.def;
  double scale = 1.0;
  bool set(std::size_t j, double v) noexcept {
    if (j == 2) return scale = v, true;
    return false;
  }
  static Wet from_parameters(const ParamValues& v) { return {v["mu"] * (1.0 - v["pore"]), v["scale"]}; }
  static std::optional<ParamProblem> check(const ParamValues& v) {
    if (v["pore"] > 0.5 && v.is_given("mu")) return ParamProblem{"pore", "pore above 0.5 with mu given", "0.6"};
    return std::nullopt;
  }
};

using Family = std::variant<Dry, Wet>;
using Parameters = geohaz::LawParameters<Family>;

TEST(LawParameters, EachKeyOnceWithTheLawsThatReadIt) {
  static_assert(Parameters::consistent());
  const auto keys = Parameters::keys();
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[0].spec.key, "mu");
  EXPECT_EQ(keys[0].laws, (std::vector<std::string_view>{"dry", "wet"}));
  EXPECT_EQ(keys[1].laws, (std::vector<std::string_view>{"wet"}));
  EXPECT_EQ(Parameters::help(keys[0]), "friction coefficient μ (dry, wet)");
  EXPECT_EQ(Parameters::help(keys[1]), "pore pressure ratio r_u (wet; 0: dry)");
  EXPECT_EQ(geohaz::parameter_index<Wet>("scale"), 2);
  EXPECT_EQ(geohaz::parameter_index<Dry>("scale"), -1);
  EXPECT_EQ(Parameters::parameters_of("wet").size(), 3u);
  EXPECT_TRUE(Parameters::parameters_of("none").empty());
}

TEST(LawParameters, TheChosenLawGetsItsValuesAndDefaults) {
  ConfigReader cfg = ConfigReader::from_string("[model]\nmu = 0.5\npore = 0.4\n");
  const Family f = Parameters::read(cfg, {"model.", "model.law", "set model.law"}, "wet");
  EXPECT_DOUBLE_EQ(std::get<Wet>(f).mu_eff, 0.3);
  EXPECT_DOUBLE_EQ(std::get<Wet>(f).scale, 1.0);
  ConfigReader dry = ConfigReader::from_string("[model]\nmu = 0.7\n");
  EXPECT_DOUBLE_EQ(std::get<Dry>(Parameters::read(dry, {"model.", "model.law", ""}, "dry")).mu, 0.7);
  // Every key is declared for the reference (--help-config), with unit and range.
  ConfigReader d = ConfigReader::describe();
  (void)Parameters::read(d, {"model.", "model.law", ""}, "dry");
  const auto refs = d.reference();
  ASSERT_EQ(refs.size(), 3u);
  EXPECT_EQ(refs[2].key, "model.scale");
  EXPECT_EQ(refs[2].unit, "m");
}

TEST(LawParameters, AKeyOfALawNotChosenIsRefusedByName) {
  ConfigReader cfg = ConfigReader::from_string("[model]\npore = 0.1\n", "case.toml");
  try {
    (void)Parameters::read(cfg, {"model.", "model.law", "set model.law"}, "dry");
    FAIL() << "model.pore read for the dry law";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "model.pore");
    EXPECT_EQ(e.file(), "case.toml");
    EXPECT_NE(e.reason().find("model.law = dry does not use it (it belongs to wet"), std::string::npos) << e.reason();
  }
}

TEST(LawParameters, RangesAndTheLawsOwnRulesAreChecked) {
  ConfigReader out = ConfigReader::from_string("[model]\npore = 1.0\n");
  EXPECT_THROW((void)Parameters::read(out, {"model.", "model.law", ""}, "wet"), InputError);
  ConfigReader rule = ConfigReader::from_string("[model]\nmu = 0.3\npore = 0.6\n");
  try {
    (void)Parameters::read(rule, {"model.", "model.law", ""}, "wet");
    FAIL() << "the law's check was not applied";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "model.pore");
    EXPECT_EQ(e.reason(), "pore above 0.5 with mu given");
  }
  // Without mu given the rule holds (given, not the value, is what it looks at).
  ConfigReader fine = ConfigReader::from_string("[model]\npore = 0.6\n");
  EXPECT_NO_THROW((void)Parameters::read(fine, {"model.", "model.law", ""}, "wet"));
}

/// A law whose second parameter defaults to the value read for its first.
struct Softening {
  static constexpr const char* name = "softening";
  static constexpr const char* summary = "softening friction";
  static constexpr std::array<ParamSpec, 2> parameters{
      {kShared, {"residual_mu", 0.0, Range::non_negative(), "1", "residual μ", "default: mu", "mu"}}};
  double mu = kShared.def, residual = kShared.def;
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? mu : residual) = v, true; }
};
using SofteningFamily = std::variant<Dry, Softening>;
using SofteningParameters = geohaz::LawParameters<SofteningFamily>;

TEST(LawParameters, ADefaultCanBeTheValueOfAnEarlierKey) {
  ConfigReader cfg = ConfigReader::from_string("[model]\nmu = 0.6\n");
  const auto s = std::get<Softening>(SofteningParameters::read(cfg, {"model.", "model.law", ""}, "softening"));
  EXPECT_DOUBLE_EQ(s.residual, 0.6);
  ConfigReader given = ConfigReader::from_string("[model]\nmu = 0.6\nresidual_mu = 0.4\n");
  EXPECT_DOUBLE_EQ(
      std::get<Softening>(SofteningParameters::read(given, {"model.", "model.law", ""}, "softening")).residual, 0.4);
}

TEST(LawParameters, AFamilyMayAcceptTheKeysOfOtherLaws) {
  // The SPH [[material]] tables: a soil's strength stays in the file when the model is switched.
  ConfigReader cfg = ConfigReader::from_string("[model]\nresidual_mu = 0.1\n");
  const geohaz::LawKeys keys{"model.", "model.law", "", false};
  const ParamValues v = SofteningParameters::read_values(cfg, keys, "dry");
  ASSERT_EQ(v.value.size(), 1u);
  EXPECT_DOUBLE_EQ(v["mu"], 0.2);
  EXPECT_FALSE(v.is_given("mu"));
}

}  // namespace
