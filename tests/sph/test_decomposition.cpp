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
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/handoff.hpp"
#include "geohaz/core/snapshot.hpp"
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

/// A CSV file of numbers: its header and its rows.
std::pair<std::string, std::vector<std::vector<double>>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string header, line;
  std::getline(in, header);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream is(line);
    std::string cell;
    while (std::getline(is, cell, ',')) row.push_back(cell.empty() ? 0.0 : std::stod(cell));
    rows.push_back(row);
  }
  return {header, rows};
}

/// The tables a distributed run makes by reductions over the ranks (series rows, the final
/// profiles; docs/sph.md "Outputs by reduction") against one process: the same columns and rows,
/// every value within `tolerance` (relative to the larger, or absolute below 1).
void expect_same_tables(const fs::path& one, const fs::path& many, double tolerance,
                        std::vector<std::string> files = {"series.csv", "surface_final.csv", "slip_surface.csv"}) {
  for (const auto& f : files) {
    const auto [ha, a] = read_csv(one / f);
    const auto [hb, b] = read_csv(many / f);
    EXPECT_EQ(ha, hb) << f;
    ASSERT_EQ(a.size(), b.size()) << f;
    if (f != "slip_surface.csv") {
      EXPECT_FALSE(a.empty()) << f;  // no slip in a short run: empty alike
    }
    for (std::size_t r = 0; r < a.size(); ++r) {
      ASSERT_EQ(a[r].size(), b[r].size()) << f << " row " << r;
      for (std::size_t c = 0; c < a[r].size(); ++c)
        EXPECT_LE(std::abs(a[r][c] - b[r][c]), tolerance * std::max({1.0, std::abs(a[r][c]), std::abs(b[r][c])}))
            << f << " row " << r << " column " << c << ": " << a[r][c] << " vs " << b[r][c];
    }
  }
}

/// sph-slope on one process and sph-slope-mpi on np ranks with the same arguments: both succeed,
/// and the summaries' numbers agree to `tolerance` (relative to the larger, or absolute below 1),
/// as do the series and the final profiles (expect_same_tables).
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
  expect_same_tables(one, many, tolerance);
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

// The series columns made of the free end (a clamped region: tip_displacement_m, a mean over the
// particles of the free end, which are every rank's) and the biaxial stresses (means over the
// specimen), reduced over the ranks.
TEST(SphDecomposition, SphSlopeMpiBiaxialWithAClampedRegionGivesTheTablesOfOneProcess) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  expect_same_summary("biaxial",
                      "--config " + (kData / "biaxial.toml").string() +
                          " --set numerics.spacing=0.005 --set run.end_time=0.004 --set run.output_interval=0.0005"
                          " --set run.snapshot_interval=0 --set clamp.boxes=[0,0,0.01,0.1] --quiet",
                      2, {"max_displacement_m", "max_plastic_strain"}, 1e-9);
  const auto [header, rows] = read_csv(kWork / "biaxial_np2" / "series.csv");
  EXPECT_NE(header.find("tip_displacement_m"), std::string::npos) << header;
  expect_same_tables(kWork / "biaxial_one", kWork / "biaxial_np2", 1e-9, {"stress_strain.csv"});
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
  fs::remove_all(out);
  const auto r = run(mpirun(SPH_SLOPE_MPI_EXE, 2,
                            "--config " + (kData / "cantilever.toml").string() + " --quiet --out " + out.string()));
  EXPECT_EQ(r.first, 2) << r.second;
  EXPECT_NE(r.second.find("does not run on several MPI ranks yet"), std::string::npos) << r.second;
  EXPECT_NE(r.second.find("numerics.formulation"), std::string::npos) << r.second;
  EXPECT_FALSE(fs::exists(out));
}

