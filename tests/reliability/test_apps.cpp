// Regression tests of issue #12 at the level of the apps: each test runs the real executables on
// the shipped examples with tiny end times and checks how they end (exit code, message, what is
// left on disk). Each of them failed on the code before the fix (signal, exit 1, "stol", a
// std::bad_alloc, a hang, or exit 2 for a full disk).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "child_process.hpp"
#include "geohaz/core/snapshot.hpp"
#include "tiff_header.hpp"

namespace fs = std::filesystem;
using geohaz::testing::ChildLimits;
using geohaz::testing::ChildResult;
using geohaz::testing::run_process;

namespace {

const fs::path kData = fs::path(GEOHAZ_SOURCE_DIR) / "data";

/// Tiny runs of the three apps (each a second or less), to which a test adds its own arguments.
std::vector<std::string> sph_column(const fs::path& out) {
  return {SPH_SLOPE_EXE,
          "--config",
          (kData / "sph/column_collapse.toml").string(),
          "--set",
          "run.end_time=0.002",
          "--set",
          "numerics.spacing=0.01",
          "--set",
          "run.velocity_png_times=[]",
          "--quiet",
          "--out",
          out.string()};
}
std::vector<std::string> dem_avalanche(const fs::path& out) {
  return {DEM_AVALANCHE_EXE,
          "--config",
          (kData / "dem/avalanche.toml").string(),
          "--set",
          "avalanche.runout_time=0.2",
          "--set",
          "avalanche.settle_time=0.05",
          "--quiet",
          "--out",
          out.string()};
}
std::vector<std::string> runout_valley(const fs::path& out) {
  return {DEBRIS_RUNOUT_EXE, "--config",  (kData / "runout/valley_small.toml").string(), "--duration", "2", "--quiet",
          "--out",           out.string()};
}

std::vector<std::string> operator+(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

class Reliability : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("geohaz_reliability_" + std::string(info->name()) + "_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  /// Run and require a normal exit with `code`; stderr must say something when code != 0.
  ChildResult expect_exit(const std::vector<std::string>& argv, int code, const ChildLimits& lim = {}) {
    ChildResult r = run_process(argv, lim);
    EXPECT_TRUE(r.exited) << r.describe() << "\n" << r.err;
    EXPECT_EQ(r.code, code) << r.err;
    if (code != 0) {
      EXPECT_FALSE(r.err.empty());
    }
    return r;
  }
  /// No "*.partial" file anywhere below dir_.
  void expect_no_partial_files() {
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      EXPECT_NE(e.path().extension(), ".partial") << "left behind: " << e.path();
  }
  fs::path dir_;
};

// Item 1: --threads 99999 crashed every app inside the OpenMP runtime; 2147483647 ran out of memory.
TEST_F(Reliability, ThreadsFarAboveTheHardwareAreCappedAndTheRunEnds) {
  for (const char* n : {"99999", "2147483647"}) {
    for (auto argv : {sph_column(dir_ / "sph"), dem_avalanche(dir_ / "dem"), runout_valley(dir_ / "runout")}) {
      const auto r = expect_exit(argv + std::vector<std::string>{"--threads", n}, 0);
      EXPECT_TRUE(has(r.err, "hardware threads")) << argv[0] << ": " << r.err;
    }
  }
}

// Items 2 and 3: a full disk (a file size limit) crashed debris-runout and dem-avalanche in HDF5's
// exit handler (signal 11) and made GeoTIFF/PNG failures "input error", exit 2. Now: exit 3, a
// message naming the file, the snapshot file readable with the snapshots written so far, and no
// ".partial" file.
TEST_F(Reliability, FullDiskEndsWithExitThreeAndReadableOutputs) {
  ChildLimits lim;
  // dem-avalanche: a snapshot every 0.01 s writes 0.73 MB; 300 kB holds the first few.
  lim.file_size = 300 * 1000;
  auto r =
      expect_exit(dem_avalanche(dir_ / "dem") + std::vector<std::string>{"--set", "output.snapshot_every=1", "--set",
                                                                         "avalanche.record_interval=0.01"},
                  3, lim);
  EXPECT_TRUE(has(r.err, "I/O error")) << r.err;
  {
    geohaz::SnapshotReader rd(dir_ / "dem/snapshots.h5");
    EXPECT_GE(rd.snapshot_count(), 1u);
  }
  // sph-slope: the snapshot file does not fit at all: nothing half-written.
  lim.file_size = 30 * 1000;
  r = expect_exit(sph_column(dir_ / "sph"), 3, lim);
  EXPECT_TRUE(has(r.err, "snapshots.h5")) << r.err;
  // debris-runout without snapshots: the first GeoTIFFs fit, a larger product (the zones' GeoPackage,
  // or a PNG) does not; the message names it.
  lim.file_size = 10 * 1000;
  r = expect_exit(runout_valley(dir_ / "runout") + std::vector<std::string>{"--set", "output.snapshots=false"}, 3, lim);
  EXPECT_TRUE(has(r.err, "I/O error") && (has(r.err, ".gpkg") || has(r.err, ".png"))) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "runout/max_depth.tif"));
  // ... and with a 3 kB limit the GeoTIFF writer is the one that fails.
  lim.file_size = 3 * 1000;
  r = expect_exit(runout_valley(dir_ / "runout3") + std::vector<std::string>{"--set", "output.snapshots=false"}, 3,
                  lim);
  EXPECT_TRUE(has(r.err, ".tif")) << r.err;
  // With snapshots: the snapshot file is refused up front or mid-run; either way exit 3.
  lim.file_size = 100 * 1000;
  expect_exit(runout_valley(dir_ / "runout_h5"), 3, lim);
  if (fs::exists(dir_ / "runout_h5/snapshots.h5")) {
    EXPECT_NO_THROW(geohaz::SnapshotReader(dir_ / "runout_h5/snapshots.h5"));
  }
  expect_no_partial_files();
}

