// Regression tests of the geohaz-ensemble app on a small analytic case: a single block (one
// particle) released at rest on a 1:2 slope above a flat run-out, Coulomb friction μ uncertain.
//  - Analytic probability: the stopping distance on the flat is s(μ) = L (tan θ − μ)/μ (energy:
//    S² = 2 g L (tan θ − μ) at the break, L the horizontal slope length, then S²/(2 μ g); the bed
//    constraint turns the velocity at the break keeping its magnitude when the curvature term is
//    off). A cell centre at x on the flat, on the particle's row, is painted when x ≤ s + r (r =
//    max(d0/2, cell) = 0.5 m), so with μ uniform on [a, b], P(reach x) = P(μ ≤ L tan θ/(L + x − r)).
//    The ensemble's exceedance map (Monte Carlo) must lie within 3σ = 3 √(p(1−p)/N) of it.
//  - 1 rank and 2 ranks (mpirun -np 2) give bit-identical aggregated rasters.
//  - A member forced to fail is reported and the maps use the others.
//  - A killed and resumed ensemble gives the same maps as an uninterrupted one.
//  - Bad input: exit 2 naming the key, nothing written.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "ensemble_case.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/synthetic_terrain.hpp"
#include "member_app_support.hpp"
#include "run_command.hpp"

namespace fs = std::filesystem;
using member_app::summary;

namespace {

using namespace ensemble_case;

fs::path work_dir() {
  return member_app::work_dir("ensemble_work", "ensemble");
}

std::string app(const std::string& args) {
  return member_app::command(GEOHAZ_ENSEMBLE_EXE, args);
}

geohaz::Raster read(const fs::path& p) {
  return geohaz::read_raster(p, geohaz::CrsPolicy::Any);
}

/// Every product raster of two output folders, value for value.
void expect_same_products(const fs::path& a, const fs::path& b) {
  const auto ja = summary(a);
  ASSERT_FALSE(ja["products"].empty());
  for (const auto& name : ja["products"]) {
    const auto ra = read(a / name.get<std::string>()), rb = read(b / name.get<std::string>());
    EXPECT_EQ(ra.data, rb.data) << name;
  }
}

}  // namespace

