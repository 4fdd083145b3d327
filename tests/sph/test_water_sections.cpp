// Pore water beyond the 2D slope (issue #32; docs/sph.md, "Pore pressure and seismic coefficients";
// label: regression): rain and r_u on DSM sections (2D section, 3D strip) and on the 3D slope, the
// pore-pressure raster (water.pore_pressure_raster), rain in the strength reduction and in Bishop's
// method at rain.evaluate_at, the pore pressure in the snapshots, and the DSM section's infinite-slope
// check with water.
//
// The sections are cut from a small synthetic DSM: a plane falling 0.5 m per m eastwards (26.6°), in
// UTM 54N; bilinear sampling reproduces a plane exactly, so the field at the particles can be checked
// against the closed form to round-off. The whole body is clamped (clamp.boxes): the particles never
// move, and u, evaluated at the positions of the step, is that of the positions reported.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/infiltration.hpp"
#include "geohaz/sph/run.hpp"
#include "geohaz/sph/summary_keys.hpp"
#include "run_command.hpp"
#include "summary_keys_check.hpp"
#include "utm_crs.hpp"

namespace {

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::sph;

const fs::path kApp = fs::path(GEOHAZ_BINARY_DIR) / "apps/sph-slope/sph-slope";
const fs::path kData = fs::path(GEOHAZ_SOURCE_DIR) / "data/sph";
// One folder per process: ctest runs the cases of this file in parallel, each writing its rasters.
const fs::path kWork =
    fs::path(GEOHAZ_BINARY_DIR) / "tests/sph" / ("water_sections_runs_" + std::to_string(::getpid()));
constexpr double kX0 = 500000.0, kY0 = 4000000.0;  // the DSM's north-west corner (UTM 54N)
constexpr double kG = 9.81, kGammaW = 1000.0 * kG;
const double kSlope = std::atan(0.5);  // the plane's inclination (rad)

std::string utm(int zone) {
  return geohaz::testing::utm_wkt(zone);
}

/// The ground: a plane falling 0.5 m per m eastwards from 60 m, 120 m × 40 m at 2 m cells.
double ground(double x, double /*y*/) {
  return 60.0 - 0.5 * (x - kX0);
}
/// The pore pressure at the base of the 3 m cover: 2 m of head at the strip's middle line, rising by
/// 0.1 m of head per m northwards (Pa).
double base_pressure(double /*x*/, double y) {
  return kGammaW * (2.0 + 0.1 * (y - (kY0 - 20.0)));
}

fs::path write_raster(const std::string& name, const std::function<double(double, double)>& f, int zone = 54,
                      int nx = 60) {
  Raster r;
  r.nx = nx;
  r.ny = 20;
  r.geotransform = {kX0, 2.0, 0.0, kY0, 0.0, -2.0};
  r.crs_wkt = utm(zone);
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) r.data.push_back(f(kX0 + 2.0 * (col + 0.5), kY0 - 2.0 * (row + 0.5)));
  fs::create_directories(kWork);
  const fs::path p = kWork / name;
  write_geotiff(p, r, true);
  return p;
}

/// A section along the strip's middle line from 10 m to 90 m east: a 3 m cover (1900 kg/m³, saturated
/// 2000) over 2 m of base (2200) on bedrock, 1 m spacing, every particle clamped, a short geostatic
/// phase (the field is evaluated in every step, gravity at its full value at its end).
std::string section_toml(int dimension) {
  const fs::path dsm = write_raster("dsm.tif", ground);
  return "[run]\ndimension = " + std::to_string(dimension) +
         "\nscenario = \"section\"\nend_time = 0.001\nsnapshot_interval = 0.0\n"
         "[geostatic]\nduration = 0.02\n"
         "[[material]]\nname = \"base\"\ndensity = 2200.0\nyoung = 50e6\npoisson = 0.25\ncohesion = 200e3\n"
         "friction = 40.0\n"
         "[[material]]\nname = \"cover\"\ndensity = 1900.0\nsaturated_density = 2000.0\nyoung = 20e6\n"
         "poisson = 0.3\ncohesion = 5e3\nfriction = 30.0\n"
         "[numerics]\nspacing = 1.0\n"
         "[clamp]\nboxes = " +
         std::string(dimension == 3 ? "[-10, -10, -100, 200, 20, 200]" : "[-10, -100, 200, 200]") +
         "\n[section]\ndsm = \"" + dsm.string() +
         "\"\npolyline = [500010.0, 3999980.0, 500090.0, 3999980.0]\nsoil_thickness = 3.0\nbase_thickness = 2.0\n" +
         (dimension == 3 ? "[geometry]\nwidth = 6.0\n" : "");
}