// Item 4: +inf passed every "(0, inf)" range: run.end_time = inf never ended; young, gravity or
// density = inf blew up at step 1.
TEST_F(Reliability, InfiniteValuesAreBadInput) {
  const std::vector<std::vector<std::string>> cases = {
      sph_column(dir_ / "o") + std::vector<std::string>{"--set", "run.end_time=inf"},
      sph_column(dir_ / "o") + std::vector<std::string>{"--set", "material[0].young=inf"},
      sph_column(dir_ / "o") + std::vector<std::string>{"--set", "numerics.gravity=+inf"},
      dem_avalanche(dir_ / "o") + std::vector<std::string>{"--set", "material.density=inf"},
      dem_avalanche(dir_ / "o") + std::vector<std::string>{"--set", "avalanche.runout_time=inf"},
  };
  for (const auto& argv : cases) {
    ChildLimits lim;
    lim.timeout_s = 30;
    const auto r = expect_exit(argv, 2, lim);
    EXPECT_TRUE(has(r.err, "not a finite number")) << r.err;
    EXPECT_TRUE(has(r.err, "command line (--set)")) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "o"));
  }
}

// Fuzz cases 62 and 116 (seed 20261201): a platen speed of 1e-9 m/s or a soil density of
// 1.8 kg/m³ made a run of seconds take hours. Both are outside the physical ranges now: exit 2
// naming the key, at once.
TEST_F(Reliability, ValuesThatWouldRunForHoursAreBadInput) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{DEM_AVALANCHE_EXE, "--config", (kData / "dem/biaxial_compression.toml").string(), "--set",
        "biaxial.loading_velocity=1e-9", "--out", (dir_ / "o").string(), "--quiet"},
       "biaxial.loading_velocity"},
      {sph_column(dir_ / "o") + std::vector<std::string>{"--set", "material[0].density=1.8"}, "density"},
      // Fuzz cases 151 and 255 (seed 20261201 after the data of 2026-12-02): element-test
      // specimens 2000 and 117 times as high as wide (1.25 million SPH particles; a disc column).
      {{SPH_SLOPE_EXE, "--config", (kData / "sph/biaxial.toml").string(), "--set", "biaxial.height=100", "--out",
        (dir_ / "o").string(), "--quiet"},
       "biaxial.height"},
      {{DEM_AVALANCHE_EXE, "--config", (kData / "dem/biaxial_compression.toml").string(), "--set", "sample.height=3.5",
        "--out", (dir_ / "o").string(), "--quiet"},
       "sample.height"},
      // Fuzz case 126 (after the data of 2026-12-02 05:00): a runout depth resolution of 0.25 mm,
      // 8.5 million particles on the Alplehner release.
      {runout_valley(dir_ / "o") + std::vector<std::string>{"--set", "model.h0=2.5e-4"}, "model.h0"},
      // Fuzz case 119 (after the data of 2026-12-02 07:30): a 50 m base under a 0.25 m slope at 1 cm
      // spacing, 640,000 particles (21 s for the fuzz's short run, minutes under the sanitizers).
      {{SPH_SLOPE_EXE, "--config", (kData / "sph/slope_2d_granular.toml").string(), "--set", "slope.base_thickness=50",
        "--out", (dir_ / "o").string(), "--quiet"},
       "slope.base_thickness"},
  };
  for (const auto& [argv, key] : cases) {
    ChildLimits lim;
    lim.timeout_s = 30;
    const auto r = expect_exit(argv, 2, lim);
    EXPECT_TRUE(has(r.err, key)) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "o"));
  }
}

