/// \file summary_keys.cpp
/// Label, unit and group of every key sph-slope (run_outputs.cpp summary_header, run_dynamic.cpp,
/// run_strength_reduction.cpp, limit_equilibrium_run.cpp, structure_report.hpp) and
/// slope-stability (stability_map.cpp) write into summary.json (summary_keys.hpp). A key written
/// without a line here fails the apps' tests (tests/common/summary_keys_check.hpp). A 2D run
/// stands for one metre of width: its areas, forces and moments are per metre (m²/m, N/m, N·m/m).
/// The figures of each material (materials[].K_Pa, ...) are not listed here: they come from the
/// constitutive models' declarations (constitutive.hpp, MaterialFigure). A key whose value is a
/// config value (config_echo) names the config key: label and unit are its declaration's
/// (config.cpp, infiltration.cpp, stability_map.cpp).

#include "geohaz/sph/summary_keys.hpp"

#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/constitutive.hpp"
#include "geohaz/sph/stability_map.hpp"

namespace geohaz::sph {

namespace {

using G = SummaryGroup;

constexpr SummaryKey kKeys[] = {
    // volumes and areas
    {"release.total_volume_m3", "failed volume handed to the run-out", "m^3", G::Volumes, true},
    {"release.volume_on_raster_m3", "failed volume on the thickness raster", "m^3", G::Volumes},
    {"release.width_m", "width the section stands for", "m", G::Volumes},
    {"release.points", "release points handed to the run-out", "1", G::Volumes},
    {"failed_area_m2_per_m", "failed area of the section (per metre width)", "m^2/m", G::Volumes, true},
    {"failed_volume_m3", "failed volume", "m^3", G::Volumes, true},
    {"failed_particles", "failed particles", "1", G::Volumes},
    // reach
    {"max_runout_m", "largest run-out of the toe during the run", "m", G::Reach, true},
    {"runout_m", "run-out of the toe at the end", "m", G::Reach},
    {"normalised_runout", "run-out / slope height", "1", G::Reach},
    {"front_m", "front position at the end", "m", G::Reach},
    {"tip_m", "tip position at the end", "m", G::Reach},
    // peak values
    {"max_displacement_m", "largest displacement", "m", G::Peak, true},
    {"max_plastic_strain", "largest plastic strain", "1", G::Peak},
    {"max_speed_m_per_s", "peak speed", "m/s", G::Peak, true},
    {"final_max_speed_m_per_s", "largest speed at the end", "m/s", G::Peak},
    {"structures[]", "loads on the structures named in the config", "", G::Peak},
    {"structures[].name", "structure", "", G::Peak},
    {"structures[].id", "structure number", "1", G::Peak},
    {"structures[].base_m", "base point", "m", G::Peak},
    {"structures[].normal", "normal", "1", G::Peak},
    {"structures[].peak_resultant_N_per_m", "peak resultant force", "N/m", G::Peak},
    {"structures[].peak_normal_N_per_m", "peak normal force F·n", "N/m", G::Peak},
    {"structures[].peak_moment_Nm_per_m", "peak moment about the base", "N*m/m", G::Peak},
    {"structures[].peak_resultant_N", "peak resultant force", "N", G::Peak},
    {"structures[].peak_normal_N", "peak normal force F·n", "N", G::Peak},
    {"structures[].peak_moment_Nm", "peak moment about the base", "N*m", G::Peak},
    {"structures[].time_of_peak_resultant_s", "time of the peak resultant", "s", G::Peak},
    {"structures[].time_of_peak_normal_s", "time of the peak normal force", "s", G::Peak},
    {"structures[].time_of_peak_moment_s", "time of the peak moment", "s", G::Peak},
    // strength: factors of safety
    {"factor_of_safety", "factor of safety", "1", G::Strength, true},
    {"outcome", "strength reduction outcome", "", G::Strength},
    {"bracket", "factor of safety bracket (stands, fails)", "1", G::Strength},
    {"bishop.factor", "Bishop: factor of safety of the critical circle", "1", G::Strength, true},
    {"bishop.yield_coefficient", "Bishop: yield coefficient k_y", "1", G::Strength},
    {"bishop.centre_x_m", "Bishop circle: centre x", "m", G::Strength},
    {"bishop.centre_z_m", "Bishop circle: centre z", "m", G::Strength},
    {"bishop.radius_m", "Bishop circle: radius", "m", G::Strength},
    {"bishop.entry_x_m", "Bishop circle: entry x", "m", G::Strength},
    {"bishop.exit_x_m", "Bishop circle: exit x", "m", G::Strength},
    {"bishop.weight_N_per_m", "Bishop circle: weight of the sliding mass", "N/m", G::Strength},
    {"bishop.direction", "Bishop circle: direction of sliding (+1: +x)", "1", G::Strength},
    {"bishop_residual.factor", "Bishop with the residual strength: factor of safety", "1", G::Strength},
    {"bishop_residual.centre_x_m", "Bishop residual circle: centre x", "m", G::Strength},
    {"bishop_residual.centre_z_m", "Bishop residual circle: centre z", "m", G::Strength},
    {"bishop_residual.radius_m", "Bishop residual circle: radius", "m", G::Strength},
    {"bishop_residual.entry_x_m", "Bishop residual circle: entry x", "m", G::Strength},
    {"bishop_residual.exit_x_m", "Bishop residual circle: exit x", "m", G::Strength},
    {"bishop_residual.weight_N_per_m", "Bishop residual circle: weight of the sliding mass", "N/m", G::Strength},
    {"bishop_residual.direction", "Bishop residual circle: direction of sliding", "1", G::Strength},
    {"bishop_residual.yield_coefficient", "Bishop residual circle: yield coefficient", "1", G::Strength},
    {"yield.factor", "circle of the smallest yield coefficient: factor of safety", "1", G::Strength},
    {"yield.yield_coefficient", "smallest yield coefficient k_y", "1", G::Strength},
    {"yield.centre_x_m", "yield circle: centre x", "m", G::Strength},
    {"yield.centre_z_m", "yield circle: centre z", "m", G::Strength},
    {"yield.radius_m", "yield circle: radius", "m", G::Strength},
    {"yield.entry_x_m", "yield circle: entry x", "m", G::Strength},
    {"yield.exit_x_m", "yield circle: exit x", "m", G::Strength},
    {"yield.weight_N_per_m", "yield circle: weight of the sliding mass", "N/m", G::Strength},
    {"yield.direction", "yield circle: direction of sliding", "1", G::Strength},
    {"infinite_slope.factor", "infinite slope: factor of safety of the cover", "1", G::Strength},
    {"infinite_slope.x_m", "infinite slope: at x", "m", G::Strength},
    {"infinite_slope.angle_deg", "infinite slope: slope angle", "deg", G::Strength},
    {"infinite_slope.window_m", "infinite slope: averaging window", "m", G::Strength},
    {"newmark.factor", "Newmark: factor of safety of the sliding circle", "1", G::Peak},
    {"newmark.yield_coefficient", "Newmark: yield coefficient k_y", "1", G::Peak},
    {"newmark.yield_acceleration_m_per_s2", "Newmark: yield acceleration", "m/s^2", G::Peak},
    {"newmark.displacement_m", "Newmark displacement of the rigid block", "m", G::Peak, true},
    {"newmark.displacement_reversed_record_m", "Newmark displacement, record reversed", "m", G::Peak},
    {"newmark.max_velocity_m_per_s", "Newmark: peak sliding velocity", "m/s", G::Peak},
    {"newmark.sliding_time_s", "Newmark: sliding time", "s", G::Peak},
    {"newmark.episodes", "Newmark: sliding episodes", "1", G::Peak},
    {"newmark.time_step_s", "Newmark: time step", "s", G::Peak},
    {"newmark.sph_max_displacement_m", "largest SPH displacement (beside Newmark)", "m", G::Peak},
    {"newmark.centre_x_m", "Newmark circle: centre x", "m", G::Peak},
    {"newmark.centre_z_m", "Newmark circle: centre z", "m", G::Peak},
    {"newmark.radius_m", "Newmark circle: radius", "m", G::Peak},
    {"newmark.entry_x_m", "Newmark circle: entry x", "m", G::Peak},
    {"newmark.exit_x_m", "Newmark circle: exit x", "m", G::Peak},
    {"newmark.weight_N_per_m", "Newmark circle: weight of the sliding mass", "N/m", G::Peak},
    {"newmark.direction", "Newmark circle: direction of sliding", "1", G::Peak},
    {"newmark.note", "Newmark", "", G::Peak},
    {"newmark_note", "Newmark", "", G::Peak},
    {"bishop_note", "Bishop", "", G::Strength},
    // time
    {"end_time_s", "simulated time", "s", G::Time},
    {"time_to_rest_s", "time to come to rest", "s", G::Time, true},
    {"stopped_at_rest", "came to rest", "", G::Time},
    // slope-stability (stability_map.cpp)
    {"fs_min", "smallest factor of safety over the cells and times", "1", G::Strength, true},
    {"first_failure_during_rain_s", "first failure during the rain", "s", G::Time, true},
    {"failed_area_m2", "failed area", "m^2", G::Volumes, true},
    {"release.volume_m3", "release volume of the failed cells", "m^3", G::Volumes, true},
    {"release.polygons", "release polygons", "1", G::Volumes},
    {"release.file", "release file", "", G::Volumes},
    {"release.attribute", "release thickness attribute", "", G::Volumes},
    {"release.thickness_direction", "release thickness measured", "", G::Volumes},
    {"release.thickness_style", "release thickness style", "", G::Volumes},
    {"release.thickness_raster", "release thickness raster", "", G::Volumes},
    {"cells.grid", "cells of the grid", "1"},
    {"cells.with_soil_cover", "cells with a soil cover", "1"},
    {"cells.failed", "cells failed", "1", G::Volumes},
    {"cells.unstable_before_rain", "cells unstable before the rain", "1"},
    {"cells.cell_area_m2", "cell area", "m^2"},
    {"rain.steps", "rain: steps of the hyetograph", "1"},
    {"rain.end_s", "rain: end", "s"},
    {"rain.total_depth_m", "rain: total depth", "m"},
    {"rain.peak_intensity_m_per_s", "rain: peak intensity", "m/s"},
    config_echo("duration_s", "run.duration", G::Time),
    {"series[]", "unstable cells over time", ""},
    {"series[].time_s", "time", "s"},
    {"series[].unstable_cells", "unstable cells", "1"},
    // bookkeeping
    {"domain_decomposition.ranks", "MPI ranks", "1"},
    {"domain_decomposition.owned_particles", "particles owned by each rank at the end", "1"},
    {"domain_decomposition.ghost_particles", "ghost particles held by each rank at the end", "1"},
    {"domain_decomposition.migrated_particles", "particles that changed rank", "1"},
    {"domain_decomposition.partitions", "partitions of the domain", "1"},
    {"domain_decomposition.rebuilds", "neighbour-list rebuilds", "1"},
    config_echo("scenario", "run.scenario"),
    config_echo("analysis", "run.analysis"),
    config_echo("dimension", "run.dimension"),
    {"model", "model", ""},
    {"version", "geohaz version", ""},
    {"config", "config", ""},
    config_echo("dsm", "terrain.dsm"),
    {"threads", "threads", "1"},
    {"soil_particles", "soil particles", "1"},
    {"boundary_particles", "boundary particles", "1"},
    config_echo("spacing_m", "numerics.spacing"),
    {"smoothing_length_m", "smoothing length", "m"},
    {"steps", "time steps", "1"},
    {"time_step_s", "time step", "s"},
    config_echo("failed_threshold_m", "output.failed_threshold"),
    config_echo("front_thickness_m", "output.front_thickness"),
    config_echo("rest_speed_m_per_s", "run.rest_speed"),
    {"bytes_per_particle", "memory per particle", "bytes"},
    {"wall_time_s", "wall-clock time", "s"},
    config_echo("seismic.kh", "seismic.kh"),
    config_echo("seismic.kv", "seismic.kv"),
    config_echo("water.phreatic_surface", "water.phreatic"),
    config_echo("water.ru", "water.ru"),
    {"water.unit_weight_N_per_m3", "unit weight of water", "N/m^3"},
    config_echo("water.pore_pressure", "water.pore_pressure"),
    {"water.source", "pore water from", ""},
    config_echo("water.table_raster", "water.table_raster"),
    config_echo("water.pore_pressure_raster", "water.pore_pressure_raster"),
    config_echo("water.history_times_s", "water.history_times"),
    config_echo("water.history_offsets_m", "water.history_offsets"),
    {"water.max_pore_pressure_Pa", "largest pore pressure", "Pa", G::Peak},
    {"water.max_pore_pressure_time_s", "time of the largest pore pressure", "s", G::Time},
    config_echo("water.rain.intensity_m_per_s", "rain.intensity"),
    config_echo("water.rain.step_s", "rain.step"),
    {"water.rain.end_s", "rain: end", "s"},
    {"water.rain.depth_m", "rain: soil depth of the infiltration model", "m"},
    config_echo("water.rain.conductivity_m_per_s", "hydrology.conductivity"),
    config_echo("water.rain.diffusivity_m2_per_s", "hydrology.diffusivity"),
    config_echo("water.rain.steady_infiltration_m_per_s", "hydrology.steady_infiltration"),
    config_echo("water.rain.water_table_depth_m", "hydrology.water_table_depth"),
    config_echo("water.rain.clock_times_s", "rain.clock_times"),
    {"water.rain.rain_time_at_start_s", "rain time at the start of the run", "s"},
    {"water.rain.rain_time_at_end_s", "rain time at the end of the run", "s", G::Time},
    config_echo("water.rain.evaluate_at_s", "rain.evaluate_at", G::Time),
    {"water.rain.bishop_factor_at_end", "Bishop's factor of safety at the end of the rain clock", "1", G::Strength},
    config_echo("tolerance", "strength_reduction.tolerance"),
    config_echo("trial_duration_s", "strength_reduction.trial_duration"),
    config_echo("trial_damping", "strength_reduction.damping"),
    config_echo("growth_ratio", "strength_reduction.growth_ratio"),
    config_echo("knee_ratio", "strength_reduction.knee_ratio"),
    {"reference_displacement_m", "strength reduction: reference displacement", "m"},
    {"trials", "strength reduction: trials", "1"},
    config_echo("restart.file", "run.restart"),
    {"restart.time_s", "restart: time", "s"},
    {"restart.step", "restart: step", "1"},
    {"restart.exact", "restart: exact state", ""},
    config_echo("geostatic.duration_s", "geostatic.duration"),
    {"geostatic.steps", "geostatic phase: steps", "1"},
    {"geostatic.max_speed_m_per_s", "geostatic phase: largest speed at its end", "m/s"},
    {"geostatic.rest_tolerance_m_per_s", "geostatic phase: at rest below the speed", "m/s"},
    {"geostatic.at_rest", "geostatic phase: at rest", ""},
    {"materials[]", "materials (derived model constants)", ""},
    {"materials[].name", "material", ""},
    {"materials[].dp_fit", "Drucker–Prager fit", ""},
    {"materials[].p_wave_speed_m_per_s", "P-wave speed", "m/s"},
    // materials[].<figure>: the constitutive models' declared figures (constitutive.hpp), added below
};

}  // namespace

std::span<const KeyReference> summary_config_declarations() {
  static const std::vector<KeyReference> refs = [] {
    ConfigReader slope = ConfigReader::describe(), stability = ConfigReader::describe();
    (void)read_config(slope, true);
    (void)read_stability_map_case(stability);
    std::vector<KeyReference> all = slope.reference();
    for (KeyReference& k : stability.reference()) all.push_back(std::move(k));
    return all;
  }();
  return refs;
}

std::span<const SummaryKey> summary_keys() noexcept {
  // kKeys (config echoes completed from the declarations), then materials[].<key> of every model's
  // figures (label and unit as the model declares them).
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const MaterialFigure& f : all_material_figures()) n.push_back("materials[]." + std::string(f.key));
    return n;
  }();
  static const std::vector<SummaryKey> keys = [] {
    std::vector<SummaryKey> all = with_config_declarations(kKeys, summary_config_declarations());
    const std::vector<MaterialFigure> figures = all_material_figures();
    for (std::size_t i = 0; i < figures.size(); ++i) all.push_back({names[i], figures[i].label, figures[i].unit});
    return all;
  }();
  return keys;
}

}  // namespace geohaz::sph
