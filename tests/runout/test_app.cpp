// Regression tests of the debris-runout app: a tiny synthetic valley run end to end (outputs exist,
// volumes balance, the flow travels down the valley), and bad inputs (exit code 2, a message naming
// the input, no output written).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/handoff.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/runout/run.hpp"
#include "geohaz/runout/summary_keys.hpp"
#include "geohaz/runout/synthetic_terrain.hpp"
#include "run_command.hpp"
#include "summary_keys_check.hpp"

namespace fs = std::filesystem;

namespace {

using Result = geohaz::testing::CommandResult;

// Run the app through the shell, capturing stdout+stderr.
Result run(const std::string& args) {
  return geohaz::testing::run_command(std::string(DEBRIS_RUNOUT_EXE) + " " + args);
}

fs::path work_dir() {
  const fs::path d = fs::path(GEOHAZ_BINARY_DIR) / "tests" / "runout" / "app_work";
  fs::create_directories(d);
  return d;
}

// The tiny synthetic valley (0.1 scale: 200 × 100 cells of 2.5 m, 500 m long), made once per run
// by the app's own generator.
// ctest runs the tests of this file as separate processes, two at a time: each process makes the
// pair in a folder of its own and renames it into place (atomic, identical contents), so no
// process reads or replaces a half-written file of another.
fs::path tiny_dsm() {
  const fs::path dsm = work_dir() / "tiny.tif", rel = work_dir() / "tiny_release.tif";
  static bool made = false;
  if (!made) {
    made = true;
    if (fs::exists(dsm) && fs::exists(rel)) return dsm;
    const fs::path own = work_dir() / ("make_" + std::to_string(::getpid()));
    fs::create_directories(own);
    const auto r =
        run("--make-synthetic-dsm " + (own / "tiny.tif").string() + " --synthetic-scale 0.1 --release-depth 3");
    EXPECT_EQ(r.code, 0) << r.output;
    fs::rename(own / "tiny_release.tif", rel);
    fs::rename(own / "tiny.tif", dsm);
    fs::remove_all(own);
  }
  return dsm;
}

bool dir_has_files(const fs::path& d) {
  return fs::exists(d) && !fs::is_empty(d);
}

}  // namespace

TEST(DebrisRunoutApp, HelpAndVersion) {
  auto r = run("--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("--release-from"), std::string::npos);
  EXPECT_NE(r.output.find("s/m^(1/3)"), std::string::npos);  // units in --help
  r = run("--help-config");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("model.icr"), std::string::npos);
  EXPECT_EQ(run("--version").code, 0);
}

