// Regression tests of the slope-stability app on a small synthetic DSM whose slope changes from
// column to column (a parabolic cylinder, on which central differences are exact): the FS map is
// the infinite-slope formula cell by cell, the failure time of each cell under steady rain is the
// analytic one, the release polygons give debris-runout exactly the volume the app reports, and
// bad inputs exit with 2 naming the key and write nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"
#include "geohaz/sph/summary_keys.hpp"
#include "run_command.hpp"
#include "summary_keys_check.hpp"

namespace fs = std::filesystem;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
// The DSM: z = z0 − a x − b x² along x (east), level along y; 40 × 12 cells of 5 m. The slope
// runs from atan(a) = 25° at the west edge to atan(a + 2 b 200) ≈ 40° at the east edge.
constexpr int kNx = 40, kNy = 12;
constexpr double kDx = 5.0, kX0 = 600000.0, kY0 = 5200000.0;
const double kA = std::tan(25.0 * kDeg), kB = (std::tan(40.0 * kDeg) - std::tan(25.0 * kDeg)) / (2.0 * 200.0);

double slope_at_column(int col) {
  const double x = (col + 0.5) * kDx;
  return std::atan(kA + 2.0 * kB * x);
}

fs::path work_dir() {
  const fs::path d = fs::path(GEOHAZ_BINARY_DIR) / "tests" / "stability" / ("work_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

fs::path make_dsm() {
  const fs::path p = work_dir() / "cylinder.tif";
  if (fs::exists(p)) return p;
  geohaz::Raster r;
  r.nx = kNx;
  r.ny = kNy;
  r.geotransform = {kX0, kDx, 0.0, kY0, 0.0, -kDx};
  r.crs_wkt = geohaz::crs_to_wkt("EPSG:32632");
  r.nodata = -9999.0;
  r.data.resize(static_cast<std::size_t>(kNx * kNy));
  for (int row = 0; row < kNy; ++row)
    for (int col = 0; col < kNx; ++col) {
      const double x = (col + 0.5) * kDx;
      r.at(col, row) = 1000.0 - kA * x - kB * x * x;
    }
  geohaz::write_geotiff(p, r, true);  // Float64: the slope from the stored values is the exact one
  return p;
}

// The case of the tests: Z = 1.5 m, water table initially at 1 m, steady rain at K_s/2 for 24 h.
const char* const kCase = R"(
[soil]
depth = 1.5
min_slope = 0.0
max_slope = 60.0
cohesion = 3000.0
friction_angle = 34.0
unit_weight_moist = 18000.0
unit_weight_saturated = 20500.0
[hydrology]
conductivity = 1.0e-5
diffusivity = 2.0e-5
water_table_depth = 1.0
[rain]
step = 86400.0
intensity = [5.0e-6]
[run]
time_step = 3600.0
[output]
pngs = false
)";

fs::path write_case() {
  const fs::path p = work_dir() / "case.toml";
  std::ofstream(p) << kCase;
  return p;
}

geohaz::testing::CommandResult stability(const std::string& args) {
  return geohaz::testing::run_command(std::string(SLOPE_STABILITY_EXE) + " " + args);
}

// The same numbers as kCase, for the closed forms below.
constexpr double kZ = 1.5, kD = 1.0, kC = 3000.0, kPhi = 34.0 * kDeg, kGm = 18000.0, kGs = 20500.0, kGw = 9810.0;
constexpr double kKs = 1e-5, kD0 = 2e-5, kRate = 0.5;

/// Iverson's FS with the column weight W = γ_m (Z − Z_w) + γ_sat Z_w, Z_w = ψ/β (docs/stability.md).
double fs_formula(double delta, double psi) {
  const double beta = std::cos(delta) * std::cos(delta);
  const double zw = std::clamp(psi / beta, 0.0, kZ);
  const double gamma_s = (kGm * (kZ - zw) + kGs * zw) / kZ;
  return std::tan(kPhi) / std::tan(delta) +
         (kC - std::max(psi, 0.0) * kGw * std::tan(kPhi)) / (gamma_s * kZ * std::sin(delta) * std::cos(delta));
}

/// ψ(Z, t) under steady rain from t = 0, written out independently of the library:
/// β (Z − d) + (I/K_s) √(D̂ t) ierfc(Z/√(D̂ t)), capped at β Z.
double psi_closed_form(double delta, double t) {
  const double beta = std::cos(delta) * std::cos(delta), dhat = 4.0 * kD0 / beta;
  double psi = beta * (kZ - kD);
  if (t > 0.0) {
    const double s = std::sqrt(dhat * t), eta = kZ / s;
    psi += kRate * s * (std::exp(-eta * eta) / std::sqrt(std::numbers::pi) - eta * std::erfc(eta));
  }
  return std::min(psi, beta * kZ);
}

}  // namespace

