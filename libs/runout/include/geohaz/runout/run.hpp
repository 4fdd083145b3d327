#pragma once
/// \file run.hpp
/// A complete debris-runout run, callable from C++ without a subprocess (the app, the ensemble
/// runner and the Python module all go through it). The configuration and its reader are in
/// config.hpp. Three steps, each with one job:
///
///  1. `load_inputs(config)`: read and validate the DSM and the release (polygons, thickness raster
///     or a hand-off file from sph-slope, docs/handoff.md) as a thickness on the DSM grid. Throws
///     InputError (file, key, value); writes nothing.
///  2. `RunoutSimulation sim(inputs, params)`: seeds the particles (volume-exact) and checks that
///     they are on the terrain (InputError otherwise); `sim.run(observer)` steps to the end while
///     painting the hazard maps and the time series; the observer sees every step (progress,
///     snapshots). SimulationError on a blow-up, with the state so far kept in the object.
///  3. `write_outputs(...)`: the rasters, pictures, series and summary into a directory.
///
/// `run_case(config, options, observer)` chains them the way `debris-runout` does (outputs created
/// only after every input is valid; snapshots during the run; progress on stderr) and returns the
/// run: the app and the Python module call only it.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"
#include "geohaz/runout/config.hpp"
#include "geohaz/runout/gauges.hpp"
#include "geohaz/runout/hazard_maps.hpp"
#include "geohaz/runout/processes.hpp"
#include "geohaz/runout/release.hpp"
#include "geohaz/runout/solver.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {

/// Read the fields and the inflow of `s` onto the DSM grid (InputError naming file, key, value).
SpatialProcesses load_processes(const ProcessSpec& s, const RunoutParameters& p, const Raster& dsm,
                                const GridSurface& surface);

/// Read the barrier lines of `s` in the DSM's CRS and check them (InputError naming the file, the
/// feature and the value: a line leaving the DSM, a height outside (0, 100] m, a permeability
/// outside [0, 1), a feature that is not a line). The side of each line holding `upstream_point`
/// (the release) is its upstream side.
std::vector<Barrier> load_barriers(const BarrierSpec& s, const Raster& dsm, const GridSurface& surface,
                                   const Vec2& upstream_point);

/// One row of a barrier's time series: the means over the window since the previous row.
struct BarrierRow {
  double time = 0.0;           ///< end of the window (s)
  double force = 0.0;          ///< normal force, impulse taken over the window / its duration (N)
  double wetted_length = 0.0;  ///< length of the bins touched in the window (m)
  double force_per_m = 0.0;    ///< force / wetted length (N/m)
  double depth = 0.0;          ///< largest depth at the wall h_w in the window (m)
  double pressure = 0.0;       ///< force_per_m / depth (Pa)
  double passed = 0.0;         ///< net volume crossed from the upstream side so far (m³)
};

/// The figures of one barrier at the end of a run.
struct BarrierResult {
  std::string name;
  double height = 0.0, permeability = 0.0, length = 0.0;  ///< m, 1, m
  double peak_force = 0.0;                                ///< N
  double peak_force_per_m = 0.0;                          ///< N/m
  double peak_pressure = 0.0;                             ///< Pa
  double retained = 0.0;    ///< volume on the upstream side within the retention distance (m³)
  double overtopped = 0.0;  ///< net volume that crossed (m³)
  double impulse = 0.0;     ///< total normal impulse (N·s)
};

/// The DSM and the release, read and checked.
struct RunoutInputs {
  Raster dsm;                     ///< the terrain raster as read (nodata marked in `dsm.nodata`)
  GridSurface surface;            ///< bilinear surface through the DSM (NaN = nodata)
  std::vector<double> thickness;  ///< release thickness on the DSM grid (m, vertical)
  double volume = 0.0;            ///< release volume read (m³)
  std::string description;        ///< "polygons relAlr.shp", "points from release.h5 (…)"
  std::string source;             ///< the release file (for messages)
  bool from_handoff = false;      ///< the release came as points with volumes
  SpatialProcesses processes;     ///< friction zones, forest, erodible layer, inflows
  /// Barrier lines in the DSM's CRS with their crest heights (the maps draw them) and the wall law.
  std::vector<Barrier> barriers;
  WallLaw wall_law;
  std::string barrier_source;  ///< the barrier file ("" for none)
  /// The profile's path given by the user (output.profile_path or the line of
  /// output.profile_path_file, in the DSM's CRS), checked; empty: the flow's own centreline.
  std::vector<Vec2> profile_path;

  const GridGeometry& grid() const noexcept { return surface.geometry(); }
};

/// Read and validate the DSM and the release of `c` (InputError naming file, key and value).
RunoutInputs load_inputs(const RunConfig& c);

/// North-up grid geometry of a raster.
GridGeometry geometry_of(const Raster& r);

class RunoutSimulation;

/// Sees a run as it goes (progress bars, snapshot writers). Default: nothing.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// After seeding, before the first step.
  virtual void started(const RunoutSimulation&) {}
  /// After every step.
  virtual void stepped(const RunoutSimulation&) {}
  /// After the last step.
  virtual void finished(const RunoutSimulation&) {}
};

/// How a run ended.
enum class RunEnd { Running, Duration, AllStopped, NoParticles, KineticEnergy };
const char* to_string(RunEnd e) noexcept;

