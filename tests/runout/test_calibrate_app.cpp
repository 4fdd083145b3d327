// Regression tests of the geohaz-calibrate app (issue #31) on the small synthetic event of
// calibration_case.hpp (Manning n and i_cr searched):
//  - 1 rank and 2 ranks (mpirun -np 2) evaluate the same members and give the same best set;
//  - a run killed with SIGKILL and rerun gives the uninterrupted result without running a member twice;
//  - a member forced to fail is recorded with its parameters and penalised, the search goes on;
//  - the best set is a debris-runout config that reads back with the best values;
//  - bad input (bounds reversed, unknown key, observation outside the DSM, on another grid or CRS):
//    exit 2 naming the key, nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "calibration_case.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"
#include "geohaz/runout/run.hpp"
#include "member_app_support.hpp"
#include "run_command.hpp"

namespace fs = std::filesystem;
using member_app::slurp;
using member_app::summary;

namespace {

const char* const kModel = "friction = \"manning\"\nn = 0.06\nicr = 0.15\nd0 = 5.0\nh0 = 0.5\ndensity = 1800.0";
const char* const kParameters =
    "[[calibration.parameter]]\nkey = \"model.n\"\nmin = 0.03\nmax = 0.12\nscale = \"log\"\n"
    "[[calibration.parameter]]\nkey = \"model.icr\"\nmin = 0.08\nmax = 0.3\n";
const char* const kSearch =
    "global_members = 6\nmorris_trajectories = 1\nlocal_starts = 2\nlocal_evaluations = 6\nlocal_algorithm = "
    "\"bobyqa\"\n";

calibration_case::Case make_case(const std::string& name, const std::string& extra = "") {
  auto c = calibration_case::make(member_app::work_dir("calibrate_app_work", name), kModel,
                                  {"model.n=0.06", "model.icr=0.15"});
  std::ofstream(c.dir / "cal.toml") << calibration_case::config(c, kParameters, std::string(kSearch) + extra);
  return c;
}

std::string app(const std::string& args) {
  return member_app::command(GEOHAZ_CALIBRATE_EXE, args);
}

}  // namespace

TEST(CalibrateApp, OneAndTwoRanksGiveTheSameMembersAndBestSet) {
  if (!member_app::have_mpi()) GTEST_SKIP() << "built without MPI";
  const auto c = make_case("ranks");
  const std::string args = (c.dir / "cal.toml").string() + " --threads 1 --quiet --out ";
  const auto r1 = geohaz::testing::run_command(app(args + (c.dir / "one").string()));
  ASSERT_EQ(r1.code, 0) << r1.output;
  const auto r2 =
      geohaz::testing::run_command(member_app::mpirun(GEOHAZ_CALIBRATE_EXE, 2, args + (c.dir / "two").string()));
  ASSERT_EQ(r2.code, 0) << r2.output;
  // members.csv holds every member's values, score and misfit terms at full precision.
  EXPECT_EQ(slurp(c.dir / "one" / "members.csv"), slurp(c.dir / "two" / "members.csv"));
  const auto j1 = summary(c.dir / "one"), j2 = summary(c.dir / "two");
  EXPECT_EQ(j1["best"], j2["best"]);
  EXPECT_EQ(j2["ranks"].get<int>(), 2);
  // Rank 1 ran members (its member.json says so).
  int on_rank1 = 0;
  for (const auto& e : fs::directory_iterator(c.dir / "two" / "members"))
    on_rank1 += nlohmann::json::parse(slurp(e.path() / "member.json"))["rank"].get<int>() == 1;
  EXPECT_GT(on_rank1, 0);
  fs::remove_all(c.dir);
}

