// dem-avalanche's defaults have one source (issue #30 item 3): the reader (config.cpp) takes every
// default from the structs its keys fill, so a config that sets nothing gives default-constructed
// structs, field by field. A default changed on one side only fails here.
#include <gtest/gtest.h>

#include <variant>

#include "geohaz/core/config.hpp"
#include "geohaz/dem/config.hpp"

using namespace geohaz;
using namespace geohaz::dem;

namespace {

RunConfig read(const std::string& toml) {
  ConfigReader r = ConfigReader::from_string(toml, "defaults.toml");
  return read_config(r, false);
}

void expect_packing_equal(const PackingSpec& a, const PackingSpec& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.r_min, b.r_min);
  EXPECT_EQ(a.r_max, b.r_max);
  EXPECT_EQ(a.porosity, b.porosity);
  EXPECT_EQ(a.density, b.density);
  EXPECT_EQ(a.locked_in_stress, b.locked_in_stress);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.expansion_steps, b.expansion_steps);
  EXPECT_EQ(a.max_relax_steps, b.max_relax_steps);
}

void expect_material_equal(const MaterialSpec& a, const MaterialSpec& b) {
  ASSERT_EQ(a.law.index(), b.law.index());
  if (const auto* l = std::get_if<LinearSpringCoulomb>(&a.law)) {
    const auto& m = std::get<LinearSpringCoulomb>(b.law);
    EXPECT_DOUBLE_EQ(l->kn, m.kn);  // the reader derives k_n = 2 E_c and k_s = k_n / ratio from them
    EXPECT_DOUBLE_EQ(l->ks, m.ks);
  } else {
    const auto& h = std::get<HertzMindlin>(a.law);
    const auto& k = std::get<HertzMindlin>(b.law);
    EXPECT_EQ(h.youngs, k.youngs);
    EXPECT_EQ(h.poisson, k.poisson);
  }
  EXPECT_EQ(a.density, b.density);
  EXPECT_EQ(a.contact.friction, b.contact.friction);
  EXPECT_EQ(a.contact.restitution, b.contact.restitution);
  EXPECT_EQ(a.contact.rolling_friction, b.contact.rolling_friction);
  EXPECT_EQ(a.contact.rolling_damping, b.contact.rolling_damping);
  EXPECT_EQ(a.contact.tangential_damping, b.contact.tangential_damping);
  EXPECT_EQ(a.contact.fragment_damping_mass, b.contact.fragment_damping_mass);
  EXPECT_EQ(a.contact.fragment_rolling, b.contact.fragment_rolling);
  EXPECT_EQ(a.bond.radius_multiplier, b.bond.radius_multiplier);
  EXPECT_EQ(a.bond.modulus, b.bond.modulus);
  EXPECT_EQ(a.bond.stiffness_ratio, b.bond.stiffness_ratio);
  EXPECT_EQ(a.bond.tensile_strength, b.bond.tensile_strength);
  EXPECT_EQ(a.bond.tensile_strength_std, b.bond.tensile_strength_std);
  EXPECT_EQ(a.bond.shear_strength, b.bond.shear_strength);
  EXPECT_EQ(a.bond.shear_strength_std, b.bond.shear_strength_std);
  EXPECT_EQ(a.bond_gap_tolerance, b.bond_gap_tolerance);
  EXPECT_EQ(a.joint_friction, b.joint_friction);
}

}  // namespace

TEST(DemConfigDefaults, AnEmptyLabConfigGivesTheStructDefaults) {
  const RunConfig c = read("");
  const RunConfig d;
  EXPECT_EQ(c.kind, d.kind);
  expect_packing_equal(c.packing, d.packing);
  expect_material_equal(c.material, d.material);
  EXPECT_EQ(c.numerics.safety_factor, d.numerics.safety_factor);
  EXPECT_EQ(c.numerics.max_speed, d.numerics.max_speed);
  EXPECT_EQ(c.snapshot_every, d.snapshot_every);
  EXPECT_EQ(c.write_tessellation, d.write_tessellation);
  EXPECT_EQ(c.confining, d.confining);
  const LabTestSpec l;
  EXPECT_EQ(c.lab.loading_velocity, l.loading_velocity);
  EXPECT_EQ(c.lab.max_axial_strain, l.max_axial_strain);
  EXPECT_EQ(c.lab.post_peak_stop, l.post_peak_stop);
  EXPECT_EQ(c.lab.local_damping, l.local_damping);
  EXPECT_EQ(c.lab.grip_fraction, l.grip_fraction);
  EXPECT_EQ(c.lab.record_interval, l.record_interval);
}

TEST(DemConfigDefaults, HertzAndJointSetDefaultsAreTheStructs) {
  const RunConfig c = read("[material]\ncontact_law = \"hertz\"\n[[joints.set]]\nspacing = 0.01\n");
  MaterialSpec d;
  d.law = HertzMindlin{};
  expect_material_equal(c.material, d);
  ASSERT_EQ(c.material.joint_sets.size(), 1u);
  const JointSet js;
  EXPECT_EQ(c.material.joint_sets[0].dip, js.dip);
  EXPECT_EQ(c.material.joint_sets[0].persistence, js.persistence);
  EXPECT_EQ(c.material.joint_sets[0].trace_length, js.trace_length);
}

TEST(DemConfigDefaults, AnAvalancheWithOnlyItsGeometryGivesTheStructDefaults) {
  // The avalanche takes the sample's radii and porosity, its own locked-in stress (none).
  const RunConfig c = read(
      "test = \"avalanche\"\n[avalanche]\nterrain_x = [0.0, 100.0, 300.0]\nterrain_z = [100.0, 0.0, 0.0]\n"
      "source_x = [10.0, 20.0, 15.0]\nsource_z = [95.0, 90.0, 98.0]\n");
  const AvalancheSpec d;
  const AvalancheSpec& a = c.avalanche;
  expect_packing_equal(a.packing, d.packing);
  expect_material_equal(a.material, d.material);
  EXPECT_EQ(a.section_spacing, d.section_spacing);
  EXPECT_EQ(a.terrain_friction, d.terrain_friction);
  EXPECT_EQ(a.terrain_restitution, d.terrain_restitution);
  EXPECT_EQ(a.terrain_rolling_friction, d.material.contact.rolling_friction);  // default: the material's
  EXPECT_EQ(a.settle_time, d.settle_time);
  EXPECT_EQ(a.settle_damping, d.settle_damping);
  EXPECT_EQ(a.strength_factor, d.strength_factor);
  EXPECT_EQ(a.trigger_acceleration, d.trigger_acceleration);
  EXPECT_EQ(a.trigger_duration, d.trigger_duration);
  EXPECT_EQ(a.runout_time, d.runout_time);
  EXPECT_EQ(a.stop_kinetic_fraction, d.stop_kinetic_fraction);
  EXPECT_EQ(a.stop_speed, d.stop_speed);
  EXPECT_EQ(a.runout_damping, d.runout_damping);
  EXPECT_EQ(a.record_interval, d.record_interval);
  EXPECT_EQ(a.volume_width, d.volume_width);
}
