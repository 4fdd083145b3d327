#pragma once
/// \file packing.hpp
/// Building a bonded rock sample (the "bonded-particle model" genesis of Potyondy & Cundall 2004,
/// §3.1, shortened):
///  1. radii uniform in [R_min, R_max] until the solid area reaches (1 − n)·W·H (target porosity n);
///  2. random sequential placement at reduced radii (no overlap), then radius expansion inside the
///     fixed container with frictionless discs and local damping, then equilibrium;
///  3. isotropic locked-in stress: the four walls servo-controlled to σ_0;
///  4. bonds on the regular-triangulation edges (tessellation.hpp) whose gap is below a tolerance,
///     strengths drawn from normal distributions with a seeded generator.
/// Everything is seeded: the same seed gives the same sample bit for bit (same build), different
/// seeds different but statistically similar samples.

#include <cstdint>
#include <vector>

#include "geohaz/dem/bonds.hpp"
#include "geohaz/dem/contact_laws.hpp"
#include "geohaz/dem/fields.hpp"
#include "geohaz/dem/walls.hpp"

namespace geohaz::dem {

struct PackingSpec {
  // The defaults are dem-avalanche's (config.cpp reads these members as its defaults): a lab
  // sample of Potyondy & Cundall's 2004 proportions.
  double width = 0.03;            ///< container width W (m)
  double height = 0.06;           ///< container height H (m)
  double r_min = 0.8e-3;          ///< smallest radius (m)
  double r_max = 1.66 * 0.8e-3;   ///< largest radius (m), R_max/R_min = 1.66 (Potyondy & Cundall 2004)
  double porosity = 0.18;         ///< target porosity n of the expansion stage
  double density = 2650;          ///< disc density (kg/m³)
  double locked_in_stress = 1e6;  ///< isotropic stress σ_0 after packing (Pa), 0: skip
  double friction_after = 0.5;    ///< μ restored after packing
  std::uint64_t seed = 1;
  int expansion_steps = 2000;  ///< radius-expansion steps
  int max_relax_steps = 6000;  ///< cap on each equilibrium stage
};

/// A packed sample: discs (ids 0..N−1, origin at the lower-left container corner) and the
/// container walls in their final (servo) position: bottom, right, top, left.
struct PackedSample {
  DiscStore discs;
  std::vector<WallSegment> walls;
  double width = 0, height = 0;       ///< final container size (m)
  double porosity = 0;                ///< 1 − Σ πR² / (W H)
  double coordination = 0;            ///< mean contacts per disc
  double stress_x = 0, stress_y = 0;  ///< final wall stresses (Pa)
};

/// Pack discs in a W × H box. The contact law is used with zero friction during expansion.
PackedSample pack_discs_in_box(const PackingSpec& spec, const ContactLaw& law);

/// Bond every pair joined by an edge of `edges` (disc indices into `discs`) whose gap
/// |x_a − x_b| − R_a − R_b is below gap_tolerance · min(R_a, R_b). Strengths ~ N(mean, std),
/// truncated at 1 % of the mean. Appends to `bonds`; returns the number added.
std::size_t install_parallel_bonds(const DiscStore& discs,
                                   const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges,
                                   const ParallelBondProperties& props, double gap_tolerance, std::uint64_t seed,
                                   BondTable& bonds);

/// Mean coordination number (contacts per disc) of a store (direct O(N) cell search).
double coordination_number(const DiscStore& discs);

}  // namespace geohaz::dem
