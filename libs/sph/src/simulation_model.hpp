#pragma once
// Private to libs/sph/src: the interface every sph-slope analysis implements (run_dynamic.cpp: the
// dynamic run; run_strength_reduction.cpp: the strength reduction; limit_equilibrium_run.cpp:
// Bishop's method with water and seismic coefficients), and the limit-equilibrium helpers the
// analyses share. What the files of a run share besides: run_support.hpp.

#include <array>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "geohaz/core/snapshot.hpp"
#include "geohaz/sph/limit_equilibrium.hpp"
#include "geohaz/sph/run.hpp"

namespace geohaz::sph {

/// What a simulation is, whatever its dimension and analysis: the dynamic run or the strength
/// reduction, in 2D or 3D. Called once per phase or output, never per particle.
class SimulationModel {
 public:
  virtual ~SimulationModel() = default;
  virtual void run(const SphSimulation& self, RunObserver* obs) = 0;
  virtual double time() const = 0;
  virtual std::int64_t step_count() const = 0;
  virtual std::size_t particle_count() const = 0;
  virtual bool main_phase_started() const = 0;
  virtual nlohmann::json summary() const = 0;
  virtual std::vector<NamedTable> tables() const = 0;
  virtual ParticleFields particles() const = 0;
  /// The state a snapshot shows now (SphRunFiles: at the start, at snapshot times, at the end).
  /// Over several ranks collective: every rank writes its part through the same writer.
  virtual void write_snapshot(SnapshotWriter& w) const = 0;
  /// Quick-look PNGs whose time has come (before a main-phase step). Over several ranks collective
  /// (the whole state is gathered for a picture), rank 0 draws.
  virtual void draw_due_pngs(const std::filesystem::path& out) = 0;
  /// Every output of a finished run into `out`; a line on stderr unless quiet.
  virtual void write_outputs(const std::filesystem::path& out) const = 0;
  /// After a SimulationError in the main phase: the series so far.
  virtual void write_partial(const std::filesystem::path& out) const = 0;
};

/// The limit-equilibrium section of a 2D slope scenario: its profile, layers, soils (γ = ρ g, γ_sat
/// = ρ_sat g), the config's pore water and seismic coefficients (`with_water_and_seismic`). Throws
/// InputError for other scenarios or what the section cannot represent.
SlopeSection limit_equilibrium_section(const RunConfig& c, bool with_water_and_seismic);

/// The cross-field checks of [water] and [seismic] (InputError naming the key): water only on a 2D
/// slope, the history's arrays, k_h and k_v not in a dynamic run (its earthquake is the record), the water's own
/// checks (SlopeSection::validate_water).
void validate_water_and_seismic(const RunConfig& c);

/// The phreatic surface clipped to the ground of the 2D slope (sampled finely): what the SPH solver
/// and the Bishop check beside it use (no ponded water, the ground a seepage face).
std::vector<std::array<double, 2>> clipped_phreatic_surface(const RunConfig& c);

// ---- run_pore_water.cpp

/// The rain's pore pressure of a config with rain.enabled (pore_pressure.hpp) for the solver: under
/// the ground polyline of the slope (2D, or uniform across a 3D width) or of a 2D DSM section, or
/// under the ground grid of a 3D DSM strip. Its clock: rain.clock_times in a dynamic run, held at
/// rain.evaluate_at in the other analyses.
std::shared_ptr<const RainPorePressure> rain_pore_pressure(const RunConfig& c);

/// The same under the ground polyline of the section's 2D profile in every dimension (Bishop's slices).
std::shared_ptr<const RainPorePressure> rain_pore_pressure_on_profile(const RunConfig& c);

/// The checks of the sources of pore water (InputError naming the key): one at a time; the rasters
/// (water.table_raster, water.pore_pressure_raster) only on a DSM section, covering it (a table raster
/// below the ground somewhere); a phreatic polyline on the slope; r_u and rain on the slope or a
/// section; rain's β > 0 on every segment (cell) of the ground.
void validate_water_sources(const RunConfig& c);

/// Bishop's pore water of rain at the rain's time t_r (s): u from the rain's head on the slice bases,
/// the initial table (parallel to the ground) for the saturated weights.
void apply_rain(PoreWater& w, const std::shared_ptr<const RainPorePressure>& rain, double t_rain);

/// The water table of a 2D DSM section's raster (water.table_raster, or the piezometric level of
/// water.pore_pressure_raster) cut along it: (s, z_w) at the profile's points. InputError naming the
/// raster's key where it has no value.
std::vector<std::array<double, 2>> section_water_table(const RunConfig& c);

/// The same over a 3D DSM strip: z_w and the DSM's z_g on a grid of the strip's local coordinates at
/// the particle spacing. InputError naming the raster's key where it has no value (geometry.width
/// where the strip leaves the DSM).
std::shared_ptr<const WaterTableGrid> section_water_table_grid(const RunConfig& c);

/// The solver's pore water of a config (dry unless [water] has a phreatic surface, r_u or a raster
/// on a section, or [rain] is enabled).
PoreWaterSettings pore_water_settings(const RunConfig& c);

/// Saturated density below the water table at the start (rain: the initial table): each soil particle of a material
/// with a saturated density whose position lies below the clipped table takes ρ_sat (mass and density scaled by
/// ρ_sat/ρ).
template <int Dim>
void saturate_below_water_table(const RunConfig& c, SphStore<Dim>& s) {
  const auto pw = pore_water_settings(c);
  if (pw.phreatic.empty() && !pw.rain && !pw.table) return;  // r_u: the materials' own densities, as Bishop's
  const auto& x = s.template get<Position<Dim>>();
  const auto& kind = s.template get<ParticleKind>();
  const auto& mat = s.template get<MaterialId>();
  auto& m = s.template get<Mass>();
  auto& rho = s.template get<Density>();
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (kind[i] != static_cast<std::uint8_t>(Kind::Soil)) continue;
    const auto k = static_cast<std::size_t>(mat[i]);
    const double sat = k < c.saturated_densities.size() ? c.saturated_densities[k] : 0.0;
    double level = 0.0;
    if (pw.rain && pw.rain->grid()) {
      if constexpr (Dim == 3) level = pw.rain->initial_level(x[i][0], x[i][1]);
    } else if (pw.rain)
      level = pw.rain->initial_level(x[i][0]);
    else if (pw.table)
      level = pw.table->level(x[i][0], x[i][Dim == 3 ? 1 : 0], 0.0);
    else
      level = pw.level(x[i][0], 0.0);
    if (!(sat > 0.0) || x[i][Dim - 1] >= level) continue;
    const double f = sat / c.materials[k].density;
    m[i] *= f;
    rho[i] *= f;
  }
}

