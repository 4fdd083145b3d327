#pragma once
/// \file profile.hpp
/// The thalweg long profile of a run (issue #33; the first figure of an AvaFrame AIMEC analysis or
/// a RAMMS report): along a path — given, or the flow's own centreline — the terrain, the peak
/// depth, speed and pressure, the run-out point and the α line (Fahrböschung) of the run-out.
///
/// Definitions, as implemented:
/// - s is the horizontal distance along the path (m), sampled every `spacing` metres and at the
///   vertices; z is the DSM's bilinear elevation there (core Terrain).
/// - The peak values at a station are the largest of the map cells across the path there: the
///   cells under the points of the path's normal within ±`half_width` (no more than half a cell
///   apart), each map on its own (the maps' peaks may come from different cells, as they come from
///   different times). A path that cuts a bend of the flow, or runs beside it, still reads the
///   flow's peak values; a station with no flow within the half-width reads 0, which there is the
///   true peak (the flow did not pass). `half_width` = 0: the cell holding the point only. The
///   values are cell values, not interpolated (that would smear a depth into dry cells).
/// - The reached part of the path is where the peak depth exceeds `min_depth`. Its highest point is
///   the top (s_top, z_top), its farthest point the run-out point (s_runout, z_runout).
/// - tan α = (z_top − z_runout) / (s_runout − s_top), and the α line is
///   z_α(s) = z_top − tan α · (s − s_top) (written for every row; it meets the terrain at the top
///   and at the run-out point).

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"
#include "geohaz/core/vec.hpp"

namespace geohaz::runout {

/// One sample of the profile.
struct ProfileRow {
  double s = 0.0;           ///< horizontal distance along the path (m)
  double x = 0.0, y = 0.0;  ///< position in the DSM's CRS (m)
  double z = 0.0;           ///< terrain elevation (m)
  double depth = 0.0;       ///< peak flow depth (m)
  double speed = 0.0;       ///< peak speed (m/s)
  double pressure = 0.0;    ///< peak dynamic pressure (Pa)
  double alpha_z = 0.0;     ///< elevation of the α line (m)
};

/// The profile and its key points.
struct ThalwegProfile {
  std::vector<ProfileRow> rows;
  bool reached = false;                   ///< some point of the path exceeds min_depth
  double s_top = 0.0, z_top = 0.0;        ///< highest reached point (m)
  double s_runout = 0.0, z_runout = 0.0;  ///< farthest reached point (m)
  double alpha_deg = 0.0;                 ///< Fahrböschung angle α (degrees)
  double half_width = 0.0;                ///< the peaks are the largest within this distance across the path (m)
};

/// Sample the DSM and the peak maps (same grid as the DSM; nodata and NaN read as 0) along `path`,
/// the peaks over ±`half_width` metres across it (m, ≥ 0). InputError when the path has fewer than
/// two distinct points or leaves the DSM's data.
ThalwegProfile thalweg_profile(const Raster& dsm, const Raster& max_depth, const Raster& max_speed,
                               const Raster& max_pressure, const std::vector<Vec2>& path, double spacing,
                               double min_depth, double half_width = 0.0);

/// The path of a profile given by the user, checked against the DSM before a run writes anything:
/// InputError naming `source`, `key`, the first point off the terrain's data and the DSM's extent,
/// or a path without two distinct vertices.
void check_profile_path(const std::vector<Vec2>& path, const Raster& dsm, const std::string& source,
                        const std::string& key);

/// Thin a polyline that moves away from `start`: `start`, then the points in order, each kept only
/// when it lies at least `min_spacing` farther from `start` than the last one kept (so a centroid
/// wandering to and fro on a deposit fan adds no length).
std::vector<Vec2> flow_centreline(const Vec2& start, const std::vector<Vec2>& fronts, double min_spacing);

/// The flow's own centreline from its maps: the cells first reached within each window of `dt`
/// seconds (arrival_time ≥ 0; −9999 or NaN: never), their centroid weighted by the peak depth, in
/// order of time, after `start` (the top of the release), thinned to `min_spacing`. The centroid of
/// a whole arrival front follows the bulk of the flow: a lone particle racing ahead or over a ridge
/// adds a few cells to a window, not the path.
std::vector<Vec2> arrival_centreline(const Raster& arrival_time, const Raster& max_depth, const Vec2& start, double dt,
                                     double min_spacing);

/// profile.csv: s_along_path_m, x_m, y_m, terrain_elevation_m, max_depth_m, max_speed_m_per_s,
/// max_pressure_Pa, alpha_line_elevation_m (α, top and run-out point are in the figure and in
/// the rows: the α line meets the terrain there).
void write_profile_csv(const std::filesystem::path& path, const ThalwegProfile& p);

/// H, L and H/L of the profile's own reach: from its top to its run-out point along the path.
struct ProfileReach {
  double drop_height = 0.0;  ///< H = z_top − z_runout (m)
  double length = 0.0;       ///< L = s_runout − s_top, horizontal along the path (m)
  double ratio = 0.0;        ///< H/L = tan α (0 when L = 0)
};
ProfileReach profile_reach(const ThalwegProfile& p) noexcept;

/// A station marked on profile.png: a vertical line at s with its label (an observed run-out
/// beside the modelled one, geohaz-calibrate).
struct ProfileMark {
  double s = 0.0;  ///< m along the path
  std::string label;
  std::array<std::uint8_t, 3> colour{0, 0, 0};
  bool dashed = false;  ///< dashed (the marks before it show through where they coincide)
};

/// What profile.png shows beside the profile itself.
struct ProfileFigure {
  /// The angle of summary.json's H/L, measured along the toe particle's own path (degrees; NaN:
  /// none): drawn dashed from the top of the profile and labelled "H/L of the toe path", so the
  /// two reaches of one run read apart from "α along the profile".
  double toe_path_angle_deg = std::numeric_limits<double>::quiet_NaN();
  std::vector<ProfileMark> marks;  ///< stations marked with vertical lines and labels
  std::string title;               ///< above the figure ("" : none)
};

/// profile.png: the terrain along the path with the peak depth drawn above it (exaggerated, the
/// factor in the legend), the α line along the profile and the run-out point, the toe path's H/L
/// and the marks of `f`, and below it the peak speed against s; axes in metres.
void write_profile_png(const std::filesystem::path& path, const ThalwegProfile& p, const ProfileFigure& f = {});

}  // namespace geohaz::runout
