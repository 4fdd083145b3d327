#pragma once
/// \file run.hpp
/// A complete sph-slope run, callable from C++ without a subprocess (the app and the Python module
/// both go through it). The shape is that of debris-runout (libs/runout/run.hpp):
///
///  1. `read_config(ConfigReader&, describe)` (config.hpp): every key into a typed RunConfig (the
///     DSM of a section and an accelerogram are read there). `validate(cfg)`: the checks across
///     keys and a dry-run build of the particles. Both throw InputError (file, key, value) and
///     write nothing.
///  2. `SphSimulation sim(cfg)`: builds the scenario and the solver; `sim.run(observer)` runs the
///     geostatic phase (or loads the restart), then the main phase in time, or the strength
///     reduction trials; the observer sees the phases and every main-phase step (progress,
///     snapshots, quick-look PNGs). SimulationError on a blow-up, with the state so far kept.
///  3. `write_outputs(sim, out)`: the series, surfaces, pictures, release file and summary.json.
///
/// `run_case(cfg, options, observer)` chains them the way `sph-slope` does (the output folder, the
/// resolved config and the snapshots during the run, progress on stderr, then the outputs) and
/// returns the run: the apps (sph-slope, sph-slope-mpi) and the Python module call only it. The
/// same front end as runout's and dem's run.hpp: `RunOptions`, `RunObserver`,
/// `CaseRun run_case(config, options, observer)`.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "geohaz/core/communicator.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/sph/constitutive.hpp"
#include "geohaz/sph/limit_equilibrium.hpp"
#include "geohaz/sph/loading.hpp"
#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"

namespace geohaz::sph {

/// Where the particles come from (Block: a free rectangle of soil, e.g. an elastic beam).
enum class ScenarioType { Slope, Column, Biaxial, Section, Block };

/// Shape of the first bending mode of a clamped–free Euler–Bernoulli beam, normalised to 1 at the
/// free end: φ(ξ) ∝ cosh kξ − cos kξ − s (sinh kξ − sin kξ), k = 1.87510, s = (cosh k + cos k)/(sinh k +
/// sin k), ξ = distance from the clamp / free length, clipped to [0, 1] (e.g. Timoshenko & Young 1955).
double cantilever_mode_shape(double xi);

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

/// Map position (DSM CRS) of the section point at distance s along the polyline and offset t to its
/// left (perpendicular to the local segment). s is clamped to the polyline.
Vec2 section_map_point(const std::vector<ProfilePoint>& profile, double s, double t);

/// Check the cross-field consistency of a config that the per-key ranges cannot express and build
/// the particles (dry run). Throws InputError naming the key. Called before any output is created.
void validate(const RunConfig& cfg);

/// A table of a run (the columns of one CSV file), numbers only.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;  ///< one value per column
  /// Columns written as integers (a count, a flag); the others with 9 significant digits.
  std::vector<bool> integer;
  /// The CSV text: the header, then one line per row (what the app writes).
  std::string csv() const;
};

/// A named table: `name` is the stem of its CSV file ("series", "structure_forces", ...).
struct NamedTable {
  std::string name;
  Table table;
};

/// The particle fields of a run's final state (of the mechanism, for a strength reduction), every
/// particle (soil and boundary), row-major arrays.
struct ParticleFields {
  int dimension = 2;
  std::size_t count = 0;
  std::vector<double> position;           ///< m, count × dimension
  std::vector<double> velocity;           ///< m/s, count × dimension
  std::vector<double> displacement;       ///< m, count × dimension
  std::vector<double> stress;             ///< Pa, count × 3 × 3 (tension positive)
  std::vector<double> plastic_strain;     ///< 1, accumulated plastic strain
  std::vector<double> pore_pressure;      ///< Pa, the prescribed u (compression positive; 0 when dry)
  std::vector<double> density;            ///< kg/m³
  std::vector<double> mass;               ///< kg (per metre out of the plane in 2D)
  std::vector<std::int32_t> material_id;  ///< index into the [[material]] list
  std::vector<std::uint8_t> kind;         ///< Kind (fields.hpp): 0 soil, else a boundary
  std::vector<std::int64_t> id;           ///< particle id, stable through reorderings
};

/// Where a run is when the observer is told about it.
struct RunProgress {
  const char* phase = "";     ///< "geostatic", "main" or "trial" (strength reduction)
  double time = 0.0;          ///< simulated time of the phase (s)
  double end_time = 0.0;      ///< simulated time at which the phase ends (s)
  std::int64_t steps = 0;     ///< steps of the phase so far
  std::size_t particles = 0;  ///< particles in the store
  double factor = 0.0;        ///< trial: the strength reduction factor F
  bool done = false;          ///< the phase (or trial) has ended: its last call
};

class SphSimulation;

