// run.analysis = limit_equilibrium and the limit-equilibrium parts of the other analyses: the
// section of a 2D slope with its pore water and seismic coefficients, the checks of [water] and
// [seismic], the Newmark report (docs/sph.md, "Pore pressure and seismic coefficients"), and the
// static Bishop check beside the dynamic run and the strength reduction.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <variant>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/sph/newmark.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

namespace {

/// The plane-strain (c, φ) of a material under the run's model (constitutive.hpp), for Bishop.
std::pair<double, double> shear_strength_of(const RunConfig& c, const MaterialParams& p, bool residual) {
  if (const auto s = plane_strain_strength(c.model, p, residual)) return *s;
  throw InputError("has no shear strength for Bishop's method; use one of " + models_with_shear_strength(),
                   c.config_source, "model.constitutive", std::string(constitutive_model_name(c.model)));
}

}  // namespace

SlopeSection limit_equilibrium_section(const RunConfig& c, bool with_water_and_seismic) {
  // Beside an SPH run a 3D slope has the section of its profile (the checks of its water).
  if (c.scenario != ScenarioType::Slope || (c.dimension != 2 && c.analysis == Analysis::LimitEquilibrium))
    throw InputError("the limit-equilibrium analysis needs the 2D slope scenario", c.config_source, "run.scenario");
  ProfileDomain d = c.slope.profile();
  apply_layers(d, c);
  const double g = c.numerics.gravity;
  std::vector<LimitEquilibriumSoil> soils;
  for (std::size_t m = 0; m < c.materials.size(); ++m) {
    const auto& p = c.materials[m];
    const double sat = m < c.saturated_densities.size() ? c.saturated_densities[m] : 0.0;
    const auto [coh, phi] = shear_strength_of(c, p, false);
    soils.push_back({p.density * g, coh, phi, with_water_and_seismic ? sat * g : 0.0});
  }
  auto s = SlopeSection::from_profile(d, soils);
  if (with_water_and_seismic) {
    s.water = c.water;
    // Beside an SPH run, the SPH's water table: clipped to the ground (no ponded water).
    if (c.analysis != Analysis::LimitEquilibrium && !c.water.phreatic.empty())
      s.water.phreatic = clipped_phreatic_surface(c);
    // Rain: its pore pressure at the start of the main phase (held at rain.evaluate_at but in a dynamic run).
    if (c.rain.enabled) {
      const auto rain = rain_pore_pressure_on_profile(c);
      apply_rain(s.water, rain, rain->rain_time(0.0));
    }
    s.seismic = c.seismic;
  }
  return s;
}

namespace {
SlopeSection section_of(const RunConfig& c, bool residual = false);
}  // namespace