/// Rain of 36 mm/h for an hour and 18 mm/h for another on K_s = 10⁻⁵ m/s, D₀ = 10⁻⁴ m²/s, the table
/// 1.5 m deep, held at the rain's time 1.5 h (in the dynamic run by the clock, else rain.evaluate_at).
const std::vector<std::string> kRain = {"rain.enabled=true",
                                        "rain.step=3600",
                                        "rain.intensity=[1e-5, 5e-6]",
                                        "hydrology.conductivity=1e-5",
                                        "hydrology.diffusivity=1e-4",
                                        "hydrology.water_table_depth=1.5",
                                        "rain.clock_times=[0, 5400, 1, 5400]",
                                        "rain.evaluate_at=5400"};

InfiltrationHistory rain_history() {
  InfiltrationParameters p;
  p.conductivity = 1e-5;
  p.diffusivity = 1e-4;
  return InfiltrationHistory(p, RainfallHistory::uniform_steps(3600.0, {1e-5, 5e-6}));
}

RunConfig config_of(const std::string& toml, const std::vector<std::string>& sets) {
  ConfigReader r = ConfigReader::from_string(toml);
  for (const auto& s : sets) r.apply_override(s);
  RunConfig c = read_config(r, false);
  r.finish();
  validate(c);
  return c;
}

struct AtStart : RunObserver {
  ParticleFields fields;
  void started(const SphSimulation& s) override { fields = s.particles(); }
};

/// Every soil particle's u at the start of the main phase against expected(x, y, z) (map position of
/// the section point, elevation): the largest difference and the largest u (Pa), and the summary.
struct Check {
  double error = 0.0, umax = 0.0;
  std::size_t soil = 0;
  nlohmann::json summary;
};

Check run_section(int dimension, const std::vector<std::string>& sets,
                  const std::function<double(double, double, double)>& expected) {
  const RunConfig c = config_of(section_toml(dimension), sets);  // the simulation keeps a reference
  SphSimulation sim(c);
  AtStart obs;
  sim.run(&obs);
  Check k;
  const auto& f = obs.fields;
  for (std::size_t i = 0; i < f.count; ++i) {
    if (f.kind[i] != 0) continue;
    const double s = f.position[dimension * i], z = f.position[dimension * i + dimension - 1];
    const double t = dimension == 3 ? f.position[dimension * i + 1] - 3.0 : 0.0;  // 6 m strip: left = north
    const double e = expected(500010.0 + s, 3999980.0 + t, z);
    k.error = std::max(k.error, std::abs(f.pore_pressure[i] - e));
    k.umax = std::max(k.umax, f.pore_pressure[i]);
    ++k.soil;
  }
  k.summary = nlohmann::json::parse(sim.summary_json());
  EXPECT_SUMMARY_KEYS_DECLARED(k.summary, geohaz::sph::summary_keys());
  return k;
}

/// Iverson's pressure head at the point's vertical depth below the plane, at the rain's time 1.5 h.
double rain_u(double x, double y, double z) {
  static const InfiltrationHistory h = rain_history();
  const double Z = ground(x, y) - z;
  return Z > 0.0 ? kGammaW * std::max(h.pressure_head(Z, 5400.0, kSlope, 1.5), 0.0) : 0.0;
}

