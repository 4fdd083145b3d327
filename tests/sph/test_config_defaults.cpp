// sph-slope's defaults have one source (issue #30 item 3): the reader (config.cpp) takes every
// numeric and boolean default from the member of RunConfig its key fills, so a config that sets
// nothing gives a default-constructed RunConfig, field by field. A default changed on one side
// only fails here (as dem_config does for dem-avalanche).
#include <gtest/gtest.h>

#include <string>

#include "geohaz/core/config.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/run.hpp"

using namespace geohaz;
using namespace geohaz::sph;

namespace {

/// Every key read (the reader's describe mode walks every branch: all scenarios and analyses).
RunConfig described() {
  ConfigReader r = ConfigReader::describe();
  return read_config(r, true);
}

/// A real read of a config that sets only the scenario (and the dimension for the 3D keys).
RunConfig read(const std::string& toml) {
  ConfigReader r = ConfigReader::from_string(toml, "defaults.toml");
  return read_config(r, false);
}

void expect_run_and_output_equal(const RunConfig& a, const RunConfig& b) {
  EXPECT_EQ(a.dimension, b.dimension);
  EXPECT_EQ(a.end_time, b.end_time);
  EXPECT_EQ(a.output_interval, b.output_interval);
  EXPECT_EQ(a.snapshot_interval, b.snapshot_interval);
  EXPECT_EQ(a.rest_speed, b.rest_speed);
  EXPECT_EQ(a.stop_at_rest, b.stop_at_rest);
  EXPECT_EQ(a.geostatic, b.geostatic);
  EXPECT_EQ(a.geostatic_duration, b.geostatic_duration);
  EXPECT_EQ(a.geostatic_damping, b.geostatic_damping);
  EXPECT_EQ(a.geostatic_elastic, b.geostatic_elastic);
  EXPECT_EQ(a.rest_tolerance, b.rest_tolerance);
  EXPECT_EQ(a.srm.f_min, b.srm.f_min);
  EXPECT_EQ(a.srm.f_max, b.srm.f_max);
  EXPECT_EQ(a.srm.tolerance, b.srm.tolerance);
  EXPECT_EQ(a.srm.damping, b.srm.damping);
  EXPECT_EQ(a.srm.trial_duration, b.srm.trial_duration);
  EXPECT_EQ(a.srm.growth_ratio, b.srm.growth_ratio);
  EXPECT_EQ(a.srm.knee_ratio, b.srm.knee_ratio);
  EXPECT_EQ(a.seismic.kh, b.seismic.kh);
  EXPECT_EQ(a.seismic.kv, b.seismic.kv);
  EXPECT_EQ(a.water.ru, b.water.ru);
  EXPECT_EQ(a.rain.enabled, b.rain.enabled);
  EXPECT_EQ(a.failed_threshold, b.failed_threshold);
  EXPECT_EQ(a.front_thickness, b.front_thickness);
  EXPECT_EQ(a.bulking_factor, b.bulking_factor);
  EXPECT_EQ(a.write_release, b.write_release);
  EXPECT_EQ(a.structure_forces, b.structure_forces);
}

void expect_geometry_equal(const RunConfig& a, const RunConfig& b) {
  EXPECT_EQ(a.slope.height, b.slope.height);
  EXPECT_EQ(a.slope.gradient, b.slope.gradient);
  EXPECT_EQ(a.slope.crest_length, b.slope.crest_length);
  EXPECT_EQ(a.slope.front_length, b.slope.front_length);
  EXPECT_EQ(a.slope.base_thickness, b.slope.base_thickness);
  EXPECT_EQ(a.slope.cut_depth, b.slope.cut_depth);
  EXPECT_EQ(a.slope.cut_gradient, b.slope.cut_gradient);
  EXPECT_EQ(a.piles.enabled, b.piles.enabled);
  EXPECT_EQ(a.piles.diameter, b.piles.diameter);
  EXPECT_EQ(a.piles.spacing, b.piles.spacing);
  EXPECT_EQ(a.column_width, b.column_width);
  EXPECT_EQ(a.column_height, b.column_height);
  EXPECT_EQ(a.floor_length, b.floor_length);
  EXPECT_EQ(a.biaxial.width, b.biaxial.width);
  EXPECT_EQ(a.biaxial.height, b.biaxial.height);
  EXPECT_EQ(a.biaxial_strain_rate, b.biaxial_strain_rate);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.block_length, b.block_length);
  EXPECT_EQ(a.block_height, b.block_height);
  EXPECT_EQ(a.initial_velocity.amplitude, b.initial_velocity.amplitude);
  EXPECT_EQ(a.initial_velocity.root, b.initial_velocity.root);
  EXPECT_EQ(a.initial_velocity.length, b.initial_velocity.length);
  EXPECT_EQ(a.section.soil_thickness, b.section.soil_thickness);
  EXPECT_EQ(a.section.base_thickness, b.section.base_thickness);
  EXPECT_EQ(a.section.soil_material, b.section.soil_material);
  EXPECT_EQ(a.section.base_material, b.section.base_material);
  EXPECT_EQ(a.section.release_width, b.section.release_width);
}

void expect_numerics_equal(const NumericalSettings& a, const NumericalSettings& b) {
  EXPECT_EQ(a.spacing, b.spacing);
  EXPECT_EQ(a.h_factor, b.h_factor);
  EXPECT_EQ(a.gravity, b.gravity);
}

}  // namespace

TEST(SphConfigDefaults, EveryKeyReadWithNothingSetGivesTheStructDefaults) {
  const RunConfig d;
  const RunConfig c = described();
  expect_run_and_output_equal(c, d);
  expect_geometry_equal(c, d);
  expect_numerics_equal(c.numerics, d.numerics);
}

TEST(SphConfigDefaults, EachScenarioReadFromAnEmptyConfigGivesTheStructDefaults) {
  const RunConfig d;
  for (const char* toml : {"run.scenario = \"slope\"", "run.scenario = \"column\"", "run.scenario = \"biaxial\"",
                           "run.scenario = \"block\"", "[run]\ndimension = 3\nscenario = \"slope\""}) {
    SCOPED_TRACE(toml);
    const RunConfig c = read(toml);
    RunConfig want;
    want.dimension = c.dimension;  // the one key set in the 3D case
    expect_run_and_output_equal(c, want);
    expect_numerics_equal(c.numerics, d.numerics);
    EXPECT_EQ(c.slope.height, d.slope.height);
    EXPECT_EQ(c.column_width, d.column_width);
    EXPECT_EQ(c.biaxial.width, d.biaxial.width);
    EXPECT_EQ(c.block_length, d.block_length);
    EXPECT_EQ(c.width, d.width);
  }
}
