#pragma once
/// \file stability_map.hpp
/// The rainfall-driven stability map of a DSM (the `slope-stability` app, docs/stability.md): per
/// cell the infinite-slope factor of safety (infinite_slope.hpp) on the soil–bedrock contact at
/// vertical depth Z, with the pressure head of rain infiltration (infiltration.hpp), over time.
///
/// Steps:
///  1. Slope angle of each cell from the DSM: δ = atan|∇z|, ∇z by central differences over the four
///     neighbours, taken as the mean of the core bilinear surface's gradient (BilinearGrid) on the
///     cell's four edge midpoints (the same central differences debris-runout uses for cos δ).
///     Cells on the raster's border or next to nodata have no slope and no result (nodata).
///  2. Cells with a slope outside [soil.min_slope, soil.max_slope] or no soil (Z ≤ 0) carry no soil
///     cover (rock faces, flats): no result.
///  3. At the evaluation times t_j = j·Δt (and the end), per cell: ψ(Z, t_j), FS(t_j); the first
///     time FS < 1 is refined by bisection between t_{j−1} and t_j to 10⁻⁶ of the step.
///  4. Unstable cells (FS < 1 at any evaluation time, or at the refined crossing) are the release:
///     polygons with the slab thickness normal to the slope, H = Z cos δ, so that debris-runout's
///     default reading (thickness normal to the slope, converted to the vertical H/cos δ) seeds the
///     soil column Z above the failure plane: volume Σ Z·cell area.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/sph/infiltration.hpp"
#include "geohaz/sph/infinite_slope.hpp"

namespace geohaz::sph {

/// Everything a stability-map run reads (config keys in read_stability_map_case).
struct StabilityMapCase {
  std::string dsm;                                           ///< DSM raster (projected CRS, m)
  double soil_depth = 1.5;                                   ///< Z, vertical depth of the failure plane (m)
  std::string soil_depth_raster;                             ///< Z per cell (m) on the DSM's grid, "" for the constant
  double min_slope = 0.0;                                    ///< cells flatter than this carry no soil (rad)
  double max_slope = 60.0 * 3.14159265358979323846 / 180.0;  ///< cells steeper than this carry no soil (rad)
  InfiniteSlopeSoil soil;                                    ///< c′, φ′, unit weights
  InfiltrationParameters hydrology;
  double water_table_depth = 1.5;  ///< d, initial water table depth (vertical, m)
  std::string water_table_raster;  ///< d per cell (m) on the DSM's grid, "" for the constant
  RainfallHistory rain;
  double duration = 0.0;      ///< simulated time (s); the rain's end when 0 was given
  double time_step = 3600.0;  ///< evaluation step Δt (s)
  int output_every = 1;       ///< FS raster every this many evaluation steps
  bool pngs = true;           ///< quick-look pictures
  std::string config_source, resolved_config;
};

/// Read (or, in describe mode, declare) every key; ranges checked here, cross-checks (unit weights'
/// order) too. InputError naming the key.
StabilityMapCase read_stability_map_case(ConfigReader& cfg);

/// The DSM, the slope and the per-cell soil and water table, all checked (InputError) before anything
/// is written.
struct StabilityMapInputs {
  Raster dsm;
  GridGeometry grid;
  std::vector<double> slope;        ///< δ (rad), NaN where undefined (border, nodata)
  std::vector<double> depth;        ///< Z (m); 0 where the cell carries no soil
  std::vector<double> water_table;  ///< d (m)
  std::vector<int> cells;           ///< indices of the cells with a result (slope, soil)
};
StabilityMapInputs load_stability_map_inputs(const StabilityMapCase& c);

/// Per-cell results (NaN where a cell has none) and the series at the evaluation times.
struct StabilityMapResult {
  std::vector<double> fs_min;               ///< smallest FS over the evaluation times and the crossing (1)
  std::vector<double> failure_time;         ///< first time FS < 1 (s), NaN: never
  std::vector<double> psi_max;              ///< largest pressure head on the failure plane (m)
  std::vector<double> times;                ///< evaluation times (s)
  std::vector<std::size_t> unstable_cells;  ///< cells with FS < 1 at each evaluation time
  std::size_t failed_cells = 0;             ///< cells that failed at some time
  std::size_t initially_unstable = 0;       ///< of which already at t = 0
  double release_volume = 0.0;              ///< Σ Z·cell area over the failed cells (m³)
};

/// Run steps 3–4. `on_output(j, t, fs)` is called at the evaluation times j with j % output_every
/// == 0 and at the last one, with FS per cell (NaN: no result); `progress(t)` after each time.
StabilityMapResult compute_stability_map(const StabilityMapInputs& in, const StabilityMapCase& c,
                                         const std::function<void(int, double, const std::vector<double>&)>& on_output,
                                         const std::function<void(double)>& progress);

/// The release of a result: slab thickness normal to the slope H = Z cos δ (m) on the failed cells,
/// 0 elsewhere, nodata outside the DSM.
Raster release_thickness(const StabilityMapInputs& in, const StabilityMapResult& r);

/// The whole run: inputs checked, then the output folder, FS(t) GeoTIFFs with styles, minimum FS,
/// failure time, peak pressure head, slope, release polygons, series.csv, summary.json.
StabilityMapResult run_stability_map(const StabilityMapCase& c, const std::filesystem::path& out, bool quiet,
                                     int threads);

}  // namespace geohaz::sph