TEST(DebrisRunoutApp, TinyValleyRunsAndBalancesVolume) {
  const fs::path dsm = tiny_dsm();
  const fs::path out = work_dir() / "tiny_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release " + (work_dir() / "tiny_release.tif").string() +
                     " --d0 2.5 --h0 0.75 --duration 60 --out " + out.string() + " --quiet --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f :
       {"max_depth.tif",        "max_speed.tif", "max_pressure.tif", "deposit.tif",   "mobile_at_end.tif",
        "arrival_time.tif",     "snapshots.h5",  "snapshots.xmf",    "series.csv",    "summary.json",
        "config.resolved.toml", "deposit.png",   "max_speed.png",    "max_depth.png", "intensity.tif",
        "intensity.png",        "intensity.qml", "max_momentum.tif", "max_depth.qml", "deposit.qml"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  const double read = j["volumes_m3"]["release_read"], seeded = j["volumes_m3"]["seeded"];
  // Release: 3 m (normal to the slope, the default) over the block 30–60 m down-valley, ±10 m
  // across: about 3 × 30 × 20 m³ (cells whose centres fall inside; up to 10 % more for the slope).
  EXPECT_NEAR(read, 1800.0, 0.15 * 1800.0);
  EXPECT_NEAR(seeded, read, 1e-9 * read);
  EXPECT_LT(std::abs(j["mass_balance_error_relative"].get<double>()), 1e-12);
  const double dep = j["volumes_m3"]["deposited"], mob = j["volumes_m3"]["mobile"], lost = j["volumes_m3"]["lost"];
  EXPECT_NEAR(dep + mob + lost, read, 1e-9 * read);
  // The kernel deposit map (with the mass still moving at the end, if the run ended at its
  // duration) integrates to the volume still in the domain (grid quadrature, 2 %).
  EXPECT_NEAR(j["volumes_m3"]["deposit_raster"].get<double>() + j["volumes_m3"]["mobile_raster"].get<double>(),
              dep + mob, 0.02 * (dep + mob));
  // Down a ≥ 0.24 gradient channel with i_cr = 0.15 the flow must travel far beyond its release
  // (≥ 100 m in 60 s), and the fahrböschung must be steeper than the energy line atan(0.15) = 8.5°
  // and gentler than the head slope atan(0.45) = 24°.
  EXPECT_GT(j["runout_length_along_path_m"].get<double>(), 100.0);
  EXPECT_GT(j["fahrboeschung"]["angle_deg"].get<double>(), 8.5);
  EXPECT_LT(j["fahrboeschung"]["angle_deg"].get<double>(), 24.0);
  EXPECT_GT(j["max_speed_m_per_s"].get<double>(), 1.0);
  // Intensity areas add up to the affected area (every reached cell is medium or strong).
  const auto& it = j["intensity"];
  EXPECT_EQ(it["scheme"], "depth_speed");
  EXPECT_EQ(it["area_low_m2"].get<double>(), 0.0);
  EXPECT_NEAR(it["area_medium_m2"].get<double>() + it["area_strong_m2"].get<double>(),
              j["area_affected_m2"].get<double>(), 1e-9 * j["area_affected_m2"].get<double>());
  EXPECT_GT(it["area_strong_m2"].get<double>(), 0.0);
  // GIS conventions: description and unit on the band, nodata set.
  const geohaz::Raster speed = geohaz::read_raster(out / "max_speed.tif");
  EXPECT_EQ(speed.unit, "m/s");
  EXPECT_EQ(speed.description, "peak surface speed");
  EXPECT_TRUE(speed.nodata.has_value());
}

// In a pipe (a log file, a cluster job) the progress is one plain line per 10 % of the run (or per
// 60 s of wall time), no terminal control characters; the end says what stopped the run and what
// "mobile" means (issue #29, item 4).
TEST(DebrisRunoutApp, ProgressInAPipeIsOneLinePerTenPercent) {
  const fs::path dsm = tiny_dsm();
  const fs::path out = work_dir() / "pipe_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release " + (work_dir() / "tiny_release.tif").string() +
                     " --d0 2.5 --h0 0.75 --duration 60 --out " + out.string() + " --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find('\r'), std::string::npos) << r.output;
  const std::regex line(R"(^debris-runout: t = [0-9.e+-]+ / 60 s \( *([0-9.]+)%\)  step [0-9]+  [0-9.e+-]+ steps/s  )"
                        R"([0-9.e+-]+ particle-steps/s  ETA [0-9hms.-]+(  \(kinetic energy [0-9.e+-]+ % of peak, )"
                        R"(stops below 1 %\))?$)");
  std::istringstream in(r.output);
  std::string l;
  std::vector<double> percent;
  while (std::getline(in, l)) {
    if (l.rfind("debris-runout: t = ", 0) != 0) continue;
    std::smatch m;
    ASSERT_TRUE(std::regex_match(l, m, line)) << l;
    percent.push_back(std::stod(m[1].str()));
  }
  // A line at the start and one per 10 % after (a fast run: the 60 s interval never comes first).
  ASSERT_GE(percent.size(), 2u) << r.output;
  EXPECT_LE(percent.size(), 11u) << r.output;
  for (std::size_t k = 1; k < percent.size(); ++k) {
    EXPECT_GE(percent[k], percent[k - 1]);
    EXPECT_GE(std::floor(percent[k] / 10.0), std::floor(percent[k - 1] / 10.0) + 1) << "two lines in one 10 %";
  }
  EXPECT_NE(r.output.find("debris-runout: stopped at t = "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("mobile (not yet held by friction"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("done in"), std::string::npos) << r.output;
}

TEST(DebrisRunoutApp, BadInputsExitTwoAndWriteNothing) {
  const fs::path dsm = tiny_dsm();
  const std::string rel = (work_dir() / "tiny_release.tif").string();
  const fs::path out = work_dir() / "bad_out";
  struct Case {
    std::string args, expect;
  };
  const std::string missing = (work_dir() / "no_such.tif").string();
  // A release raster in another place: a copy of the DSM grid shifted far away is made by writing a
  // GeoJSON polygon outside the DSM.
  const fs::path far = work_dir() / "far.geojson";
  {
    std::ofstream f(far);
    f << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32654"}},)"
      << R"("features":[{"type":"Feature","properties":{"thickness":2.0},"geometry":{"type":"Polygon","coordinates":)"
      << R"([[[100000,100000],[100100,100000],[100100,100100],[100000,100000]]]}}]})";
  }
  const fs::path empty_poly = work_dir() / "tiny_empty.geojson";
  {
    std::ofstream f(empty_poly);
    f << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32654"}},)"
      << R"("features":[{"type":"Feature","properties":{"thickness":0.0},"geometry":{"type":"Polygon","coordinates":)"
      << R"([[[480010,4309990],[480020,4309990],[480020,4309980],[480010,4309990]]]}}]})";
  }
  // A DSM in a geographic CRS (degrees): the error must suggest gdalwarp.
  const fs::path geo = work_dir() / "geographic.tif";
  {
    geohaz::Raster r;
    r.nx = r.ny = 10;
    r.geotransform = {140.0, 0.001, 0.0, 39.0, 0.0, -0.001};
    r.crs_wkt = R"(GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],)"
                R"(UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]])";
    r.data.assign(100, 100.0);
    geohaz::write_geotiff(geo, r);
  }
  const std::vector<Case> cases = {
      {geo.string() + " --release " + rel, "gdalwarp"},
      {missing + " --release " + rel, "no_such.tif"},
      {dsm.string() + " --release " + missing, "no_such.tif"},
      {dsm.string() + " --release " + rel + " --n -1", "model.n"},
      {dsm.string() + " --release " + rel + " --duration 0", "run.duration"},
      {dsm.string() + " --release " + rel + " --set model.nonsense=3", "nonsense"},
      {dsm.string() + " --release " + rel + " --friction magic", "model.friction"},
      {dsm.string() + " --release " + rel + " --set release.thickness_direction=sideways",
       "release.thickness_direction"},
      {dsm.string() + " --release " + rel + " --set run.stop_energy_fraction=-0.1", "run.stop_energy_fraction"},
      {dsm.string() + " --release " + rel + " --set numerics.lateral_mixing=-1", "numerics.lateral_mixing"},
      {dsm.string() + " --release " + far.string(), "outside the DSM"},
      {dsm.string() + " --release " + empty_poly.string(), "empty release"},
      {dsm.string(), "no release"},
  };
  for (const auto& c : cases) {
    fs::remove_all(out);
    const auto r = run(c.args + " --out " + out.string() + " --quiet");
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_FALSE(dir_has_files(out)) << c.args;
  }
}

TEST(DebrisRunoutApp, BadRheologyInputsExitTwoNamingTheKey) {
  // The rheologies of issue 34: a negative yield stress or cohesion, a flow index or a
  // concentration out of range, δ₂ ≤ δ₁, a coefficient of another law, C_v together with τ_y:
  // exit 2, the message names the key, nothing written.
  const fs::path dsm = tiny_dsm();
  const std::string rel = (work_dir() / "tiny_release.tif").string();
  const fs::path out = work_dir() / "bad_rheology_out";
  const std::string base = dsm.string() + " --release " + rel;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {" --friction bingham --set model.tau_y=-5", "model.tau_y"},
      {" --friction herschel_bulkley --set model.tau_y=-0.1", "model.tau_y"},
      {" --friction herschel_bulkley --set model.flow_index=3", "model.flow_index"},
      {" --friction herschel_bulkley --set model.flow_index=0", "model.flow_index"},
      {" --friction herschel_bulkley --set model.consistency=-1", "model.consistency"},
      {" --friction bingham --set model.viscosity=0", "model.viscosity"},
      {" --friction voellmy_cohesion --set model.cohesion=-10", "model.cohesion"},
      {" --friction voellmy_cohesion --set model.cohesion=500 --set model.mu=1.5", "model.mu"},
      {" --friction obrien_julien --set model.cv=0.9", "model.cv"},
      {" --friction obrien_julien --set model.cv=0.4 --set model.tau_y=100", "model.tau_y"},
      {" --friction pouliquen --set model.delta1=30 --set model.delta2=25", "model.delta2"},
      {" --friction pouliquen --set model.hstop_length=-1", "model.hstop_length"},
      {" --friction bingham --set model.consistency=5", "model.consistency"},
      {" --friction voellmy --set model.tau_y=50", "model.tau_y"},
  };
  for (const auto& [args, key] : cases) {
    fs::remove_all(out);
    const auto r = run(base + args + " --out " + out.string() + " --quiet");
    EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << args << "\n" << r.output;
    EXPECT_FALSE(dir_has_files(out)) << args;
  }
}

TEST(DebrisRunoutApp, ReleaseFromSphSlopeFileMatchesVolume) {
  // A release.h5 as sph-slope writes it (docs/handoff.md): 2D map points with volumes, in the
  // DSM's CRS. The app must report the volume read and seed exactly that volume.
  const fs::path dsm = tiny_dsm();
  const fs::path h5 = work_dir() / "release.h5";
  geohaz::Handoff h;
  h.crs_wkt = geohaz::runout::kSyntheticValleyCrsWkt;
  h.source = "test: displacement > 0.5 m";
  for (int k = 0; k < 300; ++k) {
    // Points spread over 20 m × 15 m around (480045, 4309875), volumes 0.5–1.4 m³.
    h.points.emplace_back(480035.0 + 20.0 * ((k * 37) % 100) / 100.0, 4309868.0 + 15.0 * ((k * 61) % 100) / 100.0);
    h.volumes.push_back(0.5 + 0.1 * (k % 10));
  }
  const double total = h.total_volume();
  geohaz::write_handoff(h5, h, "");
  const fs::path out = work_dir() / "handoff_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release-from " + h5.string() + " --d0 2.5 --h0 0.5 --duration 5 --out " +
                     out.string() + " --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  EXPECT_NEAR(j["volumes_m3"]["release_read"].get<double>(), total, 1e-12 * total);
  EXPECT_NEAR(j["volumes_m3"]["seeded"].get<double>(), total, 1e-12 * total);
  EXPECT_NE(r.output.find("m^3 read"), std::string::npos) << r.output;
  // A point outside the DSM is rejected (exit 2), nothing written.
  h.points.back() = geohaz::Vec2(0.0, 0.0);
  geohaz::write_handoff(h5, h, "");
  fs::remove_all(out);
  const auto bad = run(dsm.string() + " --release-from " + h5.string() + " --out " + out.string() + " --quiet");
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("outside the DSM"), std::string::npos) << bad.output;
  EXPECT_FALSE(dir_has_files(out));
  // sph-slope found nothing failed: an empty hand-off is bad input (exit 2), not all-zero maps.
  h.points.clear();
  h.volumes.clear();
  geohaz::write_handoff(h5, h, "");
  const auto empty = run(dsm.string() + " --release-from " + h5.string() + " --out " + out.string() + " --quiet");
  EXPECT_EQ(empty.code, 2) << empty.output;
  EXPECT_NE(empty.output.find("holds no volume"), std::string::npos) << empty.output;
  EXPECT_FALSE(dir_has_files(out));
}

TEST(DebrisRunoutApp, ReleaseInAnotherCrsIsReprojected) {
  // The same kind of release.h5, but with its points in geographic WGS 84 (lon, lat): the app must
  // reproject them onto the UTM DSM; the volume is unchanged and the run succeeds.
  const fs::path dsm = tiny_dsm();
  const std::string wgs84 =
      R"(GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],)"
      R"(UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]])";
  std::vector<geohaz::Vec2> utm;
  std::vector<double> vol;
  for (int k = 0; k < 100; ++k) {
    utm.emplace_back(480040.0 + (k % 10), 4309870.0 + (k / 10));
    vol.push_back(1.0);
  }
  const auto lonlat = geohaz::transform_points(utm, geohaz::runout::kSyntheticValleyCrsWkt, wgs84);
  ASSERT_GT(lonlat[0].x(), 140.0);  // degrees east: really geographic
  const fs::path h5 = work_dir() / "release_wgs84.h5";
  geohaz::write_handoff(h5, {lonlat, vol, wgs84, "test: WGS 84 points"}, "");
  const fs::path out = work_dir() / "reproject_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release-from " + h5.string() + " --d0 2.5 --h0 0.5 --duration 2 --out " +
                     out.string() + " --threads 1 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  EXPECT_NEAR(j["volumes_m3"]["seeded"].get<double>(), 100.0, 1e-10);
}

TEST(DebrisRunoutApp, LibraryRunInProcessGivesTheAppsNumbers) {
  // The same case through the app (a subprocess) and through runout::run.hpp in this process, as
  // the ensemble runner and the Python module call it: identical figures, bit for bit (same code,
  // one thread), and the observer sees every step.
  const fs::path dsm = tiny_dsm();
  const fs::path rel = work_dir() / "tiny_release.tif";
  const fs::path out = work_dir() / "inprocess_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release " + rel.string() + " --d0 2.5 --h0 0.75 --duration 20 --out " +
                     out.string() + " --quiet --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)

  auto cfg =
      geohaz::ConfigReader::from_string("[model]\nd0 = 2.5\nh0 = 0.75\n[run]\nduration = 20\n[terrain]\ndsm = \"" +
                                        dsm.string() + "\"\n[release]\nfile = \"" + rel.string() + "\"\n");
  const geohaz::runout::RunConfig c = geohaz::runout::read_config(cfg);
  cfg.finish();
  const geohaz::runout::RunoutInputs inputs = geohaz::runout::load_inputs(c);
  geohaz::runout::RunoutSimulation sim(inputs, c.params, c.output);
  struct Counter : geohaz::runout::RunObserver {
    std::int64_t steps = 0;
    void stepped(const geohaz::runout::RunoutSimulation&) override { ++steps; }
  } counter;
  sim.run(&counter);
  const auto res = sim.result();
  EXPECT_EQ(counter.steps, res.steps);
  EXPECT_EQ(res.steps, j["steps"].get<std::int64_t>());
  EXPECT_EQ(res.path.runout_length, j["runout_length_along_path_m"].get<double>());
  EXPECT_EQ(res.path.fahrboeschung, j["fahrboeschung"]["ratio_H_over_L"].get<double>());
  EXPECT_EQ(res.max_speed, j["max_speed_m_per_s"].get<double>());
  EXPECT_EQ(res.volumes.deposited, j["volumes_m3"]["deposited"].get<double>());
  EXPECT_EQ(std::string(geohaz::runout::to_string(res.ended)), j["ended_by"].get<std::string>());
}

TEST(DebrisRunoutApp, RunEndingAtItsDurationWithMassMovingSaysSo) {
  // 5 s of flow and no energy criterion: most of the mass still moves. The run must say so on
  // stdout and in summary.json, keep the moving mass out of deposit.tif and put it in
  // mobile_at_end.tif (the two integrate to the volume in the domain).
  const fs::path dsm = tiny_dsm();
  const fs::path out = work_dir() / "unfinished_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release " + (work_dir() / "tiny_release.tif").string() +
                     " --d0 2.5 --h0 0.75 --duration 5 --set run.stop_energy_fraction=0 --out " + out.string() +
                     " --quiet --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: the run ended at its duration"), std::string::npos) << r.output;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  EXPECT_EQ(j["ended_by"], "duration reached");
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_GT(j["mobile_at_end"]["fraction"].get<double>(), 0.5);
  EXPECT_FALSE(j["mobile_at_end"]["in_deposit_raster"].get<bool>());
  const double dep = j["volumes_m3"]["deposited"], mob = j["volumes_m3"]["mobile"];
  EXPECT_NEAR(j["volumes_m3"]["mobile_raster"].get<double>(), mob, 0.02 * mob);
  EXPECT_NEAR(j["volumes_m3"]["deposit_raster"].get<double>(), dep, 0.02 * dep + 1e-9);
}

