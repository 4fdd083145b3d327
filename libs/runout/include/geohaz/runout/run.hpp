#pragma once
/// \file run.hpp
/// A complete debris-runout run, callable from C++ without a subprocess (the app, the ensemble
/// runner and the Python module all go through it). Three steps, each with one job:
///
///  1. `load_inputs(case)`: read and validate the DSM and the release (polygons, thickness raster
///     or a hand-off file from sph-slope, docs/handoff.md) as a thickness on the DSM grid. Throws
///     InputError (file, key, value); writes nothing.
///  2. `RunoutSimulation sim(inputs, params)`: seeds the particles (volume-exact) and checks that
///     they are on the terrain (InputError otherwise); `sim.run(observer)` steps to the end while
///     painting the hazard maps and the time series; the observer sees every step (progress,
///     snapshots). SimulationError on a blow-up, with the state so far kept in the object.
///  3. `write_outputs(...)`: the rasters, pictures, series and summary into a directory.
///
/// `run_case(case, out, quiet)` chains them the way `debris-runout` does (outputs created only
/// after every input is valid; snapshots during the run; progress on stderr).

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geohaz/core/raster.hpp"
#include "geohaz/runout/gauges.hpp"
#include "geohaz/runout/hazard_maps.hpp"
#include "geohaz/runout/processes.hpp"
#include "geohaz/runout/release.hpp"
#include "geohaz/runout/solver.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz {
class ConfigReader;
}