/// r_u = 0.3 times the overburden of the 3 m cover (1900 kg/m³) and the base (2200 kg/m³) below it.
double ru_u(double x, double y, double z) {
  const double Z = std::max(ground(x, y) - z, 0.0);
  return 0.3 * kG * (1900.0 * std::min(Z, 3.0) + 2200.0 * std::max(Z - 3.0, 0.0));
}

// Rain on a 2D DSM section and on a 3D strip: every soil particle takes γ_w max(ψ, 0) with Iverson's ψ
// (infiltration.hpp InfiltrationHistory, itself checked against the analytic solution in
// stability_infiltration) at its vertical depth below the plane, δ the plane's 26.6°, to round-off
// (measured: 0 Pa in 2D and 3D, of up to 23.5 kPa).
TEST(SphWaterSections, RainOnDsmSectionsGivesEachParticleIversonsHead) {
  for (int dim : {2, 3}) {
    const auto k = run_section(dim, kRain, rain_u);
    std::printf("rain %dD: %zu soil particles, max |u - Iverson| %.3g Pa, max u %.4g Pa\n", dim, k.soil, k.error,
                k.umax);
    EXPECT_LT(k.error, 1e-9 * k.umax) << dim;
    EXPECT_GT(k.umax, kGammaW * 2.0) << dim;
    EXPECT_EQ(k.summary["water"]["source"], "rain") << dim;
  }
}

// r_u on a 2D DSM section and a 3D strip: u = r_u g ∫ρ dz over the cover and the base above the point,
// to round-off.
TEST(SphWaterSections, PorePressureRatioOnDsmSectionsGivesEachParticleItsOverburden) {
  for (int dim : {2, 3}) {
    const auto k = run_section(dim, {"water.ru=0.3"}, ru_u);
    std::printf("r_u %dD: max |u - r_u sigma_v| %.3g Pa, max u %.4g Pa\n", dim, k.error, k.umax);
    EXPECT_LT(k.error, 1e-9 * k.umax) << dim;
    EXPECT_GT(k.umax, 0.3 * kG * (1900.0 * 3.0 + 2200.0 * 1.0)) << dim;  // the deepest 4.5 m down
    EXPECT_EQ(k.summary["water"]["source"], "ru") << dim;
  }
}

/// A small slope (H = 2 m at 2H:1V, Δx = 0.5 m), clamped, with the given dimension.
std::map<std::pair<long, long>, double> slope_pressures(int dimension, const std::vector<std::string>& sets) {
  const std::string toml =
      "[run]\ndimension = " + std::to_string(dimension) +
      "\nscenario = \"slope\"\nend_time = 0.001\nsnapshot_interval = 0.0\n[geostatic]\nduration = 0.02\n"
      "[[material]]\ndensity = 2000.0\nyoung = 20e6\npoisson = 0.3\ncohesion = 10e3\nfriction = 30.0\n"
      "[numerics]\nspacing = 0.5\n[slope]\nheight = 2.0\ngradient = 2.0\ncrest_length = 2.0\nfront_length = 2.0\n"
      "base_thickness = 1.0\n[clamp]\nboxes = " +
      (dimension == 3 ? "[-1, -1, -1, 20, 5, 20]\n[geometry]\nwidth = 2.5\nperiodic = false\n" : "[-1, -1, 20, 20]\n");
  const RunConfig c = config_of(toml, sets);
  SphSimulation sim(c);
  AtStart obs;
  sim.run(&obs);
  std::map<std::pair<long, long>, double> u;  // by (x, z) in quarters of a millimetre
  const auto& f = obs.fields;
  for (std::size_t i = 0; i < f.count; ++i)
    if (f.kind[i] == 0) {
      const auto key = std::make_pair(std::lround(f.position[dimension * i] * 4e3),
                                      std::lround(f.position[dimension * i + dimension - 1] * 4e3));
      const auto [it, added] = u.emplace(key, f.pore_pressure[i]);
      if (!added) {
        EXPECT_EQ(it->second, f.pore_pressure[i]);  // the same across the 3D width
      }
    }
  return u;
}

