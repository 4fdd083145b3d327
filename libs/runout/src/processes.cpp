// Loading the spatial processes of a run (friction zones, forest, erodible layer, inflow
// hydrograph) onto the DSM grid: docs/runout.md, "Processes".
#include "geohaz/runout/processes.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>

#include "case_support.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout {

const char* to_string(EntrainmentLaw law) noexcept {
  switch (law) {
    case EntrainmentLaw::None:
      return "none";
    case EntrainmentLaw::GrowthRate:
      return "growth";
    case EntrainmentLaw::ShearStress:
      return "shear";
  }
  return "?";
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool is_vector(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".shp" || ext == ".geojson" || ext == ".json" || ext == ".gpkg" || ext == ".kml" || ext == ".gml" ||
         ext == ".sqlite";
}

/// A raster's values at the DSM cell centres (nearest cell; NaN at nodata or outside it), through
/// the CRS transformation when the raster's CRS differs. A note says when it was resampled.
std::vector<double> raster_on_grid(const std::string& file, const Raster& dsm, const std::string& key) {
  const Raster r = read_raster(file, CrsPolicy::Any);
  const GridGeometry g = geometry_of(dsm);
  std::vector<Vec2> centres;
  centres.reserve(g.cells());
  for (int row = 0; row < g.ny; ++row)
    for (int col = 0; col < g.nx; ++col) centres.push_back(g.centre(col, row));
  const bool reproject = !r.crs_wkt.empty() && !dsm.crs_wkt.empty() && !crs_equal(r.crs_wkt, dsm.crs_wkt);
  if (reproject) centres = transform_points(centres, dsm.crs_wkt, r.crs_wkt);
  const bool same_grid =
      !reproject && r.nx == dsm.nx && r.ny == dsm.ny &&
      std::equal(r.geotransform.begin(), r.geotransform.end(), dsm.geotransform.begin(),
                 [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(a)); });
  if (!same_grid)
    std::cerr << "debris-runout: note: " << key << " = " << file << " is on another grid"
              << (reproject ? " and CRS" : "") << " than the DSM: sampled at the DSM cell centres (nearest cell)\n";
  std::vector<double> out(g.cells(), kNaN);
  const double x0 = r.geotransform[0], dx = r.geotransform[1], y0 = r.geotransform[3], dy = r.geotransform[5];
  for (std::size_t k = 0; k < out.size(); ++k) {
    const double fc = (centres[k].x() - x0) / dx, fr = (centres[k].y() - y0) / dy;
    if (!(fc >= 0.0 && fr >= 0.0 && fc < r.nx && fr < r.ny)) continue;
    const double v = r.at(static_cast<int>(fc), static_cast<int>(fr));
    if (!r.is_nodata(v) && std::isfinite(v)) out[k] = v;
  }
  return out;
}

/// Paint per-polygon values on the DSM grid (cells whose centre is inside; later polygons win; NaN
/// values leave the cell as it is).
void paint(const std::vector<Polygon>& polys, const std::vector<double>& values, const GridGeometry& g,
           std::vector<double>& out) {
  for (std::size_t p = 0; p < polys.size(); ++p) {
    if (!std::isfinite(values[p])) continue;
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (const auto& v : polys[p].outer) {
      xmin = std::min(xmin, v.x());
      xmax = std::max(xmax, v.x());
      ymin = std::min(ymin, v.y());
      ymax = std::max(ymax, v.y());
    }
    const int c0 = std::max(0, static_cast<int>(std::floor((xmin - g.x0) / g.dx))),
              c1 = std::min(g.nx - 1, static_cast<int>(std::floor((xmax - g.x0) / g.dx)));
    const int r0 = std::max(0, static_cast<int>(std::floor((g.y0 - ymax) / g.dy))),
              r1 = std::min(g.ny - 1, static_cast<int>(std::floor((g.y0 - ymin) / g.dy)));
    for (int row = r0; row <= r1; ++row)
      for (int col = c0; col <= c1; ++col)
        if (polys[p].contains(g.centre(col, row))) out[g.index(col, row)] = values[p];
  }
}

/// The polygons of `file` (into `polys`) and the value of one numeric attribute per polygon (NaN
/// where null); a layer without the attribute is an InputError listing its fields.
std::vector<double> attribute_of(const std::string& file, const std::string& attribute, const Raster& dsm,
                                 std::vector<Polygon>& polys) {
  polys = read_polygons(file, attribute, dsm.crs_wkt);
  std::vector<double> v(polys.size());
  for (std::size_t p = 0; p < polys.size(); ++p) v[p] = polys[p].attribute;
  return v;
}

