#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"

namespace geohaz {
namespace {

const char* kToml = R"(
# a slope
[material]
density = 1800.0
cohesion = 0          # integers are accepted as numbers
model = "drucker_prager"

[[layer]]
top = 1.0
c = 5e3
[[layer]]
top = 0.5
c = 1e4
)";

// Read the keys the example uses, as an app would.
void read_all(ConfigReader& r) {
  r.get("material.density", 2000.0, Range::positive(), {"kg/m^3", "density"});
  r.get("material.cohesion", 0.0, Range::non_negative(), {"Pa", "cohesion"});
  r.get_choice("material.model", "elastic", {"elastic", "drucker_prager"}, {"", "constitutive model"});
  for (auto& l : r.tables("layer", {"", "soil layers"})) {
    l.get("top", 0.0, Range{}, {"m", "top elevation"});
    l.get("c", 0.0, Range::non_negative(), {"Pa", "cohesion"});
  }
}

TEST(Config, ReadsTypedValuesAndArraysOfTables) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  EXPECT_DOUBLE_EQ(r.get("material.density", 0.0, Range::positive(), {"kg/m^3", ""}), 1800.0);
  EXPECT_DOUBLE_EQ(r.get("material.cohesion", 7.0, Range::non_negative(), {"Pa", ""}), 0.0);
  EXPECT_DOUBLE_EQ(r.get("material.friction", 30.0, Range::closed(0, 90), {"deg", ""}), 30.0);  // default
  auto layers = r.tables("layer", {"", ""});
  ASSERT_EQ(layers.size(), 2u);
  EXPECT_DOUBLE_EQ(layers[1].get("c", 0.0, Range{}, {"Pa", ""}), 1e4);
}

TEST(Config, UnknownKeyIsNamedWithTheValidOnes) {
  auto r = ConfigReader::from_string(std::string(kToml) + "\n[extra]\nfoo = 1\n", "slope.toml");
  read_all(r);
  try {
    r.finish();
    FAIL() << "unknown key accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "extra.foo");
    EXPECT_EQ(e.file(), "slope.toml");
    EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos);
  }
  auto r2 = ConfigReader::from_string("[material]\ndensty = 1800\n", "slope.toml");
  read_all(r2);
  try {
    r2.finish();
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.key(), "material.densty");
    EXPECT_NE(msg.find("density"), std::string::npos) << msg;  // lists the valid keys beside it
    EXPECT_NE(msg.find("cohesion"), std::string::npos) << msg;
  }
}

TEST(Config, UnknownKeyInsideArrayOfTables) {
  auto r = ConfigReader::from_string("[[layer]]\ntop = 1\nphi = 30\n", "x.toml");
  read_all(r);
  try {
    r.finish();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "layer[0].phi");
  }
}

TEST(Config, AllKnownKeysPassFinish) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  read_all(r);
  EXPECT_NO_THROW(r.finish());
}

TEST(Config, WrongTypeNamesKeyAndValue) {
  auto r = ConfigReader::from_string("[material]\ndensity = \"heavy\"\n", "s.toml");
  try {
    r.get("material.density", 1.0, Range::positive(), {"kg/m^3", ""});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material.density");
    EXPECT_EQ(e.value(), "heavy");
    EXPECT_NE(std::string(e.what()).find("expected a number"), std::string::npos);
  }
  auto r2 = ConfigReader::from_string("n = 2.5\n", "s.toml");
  EXPECT_THROW(r2.get_int("n", 1, Range::positive(), {"1", ""}), InputError);
}

TEST(Config, OutOfRangeNamesTheRange) {
  auto r = ConfigReader::from_string("[material]\nfriction_angle = 95\n", "s.toml");
  try {
    r.get("material.friction_angle", 30.0, Range::closed_open(0, 90), {"deg", ""});
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("[0, 90)"), std::string::npos) << msg;
    EXPECT_NE(msg.find("deg"), std::string::npos) << msg;
    EXPECT_EQ(e.value(), "95");
  }
  auto r2 = ConfigReader::from_string("x = -1.0\n", "s.toml");
  EXPECT_THROW(r2.get("x", 1.0, Range::positive(), {"m", ""}), InputError);
  auto r3 = ConfigReader::from_string("x = nan\n", "s.toml");
  EXPECT_THROW(r3.get("x", 1.0, Range{}, {"m", ""}), InputError);  // NaN is never in range
}

TEST(Config, MissingRequiredKeyAndFile) {
  auto r = ConfigReader::from_string("", "s.toml");
  EXPECT_THROW(r.require("geometry.height", Range::positive(), {"m", "slope height"}), InputError);
  try {
    ConfigReader::from_file("/nonexistent/dir/slope.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/slope.toml");
  }
}