/// Sees a run as it goes (progress, snapshots, pictures). Default: nothing. A callback may throw to
/// stop the run; the exception goes on through SphSimulation::run.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// Every 50 steps of the geostatic phase or of a strength-reduction trial, and at its end.
  virtual void progress(const SphSimulation&, const RunProgress&) {}
  /// The main phase (or, for a strength reduction, the first trial) is about to start from the
  /// state after the geostatic phase or the restart.
  virtual void started(const SphSimulation&) {}
  /// Main phase: before each step, on the state the step starts from.
  virtual void before_step(const SphSimulation&) {}
  /// Main phase: after each step.
  virtual void stepped(const SphSimulation&) {}
  /// After the last step (the final row of the series is recorded).
  virtual void finished(const SphSimulation&) {}
};

class SphRunFiles;

/// One run: the scenario's particles, the solver, the time series and the figures of the summary.
class SphSimulation {
 public:
  /// Build the scenario and the solver of `cfg` (checked by validate() first); unless `quiet`,
  /// print the particle counts and the materials on stderr. Keeps a reference to `cfg`: it must
  /// outlive the simulation. With `comm` the run is spread over its ranks (domain decomposition,
  /// docs/sph.md): every rank constructs and runs the same simulation, collectively; what cannot run
  /// on several ranks yet is refused first (check_distributable).
  explicit SphSimulation(const RunConfig& cfg, bool quiet = true, std::shared_ptr<const Communicator> comm = nullptr);
  ~SphSimulation();
  SphSimulation(const SphSimulation&) = delete;
  SphSimulation& operator=(const SphSimulation&) = delete;

  /// Run to the end (end_time or at rest; or the whole strength-reduction bracketing).
  /// SimulationError on a blow-up: the series so far stays readable through tables().
  void run(RunObserver* observer = nullptr);

  const RunConfig& config() const noexcept { return cfg_; }
  double time() const;              ///< simulated time of the main phase (s)
  std::int64_t step_count() const;  ///< steps of the main phase
  std::size_t particle_count() const;
  /// The main phase has started (a SimulationError after this point leaves a series to write).
  bool main_phase_started() const;

  /// The text of summary.json (the app and the Python module read the same numbers).
  std::string summary_json() const;
  /// The CSV tables of the run so far, by file stem (series, structure_forces, stress_strain,
  /// surface_final, slip_surface; srm_trials, srm_curve, bishop_circle for a strength reduction).
  std::vector<NamedTable> tables() const;
  /// The particle fields now (the failure mechanism for a strength reduction; empty if none).
  ParticleFields particles() const;

 private:
  friend class SphRunFiles;
  friend void write_outputs(const SphSimulation& sim, const std::filesystem::path& out);
  friend void run_with_outputs(SphSimulation& sim, const std::filesystem::path& out, bool quiet, RunObserver* observer);
  struct Impl;
  const RunConfig& cfg_;
  std::unique_ptr<Impl> impl_;
};

/// Write the outputs of a finished `sim` into the existing directory `out`: the CSV tables, the
/// quick-look PNGs, release.h5 (+ release_thickness.tif) for a section and summary.json.
void write_outputs(const SphSimulation& sim, const std::filesystem::path& out);

/// Run `sim` the way the app does: when `out` is not empty, create it, write the resolved config
/// and the snapshots (and velocity PNGs) during the run, the outputs after it (and, on a
/// SimulationError in the main phase, the series so far); progress on stderr unless `quiet`.
/// `observer` (optional) sees the run too.
void run_with_outputs(SphSimulation& sim, const std::filesystem::path& out, bool quiet,
                      RunObserver* observer = nullptr);

/// How run_case runs (the fields of runout's RunOptions but its thread count, which only the runout
/// summary records, and the ranks of a distributed run).
struct RunOptions {
  std::filesystem::path out;  ///< folder of the outputs (created by run_case); empty: none
  bool quiet = false;         ///< no particle counts or progress on stderr
  /// The ranks of a run over several processes (sph-slope-mpi; SphSimulation); null: one process.
  std::shared_ptr<const Communicator> comm;
};

/// A run that has ended: the particles, tables and figures in their final state. The simulation
/// refers to the config given to run_case, which must outlive it.
struct CaseRun {
  std::unique_ptr<SphSimulation> simulation;
};

/// The whole `sph-slope` run of a validated config (validate): build, then run_with_outputs into
/// `options.out` (created; empty: nothing written), `observer` (may be null) called too. Returns the
/// run. With `options.comm`, over its ranks (SphSimulation): every rank calls it with the same
/// `out`; rank 0 makes the folder and writes the outputs, every rank its part of the snapshots
/// (core SnapshotWriter over several processes; the folder must be on a file system every rank
/// sees).
CaseRun run_case(const RunConfig& cfg, const RunOptions& options, RunObserver* observer = nullptr);

/// What a run over several ranks cannot do yet (issue #36; docs/sph.md, "Domain decomposition"):
/// InputError naming the key for the total-Lagrangian formulation (numerics.formulation). Every
/// analysis runs (the dynamic one and the strength reduction with the particles over the ranks, the
/// limit-equilibrium one on every rank alike), with its outputs, snapshots and restarts.
void check_distributable(const RunConfig& cfg);

}  // namespace geohaz::sph