void validate_water_and_seismic(const RunConfig& c) {
  validate_water_sources(c);
  const bool water = c.water.active();
  const bool le = c.analysis == Analysis::LimitEquilibrium;
  const auto& ht = c.water_history_times;
  if (ht.size() != c.water_history_offsets.size())
    throw InputError("needs as many offsets as water.history_times (" + std::to_string(ht.size()) + ")",
                     c.config_source, "water.history_offsets");
  for (std::size_t k = 1; k < ht.size(); ++k)
    if (!(ht[k] > ht[k - 1]))
      throw InputError("must increase", c.config_source, "water.history_times", std::to_string(ht[k]));
  if (!ht.empty() && c.water.phreatic.empty() && c.water_table_raster.empty() && c.pore_pressure_raster.empty())
    throw InputError("a water-table history needs water.phreatic, water.table_raster or water.pore_pressure_raster",
                     c.config_source, "water.history_times");
  if (c.analysis == Analysis::Dynamic && (c.seismic.kh != 0.0 || c.seismic.kv != 0.0))
    throw InputError(
        "the pseudo-static coefficients are for the limit-equilibrium analysis and the strength reduction; a "
        "dynamic run takes an [earthquake]",
        c.config_source, c.seismic.kh != 0.0 ? "seismic.kh" : "seismic.kv");
  if (c.analysis == Analysis::StrengthReduction && (c.seismic.kh != 0.0 || c.seismic.kv != 0.0) &&
      (c.scenario != ScenarioType::Slope || c.dimension != 2))
    throw InputError("a strength reduction with seismic coefficients needs the 2D slope scenario", c.config_source,
                     "seismic.kh");
  if (le && !(c.numerics.gravity > 0.0))
    throw InputError("the limit-equilibrium analysis needs gravity", c.config_source, "numerics.gravity",
                     std::to_string(c.numerics.gravity));
  // The Newmark analysis samples the record every millisecond (a dynamic run reports it beside the
  // SPH, whose own time steps bound the record's length in practice).
  const bool slope2d = c.scenario == ScenarioType::Slope && c.dimension == 2;
  if ((le || (c.analysis == Analysis::Dynamic && slope2d)) && c.numerics.earthquake.active() &&
      !(c.numerics.earthquake.end_time() <= 1e4))
    throw InputError("the earthquake must end within 10^4 s (Newmark samples it every millisecond)", c.config_source,
                     "earthquake.duration", std::to_string(c.numerics.earthquake.end_time()));
  if (!water && !le) return;
  // The section's 2D profile (a 3D slope's, a DSM section's along its polyline); the limit-equilibrium
  // analysis: InputError naming run.scenario for other scenarios than the 2D slope.
  auto s = c.scenario == ScenarioType::Section && !le ? section_of(c) : limit_equilibrium_section(c, true);
  s.water.phreatic = c.water.phreatic;  // the table as given (above the ground everywhere?)
  try {
    s.validate_water("water.");
  } catch (const InputError& e) {
    // The saturated unit weight is a material key in the config.
    const std::string key = e.key() == "water.saturated_unit_weight" ? "material.saturated_density" : e.key();
    throw InputError(e.reason(), c.config_source, key, e.value());
  }
}

namespace {

/// The points of a circle's arc between two x (m), for bishop_circle.csv.
Table circle_table(const BishopResult& r) {
  Table t{{"x_m", "z_m"}, {}, {}};
  const auto& C = r.circle;
  for (int k = 0; k <= 100; ++k) {
    const double x = r.x_entry + (r.x_exit - r.x_entry) * k / 100.0;
    t.rows.push_back({x, C.zc - std::sqrt(std::max(0.0, C.radius * C.radius - (x - C.xc) * (x - C.xc)))});
  }
  return t;
}

nlohmann::json circle_json(const BishopResult& r) {
  const auto& C = r.circle;
  nlohmann::json j = {{"factor", r.factor},         {"centre_x_m", C.xc},      {"centre_z_m", C.zc},
                      {"radius_m", C.radius},       {"entry_x_m", r.x_entry},  {"exit_x_m", r.x_exit},
                      {"weight_N_per_m", r.weight}, {"direction", r.direction}};
  j["yield_coefficient"] = std::isfinite(r.yield_coefficient) ? nlohmann::json(r.yield_coefficient) : nlohmann::json();
  return j;
}

}  // namespace