namespace geohaz::runout {

/// How a release thickness (polygon attribute, uniform depth or raster) is measured.
enum class ThicknessDirection {
  Normal,   ///< normal to the slope (AvaFrame com1DFA, RAMMS): a cell holds t/cos θ vertically
  Vertical  ///< vertically: a cell holds t
};
const char* to_string(ThicknessDirection d) noexcept;

/// Where the release comes from (exactly one of `file` and `handoff` is set).
struct ReleaseSpec {
  std::string file;                     ///< polygons (Shapefile, GeoJSON, GPKG, …) or a thickness raster (m)
  std::string handoff;                  ///< hand-off file with points and volumes (sph-slope's release.h5)
  std::string attribute = "thickness";  ///< polygon attribute holding the thickness (m)
  double depth = 0.0;                   ///< uniform polygon thickness (m); 0: use the attribute
  /// How `file`'s thicknesses are measured (a hand-off carries volumes: no direction).
  ThicknessDirection direction = ThicknessDirection::Normal;
};

/// Where the spatial processes come from (docs/runout.md, "Processes"); empty: not used.
struct ProcessSpec {
  std::string zones;  ///< friction zones: polygons with attributes named n, icr, m, mu, xi
  std::array<std::string, kFrictionParameters> zone_rasters;  ///< a raster per coefficient (by FrictionParameter)
  std::string forest;             ///< forest polygons (attributes stem_density, stem_diameter) or stem-density raster
  double stem_density = 0.0;      ///< stems per m² where the polygons carry none (1/m²)
  double stem_diameter = 0.3;     ///< stem diameter where the polygons carry none (m)
  double drag_coefficient = 1.0;  ///< C_D of a stem (1)
  std::string erodible;           ///< erodible depth raster (m) or polygons
  std::string erodible_attribute = "depth";  ///< polygon attribute of the erodible depth (m)
  double erodible_depth = 0.0;               ///< uniform polygon depth (m); 0: use the attribute
  std::string hydrograph;                    ///< inflow table (CSV time_s, discharge_m3_per_s)
  std::vector<double> inflow_points;         ///< [x, y] or [x1, y1, x2, y2] (m, DSM CRS)
  double inflow_azimuth = -1.0;              ///< degrees clockwise from north; < 0: down the slope
  double inflow_speed = 5.0;                 ///< surface speed of the inflowing particles (m/s)
};

/// Read the fields and the inflow of `s` onto the DSM grid (InputError naming file, key, value).
SpatialProcesses load_processes(const ProcessSpec& s, const RunoutParameters& p, const Raster& dsm,
                                const GridSurface& surface);

/// Where the barriers come from (docs/runout.md, "Barriers"); empty file: none.
struct BarrierSpec {
  std::string file;                                     ///< lines (Shapefile, GeoJSON, GPKG, …)
  std::string height_attribute = "height";              ///< attribute of the crest height above the terrain (m)
  double height = 0.0;                                  ///< crest height where the attribute is absent or null (m)
  std::string permeability_attribute = "permeability";  ///< attribute of the open fraction (1)
  double permeability = 0.0;                            ///< open fraction where the attribute is absent or null (1)
  WallLaw law;                                          ///< restitution, wall friction, retention distance
};

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

/// What to write besides the maps and the summary.
struct OutputSettings {
  double series_interval = 1.0;                             ///< s between rows of series.csv
  double snapshot_interval = 30.0;                          ///< s between particle snapshots
  bool snapshots = true;                                    ///< snapshots.h5 + .xmf
  bool pngs = true;                                         ///< quick-look PNGs
  IntensityTable intensity;                                 ///< classes of intensity.tif
  std::vector<double> map_depth_classes{0.5, 1.0, 2.0};     ///< class breaks of the depth maps (m)
  std::vector<double> map_pressure_classes{3e3, 3e4, 1e5};  ///< class breaks of the pressure map (Pa)
  std::vector<double> map_speed_classes{1.0, 3.0, 10.0};    ///< class breaks of the speed maps (m/s)
  double map_margin = 200.0;                                ///< m around the affected area in the maps
  std::string attribution;                                  ///< printed under every map ("" : the DSM's)
  /// A particle alone within 2·d0 paints the peak maps only where the depth it stands for exceeds
  /// this (m); below it is detached (hazard_maps.hpp). AvaFrame com1DFA's hmin.
  double sparse_min_depth = 0.05;
  std::vector<GaugeSpec> gauges;     ///< points and cross-section lines (gauges.hpp); none: no gauges.csv
  double gauge_interval = 1.0;       ///< s between the rows of gauges.csv
  std::vector<Vec2> profile_path;    ///< the profile along this path (m, DSM CRS); empty: the flow's centreline
  std::string profile_path_file;     ///< or along the first line of this vector file
  double profile_half_width = 50.0;  ///< m across the path over which the profile takes the peaks
};

/// Everything a run needs, in SI units. Defaults are those of the structs it holds.
struct RunoutCase {
  std::string dsm;  ///< terrain raster (projected CRS, metres)
  ReleaseSpec release;
  ProcessSpec processes;
  BarrierSpec barriers;
  RunoutParameters params;
  OutputSettings output;
  std::string resolved_config;  ///< TOML text of the resolved configuration (written beside the outputs)
  std::string config_source;    ///< config file the case came from ("" for none), for messages
};

/// Read every debris-runout key from `cfg` (defaults from RunoutCase's structs; ranges, units and
/// help text declared here once, so the app, the ensemble runner and `--help-config` agree).
/// Does not call cfg.finish(). Relative paths are resolved against the config file's folder when
/// they do not exist as given.
RunoutCase read_case(ConfigReader& cfg);

/// A coefficient key of a basal law as read_case declares it.
struct FrictionKey {
  std::string key;    ///< "model.tau_y"
  std::string label;  ///< the key's help text up to its list of laws ("yield stress τ_y")
  std::string unit;   ///< "Pa"
};
/// The model.* coefficient keys the basal law `law` (a model.friction value) reads, in
/// declaration order; empty for an unknown law. For tools that show a run's parameters (the report).
std::vector<FrictionKey> friction_keys(std::string_view law);
/// Any debris-runout key as read_case declares it (key_labels.cpp): a basal law's coefficient as
/// friction_keys gives it, any other key labelled by its help text up to the first " (", ": ",
/// "; " or ", " ("mixture density ρ"), with the declared unit ("kg/m^3"; "1" dimensionless, ""
/// for a string). std::nullopt for a key read_case does not declare. For tools that show a run's
/// or an ensemble's parameters (the report), so labels and units have one source.
std::optional<FrictionKey> case_key(std::string_view key);

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
RunoutInputs load_inputs(const RunoutCase& c);

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
std::string summary_json(const RunoutCase& c, const RunoutSimulation& sim, int threads,
                         const ThalwegProfile* profile = nullptr);

/// Write the maps (GeoTIFF on the DSM grid and CRS), the quick-look PNGs, series.csv and
/// summary.json of `sim` into the existing directory `out`.
void write_outputs(const RunoutCase& c, const RunoutSimulation& sim, const std::filesystem::path& out, int threads);

/// The whole `debris-runout` run: load and check the inputs, seed, and only then create `out`,
/// write the resolved config, run with snapshots and progress (stderr, unless quiet), and write the
/// outputs. Returns the result.
RunoutResult run_case(const RunoutCase& c, const std::filesystem::path& out, bool quiet, int threads);

}  // namespace geohaz::runout