TEST(DebrisRunoutApp, KineticEnergyCriterionEndsTheRun) {
  // With the default criterion (1 % of the peak kinetic energy) the tiny flow ends long before a
  // 1000 s duration, by that criterion, and says which.
  const fs::path dsm = tiny_dsm();
  const fs::path out = work_dir() / "energy_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release " + (work_dir() / "tiny_release.tif").string() +
                     " --d0 2.5 --h0 0.75 --duration 1000 --out " + out.string() + " --quiet --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  EXPECT_EQ(j["ended_by"], "kinetic energy below the stop fraction of its peak");
  EXPECT_LT(j["simulated_time_s"].get<double>(), 1000.0);
  const double ke = j["kinetic_energy_j"]["at_end"], peak = j["kinetic_energy_j"]["peak"];
  EXPECT_LT(ke, 0.01 * peak);
  EXPECT_GT(peak, 0.0);
  EXPECT_TRUE(j["warnings"].empty());
}

TEST(DebrisRunoutApp, ThicknessNormalToTheSlopeHoldsMoreVolume) {
  // A plane falling 1:2 (cos θ = 2/√5) and a 40 m × 40 m polygon 1 m thick: measured vertically
  // it holds 1600 m³ (64 cells of 25 m²), normal to the slope 1600/cos θ = 1788.9 m³.
  const fs::path plane = work_dir() / "plane.tif";
  {
    geohaz::Raster r;
    r.nx = r.ny = 40;
    r.geotransform = {480000.0, 5.0, 0.0, 4310000.0, 0.0, -5.0};
    r.crs_wkt = geohaz::runout::kSyntheticValleyCrsWkt;
    r.data.resize(1600);
    for (int row = 0; row < 40; ++row)
      for (int col = 0; col < 40; ++col) r.data[static_cast<std::size_t>(row * 40 + col)] = 1000.0 - 0.5 * 5.0 * col;
    geohaz::write_geotiff(plane, r);
  }
  const fs::path poly = work_dir() / "square.geojson";
  {
    std::ofstream f(poly);
    f << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32654"}},)"
      << R"("features":[{"type":"Feature","properties":{"thickness":1.0},"geometry":{"type":"Polygon","coordinates":)"
      << R"([[[480050,4309950],[480090,4309950],[480090,4309910],[480050,4309910],[480050,4309950]]]}}]})";
  }
  const auto volume = [&](const std::string& direction) {
    const fs::path out = work_dir() / ("direction_" + direction);
    fs::remove_all(out);
    const auto r =
        run(plane.string() + " --release " + poly.string() + " --set release.thickness_direction=" + direction +
            " --duration 0.1 --out " + out.string() + " --quiet --threads 1");
    EXPECT_EQ(r.code, 0) << r.output;
    std::ifstream in(out / "summary.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["release_thickness_direction"], direction);
    return j["volumes_m3"]["release_read"].get<double>();
  };
  EXPECT_NEAR(volume("vertical"), 1600.0, 1e-9);
  EXPECT_NEAR(volume("normal"), 1600.0 * std::sqrt(1.25), 1e-9);
}

namespace {

/// A GeoJSON polygon layer (EPSG:32654, the tiny valley's CRS) of axis-aligned boxes
/// [xmin, xmax] × [ymin, ymax] with one set of properties each (a JSON object body).
void write_boxes(const fs::path& path, const std::vector<std::pair<std::array<double, 4>, std::string>>& boxes) {
  std::ofstream f(path);
  f << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32654"}},)"
    << R"("features":[)";
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    const auto& [b, props] = boxes[k];
    f << (k ? "," : "") << R"({"type":"Feature","properties":{)" << props
      << R"(},"geometry":{"type":"Polygon","coordinates":[[)" << std::setprecision(12) << "[" << b[0] << "," << b[2]
      << "],[" << b[1] << "," << b[2] << "],[" << b[1] << "," << b[3] << "],[" << b[0] << "," << b[3] << "],[" << b[0]
      << "," << b[2] << "]]]}}";
  }
  f << "]}";
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
}

}  // namespace

