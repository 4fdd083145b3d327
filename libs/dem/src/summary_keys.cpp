/// \file summary_keys.cpp
/// Label, unit and group of every key dem-avalanche writes into summary.json (run.cpp
/// lab_summary, avalanche_summary; summary_keys.hpp). A key written without a line here fails
/// the app's tests (tests/common/summary_keys_check.hpp). Stresses and moduli of the biaxial
/// tests are 2D values on discs 1 m thick (Pa); energies per metre of that thickness (J/m). A key
/// whose value is a config value (config_echo) names the config key: label and unit are its
/// declaration's (config.cpp).

#include "geohaz/dem/summary_keys.hpp"

#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/dem/config.hpp"

namespace geohaz::dem {

namespace {

using G = SummaryGroup;

constexpr SummaryKey kKeys[] = {
    // biaxial tests
    {"mohr_coulomb.cohesion_Pa", "cohesion c (Mohr–Coulomb fit over the tests)", "Pa", G::Strength, true},
    {"mohr_coulomb.friction_angle_deg", "friction angle φ (Mohr–Coulomb fit)", "deg", G::Strength, true},
    {"mohr_coulomb.failure_plane_angle_deg", "failure plane angle 45° + φ/2", "deg", G::Strength},
    {"mohr_coulomb.valid", "fit valid (at least two confining stresses)", "", G::Strength},
    {"mohr_coulomb.intercept_Pa", "Mohr–Coulomb fit: σ1 at σ3 = 0", "Pa", G::Strength},
    {"mohr_coulomb.slope", "Mohr–Coulomb fit: slope dσ1/dσ3", "1", G::Strength},
    {"sample.porosity", "sample porosity", "1", G::Strength},
    {"sample.discs", "discs in the sample", "1"},
    {"sample.bonds", "bonds in the sample", "1"},
    {"sample.coordination_number", "coordination number", "1"},
    {"sample.width_m", "sample width", "m"},
    {"sample.height_m", "sample height", "m"},
    {"sample.locked_in_stress_Pa", "locked-in stress (x, y) after bonding", "Pa"},
    {"tests[]", "results per confining stress", "", G::Strength},
    {"tests[].name", "test", ""},
    config_echo("tests[].confining_stress_Pa", "confining stress σ3", "biaxial.confining_stresses", G::Strength),
    {"tests[].peak_stress_Pa", "peak axial stress σ1", "Pa", G::Strength},
    {"tests[].deviator_at_peak_Pa", "deviator at peak σ1 − σ3", "Pa", G::Strength},
    {"tests[].youngs_modulus_Pa", "Young's modulus E", "Pa", G::Strength},
    {"tests[].poisson_ratio", "Poisson's ratio ν", "1", G::Strength},
    {"tests[].peak_axial_strain", "axial strain at peak", "1", G::Strength},
    {"tests[].crack_band_inclination_deg", "crack band inclination", "deg", G::Strength},
    {"tests[].tensile_breaks", "tensile cracks", "1", G::Strength},
    {"tests[].shear_breaks", "shear cracks", "1", G::Strength},
    {"tests[].confining_stress_measured_Pa", "confining stress measured", "Pa"},
    {"tests[].bonds", "bonds", "1"},
    {"tests[].discs", "discs", "1"},
    {"tests[].porosity", "porosity", "1"},
    {"tests[].width_m", "width", "m"},
    {"tests[].height_m", "height", "m"},
    // rock avalanche
    {"volume_m3", "rock volume (per metre of section)", "m^3", G::Volumes, true},
    {"source_area_m2", "source area of the section", "m^2", G::Volumes},
    {"H_over_L", "H/L (fall height over run-out)", "1", G::Reach, true},
    {"fall_height_H_m", "fall height H", "m", G::Reach},
    {"runout_L_m", "run-out L", "m", G::Reach, true},
    {"scheidegger_1973_H_over_L", "H/L for this volume by Scheidegger (1973)", "1", G::Reach},
    {"crown", "crown (x, z)", "m", G::Reach},
    {"toe", "toe (x, z)", "m", G::Reach},
    {"toe_definition", "toe", "", G::Reach},
    {"centre_of_mass.start", "centre of mass at the start (x, z)", "m", G::Reach},
    {"centre_of_mass.end", "centre of mass at the end (x, z)", "m", G::Reach},
    {"centre_of_mass.H_over_L", "centre of mass: H/L", "1", G::Reach},
    {"runout_by_mass_quantile[]", "run-out by mass quantile", "", G::Reach},
    {"runout_by_mass_quantile[].mass_fraction", "mass fraction behind the toe", "1", G::Reach},
    {"runout_by_mass_quantile[].toe", "toe (x, z)", "m", G::Reach},
    {"runout_by_mass_quantile[].runout_L_m", "run-out L", "m", G::Reach},
    {"runout_by_mass_quantile[].fall_height_H_m", "fall height H", "m", G::Reach},
    {"runout_by_mass_quantile[].H_over_L", "H/L", "1", G::Reach},
    {"max_speed_at_end_m_per_s", "largest speed at the end", "m/s", G::Peak},
    {"peak_kinetic_energy_J_per_m", "peak kinetic energy (per metre of section)", "J/m", G::Peak},
    {"moving_mass_fraction_at_end", "mass fraction moving at the end", "1", G::Peak},
    {"bond_breaks.tensile", "bonds broken in tension", "1", G::Damage},
    {"bond_breaks.shear", "bonds broken in shear", "1", G::Damage},
    {"bond_breaks.before_release", "bonds broken before release", "1", G::Damage},
    {"bonds_initial", "bonds at the start", "1", G::Damage},
    {"bonds_intact_final", "bonds intact at the end", "1", G::Damage},
    {"fragments_final", "fragments at the end", "1", G::Damage},
    {"largest_fragment_discs", "discs in the largest fragment", "1", G::Damage},
    {"fragments_with_2_or_more_discs", "fragments of two discs or more", "1", G::Damage},
    {"fragment_mass_fraction_of_largest", "mass fraction of the largest fragment", "1", G::Damage},
    {"discontinuities.traces", "joint traces", "1", G::Damage},
    {"discontinuities.total_length_m", "total joint trace length", "m", G::Damage},
    {"discontinuities.intensity_P21_per_m", "joint intensity P21", "1/m", G::Damage},
    {"discontinuities.bonds_cut", "bonds cut by joints", "1", G::Damage},
    {"discontinuities.sets[]", "joint sets", "", G::Damage},
    {"discontinuities.sets[].dip_deg", "dip", "deg", G::Damage},
    {"discontinuities.sets[].traces", "traces", "1", G::Damage},
    {"discontinuities.sets[].length_m", "trace length", "m", G::Damage},
    {"release_time_s", "release time", "s", G::Time},
    {"simulated_time_s", "simulated time", "s", G::Time},
    {"runout_duration_s", "run-out time after release", "s", G::Time},
    {"at_rest", "came to rest", "", G::Time},
    // bookkeeping
    {"discs", "discs", "1"},
    {"steps", "time steps", "1"},
    {"model", "model", ""},
    {"version", "geohaz version", ""},
    config_echo("test", "test"),
    {"warnings", "warnings", ""},
};

}  // namespace

std::span<const KeyReference> summary_config_declarations() {
  static const std::vector<KeyReference> refs = [] {
    ConfigReader d = ConfigReader::describe();
    (void)read_config(d, true);
    return d.reference();
  }();
  return refs;
}

std::span<const SummaryKey> summary_keys() noexcept {
  static const std::vector<SummaryKey> keys = with_config_declarations(kKeys, summary_config_declarations());
  return keys;
}

}  // namespace geohaz::dem
