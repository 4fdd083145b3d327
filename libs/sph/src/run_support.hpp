#pragma once
// Private to libs/sph/src: what the files of an sph-slope run share.
//   run.cpp                     the simulation object (SphSimulation) and the files of a run
//   run_scenario.cpp            the particles, solver settings and reported structures of a config
//   run_state.cpp               the geostatic phase, the snapshots and the restart from them
//   run_outputs.cpp             quick-look pictures, CSV tables, the head of summary.json
//   run_dynamic.cpp             run.analysis = dynamic
//   run_strength_reduction.cpp  run.analysis = strength_reduction
//   run_validate.cpp            the checks before anything is built (validate)
//   limit_equilibrium_run.cpp   run.analysis = limit_equilibrium and the static Bishop check
//   run_pore_water.cpp          the pore water of a config: the solver's settings, the rasters, the checks
// The templates below are instantiated for Dim = 2 and 3 in the file that defines them.

#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "geohaz/core/snapshot.hpp"
#include "geohaz/sph/diagnostics.hpp"
#include "geohaz/sph/limit_equilibrium.hpp"
#include "geohaz/sph/run.hpp"
#include "simulation_model.hpp"

namespace geohaz::sph {

// ---- run_scenario.cpp ------------------------------------------------------------------------

/// The name of a scenario in run.scenario ("slope", "column", ...).
const char* scenario_name(ScenarioType t);

/// A scenario as built and the frame its diagnostics are measured in.
template <int Dim>
struct Built {
  Scenario<Dim> sc;
  DiagnosticFrame frame;
};

/// Width of a 3D DSM strip as built: a whole number of spacings (the builder's ny·Δx), centred on
/// the polyline. The builder and the release export must agree on it.
double strip_width(const RunConfig& c);

/// The profile domain of a DSM cross-section (surface, extent, layers, bedrock; walls left default).
ProfileDomain section_profile(const RunConfig& c);

/// The configured soil layers (layer_tops, layer_materials) on a profile domain, or none (one
/// material) when the config gives no layers.
void apply_layers(ProfileDomain& d, const RunConfig& c);

/// Which particles `build` keeps: all (one process), block `part` of `parts` (a rank's share of a
/// distributed run: BuildShare in scenario.hpp), or none (`count_only`: validate's dry run).
struct Share {
  int part = 0, parts = 1;
  bool count_only = false;
};

/// A rank's share of a distributed run (all on one process: comm null).
inline Share share_of(const Communicator* comm) {
  return comm ? Share{comm->rank(), comm->size(), false} : Share{};
}

/// The particles of the configured scenario, as many as `share` keeps (the counts, structures and
/// extents are the whole scenario's; a clamped region's soil is counted over all of it).
template <int Dim>
Built<Dim> build(const RunConfig& c, const Share& share = {});

/// The solver settings of a config for its built scenario (the main phase).
template <int Dim>
SolverSettings<Dim> settings_for(const RunConfig& c, const Scenario<Dim>& sc);

/// The structures a run reports (`output.structures`, all when empty), as indices into the
/// scenario's table. InputError naming the key, the unknown name and the names that exist.
template <int Dim>
std::vector<std::size_t> reported_structures(const RunConfig& c, const std::vector<Structure<Dim>>& table);

// ---- run_state.cpp ---------------------------------------------------------------------------

/// The fields written to snapshots: the state a restart needs plus what the issue asks to see.
/// position_at_build (the positions of the last neighbour-list build) is restart state: the list,
/// hence the Verlet-skin decisions and the order of the pair sums, is rebuilt from it.
/// `pore_pressure` (a run with pore water): pore_pressure too (Pa; recomputed from the position in
/// every step, so a restart does not need it). Only the first `count` particles (a rank's owned
/// ones; a rank writing none of a state every rank holds: 0).
template <int Dim>
void write_fields(SnapshotWriter& w, const SphStore<Dim>& s, double t, std::int64_t step, bool pore_pressure = false,
                  std::size_t count = static_cast<std::size_t>(-1));

/// A snapshot of the solver's store (its owned particles over several ranks, which write it together
/// through a SnapshotWriter of several processes) and, as a root attribute, its solver state
/// (SolverState, the same on every rank).
template <int Dim>
void write_snapshot(SnapshotWriter& w, const SphSolver<Dim>& solver, std::int64_t step);

/// What a restart file gives besides the particles.
struct Restart {
  double time = 0.0;
  std::int64_t step = 0;             ///< the snapshot's step
  std::optional<SolverState> state;  ///< absent in files written before it existed
};

/// Replace the store by the last snapshot of a file written by sph-slope.
template <int Dim>
Restart load_restart(const std::filesystem::path& path, SphStore<Dim>& s, const Share& share = {});

/// The fields of a store as flat arrays (ParticleFields).
template <int Dim>
ParticleFields fields_of(const SphStore<Dim>& s);

/// The geostatic phase's duration (s): geostatic.duration, or 20 H/c_p when it is 0 (20 transits of
/// a P wave through the slope height let the loading waves die out under Cundall damping).
/// InputError (key geostatic.duration) above 100 times that default: 2000 wave transits is a
/// loading that has settled long before or never will (the phase's rest check says which), and
/// nothing a user means; a value of 1e9 s ran for hours (issue #29).
double geostatic_duration(const RunConfig& c, double href, double cmax);

/// The geostatic phase of `solver` over `dur` seconds, the observer told at the start, every 50
/// steps and at the end (phase "geostatic").
template <int Dim>
GeostaticReport geostatic_with_progress(SphSolver<Dim>& solver, double dur, const RunConfig& c,
                                        const SphSimulation& self, RunObserver* obs);

// ---- run_outputs.cpp -------------------------------------------------------------------------

/// A number as the CSV files and the error messages write it (9 significant digits).
std::string csv_number(double v);

/// What a particle picture shows (draw_particles).
struct ParticlePicture {
  std::string title;                                 ///< above the frame: the field and the time
  std::string bar;                                   ///< the colour bar's title with its unit: "displacement (m)"
  std::vector<std::array<double, 2>> overlay = {};   ///< a polyline in (x, z) drawn in red (a slip circle)
  std::string x_title = "x (m)", z_title = "z (m)";  ///< the axes' titles (particle_picture names them)
};

/// A picture of the run's particles: `title`, `bar` and `overlay` as given, the axes titled for the
/// scenario (a section: distance along its polyline and elevation; otherwise x and z).
ParticlePicture particle_picture(const RunConfig& c, std::string title, std::string bar,
                                 std::vector<std::array<double, 2>> overlay = {});

/// Quick-look picture in a frame of core's plotter (plot.hpp): the particles in the x–z plane as
/// discs Δx across at equal scale (1 m in x = 1 m in z), soil coloured by `value` on viridis,
/// boundary grey; x and z axes numbered in metres (titled pic.x_title, pic.z_title), `pic.title` above (in 3D followed
/// by the projection: every particle projected along y, the lowest y in front), a colour bar numbered from 0 to vmax
/// below, titled `pic.bar`; written with its panel recorded (check_plot_png).
template <int Dim>
void draw_particles(const std::filesystem::path& path, const SphStore<Dim>& s, const std::vector<double>& value,
                    double vmax, double dx, const ParticlePicture& pic);

/// The table of a list of (x, z) points ("x_m,z_m": a surface or a circle).
Table xz_table(const std::vector<std::array<double, 2>>& points);

/// The summary's description of the run's particles and materials (both analyses).
template <int Dim>
nlohmann::json summary_header(const RunConfig& c, const SphSolver<Dim>& solver, std::size_t soil_count);

// ---- limit_equilibrium_run.cpp ---------------------------------------------------------------

/// Bishop's critical circle of a 2D slope or DSM section (none otherwise), at peak strength or with
/// the residual strengths of a softening soil.
BishopResult bishop_of(const RunConfig& c, bool residual = false);

/// The Bishop cross-check beside a dynamic run of a 2D slope or section of frictional soil: the
/// static factor of the critical circle (with the run's pore water, if any) at peak strength (and, for a softening
/// soil, at residual strength), or a note saying why there is none.
struct StaticBishop {
  BishopResult peak, residual;
  InfiniteSlopeResult cover;  // the translational slide of a DSM section's soil cover
  std::string note;

  static StaticBishop of(const RunConfig& c);
  static nlohmann::json circle_json(const BishopResult& r);
  void add_to(nlohmann::json& s) const;
};

}  // namespace geohaz::sph