// The tiny valley with every process of docs/runout.md "Processes": an erodible channel reach
// (growth law), a rougher fan (Manning n zone) and a forest on it. Outputs and the volume budget
// release + entrained = deposited + mobile + lost.
TEST(DebrisRunoutApp, ProcessesRunEndToEndAndBalanceVolume) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  write_boxes(d / "erodible.geojson", {{{480080, 480300, 4309835, 4309915}, R"("depth":0.5)"}});
  write_boxes(d / "zones.geojson", {{{480300, 480500, 4309750, 4310000}, R"("n":0.1)"}});
  write_boxes(d / "forest.geojson",
              {{{480350, 480450, 4309750, 4310000}, R"("stem_density":0.1,"stem_diameter":0.3)"}});
  const fs::path out = d / "processes_out";
  fs::remove_all(out);
  const auto r = run(
      dsm.string() + " --release " + (d / "tiny_release.tif").string() + " --d0 2.5 --h0 0.75 --duration 60 --out " +
      out.string() + " --quiet --threads 1" + " --set entrainment.law=growth --set entrainment.growth_rate=0.005" +
      " --set entrainment.file=" + (d / "erodible.geojson").string() +
      " --set zones.file=" + (d / "zones.geojson").string() + " --set forest.file=" + (d / "forest.geojson").string());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"erosion_depth.tif", "erosion_depth.png"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  const auto& v = j["volumes_m3"];
  const double read = v["release_read"], entrained = v["entrained"];
  EXPECT_GT(entrained, 0.05 * read);  // 220 m of erodible channel at E_s = 0.005/m: ≈ × 3 if all of it ran through
  EXPECT_NEAR(v["deposited"].get<double>() + v["mobile"].get<double>() + v["lost"].get<double>(), read + entrained,
              1e-9 * (read + entrained));
  const auto& p = j["processes"];
  EXPECT_EQ(p["entrainment"]["law"], "growth");
  EXPECT_NEAR(p["entrainment"]["entrained_volume_m3"].get<double>(), entrained, 1e-9 * entrained);
  EXPECT_LE(p["entrainment"]["max_eroded_depth_m"].get<double>(), 0.5 + 1e-12);
  EXPECT_EQ(p["friction_zones"]["coefficients"], nlohmann::json::array({"n"}));
  // Forest: 100 m × 250 m of cells with k_f = ½ · 1 · 0.1 · 0.3 = 0.015 1/m.
  EXPECT_NEAR(p["forest"]["area_m2"].get<double>(), 100.0 * 250.0, 0.03 * 100.0 * 250.0);
  EXPECT_NEAR(p["forest"]["max_drag_per_m"].get<double>(), 0.015, 1e-12);
  // The eroded depth raster integrates to the entrained volume.
  const geohaz::Raster e = geohaz::read_raster(out / "erosion_depth.tif");
  double sum = 0.0;
  for (double x : e.data)
    if (!e.is_nodata(x)) sum += x * e.cell_size_x() * e.cell_size_y();
  EXPECT_NEAR(sum, entrained, 1e-5 * entrained);  // float32 raster
}