TEST(CalibrateApp, KilledAndResumedRunGivesTheUninterruptedResultWithoutRerunningMembers) {
  const auto c = make_case("resume");
  const std::string cfg = (c.dir / "cal.toml").string();
  const fs::path whole = c.dir / "whole", resumed = c.dir / "resumed";
  const auto r = geohaz::testing::run_command(app(cfg + " --threads 1 --quiet --out " + whole.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  const auto done = [&] {
    std::map<std::string, std::string> m;
    if (!fs::exists(resumed / "members")) return m;
    for (const auto& e : fs::directory_iterator(resumed / "members"))
      if (fs::exists(e.path() / "member.json"))
        m[e.path().filename().string()] = slurp(e.path() / "member.json") + slurp(e.path() / "misfit.json");
    return m;
  };
  EXPECT_TRUE(member_app::kill_when(GEOHAZ_CALIBRATE_EXE, {cfg, "--threads", "1", "--quiet", "--out", resumed.string()},
                                    [&] { return done().size() >= 8; }))
      << "the run ended before it was killed";
  const auto before = done();
  EXPECT_GE(before.size(), 8u);
  const auto r2 = geohaz::testing::run_command(app(cfg + " --threads 1 --out " + resumed.string()));
  ASSERT_EQ(r2.code, 0) << r2.output;
  EXPECT_NE(r2.output.find("found on disk"), std::string::npos) << r2.output;
  // The members finished before the kill are untouched (a rerun would rewrite its wall time).
  const auto after = done();
  for (const auto& [name, text] : before) EXPECT_EQ(after.at(name), text) << name;
  EXPECT_EQ(slurp(whole / "members.csv"), slurp(resumed / "members.csv"));
  EXPECT_EQ(summary(whole)["best"], summary(resumed)["best"]);
  fs::remove_all(c.dir);
}

TEST(CalibrateApp, FailedMemberIsRecordedWithItsParametersAndPenalised) {
  const auto c = make_case("failed", "inject_failure = [2]\n");
  const fs::path out = c.dir / "out";
  // An observed run-out point: the thalweg's vertex 28 (the config ends in [observation]), so its
  // station along the thalweg is the length of the polyline up to it.
  const auto line = nlohmann::json::parse(slurp(c.thalweg))["features"][0]["geometry"]["coordinates"];
  double s_point = 0.0;
  for (int k = 1; k <= 28; ++k)
    s_point += std::hypot(line[k][0].get<double>() - line[k - 1][0].get<double>(),
                          line[k][1].get<double>() - line[k - 1][1].get<double>());
  std::ofstream(c.dir / "cal.toml", std::ios::app)
      << std::setprecision(12) << "runout_point = [" << line[28][0].get<double>() << ", " << line[28][1].get<double>()
      << "]\n";
  const auto r =
      geohaz::testing::run_command(app((c.dir / "cal.toml").string() + " --threads 1 --out " + out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("member 2 (design)"), std::string::npos) << r.output;
  const auto j = summary(out);
  ASSERT_EQ(j["failed"].size(), 1u);
  EXPECT_EQ(j["failed"][0]["member"].get<int>(), 2);
  EXPECT_EQ(j["failed"][0]["values"].size(), 2u);
  EXPECT_NE(j["failed"][0]["diagnosis"].get<std::string>().find("injected"), std::string::npos);
  EXPECT_NE(j["best"]["member"].get<int>(), 2);
  const std::string csv = slurp(out / "members.csv");
  EXPECT_NE(csv.find("\n2,design,0,failed,"), std::string::npos) << csv;
  // The outputs, and the best set as a config that reads back with the best values.
  for (const char* f : {"best.toml", "members.csv", "acceptable.csv", "acceptable.svg", "sensitivity.csv",
                        "comparison.tif", "comparison.png", "comparison.qml", "thalweg_profile.csv"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  geohaz::ConfigReader best = geohaz::ConfigReader::from_file(out / "best.toml");
  (void)geohaz::runout::read_config(best);
  best.finish();
  geohaz::ConfigReader again = geohaz::ConfigReader::from_file(out / "best.toml");
  EXPECT_EQ(again.get("model.n", 0.0, geohaz::Range{}, {"", ""}), j["best"]["values"][0].get<double>());
  EXPECT_EQ(again.get("model.icr", 0.0, geohaz::Range{}, {"", ""}), j["best"]["values"][1].get<double>());
  // The best member's long profile along the thalweg with the observed run-out marked beside the
  // modelled one (issue #33): stations from 0 along the thalweg, the observed run-out at the
  // point's station, the mark drawn in its colour (a vertical line of the upper panel's 700 px,
  // 3 px wide, on whole pixels: 2100 pixels, at least half of them where the modelled run-out's
  // dashed line falls on the same station).
  EXPECT_EQ(j["observation"]["runout_from"], "runout_point");
  EXPECT_NEAR(j["observation"]["runout_s_m"].get<double>(), s_point, 1e-6 * s_point);
  const auto& outputs = j["outputs"];
  for (const char* f : {"profile.csv", "profile.png"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
    EXPECT_NE(std::find(outputs.begin(), outputs.end(), f), outputs.end()) << f;
  }
  const std::string prof = slurp(out / "profile.csv");
  EXPECT_EQ(prof.find("s_along_path_m,x_m,y_m,terrain_elevation_m,max_depth_m,"), 0u);
  EXPECT_EQ(prof.find("\n0,", 0), prof.find('\n'));  // the first station at the thalweg's start
  const geohaz::Image img = geohaz::read_image(out / "profile.png");
  int observed_mark = 0;
  for (std::size_t k = 0; k + 2 < img.rgb.size(); k += 3)
    observed_mark += img.rgb[k] == 31 && img.rgb[k + 1] == 119 && img.rgb[k + 2] == 180;
  EXPECT_GT(observed_mark, 1000);
  const geohaz::Raster cmp = geohaz::read_raster(out / "comparison.tif");
  int tp = 0;
  for (double v : cmp.data) tp += v == 1.0;
  EXPECT_NEAR(tp * 25.0, j["best"]["misfit"]["tp_m2"].get<double>(), 1e-6);
#ifdef GEOHAZ_REPORT_EXE
  // The report page of this folder (issue #31: "all in the report page"): the back-analysis part
  // with the best member, the failed one counted, the acceptable set, the Morris table, the map
  // (which passes the page's map check) and the two thalweg profile plots.
  const auto rep = geohaz::testing::run_command(std::string(GEOHAZ_REPORT_EXE) + " " + out.string());
  ASSERT_EQ(rep.code, 0) << rep.output;
  const std::string html = slurp(out / "report.html");
  EXPECT_NE(html.find("<h2>Back-analysis (geohaz-calibrate)</h2>"), std::string::npos);
  EXPECT_NE(html.find("<p>Member " + std::to_string(j["best"]["member"].get<int>()) + " ("), std::string::npos);
  EXPECT_NE(html.find("local; 1 failed)"), std::string::npos);
  EXPECT_NE(html.find(std::to_string(j["acceptable_members"].get<int>()) + " successful member(s) with J"),
            std::string::npos);
  for (const char* part : {"<table class=calibration-acceptable>", "<table class=calibration-morris>",
                           "src=\"comparison.png\"", "src=\"acceptable.svg\"", "href=\"best.toml\""})
    EXPECT_NE(html.find(part), std::string::npos) << part;
  EXPECT_EQ(html.find("class=map-problem"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "report_files" / "out_thalweg_width.svg"));
  EXPECT_TRUE(fs::exists(out / "report_files" / "out_thalweg_deposit.svg"));
  EXPECT_NE(html.find("src=\"profile.png\""), std::string::npos);                  // the long profile, in the part
  EXPECT_EQ(html.find("src=\"profile.png\""), html.rfind("src=\"profile.png\""));  // once
#endif
  fs::remove_all(c.dir);
}

TEST(CalibrateApp, BadInputExitsWithTwoNamingTheKeyAndWritesNothing) {
  const auto c = make_case("bad");
  // A footprint on another grid (cells twice as large) and one in another CRS (UTM 33N).
  {
    geohaz::Raster f = geohaz::read_raster(c.footprint);
    geohaz::Raster coarse = f;
    coarse.nx = f.nx / 2, coarse.ny = f.ny / 2;
    coarse.geotransform[1] *= 2, coarse.geotransform[5] *= 2;
    coarse.data.assign(static_cast<std::size_t>(coarse.nx) * coarse.ny, 1.0);
    geohaz::write_geotiff(c.dir / "coarse.tif", coarse);
    std::string wkt = f.crs_wkt;
    for (const auto& [a, b] : {std::pair<std::string, std::string>{"54N", "33N"},
                               {"\"central_meridian\",141", "\"central_meridian\",15"},
                               {"32654", "32633"}})
      if (const auto k = wkt.find(a); k != std::string::npos) wkt.replace(k, a.size(), b);
    f.crs_wkt = wkt;
    geohaz::write_geotiff(c.dir / "utm33.tif", f);
  }
  const std::string cfg = (c.dir / "cal.toml").string() + " --out " + (c.dir / "never").string();
  const std::pair<std::string, std::string> sets[] = {
      {"calibration.parameter[1].min=0.4", "calibration.parameter[1].min"},
      {"calibration.parameter[0].key=\"model.n_typo\"", "model.n_typo"},
      {"calibration.parameter[0].min=0.001", "calibration.parameter[0].min"},  // below model.n's range
      {"observation.runout_point=[0.0, 0.0]", "observation.runout_point"},
      {"observation.footprint=\"" + (c.dir / "coarse.tif").string() + "\"", "another grid"},
      {"observation.footprint=\"" + (c.dir / "utm33.tif").string() + "\"", "another CRS"},
      {"calibration.local_algorithm=\"bobyqa\"", ""},  // valid: checks the loop itself by passing
  };
  for (const auto& [set, key] : sets) {
    if (key.empty()) continue;
    const auto r = geohaz::testing::run_command(app(cfg + " --set '" + set + "'"));
    EXPECT_EQ(r.code, 2) << set << "\n" << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(c.dir / "never")) << set;
  }
  fs::remove_all(c.dir);
}