namespace {

/// One field of snapshot k by particle id: id -> the particle's components.
std::map<std::int64_t, std::vector<double>> field_by_id(const geohaz::SnapshotReader& r, std::size_t k,
                                                        const std::string& label) {
  const auto id = r.read(k, "id");
  const auto f = r.read(k, label);
  std::map<std::int64_t, std::vector<double>> out;
  const auto c = static_cast<std::size_t>(f.components());
  for (std::size_t i = 0; i < f.count; ++i)
    out[static_cast<std::int64_t>(id.values[i])] =
        std::vector<double>(f.values.begin() + static_cast<std::ptrdiff_t>(i * c),
                            f.values.begin() + static_cast<std::ptrdiff_t>((i + 1) * c));
  return out;
}

/// Snapshot ka of file a and kb of file b: the same time and step, the same particle ids, and every
/// field within `tolerance` of the largest magnitude of that field (round-off, kRelative above).
void expect_same_snapshot(const fs::path& a, std::size_t ka, const fs::path& b, std::size_t kb,
                          double tolerance = kRelative, const std::string& skip = "") {
  const geohaz::SnapshotReader ra(a), rb(b);
  ASSERT_LT(ka, ra.snapshot_count());
  ASSERT_LT(kb, rb.snapshot_count());
  EXPECT_EQ(ra.step(ka), rb.step(kb));
  EXPECT_NEAR(ra.time(ka), rb.time(kb), 1e-12 * std::max(1.0, ra.time(ka)));
  ASSERT_EQ(ra.fields(ka), rb.fields(kb));
  double worst = 0.0;
  std::string worst_label = "none";
  for (const std::string& label : ra.fields(ka)) {
    if (label == skip) continue;
    const auto fa = field_by_id(ra, ka, label), fb = field_by_id(rb, kb, label);
    ASSERT_EQ(fa.size(), fb.size()) << label;
    double scale = 0.0, diff = 0.0;
    for (const auto& [id, va] : fa) {
      const auto it = fb.find(id);
      ASSERT_NE(it, fb.end()) << "particle " << id << " missing from " << b;
      for (std::size_t c = 0; c < va.size(); ++c) {
        scale = std::max(scale, std::abs(va[c]));
        diff = std::max(diff, std::abs(va[c] - it->second[c]));
      }
    }
    EXPECT_LE(diff, tolerance * std::max(scale, 1e-300)) << label << ": " << a << " vs " << b;
    if (scale > 0.0 && diff / scale > worst) worst = diff / scale, worst_label = label;
  }
  std::printf("%s #%zu vs %s #%zu: largest difference %.2g of the field's largest value (%s)\n",
              a.parent_path().filename().c_str(), ka, b.parent_path().filename().c_str(), kb, worst,
              worst_label.c_str());
}

const std::string kColumn = "--config " + (kData / "column_collapse.toml").string() +
                            " --set numerics.spacing=0.01 --set run.stop_at_rest=false --set run.velocity_png_times=[]"
                            " --quiet";

/// sph-slope (np = 0) or sph-slope-mpi on np ranks into kWork/name, from scratch.
fs::path run_column(const std::string& name, int np, const std::string& args) {
  const fs::path out = kWork / name;
  fs::remove_all(out);
  fs::create_directories(kWork);
  const std::string a = kColumn + " " + args + " --out " + out.string();
  const auto r =
      np == 0 ? run(std::string(SPH_SLOPE_EXE) + " " + a + " --threads 1") : run(mpirun(SPH_SLOPE_MPI_EXE, np, a));
  EXPECT_EQ(r.first, 0) << r.second;
  return out;
}

}  // namespace

// Issue #36, I/O at scale: a run on two ranks writes its snapshots in parallel, each rank its part
// file (snapshots.rank0000.h5, snapshots.rank0001.h5), joined in snapshots.h5 (core snapshot.hpp);
// read back, every snapshot is the one-process run's: the same particle ids, steps and times, every
// field within round-off.
TEST(SphDecomposition, SnapshotsWrittenByTwoRanksReadAsTheOneProcessSnapshots) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  const std::string args = "--set run.end_time=0.05 --set run.snapshot_interval=0.02";
  const fs::path one = run_column("snapshots_one", 0, args), two = run_column("snapshots_np2", 2, args);
  for (const char* part : {"snapshots.rank0000.h5", "snapshots.rank0001.h5"}) EXPECT_TRUE(fs::exists(two / part));
  EXPECT_FALSE(fs::exists(one / "snapshots.rank0000.h5"));
  const geohaz::SnapshotReader r1(one / "snapshots.h5"), r2(two / "snapshots.h5");
  ASSERT_EQ(r1.snapshot_count(), 4u);  // t = 0, 0.02, 0.04 and the end
  ASSERT_EQ(r2.snapshot_count(), r1.snapshot_count());
  EXPECT_EQ(r2.attribute("ranks"), "2");
  for (std::size_t k = 0; k < r1.snapshot_count(); ++k)
    expect_same_snapshot(one / "snapshots.h5", k, two / "snapshots.h5", k);
  // The part files together hold every particle once.
  const auto n0 = geohaz::SnapshotReader(two / "snapshots.rank0000.h5").read(3, "id").count;
  const auto n1 = geohaz::SnapshotReader(two / "snapshots.rank0001.h5").read(3, "id").count;
  EXPECT_GT(n0, 0u);
  EXPECT_GT(n1, 0u);
  EXPECT_EQ(n0 + n1, r1.read(3, "id").count);
  // The one XDMF file names the joined file only, so ParaView opens the run as one dataset.
  std::ifstream x(two / "snapshots.xmf");
  const std::string xmf((std::istreambuf_iterator<char>(x)), std::istreambuf_iterator<char>());
  EXPECT_NE(xmf.find("snapshots.h5:/snapshots/000003/position"), std::string::npos);
  EXPECT_EQ(xmf.find("rank0"), std::string::npos);
}

