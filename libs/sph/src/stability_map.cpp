#include "geohaz/sph/stability_map.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/parallel.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/sph/constitutive.hpp"

namespace geohaz::sph {

namespace fs = std::filesystem;

namespace {

constexpr const char* kApp = "slope-stability";
constexpr double kNodata = -9999.0;
/// FS values above this are written as it (TRIGRS's cap of the same value): flat cells have FS → ∞.
constexpr double kFsCap = 10.0;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string resolve(const ConfigReader& cfg, std::string p) {
  if (!p.empty() && !cfg.source().empty() && fs::path(p).is_relative() && !fs::exists(p))
    return (cfg.base_dir() / p).string();
  return p;
}

std::string fmt(double v, int digits = 6) {
  std::ostringstream o;
  o << std::setprecision(digits) << v;
  return o.str();
}

/// A per-cell raster on the DSM's grid (same size and geotransform), or InputError naming the key.
std::vector<double> read_cell_raster(const std::string& file, const char* key, const Raster& dsm) {
  const Raster r = read_raster(file, CrsPolicy::Any);
  bool same = r.nx == dsm.nx && r.ny == dsm.ny;
  for (int k = 0; k < 6 && same; ++k)
    same = std::abs(r.geotransform[k] - dsm.geotransform[k]) <= 1e-6 * std::max(1.0, std::abs(dsm.geotransform[k]));
  if (!same)
    throw InputError("must be on the DSM's grid (" + std::to_string(dsm.nx) + " x " + std::to_string(dsm.ny) +
                         " cells, same origin and cell size)",
                     file, key, file);
  std::vector<double> v(r.data.size());
  for (std::size_t k = 0; k < v.size(); ++k) v[k] = r.is_nodata(r.data[k]) ? kNaN : r.data[k];
  return v;
}

}  // namespace

StabilityMapCase read_stability_map_case(ConfigReader& cfg) {
  StabilityMapCase c;
  c.config_source = cfg.source();
  c.dsm = resolve(cfg, cfg.get_string("terrain.dsm", "",
                                      {"",
                                       "DSM raster (any GDAL format, projected CRS, m); the positional argument "
                                       "overrides it",
                                       "terrain (DSM)"}));
  // Soil cover.
  c.soil_depth = cfg.get("soil.depth", c.soil_depth, Range::open_closed(0.0, 100.0),
                         {"m", "vertical depth Z of the failure plane (soil-bedrock contact); the release thickness"});
  c.soil_depth_raster = resolve(
      cfg, cfg.get_string("soil.depth_raster", "", {"", "raster of Z (m) on the DSM's grid; overrides soil.depth"}));
  c.min_slope = kDegree * cfg.get("soil.min_slope", c.min_slope / kDegree, Range::closed_open(0.0, 90.0),
                                  {"deg", "cells flatter than this carry no soil cover (no result)"});
  c.max_slope = kDegree * cfg.get("soil.max_slope", c.max_slope / kDegree, Range::open_closed(0.0, 90.0),
                                  {"deg", "cells steeper than this carry no soil cover (rock faces; no result)"});
  auto& s = c.soil;
  s.cohesion =
      cfg.get("soil.cohesion", s.cohesion, Range::non_negative(), {"Pa", "effective cohesion c' (soil and roots)"});
  s.friction = kDegree * cfg.get("soil.friction_angle", s.friction / kDegree, Range::open_closed(0.0, 89.0),
                                 {"deg", "effective friction angle phi'"});
  s.unit_weight_moist = cfg.get("soil.unit_weight_moist", s.unit_weight_moist, Range::closed(1e3, 5e4),
                                {"N/m^3", "unit weight gamma_m of the soil above the water table"});
  s.unit_weight_saturated = cfg.get("soil.unit_weight_saturated", s.unit_weight_saturated, Range::closed(1e3, 5e4),
                                    {"N/m^3", "unit weight gamma_sat below the water table (>= gamma_m, > gamma_w)"});
  s.unit_weight_water = cfg.get("soil.unit_weight_water", s.unit_weight_water, Range::closed(9e3, 1.2e4),
                                {"N/m^3", "unit weight of water gamma_w"});
  s.suction = cfg.get_bool("soil.suction", s.suction,
                           {"", "negative pressure heads (above the water table) add strength; false: counted as 0"});
  // Hydrology and rain: the keys sph-slope reads too (infiltration.hpp).
  {
    const InfiltrationKeys k = read_infiltration_keys(cfg);
    c.hydrology = k.hydrology;
    c.water_table_depth = k.water_table_depth;
    c.rain = k.rain;
  }
  c.water_table_raster =
      resolve(cfg, cfg.get_string("hydrology.water_table_raster", "",
                                  {"", "raster of d (m) on the DSM's grid; overrides hydrology.water_table_depth"}));
  // Run and outputs.
  c.duration = cfg.get("run.duration", c.duration, Range::closed(0.0, 1e8),
                       {"s", "simulated time; 0: the end of the rain", "simulated duration"});
  c.time_step = cfg.get("run.time_step", c.time_step, Range::open_closed(0.0, 1e7),
                        {"s", "evaluation step (failure times are refined between evaluations)"});
  c.output_every =
      static_cast<int>(cfg.get_int("output.every", c.output_every, Range::closed(1, 1e6),
                                   {"1", "an FS GeoTIFF every this many evaluation steps (and the last)"}));
  c.pngs = cfg.get_bool("output.pngs", c.pngs, {"", "quick-look PNG maps of the minimum FS and the failure time"});

  // Cross-checks (the ranges alone cannot see them).
  if (s.unit_weight_moist > s.unit_weight_saturated)
    throw InputError(
        "the moist unit weight must not exceed the saturated one (" + fmt(s.unit_weight_saturated) + " N/m^3)",
        cfg.source(), "soil.unit_weight_moist", fmt(s.unit_weight_moist));
  if (!(s.unit_weight_saturated > s.unit_weight_water))
    throw InputError("the saturated unit weight must exceed that of water (" + fmt(s.unit_weight_water) + " N/m^3)",
                     cfg.source(), "soil.unit_weight_saturated", fmt(s.unit_weight_saturated));
  if (!(c.min_slope < c.max_slope))
    throw InputError("soil.min_slope must be below soil.max_slope (" + fmt(c.max_slope / kDegree) + " deg)",
                     cfg.source(), "soil.min_slope", fmt(c.min_slope / kDegree));
  if (c.duration == 0.0) c.duration = c.rain.end();
  return c;
}

StabilityMapInputs load_stability_map_inputs(const StabilityMapCase& c) {
  if (c.dsm.empty()) throw InputError("no DSM given (positional argument or terrain.dsm)", "command line");
  StabilityMapInputs in;
  in.dsm = read_raster(c.dsm, CrsPolicy::RequireProjected);
  if (in.dsm.nx < 3 || in.dsm.ny < 3) throw InputError("the DSM needs at least 3 x 3 cells", c.dsm);
  const Raster& d = in.dsm;
  in.grid = {d.nx, d.ny, d.geotransform[0], d.geotransform[3], d.cell_size_x(), d.cell_size_y()};
  const GridGeometry& g = in.grid;
  std::vector<double> z(d.data);
  for (double& v : z)
    if (d.is_nodata(v) || !std::isfinite(v)) v = kNaN;
  const BilinearGrid surface(g, std::move(z));

  in.depth = c.soil_depth_raster.empty() ? std::vector<double>(g.cells(), c.soil_depth)
                                         : read_cell_raster(c.soil_depth_raster, "soil.depth_raster", d);
  in.water_table = c.water_table_raster.empty()
                       ? std::vector<double>(g.cells(), c.water_table_depth)
                       : read_cell_raster(c.water_table_raster, "hydrology.water_table_raster", d);
  in.slope.assign(g.cells(), kNaN);
  std::size_t above_ground = 0, with_table = 0;
  for (int r = 0; r < g.ny; ++r)
    for (int col = 0; col < g.nx; ++col) {
      const std::size_t k = g.index(col, r);
      // 1. Slope: the bilinear surface's gradient on the four edge midpoints (central differences).
      const Vec2 p = g.centre(col, r);
      TerrainSample e, w, n, s;
      if (!surface.sample(p + Vec2(0.5 * g.dx, 0.0), e) || !surface.sample(p - Vec2(0.5 * g.dx, 0.0), w) ||
          !surface.sample(p + Vec2(0.0, 0.5 * g.dy), n) || !surface.sample(p - Vec2(0.0, 0.5 * g.dy), s))
        continue;
      const double gx = 0.5 * (e.gradient.x() + w.gradient.x()), gy = 0.5 * (n.gradient.y() + s.gradient.y());
      const double delta = std::atan(std::sqrt(gx * gx + gy * gy));
      in.slope[k] = delta;
      const double Z = in.depth[k], dw = in.water_table[k];
      if (!c.soil_depth_raster.empty() && !(Z >= 0.0 && Z <= 100.0) && !std::isnan(Z))
        throw InputError(
            "soil depth must be in [0, 100] m (cell " + std::to_string(col) + ", " + std::to_string(r) + ")",
            c.soil_depth_raster, "soil.depth_raster", fmt(Z));
      if (!std::isnan(dw)) {
        ++with_table;
        if (dw < 0.0) ++above_ground;
      }
      // 2. Soil cover only where the slope is in range and there is soil.
      if (!(delta >= c.min_slope && delta <= c.max_slope && Z > 0.0) || std::isnan(dw)) continue;
      if (dw < 0.0)
        throw InputError("the water table lies above the ground (depth " + fmt(dw) + " m at cell " +
                             std::to_string(col) + ", " + std::to_string(r) + "; " + std::to_string(above_ground) +
                             " of " + std::to_string(with_table) + " cells so far)",
                         c.water_table_raster, "hydrology.water_table_raster", fmt(dw));
      const double cs = std::cos(delta);
      if (c.hydrology.steady_flux / c.hydrology.conductivity >= cs * cs)
        throw InputError("the long-term infiltration I_ZLT/K_s must be below cos^2 of the slope (" + fmt(cs * cs) +
                             " at cell " + std::to_string(col) + ", " + std::to_string(r) +
                             "); lower it or soil.max_slope",
                         c.config_source, "hydrology.steady_infiltration", fmt(c.hydrology.steady_flux));
      in.cells.push_back(static_cast<int>(k));
    }
  if (in.cells.empty())
    throw InputError("no cell carries a soil cover: every slope is outside [soil.min_slope, soil.max_slope] (" +
                         fmt(c.min_slope / kDegree) + ", " + fmt(c.max_slope / kDegree) +
                         " deg), on the border or next to nodata, or the soil depth is 0",
                     c.dsm, "soil.max_slope", fmt(c.max_slope / kDegree));
  return in;
}

StabilityMapResult compute_stability_map(const StabilityMapInputs& in, const StabilityMapCase& c,
                                         const std::function<void(int, double, const std::vector<double>&)>& on_output,
                                         const std::function<void(double)>& progress) {
  const InfiltrationHistory hist(c.hydrology, c.rain);
  const std::size_t n = in.cells.size();
  // Per-cell constants (SoA over the cells with a result).
  std::vector<double> Z(n), psi0(n), beta(n), inv_zstar(n), delta(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(in.cells[i]);
    delta[i] = in.slope[k];
    Z[i] = in.depth[k];
    beta[i] = hist.beta(delta[i]);
    psi0[i] = beta[i] * (Z[i] - in.water_table[k]);
    const double cs = std::cos(delta[i]);
    inv_zstar[i] = 4.0 * c.hydrology.diffusivity / (cs * cs) / (Z[i] * Z[i]);  // D̂/Z²
  }
  const auto psi_at = [&](std::size_t i, double t) {
    return std::min(psi0[i] + Z[i] * hist.response_sum(t, inv_zstar[i]), beta[i] * Z[i]);
  };
  const auto fs_at = [&](std::size_t i, double t) {
    return infinite_slope_fs(delta[i], Z[i], psi_at(i, t), beta[i], c.soil);
  };

  StabilityMapResult r;
  const std::size_t cells = in.grid.cells();
  r.fs_min.assign(cells, kNaN);
  r.failure_time.assign(cells, kNaN);
  r.psi_max.assign(cells, kNaN);
  std::vector<double> fs_prev(n), fs_min(n), fail(n, kNaN), psi_max(n);
  std::vector<double> fs_map(cells, kNaN);
  const int steps = std::max(1, static_cast<int>(std::ceil(c.duration / c.time_step - 1e-9)));
  for (int j = 0; j <= steps; ++j) {
    const double t = std::min(c.duration, j * c.time_step),
                 t_prev = j > 0 ? std::min(c.duration, (j - 1) * c.time_step) : 0.0;
    std::size_t unstable = 0;
#pragma omp parallel for schedule(static) reduction(+ : unstable) if (parallel_worth(n))
    for (std::size_t i = 0; i < n; ++i) {
      const double psi = psi_at(i, t);
      const double f = infinite_slope_fs(delta[i], Z[i], psi, beta[i], c.soil);
      if (j == 0) {
        fs_min[i] = f;
        psi_max[i] = psi;
        if (f < 1.0) fail[i] = 0.0;
      } else {
        psi_max[i] = std::max(psi_max[i], psi);
        fs_min[i] = std::min(fs_min[i], f);
        if (f < 1.0 && std::isnan(fail[i])) {
          // 3. First crossing between the evaluations: bisection on FS(t) − 1 (FS(t_prev) ≥ 1 > FS(t)).
          double lo = t_prev, hi = t;
          while (hi - lo > 1e-6 * c.time_step) {
            const double mid = 0.5 * (lo + hi);
            (fs_at(i, mid) < 1.0 ? hi : lo) = mid;
          }
          fail[i] = hi;
          fs_min[i] = std::min(fs_min[i], 1.0);
        }
      }
      fs_prev[i] = f;
      if (f < 1.0) ++unstable;
    }
    r.times.push_back(t);
    r.unstable_cells.push_back(unstable);
    if (j % c.output_every == 0 || j == steps) {
      for (std::size_t i = 0; i < n; ++i) fs_map[static_cast<std::size_t>(in.cells[i])] = fs_prev[i];
      on_output(j, t, fs_map);
    }
    progress(t);
  }
  const double area = in.grid.cell_area();
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(in.cells[i]);
    r.fs_min[k] = fs_min[i];
    r.psi_max[k] = psi_max[i];
    r.failure_time[k] = fail[i];
    if (!std::isnan(fail[i])) {
      ++r.failed_cells;
      if (fail[i] == 0.0) ++r.initially_unstable;
      r.release_volume += Z[i] * area;
    }
  }
  return r;
}