/// Check every finite value of a field against [lo, hi]: InputError naming the file, key and value.
void check_range(const std::vector<double>& f, double lo, double hi, const std::string& file, const std::string& key,
                 const std::string& unit) {
  for (double v : f)
    if (std::isfinite(v) && !(v >= lo && v <= hi))
      throw InputError(key + " must be in [" + detail::fmt(lo) + ", " + detail::fmt(hi) + "] " + unit + " (found " +
                           detail::fmt(v) + ")",
                       file, key, detail::fmt(v));
}

/// The same against a law coefficient's declared range (friction zones).
void check_range(const std::vector<double>& f, const ParamSpec& spec, const std::string& file, const std::string& key) {
  const std::string unit = spec.unit == "1" ? "" : std::string(spec.unit);
  for (double v : f)
    if (std::isfinite(v) && !spec.range.contains(v))
      throw InputError(key + " must be in " + spec.range.str() + " " + unit + " (found " + detail::fmt(v) + ")", file,
                       key, detail::fmt(v));
}

/// The CSV table of an inflow hydrograph: time (s), discharge (m³/s), one row per line, an optional
/// header line, '#' comments.
void read_hydrograph_table(const std::string& file, Hydrograph& q) {
  std::ifstream in(file);
  if (!in) throw InputError("cannot open the hydrograph table", file, "inflow.hydrograph");
  std::string line;
  int lineno = 0;
  bool first = true;  // the first non-comment line may be a header
  while (std::getline(in, line)) {
    ++lineno;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const bool header_allowed = first;
    first = false;
    std::replace(line.begin(), line.end(), ';', ',');
    std::istringstream row(line);
    std::string a, b;
    if (!std::getline(row, a, ',') || !std::getline(row, b, ','))
      throw InputError("line " + std::to_string(lineno) + ": expected 'time_s,discharge_m3_per_s'", file);
    double t, d;
    try {
      t = std::stod(a);
      d = std::stod(b);
    } catch (const std::exception&) {
      if (header_allowed) continue;  // a header
      throw InputError("line " + std::to_string(lineno) + ": not two numbers: '" + line + "'", file);
    }
    const std::string where = "line " + std::to_string(lineno) + ": ";
    if (!std::isfinite(t) || !std::isfinite(d)) throw InputError(where + "time and discharge must be finite", file);
    if (d < 0.0)
      throw InputError(where + "negative discharge " + detail::fmt(d) + " m^3/s (must be ≥ 0)", file, "",
                       detail::fmt(d));
    if (t < 0.0)
      throw InputError(where + "negative time " + detail::fmt(t) + " s (must be ≥ 0)", file, "", detail::fmt(t));
    if (!q.time.empty() && !(t > q.time.back()))
      throw InputError(where + "time " + detail::fmt(t) + " s is not after the previous row's " +
                           detail::fmt(q.time.back()) + " s (times must increase)",
                       file, "", detail::fmt(t));
    q.time.push_back(t);
    q.discharge.push_back(d);
  }
  if (q.time.size() < 2) throw InputError("the hydrograph needs at least two rows (time_s,discharge_m3_per_s)", file);
  if (!(q.volume() > 0.0)) throw InputError("the hydrograph delivers no volume (all discharges zero)", file);
}