// The 3D slope (uniform across its width) with r_u and with rain gives every particle the u of the 2D
// slope's particle at the same (x, z), to round-off.
TEST(SphWaterSections, ThreeDimensionalSlopeTakesTheTwoDimensionalPorePressure) {
  for (const auto& sets : std::vector<std::vector<std::string>>{
           {"water.ru=0.25"},
           {"rain.enabled=true", "rain.step=3600", "rain.intensity=[1e-5]", "hydrology.diffusivity=1e-4",
            "hydrology.water_table_depth=1.0", "rain.clock_times=[0, 3600, 1, 3600]"}}) {
    const auto u2 = slope_pressures(2, sets), u3 = slope_pressures(3, sets);
    std::size_t matched = 0;
    double diff = 0.0, umax = 0.0;
    for (const auto& [key, v] : u3) {
      const auto it = u2.find(key);
      if (it == u2.end()) continue;
      ++matched;
      diff = std::max(diff, std::abs(it->second - v));
      umax = std::max(umax, v);
    }
    std::printf("%s: %zu of %zu points matched, max |u3 - u2| %.3g Pa, max u %.4g Pa\n", sets.front().c_str(), matched,
                u3.size(), diff, umax);
    EXPECT_EQ(matched, u3.size());
    EXPECT_GT(umax, 1e4);
    EXPECT_LE(diff, 1e-9 * umax);
  }
}

// The pore-pressure raster: u_b at the base of the 3 m cover gives the piezometric level z_g − 3 +
// u_b/γ_w; every soil particle of the 2D section and of the 3D strip takes γ_w max(min(level, z_g) −
// z, 0) of its map position, to round-off; Bishop's factor beside the 2D section falls below the dry
// one.
TEST(SphWaterSections, PorePressureRasterGivesEachParticleItsHead) {
  const fs::path raster = write_raster("pore.tif", base_pressure);
  auto expected = [](double x, double y, double z) {
    const double level = ground(x, y) - 3.0 + base_pressure(x, y) / kGammaW;
    return kGammaW * std::max(std::min(level, ground(x, y)) - z, 0.0);
  };
  for (int dim : {2, 3}) {
    const auto k = run_section(dim, {"water.pore_pressure_raster=\"" + raster.string() + "\""}, expected);
    std::printf("pore-pressure raster %dD: max |u - expected| %.3g Pa, max u %.4g Pa\n", dim, k.error, k.umax);
    EXPECT_LT(k.error, 1e-9 * k.umax) << dim;
    EXPECT_GT(k.umax, kGammaW * 3.0) << dim;  // 2 m at the base, the deepest 1.5 m below it
    EXPECT_EQ(k.summary["water"]["source"], "pore_pressure_raster") << dim;
    if (dim == 2) {
      const auto dry = run_section(2, {}, [](double, double, double) { return 0.0; });
      EXPECT_LT(k.summary["bishop"]["factor"].get<double>(), dry.summary["bishop"]["factor"].get<double>() - 0.01);
    }
  }
}