nlohmann::json newmark_report(const RunConfig& c) {
  const auto& quake = c.numerics.earthquake;
  if (!quake.active()) return nullptr;
  auto s = limit_equilibrium_section(c, true);
  s.seismic = {};  // the yield coefficient of the static section (k_v of the record is not used)
  BishopSearchSettings set;
  set.minimise_yield_coefficient = true;
  const auto r = bishop_critical_circle(s, set);
  const double g = c.numerics.gravity, ay = r.yield_coefficient * g;
  // The record is the acceleration applied to every particle (loading.hpp): it drives the block in the
  // direction of sliding where direction · a_h > a_y. Integrated to the record's end; a block still
  // sliding then decelerates at a_y and adds v²/(2 a_y) (unbounded for k_y = 0: null).
  const double dt = 1e-3, t_end = quake.end_time() + dt;
  auto run = [&](int direction) {
    auto n = newmark_displacement(quake, ay, direction, t_end, dt);
    if (n.final_velocity > 0.0) {
      if (ay > 0.0) {
        n.displacement += 0.5 * n.final_velocity * n.final_velocity / ay;
        n.sliding_time += n.final_velocity / ay;
      } else {
        n.displacement = std::numeric_limits<double>::infinity();
      }
    }
    return n;
  };
  const auto along = run(r.direction), against = run(-r.direction);
  nlohmann::json j = circle_json(r);
  j["yield_acceleration_m_per_s2"] = ay;
  auto finite = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  j["displacement_m"] = finite(along.displacement);
  j["max_velocity_m_per_s"] = along.max_velocity;
  j["sliding_time_s"] = along.sliding_time;
  j["episodes"] = along.episodes;
  j["displacement_reversed_record_m"] = finite(against.displacement);
  j["time_step_s"] = dt;
  j["note"] =
      "Newmark (1965) rigid block on the circle of the smallest yield coefficient k_y (Bishop, static); the record "
      "drives it in the direction of sliding as the SPH run applies it to the particles; displacement along the "
      "slip surface's direction of sliding; null: k_y = 0 (F <= 1 without shaking), the block never stops";
  return j;
}

namespace {

/// run.analysis = limit_equilibrium: Bishop's critical circle with the pore water and the
/// seismic coefficients, the yield coefficient of the static section and, with an earthquake, the
/// Newmark displacement.
class LimitEquilibriumRun final : public SimulationModel {
 public:
  LimitEquilibriumRun(const RunConfig& c, bool quiet) : c_(c), quiet_(quiet) {}
  void run(const SphSimulation& self, RunObserver* obs) override {
    if (obs) obs->started(self);
    const auto s = limit_equilibrium_section(c_, true);
    // No admissible circle (a section that cannot slide, or one no circle of the search fits): a
    // result, reported in the summary, not an input error (the output folder exists by now).
    try {
      critical_ = bishop_critical_circle(s);
      newmark_ = newmark_report(c_);
    } catch (const InputError& e) {
      note_ = e.reason();
    }
    if (newmark_.is_null() && critical_.admissible()) {  // the yield coefficient of the static section all the same
      auto st = s;
      st.seismic = {};
      BishopSearchSettings set;
      set.minimise_yield_coefficient = true;
      try {
        yield_ = bishop_critical_circle(st, set);
      } catch (const InputError&) {  // no circle with a determined k_y: reported as null
      }
    }
    if (obs) obs->finished(self);
  }
  double time() const override { return 0.0; }
  std::int64_t step_count() const override { return 0; }
  std::size_t particle_count() const override { return 0; }
  bool main_phase_started() const override { return false; }
  nlohmann::json summary() const override {
    nlohmann::json s;
    s["scenario"] = "slope";
    s["dimension"] = 2;
    s["config"] = c_.config_source;
    s["analysis"] = "limit_equilibrium";
    s["bishop"] = critical_.admissible() ? circle_json(critical_) : nlohmann::json();
    s["factor_of_safety"] = critical_.admissible() ? nlohmann::json(critical_.factor) : nlohmann::json();
    if (!note_.empty()) s["bishop_note"] = note_;
    s["seismic"] = {{"kh", c_.seismic.kh}, {"kv", c_.seismic.kv}};
    s["water"] = water_summary(c_, 0.0);
    if (!newmark_.is_null())
      s["newmark"] = newmark_;
    else
      s["yield"] = yield_.admissible() ? circle_json(yield_) : nlohmann::json();
    return s;
  }
  std::vector<NamedTable> tables() const override {
    std::vector<NamedTable> t;
    if (critical_.admissible()) t.push_back({"bishop_circle", circle_table(critical_)});
    return t;
  }
  ParticleFields particles() const override { return {}; }
  void write_snapshot(SnapshotWriter&) const override {}
  void draw_due_pngs(const std::filesystem::path&) override {}
  void write_outputs(const std::filesystem::path& out) const override {
    for (const auto& [name, table] : tables()) write_text_file(out / (name + ".csv"), table.csv());
    write_text_file(out / "summary.json", summary().dump(2) + "\n");
    if (!quiet_) {
      if (critical_.admissible())
        std::fprintf(stderr, "sph-slope: Bishop factor of safety %.4g", critical_.factor);
      else
        std::fprintf(stderr, "sph-slope: %s", note_.c_str());
      if (!newmark_.is_null()) {
        const auto& ky = newmark_["yield_coefficient"];
        const auto& d = newmark_["displacement_m"];
        std::fprintf(stderr, ", k_y %.4g, Newmark displacement %s", ky.is_number() ? ky.get<double>() : 0.0,
                     d.is_number() ? (std::to_string(d.get<double>()) + " m").c_str() : "unbounded (k_y = 0)");
      }
      std::fprintf(stderr, "; outputs in %s\n", out.string().c_str());
    }
  }
  void write_partial(const std::filesystem::path&) const override {}

