#pragma once
/// \file config.hpp
/// The sph-slope configuration as typed structs (RunConfig and its parts, SI units, angles in
/// radians) and its reader: every key declared once in `libs/sph/src/config.cpp` (unit, default,
/// range, help text) and read into a RunConfig. The app, the Python module and `--help-config` all
/// go through `read_config`, so they cannot disagree on a key. The run of a config (the simulation,
/// its observer, result and outputs) is in run.hpp; the same split as runout's and dem's config.hpp.

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"
#include "geohaz/sph/constitutive.hpp"
#include "geohaz/sph/limit_equilibrium.hpp"
#include "geohaz/sph/loading.hpp"
#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"

namespace geohaz {
class ConfigReader;
}

namespace geohaz::sph {

/// Where the particles come from (Block: a free rectangle of soil, e.g. an elastic beam).
enum class ScenarioType { Slope, Column, Biaxial, Section, Block };

/// Velocity given to the soil at the start of the main phase (after any geostatic phase).
struct InitialVelocity {
  enum class Type { None, Uniform, CantileverMode };
  Type type = Type::None;
  std::vector<double> value;  ///< m/s, one component per axis (Uniform)
  /// CantileverMode: v_z = amplitude·φ((x − root)/length) (cantilever_mode_shape), axis Dim−1 (m/s).
  double amplitude = 0.0;
  double root = 0.0;    ///< m: x of the clamped end of the beam
  double length = 1.0;  ///< m: free length of the beam
};

/// Pile rows of SPH-slope paper (2020), Fig. 17 (3D): one row across the width at a position along the face.
struct PileRows {
  bool enabled = false;
  double position =
      0.5;  ///< fraction along the face from the toe (0) to the crest edge (1): lower 0.25, middle 0.5, upper 0.75
  double diameter = 0.02;  ///< m
  double spacing = 0.05;   ///< centre spacing across the width (m)
};

/// A DSM cross-section prepared by the app: the profile and its map geometry. In 2D a plane-strain
/// section along the polyline; in 3D a strip of the terrain `width` wide centred on the polyline
/// (local x = distance s along the polyline, local y − width/2 = offset t to its left).
struct SectionInput {
  std::vector<ProfilePoint> profile;  ///< s (m along the polyline), x, y (map), z (m)
  std::string crs_wkt;
  std::shared_ptr<const Raster> dsm;       ///< for release_thickness.tif (may be null)
  std::shared_ptr<const Terrain> terrain;  ///< the DSM surface (3D sections; may be null in 2D)
  double soil_thickness = 2.0;             ///< m: soil layer (material `soil_material`) below the surface
  /// true: soil + base layers rest on fixed bedrock following the surface; false: the base fills
  /// down to a flat bottom base_thickness below the lowest point of the soil.
  bool bedrock = true;
  double base_thickness = 2.0;  ///< m: base material below the lowest point of the soil layer
  int soil_material = 1, base_material = 0;
  double release_width = 10.0;  ///< W (m): plane-strain particles are spread over this width
  /// The water table raster (`water.table_raster`, the DSM's CRS): elevation of the table (m);
  /// null: none.
  std::shared_ptr<const Terrain> water_table;
  /// The pore-pressure raster (`water.pore_pressure_raster`, the DSM's CRS): u (Pa) at the base of the
  /// soil cover (vertical depth soil_thickness below the ground); null: none.
  std::shared_ptr<const Terrain> pore_pressure;
};

/// What a run computes.
enum class Analysis {
  Dynamic,            ///< the main phase in time (failure, run-out, shaking)
  StrengthReduction,  ///< the factor of safety by strength reduction (docs/sph.md, "Factor of safety")
  /// Bishop's method only (2D slope): the critical circle with pore water and seismic coefficients,
  /// the yield coefficient k_y and, with an earthquake, the Newmark displacement (docs/sph.md,
  /// "Pore pressure and seismic coefficients"); no particles.
  LimitEquilibrium
};

/// Strength reduction (Dawson et al. 1999; Griffiths & Lane 1999): from the geostatic state, trials
/// with every material's c/F, atan(tan φ/F) and atan(tan ψ/F), each a damped quasi-static run of
/// `trial_duration`; a trial fails when its largest displacement u has not converged (it grew by
/// more than `growth_ratio` of its final value over the last quarter of the trial) or lies beyond the
/// knee of the F–u curve (u > `knee_ratio` times u of the f_min trial). F is bisected in
/// [f_min, f_max] until the bracket is narrower than `tolerance`.
struct StrengthReductionSettings {
  double f_min = 0.5, f_max = 2.0;  ///< initial bracket of F
  double tolerance = 0.01;          ///< ΔF: bisection stops when f_failed − f_stable ≤ tolerance
  double damping = 0.7;             ///< Cundall ζ of the trials
  double trial_duration = 0.0;      ///< s; 0 → 30 H / c_p
  double growth_ratio = 0.05;       ///< failure: u(T) − u(3T/4) > growth_ratio · u(T)
  double knee_ratio = 5.0;          ///< failure: u(T) > knee_ratio · u(T) of the f_min trial
};

/// Everything a run needs (SI units; angles already in radians).
struct RunConfig {
  int dimension = 2;
  ScenarioType scenario = ScenarioType::Slope;
  ConstitutiveModel model = DruckerPrager{};
  std::vector<MaterialParams> materials;
  std::vector<std::string> material_names;

