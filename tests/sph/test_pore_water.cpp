// SPH with prescribed pore water (solver.hpp PoreWaterSettings; docs/sph.md, "Pore pressure and
// seismic coefficients"; label: regression): the effective stress of a saturated deposit is that of
// its buoyant weight, a saturated slope with a hydrostatic pore pressure stays at rest, and a water
// table rising in a marginal slope (the loading history) fails it at the level Bishop predicts.
// The slope of data/sph/slope_water_newmark.toml (H = 10 m at 2H:1V on a 5 m base, c′ = 5 kPa,
// φ′ = 25°) at 1 m spacing (675 particles): a few seconds per run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/limit_equilibrium.hpp"
#include "geohaz/sph/pore_pressure.hpp"
#include "geohaz/sph/run.hpp"

namespace {

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::sph;

constexpr double kG = 9.81, kRho = 2038.74, kRhoSat = 2140.67, kRhoW = 1000.0;

RunConfig slope_config(const std::vector<std::string>& more) {
  ConfigReader r = ConfigReader::from_file(fs::path(GEOHAZ_SOURCE_DIR) / "data/sph/slope_water_newmark.toml");
  for (const char* o :
       {"run.analysis=dynamic", "earthquake.type=none", "numerics.spacing=1.0", "run.output_interval=0.25",
        "run.snapshot_interval=0", "numerics.damping=0.7", "geostatic.elastic=false", "material[0].cohesion=5000"})
    r.apply_override(o);
  for (const auto& o : more) r.apply_override(o);
  RunConfig c = read_config(r, false);
  r.finish();
  c.resolved_config = r.resolved();
  validate(c);
  return c;
}

/// The particles at the start of the main phase (after the geostatic phase).
struct AtStart : RunObserver {
  ParticleFields fields;
  void started(const SphSimulation& s) override { fields = s.particles(); }
};

/// Column `name` of the series table.
std::vector<double> series(const SphSimulation& sim, const std::string& name) {
  for (const auto& t : sim.tables())
    if (t.name == "series") {
      const auto& cols = t.table.columns;
      const auto k = static_cast<std::size_t>(std::find(cols.begin(), cols.end(), name) - cols.begin());
      std::vector<double> v;
      for (const auto& row : t.table.rows) v.push_back(row.at(k));
      return v;
    }
  return {};
}

/// Mean of σ_zz / (−γ′ d) over the soil particles under the level ground in front of the toe
/// (50 < x < 60 m, depth d = 5 − z > 1.5 m), γ′ the unit weight that should carry the stress.
double vertical_stress_ratio(const ParticleFields& f, double gamma) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < f.count; ++i) {
    const double x = f.position[2 * i], z = f.position[2 * i + 1], d = 5.0 - z;
    if (f.kind[i] != 0 || x < 50.0 || x > 60.0 || d < 1.5) continue;
    sum += f.stress[9 * i + 4] / (-gamma * d);  // σ_zz: the vertical axis of the 2D section is the 2nd
    ++n;
  }
  return n ? sum / n : 0.0;
}

// A deposit saturated to its surface (the table at the level ground in front of the toe, z = 5 m)
// carries the effective stress of its buoyant weight, σ′_zz = −(γ_sat − γ_w) d, where the dry one
// carries −γ d: the two ratios agree within 2 % (both share the discretisation of the surface row).
// And the saturated slope stays at rest: with the table at the toe level and at 14 m (1 m under the
// crest, drawn down the face), the largest displacement and speed of the main phase stay at the dry
// slope's settling (millimetres, mm/s), far from the rest speed 0.01 √(gH) ≈ 0.1 m/s.
TEST(SphPoreWater, SaturatedSlopeCarriesBuoyantEffectiveStressAndStaysAtRest) {
  auto run = [](const std::vector<std::string>& more, AtStart& obs) {
    RunConfig c = slope_config(more);
    SphSimulation sim(c);
    sim.run(&obs);
    return std::pair{series(sim, "max_displacement_m"), series(sim, "max_speed_m_per_s")};
  };
  AtStart dry_obs, wet_obs, high_obs;
  // A strong soil (c′ = 50 kPa: Bishop's F stays above 1.5 with the table 1 m under the crest).
  const auto dry = run({"water.phreatic=[]", "run.end_time=1.0", "material[0].cohesion=50000"}, dry_obs);
  const auto wet = run({"water.phreatic=[0,5,65,5]", "run.end_time=1.0", "material[0].cohesion=50000"}, wet_obs);
  const auto high = run({"water.phreatic=[0,14,65,14]", "run.end_time=1.0", "material[0].cohesion=50000"}, high_obs);
  const double r_dry = vertical_stress_ratio(dry_obs.fields, kRho * kG);
  const double r_wet = vertical_stress_ratio(wet_obs.fields, (kRhoSat - kRhoW) * kG);
  std::printf("sigma'_zz / (-gamma' d): dry %.4f, saturated %.4f\n", r_dry, r_wet);
  EXPECT_NEAR(r_dry, 1.0, 0.1);
  EXPECT_NEAR(r_wet, r_dry, 0.02 * r_dry);
  for (const auto* s : {&wet, &high}) {
    const double umax = *std::max_element(s->first.begin(), s->first.end());
    const double vmax = *std::max_element(s->second.begin(), s->second.end());
    std::printf("main phase: max displacement %.4g m, max speed %.4g m/s\n", umax, vmax);
    EXPECT_LT(umax, 0.01);
    EXPECT_LT(vmax, 0.01);
  }
}

