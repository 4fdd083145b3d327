// The pore water of an sph-slope config (docs/sph.md, "Pore pressure and seismic coefficients"):
// the solver's PoreWaterSettings made from [water] and [rain] on the slope (2D, 3D) and on DSM
// sections (2D, 3D strip), the rasters of a section (water table, pore pressure) cut along it or
// sampled over the strip, the rain's pressure head on Bishop's slice bases, and the checks of the
// sources of pore water.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "geohaz/core/errors.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

namespace {

/// The section's raster of pore water ("" if none): its key and its path.
std::pair<const char*, const std::string*> section_raster(const RunConfig& c) {
  if (!c.pore_pressure_raster.empty()) return {"water.pore_pressure_raster", &c.pore_pressure_raster};
  return {"water.table_raster", &c.water_table_raster};
}

/// The water table's elevation the section's raster gives at map point (x, y) with ground z_g (m;
/// NaN where the raster has no value): water.table_raster as it is; water.pore_pressure_raster, u_b
/// at the base of the soil cover (vertical depth D = section.soil_thickness), its piezometric level
/// z_g − D + u_b/γ_w.
double raster_table_at(const RunConfig& c, double x, double y, double zg) {
  if (c.section.pore_pressure) {
    const double ub = c.section.pore_pressure->elevation(x, y);
    return zg - c.section.soil_thickness + ub / c.water.unit_weight;
  }
  return c.section.water_table->elevation(x, y);
}

bool has_section_raster(const RunConfig& c) {
  return c.scenario == ScenarioType::Section && (c.section.water_table || c.section.pore_pressure);
}

/// The grid of a 3D strip's local coordinates at the particle spacing with the DSM's ground at its
/// nodes (map point of node (s, y): section_map_point(s, y − W/2)).
std::shared_ptr<StripGrid> strip_ground_grid(const RunConfig& c) {
  const auto& P = c.section.profile;
  const double dx = c.numerics.spacing, width = strip_width(c), half = 0.5 * width;
  auto g = std::make_shared<StripGrid>();
  const double length = P.back().s - P.front().s;
  g->x0 = P.front().s;
  g->nx = std::max(2, static_cast<int>(std::ceil(length / dx)) + 1);
  g->dx = length / (g->nx - 1);
  g->y0 = 0.0;
  g->ny = std::max(2, static_cast<int>(std::ceil(width / dx)) + 1);
  g->dy = width / (g->ny - 1);
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) {
      const Vec2 q = section_map_point(P, g->x0 + i * g->dx, g->y0 + j * g->dy - half);
      const double zg = c.section.terrain->elevation(q.x(), q.y());
      if (!std::isfinite(zg))
        throw InputError("the 3D section strip leaves the DSM's data at (" + csv_number(q.x()) + ", " +
                             csv_number(q.y()) + "): narrow geometry.width or move the polyline",
                         c.config_source, "geometry.width", csv_number(c.width));
      g->ground.push_back(zg);
    }
  return g;
}

/// The clock of the rain's pore pressure: the config's in a dynamic run; held at rain.evaluate_at in
/// the strength reduction and the limit-equilibrium analysis (one pore-pressure field).
std::vector<std::array<double, 2>> rain_clock(const RunConfig& c) {
  if (c.analysis == Analysis::Dynamic) return c.rain.clock;
  return {{0.0, c.rain.evaluate_at}, {1.0, c.rain.evaluate_at}};
}

/// u = r_u g ∫ρ dz: the soil column of the slope's initial profile and layers, or of a DSM section's
/// cover over its base (the ground of the profile, or of the 3D strip's grid), as Bishop's slices
/// take it (limit_equilibrium.cpp, column_of).
OverburdenProfile overburden_of(const RunConfig& c) {
  OverburdenProfile o;
  auto density = [&](int m) { return c.materials[static_cast<std::size_t>(m)].density; };
  if (c.scenario == ScenarioType::Section) {
    const ProfileDomain d = section_profile(c);
    o.ground = d.surface;
    o.densities = {density(d.layer_materials.front())};
    o.surface_layer_depth = d.surface_layer_depth;
    o.surface_density = density(d.surface_material);
    if (c.dimension == 3) o.grid = strip_ground_grid(c);
    return o;
  }
  ProfileDomain d = c.slope.profile();
  apply_layers(d, c);
  o.ground = d.surface;
  o.tops = d.layer_materials.empty() ? std::vector<double>{} : d.layer_tops;
  if (d.layer_materials.empty())
    o.densities = {c.materials.front().density};
  else
    for (const int m : d.layer_materials) o.densities.push_back(density(m));
  return o;
}

}  // namespace