Raster release_thickness(const StabilityMapInputs& in, const StabilityMapResult& r) {
  Raster t = in.dsm.like(0.0, kNodata);
  for (std::size_t k = 0; k < t.data.size(); ++k) {
    if (in.dsm.is_nodata(in.dsm.data[k])) t.data[k] = kNodata;
    if (!std::isnan(r.failure_time[k])) t.data[k] = in.depth[k] * std::cos(in.slope[k]);
  }
  t.description = "release slab thickness normal to the slope, Z cos(slope), of the cells that failed";
  t.unit = std::string(1, 'm');  // not = "m": GCC 12 -Wrestrict false positive (as in debris-runout)
  return t;
}

StabilityMapResult run_stability_map(const StabilityMapCase& c, const fs::path& out, bool quiet, int threads) {
  // 1-2. Inputs, all checked before anything is written.
  const StabilityMapInputs in = load_stability_map_inputs(c);
  make_output_dir(out);
  write_text_file(out / "config.resolved.toml", c.resolved_config);
  fs::create_directories(out / "fs");
  if (!quiet)
    std::cerr << kApp << ": " << in.cells.size() << " of " << in.grid.cells() << " cells with a soil cover, rain "
              << fmt(c.rain.depth_until(c.rain.end()) * 1e3) << " mm over " << fmt(c.rain.end() / 3600.0)
              << " h, evaluated every " << fmt(c.time_step) << " s to " << fmt(c.duration) << " s, " << threads
              << " thread(s)\n";

  const auto to_raster = [&](const std::vector<double>& v, const char* description, const char* unit, double cap) {
    Raster r = in.dsm.like(kNodata, kNodata);
    for (std::size_t k = 0; k < v.size(); ++k)
      if (!std::isnan(v[k])) r.data[k] = std::min(v[k], cap);
    r.description = description;
    r.unit = unit;
    return r;
  };
  const auto fs_style = [](const fs::path& p) { write_qgis_ramp_style(p, ColourRamp::Magma, 0.0, 2.0, "1", -1e300); };
  // 3. The evaluations, writing FS(t) as they come.
  ProgressReporter progress(kApp, c.duration, quiet);
  AtomicTextFile times_csv(out / "fs" / "times.csv");
  times_csv << "file,time_s\n";
  std::int64_t step = 0;
  const StabilityMapResult r = compute_stability_map(
      in, c,
      [&](int, double t, const std::vector<double>& fsv) {
        char name[64];
        std::snprintf(name, sizeof name, "fs_t%07.0fs", t);
        const Raster ras = to_raster(fsv, "factor of safety of the infinite slope on the failure plane", "1", kFsCap);
        write_geotiff(out / "fs" / (std::string(name) + ".tif"), ras);
        fs_style(out / "fs" / (std::string(name) + ".qml"));
        times_csv << name << ".tif," << fmt(t, 12) << '\n';
      },
      [&](double t) { progress.update(t, ++step, in.cells.size()); });
  times_csv.commit();
  progress.finish(c.duration, step, in.cells.size());

  // 4. Maps, release, series and summary.
  const Raster r_min = to_raster(r.fs_min, "minimum factor of safety over the run", "1", kFsCap);
  write_geotiff(out / "fs_min.tif", r_min);
  fs_style(out / "fs_min.qml");
  const Raster r_fail = to_raster(r.failure_time, "time of first failure FS < 1 (nodata: never)", "s", 1e300);
  write_geotiff(out / "failure_time.tif", r_fail);
  write_qgis_ramp_style(out / "failure_time.qml", ColourRamp::Viridis, 0.0, c.duration, "s", -1.0);
  write_geotiff(out / "max_pressure_head.tif",
                to_raster(r.psi_max, "largest pressure head on the failure plane", "m", 1e300));
  write_qgis_ramp_style(out / "max_pressure_head.qml", ColourRamp::Viridis, 0.0, c.soil_depth, "m", -1e300);
  std::vector<double> slope_deg(in.slope);
  for (double& v : slope_deg) v /= kDegree;
  write_geotiff(out / "slope.tif", to_raster(slope_deg, "slope angle", "deg", 90.0));
  write_qgis_ramp_style(out / "slope.qml", ColourRamp::Magma, 0.0, 60.0, "deg", -1.0);
  const Raster thick = release_thickness(in, r);
  const std::size_t polygons = write_raster_polygons(out / "release.gpkg", thick, "thickness", "release");
  if (c.pngs) {
    QuicklookOptions o;
    o.crop_margin_m = -1.0;
    o.scale_bar = true;
    o.north_arrow = true;
    o.ramp = ColourRamp::Magma;  // dark: low FS
    o.title = "minimum factor of safety";
    o.unit = "1";
    o.vmin = 0.0;
    o.vmax = 2.0;
    o.overlay_min = -1.0;
    const Raster& shown = r_min;
    write_quicklook_png(out / "fs_min.png", in.dsm, &shown, o);
    if (r.failed_cells > 0) {
      QuicklookOptions f;
      f.ramp = ColourRamp::Viridis;
      f.title = "time of first failure";
      f.unit = "h";
      f.overlay_min = -1.0;
      f.scale_bar = true;
      f.north_arrow = true;
      f.crop_margin_m = 200.0;  // the failed cells and their surroundings
      Raster hours = r_fail;
      for (double& v : hours.data)
        if (v != kNodata) v /= 3600.0;
      write_quicklook_png(out / "failure_time.png", in.dsm, &hours, f);
    }
  }
  {
    AtomicTextFile csv(out / "series.csv");
    csv << "time_s,rain_intensity_m_per_s,rain_depth_m,unstable_cells,unstable_area_m2\n";
    csv.stream() << std::setprecision(10);
    for (std::size_t j = 0; j < r.times.size(); ++j)
      csv << r.times[j] << ',' << c.rain.intensity_at(r.times[j]) << ',' << c.rain.depth_until(r.times[j]) << ','
          << r.unstable_cells[j] << ',' << static_cast<double>(r.unstable_cells[j]) * in.grid.cell_area() << '\n';
    csv.commit();
  }
  double first = kNaN;
  for (std::size_t k = 0; k < r.failure_time.size(); ++k)
    if (r.failure_time[k] > 0.0 && !(first <= r.failure_time[k])) first = r.failure_time[k];
  double fsmin = kNaN;
  for (double v : r.fs_min)
    if (!std::isnan(v) && !(fsmin <= v)) fsmin = v;
  nlohmann::json j;
  j["model"] = kApp;
  j["version"] = GEOHAZ_VERSION;
  j["dsm"] = c.dsm;
  j["threads"] = threads;
  j["wall_time_s"] = progress.elapsed();
  j["cells"] = {{"grid", in.grid.cells()},
                {"with_soil_cover", in.cells.size()},
                {"failed", r.failed_cells},
                {"unstable_before_rain", r.initially_unstable},
                {"cell_area_m2", in.grid.cell_area()}};
  j["rain"] = {{"steps", c.rain.intensities.size()},
               {"end_s", c.rain.end()},
               {"total_depth_m", c.rain.depth_until(c.rain.end())},
               {"peak_intensity_m_per_s", *std::max_element(c.rain.intensities.begin(), c.rain.intensities.end())}};
  j["duration_s"] = c.duration;
  j["time_step_s"] = c.time_step;
  j["fs_min"] = std::isnan(fsmin) ? nlohmann::json(nullptr) : nlohmann::json(fsmin);
  j["first_failure_during_rain_s"] = std::isnan(first) ? nlohmann::json(nullptr) : nlohmann::json(first);
  j["failed_area_m2"] = static_cast<double>(r.failed_cells) * in.grid.cell_area();
  j["release"] = {{"file", "release.gpkg"},
                  {"polygons", polygons},
                  {"attribute", "thickness"},
                  {"thickness_direction", "normal"},
                  {"volume_m3", r.release_volume}};
  nlohmann::json series = nlohmann::json::array();
  for (std::size_t k = 0; k < r.times.size(); ++k)
    series.push_back({{"time_s", r.times[k]}, {"unstable_cells", r.unstable_cells[k]}});
  j["series"] = series;
  write_text_file(out / "summary.json", j.dump(2) + "\n");
  if (!quiet)
    std::cerr << kApp << ": " << r.failed_cells << " cells failed (" << r.initially_unstable
              << " already before the rain), release volume " << fmt(r.release_volume) << " m^3 in " << polygons
              << " polygon(s); minimum FS " << fmt(fsmin, 4) << "; outputs in " << out.string() << "\n";
  return r;
}

}  // namespace geohaz::sph
