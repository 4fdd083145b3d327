#pragma once
/// \file experiments.hpp
/// What the dem-avalanche app runs: laboratory tests on a bonded sample (biaxial compression with
/// servo-controlled lateral walls and strain-controlled platens; direct tension with gripped ends)
/// and a rock avalanche (a bonded, jointed rock mass released on a terrain profile). The drivers
/// take plain structs (no config lookups) and return curves and derived numbers; outputs are
/// written by the app through output.hpp.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "geohaz/dem/joints.hpp"
#include "geohaz/dem/packing.hpp"
#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {

/// Micro-parameters of the bonded material.
struct MaterialSpec {
  ContactLaw law = LinearSpringCoulomb{};
  ContactProperties contact;
  ParallelBondProperties bond;
  double density = 2650;             ///< kg/m³
  double bond_gap_tolerance = 0.1;   ///< bond tessellation edges with gap < this × min(R_A, R_B)
  double joint_friction = 0.5;       ///< μ of joint contacts
  std::vector<JointSet> joint_sets;  ///< joint sets (may be empty)
  std::vector<JointTrace> traces;    ///< explicit traces (sample coordinates)
};

/// A bonded, jointed sample built in a box: discs, bonds, joint pairs and the report.
struct BondedSample {
  PackedSample packed;
  BondTable bonds;
  std::vector<JointPair> joints;
  std::vector<JointTrace> traces;
  DiscontinuityReport discontinuities;
};

/// Pack, tessellate, bond and cut by joints.
BondedSample build_bonded_sample(const PackingSpec& packing, const MaterialSpec& material);

/// Set up a solver with a sample's discs, bonds and joints and the material's contact model.
void load_sample(DemSolver& s, const BondedSample& sample, const MaterialSpec& material);

/// Called while a test runs: the solver, and a phase name ("consolidation", "loading", "settling", "runout").
using RecordCallback = std::function<void(const DemSolver&, const std::string& phase)>;

enum class LabTest { BiaxialCompression, BiaxialTension };

struct LabTestSpec {
  LabTest test = LabTest::BiaxialCompression;
  PackingSpec packing;
  MaterialSpec material;
  double confining_stress = 1e6;   ///< σ_3 on the lateral walls (Pa); 0: unconfined (walls removed)
  double loading_velocity = 0.25;  ///< speed of each platen / grip (m/s)
  double max_axial_strain = 0.02;  ///< stop at this strain
  double post_peak_stop = 0.7;     ///< stop once the stress drops below this fraction of the peak
  double local_damping = 0.7;      ///< Cundall α for the quasi-static test
  double grip_fraction = 0.1;      ///< tension: fraction of the height gripped at each end
  int record_interval = 50;        ///< steps between curve points
};

/// One point of the stress–strain record. Stresses compression-positive (tension test: tension-
/// positive axial stress), strains compression-positive.
struct CurvePoint {
  double time, axial_strain, lateral_strain, volumetric_strain, axial_stress, lateral_stress;
  std::size_t ae_count;  ///< bond breaks since the previous point
  double ae_energy;      ///< energy released since the previous point (J/m)
  std::size_t broken_total;
};

struct LabTestResult {
  std::vector<CurvePoint> curve;
  double peak_stress = 0;  ///< peak axial (compression: σ_1; tension: tensile) stress (Pa)
  double peak_strain = 0;
  double deviator_at_peak = 0;  ///< σ_1 − σ_3 at peak (Pa)
  double confining_stress = 0;  ///< mean lateral stress at peak (Pa)
  double youngs_modulus = 0;    ///< slope of (σ_a − σ_3) vs ε_a between 10 % and 50 % of the peak (Pa)
  double poisson_ratio = 0;     ///< −Δε_l/Δε_a over the same range (σ_3 = 0: ε_l from the disc envelope)
  double crack_plane_angle =
      0;  ///< inclination of the crack band to the horizontal (degrees, principal axis of crack positions after peak)
  std::size_t tensile_breaks = 0, shear_breaks = 0, bonds = 0;
  double porosity = 0, width = 0, height = 0;
  std::size_t discs = 0;
  std::vector<AcousticEvent> events;
};

/// Run a laboratory test on `sample` (the solver is left in its final state for output).
LabTestResult run_lab_test(const LabTestSpec& spec, const BondedSample& sample, DemSolver& solver,
                           const RecordCallback& observe = {});

/// Least-squares Mohr–Coulomb envelope from peak (σ_3, σ_1) pairs: σ_1 = a + b σ_3,
/// φ = asin((b − 1)/(b + 1)), c = a (1 − sin φ)/(2 cos φ); failure plane at 45° + φ/2 to σ_3's plane.
struct MohrCoulombFit {
  double cohesion = 0, friction_angle = 0, intercept = 0, slope = 0, failure_plane_angle = 0;
  bool valid = false;
};
MohrCoulombFit fit_mohr_coulomb(const std::vector<double>& sigma3, const std::vector<double>& sigma1);

// ------------------------------------------------------------------------------------------
// Rock avalanche