// Restart on another rank count: the checkpoint of a run on two ranks continues on one process, and
// that of one process on two ranks, to the final state of the uninterrupted one-process run (round-off:
// the pair sums in another order; the restart reads Δt, the step and the positions of the last list
// build from the checkpoint, so the steps are the same).
TEST(SphDecomposition, RestartOnAnotherRankCountReachesTheUninterruptedState) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  const std::string first = "--set run.end_time=0.025 --set run.snapshot_interval=0",
                    second = "--set run.end_time=0.05";
  const fs::path whole = run_column("restart_whole", 0, second + " --set run.snapshot_interval=0");
  const fs::path half2 = run_column("restart_half_np2", 2, first), half1 = run_column("restart_half_one", 0, first);
  const fs::path on1 =
      run_column("restart_np2_on_one", 0, second + " --set run.restart=" + (half2 / "snapshots.h5").string());
  const fs::path on2 =
      run_column("restart_one_on_np2", 2, second + " --set run.restart=" + (half1 / "snapshots.h5").string());
  const geohaz::SnapshotReader rw(whole / "snapshots.h5");
  const std::size_t last = rw.snapshot_count() - 1;
  for (const fs::path& restarted : {on1, on2}) {
    SCOPED_TRACE(restarted.string());
    // On two ranks the first step builds the lists afresh (the ranks' ghosts), so position_at_build,
    // the solver's record of that build, is the restart's; the state itself is the same.
    const std::string skip = restarted == on2 ? "position_at_build" : "";
    const auto s = summary(restarted);
    ASSERT_TRUE(s.contains("restart")) << s.dump(2);
    EXPECT_TRUE(s["restart"]["exact"].get<bool>());  // the solver state was in the checkpoint
    const geohaz::SnapshotReader rr(restarted / "snapshots.h5");
    expect_same_snapshot(whole / "snapshots.h5", last, restarted / "snapshots.h5", rr.snapshot_count() - 1, kRelative,
                         skip);
  }
}

