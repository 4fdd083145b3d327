// The SPH domain decomposition (issue #36; docs/sph.md, "Domain decomposition"): the solver on 1, 2
// and 4 ranks (oversubscribed, one thread each) against the one-process solver, particle by
// particle, through the rank program decomposition_ranks.cpp; and sph-slope-mpi under mpirun against
// sph-slope. Built without MPI (GEOHAZ_MPI off or no MPI installed) every case skips.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/sph/summary_keys.hpp"
#include "summary_keys_check.hpp"

namespace fs = std::filesystem;

namespace {

bool have_mpi() {
  return !std::string(SPH_DECOMPOSITION_EXE).empty();
}

/// `exe args` under mpirun with np ranks of one OpenMP thread each (more ranks than cores allowed;
/// as root in CI containers).
std::string mpirun(const std::string& exe, int np, const std::string& args) {
  std::string cmd =
      std::string(GEOHAZ_SPH_MPIEXEC) + " --oversubscribe -x OMP_NUM_THREADS=1 -np " + std::to_string(np) + " ";
  if (::geteuid() == 0) cmd += "--allow-run-as-root ";
  return cmd + exe + " " + args;
}

/// Run a command; its exit code and standard output.
std::pair<int, std::string> run(const std::string& cmd) {
  std::string out;
  FILE* p = ::popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return {-1, out};
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), static_cast<int>(buf.size()), p)) out += buf.data();
  const int status = ::pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

/// The "case ..." line of the rank program as name → value.
std::map<std::string, double> result(const std::string& out) {
  std::map<std::string, double> r;
  const auto at = out.find("case ");
  if (at == std::string::npos) return r;
  std::istringstream is(out.substr(at, out.find('\n', at) - at));
  std::string key, value;
  while (is >> key >> value) {
    try {
      r[key] = std::stod(value);
    } catch (const std::exception&) {
      r[key] = 0.0;  // the case name
    }
  }
  return r;
}

// The tolerance: the runs differ only in the order of the pair and reduction sums (owned and ghost
// particles in another order, the sums over ranks), which is round-off, 1e-16 of each term per step
// (measured: 1e-16–1e-15 of the largest value after 100 steps, 1e-14 for the stress of the elastic
// block, whose stress is small against its velocity terms); 1e-12 leaves room for the order of
// growth of round-off over these few hundred steps without letting a missing or stale ghost field
// through (that gives differences of the order of the field itself at the halo).
constexpr double kRelative = 1e-12;

void expect_same_as_one_process(const std::string& args, int np) {
  const auto [code, out] = run(mpirun(SPH_DECOMPOSITION_EXE, np, args));
  ASSERT_EQ(code, 0) << out;
  const auto r = result(out);
  ASSERT_EQ(r.count("ranks"), 1u) << out;
  EXPECT_EQ(r.at("ranks"), np);
  for (const char* f : {"position", "velocity", "stress", "density", "dt"})
    EXPECT_LT(r.at(f), kRelative) << f << ": " << out;
  EXPECT_EQ(r.at("repeat"), 1.0) << "a second run on " << np << " ranks differs: " << out;
  if (np > 1) {
    EXPECT_GT(r.at("ghosts"), 0.0) << out;
  }
}

}  // namespace

TEST(SphDecomposition, ColumnCollapse2DOnOneTwoAndFourRanksMatchesOneProcess) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  for (int np : {1, 2, 4}) expect_same_as_one_process("column2d 100", np);
}

TEST(SphDecomposition, PeriodicSlope3DOnOneTwoAndFourRanksMatchesOneProcess) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  for (int np : {1, 2, 4}) expect_same_as_one_process("slope3d 30", np);
}

TEST(SphDecomposition, ElasticBlockCrossingTheRankBoundaryKeepsItsStressHistory) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  // The block moves 0.13 m in 200 steps across the first partition's cut at its middle: about a
  // third of it changes rank with its stress, which must then match the one-process block's.
  for (int np : {2, 4}) {
    const auto [code, out] = run(mpirun(SPH_DECOMPOSITION_EXE, np, "block2d 200"));
    ASSERT_EQ(code, 0) << out;
    const auto r = result(out);
    ASSERT_EQ(r.count("migrated"), 1u) << out;
    EXPECT_GT(r.at("migrated"), 50.0) << out;
    for (const char* f : {"position", "velocity", "stress", "density"})
      EXPECT_LT(r.at(f), kRelative) << f << ": " << out;
  }
}

