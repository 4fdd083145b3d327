// The constitutive models own their [[material]] keys (issue #30; constitutive.hpp `parameters`,
// core/law_parameters.hpp): the reader, the defaults, the models' rules and the help text follow
// each model's declaration; the strength reduction is a member of the model (reduce_strength).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/constitutive.hpp"
#include "geohaz/sph/run.hpp"
#include "geohaz/sph/summary_keys.hpp"

using namespace geohaz;
using namespace geohaz::sph;

namespace {

RunConfig read(const std::string& toml) {
  ConfigReader r = ConfigReader::from_string(toml, "case.toml");
  return read_config(r, false);
}

constexpr double kDegree = std::numbers::pi / 180.0;

TEST(MaterialParameters, EachModelsKeysLandInTheMaterial) {
  const RunConfig c = read(
      "[model]\nconstitutive = \"drucker_prager_softening\"\n[[material]]\ncohesion = 5e3\nfriction = 35\n"
      "dilatancy = 5\nresidual_friction = 25\nsoftening_strain = 0.1\n");
  ASSERT_EQ(c.materials.size(), 1u);
  const MaterialParams& p = c.materials[0];
  EXPECT_EQ(p.cohesion, 5e3);
  EXPECT_DOUBLE_EQ(p.friction, 35 * kDegree);
  EXPECT_DOUBLE_EQ(p.dilatancy, 5 * kDegree);
  EXPECT_EQ(p.residual_cohesion, 5e3);  // default_from: the peak cohesion
  EXPECT_DOUBLE_EQ(p.residual_friction, 25 * kDegree);
  EXPECT_EQ(p.softening_strain, 0.1);
  // Defaults of the keys not given are the declared ones.
  EXPECT_EQ(p.yield_stress, VonMises::parameters[0].def);
  EXPECT_EQ(p.viscosity, NewtonianFluid::parameters[0].def);
}

TEST(MaterialParameters, TheModelsRulesNameTheKey) {
  try {
    (void)read("[[material]]\nfriction = 20\ndilatancy = 25\n");
    FAIL() << "dilatancy above the friction angle accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material.dilatancy");
  }
  try {
    (void)read(
        "[model]\nconstitutive = \"drucker_prager_softening\"\n[[material]]\ncohesion = 1e3\n"
        "residual_cohesion = 2e3\n");
    FAIL() << "residual cohesion above the peak accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material.residual_cohesion");
  }
}

// A key of a model that is not chosen is refused (as the runout and DEM readers do), naming the
// key, the chosen model and the keys it reads; the shared keys of the chosen model are accepted.
TEST(MaterialParameters, AnotherModelsKeyIsRefused) {
  try {
    (void)read("[model]\nconstitutive = \"drucker_prager\"\n[[material]]\ncohesion = 1e3\nyield_stress = 2e5\n");
    FAIL() << "a von_mises key accepted for drucker_prager";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material.yield_stress");
    EXPECT_EQ(e.file(), "case.toml");
    const std::string m = e.what();
    EXPECT_NE(m.find("model.constitutive = drucker_prager"), std::string::npos) << m;
    EXPECT_NE(m.find("it belongs to von_mises"), std::string::npos) << m;
    EXPECT_NE(m.find("drucker_prager reads material.cohesion, material.friction, material.dilatancy"),
              std::string::npos)
        << m;
  }
  try {
    (void)read("[model]\nconstitutive = \"linear_elastic\"\n[[material]]\nfriction = 30\n");
    FAIL() << "a friction angle accepted for linear_elastic";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material.friction");
    EXPECT_NE(std::string(e.what()).find("linear_elastic reads none of these keys"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW((void)read("[model]\nconstitutive = \"von_mises\"\n[[material]]\nyield_stress = 2e5\n"));
}

// The figures summary.json reports per material are the models' declarations: the same keys as the
// hand-written cases before (in the same column order), a parameter's label and unit from its ParamSpec.
TEST(MaterialParameters, TheSummaryFiguresComeFromTheModels) {
  std::vector<std::string> keys;
  for (const MaterialFigure& f : all_material_figures()) keys.emplace_back(f.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"K_Pa", "G_Pa", "yield_stress_Pa", "alpha_phi", "k_c_Pa", "alpha_psi",
                                            "residual_alpha_phi", "residual_k_c_Pa", "softening_strain",
                                            "min_density_kg_per_m3", "viscosity_Pa_s"}));
  const SummaryKey* k = find_summary_key(summary_keys(), "materials[].yield_stress_Pa");
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->label, VonMises::parameters[0].meaning);
  EXPECT_EQ(k->unit, "Pa");
  MaterialParams p;
  p.yield_stress = 2e5;
  p.finalise();
  std::vector<std::string> vm;
  for (const MaterialFigure& f : material_figures(VonMises{})) vm.emplace_back(f.key);
  EXPECT_EQ(vm, (std::vector<std::string>{"K_Pa", "G_Pa", "yield_stress_Pa"}));
  EXPECT_EQ(material_figures(VonMises{})[2].value(p), 2e5);
  EXPECT_EQ(material_figures(DruckerPrager{})[0].value(p), p.bulk);
}

TEST(MaterialParameters, TheHelpListsTheModelsThatReadAKey) {
  ConfigReader d = ConfigReader::describe();
  (void)read_config(d, true);
  bool found = false;
  for (const KeyReference& k : d.reference())
    if (k.key == "material[].yield_stress") {
      found = true;
      EXPECT_EQ(k.help, "uniaxial yield stress (von_mises)");
      EXPECT_EQ(k.unit, "Pa");
    }
  EXPECT_TRUE(found);
  EXPECT_EQ(ConstitutiveModelParameters::parameters_of("drucker_prager").size(), 3u);
  EXPECT_TRUE(ConstitutiveModelParameters::parameters_of("linear_elastic").empty());
}

TEST(MaterialParameters, EveryModelWithAStrengthReducesIt) {
  // The strength reduction is the model's member: von Mises divides σ_y, Drucker–Prager c and tan φ;
  // a model without a strength is refused (test_constitutive.cpp checks the values).
  MaterialParams p;
  p.yield_stress = 3e5;
  EXPECT_DOUBLE_EQ(reduced_strength(VonMises{}, {p}, 1.5).front().yield_stress, 2e5);
  EXPECT_TRUE(has_shear_strength(VonMises{}));
  EXPECT_FALSE(has_shear_strength(NewtonianFluid{}));
  EXPECT_EQ(models_with_shear_strength(), "von_mises, drucker_prager, drucker_prager_softening");
}

}  // namespace