/// Friction zones: polygons with coefficient attributes, then per-coefficient rasters, into
/// out.friction (NaN outside the zones).
void load_friction_zones(const ProcessSpec& s, const RunoutParameters& p, const Raster& dsm, const GridGeometry& g,
                         SpatialProcesses& out) {
  const std::string law = friction_name(p.friction);
  const auto law_has = [&](int k) { return has_parameter(p.friction, k); };
  std::string law_keys;
  for (int k = 0; k < kFrictionParameters; ++k)
    if (law_has(k))
      law_keys += (law_keys.empty() ? "" : ", ") + std::string(kFrictionParameterNames[static_cast<std::size_t>(k)]);
  if (!s.zones.empty()) {
    const std::vector<std::string> fields = vector_field_names(s.zones);
    bool any = false;
    for (int k = 0; k < kFrictionParameters; ++k) {
      const std::string name = kFrictionParameterNames[static_cast<std::size_t>(k)];
      if (std::find(fields.begin(), fields.end(), name) == fields.end()) continue;
      if (!law_has(k)) {
        std::cerr << "debris-runout: note: " << s.zones << ": attribute '" << name << "' is not a coefficient of the "
                  << law << " law: ignored\n";
        continue;
      }
      std::vector<Polygon> polys;
      const auto v = attribute_of(s.zones, name, dsm, polys);
      check_range(v, zone_parameter(k), s.zones, name);
      auto& f = out.friction[static_cast<std::size_t>(k)];
      f.assign(g.cells(), kNaN);
      paint(polys, v, g, f);
      any = true;
    }
    if (!any)
      throw InputError("the friction zones hold no attribute for a coefficient of the " + law +
                           " law (expected one of " + law_keys + ")",
                       s.zones, "zones.file");
  }
  for (int k = 0; k < kFrictionParameters; ++k) {
    const std::string& file = s.zone_rasters[static_cast<std::size_t>(k)];
    if (file.empty()) continue;
    const std::string key = std::string("zones.") + kFrictionParameterNames[static_cast<std::size_t>(k)];
    if (!law_has(k))
      throw InputError("a raster for '" + std::string(kFrictionParameterNames[static_cast<std::size_t>(k)]) +
                           "' is given but the " + law + " law has no such coefficient",
                       file, key);
    const auto v = raster_on_grid(file, dsm, key);
    check_range(v, zone_parameter(k), file, key);
    auto& f = out.friction[static_cast<std::size_t>(k)];
    if (f.empty()) f.assign(g.cells(), kNaN);
    for (std::size_t c = 0; c < v.size(); ++c)
      if (std::isfinite(v[c])) f[c] = v[c];
  }
}

/// Forest: k_f = ½ C_D n d per cell, into out.forest_drag (none without s.forest).
void load_forest(const ProcessSpec& s, const Raster& dsm, const GridGeometry& g, SpatialProcesses& out) {
  if (!s.forest.empty()) {
    std::vector<double> density(g.cells(), kNaN), diameter(g.cells(), kNaN);
    if (is_vector(s.forest)) {
      const std::vector<std::string> fields = vector_field_names(s.forest);
      const auto has = [&](const char* f) { return std::find(fields.begin(), fields.end(), f) != fields.end(); };
      std::vector<Polygon> polys;
      std::vector<double> vn, vd;
      if (has("stem_density")) {
        vn = attribute_of(s.forest, "stem_density", dsm, polys);
      } else {
        polys = read_polygons(s.forest, "", dsm.crs_wkt);
        vn.assign(polys.size(), s.stem_density);
      }
      if (has("stem_diameter"))
        vd = attribute_of(s.forest, "stem_diameter", dsm, polys);
      else
        vd.assign(polys.size(), s.stem_diameter);
      for (std::size_t k = 0; k < polys.size(); ++k) {
        if (!std::isfinite(vn[k])) vn[k] = s.stem_density;
        if (!std::isfinite(vd[k])) vd[k] = s.stem_diameter;
      }
      check_range(vn, 0.0, 10.0, s.forest, "stem_density", "stems/m^2");
      check_range(vd, 0.0, 5.0, s.forest, "stem_diameter", "m");
      paint(polys, vn, g, density);
      paint(polys, vd, g, diameter);
    } else {
      density = raster_on_grid(s.forest, dsm, "forest.file");
      check_range(density, 0.0, 10.0, s.forest, "forest.file (stem density)", "stems/m^2");
      std::fill(diameter.begin(), diameter.end(), s.stem_diameter);
    }
    out.forest_drag.assign(g.cells(), 0.0);
    bool any = false;
    for (std::size_t c = 0; c < out.forest_drag.size(); ++c)
      if (std::isfinite(density[c]) && std::isfinite(diameter[c])) {
        out.forest_drag[c] = 0.5 * s.drag_coefficient * density[c] * diameter[c];
        any = any || out.forest_drag[c] > 0.0;
      }
    if (!any)
      throw InputError(
          "the forest covers no DSM cell with a positive stem density and diameter (set "
          "forest.stem_density / forest.stem_diameter or the attributes)",
          s.forest, "forest.file");
  }
}