 private:
  const RunConfig& c_;
  bool quiet_;
  BishopResult critical_, yield_;
  nlohmann::json newmark_;
  std::string note_;
};

}  // namespace

// ---- The static Bishop check beside the dynamic run and the strength reduction (run_support.hpp)

namespace {

/// The limit-equilibrium section of a 2D slope or DSM-section scenario, at peak strength or with the
/// residual strengths of a softening soil, with the config's pore water; a slope with its seismic
/// coefficients.
SlopeSection section_of(const RunConfig& c, bool residual) {
  ProfileDomain d;
  if (c.scenario == ScenarioType::Slope) {
    d = c.slope.profile();
    apply_layers(d, c);
  } else {
    d = section_profile(c);
  }
  std::vector<LimitEquilibriumSoil> soils;
  for (std::size_t k = 0; k < c.materials.size(); ++k) {
    const auto& m = c.materials[k];
    const double sat = k < c.saturated_densities.size() ? c.saturated_densities[k] : 0.0;
    const auto [coh, phi] = shear_strength_of(c, m, residual);
    soils.push_back({m.density * c.numerics.gravity, coh, phi, sat * c.numerics.gravity});
  }
  auto s = SlopeSection::from_profile(d, soils);
  if (c.scenario == ScenarioType::Section) {
    s.water = c.water;  // r_u as given: on the cover's and the base's column (column_of)
    if (c.section.water_table || c.section.pore_pressure) {
      // The raster's table cut along the section, clipped to the ground as the SPH's.
      const auto cut = section_water_table(c);
      for (std::size_t k = 0; k < cut.size(); ++k)
        s.water.phreatic.push_back({cut[k][0], std::min(cut[k][1], c.section.profile[k].z)});
    } else if (c.rain.enabled) {
      const auto rain = rain_pore_pressure_on_profile(c);
      apply_rain(s.water, rain, rain->rain_time(0.0));
    }
  }
  if (c.scenario == ScenarioType::Slope) {
    // The pore water (clipped to the ground as the SPH's) and the pseudo-static coefficients of the
    // strength reduction (a dynamic run has none: its earthquake is the record).
    const auto le = limit_equilibrium_section(c, true);
    s.water = le.water;
    s.seismic = le.seismic;
  }
  return s;
}

}  // namespace

BishopResult bishop_of(const RunConfig& c, bool residual) {
  if (c.dimension != 2 || (c.scenario != ScenarioType::Slope && c.scenario != ScenarioType::Section)) return {};
  return bishop_critical_circle(section_of(c, residual));
}

StaticBishop StaticBishop::of(const RunConfig& c) {
  StaticBishop b;
  if (c.dimension != 2 || !has_shear_strength(c.model) ||
      (c.scenario != ScenarioType::Slope && c.scenario != ScenarioType::Section))
    return b;
  try {
    b.peak = bishop_of(c);
    if (std::holds_alternative<DruckerPragerSoftening>(c.model)) b.residual = bishop_of(c, true);
    if (c.scenario == ScenarioType::Section) b.cover = infinite_slope_minimum(section_of(c));
  } catch (const InputError& e) {
    b.note = e.reason();
  }
  return b;
}

