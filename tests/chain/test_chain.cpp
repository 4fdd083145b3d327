// The chain on a small case: a soil layer on a DSM cross-section fails (sph-slope), its failed
// mass is handed over as release.h5, and debris-runout runs it out over the same DSM. The volume
// handed over must be the volume read and the volume seeded, to round-off (no bulking here).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "geohaz/core/snapshot.hpp"
#include "run_command.hpp"

namespace fs = std::filesystem;

namespace {

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  EXPECT_TRUE(in.good()) << p;
  return nlohmann::json::parse(in);
}

int run(const std::string& cmd) {
  const auto r = geohaz::testing::run_command(cmd);
  if (r.code != 0) std::fputs(r.output.c_str(), stderr);
  return r.code;
}

/// Runs sph-slope (`cmd` writes to out/slope) and reads its summary and the volume it handed over,
/// which must be positive (else the chain test would be vacuous).
void run_slope(const std::string& cmd, const fs::path& out, nlohmann::json& slope, double& handed) {
  ASSERT_EQ(run(cmd), 0) << cmd;
  slope = read_json(out / "slope" / "summary.json");
  ASSERT_TRUE(slope.contains("release")) << slope.dump(2);
  handed = slope["release"]["total_volume_m3"].get<double>();
  ASSERT_GT(handed, 0.0) << "no failed mass: the chain test would be vacuous";
}

TEST(Chain, SectionFailureRunsOutWithTheSameVolume) {
  const fs::path src = GEOHAZ_SOURCE_DIR;
  const fs::path out = fs::temp_directory_path() / ("geohaz_chain_" + std::to_string(getpid()));
  fs::remove_all(out);
  // The bundled section example, shortened: 1.5 s of post-geostatic motion on a 35° hillside.
  const std::string sph = std::string(SPH_SLOPE_EXE) + " --config " + (src / "data/sph/section_dsm.toml").string() +
                          " --set run.end_time=1.5 --set run.stop_at_rest=false --set run.snapshot_interval=0" +
                          " --threads 2 --quiet --out " + (out / "slope").string();
  nlohmann::json slope;
  double handed = 0.0;
  ASSERT_NO_FATAL_FAILURE(run_slope(sph, out, slope, handed));

  // The release file itself sums to the same volume.
  geohaz::SnapshotReader rel(out / "slope" / "release.h5");
  const auto vol = rel.read(0, "volume");
  double sum = 0.0;
  for (double v : vol.values) sum += v;
  EXPECT_NEAR(sum, handed, 1e-9 * handed);
  EXPECT_EQ(rel.model(), "sph-slope-release");

  const std::string runout = std::string(DEBRIS_RUNOUT_EXE) + " " + (src / "data/sph/hillside_dsm.asc").string() +
                             " --release-from " + (out / "slope" / "release.h5").string() +
                             " --duration 60 --threads 2 --quiet --out " + (out / "runout").string();
  ASSERT_EQ(run(runout), 0) << runout;
  const auto flow = read_json(out / "runout" / "summary.json");
  const auto& v = flow["volumes_m3"];
  EXPECT_NEAR(v["release_read"].get<double>(), handed, 1e-9 * handed);
  EXPECT_NEAR(v["seeded"].get<double>(), handed, 1e-9 * handed);
  // Mass is conserved through the runout: what is deposited, moving or lost is what was seeded.
  EXPECT_NEAR(v["deposited"].get<double>() + v["mobile"].get<double>() + v["lost"].get<double>(), handed,
              1e-9 * handed);
  for (const char* map : {"max_depth.tif", "max_speed.tif", "max_pressure.tif", "deposit.tif", "arrival_time.tif"})
    EXPECT_TRUE(fs::exists(out / "runout" / map)) << map;
  fs::remove_all(out);
}

// The 3D variant: a 6 m wide strip of the same hillside centred on a 50 m polyline, with roller
// side walls following the terrain; each failed particle is handed over at its own map position
// with its own volume Δx³. The soil is weakened (φ = 20°, c = 1 kPa) because the 3D
// Drucker–Prager fit (compression cone) is stronger than the plane-strain one.
TEST(Chain, ThreeDStripOnTheDsmHandsOverItsParticles) {
  const fs::path src = GEOHAZ_SOURCE_DIR;
  const fs::path out = fs::temp_directory_path() / ("geohaz_chain3d_" + std::to_string(getpid()));
  fs::remove_all(out);
  const double y_axis = 4000040.0, width = 6.0;
  const std::string sph = std::string(SPH_SLOPE_EXE) + " --config " + (src / "data/sph/section_dsm.toml").string() +
                          " --set run.dimension=3 --set geometry.width=6 --set numerics.spacing=1.0" +
                          " --set section.polyline=[500030.0,4000040.0,500080.0,4000040.0]" +
                          " --set material[1].friction=20 --set material[1].cohesion=1e3" +
                          " --set run.end_time=1.0 --set run.stop_at_rest=false --set run.snapshot_interval=0" +
                          " --threads 2 --quiet --out " + (out / "slope").string();
  nlohmann::json slope;
  double handed = 0.0;
  ASSERT_NO_FATAL_FAILURE(run_slope(sph, out, slope, handed));
  // One point per failed particle of volume Δx³ = 1 m³, all on the strip.
  EXPECT_NEAR(handed, slope["failed_volume_m3"].get<double>(), 1e-9 * handed);
  geohaz::SnapshotReader rel(out / "slope" / "release.h5");
  const auto pos = rel.read(0, "position");
  const auto vol = rel.read(0, "volume");
  ASSERT_EQ(pos.count, vol.count);
  double sum = 0.0;
  for (std::size_t q = 0; q < vol.count; ++q) {
    sum += vol.values[q];
    EXPECT_NEAR(vol.values[q], 1.0, 1e-12);
    EXPECT_LE(std::abs(pos.values[2 * q + 1] - y_axis), 0.5 * width + 0.5) << "point " << q << " off the strip";
  }
  EXPECT_NEAR(sum, handed, 1e-9 * handed);

  const std::string runout = std::string(DEBRIS_RUNOUT_EXE) + " " + (src / "data/sph/hillside_dsm.asc").string() +
                             " --release-from " + (out / "slope" / "release.h5").string() +
                             " --duration 30 --threads 2 --quiet --out " + (out / "runout").string();
  ASSERT_EQ(run(runout), 0) << runout;
  const auto flow = read_json(out / "runout" / "summary.json");
  EXPECT_NEAR(flow["volumes_m3"]["release_read"].get<double>(), handed, 1e-9 * handed);
  EXPECT_NEAR(flow["volumes_m3"]["seeded"].get<double>(), handed, 1e-9 * handed);
  fs::remove_all(out);
}

}  // namespace