/// Erodible layer (m, vertical), into out.erodible_depth; checked against the entrainment law.
void load_erodible(const ProcessSpec& s, const RunoutParameters& p, const Raster& dsm, const GridGeometry& g,
                   SpatialProcesses& out) {
  if (!s.erodible.empty()) {
    if (p.entrainment.law == EntrainmentLaw::None)
      throw InputError("an erodible layer is given but entrainment.law = none (choose growth or shear)", s.erodible,
                       "entrainment.law");
    std::vector<double> e(g.cells(), kNaN);
    if (is_vector(s.erodible)) {
      std::vector<Polygon> polys;
      std::vector<double> v;
      if (s.erodible_depth > 0.0) {
        polys = read_polygons(s.erodible, "", dsm.crs_wkt);
        v.assign(polys.size(), s.erodible_depth);
      } else {
        v = attribute_of(s.erodible, s.erodible_attribute, dsm, polys);
      }
      check_range(v, 0.0, 100.0, s.erodible, s.erodible_depth > 0.0 ? "entrainment.depth" : s.erodible_attribute, "m");
      paint(polys, v, g, e);
    } else {
      e = raster_on_grid(s.erodible, dsm, "entrainment.file");
      check_range(e, 0.0, 100.0, s.erodible, "entrainment.file (erodible depth)", "m");
    }
    out.erodible_depth.assign(g.cells(), 0.0);
    double total = 0.0;
    for (std::size_t c = 0; c < e.size(); ++c)
      if (std::isfinite(e[c]) && std::isfinite(dsm.data[c]) && !dsm.is_nodata(dsm.data[c])) {
        out.erodible_depth[c] = e[c];
        total += e[c];
      }
    if (!(total > 0.0))
      throw InputError("the erodible layer has no positive depth on the DSM", s.erodible, "entrainment.file");
  } else if (p.entrainment.law != EntrainmentLaw::None) {
    throw InputError(std::string("entrainment.law = ") + to_string(p.entrainment.law) +
                         " needs an erodible layer (entrainment.file: depth raster or polygons)",
                     "config", "entrainment.file");
  }
}

/// Inflow hydrograph at a point or short line, into out.inflows (none without s.hydrograph).
void load_inflow(const ProcessSpec& s, const RunoutParameters& p, const GridSurface& surface, const GridGeometry& g,
                 SpatialProcesses& out) {
  if (!s.hydrograph.empty()) {
    Hydrograph q;
    q.source = s.hydrograph;
    read_hydrograph_table(s.hydrograph, q);
    if (s.inflow_points.size() != 2 && s.inflow_points.size() != 4)
      throw InputError("inflow.points must be [x, y] (a point) or [x1, y1, x2, y2] (a short line), map coordinates (m)",
                       "config", "inflow.points");
    q.a = Vec2(s.inflow_points[0], s.inflow_points[1]);
    q.b = s.inflow_points.size() == 4 ? Vec2(s.inflow_points[2], s.inflow_points[3]) : q.a;
    for (const Vec2& e : {q.a, q.b}) {
      SurfaceSample smp;
      if (!surface.sample(e, smp))
        throw InputError("the inflow point (" + detail::fmt(e.x()) + ", " + detail::fmt(e.y()) +
                             ") is outside the DSM or on nodata (the DSM extent is " + detail::fmt(g.x0) + " … " +
                             detail::fmt(g.x0 + g.nx * g.dx) + " × " + detail::fmt(g.y0 - g.ny * g.dy) + " … " +
                             detail::fmt(g.y0) + ")",
                         "config", "inflow.points");
    }
    if ((q.b - q.a).norm() > 20.0 * p.d0)
      throw InputError("the inflow line is " + detail::fmt((q.b - q.a).norm()) +
                           " m long: a short line (≤ 20 d0 = " + detail::fmt(20.0 * p.d0) + " m) is expected",
                       "config", "inflow.points");
    if (s.inflow_azimuth >= 0.0) {
      const double az = s.inflow_azimuth * 3.14159265358979323846 / 180.0;  // clockwise from north
      q.direction = Vec2(std::sin(az), std::cos(az));
    } else {
      SurfaceSample smp;
      surface.sample(0.5 * (q.a + q.b), smp);
      if (!(smp.grad.norm() > 1e-9))
        throw InputError("the terrain at the inflow is flat: give inflow.azimuth", "config", "inflow.azimuth");
      q.direction = -smp.grad.normalized();
    }
    q.speed = s.inflow_speed;
    out.inflows.push_back(std::move(q));
  }
}

}  // namespace

SpatialProcesses load_processes(const ProcessSpec& s, const RunoutParameters& p, const Raster& dsm,
                                const GridSurface& surface) {
  SpatialProcesses out;
  const GridGeometry g = geometry_of(dsm);
  out.grid = g;
  load_friction_zones(s, p, dsm, g, out);
  load_forest(s, dsm, g, out);
  load_erodible(s, p, dsm, g, out);
  load_inflow(s, p, surface, g, out);
  return out;
}

}  // namespace geohaz::runout
