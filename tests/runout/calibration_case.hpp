#pragma once
// A synthetic back-analysis case for the calibration tests: the synthetic valley (synthetic_terrain.hpp)
// scaled down, a release block near its head, and an "observed event" made by a debris-runout run
// with known parameters: its footprint (peak depth > 0.1 m) and deposit as rasters on the DSM grid,
// and the valley's thalweg as a GeoJSON line.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/run.hpp"
#include "geohaz/runout/synthetic_terrain.hpp"

namespace calibration_case {

namespace fs = std::filesystem;

struct Case {
  fs::path dir, base, footprint, deposit, thalweg;
  double runout_s = 0.0;  ///< the truth's farthest affected cell along the thalweg (m)
};

/// The valley at `scale` (cells of `cell` m), the base case with the `model` block (TOML lines after
/// [model]), and the truth run with the `truth` overrides (key=value).
inline Case make(const fs::path& d, const std::string& model, const std::vector<std::string>& truth, double scale = 0.1,
                 double cell = 5.0) {
  using namespace geohaz;
  using namespace geohaz::runout;
  fs::create_directories(d);
  SyntheticValley v = SyntheticValley{}.scaled(scale);
  const double len = v.length();
  v.cell = cell;
  v.nx = static_cast<int>(std::lround(len / cell));
  v.ny = static_cast<int>(std::lround(v.ny * 2.5 / cell));
  const GridGeometry g = v.geometry();
  Raster dsm;
  dsm.nx = g.nx, dsm.ny = g.ny;
  dsm.geotransform = {g.x0, g.dx, 0.0, g.y0, 0.0, -g.dy};
  dsm.crs_wkt = kSyntheticValleyCrsWkt;
  dsm.nodata = -9999.0;
  dsm.data = v.surface().values();
  Raster rel = dsm.like(0.0, -9999.0);
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      const Vec2 p = g.centre(c, r);
      const double s = p.x() - g.x0;
      if (s > 0.06 * len && s < 0.14 * len && std::abs(p.y() - v.thalweg_y(p.x())) < 0.03 * len) rel.at(c, r) = 2.0;
    }
  write_geotiff(d / "dsm.tif", dsm);
  write_geotiff(d / "release.tif", rel);
  {
    std::ofstream b(d / "base.toml");
    b << "[terrain]\ndsm = \"dsm.tif\"\n[release]\nfile = \"release.tif\"\nthickness_direction = \"vertical\"\n"
         "[model]\n"
      << model << "\n[run]\nduration = 300.0\n";
  }
  {
    // The thalweg from the release to the east edge, in the DSM's CRS (EPSG:32654).
    std::ofstream t(d / "thalweg.geojson");
    t << std::setprecision(12)
      << "{\"type\": \"FeatureCollection\", \"crs\": {\"type\": \"name\", \"properties\": {\"name\": "
         "\"urn:ogc:def:crs:EPSG::32654\"}}, \"features\": [{\"type\": \"Feature\", \"properties\": {}, "
         "\"geometry\": {\"type\": \"LineString\", \"coordinates\": [";
    const int n = 40;
    for (int k = 0; k <= n; ++k) {
      const double x = g.x0 + len * (0.05 + 0.93 * k / n);
      t << (k ? ", " : "") << '[' << x << ", " << v.thalweg_y(x) << ']';
    }
    t << "]}}]}\n";
  }
  // The truth.
  ConfigReader cfg = ConfigReader::from_file(d / "base.toml");
  for (const auto& o : truth) cfg.apply_override(o);
  RunConfig c = read_config(cfg);
  const RunoutInputs in = load_inputs(c);
  RunoutSimulation sim(in, c.params, c.output);
  sim.run();
  Raster fp = dsm.like(0.0, -9999.0), dep = dsm.like(0.0, -9999.0);
  const auto deposit = sim.deposit();
  for (std::size_t k = 0; k < fp.data.size(); ++k) {
    fp.data[k] = sim.maps().max_depth()[k] > 0.1 ? 1.0 : 0.0;
    dep.data[k] = deposit[k];
  }
  write_geotiff(d / "footprint.tif", fp);
  write_geotiff(d / "deposit.tif", dep, true);
  Case out{d, d / "base.toml", d / "footprint.tif", d / "deposit.tif", d / "thalweg.geojson", 0.0};
  return out;
}

/// The footprint raster eroded (grow = −1) or dilated (+1) by one cell (4-neighbourhood).
inline void morph(const fs::path& in, const fs::path& out, int grow) {
  geohaz::Raster f = geohaz::read_raster(in);
  geohaz::Raster o = f;
  for (int r = 0; r < f.ny; ++r)
    for (int c = 0; c < f.nx; ++c) {
      const bool self = f.at(c, r) > 0.5;
      bool any = false, all = true;
      for (const auto& [dc, dr] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int cc = c + dc, rr = r + dr;
        const bool v = cc >= 0 && rr >= 0 && cc < f.nx && rr < f.ny && f.at(cc, rr) > 0.5;
        any = any || v, all = all && v;
      }
      o.at(c, r) = grow > 0 ? (self || any ? 1.0 : 0.0) : (self && all ? 1.0 : 0.0);
    }
  geohaz::write_geotiff(out, o);
}

/// A calibration config for the case.
inline std::string config(const Case& c, const std::string& parameters, const std::string& extra = "",
                          bool deposit = true) {
  std::ostringstream o;
  o << "[calibration]\nbase = \"" << c.base.string() << "\"\n"
    << extra << "\n"
    << parameters << "\n[observation]\nfootprint = \"" << c.footprint.string() << "\"\nthalweg = \""
    << c.thalweg.string() << "\"\n";
  if (deposit) o << "deposit = \"" << c.deposit.string() << "\"\n";
  return o.str();
}

}  // namespace calibration_case