// An inflow hydrograph alone (no release): the injected volume is ∫Q dt and the budget closes.
TEST(DebrisRunoutApp, HydrographInflowDeliversItsVolume) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  write_text(d / "hydrograph.csv", "time_s,discharge_m3_per_s\n0,0\n5,10\n20,0\n");  // 100 m³
  const fs::path out = d / "hydrograph_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --d0 2.5 --h0 0.75 --duration 60 --out " + out.string() + " --quiet --threads 1" +
                     " --set inflow.hydrograph=" + (d / "hydrograph.csv").string() +
                     " --set inflow.points=[480040,4309880,480040,4309890] --set inflow.speed=3");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  const auto& v = j["volumes_m3"];
  EXPECT_NEAR(v["injected"].get<double>(), 100.0, 1e-9 * 100.0);
  EXPECT_NEAR(j["processes"]["inflow"]["volume_of_table_m3"].get<double>(), 100.0, 1e-12);
  EXPECT_NEAR(v["deposited"].get<double>() + v["mobile"].get<double>() + v["lost"].get<double>(), 100.0, 1e-9 * 100.0);
  EXPECT_GT(j["runout_length_along_path_m"].get<double>(), 50.0);  // it flowed down the valley
}

TEST(DebrisRunoutApp, BadProcessInputsExitTwoAndWriteNothing) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  const std::string rel = " --release " + (d / "tiny_release.tif").string();
  write_boxes(d / "erodible_negative.geojson", {{{480080, 480300, 4309835, 4309915}, R"("depth":-1)"}});
  write_boxes(d / "erodible_ok.geojson", {{{480080, 480300, 4309835, 4309915}, R"("depth":1)"}});
  write_text(d / "q_not_increasing.csv", "time_s,discharge_m3_s\n0,0\n10,5\n10,3\n");
  write_text(d / "q_negative.csv", "0,0\n10,-5\n20,0\n");
  write_text(d / "q_ok.csv", "0,0\n10,5\n20,0\n");
  const std::string inflow = " --set inflow.points=[480040,4309880]";
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {rel + " --set entrainment.law=growth --set entrainment.growth_rate=0.01 --set entrainment.file=" +
           (d / "erodible_negative.geojson").string(),
       "depth"},
      {rel + " --set entrainment.law=growth --set entrainment.growth_rate=-0.01", "entrainment.growth_rate"},
      {rel + " --set entrainment.law=growth --set entrainment.growth_rate=0.01", "entrainment.file"},
      {rel + " --set entrainment.file=" + (d / "erodible_ok.geojson").string(), "entrainment.law"},
      {rel + " --set entrainment.law=shear --set entrainment.file=" + (d / "erodible_ok.geojson").string(),
       "entrainment.coefficient"},
      {" --set inflow.hydrograph=" + (d / "q_not_increasing.csv").string() + inflow, "line 4"},
      {" --set inflow.hydrograph=" + (d / "q_negative.csv").string() + inflow, "negative discharge"},
      {" --set inflow.hydrograph=" + (d / "q_ok.csv").string() + " --set inflow.points=[100,100]", "inflow.points"},
      {" --set inflow.hydrograph=" + (d / "q_ok.csv").string(), "inflow.points"},
      {rel + " --set forest.drag_coefficient=-1", "forest.drag_coefficient"},
      {rel + " --set zones.mu=" + (d / "tiny_release.tif").string(), "zones.mu"},
      {rel + " --set intensity.pressure_classes=[30000,3000]", "intensity.pressure_classes"},
      {rel + " --set intensity.pressure_classes=[-1,3000]", "intensity.pressure_classes"},
      {rel + " --set intensity.strong_depth=-1", "intensity.strong_depth"},
      {rel + " --set intensity.scheme=colour", "intensity.scheme"},
  };
  const fs::path out = d / "bad_process_out";
  for (const auto& c : cases) {
    fs::remove_all(out);
    const auto r = run(dsm.string() + c.args + " --out " + out.string() + " --quiet");
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_FALSE(dir_has_files(out)) << c.args;
  }
}