/// The key figures of a finished (or interrupted) run.
struct RunoutResult {
  RunoutSummary path;  ///< run-out, fahrböschung, centre of mass
  VolumeBudget volumes;
  double max_speed = 0.0;              ///< m/s, over the whole map
  double max_pressure = 0.0;           ///< Pa, ρ·(max speed)²
  double affected_area = 0.0;          ///< m², cells with max depth > 0
  double deposit_raster_volume = 0.0;  ///< m³, integral of the deposit raster
  double mobile_raster_volume = 0.0;   ///< m³, integral of mobile_at_end
  double max_speed_at_end = 0.0;       ///< m/s, fastest particle when the run ended
  /// Fraction of the released volume still moving at the end (1).
  double mobile_fraction() const noexcept { return volumes.initial > 0.0 ? volumes.mobile / volumes.initial : 0.0; }
  /// The run ended at its duration with more than 1 % of the volume moving: the maps are of an
  /// unfinished flow.
  bool unfinished() const noexcept { return ended == RunEnd::Duration && mobile_fraction() > 0.01; }
  std::size_t particles_released = 0, particles_left = 0;
  double simulated_time = 0.0;  ///< s
  std::int64_t steps = 0;
  double wall_time = 0.0;  ///< s spent in run()
  RunEnd ended = RunEnd::Running;
};

/// One run: particles seeded from the inputs, the solver, the hazard maps and the time series.
class RunoutSimulation {
 public:
  /// Seed the release of `in` with `params`; InputError when a particle would start off the terrain
  /// or the release needs more than `max_particles`. Keeps a reference to `in`'s surface: `in`
  /// must outlive the simulation.
  RunoutSimulation(const RunoutInputs& in, RunoutParameters params, OutputSettings output = {},
                   std::size_t max_particles = 20'000'000);

  /// Step until the run ends (duration, all at rest, no particles left). Rows of the time series
  /// are taken every output.series_interval. SimulationError on a blow-up (the state so far, maps
  /// and series included, stays readable).
  void run(RunObserver* observer = nullptr);

  const RunoutSolver<GridSurface>& solver() const noexcept { return solver_; }
  const RunoutParameters& parameters() const noexcept { return solver_.parameters(); }
  const OutputSettings& output() const noexcept { return output_; }
  const HazardMaps& maps() const noexcept { return maps_; }
  const std::vector<SeriesRow>& series() const noexcept { return series_; }
  /// Per barrier, its time series (a row with every row of series()).
  const std::vector<std::vector<BarrierRow>>& barrier_series() const noexcept { return barrier_series_; }
  /// The gauges of output.gauges (rows every output.gauge_interval).
  const GaugeRecorder& gauges() const noexcept { return gauges_; }
  /// Per barrier, its figures now.
  std::vector<BarrierResult> barrier_results() const;
  const SeedReport& seeded() const noexcept { return seeded_; }
  const RunoutInputs& inputs() const noexcept { return in_; }
  /// Final deposit thickness on the DSM grid (m, vertical). When the run ended at its duration with
  /// mass still moving, only the resting particles: the moving ones are mobile_at_end(). Ended by
  /// the kinetic-energy criterion (the flow has come to rest in the sense of practice), at rest, or
  /// still running: every particle.
  std::vector<double> deposit() const;
  /// Thickness (m, vertical) of the particles still moving when the run ended at its duration
  /// (zero otherwise).
  std::vector<double> mobile_at_end() const;
  /// The key figures now.
  RunoutResult result() const;

 private:
  const RunoutInputs& in_;
  OutputSettings output_;
  RunoutSolver<GridSurface> solver_;
  SeedReport seeded_;
  HazardMaps maps_;
  ReleaseTop top_;
  std::vector<SeriesRow> series_;
  std::vector<std::vector<BarrierRow>> barrier_series_;
  GaugeRecorder gauges_;
  std::vector<double> last_impulse_;
  double last_row_time_ = 0.0;
  void record_barrier_rows();
  double next_series_ = 0.0;
  double wall_time_ = 0.0;
};

struct ThalwegProfile;
/// The key figures of `sim` as the JSON text of summary.json (the app, the Python module and the
/// ensemble runner read the same numbers); with the run's `profile` (write_outputs) its "profile"
/// block too: H, L and H/L along the profile path beside the toe path's "fahrboeschung".
std::string summary_json(const RunConfig& c, const RunoutSimulation& sim, int threads,
                         const ThalwegProfile* profile = nullptr);

/// Write the maps (GeoTIFF on the DSM grid and CRS), the quick-look PNGs, series.csv and
/// summary.json of `sim` into the existing directory `out`.
void write_outputs(const RunConfig& c, const RunoutSimulation& sim, const std::filesystem::path& out, int threads);

/// How run_case runs.
struct RunOptions {
  std::filesystem::path out;  ///< folder of the outputs (created only once every input is valid); empty: none
  bool quiet = false;         ///< no description, progress or end lines on stderr (warnings still on stdout)
  int threads = 1;            ///< OpenMP threads (set up by the caller; written into summary.json)
};

/// A run that has ended: what it read, the particles and maps in their final state, and its figures.
struct CaseRun {
  std::unique_ptr<RunoutInputs> inputs;          ///< the DSM, release and processes (the simulation refers to them)
  std::unique_ptr<RunoutSimulation> simulation;  ///< the final state: particles, maps, series
  RunoutResult result;                           ///< simulation->result()
};

/// The whole `debris-runout` run: load and check the inputs, seed, and only then (options.out not
/// empty) create the folder, write the resolved config and run with snapshots; progress on stderr
/// (unless quiet), `observer` (may be null) called too; then the outputs. Returns the run.
CaseRun run_case(const RunConfig& c, const RunOptions& options, RunObserver* observer = nullptr);

}  // namespace geohaz::runout