std::shared_ptr<const RainPorePressure> rain_pore_pressure_on_profile(const RunConfig& c) {
  const auto& k = c.rain.infiltration;
  const auto ground = c.scenario == ScenarioType::Section ? section_profile(c).surface : c.slope.profile().surface;
  return std::make_shared<const RainPorePressure>(k.hydrology, k.rain, ground, k.water_table_depth, rain_clock(c));
}

std::shared_ptr<const RainPorePressure> rain_pore_pressure(const RunConfig& c) {
  if (c.scenario != ScenarioType::Section || c.dimension != 3) return rain_pore_pressure_on_profile(c);
  const auto& k = c.rain.infiltration;
  return std::make_shared<const RainPorePressure>(k.hydrology, k.rain, strip_ground_grid(c), k.water_table_depth,
                                                  rain_clock(c));
}

void apply_rain(PoreWater& w, const std::shared_ptr<const RainPorePressure>& rain, double t_rain) {
  // The initial table, parallel to the ground, sets where the soil weighs its saturated unit weight
  // (as the SPH's particles, saturate_below_water_table); the rain's head gives u.
  w.phreatic.clear();
  for (const auto& p : rain->ground()) w.phreatic.push_back({p[0], p[1] - rain->water_table_depth()});
  w.pressure_field = [rain, gw = w.unit_weight, t_rain](double x, double z) {
    return gw * std::max(rain->head(x, z, t_rain), 0.0);
  };
}

std::vector<std::array<double, 2>> clipped_phreatic_surface(const RunConfig& c) {
  const auto ground = c.slope.profile();
  PoreWater w = c.water;
  std::vector<std::array<double, 2>> out;
  const int n = 4000;
  for (int k = 0; k <= n; ++k) {
    const double x = ground.x_left + (ground.x_right - ground.x_left) * k / n;
    out.push_back({x, std::min(w.level_at(x), surface_at(ground.surface, x))});
  }
  return out;
}

std::vector<std::array<double, 2>> section_water_table(const RunConfig& c) {
  const auto [key, path] = section_raster(c);
  std::vector<std::array<double, 2>> cut;
  for (const auto& p : c.section.profile) {
    const double z = raster_table_at(c, p.x, p.y, p.z);
    if (!std::isfinite(z))
      throw InputError("the raster has no value at the section's point (" + csv_number(p.x) + ", " + csv_number(p.y) +
                           ") (s = " + csv_number(p.s) + " m): it must cover the section, without nodata",
                       c.config_source, key, *path);
    cut.push_back({p.s, z});
  }
  return cut;
}

std::shared_ptr<const WaterTableGrid> section_water_table_grid(const RunConfig& c) {
  const auto [key, path] = section_raster(c);
  const auto& P = c.section.profile;
  const double half = 0.5 * strip_width(c);
  auto g = std::make_shared<WaterTableGrid>();
  static_cast<StripGrid&>(*g) = *strip_ground_grid(c);
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) {
      const Vec2 q = section_map_point(P, g->x0 + i * g->dx, g->y0 + j * g->dy - half);
      const double zw = raster_table_at(c, q.x(), q.y(), g->ground[static_cast<std::size_t>(j * g->nx + i)]);
      if (!std::isfinite(zw))
        throw InputError("the raster has no value at (" + csv_number(q.x()) + ", " + csv_number(q.y()) +
                             ") on the 3D strip: it must cover the strip, without nodata",
                         c.config_source, key, *path);
      g->table.push_back(zw);
    }
  return g;
}

PoreWaterSettings pore_water_settings(const RunConfig& c) {
  PoreWaterSettings pw;
  const bool section = c.scenario == ScenarioType::Section;
  if (!section && c.scenario != ScenarioType::Slope) return pw;
  if (!(has_section_raster(c) || c.water.active() || c.rain.enabled)) return pw;
  pw.density = c.numerics.gravity > 0.0 ? c.water.unit_weight / c.numerics.gravity : 1000.0;
  if (has_section_raster(c)) {
    // A DSM section: the raster's table cut along the section (2D, clipped to the profile) or over the strip (3D).
    pw.history_times = c.water_history_times;
    pw.history_offsets = c.water_history_offsets;
    if (c.dimension == 2) {
      pw.phreatic = section_water_table(c);
      pw.ground = section_profile(c).surface;
    } else {
      pw.table = section_water_table_grid(c);
    }
    return pw;
  }
  if (c.rain.enabled) {
    pw.rain = rain_pore_pressure(c);
    return pw;
  }
  if (c.water.ru > 0.0) {
    pw.ru = c.water.ru;
    pw.overburden = overburden_of(c);
    return pw;
  }
  // A phreatic polyline: the slope (uniform across a 3D width).
  pw.phreatic = c.water.phreatic;
  pw.ground = c.slope.profile().surface;
  pw.history_times = c.water_history_times;
  pw.history_offsets = c.water_history_offsets;
  return pw;
}