// A pore-pressure ratio r_u = 0.3 (u = r_u times the overburden stress at every particle): under the
// level ground in front of the toe the total vertical stress is still the weight, so the effective
// stress carries the rest, σ′_zz = −(1 − r_u) γ d. The ratio to it agrees with the dry deposit's ratio
// to −γ d within 2 % (as the saturated deposit above: both share the surface row's discretisation).
TEST(SphPoreWater, DepositUnderPorePressureRatioCarriesTheReducedEffectiveStress) {
  auto start = [](const std::vector<std::string>& more) {
    RunConfig c = slope_config(more);
    SphSimulation sim(c);
    AtStart obs;
    sim.run(&obs);
    return obs.fields;
  };
  const double ru = 0.3;
  const auto dry = start({"water.phreatic=[]", "run.end_time=0.05", "material[0].cohesion=50000"});
  const auto wet = start({"water.phreatic=[]", "water.ru=0.3", "run.end_time=0.05", "material[0].cohesion=50000"});
  const double r_dry = vertical_stress_ratio(dry, kRho * kG);
  const double r_ru = vertical_stress_ratio(wet, (1.0 - ru) * kRho * kG);
  std::printf("sigma'_zz / (-gamma' d): dry %.4f, r_u = 0.3 %.4f\n", r_dry, r_ru);
  EXPECT_NEAR(r_dry, 1.0, 0.1);
  EXPECT_NEAR(r_ru, r_dry, 0.02 * r_dry);
}

