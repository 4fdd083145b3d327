// The contact laws own their material.* keys (issue #30; contact_laws.hpp `parameters`,
// core/law_parameters.hpp): reader, defaults, refusal of another law's key and help text.
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/dem/config.hpp"

using namespace geohaz;
using namespace geohaz::dem;

namespace {

RunConfig read(const std::string& toml) {
  ConfigReader r = ConfigReader::from_string(toml, "case.toml");
  return read_config(r, false);
}

TEST(ContactParameters, TheLinearLawDerivesItsStiffnessesFromItsKeys) {
  const RunConfig c = read("[material]\ncontact_law = \"linear\"\ncontact_modulus = 1e9\nstiffness_ratio = 2\n");
  const auto& l = std::get<LinearSpringCoulomb>(c.material.law);
  EXPECT_EQ(l.kn, 2e9);
  EXPECT_EQ(l.ks, 1e9);
  const RunConfig d = read("[material]\ncontact_law = \"hertz\"\n");
  EXPECT_EQ(std::get<HertzMindlin>(d.material.law).youngs, HertzMindlin{}.youngs);
  EXPECT_EQ(std::get<HertzMindlin>(d.material.law).poisson, HertzMindlin{}.poisson);
}

TEST(ContactParameters, AKeyOfTheOtherLawExitsTwoNamingIt) {
  for (const auto& [law, key] : {std::pair<std::string, std::string>{"linear", "youngs_modulus"},
                                 {"linear", "poisson_ratio"},
                                 {"hertz", "contact_modulus"},
                                 {"hertz", "stiffness_ratio"}}) {
    try {
      (void)read("[material]\ncontact_law = \"" + law + "\"\n" + key + " = 0.3\n");
      ADD_FAILURE() << key << " accepted for " << law;
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "material." + key);
      EXPECT_NE(e.reason().find("material.contact_law = " + law + " does not use it"), std::string::npos) << e.reason();
    }
  }
}

TEST(ContactParameters, TheHelpListsTheLawThatReadsAKey) {
  ConfigReader d = ConfigReader::describe();
  (void)read_config(d, true);
  bool found = false;
  for (const KeyReference& k : d.reference())
    if (k.key == "material.youngs_modulus") {
      found = true;
      EXPECT_EQ(k.help, "particle Young's modulus (hertz)");
      EXPECT_EQ(k.default_value, "2e+10");
    }
  EXPECT_TRUE(found);
}

}  // namespace
