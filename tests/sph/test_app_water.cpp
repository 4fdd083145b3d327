// Regression tests of sph-slope's pore water and seismic coefficients (label: regression; docs/sph.md,
// "Pore pressure and seismic coefficients"): run.analysis = limit_equilibrium with [water], [seismic]
// and an [earthquake] (Newmark), the Newmark report beside a dynamic SPH run, the strength reduction
// with a horizontal seismic coefficient against Bishop, and bad water input exiting with 2 naming the
// key and writing nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/sph/loading.hpp"
#include "geohaz/sph/newmark.hpp"
#include "geohaz/sph/summary_keys.hpp"
#include "run_command.hpp"
#include "summary_keys_check.hpp"

namespace {

namespace fs = std::filesystem;
const fs::path kApp = fs::path(GEOHAZ_BINARY_DIR) / "apps/sph-slope/sph-slope";
const fs::path kData = fs::path(GEOHAZ_SOURCE_DIR) / "data/sph";
const fs::path kWork = fs::path(GEOHAZ_BINARY_DIR) / "tests/sph/app_water_runs";

struct Result {
  int code;
  std::string err;
};

Result run(const std::string& args, const std::string& name) {
  fs::create_directories(kWork);
  const auto r = geohaz::testing::run_command(kApp.string() + " " + args + " --threads 1");
  std::ofstream(kWork / (name + ".log")) << r.output;  // kept for inspection after a failure
  return {r.code, r.output};
}

/// The run's summary.json, every number of which must have a declared label and unit (issue #33).
nlohmann::json summary(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::sph::summary_keys());
  return j;
}

const std::string kAcads = (kData / "acads_1a_srm.toml").string();
const std::string kWater = (kData / "slope_water_newmark.toml").string();

// ACADS 1(a) by limit equilibrium alone: Bishop's 0.985 (the unit tests' value, the same section), no
// particles (no snapshots); r_u = 0.25 and a water table lower it, k_h = 0.1 lowers it more.
TEST(SphSlopeWater, LimitEquilibriumAnalysisOfAcadsWithWaterAndSeismicCoefficient) {
  const fs::path out = kWork / "le_acads";
  auto factor = [&](const std::string& sets) {
    fs::remove_all(out);
    const auto r = run(
        "--config " + kAcads + " --out " + out.string() + " --set run.analysis=limit_equilibrium " + sets + " --quiet",
        "le_acads");
    EXPECT_EQ(r.code, 0) << r.err;
    return summary(out)["factor_of_safety"].get<double>();
  };
  const double dry = factor("");
  EXPECT_NEAR(dry, 0.985, 0.002);
  for (const char* f : {"summary.json", "bishop_circle.csv", "config.resolved.toml"}) EXPECT_TRUE(fs::exists(out / f));
  EXPECT_FALSE(fs::exists(out / "snapshots.h5"));
  const double ru = factor("--set water.ru=0.25");
  const double table = factor("--set water.phreatic=[0,12,25,11,45,5,65,5]");
  const double kh = factor("--set seismic.kh=0.1");
  EXPECT_LT(ru, dry);
  EXPECT_LT(table, dry);
  EXPECT_LT(kh, dry);
}

// The example with a water table and a sine: F > 1, a yield coefficient in (0, 1), and the Newmark
// displacement of the report equal to the library's for the reported k_y and the same record (the
// plumbing; the closed forms are in test_newmark.cpp).
TEST(SphSlopeWater, ExampleReportsYieldCoefficientAndNewmarkDisplacement) {
  const fs::path out = kWork / "le_example";
  fs::remove_all(out);
  const auto r = run("--config " + kWater + " --out " + out.string() + " --quiet", "le_example");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(out);
  EXPECT_GT(s["factor_of_safety"].get<double>(), 1.0);
  const auto& n = s["newmark"];
  const double ky = n["yield_coefficient"].get<double>();
  EXPECT_GT(ky, 0.0);
  EXPECT_LT(ky, 3.0 / 9.81);  // the sine's peak exceeds the yield acceleration: the block slides
  EXPECT_LE(ky, s["bishop"]["yield_coefficient"].get<double>() + 1e-9);  // the smallest k_y
  const auto quake = geohaz::sph::EarthquakeLoading::sine(3.0, 1.0, 0.0, 3.0, 0.0);
  const auto lib = geohaz::sph::newmark_displacement(quake, ky * 9.81, n["direction"].get<int>(), 6.0, 1e-3);
  EXPECT_GT(lib.displacement, 0.0);
  EXPECT_NEAR(n["displacement_m"].get<double>(), lib.displacement, 1e-9);
  EXPECT_EQ(n["episodes"].get<int>(), 3);
}

