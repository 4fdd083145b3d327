// A water table raster on DSM sections (water.table_raster; docs/sph.md, "Pore pressure and seismic
// coefficients"; label: regression): on a small synthetic DSM (a 26.6° plane, UTM 54N) with a table
// raster that is a plane too (bilinear sampling reproduces planes exactly), every soil particle of a
// 2D section and of a 3D strip takes u = γ_w max(z_w − z, 0) with z_w the raster at the particle's
// map position, Bishop's factor beside the 2D section falls with the table, and bad rasters exit 2
// naming the key with nothing written.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/run.hpp"
#include "run_command.hpp"
#include "utm_crs.hpp"

namespace {

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::sph;

const fs::path kApp = fs::path(GEOHAZ_BINARY_DIR) / "apps/sph-slope/sph-slope";
// One folder per process: ctest runs the cases of this file in parallel, and each writes dsm.tif
// and table.tif (two cases writing the same file failed the rename of one of them).
const fs::path kWork = fs::path(GEOHAZ_BINARY_DIR) / "tests/sph" / ("water_table_runs_" + std::to_string(::getpid()));
constexpr double kX0 = 500000.0, kY0 = 4000000.0;  // the DSM's north-west corner (UTM 54N)
constexpr double kGammaW = 1000.0 * 9.81;

std::string utm(int zone) {
  return geohaz::testing::utm_wkt(zone);
}

/// The ground: a plane falling 0.5 m per m eastwards from 60 m (26.6°), 120 m × 40 m at 2 m cells.
double ground(double x, double /*y*/) {
  return 60.0 - 0.5 * (x - kX0);
}
/// The table: 1.5 m under the ground at the strip's middle line, rising 0.1 m per m northwards.
double table(double x, double y) {
  return ground(x, y) - 1.5 + 0.1 * (y - (kY0 - 20.0));
}

/// A raster of f on the DSM's grid (or a smaller one), in UTM `zone`.
fs::path write_raster(const std::string& name, double (*f)(double, double), double offset = 0.0, int zone = 54,
                      int nx = 60) {
  Raster r;
  r.nx = nx;
  r.ny = 20;
  r.geotransform = {kX0, 2.0, 0.0, kY0, 0.0, -2.0};
  r.crs_wkt = utm(zone);
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) {
      const double x = kX0 + 2.0 * (col + 0.5), y = kY0 - 2.0 * (row + 0.5);
      r.data.push_back(f(x, y) + offset);
    }
  fs::create_directories(kWork);
  const fs::path p = kWork / name;
  write_geotiff(p, r, true);
  return p;
}

/// The section: along the strip's middle line from 10 m to 90 m east, a 3 m cover over 2 m of base on
/// bedrock, strong soil (it stays put), 1 m spacing, a geostatic phase of a few steps (the field is
/// evaluated in every step, gravity at its full value by the end).
std::string section_toml(const fs::path& dsm, int dimension) {
  return "[run]\ndimension = " + std::to_string(dimension) +
         "\nscenario = \"section\"\nend_time = 0.001\n"
         "[geostatic]\nduration = 0.02\n"
         "[[material]]\nname = \"base\"\ndensity = 2200.0\nyoung = 50e6\npoisson = 0.25\ncohesion = 200e3\n"
         "friction = 40.0\n"
         "[[material]]\nname = \"cover\"\ndensity = 1900.0\nyoung = 20e6\npoisson = 0.3\ncohesion = 50e3\n"
         "friction = 30.0\n"
         "[numerics]\nspacing = 1.0\n"
         "[section]\ndsm = \"" +
         dsm.string() +
         "\"\npolyline = [500010.0, 3999980.0, 500090.0, 3999980.0]\nsoil_thickness = 3.0\nbase_thickness = 2.0\n" +
         (dimension == 3 ? "[geometry]\nwidth = 6.0\n" : "");
}

struct AtStart : RunObserver {
  ParticleFields fields;
  void started(const SphSimulation& s) override { fields = s.particles(); }
};

/// The largest |u − γ_w max(z_w − z, 0)| over the soil particles (Pa) at the start of the main phase, the
/// largest u, and the summary.
struct Check {
  double error = 0.0, umax = 0.0;
  nlohmann::json summary;
};

Check run_section(int dimension, const std::vector<std::string>& sets) {
  const fs::path dsm = write_raster("dsm.tif", ground);
  ConfigReader r = ConfigReader::from_string(section_toml(dsm, dimension));
  for (const auto& s : sets) r.apply_override(s);
  RunConfig c = read_config(r, false);
  r.finish();
  validate(c);
  SphSimulation sim(c);
  AtStart obs;
  sim.run(&obs);
  Check k;
  const auto& f = obs.fields;
  const double half = 3.0;  // the strip is 6 m wide, centred on the polyline (local y − 3 m to its left: north)
  for (std::size_t i = 0; i < f.count; ++i) {
    if (f.kind[i] != 0) continue;
    const double s = f.position[dimension * i], z = f.position[dimension * i + dimension - 1];
    const double t = dimension == 3 ? f.position[dimension * i + 1] - half : 0.0;
    const double x = 500010.0 + s, y = 3999980.0 + t;
    const double expected = kGammaW * std::max(std::min(table(x, y), ground(x, y)) - z, 0.0);
    k.error = std::max(k.error, std::abs(f.pore_pressure[i] - expected));
    k.umax = std::max(k.umax, f.pore_pressure[i]);
  }
  k.summary = nlohmann::json::parse(sim.summary_json());
  return k;
}

