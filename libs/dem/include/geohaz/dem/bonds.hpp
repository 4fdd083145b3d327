#pragma once
/// \file bonds.hpp
/// Parallel bonds of the bonded-particle model (Potyondy & Cundall 2004, Int. J. Rock Mech. Min.
/// Sci. 41:1329–1364, eqs. 8–13), in 2D with unit thickness:
///   bond radius R̄ = λ̄ min(R_A, R_B), area A = 2R̄·1, moment of inertia I = 2/3 R̄³·1,
///   normal force F̄_n = −k̄_n A (d − d_0)  (total form: d_0 = centre distance when bonded),
///   shear force ΔF̄_s = −k̄_s A Δu_s, moment ΔM̄ = −k̄_n I Δθ (incremental),
///   peripheral stresses σ_max = −F̄_n/A + |M̄| R̄/I (tension positive), τ_max = |F̄_s|/A.
/// A bond breaks in tension when σ_max ≥ σ̄_c, otherwise in shear when τ_max ≥ τ̄_c; it is then
/// removed with its load, and the break is an acoustic-emission event whose energy is the strain
/// energy the bond held: F̄_n²/(2k̄_n A) + F̄_s²/(2k̄_s A) + M̄²/(2k̄_n I).
/// Bonds are stored as flat arrays keyed by disc ids (structure of arrays), so they survive sorting.

#include <cstdint>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz::dem {

/// Micro-parameters of the parallel bonds (means and standard deviations of the strengths).
/// Stiffnesses follow from a bond modulus as in PFC2D (Potyondy & Cundall 2004, eq. 20):
/// k̄_n = Ē_c/(R_A + R_B), k̄_s = k̄_n/(k̄_n/k̄_s), so the macro modulus does not depend on disc size.
struct ParallelBondProperties {
  // The dem-avalanche config takes its defaults from here (one copy of each fact, issue #11): the
  // bonded granite-like rock of data/dem/biaxial_compression.toml.
  double radius_multiplier = 1.0;      ///< λ̄
  double modulus = 20e9;               ///< Ē_c (Pa)
  double stiffness_ratio = 2.5;        ///< k̄_n/k̄_s
  double tensile_strength = 50e6;      ///< mean σ̄_c (Pa)
  double tensile_strength_std = 10e6;  ///< standard deviation of σ̄_c (Pa)
  double shear_strength = 50e6;        ///< mean τ̄_c (Pa)
  double shear_strength_std = 10e6;    ///< standard deviation of τ̄_c (Pa)
};

/// State of a bond.
enum class BondState : std::uint8_t { Intact = 0, BrokenTension = 1, BrokenShear = 2, CutByJoint = 3 };

/// Failure mode of an AE event.
enum class FailureMode : std::uint8_t { Tensile = 1, Shear = 2 };

/// An acoustic-emission event: one bond break.
struct AcousticEvent {
  double time;    ///< s
  Vec2 position;  ///< bond centre (m)
  FailureMode mode;
  double energy;      ///< released strain energy (J/m)
  std::int64_t bond;  ///< index in the bond table
};

/// All bonds of a sample, structure of arrays.
struct BondTable {
  std::vector<std::int64_t> id_a, id_b;  ///< disc ids
  std::vector<double> radius;            ///< R̄ (m)
  std::vector<double> rest_length;       ///< d_0 (m)
  std::vector<double> normal_stiffness;  ///< k̄_n of this bond (Pa/m)
  std::vector<double> shear_stiffness;   ///< k̄_s of this bond (Pa/m)
  std::vector<double> shear_force;       ///< F̄_s on A along t (N/m)
  std::vector<double> moment;            ///< M̄ on A (N·m/m)
  std::vector<double> normal_force;      ///< F̄_n on A along n, last step (N/m; < 0 tension)
  std::vector<double> tensile_strength;  ///< σ̄_c of this bond (Pa)
  std::vector<double> shear_strength;    ///< τ̄_c of this bond (Pa)
  std::vector<BondState> state;
  // Work arrays written by the bond loop and gathered by the discs.
  std::vector<Vec2> force_on_a;  ///< N/m
  std::vector<double> torque_on_a, torque_on_b;

  std::size_t size() const noexcept { return id_a.size(); }
  std::size_t intact_count() const noexcept;
  /// Append an intact bond (stiffnesses in Pa/m, strengths already drawn).
  void add(std::int64_t a, std::int64_t b, double radius, double rest_length, double kn, double ks, double sigma_c,
           double tau_c);
};

}  // namespace geohaz::dem