// The strength reduction on two ranks: the geostatic phase and every trial spread over the ranks, the
// trials' decisions and steps those of one process, their displacements within round-off (the
// largest soil displacement after 800 steps of plastic flow agreed in all 9 printed digits, the
// failed trial's state to 3e-12 of each field's largest value; round-off grows faster in a failing
// slope than in the elastic-plastic column, so 1e-6, which still catches a particle lost or counted
// twice), the same factor of safety.
TEST(SphDecomposition, StrengthReductionOnTwoRanksGivesTheTrialsOfOneProcess) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  const std::string args = "--config " + (kData / "acads_1a_srm.toml").string() +
                           " --set numerics.spacing=1.0 --set strength_reduction.f_min=0.8"
                           " --set strength_reduction.f_max=1.3 --set strength_reduction.tolerance=0.5"
                           " --set strength_reduction.trial_duration=0.8 --set geostatic.duration=0.8 --quiet";
  const fs::path one = kWork / "srm_one", two = kWork / "srm_np2";
  fs::remove_all(one);
  fs::remove_all(two);
  fs::create_directories(kWork);
  auto r = run(std::string(SPH_SLOPE_EXE) + " " + args + " --threads 1 --out " + one.string());
  ASSERT_EQ(r.first, 0) << r.second;
  r = run(mpirun(SPH_SLOPE_MPI_EXE, 2, args + " --out " + two.string()));
  ASSERT_EQ(r.first, 0) << r.second;
  const auto a = summary(one), b = summary(two);
  EXPECT_EQ(a["outcome"], b["outcome"]);
  EXPECT_EQ(a["factor_of_safety"], b["factor_of_safety"]);
  EXPECT_EQ(a["trials"], b["trials"]);
  std::ifstream fa(one / "srm_trials.csv"), fb(two / "srm_trials.csv");
  std::string la, lb;
  std::getline(fa, la);
  std::getline(fb, lb);
  int rows = 0;
  while (std::getline(fa, la) && std::getline(fb, lb)) {
    double va[6], vb[6];
    char c;
    std::istringstream ia(la), ib(lb);
    for (int k = 0; k < 6; ++k) ia >> va[k] >> c, ib >> vb[k] >> c;
    for (int k : {0, 1, 4, 5}) EXPECT_EQ(va[k], vb[k]) << la << " vs " << lb;  // trial, F, failed, steps
    EXPECT_NEAR(va[2], vb[2], 1e-6 * va[2]) << la << " vs " << lb;             // displacement
    ++rows;
  }
  EXPECT_EQ(rows, 2);
  // The mechanism (snapshot 1): the failed trial's state, gathered by particle id.
  expect_same_snapshot(one / "snapshots.h5", 1, two / "snapshots.h5", 1, 1e-6);
}

// The hand-off to debris-runout written from a run on two ranks: the release of the DSM section holds
// the points and volumes of the one-process run's (in another order: matched point by point).
TEST(SphDecomposition, SectionReleaseFromTwoRanksEqualsTheOneProcessRelease) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI (GEOHAZ_MPI)";
  const std::string args = "--config " + (kData / "section_dsm.toml").string() +
                           " --set numerics.spacing=1.0 --set run.end_time=1.0 --set geostatic.duration=1.5 --quiet";
  const fs::path one = kWork / "release_one", two = kWork / "release_np2";
  fs::remove_all(one);
  fs::remove_all(two);
  fs::create_directories(kWork);
  auto r = run(std::string(SPH_SLOPE_EXE) + " " + args + " --threads 1 --out " + one.string());
  ASSERT_EQ(r.first, 0) << r.second;
  r = run(mpirun(SPH_SLOPE_MPI_EXE, 2, args + " --out " + two.string()));
  ASSERT_EQ(r.first, 0) << r.second;
  const auto a = summary(one), b = summary(two);
  EXPECT_EQ(a["failed_particles"], b["failed_particles"]);
  EXPECT_NEAR(a["failed_area_m2_per_m"].get<double>(), b["failed_area_m2_per_m"].get<double>(), 1e-9);
  const geohaz::Handoff ha = geohaz::read_handoff(one / "release.h5"), hb = geohaz::read_handoff(two / "release.h5");
  ASSERT_GT(ha.points.size(), 0u);
  ASSERT_EQ(ha.points.size(), hb.points.size());
  EXPECT_EQ(ha.step, hb.step);
  std::vector<bool> used(hb.points.size(), false);
  double total_a = 0.0, total_b = 0.0;
  for (std::size_t i = 0; i < ha.points.size(); ++i) {
    std::size_t best = 0;
    double d2 = 1e300;
    for (std::size_t j = 0; j < hb.points.size(); ++j) {
      const double dj = (ha.points[i] - hb.points[j]).squaredNorm();
      if (!used[j] && dj < d2) d2 = dj, best = j;
    }
    used[best] = true;
    EXPECT_LT(std::sqrt(d2), 1e-6) << "point " << i;  // m, positions agree to round-off (1e-12 of 1e3 m)
    EXPECT_NEAR(ha.volumes[i], hb.volumes[best], 1e-12 * ha.volumes[i]) << "point " << i;
    total_a += ha.volumes[i];
    total_b += hb.volumes[best];
  }
  EXPECT_NEAR(total_a, total_b, 1e-9 * total_a);
  EXPECT_TRUE(fs::exists(two / "release_thickness.tif"));
}