// An erodible-depth raster on a coarser grid than the DSM is sampled at the DSM cell centres with a
// note; the shear law erodes only where the flow's basal shear exceeds τ_c.
TEST(DebrisRunoutApp, ErodibleRasterOnAnotherGridIsResampled) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  const geohaz::Raster t = geohaz::read_raster(dsm);
  geohaz::Raster e;  // 10 m cells over the DSM's extent (the DSM has 2.5 m), 0.3 m deep below x = 480250
  e.nx = t.nx / 4;
  e.ny = t.ny / 4;
  e.geotransform = {t.geotransform[0], 10.0, 0.0, t.geotransform[3], 0.0, -10.0};
  e.crs_wkt = t.crs_wkt;
  e.nodata = -9999.0;
  e.data.assign(static_cast<std::size_t>(e.nx) * e.ny, -9999.0);
  for (int r = 0; r < e.ny; ++r)
    for (int c = 0; c < e.nx; ++c)
      if (e.cell_centre(c, r).x() < 480250.0) e.at(c, r) = 0.3;
  geohaz::write_geotiff(d / "erodible_coarse.tif", e);
  const fs::path out = d / "erodible_raster_out";
  fs::remove_all(out);
  const auto r = run(
      dsm.string() + " --release " + (d / "tiny_release.tif").string() + " --d0 2.5 --h0 0.75 --duration 40 --out " +
      out.string() + " --threads 1" + " --set entrainment.law=shear --set entrainment.critical_shear=500" +
      " --set entrainment.coefficient=1e-6 --set entrainment.file=" + (d / "erodible_coarse.tif").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("another grid"), std::string::npos) << r.output;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  EXPECT_GT(j["volumes_m3"]["entrained"].get<double>(), 0.0);
  EXPECT_LE(j["processes"]["entrainment"]["max_eroded_depth_m"].get<double>(), 0.3 + 1e-12);
  const geohaz::Raster ero = geohaz::read_raster(out / "erosion_depth.tif");
  for (int rr = 0; rr < ero.ny; ++rr)
    for (int c = 0; c < ero.nx; ++c)
      if (ero.cell_centre(c, rr).x() > 480250.0) {
        EXPECT_EQ(ero.at(c, rr), 0.0) << c << ", " << rr;
      }
}

namespace {

/// A GeoJSON layer (EPSG:32654) of features of one geometry type (`type`: "LineString", "Point",
/// …) with the given coordinates JSON and properties each.
void write_features(const fs::path& path, const std::string& type,
                    const std::vector<std::pair<std::string, std::string>>& features) {
  std::ofstream f(path);
  f << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32654"}},)"
    << R"("features":[)";
  for (std::size_t k = 0; k < features.size(); ++k)
    f << (k ? "," : "") << R"({"type":"Feature","properties":{)" << features[k].second << R"(},"geometry":{"type":")"
      << type << R"(","coordinates":)" << features[k].first << "}}";
  f << "]}";
}

}  // namespace

// A 2 m check dam across the tiny valley's channel: the run writes its force series and the
// barriers block of summary.json; the retained and overtopped volumes do not exceed the release, and
// the flow's volume budget still closes.
TEST(DebrisRunoutApp, BarrierAcrossTheChannelWritesItsForceSeries) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  write_features(d / "dam.geojson", "LineString", {{"[[480250,4309800],[480250,4309950]]", R"("height":2)"}});
  const fs::path out = d / "barrier_out";
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release " + (d / "tiny_release.tif").string() +
                     " --d0 2.5 --h0 0.75 --duration 60 --out " + out.string() + " --quiet --threads 1" +
                     " --set barriers.file=" + (d / "dam.geojson").string());
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(out / "barriers" / "barrier_0.csv"));
  std::ifstream csv(out / "barriers" / "barrier_0.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("time_s,force_N,force_per_m_N_m,", 0), 0u) << header;
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  ASSERT_EQ(j["barriers"].size(), 1u);
  const auto& b = j["barriers"][0];
  EXPECT_EQ(b["name"], "barrier_0");
  EXPECT_DOUBLE_EQ(b["crest_height_m"].get<double>(), 2.0);
  EXPECT_NEAR(b["length_m"].get<double>(), 150.0, 1e-9);
  EXPECT_EQ(b["vertices_xy_m"].size(), 2u);
  const double read = j["volumes_m3"]["release_read"];
  const double retained = b["retained_volume_m3"], over = b["overtopped_volume_m3"];
  EXPECT_GT(b["peak_force_n"].get<double>(), 0.0);  // the flow reached it
  EXPECT_GT(retained, 0.0);
  EXPECT_LE(retained + over, read * (1.0 + 1e-9));
  const auto& v = j["volumes_m3"];
  EXPECT_NEAR(v["deposited"].get<double>() + v["mobile"].get<double>() + v["lost"].get<double>(), read, 1e-9 * read);
}

