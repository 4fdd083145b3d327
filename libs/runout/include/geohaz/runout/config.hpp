#pragma once
/// \file config.hpp
/// The debris-runout configuration as typed structs (RunConfig: the DSM, the release, the spatial
/// processes, the barriers, the model parameters and the outputs, all in SI units) and its reader,
/// read_config, which declares every key once with its default, range, unit and help text. The
/// same shape as sph/config.hpp and dem/config.hpp; the run itself is in run.hpp.

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geohaz/core/vec.hpp"
#include "geohaz/runout/barriers.hpp"
#include "geohaz/runout/gauges.hpp"
#include "geohaz/runout/hazard_maps.hpp"
#include "geohaz/runout/processes.hpp"
#include "geohaz/runout/solver.hpp"

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

/// Where the barriers come from (docs/runout.md, "Barriers"); empty file: none.
struct BarrierSpec {
  std::string file;                                     ///< lines (Shapefile, GeoJSON, GPKG, …)
  std::string height_attribute = "height";              ///< attribute of the crest height above the terrain (m)
  double height = 0.0;                                  ///< crest height where the attribute is absent or null (m)
  std::string permeability_attribute = "permeability";  ///< attribute of the open fraction (1)
  double permeability = 0.0;                            ///< open fraction where the attribute is absent or null (1)
  WallLaw law;                                          ///< restitution, wall friction, retention distance
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
struct RunConfig {
  std::string dsm;  ///< terrain raster (projected CRS, metres)
  ReleaseSpec release;
  ProcessSpec processes;
  BarrierSpec barriers;
  RunoutParameters params;
  OutputSettings output;
  std::string resolved_config;  ///< TOML text of the resolved configuration (written beside the outputs)
  std::string config_source;    ///< config file the case came from ("" for none), for messages
};

/// Read every debris-runout key from `cfg` (defaults from RunConfig's structs; ranges, units and
/// help text declared here once, so the app, the ensemble runner and `--help-config` agree).
/// Does not call cfg.finish(). Relative paths are resolved against the config file's folder when
/// they do not exist as given.
RunConfig read_config(ConfigReader& cfg);

/// A coefficient key of a basal law as read_config declares it.
struct FrictionKey {
  std::string key;    ///< "model.tau_y"
  std::string label;  ///< the key's help text up to its list of laws ("yield stress τ_y")
  std::string unit;   ///< "Pa"
};
/// The model.* coefficient keys the basal law `law` (a model.friction value) reads, in
/// declaration order; empty for an unknown law. For tools that show a run's parameters (the report).
std::vector<FrictionKey> friction_keys(std::string_view law);
/// Any debris-runout key as read_config declares it (key_labels.cpp): a basal law's coefficient as
/// friction_keys gives it, any other key labelled by its declared short label (KeyDoc::label) or,
/// for a key declared without one, by its help text up to the first " (", ": ",
/// "; " or ", " ("mixture density ρ"), with the declared unit ("kg/m^3"; "1" dimensionless, ""
/// for a string). std::nullopt for a key read_config does not declare. For tools that show a run's
/// or an ensemble's parameters (the report), so labels and units have one source.
std::optional<FrictionKey> case_key(std::string_view key);

}  // namespace geohaz::runout