namespace {

const fs::path kData = fs::path(GEOHAZ_SOURCE_DIR) / "data/sph";
const fs::path kWork = fs::path(GEOHAZ_BINARY_DIR) / "tests/sph/decomposition_runs";

nlohmann::json summary(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

/// sph-slope on one process and sph-slope-mpi on np ranks with the same arguments: both succeed,
/// and the summaries' numbers agree to `tolerance` (relative to the larger, or absolute below 1).
void expect_same_summary(const std::string& name, const std::string& args, int np, const std::vector<std::string>& keys,
                         double tolerance) {
  const fs::path one = kWork / (name + "_one"), many = kWork / (name + "_np" + std::to_string(np));
  fs::remove_all(one);
  fs::remove_all(many);
  fs::create_directories(kWork);
  auto r = run(std::string(SPH_SLOPE_EXE) + " " + args + " --threads 1 --out " + one.string());
  ASSERT_EQ(r.first, 0) << r.second;
  r = run(mpirun(SPH_SLOPE_MPI_EXE, np, args + " --out " + many.string()));
  ASSERT_EQ(r.first, 0) << r.second;
  const auto a = summary(one), b = summary(many);
  ASSERT_TRUE(b.contains("domain_decomposition")) << b.dump(2);
  EXPECT_EQ(b["domain_decomposition"]["ranks"], np);
  EXPECT_SUMMARY_KEYS_DECLARED(b, geohaz::sph::summary_keys());  // the report labels them (issue #33)
  EXPECT_EQ(a["boundary_particles"], b["boundary_particles"]);
  EXPECT_EQ(a["failed_particles"], b["failed_particles"]);
  EXPECT_EQ(a["steps"], b["steps"]);
  for (const auto& k : keys) {
    ASSERT_TRUE(a.contains(k) && b.contains(k)) << k;
    const double x = a[k].get<double>(), y = b[k].get<double>();
    EXPECT_LE(std::abs(x - y), tolerance * std::max({1.0, std::abs(x), std::abs(y)})) << k << ": " << x << " vs " << y;
  }
  for (const char* f : {"series.csv", "snapshots.h5", "snapshots.xmf", "final_displacement.png", "summary.json"})
    EXPECT_TRUE(fs::exists(many / f)) << f;
}

}  // namespace

// The summary's figures are sums and maxima over the final state (run-out, front, speeds, energy,
// failed mass), which differs from the one-process state by round-off only (above): 1e-9 of each
// figure bounds the round-off of those sums by far and still catches a particle missing from, or
// counted twice in, the gathered state (a change of 1/N ≥ 1e-4 in a mass or energy sum).
TEST(SphDecomposition, SphSlopeMpiOnTwoRanksGivesTheSummaryOfOneProcess) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  expect_same_summary("column",
                      "--config " + (kData / "column_collapse.toml").string() +
                          " --set numerics.spacing=0.01 --set run.stop_at_rest=false --set run.end_time=0.05"
                          " --set run.velocity_png_times=[] --quiet",
                      2,
                      {"runout_m", "front_m", "tip_m", "max_speed_m_per_s", "final_max_speed_m_per_s",
                       "max_displacement_m", "max_plastic_strain", "failed_area_m2_per_m"},
                      1e-9);
}

TEST(SphDecomposition, SphSlopeMpi3DPeriodicSlopeWithPilesOnFourRanks) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  expect_same_summary("piles_3d",
                      "--config " + (kData / "slope_piles_3d.toml").string() +
                          " --set numerics.spacing=0.04 --set geometry.width=0.24 --set piles.spacing=0.12"
                          " --set piles.diameter=0.08 --set run.end_time=0.02 --set geostatic.duration=0.1"
                          " --set run.velocity_png_times=[] --quiet",
                      4, {"runout_m", "max_speed_m_per_s", "max_displacement_m", "failed_volume_m3"}, 1e-9);
  const auto a = summary(kWork / "piles_3d_one"), b = summary(kWork / "piles_3d_np4");
  // The loads on the piles: sums over the soil-pile pairs of every rank, in rank order.
  ASSERT_EQ(a["structures"].size(), b["structures"].size());
  for (std::size_t k = 0; k < a["structures"].size(); ++k) {
    const double x = a["structures"][k]["peak_resultant_N"].get<double>();
    const double y = b["structures"][k]["peak_resultant_N"].get<double>();
    EXPECT_NEAR(x, y, 1e-9 * std::max(1.0, std::abs(x))) << a["structures"][k]["name"];
  }
}

TEST(SphDecomposition, WhatDoesNotRunOnSeveralRanksExitsTwoNamingItAndWritesNothing) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  const fs::path out = kWork / "refused";
  for (const std::string& args :
       {"--config " + (kData / "acads_1a_srm.toml").string(),
        "--config " + (kData / "column_collapse.toml").string() + " --set run.restart=missing.h5",
        "--config " + (kData / "column_collapse.toml").string() + " --set run.velocity_png_times=[0.01]"}) {
    fs::remove_all(out);
    const auto r = run(mpirun(SPH_SLOPE_MPI_EXE, 2, args + " --quiet --out " + out.string()));
    EXPECT_EQ(r.first, 2) << args << "\n" << r.second;
    EXPECT_NE(r.second.find("does not run on several MPI ranks yet"), std::string::npos) << r.second;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
}