/// The level L (m, elevation) of a horizontal water table, drawn down the face and clipped to the
/// ground as the SPH's, at which Bishop's critical factor is 1 (bisection to 1 cm).
double bishop_failure_level() {
  SlopeGeometry g;
  g.height = 10.0;
  g.gradient = 2.0;
  g.crest_length = 25.0;
  g.front_length = 20.0;
  g.base_thickness = 5.0;
  auto s = SlopeSection::from_profile(g.profile(), {{kRho * kG, 5000.0, 25.0 * std::numbers::pi / 180.0}});
  s.water.unit_weight = kRhoW * kG;
  auto factor = [&](double L) {
    s.water.phreatic.clear();
    for (int k = 0; k <= 650; ++k) {
      const double x = 0.1 * k;
      s.water.phreatic.push_back({x, std::min(L, surface_at(s.surface, x))});
    }
    return bishop_critical_circle(s).factor;
  };
  double lo = 5.0, hi = 15.0;  // F(5) > 1 > F(15)
  while (hi - lo > 0.01) {
    const double mid = 0.5 * (lo + hi);
    (factor(mid) > 1.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// A marginal slope (dry F = 1.35) with its water table rising from the toe level (z = 5 m) at 1 m/s·…
// (the history water.history_*: to the level L over 5 s, then held 5 s): at L = 0.95 L* it comes to
// rest again (its displacement grew by less than 5 % over the last quarter, the strength reduction's
// criterion), at 1.05 L* it fails (grew by more, or ended beyond 5× the stable trial's: the knee
// criterion), L* Bishop's level of F = 1 with the same clipped table. 5 % of the level, as the issue asks.
TEST(SphPoreWater, RisingWaterTableFailsTheSlopeAtBishopsLevel) {
  const double Ls = bishop_failure_level();
  std::printf("Bishop: F = 1 at water level %.3f m\n", Ls);
  ASSERT_GT(Ls, 8.0);
  ASSERT_LT(Ls, 11.0);
  auto trial = [](double L) {
    RunConfig c =
        slope_config({"water.phreatic=[0,5,65,5]", "material[0].saturated_density=0", "run.end_time=10",
                      "water.history_times=[0,5]", "water.history_offsets=[0," + std::to_string(L - 5.0) + "]"});
    SphSimulation sim(c);
    sim.run();
    const auto t = series(sim, "time_s"), u = series(sim, "max_displacement_m");
    double u75 = 0.0;
    for (std::size_t k = 0; k < t.size(); ++k)
      if (t[k] <= 7.5 + 1e-9) u75 = u[k];
    std::printf("level %.3f m: displacement %.4g m at 7.5 s, %.4g m at 10 s\n", L, u75, u.back());
    return std::pair{u75, u.back()};
  };
  const auto [s75, s100] = trial(0.95 * Ls);
  EXPECT_LT(s100 - s75, 0.05 * s100);  // converged: stable
  const auto [f75, f100] = trial(1.05 * Ls);
  EXPECT_TRUE(f100 - f75 > 0.05 * f100 || f100 > 5.0 * s100) << f75 << " " << f100;
}

/// The rain of the rain tests: 36 mm/h (= K_s: all of it infiltrates) for 12 h on a soil of
/// D_0 = 1e-3 m²/s with the initial water table 6 m below the ground (keys of slope-stability).
const std::vector<std::string> kRain = {"rain.enabled=true",
                                        "water.phreatic=[]",
                                        "hydrology.conductivity=1e-5",
                                        "hydrology.diffusivity=1e-3",
                                        "hydrology.water_table_depth=6",
                                        "rain.step=43200",
                                        "rain.intensity=[1e-5]",
                                        "material[0].saturated_density=0"};

/// The rain time t_B (s) at which Bishop's critical factor with the rain's pore pressure reaches 1
/// (bisection to 10 s between 0 and 12 h; F(0) > 1 > F(12 h)).
double bishop_failure_rain_time() {
  SlopeGeometry g;
  g.height = 10.0;
  g.gradient = 2.0;
  g.crest_length = 25.0;
  g.front_length = 20.0;
  g.base_thickness = 5.0;
  auto s = SlopeSection::from_profile(g.profile(), {{kRho * kG, 5000.0, 25.0 * std::numbers::pi / 180.0}});
  InfiltrationParameters p;
  p.conductivity = 1e-5;
  p.diffusivity = 1e-3;
  const RainPorePressure rain(p, RainfallHistory::uniform_steps(43200.0, {1e-5}), g.profile().surface, 6.0, {});
  auto factor = [&](double t) {
    s.water.pressure_field = [&](double x, double z) { return kRhoW * kG * std::max(rain.head(x, z, t), 0.0); };
    return bishop_critical_circle(s).factor;
  };
  double lo = 0.0, hi = 43200.0;
  EXPECT_GT(factor(lo), 1.0);
  EXPECT_LT(factor(hi), 1.0);
  while (hi - lo > 10.0) {
    const double mid = 0.5 * (lo + hi);
    (factor(mid) > 1.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Rain as a loading history: the marginal slope (dry F = 1.35) stands under the initial water table
// and fails when the rain-driven pressure head passes the level at which Bishop's factor with the
// same pore pressure is 1. The rain's clock runs the rain to a rain time t over the first 5 s of the
// main phase and holds it for 5 s (rain.clock_times = [0, 0, 5, t]): at t = 0.95 t_B the slope comes
// to rest again (its displacement grew by less than 5 % over the last quarter), at 1.05 t_B it fails
// (grew by more, or ended beyond 5x the stable run's). 5 % of the time (about 0.035 in Bishop's F
// here, where F falls by 0.1 per hour of rain), as the issue asks.
TEST(SphPoreWater, RainFailsTheSlopeAtBishopsTime) {
  const double tb = bishop_failure_rain_time();
  std::printf("Bishop: F = 1 after %.0f s (%.2f h) of rain\n", tb, tb / 3600.0);
  ASSERT_GT(tb, 3600.0);
  ASSERT_LT(tb, 36000.0);
  auto trial = [](double t) {
    auto sets = kRain;
    sets.push_back("run.end_time=10");
    sets.push_back("rain.clock_times=[0,0,5," + std::to_string(t) + "]");
    RunConfig c = slope_config(sets);
    SphSimulation sim(c);
    sim.run();
    const auto time = series(sim, "time_s"), u = series(sim, "max_displacement_m");
    double u75 = 0.0;
    for (std::size_t k = 0; k < time.size(); ++k)
      if (time[k] <= 7.5 + 1e-9) u75 = u[k];
    std::printf("rain time %.0f s: displacement %.4g m at 7.5 s, %.4g m at 10 s (rain time %.0f s)\n", t, u75, u.back(),
                series(sim, "rain_time_s").back());
    return std::pair{u75, u.back()};
  };
  const auto [s75, s100] = trial(0.95 * tb);
  EXPECT_LT(s100 - s75, 0.05 * s100);  // converged: stable
  const auto [f75, f100] = trial(1.05 * tb);
  EXPECT_TRUE(f100 - f75 > 0.05 * f100 || f100 > 5.0 * s100) << f75 << " " << f100;
}

}  // namespace
