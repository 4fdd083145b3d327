/// \file summary_keys.cpp
/// Label, unit and group of every key debris-runout (run.cpp summary_json, run_outputs.cpp),
/// geohaz-ensemble (ensemble.cpp) and geohaz-calibrate (calibrate_outputs.cpp) write into
/// summary.json (summary_keys.hpp). A key written without a line here fails the apps' tests
/// (tests/common/summary_keys_check.hpp). A key whose value is a config value (config_echo) names
/// the config key: label and unit are its declaration's (config.cpp, ensemble.cpp, calibrate.cpp).

#include "geohaz/runout/summary_keys.hpp"

#include <utility>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/runout/calibrate.hpp"
#include "geohaz/runout/config.hpp"
#include "geohaz/runout/ensemble.hpp"

namespace geohaz::runout {

namespace {

using G = SummaryGroup;

constexpr SummaryKey kKeys[] = {
    // debris-runout: volumes and areas
    {"volumes_m3.release_read", "release volume read", "m^3", G::Volumes, true},
    {"volumes_m3.seeded", "volume seeded as particles", "m^3", G::Volumes},
    {"volumes_m3.deposited", "volume stopped (deposited particles)", "m^3", G::Volumes},
    {"volumes_m3.mobile", "volume still moving at the end", "m^3", G::Volumes},
    {"volumes_m3.lost", "volume lost over the DTM edge", "m^3", G::Volumes},
    {"volumes_m3.deposit_raster", "deposit volume on the raster", "m^3", G::Volumes, true},
    {"volumes_m3.mobile_raster", "moving volume on the raster", "m^3", G::Volumes},
    {"volumes_m3.entrained", "volume entrained from the bed", "m^3", G::Volumes},
    {"volumes_m3.injected", "volume injected by inflows", "m^3", G::Volumes},
    {"area_affected_m2", "area reached by the flow", "m^2", G::Volumes, true},
    {"mobile_at_end.fraction", "fraction still moving at the end", "1", G::Volumes},
    {"mobile_at_end.volume_m3", "volume still moving at the end", "m^3", G::Volumes},
    {"intensity.area_low_m2", "area of low intensity", "m^2", G::Volumes},
    {"intensity.area_medium_m2", "area of medium intensity", "m^2", G::Volumes},
    {"intensity.area_strong_m2", "area of strong intensity", "m^2", G::Volumes},
    // debris-runout: reach and H/L
    {"fahrboeschung.ratio_H_over_L", "H/L of the toe path (Fahrböschung: release top to toe)", "1", G::Reach, true},
    {"fahrboeschung.angle_deg", "angle of the toe path's H/L (Fahrböschung)", "deg", G::Reach},
    {"fahrboeschung.drop_height_m", "drop height H (release top to toe)", "m", G::Reach, true},
    {"fahrboeschung.reach_m", "horizontal reach L along the toe path", "m", G::Reach, true},
    {"fahrboeschung.toe_x_m", "toe easting", "m", G::Reach},
    {"fahrboeschung.toe_y_m", "toe northing", "m", G::Reach},
    {"runout_length_along_path_m", "run-out length along the path", "m", G::Reach},
    {"profile.ratio_H_over_L", "H/L along the profile (tan α)", "1", G::Reach, true},
    {"profile.alpha_deg", "α along the profile", "deg", G::Reach},
    {"profile.drop_height_m", "profile: drop height H (top to run-out point)", "m", G::Reach},
    {"profile.length_m", "profile: length L along the path (top to run-out point)", "m", G::Reach},
    {"profile.top_station_m", "profile: station of the top of the reached part", "m", G::Reach},
    {"profile.runout_station_m", "profile: station of the run-out point", "m", G::Reach},
    {"profile.top_elevation_m", "profile: elevation of the top", "m", G::Reach},
    {"profile.runout_elevation_m", "profile: elevation of the run-out point", "m", G::Reach},
    {"profile.runout_xy_m", "profile: run-out point (x, y)", "m", G::Reach},
    config_echo("profile.half_width_m", "output.profile_half_width", G::Reach),
    {"profile.path", "profile path", "", G::Reach},
    {"profile.reached", "the flow reached the profile path", "", G::Reach},
    {"centre_of_mass.travel_m", "centre of mass: horizontal travel", "m", G::Reach},
    {"centre_of_mass.drop_m", "centre of mass: drop", "m", G::Reach},
    {"centre_of_mass.angle_deg", "centre of mass: travel angle", "deg", G::Reach},
    // debris-runout: peak values
    {"max_speed_m_per_s", "peak speed", "m/s", G::Peak, true},
    {"max_pressure_pa", "peak dynamic pressure ρv²", "Pa", G::Peak, true},
    {"mobile_at_end.max_speed_m_per_s", "largest speed at the end", "m/s", G::Peak},
    {"kinetic_energy_j.peak", "peak kinetic energy", "J", G::Peak},
    {"kinetic_energy_j.at_end", "kinetic energy at the end", "J", G::Peak},
    {"processes.entrainment.max_eroded_depth_m", "deepest erosion", "m", G::Peak},
    // debris-runout: time
    {"simulated_time_s", "simulated time", "s", G::Time, true},
    {"ended_by", "the run ended by", "", G::Time},
    {"unfinished", "the run ended with mass still moving", "", G::Time},
    // debris-runout: bookkeeping
    {"particles_released", "particles released", "1"},
    {"particles_left", "particles left at the end", "1"},
    {"lost_particles", "particles lost over the DTM edge", "1"},
    {"steps", "time steps", "1"},
    {"wall_time_s", "wall-clock time", "s"},
    {"threads", "threads", "1"},
    config_echo("stop_energy_fraction", "run.stop_energy_fraction"),
    {"mass_balance_error_relative", "relative mass-balance error", "1"},
    {"mobile_at_end.in_deposit_raster", "the moving mass is in the deposit raster", ""},
    config_echo("release_thickness_direction", "release.thickness_direction"),
    config_echo("intensity.scheme", "intensity.scheme"),
    config_echo("intensity.strong_depth_m", "intensity.strong_depth"),
    config_echo("intensity.strong_speed_m_per_s", "intensity.strong_speed"),
    config_echo("intensity.medium_pressure_pa", "intensity: medium from the pressure", "intensity.pressure_classes"),
    config_echo("intensity.strong_pressure_pa", "intensity: strong from the pressure", "intensity.pressure_classes"),
    {"detached.volume_m3", "detached particles: volume", "m^3"},
    {"detached.particles", "detached particles", "1"},
    {"detached.on_raster_at_end_m3", "detached particles: volume on the raster at the end", "m^3"},
    {"detached.left_raster_m3", "detached particles: volume that left the raster", "m^3"},
    {"detached.left_raster_particles", "detached particles that left the raster", "1"},
    {"detached.farthest_distance_m", "detached particles: farthest distance from the main mass", "m"},
    {"detached.farthest_xy_m", "detached particles: farthest point (x, y)", "m"},
    {"detached.in_maps", "detached particles in the maps", ""},
    {"left_raster.volume_m3", "volume that left the terrain data", "m^3"},
    {"left_raster.particles", "particles that left the terrain data", "1"},
    {"left_raster.at_edge_m3", "volume that left over the raster edge", "m^3"},
    {"left_raster.over_nodata_m3", "volume that left over nodata cells", "m^3"},
    {"left_raster.last_seen[]", "where the mass left the terrain data", "", G::Volumes},
    {"left_raster.last_seen[].x_m", "last seen: easting", "m"},
    {"left_raster.last_seen[].y_m", "last seen: northing", "m"},
    {"left_raster.last_seen[].volume_m3", "last seen: volume", "m^3"},
    {"left_raster.last_seen[].detached", "last seen: detached", ""},
    {"left_raster.last_seen[].where", "last seen: where", ""},
    config_echo("processes.entrainment.law", "entrainment.law"),
    config_echo("processes.entrainment.growth_rate_per_m", "entrainment.growth_rate"),
    config_echo("processes.entrainment.critical_shear_pa", "entrainment.critical_shear"),
    config_echo("processes.entrainment.coefficient_m_per_s_pa", "entrainment.coefficient"),
    {"processes.entrainment.entrained_volume_m3", "volume entrained", "m^3"},
    {"processes.entrainment.growth_factor", "volume growth factor by entrainment", "1"},
    config_echo("processes.entrainment.file", "entrainment.file"),
    {"processes.entrainment.terrain", "terrain under erosion", ""},
    config_echo("processes.friction_zones.file", "zones.file"),
    {"processes.friction_zones.coefficients", "coefficients set by zones", ""},
    config_echo("processes.forest.file", "forest.file"),
    {"processes.forest.area_m2", "forest area", "m^2"},
    {"processes.forest.max_drag_per_m", "largest forest drag k_f", "1/m"},
    config_echo("processes.forest.drag_coefficient", "forest.drag_coefficient"),
    config_echo("processes.inflow.hydrograph", "inflow.hydrograph"),
    {"processes.inflow.volume_of_table_m3", "inflow: volume of the hydrograph table", "m^3"},
    {"processes.inflow.injected_m3", "inflow: volume injected", "m^3"},
    {"processes.inflow.end_time_s", "inflow: end of the hydrograph", "s"},
    config_echo("processes.inflow.speed_m_per_s", "inflow.speed"),
    {"processes.inflow.direction_xy", "inflow: direction (x, y)", "1"},
    {"barriers[]", "barriers", "", G::Peak},
    {"barriers[].name", "barrier", ""},
    {"barriers[].file", "barrier file", ""},
    {"barriers[].series", "barrier force series", ""},
    {"barriers[].crest_height_m", "crest height", "m"},
    {"barriers[].permeability", "permeability", "1"},
    {"barriers[].length_m", "length", "m"},
    {"barriers[].peak_force_n", "peak force", "N"},
    {"barriers[].peak_force_per_m_n_m", "peak force per metre", "N/m"},
    {"barriers[].peak_pressure_pa", "peak pressure", "Pa"},
    {"barriers[].retained_volume_m3", "volume retained", "m^3"},
    {"barriers[].overtopped_volume_m3", "volume overtopped", "m^3"},
    {"barriers[].impulse_n_s", "impulse", "N*s"},
    {"barriers[].vertices_xy_m", "vertices (x, y)", "m"},
    config_echo("barrier_law.restitution", "barriers.restitution"),
    config_echo("barrier_law.wall_friction", "barriers.wall_friction"),
    config_echo("barrier_law.retention_distance_m", "barriers.retention_distance"),
    config_echo("barrier_law.force_window_s", "barrier: force averaging window", "output.series_interval"),
    {"gauges[]", "gauges", "", G::Peak},
    {"gauges[].name", "gauge", ""},
    {"gauges[].kind", "kind", ""},
    {"gauges[].vertices_xy_m", "vertices (x, y)", "m"},
    {"gauges[].peak_depth_m", "peak depth", "m"},
    {"gauges[].peak_speed_m_per_s", "peak speed", "m/s"},
    {"gauges[].peak_discharge_m3_per_s", "peak discharge", "m^3/s"},
    {"gauges[].net_volume_m3", "net volume that passed", "m^3"},
    {"model", "model", ""},
    {"version", "geohaz version", ""},
    config_echo("dsm", "terrain.dsm"),
    {"release", "release", ""},
    config_echo("friction", "model.friction"),
    {"warnings", "warnings", ""},

    // geohaz-ensemble (ensemble.cpp): the statistics over the members that ran
    {"members", "members", "1"},
    {"succeeded", "members that ran to the end", "1"},
    {"unfinished_members", "members ending with mass still moving", "1"},
    config_echo("sampling", "ensemble.sampling"),
    config_echo("seed", "ensemble.seed"),
    {"base_case", "base case", ""},
    {"runout_length_along_path_m.*", "run-out length along the path", "m", G::Reach},
    {"fahrboeschung_ratio_H_over_L.*", "H/L of the toe path (Fahrböschung)", "1", G::Reach},
    {"area_affected_m2.*", "area reached by the flow", "m^2", G::Volumes},
    {"member_wall_time_s.*", "wall-clock time of a member", "s"},
    {"member_cpu_time_s.*", "CPU time of a member", "s"},
    {"members_cpu_time_total_s", "CPU time of all members", "s"},
    {"parameters[]", "parameters", ""},
    {"parameters[].key", "parameter", ""},
    {"parameters[].distribution", "distribution", ""},
    {"parameters[].min", "smallest value", kUnitOfParameter},
    {"parameters[].max", "largest value", kUnitOfParameter},
    {"parameters[].mean", "mean", kUnitOfParameter},
    {"parameters[].sd", "standard deviation", kUnitOfParameter},
    {"parameters[].median", "median", kUnitOfParameter},
    {"parameters[].sigma", "σ of ln", "1"},
    {"parameters[].values", "values", kUnitOfParameter},
    {"parameters[].weights", "weights", "1"},
    {"parameters[].value", "value", kUnitOfParameter},
    {"parameters[].lower", "truncated below at", kUnitOfParameter},
    {"parameters[].upper", "truncated above at", kUnitOfParameter},
    {"parameters[].scale", "scale", ""},
    {"release_alternatives", "alternative release files", ""},
    {"products", "products", ""},
    {"percentile_accuracy.method", "percentile maps: method", ""},
    config_echo("percentile_accuracy.bins", "products.bins"),
    {"percentile_accuracy.max_relative_error_depth", "percentile maps: largest relative error of depth", "1"},
    {"percentile_accuracy.max_relative_error_speed", "percentile maps: largest relative error of speed", "1"},
    {"percentile_accuracy.max_relative_error_pressure", "percentile maps: largest relative error of pressure", "1"},
    {"percentile_accuracy.depth_range_m", "percentile maps: depth range of the histogram", "m"},
    {"percentile_accuracy.speed_range_m_per_s", "percentile maps: speed range of the histogram", "m/s"},
    {"percentile_accuracy.pressure_range_pa", "percentile maps: pressure range of the histogram", "Pa"},
    {"aggregation_window_cells", "cells in the aggregation window", "1"},
    {"aggregation_bytes_per_cell", "memory per aggregated cell", "bytes"},
    {"aggregation_wall_time_s", "wall-clock time of the aggregation", "s"},
    {"ranks", "MPI ranks", "1"},
    {"threads_per_rank", "threads per rank", "1"},
    {"failed[]", "failed members", ""},
    {"failed[].member", "member", "1"},
    {"failed[].values", "the member's parameter values", kUnitOfParameter},
    {"failed[].diagnosis", "diagnosis", ""},

    // geohaz-calibrate (calibrate_outputs.cpp): the best member and its misfit
    {"best.member", "best member", "1"},
    {"best.stage", "stage of the best member", ""},
    {"best.parameters.*", "best value", kUnitOfParameter},
    {"best.values", "best values (in the order of the parameters)", kUnitOfParameter},
    {"best.misfit.score", "misfit score J of the best member", "1", G::Other, true},
    {"best.misfit.tversky", "Tversky index T of the footprints", "1", G::Other, true},
    {"best.misfit.tp_m2", "true positive area (both)", "m^2", G::Volumes},
    {"best.misfit.fp_m2", "false positive area (modelled only)", "m^2", G::Volumes},
    {"best.misfit.fn_m2", "false negative area (observed only)", "m^2", G::Volumes},
    {"best.misfit.runout_s_m", "modelled run-out along the thalweg", "m", G::Reach},
    {"best.misfit.runout_diff_m", "modelled minus observed run-out along the thalweg", "m", G::Reach},
    {"best.misfit.depth_rmse_m", "deposit depth RMSE", "m"},
    {"best.misfit.volume_m3", "modelled deposit volume", "m^3", G::Volumes},
    {"best.misfit.terms.footprint", "score term: footprint", "1"},
    {"best.misfit.terms.runout", "score term: run-out", "1"},
    {"best.misfit.terms.depth", "score term: deposit depth", "1"},
    {"best.misfit.terms.volume", "score term: volume", "1"},
    {"observation.footprint_area_m2", "observed footprint area", "m^2", G::Volumes},
    {"observation.runout_s_m", "observed run-out along the thalweg", "m", G::Reach},
    {"observation.runout_from", "observed run-out from", ""},
    {"observation.deposit_raster", "observed deposit raster given", ""},
    {"observation.volume_m3", "observed deposit volume", "m^3", G::Volumes},
    {"score.definition", "score", ""},
    config_echo("score.depth_threshold_m", "score.depth_threshold"),
    config_echo("score.tversky_alpha", "score.tversky_alpha"),
    config_echo("score.tversky_beta", "score.tversky_beta"),
    config_echo("score.w_footprint", "score.w_footprint"),
    config_echo("score.w_runout", "score.w_runout"),
    config_echo("score.w_depth", "score.w_depth"),
    config_echo("score.w_volume", "score.w_volume"),
    config_echo("score.failed_penalty", "score.failed_penalty"),
    config_echo("score.acceptable_tolerance", "score.acceptable_tolerance"),
    config_echo("design_members", "calibration.global_members"),
    {"morris_members", "members of the Morris trajectories", "1"},
    {"local_members", "members of the local searches", "1"},
    config_echo("local_search.algorithm", "calibration.local_algorithm"),
    config_echo("local_search.starts", "calibration.local_starts"),
    config_echo("local_search.restarts", "calibration.local_restarts"),
    {"local_search.searches", "local searches run", "1"},
    {"local_search.stops", "why the local searches ended", ""},
    {"acceptable_members", "acceptable members", "1"},
    {"acceptable_range.*", "range over the acceptable members", kUnitOfParameter},
    {"sensitivity[]", "Morris sensitivity", ""},
    {"sensitivity[].key", "parameter", ""},
    {"sensitivity[].mu_star", "Morris μ*", "1"},
    {"sensitivity[].mu", "Morris μ", "1"},
    {"sensitivity[].sigma", "Morris σ", "1"},
    {"sensitivity[].effects", "elementary effects", "1"},
    {"outputs", "outputs", ""},
};

}  // namespace

std::span<const KeyReference> summary_config_declarations() {
  static const std::vector<KeyReference> refs = [] {
    ConfigReader run = ConfigReader::describe(), ensemble = ConfigReader::describe(),
                 calibration = ConfigReader::describe();
    (void)read_config(run);
    describe_ensemble(ensemble);
    describe_calibration(calibration);
    std::vector<KeyReference> all = run.reference();
    for (const ConfigReader* r : {&ensemble, &calibration})
      for (KeyReference& k : r->reference()) all.push_back(std::move(k));
    return all;
  }();
  return refs;
}

std::span<const SummaryKey> summary_keys() noexcept {
  static const std::vector<SummaryKey> keys = with_config_declarations(kKeys, summary_config_declarations());
  return keys;
}

}  // namespace geohaz::runout