  // Geometry.
  SlopeGeometry slope;
  WallType left_wall = WallType::Fixed, right_wall = WallType::Fixed, bottom_wall = WallType::Fixed;
  double width = 0.1;  ///< 3D width (m)
  bool periodic_width = true;
  std::vector<double> layer_tops;  ///< m (elevations), slope scenario
  std::vector<int> layer_materials;
  PileRows piles;
  double column_width = 0.1, column_height = 0.1, floor_length = 0.4;  ///< m
  BiaxialGeometry biaxial;
  double block_length = 1.0, block_height = 0.1;  ///< m: the block scenario's rectangle [0, L] × [0, H]
  /// Clamped regions: boxes of 2·Dim numbers each (x_lo, [y_lo,] z_lo, x_hi, [y_hi,] z_hi), m. Soil
  /// particles inside are held at rest in place (field Clamped); each box must hold soil.
  std::vector<double> clamp_boxes;
  InitialVelocity initial_velocity;
  double biaxial_strain_rate = 0.5;  ///< 1/s, > 0 compression, < 0 tension
  SectionInput section;

  NumericalSettings numerics;  ///< the solver's settings (the domain geometry comes from the scenario)
  // Geostatic phase.
  bool geostatic = true;
  double geostatic_duration = 0.0;  ///< s; 0 → 20 H / c_p
  double geostatic_damping = 0.7;
  bool geostatic_elastic = true;
  double rest_tolerance = 0.01;  ///< at rest: max |v| < tol·√(g H)
  Analysis analysis = Analysis::Dynamic;
  StrengthReductionSettings srm;
  /// Pore water of the section ([water]; PoreWater::unit_weight = water density × gravity): in
  /// Bishop's method and, as a prescribed pore pressure (solver.hpp PoreWaterSettings, the table
  /// clipped to the ground), in the SPH solver of the slope and of a DSM section.
  PoreWater water;
  /// `water.table_raster` as given (resolved against the config's folder; "" none): the water table of
  /// a DSM section, loaded into section.water_table.
  std::string water_table_raster;
  /// `water.pore_pressure_raster` as given (resolved; "" none): the pore pressure at the base of a DSM
  /// section's soil cover, loaded into section.pore_pressure.
  std::string pore_pressure_raster;
  /// Loading history of the water table in the main phase: times (s) and offsets Δz (m).
  std::vector<double> water_history_times, water_history_offsets;
  /// Saturated density per material (kg/m³; 0: the material's density), below the phreatic surface.
  std::vector<double> saturated_densities;
  /// Rain infiltration as the pore-pressure history of the main phase ([rain] with rain.enabled and
  /// [hydrology]: the keys of slope-stability, infiltration.hpp; docs/sph.md): the pressure head of
  /// Iverson (2000) column by column, the rain's time t_r = clock(t) of the main-phase time t.
  struct Rain {
    bool enabled = false;
    InfiltrationKeys infiltration;
    std::vector<std::array<double, 2>> clock;  ///< (t, t_r) pairs (s); empty: t_r = t
    /// The rain's time t_r (s) whose pore pressure the strength reduction and the limit-equilibrium
    /// analysis take (a dynamic run follows the clock); the reader's default: the end of the rain.
    double evaluate_at = 0.0;
  } rain;
  /// Pseudo-static coefficients ([seismic]): in Bishop's method and in the strength-reduction trials.
  SeismicCoefficients seismic;
  // Main phase.
  double end_time = 1.0;                   ///< s
  double output_interval = 0.01;           ///< s (time series)
  double snapshot_interval = 0.1;          ///< s (0: first and last only)
  std::vector<double> velocity_png_times;  ///< s
  double rest_speed = 0.005;               ///< m/s; "at rest" for time-to-rest
  bool stop_at_rest = false;
  double failed_threshold = 0.01;  ///< m: displacement above which soil counts as failed
  double front_thickness = 0.0;    ///< m: deposit thickness that defines the front (0: 2Δx)
  double bulking_factor = 1.0;
  bool write_release = true;  ///< section scenario: release.h5 (+ release_thickness.tif)
  /// Loads on the walls and piles (structure_forces.csv, summary.json `structures`, PNG).
  bool structure_forces = true;
  /// Names of the structures to report (scenario.hpp Structure::name); empty: all.
  std::vector<std::string> structures;
  std::filesystem::path restart;  ///< snapshot file to restart from ("" none)

  std::string resolved_config;  ///< TOML text of the resolved config (written and stored in HDF5)
  std::string config_source;    ///< config file name
};

/// Read every sph-slope key from `r` into a typed RunConfig (SI units, angles in radians). In
/// describe mode (`describe` true) every section is read, whatever the scenario, so that
/// `--help-config` lists them all, and nothing is loaded from disk. Otherwise the inputs named by the
/// config (a DSM for the section scenario, an accelerogram) are read and checked here; InputError
/// names the file, the key and the value. Does not call r.finish() nor fill `resolved_config`.
RunConfig read_config(ConfigReader& r, bool describe);

}  // namespace geohaz::sph