nlohmann::json StaticBishop::circle_json(const BishopResult& r) {
  const auto& C = r.circle;
  return {{"factor", r.factor},   {"centre_x_m", C.xc},     {"centre_z_m", C.zc},
          {"radius_m", C.radius}, {"entry_x_m", r.x_entry}, {"exit_x_m", r.x_exit}};
}

void StaticBishop::add_to(nlohmann::json& s) const {
  if (!note.empty()) s["bishop_note"] = note;
  if (peak.admissible()) s["bishop"] = circle_json(peak);
  if (residual.admissible()) s["bishop_residual"] = circle_json(residual);
  if (std::isfinite(cover.factor))
    s["infinite_slope"] = {{"factor", cover.factor},
                           {"x_m", cover.x},
                           {"angle_deg", cover.angle * 180.0 / std::numbers::pi},
                           {"window_m", cover.window}};
}

namespace {

/// The rain block of summary.json: the rain and hydrology, the clock, and Bishop's factor with the
/// rain's pore pressure at the rain's time of the run's end t_end (s).
nlohmann::json rain_summary(const RunConfig& c, double t_end) {
  const auto& k = c.rain.infiltration;
  const auto rain = rain_pore_pressure_on_profile(c);
  nlohmann::json clock = nlohmann::json::array();
  for (const auto& p : c.rain.clock) clock.push_back({p[0], p[1]});
  nlohmann::json r = {{"intensity_m_per_s", k.rain.intensities},
                      {"step_s", k.rain.times.size() > 1 ? k.rain.times[1] - k.rain.times[0] : 0.0},
                      {"end_s", k.rain.end()},
                      {"depth_m", k.rain.depth_until(k.rain.end())},
                      {"conductivity_m_per_s", k.hydrology.conductivity},
                      {"diffusivity_m2_per_s", k.hydrology.diffusivity},
                      {"steady_infiltration_m_per_s", k.hydrology.steady_flux},
                      {"water_table_depth_m", k.water_table_depth},
                      {"clock_times_s", clock},
                      {"rain_time_at_start_s", rain->rain_time(0.0)},
                      {"rain_time_at_end_s", rain->rain_time(t_end)}};
  if (c.analysis != Analysis::Dynamic) r["evaluate_at_s"] = c.rain.evaluate_at;
  r["bishop_factor_at_end"] = nullptr;
  if (has_shear_strength(c.model) && c.dimension == 2) try {
      auto s = section_of(c);
      apply_rain(s.water, rain, rain->rain_time(t_end));
      r["bishop_factor_at_end"] = bishop_critical_circle(s).factor;
    } catch (const InputError&) {  // no admissible circle: null
    }
  return r;
}

}  // namespace

nlohmann::json water_summary(const RunConfig& c, double t_end) {
  const auto& w = c.water;
  nlohmann::json j = {{"phreatic_surface", w.phreatic.empty() ? nlohmann::json() : nlohmann::json(w.phreatic)},
                      {"ru", w.ru},
                      {"unit_weight_N_per_m3", w.unit_weight},
                      {"pore_pressure", w.head_loss_correction ? "head_loss_corrected" : "vertical_head"}};
  j["source"] =
      !c.pore_pressure_raster.empty() ? "pore_pressure_raster"
      : !c.water_table_raster.empty()
          ? "table_raster"
          : (c.rain.enabled ? "rain" : (!w.phreatic.empty() ? "phreatic_surface" : (w.ru > 0.0 ? "ru" : "none")));
  if (!c.water_table_raster.empty()) j["table_raster"] = c.water_table_raster;
  if (!c.pore_pressure_raster.empty()) j["pore_pressure_raster"] = c.pore_pressure_raster;
  if (!c.water_history_times.empty()) {
    j["history_times_s"] = c.water_history_times;
    j["history_offsets_m"] = c.water_history_offsets;
  }
  if (c.rain.enabled) j["rain"] = rain_summary(c, t_end);
  return j;
}

std::unique_ptr<SimulationModel> make_limit_equilibrium_run(const RunConfig& c, bool quiet) {
  return std::make_unique<LimitEquilibriumRun>(c, quiet);
}

}  // namespace geohaz::sph