// FS(0) of every interior cell is the formula with the cell's exact slope (Float32 output: 1e-6).
TEST(SlopeStabilityApp, FactorOfSafetyIsTheInfiniteSlopeFormulaPerCell) {
  const fs::path out = work_dir() / "fs_formula";
  fs::remove_all(out);
  const auto r = stability(make_dsm().string() + " --config " + write_case().string() + " --out " + out.string() +
                           " --quiet --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  const geohaz::Raster f = geohaz::read_raster(out / "fs" / "fs_t0000000s.tif");
  int checked = 0;
  for (int row = 0; row < kNy; ++row)
    for (int col = 0; col < kNx; ++col) {
      const bool border = row == 0 || col == 0 || row == kNy - 1 || col == kNx - 1;
      if (border) {
        EXPECT_TRUE(f.is_nodata(f.at(col, row))) << col << ", " << row;
        continue;
      }
      const double delta = slope_at_column(col);
      const double beta = std::cos(delta) * std::cos(delta);
      const double expected = fs_formula(delta, beta * (kZ - kD));
      EXPECT_NEAR(f.at(col, row), expected, 1e-6 * expected) << col << ", " << row;
      ++checked;
    }
  EXPECT_EQ(checked, (kNx - 2) * (kNy - 2));
}

// Under steady rain the water rises; each column fails when FS(ψ(t)) = 1. The analytic time is the
// root of that equation from the closed form above (bisection to 1e-4 s); the app refines its
// crossing to 1e-6 of its 1 h step and writes Float32 seconds: 0.05 s.
TEST(SlopeStabilityApp, FailureTimePerCellIsTheAnalyticTime) {
  const fs::path out = work_dir() / "failure_time";
  fs::remove_all(out);
  const auto r =
      stability(make_dsm().string() + " --config " + write_case().string() + " --out " + out.string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const geohaz::Raster ft = geohaz::read_raster(out / "failure_time.tif");
  int failing = 0, stable = 0, initially = 0;
  for (int col = 1; col < kNx - 1; ++col) {
    const double delta = slope_at_column(col);
    const auto g = [&](double t) { return fs_formula(delta, psi_closed_form(delta, t)) - 1.0; };
    const double v = ft.at(col, kNy / 2);
    if (g(86400.0) >= 0.0) {  // stable to the end
      EXPECT_TRUE(ft.is_nodata(v)) << "column " << col << ": " << v;
      ++stable;
      continue;
    }
    if (g(0.0) < 0.0) {  // unstable before the rain: failure time 0
      EXPECT_EQ(v, 0.0) << "column " << col;
      ++initially;
      continue;
    }
    double lo = 0.0, hi = 86400.0;
    while (hi - lo > 1e-4) ((g(0.5 * (lo + hi)) < 0.0) ? hi : lo) = 0.5 * (lo + hi);
    EXPECT_NEAR(v, hi, 0.05) << "column " << col;
    ++failing;
  }
  // The case is built so that both kinds occur.
  EXPECT_GT(failing, 5);
  EXPECT_GT(stable, 5);
  EXPECT_GT(initially, 0);
}

// The release polygons, read by debris-runout with its defaults (thickness normal to the slope),
// give it exactly the volume slope-stability reports: Σ Z · cell area over the failed cells.
TEST(SlopeStabilityApp, ReleasePolygonVolumeIsWhatDebrisRunoutSeeds) {
  const fs::path out = work_dir() / "chain", run = work_dir() / "chain_runout";
  fs::remove_all(out);
  fs::remove_all(run);
  const fs::path dsm = make_dsm();
  auto r = stability(dsm.string() + " --config " + write_case().string() + " --out " + out.string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream sj(out / "summary.json");
  const auto s = nlohmann::json::parse(sj);
  EXPECT_SUMMARY_KEYS_DECLARED(s, geohaz::sph::summary_keys());  // every number labelled (issue #33)
  const double volume = s["release"]["volume_m3"].get<double>();
  const double failed = s["cells"]["failed"].get<double>();
  EXPECT_NEAR(volume, failed * kZ * kDx * kDx, 1e-9 * volume);
  ASSERT_GT(volume, 0.0);
  r = geohaz::testing::run_command(std::string(DEBRIS_RUNOUT_EXE) + " " + dsm.string() + " --release " +
                                   (out / "release.gpkg").string() + " --duration 0.5 --d0 5 --h0 0.25 --out " +
                                   run.string() + " --quiet --set output.png=false");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream rj(run / "summary.json");
  const auto j = nlohmann::json::parse(rj);
  // Float32 polygon values (the polygonizer's): 1e-6 relative.
  EXPECT_NEAR(j["volumes_m3"]["release_read"].get<double>(), volume, 1e-6 * volume);
  EXPECT_NEAR(j["volumes_m3"]["seeded"].get<double>(), volume, 1e-6 * volume);
}

// Bad input: exit 2, the key named, nothing written.
TEST(SlopeStabilityApp, BadInputExitsTwoNamingTheKeyAndWritesNothing) {
  const fs::path dsm = make_dsm(), cfg = write_case();
  // A water table raster above the ground everywhere.
  geohaz::Raster wt = geohaz::read_raster(dsm);
  for (double& v : wt.data) v = -0.5;
  const fs::path wt_file = work_dir() / "water_table_above.tif";
  geohaz::write_geotiff(wt_file, wt);
  const std::pair<std::string, std::string> cases[] = {
      {"--set hydrology.water_table_depth=-0.5", "hydrology.water_table_depth"},
      {"--set hydrology.water_table_raster=\\\"" + wt_file.string() + "\\\"", "hydrology.water_table_raster"},
      {"--set hydrology.conductivity=-1e-5", "hydrology.conductivity"},
      {"--set soil.unit_weight_moist=21000", "soil.unit_weight_moist"},
      {"--set soil.unit_weight_saturated=9000 --set soil.unit_weight_moist=8000", "soil.unit_weight_saturated"},
  };
  for (const auto& [args, key] : cases) {
    const fs::path out = work_dir() / "bad_out";
    fs::remove_all(out);
    const auto r = stability(dsm.string() + " --config " + cfg.string() + " " + args + " --out " + out.string());
    EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
}
