#pragma once
// Test helper shared by the DEM regression and validation tests: the bonded sample both use
// (linear contacts, E_c = 20 GPa, kn/ks = 2.5, μ = 0.5, parallel bonds of 50 ± 10 MPa), so the
// small regression cases and the long validation runs test the same material at two sizes.
#include <cstdint>

#include "geohaz/dem/experiments.hpp"

namespace geohaz::dem::testing {

/// Packing size and run controls that differ between the regression and validation samples.
struct LabSize {
  double width, height;  ///< m
  double r_min;          ///< m (r_max = 1.66 r_min)
  std::uint64_t seed;
  int expansion_steps, max_relax_steps;
  double loading_velocity;  ///< m/s of the platens
};

inline LabTestSpec bonded_lab(const LabSize& z) {
  LabTestSpec s;
  s.packing.width = z.width;
  s.packing.height = z.height;
  s.packing.r_min = z.r_min;
  s.packing.r_max = 1.66 * z.r_min;
  s.packing.porosity = 0.18;
  s.packing.locked_in_stress = 1e6;
  s.packing.seed = z.seed;
  s.packing.expansion_steps = z.expansion_steps;
  s.packing.max_relax_steps = z.max_relax_steps;
  const double Ec = 20e9;
  s.material.law = LinearSpringCoulomb{2 * Ec, 2 * Ec / 2.5};
  s.material.contact.friction = 0.5;
  s.material.bond.modulus = Ec;
  s.material.bond.stiffness_ratio = 2.5;
  s.material.bond.tensile_strength = 50e6;
  s.material.bond.tensile_strength_std = 10e6;
  s.material.bond.shear_strength = 50e6;
  s.material.bond.shear_strength_std = 10e6;
  s.loading_velocity = z.loading_velocity;
  s.max_axial_strain = 0.01;
  return s;
}

}  // namespace geohaz::dem::testing