namespace {

/// The checks of a section's raster (water.table_raster or water.pore_pressure_raster): a DSM
/// section, one source of pore water, the raster covering the section (or strip); a table raster
/// lying below the ground somewhere.
void validate_section_raster(const RunConfig& c, const char* key, const std::string& path) {
  if (path.empty()) return;
  const std::string& src = c.config_source;
  const std::string table = "water.table_raster";
  if (c.scenario != ScenarioType::Section)
    throw InputError(std::string("a ") + (key == table ? "water table" : "pore-pressure") +
                         " raster needs a DSM section (run.scenario = section); a slope takes water.phreatic",
                     src, key, path);
  const bool other = !c.water.phreatic.empty() || c.water.ru > 0.0 || c.rain.enabled ||
                     (key != table && !c.water_table_raster.empty());
  if (other)
    throw InputError(
        "one source of pore water at a time: water.pore_pressure_raster, water.table_raster, water.phreatic, "
        "water.ru or rain",
        src, key, path);
  if (key != table && !(c.numerics.gravity > 0.0))
    throw InputError("a pore-pressure raster needs gravity (its level is z_g - D + u / (rho_w g))", src,
                     "numerics.gravity", csv_number(c.numerics.gravity));
  if (!has_section_raster(c)) return;  // describe mode, or not loaded
  bool below = false;
  if (c.dimension == 2) {
    const auto cut = section_water_table(c);
    for (std::size_t k = 0; k < cut.size(); ++k) below = below || cut[k][1] < c.section.profile[k].z;
  } else {
    const auto g = section_water_table_grid(c);
    for (std::size_t k = 0; k < g->table.size(); ++k) below = below || g->table[k] < g->ground[k];
  }
  if (!below && key == table)
    throw InputError("the water table lies above the ground over the whole section", src, key, path);
}

/// The checks of [rain] in sph-slope: one source of water, the slope or a DSM section, β > 0 on
/// every segment (cell) of the ground.
void validate_rain(const RunConfig& c) {
  const std::string& src = c.config_source;
  if (!c.water.phreatic.empty() || c.water.ru > 0.0)
    throw InputError("one source of pore water at a time: rain, water.phreatic or water.ru", src, "rain.enabled",
                     "true");
  if (c.scenario != ScenarioType::Slope && c.scenario != ScenarioType::Section)
    throw InputError("rain needs the slope or the section scenario", src, "rain.enabled", "true");
  if (c.scenario == ScenarioType::Section && c.section.profile.empty()) return;  // describe mode
  const auto& h = c.rain.infiltration.hydrology;
  const double beta = rain_pore_pressure(c)->smallest_beta();
  if (!(beta > 0.0))
    throw InputError("the long-term infiltration I_ZLT/K_s must be below cos^2 of the steepest ground segment (" +
                         std::to_string(beta + h.steady_flux / h.conductivity) +
                         "): no steady slope-parallel flow otherwise",
                     src, "hydrology.steady_infiltration", std::to_string(h.steady_flux));
}

}  // namespace

void validate_water_sources(const RunConfig& c) {
  validate_section_raster(c, "water.pore_pressure_raster", c.pore_pressure_raster);
  validate_section_raster(c, "water.table_raster", c.water_table_raster);
  const auto& w = c.water;
  if (!w.phreatic.empty() && c.scenario != ScenarioType::Slope)
    throw InputError("a phreatic polyline needs the slope scenario (a DSM section takes water.table_raster)",
                     c.config_source, "water.phreatic");
  if (w.ru > 0.0 && c.scenario != ScenarioType::Slope && c.scenario != ScenarioType::Section)
    throw InputError("r_u needs the slope or the section scenario", c.config_source, "water.ru", std::to_string(w.ru));
  if (c.rain.enabled) validate_rain(c);
}

}  // namespace geohaz::sph
