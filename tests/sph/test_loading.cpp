// Unit tests of the earthquake loading (loading.hpp): sine with ramps, accelerogram interpolation
// and CSV parsing with the InputError rules.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "geohaz/core/errors.hpp"
#include "geohaz/sph/loading.hpp"

namespace geohaz::sph {
namespace {

TEST(EarthquakeLoading, NoneIsZero) {
  EarthquakeLoading e;
  EXPECT_FALSE(e.active());
  EXPECT_EQ(e.horizontal(1.0), 0.0);
}

TEST(EarthquakeLoading, SineWithRamps) {
  // 1 Hz, 500 gal (SWJTU lecture 2010), from t = 1 s for 4 s, 0.5 s ramps.
  const auto e = EarthquakeLoading::sine(5.0, 1.0, 1.0, 4.0, 0.5);
  EXPECT_TRUE(e.active());
  EXPECT_EQ(e.horizontal(0.5), 0.0);
  EXPECT_EQ(e.horizontal(5.5), 0.0);
  // Full amplitude inside: t − t0 = 1.25 s → sin(2π·1.25) = 1.
  EXPECT_NEAR(e.horizontal(2.25), 5.0, 1e-12);
  // Within the ramp: t − t0 = 0.25 s → r = 0.5, sin(π/2) = 1.
  EXPECT_NEAR(e.horizontal(1.25), 2.5, 1e-12);
  // End ramp: t − t0 = 3.75 s → r = 0.5, sin(2π·3.75) = −1.
  EXPECT_NEAR(e.horizontal(4.75), -2.5, 1e-12);
  EXPECT_EQ(e.vertical(2.0), 0.0);
  EXPECT_DOUBLE_EQ(e.end_time(), 5.0);
}

TEST(EarthquakeLoading, RecordInterpolates) {
  const auto e = EarthquakeLoading::record({0.0, 1.0, 2.0}, {0.0, 2.0, -2.0}, {1.0, 1.0, 3.0});
  EXPECT_NEAR(e.horizontal(0.5), 1.0, 1e-12);
  EXPECT_NEAR(e.horizontal(1.5), 0.0, 1e-12);
  EXPECT_NEAR(e.vertical(1.5), 2.0, 1e-12);
  EXPECT_EQ(e.horizontal(2.5), 0.0);
  EXPECT_THROW(EarthquakeLoading::record({0.0, 0.0}, {1.0, 1.0}, {}), InputError);
}

TEST(EarthquakeLoading, CsvParsing) {
  const auto dir = std::filesystem::temp_directory_path() / "geohaz_sph_loading_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir / "ok.csv");
    f << "# accelerogram\ntime_s,a_h\n0,0\n0.1, 1.5\n0.2,-1.5 # comment\n";
  }
  const auto e = EarthquakeLoading::read_csv(dir / "ok.csv");
  EXPECT_NEAR(e.horizontal(0.15), 0.0, 1e-12);
  EXPECT_NEAR(e.horizontal(0.05), 0.75, 1e-12);
  {
    std::ofstream f(dir / "bad.csv");
    f << "time,a_h\n0,0\n0.1,abc\n";
  }
  try {
    EarthquakeLoading::read_csv(dir / "bad.csv");
    FAIL() << "expected InputError";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("line 3"), std::string::npos) << err.what();
    EXPECT_EQ(err.file(), (dir / "bad.csv").string());
  }
  {
    std::ofstream f(dir / "decreasing.csv");
    f << "0,0\n0.2,1\n0.1,2\n";
  }
  EXPECT_THROW(EarthquakeLoading::read_csv(dir / "decreasing.csv"), InputError);
  EXPECT_THROW(EarthquakeLoading::read_csv(dir / "missing.csv"), InputError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace geohaz::sph