// A dynamic SPH run with an earthquake on a 2D slope reports the Newmark block beside it (k_y = 0,
// a slope failing without shaking, gives a null displacement: the block never stops).
TEST(SphSlopeWater, DynamicRunWithEarthquakeReportsNewmarkBesideSph) {
  const fs::path out = kWork / "dynamic_newmark";
  fs::remove_all(out);
  const auto r = run("--config " + (kData / "slope_2d_granular.toml").string() + " --out " + out.string() +
                         " --set numerics.spacing=0.025 --set run.end_time=0.1 --set earthquake.type=sine"
                         " --set earthquake.amplitude=8 --set earthquake.frequency=5 --set earthquake.duration=0.1 "
                         "--set earthquake.ramp=0"
                         " --set material[0].cohesion=1000 --quiet",
                     "dynamic_newmark");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(out);
  ASSERT_TRUE(s.contains("newmark")) << s.dump(2);
  // With c = 1 kPa the 0.25 m slope stands (k_y = 0.54) and the 8 m/s² half-sine (5 Hz) exceeds k_y g.
  EXPECT_GT(s["newmark"]["yield_coefficient"].get<double>(), 0.0);
  EXPECT_GT(s["newmark"]["displacement_m"].get<double>(), 0.0);
  EXPECT_EQ(s["newmark"]["sph_max_displacement_m"].get<double>(), s["max_displacement_m"].get<double>());
}

// Strength reduction with k_h = 0.1 on ACADS 1(a) at Δx = 1 m, bracket [0.6, 1.0], ΔF = 0.04: within
// 5 % of Bishop with the same k_h (0.790). About 10 s on one thread.
TEST(SphSlopeWater, StrengthReductionWithSeismicCoefficientAgreesWithBishop) {
  const fs::path out = kWork / "srm_kh";
  fs::remove_all(out);
  const auto r = run("--config " + kAcads + " --out " + out.string() +
                         " --set numerics.spacing=1.0 --set strength_reduction.f_min=0.6"
                         " --set strength_reduction.f_max=1.0 --set strength_reduction.tolerance=0.04"
                         " --set seismic.kh=0.1 --quiet",
                     "srm_kh");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(out);
  EXPECT_EQ(s["outcome"], "bracketed");
  const double F = s["factor_of_safety"].get<double>(), Fb = s["bishop"]["factor"].get<double>();
  EXPECT_NEAR(Fb, 0.790, 0.005);
  EXPECT_NEAR(F, Fb, 0.05 * Fb);
  EXPECT_EQ(s["seismic"]["kh"].get<double>(), 0.1);
}

// Strength reduction with a water table (z = 8 m under the crest, drawn down the face, clipped to the
// ground) on the example's slope with c′ = 5 kPa at Δx = 1 m, bracket [0.9, 1.3], ΔF = 0.04: the SPH
// trials carry the pore pressure, Bishop beside them the same clipped table (1.123); within 5 %.
// About 12 s on one thread.
TEST(SphSlopeWater, StrengthReductionWithWaterTableAgreesWithBishop) {
  const fs::path out = kWork / "srm_water";
  fs::remove_all(out);
  const auto r = run("--config " + kWater + " --out " + out.string() +
                         " --set run.analysis=strength_reduction --set earthquake.type=none"
                         " --set numerics.spacing=1.0 --set material[0].cohesion=5000"
                         " --set water.phreatic=[0,8,65,8] --set strength_reduction.f_min=0.9"
                         " --set strength_reduction.f_max=1.3 --set strength_reduction.tolerance=0.04 --quiet",
                     "srm_water");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(out);
  EXPECT_EQ(s["outcome"], "bracketed");
  const double F = s["factor_of_safety"].get<double>(), Fb = s["bishop"]["factor"].get<double>();
  EXPECT_NEAR(Fb, 1.123, 0.005);
  EXPECT_NEAR(F, Fb, 0.05 * Fb);
}

// Strength reduction with a pore-pressure ratio r_u = 0.25 (u = r_u times the overburden stress at every
// particle, the same key as Bishop's) on the example's slope with c′ = 5 kPa at Δx = 1 m: Bishop with the
// same r_u gives 1.033, and the bracket [0.98, 1.08] is its ±5 % (−5.1 %, +4.5 %): the outcome
// "bracketed" (f_min stable, f_max failed) puts F within it (1.030), three trials (ΔF = 0.05). About
// 5 s on one thread.
TEST(SphSlopeWater, StrengthReductionWithPorePressureRatioAgreesWithBishop) {
  const fs::path out = kWork / "srm_ru";
  fs::remove_all(out);
  const auto r = run("--config " + kWater + " --out " + out.string() +
                         " --set run.analysis=strength_reduction --set earthquake.type=none"
                         " --set numerics.spacing=1.0 --set material[0].cohesion=5000"
                         " --set water.phreatic=[] --set water.ru=0.25 --set strength_reduction.f_min=0.98"
                         " --set strength_reduction.f_max=1.08 --set strength_reduction.tolerance=0.05 --quiet",
                     "srm_ru");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(out);
  EXPECT_EQ(s["outcome"], "bracketed");
  const double F = s["factor_of_safety"].get<double>(), Fb = s["bishop"]["factor"].get<double>();
  std::printf("r_u = 0.25: strength reduction %.4f, Bishop %.4f\n", F, Fb);
  EXPECT_NEAR(Fb, 1.033, 0.002);
  EXPECT_NEAR(F, Fb, 0.05 * Fb);
}