// 2D: the raster cut along the section is the phreatic polyline (clipped to the profile): every soil
// particle's u within 5 Pa of γ_w (z_w − z) at its position (0.5 mm of head: the particles move by
// less in the last geostatic step, whose positions the field was evaluated at; measured 0.3 Pa), u up
// to the deepest particle's ≈ γ_w 3 m. Bishop's factor beside it
// falls with the table (the dry section's against the wet one's).
TEST(SphWaterTable, TableRasterCutAlongA2DSectionGivesEachParticleItsHead) {
  const fs::path wt = write_raster("table.tif", table);
  const auto wet = run_section(2, {"water.table_raster=\"" + wt.string() + "\""});
  std::printf("2D: max |u - expected| %.3g Pa, max u %.4g Pa\n", wet.error, wet.umax);
  EXPECT_LT(wet.error, 5.0);
  EXPECT_GT(wet.umax, kGammaW * 2.5);
  EXPECT_EQ(wet.summary["water"]["source"], "table_raster");
  // The summary's largest u over the series' rows (the start and the end of the 1 ms main phase).
  EXPECT_NEAR(wet.summary["water"]["max_pore_pressure_Pa"].get<double>(), wet.umax, 1e-4 * wet.umax);
  const auto dry = run_section(2, {});
  EXPECT_EQ(dry.umax, 0.0);
  EXPECT_FALSE(dry.summary.contains("water"));
  const double fw = wet.summary["bishop"]["factor"].get<double>(), fd = dry.summary["bishop"]["factor"].get<double>();
  std::printf("Bishop beside the section: dry %.4f, with the table %.4f\n", fd, fw);
  EXPECT_LT(fw, fd - 0.01);
}

// 3D: the raster sampled over the strip (the table rises 0.6 m across its 6 m width): every soil
// particle takes the head of its own map position, within 5 Pa (measured 0.3 Pa).
TEST(SphWaterTable, TableRasterOverA3DStripGivesEachParticleItsHead) {
  const fs::path wt = write_raster("table.tif", table);
  const auto k = run_section(3, {"water.table_raster=\"" + wt.string() + "\""});
  std::printf("3D: max |u - expected| %.3g Pa, max u %.4g Pa\n", k.error, k.umax);
  EXPECT_LT(k.error, 5.0);
  EXPECT_GT(k.umax, kGammaW * 2.5);
  EXPECT_EQ(k.summary["water"]["source"], "table_raster");
}

// Bad rasters: another CRS, not covering the section, above the ground everywhere, on a slope
// scenario, beside water.phreatic: exit 2 naming water.table_raster, nothing written.
TEST(SphWaterTable, BadTableRasterExitsTwoNamingTheKey) {
  const fs::path dsm = write_raster("dsm.tif", ground);
  fs::create_directories(kWork);
  const fs::path cfg = kWork / "section.toml";
  std::ofstream(cfg) << section_toml(dsm, 2);
  const fs::path slope = fs::path(GEOHAZ_SOURCE_DIR) / "data/sph/slope_water_newmark.toml";
  const fs::path good = write_raster("table.tif", table);
  const fs::path out = kWork / "bad_table";
  for (const auto& [config, sets] : std::vector<std::pair<fs::path, std::string>>{
           {cfg, "water.table_raster=\"" + write_raster("utm55.tif", table, 0.0, 55).string() + "\""},
           {cfg, "water.table_raster=\"" + write_raster("short.tif", table, 0.0, 54, 30).string() + "\""},
           {cfg, "water.table_raster=\"" + write_raster("above.tif", ground, 1.0).string() + "\""},
           {cfg, "water.table_raster=\"" + (kWork / "missing.tif").string() + "\""},
           {cfg, "water.table_raster=\"" + good.string() + "\" --set water.ru=0.2"},
           {slope, "water.phreatic=[] --set water.table_raster=\"" + good.string() + "\""}}) {
    fs::remove_all(out);
    const auto r = geohaz::testing::run_command(kApp.string() + " --config " + config.string() + " --out " +
                                                out.string() + " --set " + sets + " --threads 1");
    EXPECT_EQ(r.code, 2) << sets << ": " << r.output;
    EXPECT_NE(r.output.find("water.table_raster"), std::string::npos) << sets << ": " << r.output;
    EXPECT_FALSE(fs::exists(out)) << sets;
  }
}

}  // namespace