// Issue #29, the two inputs the fuzzing still found: a geostatic phase of 1e9 s ran for hours (now
// bounded by 100 times the slope's natural loading time 20 H/c_p, docs/sph.md), and a 10,000-character
// file name ended with exit 3 "filesystem error: status: File name too long" (bad input: exit 2
// naming the key or argument; the check runs before anything is written).
TEST_F(Reliability, GeostaticPhaseOfHoursIsBadInput) {
  ChildLimits lim;
  lim.timeout_s = 30;
  const auto r = expect_exit(
      {SPH_SLOPE_EXE, "--config", (kData / "sph/slope_2d_granular.toml").string(), "--set", "numerics.spacing=0.025",
       "--set", "geostatic.duration=1e9", "--quiet", "--out", (dir_ / "o").string()},
      2, lim);
  EXPECT_TRUE(has(r.err, "geostatic.duration")) << r.err;
  EXPECT_TRUE(has(r.err, "20 H/c_p")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

TEST_F(Reliability, FileNameTooLongIsBadInputNamingTheKey) {
  const std::string long_name = (dir_ / std::string(10000, 'a')).string() + ".tif";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {runout_valley(dir_ / "o") + std::vector<std::string>{"--release", long_name}, "release.file"},
      {runout_valley(dir_ / "o") + std::vector<std::string>{"--set", "terrain.dsm=\"" + long_name + "\""},
       "terrain.dsm"},
      {{DEBRIS_RUNOUT_EXE, (kData / "terrain/alr/avaAlr.tif").string(), "--release",
        (kData / "terrain/alr/relAlr.shp").string(), "--quiet", "--out", long_name},
       "--out"},
      {{SPH_SLOPE_EXE, "--config", (kData / "sph/column_collapse.toml").string(), "--quiet", "--out", long_name},
       "--out"},
  };
  for (const auto& [argv, key] : cases) {
    ChildLimits lim;
    lim.timeout_s = 30;
    const auto r = expect_exit(argv, 2, lim);
    EXPECT_TRUE(has(r.err, key)) << r.err;
    EXPECT_TRUE(has(r.err, "file name too long")) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "o"));
  }
}

