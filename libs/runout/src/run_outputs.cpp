/// \file run_outputs.cpp
/// The profile and gauge parts of a debris-runout run (run_outputs.hpp).

#include "run_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geohaz/core/errors.hpp"
#include "geohaz/runout/profile.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout::detail {

void load_output_geometry(const RunConfig& c, RunoutInputs& in) {
  const std::string source = c.config_source.empty() ? "command line" : c.config_source;
  const OutputSettings& o = c.output;
  if (!o.profile_path_file.empty()) {
    const std::vector<Polyline> lines = read_lines(o.profile_path_file, "", in.dsm.crs_wkt);
    in.profile_path = lines.front().vertices;  // read_lines refuses a file without lines
    check_profile_path(in.profile_path, in.dsm, o.profile_path_file, "output.profile_path_file");
  } else if (!o.profile_path.empty()) {
    in.profile_path = o.profile_path;
    check_profile_path(in.profile_path, in.dsm, source, "output.profile_path");
  }
  check_gauges(o.gauges, in.dsm, source);
}

std::optional<ThalwegProfile> write_profile_outputs(const RunConfig& c, const RunoutSimulation& sim,
                                                    const Raster& depth, const Raster& speed, const Raster& pressure,
                                                    const Raster& arrival, const fs::path& out) {
  const Raster& dsm = sim.inputs().dsm;
  const Terrain terrain(dsm);
  std::vector<Vec2> path = sim.inputs().profile_path;
  if (path.empty()) {
    Vec2 start(std::numeric_limits<double>::quiet_NaN(), 0.0);
    double z_top = -std::numeric_limits<double>::infinity();
    const auto& thick = sim.inputs().thickness;
    for (int row = 0; row < dsm.ny; ++row)
      for (int col = 0; col < dsm.nx; ++col) {
        const std::size_t k = static_cast<std::size_t>(row) * dsm.nx + col;
        if (k >= thick.size() || !(thick[k] > 0.0)) continue;
        const Vec2 q = dsm.cell_centre(col, row);
        const double z = terrain.elevation(q.x(), q.y());
        if (std::isfinite(z) && z > z_top) {
          z_top = z;
          start = q;
        }
      }
    if (!std::isfinite(start.x())) return std::nullopt;  // no release on the grid (a hand-off outside it)
    for (const Vec2& q : arrival_centreline(arrival, depth, start, c.output.series_interval, dsm.cell_size_x()))
      if (std::isfinite(terrain.elevation(q.x(), q.y()))) path.push_back(q);
    if (path.size() < 2) return std::nullopt;
  }
  const double min_depth = std::max(c.output.intensity.min_depth, 0.01);
  const ThalwegProfile p =
      thalweg_profile(dsm, depth, speed, pressure, path, dsm.cell_size_x(), min_depth, c.output.profile_half_width);
  write_profile_csv(out / "profile.csv", p);
  ProfileFigure figure;  // both reaches of the run, each with its name (docs/runout.md)
  const RunoutResult res = sim.result();
  if (res.path.reach > 0.0) figure.toe_path_angle_deg = res.path.fahrboeschung_deg;
  if (c.output.pngs) write_profile_png(out / "profile.png", p, figure);
  return p;
}

nlohmann::json profile_summary(const ThalwegProfile& p, bool given_path) {
  const ProfileReach r = profile_reach(p);
  nlohmann::json j = {
      {"path", given_path ? "given" : "flow centreline"}, {"reached", p.reached}, {"half_width_m", p.half_width}};
  if (!p.reached) return j;
  Vec2 xy(0.0, 0.0);
  for (const ProfileRow& row : p.rows)
    if (row.s == p.s_runout) xy = Vec2(row.x, row.y);
  j.update({{"top_station_m", p.s_top},
            {"top_elevation_m", p.z_top},
            {"runout_station_m", p.s_runout},
            {"runout_elevation_m", p.z_runout},
            {"runout_xy_m", {xy.x(), xy.y()}},
            {"drop_height_m", r.drop_height},
            {"length_m", r.length},
            {"ratio_H_over_L", r.ratio},
            {"alpha_deg", p.alpha_deg}});
  return j;
}

void write_gauge_outputs(const RunConfig& c, const RunoutSimulation& sim, const fs::path& out) {
  const GaugeRecorder& g = sim.gauges();
  if (g.empty()) return;
  write_gauges_csv(out / "gauges.csv", g);
  if (c.output.pngs) write_gauges_png(out / "gauges.png", g);
}

nlohmann::json gauges_summary(const RunoutSimulation& sim) {
  nlohmann::json out = nlohmann::json::array();
  const GaugeRecorder& g = sim.gauges();
  for (std::size_t k = 0; k < g.gauges().size(); ++k) {
    const GaugeSpec& s = g.gauges()[k];
    nlohmann::json verts = nlohmann::json::array();
    for (const Vec2& v : s.vertices) verts.push_back({v.x(), v.y()});
    double h = 0.0, v = 0.0, q = 0.0;
    for (const GaugeRow& r : g.rows()[k]) {
      h = std::max(h, r.depth);
      v = std::max(v, r.speed);
      if (std::isfinite(r.discharge) && std::abs(r.discharge) > std::abs(q)) q = r.discharge;
    }
    nlohmann::json j = {{"name", s.name},
                        {"kind", s.is_line() ? "line" : "point"},
                        {"vertices_xy_m", verts},
                        {"peak_depth_m", h},
                        {"peak_speed_m_per_s", v}};
    if (s.is_line()) {
      j["peak_discharge_m3_per_s"] = q;
      j["net_volume_m3"] = g.crossed(k);
    }
    out.push_back(j);
  }
  return out;
}

}  // namespace geohaz::runout::detail