// A barrier line leaving the DSM, a negative or missing crest height, a permeability of 1, a file of
// points or of polygons: exit 2 naming the file, the feature and the value; nothing written.
TEST(DebrisRunoutApp, BadBarrierInputsExitTwoAndWriteNothing) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  const std::string rel = " --release " + (d / "tiny_release.tif").string();
  write_features(d / "dam_outside.geojson", "LineString", {{"[[480250,4309800],[480250,4319950]]", R"("height":2)"}});
  write_features(d / "dam_negative.geojson", "LineString",
                 {{"[[480250,4309800],[480250,4309950]]", R"("height":2)"},
                  {"[[480300,4309800],[480300,4309950]]", R"("height":-1)"}});
  write_features(d / "dam_noheight.geojson", "LineString", {{"[[480250,4309800],[480250,4309950]]", R"("name":"a")"}});
  write_features(d / "dam_open.geojson", "LineString",
                 {{"[[480250,4309800],[480250,4309950]]", R"("height":2,"permeability":1)"}});
  write_features(d / "dam_points.geojson", "Point", {{"[480250,4309800]", R"("height":2)"}});
  write_boxes(d / "dam_polygons.geojson", {{{480250, 480260, 4309800, 4309950}, R"("height":2)"}});
  struct Case {
    std::string file;
    std::vector<std::string> expect;
  };
  const std::vector<Case> cases = {
      {"dam_outside.geojson", {"feature 0", "leaves the DSM", "480250.0, 4"}},
      {"dam_negative.geojson", {"feature 1", "(0, 100]", "-1"}},
      {"dam_noheight.geojson", {"barriers.height"}},
      {"dam_open.geojson", {"feature 0", "[0, 1)", "permeability"}},
      {"dam_points.geojson", {"feature 0", "Point", "not a line"}},
      {"dam_polygons.geojson", {"feature 0", "Polygon", "not a line"}},
  };
  const fs::path out = d / "bad_barrier_out";
  for (const auto& c : cases) {
    fs::remove_all(out);
    const auto r = run(dsm.string() + rel + " --set barriers.file=" + (d / c.file).string() + " --out " + out.string() +
                       " --quiet");
    EXPECT_EQ(r.code, 2) << c.file << "\n" << r.output;
    for (const auto& e : c.expect)
      EXPECT_NE(r.output.find(e), std::string::npos) << c.file << ": " << e << "\n" << r.output;
    EXPECT_NE(r.output.find(c.file), std::string::npos) << r.output;
    EXPECT_FALSE(dir_has_files(out)) << c.file;
  }
  // A negative default height is refused by the config's range.
  fs::remove_all(out);
  const auto r = run(dsm.string() + rel + " --set barriers.file=" + (d / "dam_noheight.geojson").string() +
                     " --set barriers.height=-2 --out " + out.string() + " --quiet");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("barriers.height"), std::string::npos) << r.output;
  EXPECT_FALSE(dir_has_files(out));
}

// Gauges and a profile path (issue #33): a point and a cross-section across the channel, the
// profile along a straight line down the valley. gauges.csv in long format with a row per gauge
// every second; the section's cumulative volume is the summary's net volume and at most the
// release; profile.csv starts at the given path.
TEST(DebrisRunoutApp, GaugesAndProfilePathWriteTheirFiles) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  const fs::path cfg = d / "gauges.toml", out = d / "gauges_out";
  {
    std::ofstream f(cfg);
    f << "[output]\ngauge_interval = 1.0\nprofile_path = [480020.0, 4309875.0, 480480.0, 4309875.0]\n"
      << "[[output.gauges]]\nname = \"channel\"\npoint = [480200.0, 4309875.0]\n"
      << "[[output.gauges]]\nname = \"section\"\nline = [480250.0, 4309780.0, 480250.0, 4309970.0]\n";
  }
  fs::remove_all(out);
  const auto r = run(dsm.string() + " --release " + (d / "tiny_release.tif").string() + " --config " + cfg.string() +
                     " --d0 2.5 --h0 0.75 --duration 60 --out " + out.string() + " --quiet --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(out / "gauges.png"));
  std::ifstream csv(out / "gauges.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "gauge,t_s,depth_m,speed_m_per_s,discharge_m3_per_s,cumulative_volume_m3");
  int channel = 0, section = 0;
  double last_cumulative = 0.0, hmax = 0.0;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (cells[0] == "channel") {
      ++channel;
      hmax = std::max(hmax, std::stod(cells[2]));
    } else {
      ++section;
      ASSERT_EQ(cells.size(), 6u) << line;
      last_cumulative = std::stod(cells[5]);
    }
  }
  EXPECT_GE(channel, 60);  // t = 0 … 60 s every second
  EXPECT_EQ(section, channel);
  EXPECT_GT(hmax, 0.0);
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  ASSERT_EQ(j["gauges"].size(), 2u);
  EXPECT_EQ(j["gauges"][1]["kind"], "line");
  const double net = j["gauges"][1]["net_volume_m3"], read = j["volumes_m3"]["release_read"];
  EXPECT_NEAR(last_cumulative, net, 1e-6 * read);
  EXPECT_GT(net, 0.0);  // the flow went down the valley, across the section from west to east
  EXPECT_LE(net, read * (1.0 + 1e-9));
  std::ifstream prof(out / "profile.csv");
  std::getline(prof, line);
  std::getline(prof, line);
  EXPECT_EQ(line.rfind("0,480020,4309875,", 0), 0u) << line;
  // summary.json's profile block is the reach along this path, recomputed here from profile.csv:
  // the reached stations (peak depth > 1 cm, the default intensity.min_depth 0 raised to 1 cm),
  // the highest of them the top, the farthest the run-out point, H/L = (z_top − z_runout) /
  // (s_runout − s_top). The CSV holds 10 significant digits: 1e-8 relative.
  double s_top = 0.0, z_top = -1e300, s_run = -1.0, z_run = 0.0;
  do {
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) v.push_back(std::stod(c));
    ASSERT_EQ(v.size(), 8u) << line;
    if (!(v[4] > 0.01)) continue;
    if (v[3] > z_top) s_top = v[0], z_top = v[3];
    if (v[0] > s_run) s_run = v[0], z_run = v[3];
  } while (std::getline(prof, line));
  ASSERT_GT(s_run, s_top);
  const auto& pj = j["profile"];
  EXPECT_EQ(pj["path"], "given");
  EXPECT_EQ(pj["reached"], true);
  EXPECT_NEAR(pj["top_station_m"].get<double>(), s_top, 1e-8 * s_run);
  EXPECT_NEAR(pj["runout_station_m"].get<double>(), s_run, 1e-8 * s_run);
  EXPECT_NEAR(pj["drop_height_m"].get<double>(), z_top - z_run, 1e-8 * z_top);
  EXPECT_NEAR(pj["length_m"].get<double>(), s_run - s_top, 1e-8 * s_run);
  const double hl = (z_top - z_run) / (s_run - s_top);
  EXPECT_NEAR(pj["ratio_H_over_L"].get<double>(), hl, 1e-7 * hl);
  EXPECT_NEAR(pj["alpha_deg"].get<double>(), std::atan(hl) * 180.0 / M_PI, 1e-6);
  // The toe path's H/L is another number of the same run (another path), kept under its own name.
  EXPECT_TRUE(j["fahrboeschung"]["ratio_H_over_L"].is_number());
}