// A missing input file says so, not "cannot read as a raster" (issue #29).
TEST_F(Reliability, MissingInputFileSaysNoSuchFile) {
  const auto r = expect_exit({DEBRIS_RUNOUT_EXE, (dir_ / "nothing_here.tif").string(), "--release",
                              (kData / "terrain/alr/relAlr.shp").string(), "--quiet", "--out", (dir_ / "o").string()},
                             2);
  EXPECT_TRUE(has(r.err, "no such file")) << r.err;
  EXPECT_TRUE(has(r.err, "nothing_here.tif")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// Item 5: a malformed index in --set ended with "error: stol", exit 1, in every app.
TEST_F(Reliability, MalformedSetIndexIsBadInputNamingTheCommandLine) {
  for (const char* set :
       {"material[abc].density=1", "material[].density=1", "material[12345678901234567890].density=1"}) {
    for (auto argv : {sph_column(dir_ / "o"), dem_avalanche(dir_ / "o"), runout_valley(dir_ / "o")}) {
      const auto r = expect_exit(argv + std::vector<std::string>{"--set", set}, 2);
      EXPECT_TRUE(has(r.err, "malformed array index")) << r.err;
      EXPECT_TRUE(has(r.err, "command line (--set)")) << r.err;
      EXPECT_FALSE(fs::exists(dir_ / "o"));
    }
  }
}

// Item 6: spacing 0.04 and width 0.2 passed the 3D periodic width check but the neighbour list
// rejected them mid-run ("a periodic axis must be at least twice the cut-off", exit 1, files left).
TEST_F(Reliability, PeriodicWidthTheNeighbourListWouldRejectIsBadInput) {
  const auto r = expect_exit(
      {SPH_SLOPE_EXE, "--config", (kData / "sph/slope_3d_periodic.toml").string(), "--set", "numerics.spacing=0.04",
       "--set", "geometry.width=0.2", "--set", "run.end_time=0.001", "--quiet", "--out", (dir_ / "o").string()},
      2);
  EXPECT_TRUE(has(r.err, "'geometry.width'")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// Item 7: inputs needing too much memory ended in "std::bad_alloc" naming nothing.
TEST_F(Reliability, InputsNeedingTooMuchMemoryAreBadInputNamingKeyAndEstimate) {
  struct Case {
    std::vector<std::string> argv;
    std::string key;
  };
  // A copy of the valley DSM whose header declares 100000 × 100000 cells (the file stays small).
  const fs::path huge = dir_ / "huge_dsm.tif";
  fs::copy_file(kData / "runout/valley_small.tif", huge);
  ASSERT_TRUE(geohaz::testing::set_tiff_size(huge, 100000, 100000));
  const std::vector<Case> cases = {
      {sph_column(dir_ / "o") + std::vector<std::string>{"--set", "numerics.spacing=1e-6"}, "'numerics.spacing'"},
      {sph_column(dir_ / "o") + std::vector<std::string>{"--set", "column.floor_length=3e12"}, "column.floor_length"},
      {dem_avalanche(dir_ / "o") + std::vector<std::string>{"--set", "sample.r_min=1e-7", "--set", "sample.r_max=2e-7"},
       "'sample.r_min'"},
      {{DEBRIS_RUNOUT_EXE, huge.string(), "--release", (kData / "runout/valley_small_release.tif").string(), "--quiet",
        "--out", (dir_ / "o").string()},
       huge.string()},
  };
  for (const auto& c : cases) {
    const auto r = expect_exit(c.argv, 2);
    EXPECT_TRUE(has(r.err, c.key)) << r.err;
    EXPECT_TRUE(has(r.err, "of memory")) << r.err;
    EXPECT_FALSE(has(r.err, "bad_alloc")) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "o"));
  }
}

// Item 8: a profile leaving the terrain named neither file nor key.
TEST_F(Reliability, ProfileLeavingTheTerrainNamesTheFileAndTheKey) {
  const fs::path sph = kData / "sph/section_dsm.toml";
  auto r = expect_exit(
      {SPH_SLOPE_EXE, "--config", sph.string(), "--set", "section.polyline=[500010.0, 4000040.0, 900110.0, 4000040.0]",
       "--quiet", "--out", (dir_ / "o").string()},
      2);
  EXPECT_TRUE(has(r.err, "section.polyline")) << r.err;
  EXPECT_TRUE(has(r.err, "hillside_dsm.asc")) << r.err;
  r = expect_exit(
      dem_avalanche(dir_ / "o") + std::vector<std::string>{"--config", (kData / "dem/avalanche_alr.toml").string(),
                                                           "--set", "avalanche.section_x[0]=1"},
      2);
  // (--set of one array element is no TOML: this asserts the message names the command line.)
  EXPECT_TRUE(has(r.err, "command line")) << r.err;
  std::ifstream in(kData / "dem/avalanche_alr.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const auto at = toml.find("section_x = [");
  ASSERT_NE(at, std::string::npos);
  toml.replace(at, 13, "section_x = [9.0e6, ");  // the profile starts far off the DSM
  const auto aty = toml.find("section_y = [");
  ASSERT_NE(aty, std::string::npos);
  toml.replace(aty, 13, "section_y = [5.2e6, ");
  std::ofstream(dir_ / "alr.toml") << toml;
  fs::create_directories(dir_ / "terrain/alr");
  r = expect_exit({DEM_AVALANCHE_EXE, "--config", (dir_ / "alr.toml").string(), "--set",
                   "avalanche.dsm=\"" + (kData / "terrain/alr/avaAlr.tif").string() + "\"", "--quiet", "--out",
                   (dir_ / "o").string()},
                  2);
  EXPECT_TRUE(has(r.err, "avalanche.section_x")) << r.err;
  EXPECT_TRUE(has(r.err, "avaAlr.tif")) << r.err;
}

// Item 8: checks inside the libraries (here the 3D scenario builder's minimum width) named no file.
TEST_F(Reliability, ScenarioErrorsNameTheConfigFile) {
  const auto r = expect_exit(
      sph_column(dir_ / "o") + std::vector<std::string>{"--set", "run.dimension=3", "--set", "geometry.periodic=false",
                                                        "--set", "geometry.width=0.001"},
      2);
  EXPECT_TRUE(has(r.err, "column_collapse.toml")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// Item 8: "--set run=5" complained about column.floor_length; a stray positional argument was
// ignored by sph-slope and dem-avalanche.
TEST_F(Reliability, SetOfATableAndStrayArgumentsAreBadInput) {
  auto r = expect_exit(sph_column(dir_ / "o") + std::vector<std::string>{"--set", "run=5"}, 2);
  EXPECT_TRUE(has(r.err, "'run'")) << r.err;
  EXPECT_FALSE(has(r.err, "floor_length")) << r.err;
  for (auto argv : {sph_column(dir_ / "o"), dem_avalanche(dir_ / "o")}) {
    r = expect_exit(argv + std::vector<std::string>{"stray.toml"}, 2);
    EXPECT_TRUE(has(r.err, "positional")) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// Item 8: an empty array could not be set with --set although the default is empty.
TEST_F(Reliability, EmptyArrayCanBeSetWhereTheDefaultIsEmpty) {
  auto argv = sph_column(dir_ / "o");
  argv.insert(argv.begin() + 1, {"--set", "run.velocity_png_times=[0.001]"});  // replaced by the [] after it
  expect_exit(argv, 0);
  for (const auto& e : fs::directory_iterator(dir_ / "o"))
    EXPECT_FALSE(has(e.path().filename().string(), "velocity_t")) << e.path();
}

// Item 8: the final snapshot was written twice when the end time fell on a snapshot time (the
// rock-avalanche .xmf held every disc twice at its last time).
TEST_F(Reliability, FinalSnapshotIsWrittenOnce) {
  expect_exit(dem_avalanche(dir_ / "dem") + std::vector<std::string>{"--set", "output.snapshot_every=1"}, 0);
  expect_exit(sph_column(dir_ / "sph") + std::vector<std::string>{"--set", "run.snapshot_interval=0.001"}, 0);
  for (const char* app : {"dem", "sph"}) {
    geohaz::SnapshotReader rd(dir_ / app / "snapshots.h5");
    ASSERT_GE(rd.snapshot_count(), 2u);
    std::set<std::int64_t> steps;
    for (std::size_t k = 0; k < rd.snapshot_count(); ++k) EXPECT_TRUE(steps.insert(rd.step(k)).second) << app << k;
  }
}

// The exit codes are stated in every app's --help.
TEST_F(Reliability, HelpStatesTheExitCodes) {
  for (const char* exe : {SPH_SLOPE_EXE, DEM_AVALANCHE_EXE, DEBRIS_RUNOUT_EXE}) {
    const auto r = expect_exit({exe, "--help"}, 0);
    EXPECT_TRUE(has(r.out, "Exit codes: 0 done; 1 the simulation failed")) << exe;
    EXPECT_TRUE(has(r.out, "3 an I/O or system failure")) << exe;
  }
}

}  // namespace