/// The pore water of a run for summary.json (`water`): its source ("phreatic_surface", "ru", "rain" or
/// "none"), the keys' values, the history and, with rain, the rain, the hydrology, the clock and
/// Bishop's factor at the rain's time of the main-phase time t_end (s).
nlohmann::json water_summary(const RunConfig& c, double t_end);

/// The Newmark report of a 2D slope under the config's earthquake: the circle of the smallest yield
/// coefficient (static: no k_h), k_y, and the rigid-block displacement for the record applied in the
/// direction of sliding, as the SPH run applies it (and the other way). Null if no earthquake.
nlohmann::json newmark_report(const RunConfig& c);

/// The analysis run.analysis = limit_equilibrium.
std::unique_ptr<SimulationModel> make_limit_equilibrium_run(const RunConfig& c, bool quiet);

/// The analysis run.analysis = dynamic (run_dynamic.cpp) in the config's dimension.
std::unique_ptr<SimulationModel> make_dynamic_run(const RunConfig& c, bool quiet,
                                                  std::shared_ptr<const Communicator> comm = nullptr);

/// The analysis run.analysis = strength_reduction (run_strength_reduction.cpp) in the config's dimension;
/// with `comm` the geostatic phase and every trial over its ranks.
std::unique_ptr<SimulationModel> make_strength_reduction_run(const RunConfig& c, bool quiet,
                                                             std::shared_ptr<const Communicator> comm = nullptr);

}  // namespace geohaz::sph
