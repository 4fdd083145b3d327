// The debris-runout configuration keys: declared once here (unit, default, range, help), read into
// RunConfig. Defaults come from the structs of run.hpp / solver.hpp; the basal laws' coefficients
// from their own declarations (friction/*.hpp, core/law_parameters.hpp).
#include "geohaz/core/config.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/runout/config.hpp"

namespace geohaz::runout {

namespace {

/// The friction law named in the config, with its coefficients model.<key>: the keys, defaults,
/// ranges, units and rules are each law's own declaration (friction/*.hpp); a key of a law that is
/// not chosen is an error.
BasalFriction read_friction(ConfigReader& cfg) {
  const std::string law = cfg.get_choice("model.friction", ModifiedManningFriction::name, BasalFrictionNames::choices(),
                                         {"", BasalFrictionNames::help("basal shear law"), "basal friction law"});
  return BasalFrictionParameters::read(cfg, {"model.", "model.friction", "set model.friction or --friction"}, law);
}

/// A path given in the config: relative to the config file's folder when it does not exist as
/// given (so a case file can name its inputs beside it).
std::string resolve(const ConfigReader& cfg, const std::string& key, std::string p) {
  namespace fs = std::filesystem;
  check_file_name(p, cfg.source().empty() ? "command line" : cfg.source(), key);
  if (!p.empty() && !cfg.source().empty() && fs::path(p).is_relative() && !fs::exists(p))
    return (cfg.base_dir() / p).string();
  return p;
}

/// Entrainment, friction zones, forest and the inflow hydrograph (docs/runout.md, "Processes").
void read_processes(ConfigReader& cfg, RunConfig& c) {
  auto& e = c.params.entrainment;
  auto& s = c.processes;
  const std::string law = cfg.get_choice("entrainment.law", to_string(e.law), {"none", "growth", "shear"},
                                         {"",
                                          "bed erosion: none, growth (dV/ds = E_s V, McDougall & Hungr 2005) or "
                                          "shear (rate k_e (τ_b − τ_c) where τ_b > τ_c)",
                                          "entrainment law"});
  e.law = law == "growth"  ? EntrainmentLaw::GrowthRate
          : law == "shear" ? EntrainmentLaw::ShearStress
                           : EntrainmentLaw::None;
  e.growth_rate = cfg.get("entrainment.growth_rate", e.growth_rate, Range::closed(0.0, 1.0),
                          {"1/m", "E_s of the growth law: volume growth per metre of path inside the erodible area",
                           "entrainment growth rate E_s"});
  e.critical_shear = cfg.get("entrainment.critical_shear", e.critical_shear, Range::closed(0.0, 1e7),
                             {"Pa", "τ_c of the shear law: no erosion below this basal shear stress",
                              "entrainment critical basal shear stress"});
  e.erosion_coefficient =
      cfg.get("entrainment.coefficient", e.erosion_coefficient, Range::closed(0.0, 1.0),
              {"m/(s*Pa)", "k_e of the shear law: erosion rate (m/s of bed depth) per Pa of excess shear",
               "entrainment erosion coefficient"});
  s.erodible =
      resolve(cfg, "entrainment.file",
              cfg.get_string("entrainment.file", "",
                             {"", "erodible layer: depth raster (m, vertical) or polygons", "erodible layer file"}));
  s.erodible_attribute = cfg.get_string("entrainment.attribute", s.erodible_attribute,
                                        {"", "polygon attribute holding the erodible depth (m)"});
  s.erodible_depth = cfg.get("entrainment.depth", s.erodible_depth, Range::closed(0.0, 100.0),
                             {"m", "uniform erodible depth of the polygons; 0: use the attribute"});
  if (e.law == EntrainmentLaw::GrowthRate && !(e.growth_rate > 0.0))
    throw InputError("entrainment.law = growth needs entrainment.growth_rate > 0 (1/m)", cfg.source(),
                     "entrainment.growth_rate", "0");
  if (e.law == EntrainmentLaw::ShearStress && !(e.erosion_coefficient > 0.0))
    throw InputError("entrainment.law = shear needs entrainment.coefficient > 0 (m/(s*Pa))", cfg.source(),
                     "entrainment.coefficient", "0");

  std::string zone_names;
  for (const char* n : kFrictionParameterNames) (zone_names += zone_names.empty() ? "" : ", ") += n;
  s.zones = resolve(cfg, "zones.file",
                    cfg.get_string("zones.file", "",
                                   {"",
                                    "friction zones: polygons whose attributes (the law's coefficients: " + zone_names +
                                        ") override the global coefficients inside them",
                                    "friction zones file"}));
  for (int k = 0; k < kFrictionParameters; ++k) {
    const std::string name = kFrictionParameterNames[static_cast<std::size_t>(k)];
    s.zone_rasters[static_cast<std::size_t>(k)] =
        resolve(cfg, "zones." + name,
                cfg.get_string("zones." + name, "",
                               {"", "raster of the friction coefficient " + name + " (nodata: the global value)"}));
  }

  s.forest = resolve(cfg, "forest.file",
                     cfg.get_string("forest.file", "",
                                    {"",
                                     "forest: polygons (attributes stem_density, stem_diameter) or a "
                                     "stem-density raster (1/m^2)",
                                     "forest file"}));
  s.stem_density = cfg.get("forest.stem_density", s.stem_density, Range::closed(0.0, 10.0),
                           {"1/m^2", "stems per square metre where the polygons carry none"});
  s.stem_diameter = cfg.get("forest.stem_diameter", s.stem_diameter, Range::open_closed(0.0, 5.0),
                            {"m", "stem diameter at breast height where the polygons carry none"});
  s.drag_coefficient =
      cfg.get("forest.drag_coefficient", s.drag_coefficient, Range::open_closed(0.0, 10.0),
              {"1", "drag coefficient C_D of a stem (k_f = ½ C_D n d)", "forest drag coefficient C_D"});

  s.hydrograph =
      resolve(cfg, "inflow.hydrograph",
              cfg.get_string("inflow.hydrograph", "",
                             {"", "inflow hydrograph table: CSV time_s,discharge_m3_per_s", "inflow hydrograph"}));
  s.inflow_points = cfg.get_array("inflow.points", s.inflow_points, Range::closed(-1e8, 1e8),
                                  {"m", "inflow point [x, y] or short line [x1, y1, x2, y2] in the DSM's CRS"});
  s.inflow_azimuth = cfg.get("inflow.azimuth", s.inflow_azimuth, Range::closed_open(-1.0, 360.0),
                             {"deg", "inflow direction clockwise from north; -1: down the steepest slope"});
  s.inflow_speed = cfg.get("inflow.speed", s.inflow_speed, Range::open_closed(0.0, 100.0),
                           {"m/s", "surface speed of the inflowing material", "inflow: speed"});
  if (!s.hydrograph.empty() && s.inflow_points.empty())
    throw InputError("inflow.hydrograph needs inflow.points ([x, y] or [x1, y1, x2, y2], m)", cfg.source(),
                     "inflow.points");
}

/// Barriers across the flow (docs/runout.md, "Barriers").
void read_barriers(ConfigReader& cfg, BarrierSpec& b) {
  b.file =
      resolve(cfg, "barriers.file",
              cfg.get_string("barriers.file", "",
                             {"", "barrier lines (Shapefile/GeoJSON/GPKG): check dams, walls, slit or net barriers"}));
  b.height_attribute = cfg.get_string("barriers.height_attribute", b.height_attribute,
                                      {"", "line attribute holding the crest height above the terrain (m)"});
  b.height =
      cfg.get("barriers.height", b.height, Range::closed(0.0, 100.0),
              {"m", "crest height above the terrain where the attribute is absent or null; 0: attribute required"});
  b.permeability_attribute =
      cfg.get_string("barriers.permeability_attribute", b.permeability_attribute,
                     {"", "line attribute holding the open fraction of a slit or net barrier (1)"});
  b.permeability = cfg.get("barriers.permeability", b.permeability, Range::closed_open(0.0, 1.0),
                           {"1", "fraction of the arriving particles an open barrier lets through; 0: closed wall"});
  b.law.restitution = cfg.get(
      "barriers.restitution", b.law.restitution, Range::closed(0.0, 1.0),
      {"1", "restitution e: normal speed after hitting the wall over before (0: stopped)", "barrier: restitution e"});
  b.law.friction =
      cfg.get("barriers.wall_friction", b.law.friction, Range::closed(0.0, 2.0),
              {"1", "Coulomb friction μ_w along the wall on the normal impulse", "barrier: wall friction μ_w"});
  b.law.retention_distance =
      cfg.get("barriers.retention_distance", b.law.retention_distance, Range::open_closed(0.0, 1e5),
              {"m", "retained volume = volume upstream of the line within this distance at the end",
               "barrier: retention distance"});
}

/// The map keys (docs/runout.md "Outputs"): class breaks of the depth and pressure maps, the
/// margin around the affected area and the attribution printed under every map.
void read_map_settings(ConfigReader& cfg, OutputSettings& o) {
  const std::string file = cfg.source().empty() ? "command line" : cfg.source();
  const auto increasing = [&](const char* key, const std::vector<double>& v, const char* unit) {
    for (std::size_t k = 1; k < v.size(); ++k)
      if (!(v[k] > v[k - 1]))
        throw InputError(std::string(key) + " must increase (got " + std::to_string(v[k - 1]) + " then " +
                             std::to_string(v[k]) + " " + unit + ")",
                         file, key);
    return v;
  };
  o.map_depth_classes = increasing(
      "output.map_depth_classes",
      cfg.get_array("output.map_depth_classes", o.map_depth_classes, Range::open_closed(0.0, 1e3),
                    {"m", "class breaks of the peak depth and deposit maps, increasing (empty: a continuous ramp)"}),
      "m");
  o.map_pressure_classes = increasing(
      "output.map_pressure_classes",
      cfg.get_array(
          "output.map_pressure_classes", o.map_pressure_classes, Range::open_closed(0.0, 1e9),
          {"Pa", "class breaks of the peak pressure map, increasing (shown in kPa; empty: a continuous ramp)"}),
      "Pa");
  o.map_speed_classes =
      increasing("output.map_speed_classes",
                 cfg.get_array("output.map_speed_classes", o.map_speed_classes, Range::open_closed(0.0, 1e3),
                               {"m/s", "class breaks of the peak speed maps, increasing (empty: a continuous ramp)"}),
                 "m/s");
  o.map_margin = cfg.get("output.map_margin", o.map_margin, Range::closed(0.0, 1e5),
                         {"m", "margin around the affected area (and the release) in every map of the run"});
  o.attribution = cfg.get_string("output.attribution", o.attribution,
                                 {"",
                                  "data attribution printed under every map (the terrain's licence often asks "
                                  "for it); empty: the DSM's own metadata (TIFFTAG_COPYRIGHT), if any"});
}

/// The gauges and the profile path (docs/runout.md "Gauges", "Thalweg profile"). The checks that
/// need the DSM (on its data, a name and a point or line given) are check_gauges() and
/// check_profile_path(), at load_inputs().
void read_gauges_and_profile(ConfigReader& cfg, OutputSettings& o) {
  const std::string file = cfg.source().empty() ? "command line" : cfg.source();
  const auto count = [](std::size_t n) { return std::to_string(n) + " number" + (n == 1 ? "" : "s"); };
  const auto vertices = [](const std::vector<double>& v) {
    std::vector<Vec2> out;
    for (std::size_t k = 0; k + 1 < v.size(); k += 2) out.emplace_back(v[k], v[k + 1]);
    return out;
  };
  o.gauge_interval = cfg.get("output.gauge_interval", o.gauge_interval, Range::open_closed(0.0, 1e6),
                             {"s", "simulated time between the rows of gauges.csv"});
  std::vector<ConfigReader> tables =
      cfg.tables("output.gauges", {"", "gauges ([[output.gauges]]): name and point = [x, y] or line = [x1, y1, ...]"});
  for (std::size_t k = 0; k < tables.size(); ++k) {
    ConfigReader& t = tables[k];
    const std::string key = "output.gauges[" + std::to_string(k) + "]";
    GaugeSpec g;
    g.name = t.get_string("name", "", {"", "the gauge's name in gauges.csv and gauges.png"});
    const std::vector<double> point =
        t.get_array("point", {}, Range::closed(-1e8, 1e8),
                    {"m", "point gauge [x, y] in the DSM's CRS: flow depth (m) and speed (m/s) over time"});
    const std::vector<double> line = t.get_array(
        "line", {}, Range::closed(-1e8, 1e8),
        {"m",
         "cross-section [x1, y1, x2, y2, ...] in the DSM's CRS: discharge (m^3/s, + to the right walking from "
         "the first vertex), cumulative volume (m^3), mean depth and speed over time"});
    if (!point.empty() && !line.empty())
      throw InputError("a gauge is either a point or a line: give point = [x, y] or line = [x1, y1, ...], not both",
                       file, key);
    if (!point.empty() && point.size() != 2)
      throw InputError("point must be [x, y] (m, the DSM's CRS)", file, key + ".point", count(point.size()));
    if (!line.empty() && (line.size() < 4 || line.size() % 2 != 0))
      throw InputError("line needs two or more vertices [x1, y1, x2, y2, ...]: an even count of at least 4 numbers (m)",
                       file, key + ".line", count(line.size()));
    g.vertices = vertices(point.empty() ? line : point);
    o.gauges.push_back(std::move(g));
  }
  const std::vector<double> path = cfg.get_array(
      "output.profile_path", {}, Range::closed(-1e8, 1e8),
      {"m",
       "the thalweg profile along this polyline [x1, y1, x2, y2, ...] (DSM's CRS) instead of the flow's own "
       "centreline"});
  if (!path.empty() && (path.size() < 4 || path.size() % 2 != 0))
    throw InputError(
        "output.profile_path needs two or more vertices [x1, y1, x2, y2, ...]: an even count of at "
        "least 4 numbers (m)",
        file, "output.profile_path", count(path.size()));
  o.profile_path = vertices(path);
  o.profile_path_file =
      resolve(cfg, "output.profile_path_file",
              cfg.get_string("output.profile_path_file", "",
                             {"", "the profile along the first line of this file (Shapefile/GeoPackage/GeoJSON)"}));
  if (!o.profile_path.empty() && !o.profile_path_file.empty())
    throw InputError("give output.profile_path or output.profile_path_file, not both", file, "output.profile_path_file",
                     o.profile_path_file);
  o.profile_half_width =
      cfg.get("output.profile_half_width", o.profile_half_width, Range::closed(0.0, 1e4),
              {"m",
               "the profile's peak values are the largest within this distance across the path (0: the cell "
               "under the path only)",
               "profile: peaks taken within this distance across the path"});
}

}  // namespace

RunConfig read_config(ConfigReader& cfg) {
  RunConfig c;
  c.config_source = cfg.source();
  c.dsm = resolve(cfg, "terrain.dsm",
                  cfg.get_string("terrain.dsm", "",
                                 {"",
                                  "DSM raster (any GDAL format, projected CRS); the positional "
                                  "argument overrides it",
                                  "terrain (DSM)"}));
  auto& r = c.release;
  r.file = resolve(
      cfg, "release.file",
      cfg.get_string("release.file", "", {"", "release polygons (Shapefile/GeoJSON/GPKG) or thickness raster (m)"}));
  r.handoff = resolve(cfg, "release.from",
                      cfg.get_string("release.from", "", {"", "release points from sph-slope (release.h5)"}));
  r.attribute = cfg.get_string("release.attribute", r.attribute, {"", "polygon attribute holding the thickness (m)"});
  r.depth = cfg.get("release.depth", r.depth, Range::closed(0.0, 200.0),
                    {"m", "uniform polygon release thickness; 0: use the attribute"});
  const std::string dir =
      cfg.get_choice("release.thickness_direction", to_string(r.direction), {"normal", "vertical"},
                     {"",
                      "how release thicknesses (attribute, release.depth, raster) are measured: normal to the "
                      "slope (com1DFA, RAMMS) or vertically",
                      "release thickness measured"});
  r.direction = dir == "vertical" ? ThicknessDirection::Vertical : ThicknessDirection::Normal;

  auto& p = c.params;
  p.friction = read_friction(cfg);
  p.density = cfg.get("model.density", p.density, Range::closed(500.0, 5000.0), {"kg/m^3", "mixture density ρ"});
  p.gravity = cfg.get("model.gravity", p.gravity, Range::open_closed(0.0, 100.0), {"m/s^2", "gravity g"});
  p.d0 = cfg.get("model.d0", p.d0, Range::open_closed(0.0, 1000.0), {"m", "reference particle spacing d0"});
  // h0 is the model's depth resolution: below a centimetre there is no flow depth left to resolve,
  // only particles (0.25 mm on the Alplehner release is 8.5 million of them: hours, fuzz case 126).
  p.h0 = cfg.get("model.h0", p.h0, Range::closed(0.01, 100.0),
                 {"m", "reference depth h0; particle volume V0 = h0·d0^2 (choose ≲ ¼ of the flow depth)"});
  p.duration = cfg.get("run.duration", p.duration, Range::open_closed(0.0, 1e6),
                       {"s", "longest simulated time (the run may end earlier: run.stop_energy_fraction)"});
  p.stop_energy_fraction =
      cfg.get("run.stop_energy_fraction", p.stop_energy_fraction, Range::closed_open(0.0, 1.0),
              {"1", "end the run when the kinetic energy falls below this fraction of its peak; 0: never",
               "kinetic energy fraction that ends the run"});
  p.curvature = cfg.get_bool("model.curvature", p.curvature,
                             {"", "bed curvature along the velocity in the normal force and the bed constraint"});
  p.cfl = cfg.get("numerics.cfl", p.cfl, Range::open_closed(0.0, 1.0), {"1", "Courant number on d0 with |v|+√(gh)"});
  p.dt_max = cfg.get("numerics.dt_max", p.dt_max, Range::open_closed(0.0, 100.0), {"s", "largest time step"});
  p.min_depth = cfg.get("numerics.min_depth", p.min_depth, Range::open_closed(0.0, 10.0),
                        {"m", "floor on the depth in the friction law"});
  p.skin = cfg.get("numerics.skin", p.skin, Range::closed(0.0, 2.0),
                   {"1", "neighbour-list skin in units of d0 (list rebuilt after skin·d0/2 of motion)"});
  p.lateral_mixing = cfg.get("numerics.lateral_mixing", p.lateral_mixing, Range::closed(0.0, 1e4),
                             {"1",
                              "C_mix of the lateral-mixing artificial viscosity (AvaFrame com1DFA's "
                              "subgridMixingFactor); 0: off"});
  p.smoothing = cfg.get("numerics.smoothing", p.smoothing, Range::closed(0.0, 1.0),
                        {"1", "velocity smoothing ε per step (Monaghan 1994 XSPH); 0: off"});
  const std::string norm = cfg.get_choice("numerics.pressure_normalisation", "consistent", {"consistent", "seed"},
                                          {"",
                                           "head-pressure constant: consistent (continuum −g∇h) or seed (C = 1, the "
                                           "raw coefficient of SWJTU lecture (2010), §3)"});
  p.pressure_scale = norm == "seed" ? 1.0 : HeadPressureForce::consistent_normalisation();

  read_processes(cfg, c);
  read_barriers(cfg, c.barriers);

  auto& o = c.output;
  o.series_interval = cfg.get("output.series_interval", o.series_interval, Range::open_closed(0.0, 1e6),
                              {"s", "time between rows of series.csv"});
  o.snapshot_interval = cfg.get("output.snapshot_interval", o.snapshot_interval, Range::open_closed(0.0, 1e6),
                                {"s", "time between particle snapshots"});
  o.snapshots = cfg.get_bool("output.snapshots", o.snapshots, {"", "write snapshots.h5 + .xmf"});
  o.pngs = cfg.get_bool("output.png", o.pngs, {"", "write the quick-look PNGs"});
  o.sparse_min_depth = cfg.get(
      "output.sparse_min_depth", o.sparse_min_depth, Range::open_closed(0.0, 10.0),
      {"m",
       "a particle with no other within 2 d0 paints the peak maps with its volume over its footprint V/s^2 (s: "
       "distance to its nearest particle) only where that exceeds this; below it is detached, left out of the maps "
       "and reported (AvaFrame com1DFA hmin: 0.05 m)"});
  auto& it = o.intensity;
  const std::string scheme =
      cfg.get_choice("intensity.scheme", to_string(it.scheme), {"depth_speed", "pressure"},
                     {"",
                      "intensity classes: depth_speed (Swiss debris-flow guideline: strong where peak depth > "
                      "strong_depth and peak speed > strong_speed, medium elsewhere reached) or pressure",
                      "intensity scheme"});
  it.scheme = scheme == "pressure" ? IntensityScheme::Pressure : IntensityScheme::DepthSpeed;
  it.min_depth = cfg.get("intensity.min_depth", it.min_depth, Range::closed(0.0, 100.0),
                         {"m", "a cell counts as reached when its peak depth exceeds this"});
  it.strong_depth = cfg.get("intensity.strong_depth", it.strong_depth, Range::open_closed(0.0, 100.0),
                            {"m", "depth_speed: peak depth above which (with the speed) a cell is strong",
                             "intensity: strong above the depth"});
  it.strong_speed = cfg.get("intensity.strong_speed", it.strong_speed, Range::open_closed(0.0, 200.0),
                            {"m/s", "depth_speed: peak speed above which (with the depth) a cell is strong",
                             "intensity: strong above the speed"});
  const std::vector<double> classes = cfg.get_array(
      "intensity.pressure_classes", {it.medium_pressure, it.strong_pressure}, Range::open_closed(0.0, 1e9),
      {"Pa", "pressure: [medium, strong] lower bounds of peak ρv², increasing"}, 2);
  if (!(classes[0] < classes[1]))
    throw InputError("intensity.pressure_classes must increase: [medium, strong] = [" + std::to_string(classes[0]) +
                         ", " + std::to_string(classes[1]) + "] Pa",
                     cfg.source().empty() ? "command line" : cfg.source(), "intensity.pressure_classes");
  it.medium_pressure = classes[0];
  it.strong_pressure = classes[1];
  read_map_settings(cfg, o);
  read_gauges_and_profile(cfg, o);
  return c;
}

std::vector<FrictionKey> friction_keys(std::string_view law) {
  std::vector<FrictionKey> out;
  for (const auto& k : BasalFrictionParameters::keys())
    if (std::find(k.laws.begin(), k.laws.end(), law) != k.laws.end())
      out.push_back({"model." + std::string(k.spec.key), std::string(k.spec.meaning), std::string(k.spec.unit)});
  return out;
}

}  // namespace geohaz::runout
