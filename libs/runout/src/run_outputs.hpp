#pragma once
/// \file run_outputs.hpp
/// The profile and gauge parts of a debris-runout run (internal to libs/runout; not installed):
/// their geometry read and checked with the other inputs, their files written with the outputs.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "geohaz/runout/profile.hpp"
#include "geohaz/runout/run.hpp"

namespace geohaz::runout::detail {

/// The profile path (output.profile_path, or the first line of output.profile_path_file in the
/// DSM's CRS) into `in.profile_path`, and the gauges, checked against `in.dsm` (InputError naming
/// the file, key, value and allowed extent; nothing is written yet).
void load_output_geometry(const RunConfig& c, RunoutInputs& in);

/// profile.csv and profile.png: along the user's path, or the flow's own centreline (from the
/// highest cell of the release through the depth-weighted centroids of the arrival fronts, one per
/// output.series_interval; points off the DSM's data skipped), peaks over
/// ±output.profile_half_width. The figure names both reaches of the run: α along the profile and
/// the H/L of the toe path (summary.json's fahrboeschung). Returns the profile (none without one).
std::optional<ThalwegProfile> write_profile_outputs(const RunConfig& c, const RunoutSimulation& sim,
                                                    const Raster& depth, const Raster& speed, const Raster& pressure,
                                                    const Raster& arrival, const std::filesystem::path& out);

/// summary.json's "profile": the path, the top and the run-out point's stations and elevations,
/// H, L and H/L = tan α measured along the profile path (profile_reach), α.
nlohmann::json profile_summary(const ThalwegProfile& p, bool given_path);

/// gauges.csv and gauges.png (none without gauges).
void write_gauge_outputs(const RunConfig& c, const RunoutSimulation& sim, const std::filesystem::path& out);

/// The gauges for summary.json: name, kind, vertices, peak depth, speed and discharge, net volume.
nlohmann::json gauges_summary(const RunoutSimulation& sim);

}  // namespace geohaz::runout::detail