// The infinite-slope check of a DSM section with the water table at the ground (a table raster 1 µm
// below it: m = 1): the factor equals the hand formula FS = [c′ + (γ_sat − γ_w) t cos²β tan φ′] /
// (γ_sat t sin β cos β) (slope-parallel seepage, the formula slope-stability evaluates), and the dry one
// c′/(γ t sin β cos β) + tan φ′/tan β. Tolerance: the table's 1 µm (3e-7 of t).
TEST(SphWaterSections, InfiniteSlopeCheckWithTheTableAtTheGroundMatchesTheHandFormula) {
  const double t = 3.0, c = 5e3, phi = 30.0 * std::numbers::pi / 180.0, gm = 1900.0 * kG, gs = 2000.0 * kG;
  const double sn = std::sin(kSlope), cs = std::cos(kSlope);
  const double dry_hand = c / (gm * t * sn * cs) + std::tan(phi) / std::tan(kSlope);
  const double wet_hand = (c + (gs - kGammaW) * t * cs * cs * std::tan(phi)) / (gs * t * sn * cs);
  const auto dry = run_section(2, {}, [](double, double, double) { return 0.0; });
  const fs::path table = write_raster("table_at_ground.tif", [](double x, double y) { return ground(x, y) - 1e-6; });
  const auto wet = run_section(2, {"water.table_raster=\"" + table.string() + "\""}, [](double x, double y, double z) {
    return kGammaW * std::max(ground(x, y) - 1e-6 - z, 0.0);
  });
  const double fd = dry.summary["infinite_slope"]["factor"].get<double>();
  const double fw = wet.summary["infinite_slope"]["factor"].get<double>();
  std::printf("infinite slope: dry %.6f (hand %.6f), table at the ground %.6f (hand %.6f)\n", fd, dry_hand, fw,
              wet_hand);
  EXPECT_NEAR(fd, dry_hand, 1e-12 * dry_hand);
  EXPECT_NEAR(fw, wet_hand, 1e-6 * wet_hand);
}

/// Bishop's factor of the limit-equilibrium analysis of slope_water_newmark.toml with c′ = 5 kPa.
double bishop(const std::vector<std::string>& sets) {
  ConfigReader r = ConfigReader::from_file(kData / "slope_water_newmark.toml");
  for (const auto& s : std::vector<std::string>{"earthquake.type=\"none\"", "material[0].cohesion=5000"})
    r.apply_override(s);
  for (const auto& s : sets) r.apply_override(s);
  RunConfig c = read_config(r, false);
  r.finish();
  validate(c);
  SphSimulation sim(c);
  sim.run(nullptr);
  return nlohmann::json::parse(sim.summary_json())["factor_of_safety"].get<double>();
}

