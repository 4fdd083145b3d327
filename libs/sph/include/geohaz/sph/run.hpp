#pragma once
/// \file run.hpp
/// A complete sph-slope run, callable from C++ without a subprocess (the app and the Python module
/// both go through it). The shape is that of debris-runout (libs/runout/run.hpp):
///
///  1. `read_config(ConfigReader&, describe)` (config.hpp, with RunConfig and its parts): every key
///     into a typed RunConfig (the DSM of a section and an accelerogram are read there).
///     `validate(cfg)`: the checks across keys and a dry-run build of the particles. Both throw
///     InputError (file, key, value) and write nothing.
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
#include "geohaz/sph/config.hpp"

namespace geohaz::sph {

/// Shape of the first bending mode of a clamped–free Euler–Bernoulli beam, normalised to 1 at the
/// free end: φ(ξ) ∝ cosh kξ − cos kξ − s (sinh kξ − sin kξ), k = 1.87510, s = (cosh k + cos k)/(sinh k +
/// sin k), ξ = distance from the clamp / free length, clipped to [0, 1] (e.g. Timoshenko & Young 1955).
double cantilever_mode_shape(double xi);

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