TEST(EnsembleApp, ExceedanceMatchesTheAnalyticStoppingDistribution) {
  const fs::path d = work_dir();
  make_case(d);
  const int n = 64;
  write_ensemble(d / "ens.toml", n, "monte_carlo");
  const fs::path out = d / "mc";
  const auto r =
      geohaz::testing::run_command(app((d / "ens.toml").string() + " --out " + out.string() + " --threads 1 --quiet"));
  ASSERT_EQ(r.code, 0) << r.output;
  // Per member: the toe's horizontal distance from the release is L tan θ/μ (slope L + flat s).
  std::ifstream csv(out / "members.csv");
  std::string line;
  std::getline(csv, line);
  const double x_rel = kX0 + 10.5 * kCell;  // centre of the release cell
  const double L = -x_rel;
  int rows = 0;
  std::vector<double> mus;
  while (std::getline(csv, line)) {
    std::stringstream s(line);
    std::string f[6];
    for (auto& x : f) std::getline(s, x, ',');
    ASSERT_EQ(f[1], "ok");
    const double mu = std::stod(f[2]), reach = std::stod(f[5]);
    // The step across the break mixes the two slopes over S·dt ≤ 0.06 m (S ≤ 11 m/s, dt ≤ 5 ms); the bilinear DSM
    // rounds the break over one cell (0.5 m): 0.3 m.
    EXPECT_NEAR(reach, L * kTanTheta / mu, 0.3) << "mu " << mu;
    mus.push_back(mu);
    ++rows;
  }
  EXPECT_EQ(rows, n);
  const auto p = read(out / "prob_max_depth_gt_1e-06m.tif");
  const int row = kNy / 2;
  int checked = 0;
  for (int c = 0; c < kNx; ++c) {
    const double x = kX0 + (c + 0.5) * kCell;
    if (x < 1.0) continue;  // the flat only
    const double mu_star = L * kTanTheta / (L + x - kRadius);
    const double exact = std::clamp((mu_star - kMuA) / (kMuB - kMuA), 0.0, 1.0);
    const double sigma = std::sqrt(std::max(exact * (1.0 - exact), 1.0 / n) / n);
    EXPECT_LE(std::abs(p.at(c, row) - exact), 3.0 * sigma) << "x = " << x << " exact " << exact;
    // Sharper: the map counts exactly the members whose analytic stop s(μ_i) + r lies beyond x,
    // give or take those within the 0.3 m of the reach tolerance.
    int surely = 0, possibly = 0;
    for (double mu : mus) {
      const double s_mu = L * (kTanTheta - mu) / mu;
      surely += s_mu + kRadius >= x + 0.3;
      possibly += s_mu + kRadius >= x - 0.3;
    }
    EXPECT_GE(p.at(c, row) * n, surely - 1e-4) << "x = " << x;
    EXPECT_LE(p.at(c, row) * n, possibly + 1e-4) << "x = " << x;
    ++checked;
  }
  EXPECT_GT(checked, 50);
  const auto j = summary(out);
  EXPECT_EQ(j["succeeded"].get<int>(), n);
  EXPECT_EQ(j["model"], "geohaz-ensemble");
  // Every probability map drawn (issue #33); the distributions are drawn by geohaz-report.
  for (const char* f :
       {"members.csv", "mean_max_depth.tif", "p50_max_speed.tif", "p90_max_pressure.tif",
        "prob_max_depth_gt_1e-06m.qml", "prob_max_depth_gt_1e-06m.png", "prob_max_pressure_gt_1000Pa.png",
        "prob_intensity_ge_2.png", "mean_max_depth.png", "p90_max_depth.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  fs::remove_all(d);
}

TEST(EnsembleApp, OneAndTwoRanksGiveIdenticalRasters) {
  if (!member_app::have_mpi()) GTEST_SKIP() << "built without MPI";
  const fs::path d = work_dir();
  make_case(d);
  write_ensemble(d / "ens.toml", 12, "latin_hypercube");
  const std::string args = (d / "ens.toml").string() + " --threads 1 --quiet --out ";
  auto r1 = geohaz::testing::run_command(app(args + (d / "one").string()));
  ASSERT_EQ(r1.code, 0) << r1.output;
  auto r2 = geohaz::testing::run_command(member_app::mpirun(GEOHAZ_ENSEMBLE_EXE, 2, args + (d / "two").string()));
  ASSERT_EQ(r2.code, 0) << r2.output;
  EXPECT_EQ(summary(d / "two")["ranks"].get<int>(), 2);
  expect_same_products(d / "one", d / "two");
  // Both ranks computed members (dynamic balancing hands work to whoever asks).
  std::ifstream csv(d / "two" / "members.csv");
  std::string all((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  EXPECT_NE(all.find(",1,1,\""), std::string::npos) << all;  // rank 1, threads 1
  fs::remove_all(d);
}

TEST(EnsembleApp, FailedMemberIsReportedAndTheOthersAggregated) {
  const fs::path d = work_dir();
  make_case(d);
  write_ensemble(d / "ens.toml", 8, "latin_hypercube", "inject_failure = [3]");
  const fs::path out = d / "out";
  const auto r = geohaz::testing::run_command(app((d / "ens.toml").string() + " --threads 1 --out " + out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("member 3/8 (rank 0) FAILED"), std::string::npos) << r.output;
  const auto j = summary(out);
  EXPECT_EQ(j["succeeded"].get<int>(), 7);
  ASSERT_EQ(j["failed"].size(), 1u);
  EXPECT_EQ(j["failed"][0]["member"].get<int>(), 3);
  EXPECT_NE(j["failed"][0]["diagnosis"].get<std::string>().find("injected"), std::string::npos);
  // Probabilities are counts over the 7 members that ran.
  const auto p = read(out / "prob_max_depth_gt_1e-06m.tif");
  for (double v : p.data) {
    if (v == -9999.0) continue;
    EXPECT_NEAR(v * 7.0, std::round(v * 7.0), 1e-5) << v;
  }
  fs::remove_all(d);
}

TEST(EnsembleApp, KilledAndResumedEnsembleGivesTheUninterruptedResult) {
  const fs::path d = work_dir();
  make_case(d);
  write_ensemble(d / "ens.toml", 16, "latin_hypercube");
  const std::string cfg = (d / "ens.toml").string();
  const fs::path whole = d / "whole", resumed = d / "resumed";
  const auto r = geohaz::testing::run_command(app(cfg + " --threads 1 --quiet --out " + whole.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  // Start, wait until some members are on disk, kill -9, then rerun to completion.
  const auto count_done = [&] {
    int k = 0;
    for (int i = 0; i < 16; ++i) {
      char name[16];
      std::snprintf(name, sizeof name, "%06d", i);
      k += fs::exists(resumed / "members" / name / "member.json");
    }
    return k;
  };
  EXPECT_TRUE(member_app::kill_when(GEOHAZ_ENSEMBLE_EXE, {cfg, "--threads", "1", "--quiet", "--out", resumed.string()},
                                    [&] { return count_done() >= 3; }))
      << "the run ended before it was killed";
  const int before = count_done();
  const auto r2 = geohaz::testing::run_command(app(cfg + " --threads 1 --out " + resumed.string()));
  ASSERT_EQ(r2.code, 0) << r2.output;
  EXPECT_GE(before, 3);
  EXPECT_NE(r2.output.find("finished before"), std::string::npos) << r2.output;
  expect_same_products(whole, resumed);
  fs::remove_all(d);
}

TEST(EnsembleApp, BadInputExitsWithTwoNamingTheKeyAndWritesNothing) {
  const fs::path d = work_dir();
  make_case(d);
  struct Case {
    std::string param, extra, key;
  };
  const Case cases[] = {
      {"distribution = \"normal\"\nmean = 0.3\nsd = 0.0", "", "sd"},
      {"distribution = \"uniform\"\nmin = 0.4\nmax = 0.2", "", "min"},
      {"distribution = \"lognormal\"\nmedian = 0.3\nsigma = -1", "", "sigma"},
  };
  for (const auto& c : cases) {
    std::ofstream e(d / "bad.toml");
    e << "[ensemble]\nbase = \"base.toml\"\nmembers = 4\n[[ensemble.parameter]]\nkey = \"model.mu\"\n"
      << c.param << "\n";
    e.close();
    const fs::path out = d / "never";
    const auto r = geohaz::testing::run_command(app((d / "bad.toml").string() + " --out " + out.string()));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(c.key), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
  }
  write_ensemble(d / "ens.toml", 4, "latin_hypercube");
  const std::string cfg = (d / "ens.toml").string() + " --out " + (d / "never").string();
  const std::pair<std::string, std::string> sets[] = {
      {"ensemble.members=0", "ensemble.members"},
      {"products.depth_thresholds=[0.0]", "products.depth_thresholds"},
      {"products.pressure_thresholds=[-5.0]", "products.pressure_thresholds"},
      {"ensemble.parameter[0].key=\"model.friction_typo\"", "model.friction_typo"},
  };
  for (const auto& [set, key] : sets) {
    const auto r = geohaz::testing::run_command(app(cfg + " --set '" + set + "'"));
    EXPECT_EQ(r.code, 2) << set << "\n" << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(d / "never"));
  }
  fs::remove_all(d);
}