const std::vector<std::string> kSlopeRain = {
    "water.phreatic=[]",     "rain.enabled=true",           "rain.step=43200",
    "rain.intensity=[1e-5]", "hydrology.conductivity=1e-5", "hydrology.diffusivity=1e-3"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// Bishop under rain at rain.evaluate_at = 0 is the initial state: with the table 2 m deep it equals
// Bishop with that table (water.phreatic = the ground 2 m lower, head_loss_corrected: Iverson's initial
// ψ = cos²δ (Z − d) is slope-parallel seepage), to round-off, below the dry factor; with the table 20 m
// deep (below the whole slope) the dry factor exactly. After 4 h of rain the factor is lower still.
TEST(SphWaterSections, BishopUnderRainAtTimeZeroIsTheInitialTable) {
  const double rain0 = bishop(with(kSlopeRain, {"hydrology.water_table_depth=2", "rain.evaluate_at=0"}));
  const double table = bishop({"water.phreatic=[0,13,25,13,45,3,65,3]", "water.pore_pressure=\"head_loss_corrected\""});
  const double deep = bishop(with(kSlopeRain, {"hydrology.water_table_depth=20", "rain.evaluate_at=0"}));
  const double dry = bishop({"water.phreatic=[]"});
  const double rain4h = bishop(with(kSlopeRain, {"hydrology.water_table_depth=2", "rain.evaluate_at=14400"}));
  std::printf("Bishop: rain at t = 0 %.10f, initial table %.10f; deep table %.10f, dry %.10f; after 4 h %.4f\n", rain0,
              table, deep, dry, rain4h);
  EXPECT_NEAR(rain0, table, 1e-9 * table);
  EXPECT_LT(table, dry - 0.02);
  EXPECT_EQ(deep, dry);
  EXPECT_LT(rain4h, rain0 - 0.02);
}

// The strength reduction under rain (the table 2 m deep) at rain.evaluate_at = 1 h (the trials' pore pressure held
// there) agrees with Bishop under the same pore pressure within 5 %: the bracket [0.95, 1.05] F_Bishop is "bracketed"
// (f_min stable, f_max failed) with the tolerance its width, two or three trials at Δx = 1 m (as the r_u test of
// sph_app_water). About 6 s on one thread.
TEST(SphWaterSections, StrengthReductionUnderRainAgreesWithBishop) {
  const auto sets = with(kSlopeRain, {"hydrology.water_table_depth=2", "rain.evaluate_at=3600"});
  const double fb = bishop(sets);
  ConfigReader r = ConfigReader::from_file(kData / "slope_water_newmark.toml");
  std::ostringstream lo, hi, tol;
  lo << "strength_reduction.f_min=" << 0.95 * fb;
  hi << "strength_reduction.f_max=" << 1.05 * fb;
  tol << "strength_reduction.tolerance=" << 0.1 * fb + 1e-9;
  for (const auto& s :
       with(sets, {"earthquake.type=\"none\"", "material[0].cohesion=5000", "run.analysis=\"strength_reduction\"",
                   "numerics.spacing=1.0", lo.str(), hi.str(), tol.str()}))
    r.apply_override(s);
  RunConfig c = read_config(r, false);
  r.finish();
  validate(c);
  SphSimulation sim(c);
  sim.run(nullptr);
  const auto s = nlohmann::json::parse(sim.summary_json());
  EXPECT_SUMMARY_KEYS_DECLARED(s, geohaz::sph::summary_keys());
  std::printf("rain at 1 h: Bishop (limit equilibrium) %.4f, beside the strength reduction %.4f, outcome %s, F %s\n",
              fb, s["bishop"]["factor"].get<double>(), s["outcome"].get<std::string>().c_str(),
              s["factor_of_safety"].dump().c_str());
  EXPECT_NEAR(s["bishop"]["factor"].get<double>(), fb, 1e-12 * fb);
  EXPECT_EQ(s["outcome"], "bracketed");
  EXPECT_EQ(s["water"]["rain"]["evaluate_at_s"].get<double>(), 3600.0);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The snapshots of a run with pore water carry pore_pressure (HDF5 dataset and XDMF attribute, for
// ParaView), equal to the closed form at the snapshot's positions; a dry run's snapshots do not.
TEST(SphWaterSections, SnapshotsCarryThePorePressure) {
  fs::create_directories(kWork);
  const fs::path cfg = kWork / "snapshot.toml";
  std::ofstream(cfg) << section_toml(2);
  for (const bool wet : {true, false}) {
    const fs::path out = kWork / (wet ? "snapshot_wet" : "snapshot_dry");
    fs::remove_all(out);
    const auto r = geohaz::testing::run_command(kApp.string() + " --config " + cfg.string() + " --out " + out.string() +
                                                (wet ? " --set water.ru=0.3" : "") +
                                                " --set run.snapshot_interval=0.0005 --threads 1 --quiet");
    ASSERT_EQ(r.code, 0) << r.output;
    SnapshotReader snaps(out / "snapshots.h5");
    const std::size_t k = snaps.snapshot_count() - 1;
    ASSERT_EQ(snaps.has_field(k, "pore_pressure"), wet);
    if (!wet) {
      EXPECT_EQ(slurp(out / "snapshots.xmf").find("pore_pressure"), std::string::npos);
      continue;
    }
    EXPECT_NE(slurp(out / "snapshots.xmf").find("pore_pressure"), std::string::npos);
    const auto u = snaps.read(k, "pore_pressure"), x = snaps.read(k, "position"), kind = snaps.read(k, "kind");
    EXPECT_EQ(u.unit, "Pa");
    double error = 0.0, umax = 0.0;
    for (std::size_t i = 0; i < u.count; ++i) {
      if (kind.values[i] != 0.0) continue;
      error = std::max(error, std::abs(u.values[i] - ru_u(500010.0 + x.values[2 * i], 0.0, x.values[2 * i + 1])));
      umax = std::max(umax, u.values[i]);
    }
    std::printf("snapshot %zu: max |u - r_u sigma_v| %.3g Pa, max u %.4g Pa\n", k, error, umax);
    EXPECT_GT(umax, 1e4);
    EXPECT_LT(error, 1e-9 * umax);
  }
}

// Pore water where it does not apply: r_u and rain on a column, a phreatic polyline on a DSM section
// (it takes water.table_raster): exit 2 naming the key, nothing written.
TEST(SphWaterSections, PoreWaterOutsideTheSlopeAndTheSectionExitsTwo) {
  fs::create_directories(kWork);
  const fs::path column = kWork / "column.toml", section = kWork / "section.toml";
  std::ofstream(column) << "[run]\nscenario = \"column\"\n[[material]]\ndensity = 2000.0\nyoung = 20e6\n"
                           "poisson = 0.3\ncohesion = 0.0\nfriction = 30.0\n";
  std::ofstream(section) << section_toml(2);
  const fs::path out = kWork / "bad_scenario";
  for (const auto& [config, sets, key] : std::vector<std::tuple<fs::path, std::string, std::string>>{
           {column, "water.ru=0.2", "water.ru"},
           {column, "rain.enabled=true", "rain.enabled"},
           {section, "water.phreatic=[0,50,80,10]", "water.phreatic"}}) {
    fs::remove_all(out);
    const auto r = geohaz::testing::run_command(kApp.string() + " --config " + config.string() + " --out " +
                                                out.string() + " --set " + sets + " --threads 1");
    EXPECT_EQ(r.code, 2) << sets << ": " << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << sets << ": " << r.output;
    EXPECT_FALSE(fs::exists(out)) << sets;
  }
}

// Bad pore-pressure rasters: another CRS, not covering the section, beside a table raster or r_u, on
// a slope: exit 2 naming water.pore_pressure_raster, nothing written.
TEST(SphWaterSections, BadPorePressureRasterExitsTwoNamingTheKey) {
  fs::create_directories(kWork);
  const fs::path cfg = kWork / "bad.toml";
  std::ofstream(cfg) << section_toml(2);
  const fs::path slope = kData / "slope_water_newmark.toml";
  const fs::path good = write_raster("pore_good.tif", base_pressure);
  const std::string key = "water.pore_pressure_raster";
  const fs::path out = kWork / "bad_pore";
  for (const auto& [config, sets] : std::vector<std::pair<fs::path, std::string>>{
           {cfg, key + "=\"" + write_raster("pore_utm55.tif", base_pressure, 55).string() + "\""},
           {cfg, key + "=\"" + write_raster("pore_short.tif", base_pressure, 54, 30).string() + "\""},
           {cfg, key + "=\"" + (kWork / "missing.tif").string() + "\""},
           {cfg, key + "=\"" + good.string() + "\" --set water.table_raster=\"" + good.string() + "\""},
           {cfg, key + "=\"" + good.string() + "\" --set water.ru=0.2"},
           {slope, "water.phreatic=[] --set " + key + "=\"" + good.string() + "\""}}) {
    fs::remove_all(out);
    const auto r = geohaz::testing::run_command(kApp.string() + " --config " + config.string() + " --out " +
                                                out.string() + " --set " + sets + " --threads 1");
    EXPECT_EQ(r.code, 2) << sets << ": " << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << sets << ": " << r.output;
    EXPECT_FALSE(fs::exists(out)) << sets;
  }
}

}  // namespace
