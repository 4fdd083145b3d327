// The thalweg long profile (profile.hpp, issue #33): on an inclined plane carrying a uniform flow
// in a straight strip, the profile along the strip is the analytic one.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster_extra.hpp"
#include "geohaz/runout/profile.hpp"

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace {

// A 30° plane falling to the east, 5 m cells, 200 × 40 cells (1000 m × 200 m).
constexpr double kDx = 5.0, kX0 = 500000.0, kY0 = 5200000.0, kZ0 = 2000.0;
const double kTan = std::tan(30.0 * M_PI / 180.0);

Raster plane() {
  Raster r;
  r.nx = 200;
  r.ny = 40;
  r.geotransform = {kX0, kDx, 0.0, kY0, 0.0, -kDx};
  r.crs_wkt = crs_to_wkt("EPSG:32632");
  r.nodata = -9999.0;
  r.data.resize(static_cast<std::size_t>(r.nx) * r.ny);
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) r.at(col, row) = kZ0 - kTan * (r.cell_centre(col, row).x() - kX0);
  return r;
}

}  // namespace

// A uniform flow of depth h = 1.2 m at v = 8 m/s (pressure ρv² with ρ = 2000 kg/m³) covers the cells
// from 100 m to 600 m east, rows 15–24. Along the strip's centre line from 50 m to 700 m, sampled
// every metre: the terrain is the plane (bilinear is exact on a plane), the peak values are h, v
// and ρv² inside the reached part and 0 outside, the run-out point is the last sample before 600 m,
// and α is the plane's 30° (any two points of a plane along its fall line give its slope).
TEST(ThalwegProfile, UniformFlowOnAPlaneGivesTheAnalyticProfile) {
  const Raster dsm = plane();
  Raster depth = dsm.like(0.0, -9999.0), speed = depth, pressure = depth;
  const double h = 1.2, v = 8.0, rho = 2000.0;
  for (int row = 15; row < 25; ++row)
    for (int col = 20; col < 120; ++col) {
      depth.at(col, row) = h;
      speed.at(col, row) = v;
      pressure.at(col, row) = rho * v * v;
    }
  const double yc = kY0 - 20 * kDx;  // the strip's centre line (between rows 19 and 20)
  const ThalwegProfile p =
      thalweg_profile(dsm, depth, speed, pressure, {{kX0 + 50.0, yc}, {kX0 + 700.0, yc}}, 1.0, 0.01);
  ASSERT_EQ(p.rows.size(), 651u);
  ASSERT_TRUE(p.reached);
  for (const ProfileRow& r : p.rows) {
    const double x = r.x - kX0;
    EXPECT_NEAR(r.s, x - 50.0, 1e-9);
    EXPECT_NEAR(r.z, kZ0 - kTan * x, 1e-9) << x;
    const bool inside = x >= 100.0 && x < 600.0;
    EXPECT_DOUBLE_EQ(r.depth, inside ? h : 0.0) << x;
    EXPECT_DOUBLE_EQ(r.speed, inside ? v : 0.0) << x;
    EXPECT_DOUBLE_EQ(r.pressure, inside ? rho * v * v : 0.0) << x;
    // The α line runs along the plane itself here.
    EXPECT_NEAR(r.alpha_z, r.z, 1e-9) << x;
  }
  EXPECT_DOUBLE_EQ(p.s_top, 50.0);      // x = 100 m, the first reached sample
  EXPECT_DOUBLE_EQ(p.s_runout, 549.0);  // x = 599 m, the last sample inside the last cell
  EXPECT_NEAR(p.alpha_deg, 30.0, 1e-9);
  EXPECT_NEAR(p.z_top - p.z_runout, kTan * 499.0, 1e-9);
  // H, L and H/L of the profile's own reach (summary.json's "profile" block): along the plane.
  const ProfileReach reach = profile_reach(p);
  EXPECT_NEAR(reach.drop_height, kTan * 499.0, 1e-9);
  EXPECT_DOUBLE_EQ(reach.length, 499.0);
  EXPECT_NEAR(reach.ratio, kTan, 1e-12);

  // The files: a CSV row per sample and a picture.
  const fs::path dir = fs::temp_directory_path() / ("geohaz_profile_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  write_profile_csv(dir / "profile.csv", p);
  write_profile_png(dir / "profile.png", p);
  const Image img = read_image(dir / "profile.png");
  EXPECT_EQ(img.width, 1800);
  std::ifstream in(dir / "profile.csv");
  std::string line;
  int lines = 0;
  while (std::getline(in, line)) ++lines;
  EXPECT_EQ(lines, 652);
  // Both reaches named on the figure: the toe path's H/L dashed in orange from the top, and a
  // marked station (an observed run-out) as a vertical line in its colour (pixel counts: the
  // dashed line, antialiased, and the vertical 3 x 700 px line on whole pixels, against none).
  const auto count = [&](const Image& im, std::array<std::uint8_t, 3> c) {
    int n = 0;
    for (std::size_t k = 0; k + 2 < im.rgb.size(); k += 3)
      n += im.rgb[k] == c[0] && im.rgb[k + 1] == c[1] && im.rgb[k + 2] == c[2];
    return n;
  };
  const std::array<std::uint8_t, 3> orange{230, 140, 20}, blue{31, 119, 180};
  EXPECT_EQ(count(img, orange), 0);
  ProfileFigure f;
  f.toe_path_angle_deg = 35.0;
  f.marks = {{300.0, "observed run-out", blue}};
  write_profile_png(dir / "profile_marked.png", p, f);
  const Image marked = read_image(dir / "profile_marked.png");
  EXPECT_GT(count(marked, orange), 100);
  EXPECT_GT(count(marked, blue), 1500);
  fs::remove_all(dir);
}

// The flow's own centreline keeps the start and the fronts at least one spacing apart.
TEST(ThalwegProfile, CentrelineThinsTheFronts) {
  const auto c = flow_centreline({0, 0}, {{0.5, 0}, {2, 0}, {2.5, 0}, {6, 0}}, 1.0);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_DOUBLE_EQ(c[1].x(), 2.0);
  EXPECT_DOUBLE_EQ(c[2].x(), 6.0);
}

// A path off the terrain is an input error naming the point.
TEST(ThalwegProfile, PathOffTheTerrainIsAnInputError) {
  const Raster dsm = plane();
  const Raster zero = dsm.like(0.0, -9999.0);
  EXPECT_THROW(
      thalweg_profile(dsm, zero, zero, zero, {{kX0 + 50.0, kY0 - 50.0}, {kX0 + 5000.0, kY0 - 50.0}}, 1.0, 0.01),
      InputError);
}

// The centreline from the arrival map: a flow whose front moves east by 10 m each second in a
// 50 m wide strip, with a lone cell reached far to the north at 5 s; the depth-weighted centroid
// of each second's front stays on the strip's axis, the lone cell pulls one point by its weight
// share only.
TEST(ThalwegProfile, ArrivalCentrelineFollowsTheBulkOfTheFlow) {
  const Raster dsm = plane();
  Raster arrival = dsm.like(-9999.0, -9999.0), depth = dsm.like(0.0, -9999.0);
  for (int row = 15; row < 25; ++row)
    for (int col = 0; col < 100; ++col) {
      arrival.at(col, row) = 0.5 * col + 0.25;  // 2 cells (10 m) per second
      depth.at(col, row) = 1.0;
    }
  arrival.at(50, 2) = 5.1;  // the lone cell, 1 m deep like the others
  depth.at(50, 2) = 1.0;
  const Vec2 start(kX0, kY0 - 100.0);
  const auto c = arrival_centreline(arrival, depth, start, 1.0, 5.0);
  ASSERT_GE(c.size(), 40u);
  const double axis = kY0 - 100.0;  // between rows 19 and 20
  int off_axis = 0;
  for (std::size_t k = 1; k < c.size(); ++k) {
    if (std::abs(c[k].y() - axis) > 1e-6) ++off_axis;
    EXPECT_LT(std::abs(c[k].y() - axis), (kY0 - 12.5 - axis) / 21.0 + 1e-6);  // at most 1/21 of the way
    if (k > 1) {
      EXPECT_GT(c[k].x(), c[k - 1].x());  // in order of time
    }
  }
  EXPECT_EQ(off_axis, 1);
}

// Issue #33 item 3: a path beside the flow (a centreline cutting a bend runs so). The strip of the
// first test (h, v on rows 15–24, x = 100–600 m) and a second strip twice as deep 115 m south of
// the path; the path runs 20 m north of the first strip. Read under the path only (half-width 0)
// every station is 0 — the gaps of the Alplehner profile. Across ±30 m the stations beside the
// strip read its h, v and ρv² and the others 0; the second strip, beyond the half-width, is not
// read. Across ±130 m it is (its 2h), so the half-width is what limits the section.
TEST(ThalwegProfile, PeaksAcrossThePathFillTheGapsBesideTheFlow) {
  const Raster dsm = plane();
  Raster depth = dsm.like(0.0, -9999.0), speed = depth, pressure = depth;
  const double h = 1.2, v = 8.0, rho = 2000.0;
  for (int col = 20; col < 120; ++col) {
    for (int row = 15; row < 25; ++row) {
      depth.at(col, row) = h;
      speed.at(col, row) = v;
      pressure.at(col, row) = rho * v * v;
    }
    for (int row = 34; row < 39; ++row) {
      depth.at(col, row) = 2.0 * h;
      speed.at(col, row) = v;
      pressure.at(col, row) = rho * v * v;
    }
  }
  const double y = kY0 - 55.0;  // the strip's north edge is at kY0 − 75 m
  const std::vector<Vec2> path{{kX0 + 50.0, y}, {kX0 + 700.0, y}};
  const ThalwegProfile under = thalweg_profile(dsm, depth, speed, pressure, path, 1.0, 0.01, 0.0);
  EXPECT_FALSE(under.reached);
  for (const ProfileRow& r : under.rows) EXPECT_EQ(r.depth, 0.0);
  const ThalwegProfile across = thalweg_profile(dsm, depth, speed, pressure, path, 1.0, 0.01, 30.0);
  ASSERT_TRUE(across.reached);
  for (const ProfileRow& r : across.rows) {
    const double x = r.x - kX0;
    const bool beside = x >= 100.0 && x < 600.0;
    EXPECT_DOUBLE_EQ(r.depth, beside ? h : 0.0) << x;
    EXPECT_DOUBLE_EQ(r.speed, beside ? v : 0.0) << x;
    EXPECT_DOUBLE_EQ(r.pressure, beside ? rho * v * v : 0.0) << x;
  }
  EXPECT_DOUBLE_EQ(across.s_runout, 549.0);
  EXPECT_NEAR(across.alpha_deg, 30.0, 1e-9);
  const ThalwegProfile wide = thalweg_profile(dsm, depth, speed, pressure, path, 1.0, 0.01, 130.0);
  for (const ProfileRow& r : wide.rows) {
    const double x = r.x - kX0;
    EXPECT_DOUBLE_EQ(r.depth, x >= 100.0 && x < 600.0 ? 2.0 * h : 0.0) << x;
  }
}

// A user's path off the terrain is an InputError naming the key, the point and the extent; a path
// without length too.
TEST(ThalwegProfile, UserPathOffTheTerrainIsRefusedBeforeTheRun) {
  const Raster dsm = plane();
  try {
    check_profile_path({{kX0 + 50.0, kY0 - 50.0}, {kX0 + 1500.0, kY0 - 50.0}}, dsm, "case.toml", "output.profile_path");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    for (const char* part : {"case.toml", "output.profile_path", "5199950.0)", "x in [500000.0, 501000.0]"})
      EXPECT_NE(m.find(part), std::string::npos) << part << " in " << m;
  }
  EXPECT_THROW(check_profile_path({{kX0 + 50.0, kY0 - 50.0}, {kX0 + 50.0, kY0 - 50.0}}, dsm, "c", "k"), InputError);
  EXPECT_NO_THROW(check_profile_path({{kX0 + 50.0, kY0 - 50.0}, {kX0 + 900.0, kY0 - 150.0}}, dsm, "c", "k"));
}