// The profile path from a vector file (output.profile_path_file): its first line, here a GeoJSON
// LineString in the tiny valley's CRS, gives the same profile as the same vertices written in the
// config (output.profile_path), station for station; both paths together exit 2.
TEST(DebrisRunoutApp, ProfilePathFromALineFileEqualsTheSameVerticesInTheConfig) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  const fs::path line_file = d / "profile_line.geojson";
  {
    std::ofstream f(line_file);
    f << R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32654"}},)"
      << R"("features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":)"
      << "[[480020.0,4309875.0],[480250.0,4309900.0],[480480.0,4309875.0]]}}]}";
  }
  const std::string base = dsm.string() + " --release " + (d / "tiny_release.tif").string() +
                           " --d0 2.5 --h0 0.75 --duration 30 --quiet --threads 1";
  auto read_all = [](const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  };
  const fs::path out_file = d / "profile_file_out", out_list = d / "profile_list_out";
  fs::remove_all(out_file);
  fs::remove_all(out_list);
  const auto a = run(base + " --set output.profile_path_file=" + line_file.string() + " --out " + out_file.string());
  ASSERT_EQ(a.code, 0) << a.output;
  const fs::path cfg = d / "profile_list.toml";
  {
    std::ofstream f(cfg);
    f << "[output]\nprofile_path = [480020.0, 4309875.0, 480250.0, 4309900.0, 480480.0, 4309875.0]\n";
  }
  const auto b = run(base + " --config " + cfg.string() + " --out " + out_list.string());
  ASSERT_EQ(b.code, 0) << b.output;
  const std::string pa = read_all(out_file / "profile.csv"), pb = read_all(out_list / "profile.csv");
  EXPECT_GT(std::count(pa.begin(), pa.end(), '\n'), 10);
  EXPECT_EQ(pa, pb);
  EXPECT_EQ(pa.find("0,480020,4309875,", pa.find('\n') + 1), pa.find('\n') + 1) << pa.substr(0, 200);
  // Both forms at once: exit 2 naming the key, nothing written.
  const fs::path out_both = d / "profile_both_out";
  fs::remove_all(out_both);
  const auto c =
      run(dsm.string() + " --release " + (d / "tiny_release.tif").string() + " --config " + cfg.string() +
          " --set output.profile_path_file=" + line_file.string() + " --out " + out_both.string() + " --quiet");
  EXPECT_EQ(c.code, 2) << c.output;
  EXPECT_NE(c.output.find("output.profile_path_file"), std::string::npos) << c.output;
  EXPECT_FALSE(dir_has_files(out_both));
}

// Bad gauges and profile paths: exit 2 naming the file, the key and the value, nothing written.
TEST(DebrisRunoutApp, BadGaugeInputsExitTwoAndWriteNothing) {
  const fs::path dsm = tiny_dsm(), d = work_dir();
  const std::string base = dsm.string() + " --release " + (d / "tiny_release.tif").string();
  struct Case {
    std::string toml;
    std::vector<std::string> expect;
  };
  const std::vector<Case> cases = {
      {"[[output.gauges]]\nname = \"far\"\npoint = [490000.0, 4309875.0]\n",
       {"output.gauges[0].point", "490000.0", "x in [480000.0, 480500.0]", "off the terrain"}},
      {"[[output.gauges]]\nname = \"short\"\nline = [480250.0, 4309780.0]\n",
       {"output.gauges[0].line", "2 numbers", "two or more vertices"}},
      {"[[output.gauges]]\nname = \"odd\"\nline = [480250.0, 4309780.0, 480250.0]\n", {"output.gauges[0].line"}},
      {"[output]\ngauge_interval = 0.0\n", {"output.gauge_interval", "(0, 1e+06]"}},
      {"[output]\ngauge_interval = -1.0\n", {"output.gauge_interval"}},
      {"[[output.gauges]]\nname = \"x\"\npoint = [480200.0, 4309875.0]\nradius = 3\n", {"radius"}},
      {"[[output.gauges]]\nname = \"both\"\npoint = [480200.0, 4309875.0]\nline = [480250.0, 4309780.0, 480250.0, "
       "4309970.0]\n",
       {"output.gauges[0]", "not both"}},
      {"[[output.gauges]]\npoint = [480200.0, 4309875.0]\n", {"output.gauges[0].name"}},
      {"[[output.gauges]]\nname = \"a\"\npoint = [480200.0, 4309875.0]\n[[output.gauges]]\nname = \"a\"\npoint = "
       "[480210.0, 4309875.0]\n",
       {"output.gauges[1].name", "unique"}},
      {"[output]\nprofile_path = [480020.0, 4309875.0, 481000.0, 4309875.0]\n",
       {"output.profile_path", "leaves the terrain", "x in [480000.0, 480500.0]"}},
      {"[output]\nprofile_path = [480020.0, 4309875.0]\n", {"output.profile_path", "two or more vertices"}},
  };
  const fs::path cfg = d / "bad_gauges.toml", out = d / "bad_gauges_out";
  for (const auto& c : cases) {
    {
      std::ofstream f(cfg);
      f << c.toml;
    }
    fs::remove_all(out);
    const auto r = run(base + " --config " + cfg.string() + " --out " + out.string() + " --quiet");
    EXPECT_EQ(r.code, 2) << c.toml << "\n" << r.output;
    EXPECT_NE(r.output.find("bad_gauges.toml"), std::string::npos) << c.toml << "\n" << r.output;
    for (const auto& e : c.expect) EXPECT_NE(r.output.find(e), std::string::npos) << e << " in\n" << r.output;
    EXPECT_FALSE(dir_has_files(out)) << c.toml;
  }
}