// The rain example (data/sph/slope_rain.toml) shrunk: the 12 h of rain in 2 s of a 3 s main phase.
// The summary reports the rain, its clock and the largest pore pressure (the deepest particle under
// the crest, 14.5 m below the ground with the table at 6 m: ψ ≥ 8.5 m, 83 kPa at the start), the
// series the rain's time; Bishop's factor falls from the dry slope's (the initial table lies below
// its circle) to below 1 at the rain's end, and the slope moves (more than 10 cm). About 4 s.
TEST(SphSlopeWater, RainExampleReportsTheRainItsClockAndPorePressure) {
  const fs::path out = kWork / "rain_example";
  fs::remove_all(out);
  const auto r = run("--config " + (kData / "slope_rain.toml").string() + " --out " + out.string() +
                         " --set run.end_time=3 --set rain.clock_times=[0,0,2,43200] --set run.snapshot_interval=0"
                         " --quiet",
                     "rain_example");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(out);
  const auto& w = s["water"];
  EXPECT_EQ(w["source"], "rain");
  EXPECT_EQ(w["rain"]["rain_time_at_end_s"].get<double>(), 43200.0);
  EXPECT_EQ(w["rain"]["water_table_depth_m"].get<double>(), 6.0);
  EXPECT_NEAR(w["rain"]["depth_m"].get<double>(), 0.432, 1e-12);  // 36 mm/h for 12 h
  EXPECT_GT(w["max_pore_pressure_Pa"].get<double>(), 1000.0 * 9.81 * 8.5);
  EXPECT_GT(s["bishop"]["factor"].get<double>(), 1.3);
  EXPECT_LT(w["rain"]["bishop_factor_at_end"].get<double>(), 1.0);
  EXPECT_GT(s["max_displacement_m"].get<double>(), 0.1);
  std::ifstream series(out / "series.csv");
  std::string header;
  std::getline(series, header);
  EXPECT_NE(header.find("max_pore_pressure_Pa"), std::string::npos) << header;
  EXPECT_NE(header.find("rain_time_s"), std::string::npos) << header;
}

// Bad water input: exit 2 naming the key, nothing written.
TEST(SphSlopeWater, BadWaterInputExitsTwoNamingTheKey) {
  const fs::path out = kWork / "bad_water";
  for (const auto& [sets, key] : std::vector<std::pair<std::string, std::string>>{
           {"water.ru=1.0", "water.ru"},
           {"water.ru=-0.1", "water.ru"},
           {"water.phreatic=[0,20,65,20]", "water.phreatic"},                     // above the ground everywhere
           {"water.phreatic=[0,12,25]", "water.phreatic"},                        // not pairs
           {"water.phreatic=[30,12,25,11]", "water.phreatic"},                    // x decreasing
           {"material[0].saturated_density=1900", "material.saturated_density"},  // below the density
           {"water.ru=0.2 --set water.phreatic=[0,12,65,5]", "water.ru"},         // both
           {"run.dimension=3 --set water.phreatic=[] --set water.ru=0.2", "run.scenario"},  // Bishop: 2D slope
           {"water.history_times=[0,5]", "water.history_offsets"},                          // lengths differ
           {"run.analysis=dynamic --set water.phreatic=[] --set seismic.kh=0.1", "seismic.kh"},
           {"run.analysis=dynamic --set rain.enabled=true", "rain.enabled"},  // and a phreatic surface
           {"run.analysis=dynamic --set water.phreatic=[] --set rain.enabled=true --set rain.clock_times=[0,0,5]",
            "rain.clock_times"},  // not pairs
           {"run.analysis=dynamic --set water.phreatic=[] --set rain.enabled=true --set "
            "rain.clock_times=[0,0,5,10,4,20]",
            "rain.clock_times"},  // the run's time decreasing
           {"hydrology.conductivity=-1e-5", "hydrology.conductivity"},
           {"hydrology.steady_infiltration=2e-5", "hydrology.steady_infiltration"},  // above K_s
           {"run.analysis=dynamic --set water.phreatic=[] --set rain.enabled=true --set "
            "hydrology.steady_infiltration=9e-6",
            "hydrology.steady_infiltration"}}) {  // above K_s cos^2 of the face (0.8 K_s)
    fs::remove_all(out);
    const auto r = run("--config " + kWater + " --out " + out.string() + " --set " + sets, "bad_water");
    EXPECT_EQ(r.code, 2) << sets << ": " << r.err;
    EXPECT_NE(r.err.find(key), std::string::npos) << sets << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << sets;
  }
}

}  // namespace