struct AvalancheSpec {
  std::vector<Vec2> terrain;     ///< profile (distance along the section, elevation) (m), downhill in +x
  double section_spacing = 5.0;  ///< m, sampling interval of a profile cut from a DSM (avalanche.section_spacing)
  double terrain_friction = 0.6, terrain_restitution = 0.3;
  double terrain_rolling_friction = -1.0;  ///< μ_r of disc–terrain contacts (< 0: material.contact's)
  std::vector<Vec2> source;                ///< rock-mass polygon (m)
  /// Radii, porosity, seed (width/height are taken from the polygon); no locked-in stress by default
  /// (the mass is cut out of the packing box).
  PackingSpec packing = [] {
    PackingSpec p;
    p.locked_in_stress = 0.0;
    return p;
  }();
  MaterialSpec material;
  double settle_time = 1.0;  ///< s, gravity settling with damping and the support in place
  double settle_damping = 0.7;
  std::vector<Vec2> support;                 ///< optional support wall (2 points) removed at release
  double strength_factor = 1.0;              ///< bond strengths × this at release (weakening trigger)
  Vec2 trigger_acceleration = Vec2::Zero();  ///< extra acceleration during the trigger (m/s²)
  double trigger_duration = 0.0;             ///< s
  double runout_time = 300.0;                ///< s after release: the longest run (it ends earlier at rest)
  /// The run ends at the first record where the kinetic energy is below this fraction of its peak
  /// after release and no disc is faster than stop_speed, ∈ (0, 1).
  double stop_kinetic_fraction = 1e-3;
  double stop_speed = 0.1;       ///< m/s, ≥ 0 (0: the kinetic-energy criterion alone)
  double runout_damping = 0.0;   ///< Cundall α during the run-out
  double record_interval = 0.1;  ///< s between time-series points
  double volume_width = 0.0;     ///< out-of-plane width to turn the 2D area into a volume (m); 0: source length
};

struct AvalanchePoint {
  double time, front, front_velocity, kinetic_energy;
  double max_speed;        ///< fastest disc (m/s)
  double moving_fraction;  ///< mass fraction of the discs faster than stop_speed
  std::size_t fragments, largest_fragment, ae_count;
  double ae_energy;
};

/// Run-out measured to the x below which a fraction of the mass lies (a mass quantile of the
/// deposit), with the fall height from the crown and H/L.
struct RunoutQuantile {
  double fraction = 0, x = 0, z = 0, runout = 0, fall_height = 0, h_over_l = 0;
};

/// One fragment at the end of the run.
struct FragmentSummary {
  std::size_t discs = 0;
  double mass = 0;      ///< kg per m of thickness
  double x = 0, z = 0;  ///< centre of mass (m)
  double travel = 0;    ///< horizontal travel of its centre of mass from where its discs started (m)
};

struct AvalancheResult {
  std::vector<AvalanchePoint> series;
  double crown_x = 0, crown_z = 0, toe_x = 0, toe_z = 0;
  double runout = 0, fall_height = 0, h_over_l = 0;
  double area = 0, volume = 0;                     ///< source area (m²) and volume (m³) with volume_width
  double scheidegger_h_over_l = 0;                 ///< log10(H/L) = −0.15666 log10(V) + 0.62419 (Scheidegger 1973)
  std::vector<std::pair<double, double>> deposit;  ///< (x, thickness) profile (m)
  std::vector<std::size_t> fragment_sizes;         ///< discs per fragment at the end, descending
  std::vector<FragmentSummary> fragments;          ///< same order as fragment_sizes
  /// Toe at the mass quantiles 0.5, 0.9, 0.95, 0.99 and 1 (farthest disc) of x; the headline
  /// toe/runout/h_over_l above is the 0.99 one.
  std::vector<RunoutQuantile> quantiles;
  /// Centre of mass after settling and at the end (m), and its travel angle tan = ΔH/ΔL.
  Vec2 com_start = Vec2::Zero(), com_end = Vec2::Zero();
  double com_h_over_l = 0;
  std::size_t discs = 0, bonds = 0, joints_cut = 0;
  DiscontinuityReport discontinuities;
  std::vector<AcousticEvent> events;  ///< all bond breaks, settling included
  double release_time = 0;            ///< s (simulated time at release)
  bool at_rest = false;               ///< the stop criterion ended the run (false: runout_time was reached)
  double duration = 0;                ///< s of run-out simulated after release
  double peak_kinetic_energy = 0;     ///< J/m
  double max_speed_at_end = 0;        ///< m/s
  double moving_fraction_at_end = 0;  ///< mass fraction faster than stop_speed at the end
  std::size_t events_before_release = 0;
};

/// Cheap checks of an avalanche set-up before anything is written: the source polygon must hold a
/// few discs (area vs disc size) and lie above the terrain. Throws InputError naming the key.
void check_avalanche_spec(const AvalancheSpec& spec);

/// Run a rock avalanche (the solver is left in its final state).
AvalancheResult run_avalanche(const AvalancheSpec& spec, DemSolver& solver, const RecordCallback& observe = {});

/// Fragments: clusters of discs joined by intact bonds (union–find). Writes the Fragment field
/// and returns the sizes, descending.
std::vector<std::size_t> label_fragments(DemSolver& s);

/// Scheidegger (1973) fahrböschung: H/L = 10^(−0.15666 log10 V + 0.62419), V in m³.
double scheidegger_h_over_l(double volume);

}  // namespace geohaz::dem