TEST(Config, SyntaxErrorGivesLine) {
  try {
    ConfigReader::from_string("a = 1\nb = = 2\n", "bad.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
}

TEST(Config, ChoiceListsTheAllowedValues) {
  auto r = ConfigReader::from_string("model = \"mohr\"\n", "s.toml");
  try {
    r.get_choice("model", "elastic", {"elastic", "drucker_prager"}, {"", ""});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("elastic|drucker_prager"), std::string::npos);
  }
}

TEST(Config, OverridesReplaceAndCreateKeys) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  r.apply_override("material.density=2100");
  r.apply_override("material.model = elastic");   // bare word → string
  r.apply_override("run.duration=2.5");           // new table
  r.apply_override("layer[1].c=3e3");             // element of an array of tables
  EXPECT_DOUBLE_EQ(r.get("material.density", 0.0, Range::positive(), {"", ""}), 2100.0);
  EXPECT_EQ(r.get_string("material.model", "", {"", ""}), "elastic");
  EXPECT_DOUBLE_EQ(r.get("run.duration", 0.0, Range::positive(), {"s", ""}), 2.5);
  EXPECT_DOUBLE_EQ(r.tables("layer", {"", ""})[1].get("c", 0.0, Range{}, {"", ""}), 3e3);
  EXPECT_THROW(r.apply_override("no_equals_sign"), InputError);
  EXPECT_THROW(r.apply_override("layer[5].c=1"), InputError);
}

TEST(Config, ResolvedConfigHoldsDefaultsAndParsesBack) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  read_all(r);
  r.get("run.duration", 8.0, Range::positive(), {"s", ""});
  const std::string text = r.resolved();
  auto back = ConfigReader::from_string(text, "resolved.toml");
  EXPECT_DOUBLE_EQ(back.get("run.duration", 0.0, Range{}, {"", ""}), 8.0);
  EXPECT_DOUBLE_EQ(back.get("material.density", 0.0, Range{}, {"", ""}), 1800.0);
  EXPECT_EQ(back.tables("layer", {"", ""}).size(), 2u);
}

TEST(Config, DescribeModeBuildsTheReference) {
  auto d = ConfigReader::describe();
  read_all(d);
  d.require("geometry.height", Range::positive(), {"m", "slope height"});
  const auto refs = d.reference();
  ASSERT_GE(refs.size(), 6u);
  bool found_layer = false, found_height = false;
  for (const auto& k : refs) {
    if (k.key == "layer[].c") found_layer = k.unit == "Pa";
    if (k.key == "geometry.height") found_height = k.default_value == "(required)" && k.range == "(0, inf)";
  }
  EXPECT_TRUE(found_layer);
  EXPECT_TRUE(found_height);
  EXPECT_NE(ConfigReader::format_reference(refs).find("slope height"), std::string::npos);
}

TEST(App, ExitCodesFollowTheErrorKind) {
  EXPECT_EQ(run_main("t", [] { return 0; }), kExitOk);
  EXPECT_EQ(run_main("t", []() -> int { throw InputError("bad", "f.toml", "k", "v"); }), kExitInputError);
  EXPECT_EQ(run_main("t", []() -> int { throw SimulationError("NaN at particle 3"); }), kExitFailure);
  EXPECT_EQ(run_main("t", []() -> int { throw std::runtime_error("disk full"); }), kExitFailure);
}

TEST(App, CommandLineErrorsAreInputErrors) {
  boost::program_options::options_description desc;
  CommonOptions o;
  add_common_options(desc, o, "out");
  const char* argv[] = {"app", "--no-such-option"};
  EXPECT_THROW(parse_command_line(2, argv, "app", "", desc), InputError);
  const char* argv2[] = {"app", "--threads", "two"};
  EXPECT_THROW(parse_command_line(3, argv2, "app", "", desc), InputError);
  const char* argv3[] = {"app", "--set", "a.b=1", "--set", "c=2", "--quiet"};
  EXPECT_TRUE(parse_command_line(6, argv3, "app", "", desc));
  EXPECT_EQ(o.set.size(), 2u);
  EXPECT_TRUE(o.quiet);
  EXPECT_THROW(setup_threads(-1), InputError);
}

TEST(InputError, MessageCarriesContext) {
  InputError e("must be positive", "run.toml", "duration", "-3");
  EXPECT_EQ(std::string(e.what()), "run.toml: 'duration' = '-3': must be positive");
  EXPECT_EQ(e.reason(), "must be positive");
}

}  // namespace
}  // namespace geohaz
