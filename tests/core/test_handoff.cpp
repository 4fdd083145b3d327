// Unit tests for handoff.hpp: the sph-slope → debris-runout hand-off file (docs/handoff.md) round
// trips exactly, and the reader refuses every malformed file with an InputError naming the field.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/handoff.hpp"
#include "geohaz/core/snapshot.hpp"

namespace geohaz {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path d = fs::path(GEOHAZ_BINARY_DIR) / "test-scratch" / "handoff";
  fs::create_directories(d);
  return d / name;
}

Handoff sample() {
  Handoff h;
  for (int k = 0; k < 50; ++k) {
    h.points.emplace_back(480000.0 + 0.37 * k, 4309000.0 - 1.0 / 3.0 * k);
    h.volumes.push_back(0.1 + 0.01 * k);
  }
  h.crs_wkt = "LOCAL_CS[\"test\"]";
  h.source = "section.toml; 2D section; displacement > 0.01 m; width 10 m";
  h.bulking_factor = 1.25;
  h.time = 12.5;
  h.step = 4321;
  return h;
}

/// Write a file by hand with the hand-off layout but chosen fields/attributes.
void write_raw(const fs::path& p, const std::string& model, const std::vector<Vec2>& pts,
               const std::vector<double>& vol, double total_attr, bool with_volume = true) {
  SnapshotWriter w(p, model, 2, "");
  w.set_attribute("total_volume", total_attr);
  std::vector<FieldView> views{{"position", "m", ScalarType::Float64, pts.data(), pts.size(), 2, 1}};
  if (with_volume) views.push_back({"volume", "m^3", ScalarType::Float64, vol.data(), vol.size(), 1, 1});
  w.write(0.0, 0, views);
}

TEST(Handoff, RoundTripIsExact) {
  const Handoff h = sample();
  const fs::path p = scratch("roundtrip.h5");
  write_handoff(p, h, "[run]\nend_time = 1\n");
  const Handoff r = read_handoff(p);
  ASSERT_EQ(r.points.size(), h.points.size());
  for (std::size_t i = 0; i < h.points.size(); ++i) {
    EXPECT_EQ(r.points[i], h.points[i]) << i;  // bit for bit: doubles stored as doubles
    EXPECT_EQ(r.volumes[i], h.volumes[i]) << i;
  }
  EXPECT_EQ(r.crs_wkt, h.crs_wkt);
  EXPECT_EQ(r.source, h.source);
  EXPECT_EQ(r.bulking_factor, h.bulking_factor);
  EXPECT_EQ(r.time, h.time);
  EXPECT_EQ(r.step, h.step);
  EXPECT_EQ(r.total_volume(), h.total_volume());
}

TEST(Handoff, MismatchedPointsAndVolumesAreABugNotAFile) {
  Handoff h = sample();
  h.volumes.pop_back();
  EXPECT_THROW(write_handoff(scratch("bad.h5"), h, ""), std::invalid_argument);
}

/// The reader's refusal names the field of the problem.
void expect_refused(const fs::path& p, const std::string& key, const std::string& words) {
  try {
    read_handoff(p);
    ADD_FAILURE() << "read_handoff accepted " << p;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), p.string());
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(Handoff, ReaderRefusesMalformedFiles) {
  const std::vector<Vec2> pts{{1.0, 2.0}, {3.0, 4.0}};
  const std::vector<double> vol{0.5, 1.5};
  const fs::path p = scratch("malformed.h5");

  write_raw(p, "debris-runout", pts, vol, 2.0);  // a snapshot file of another model
  expect_refused(p, "model", "not a hand-off file");

  write_raw(p, kHandoffModel, pts, vol, 2.0, /*with_volume=*/false);
  expect_refused(p, "volume", "lacks the field");

  write_raw(p, kHandoffModel, pts, {0.5, -1.5}, -1.0);
  expect_refused(p, "volume", "negative or non-finite");

  write_raw(p, kHandoffModel, pts, {0.0, 0.0}, 0.0);  // sph-slope found no failed material
  expect_refused(p, "volume", "holds no volume");

  write_raw(p, kHandoffModel, {}, {}, 0.0);  // no points at all
  expect_refused(p, "volume", "holds no volume");

  write_raw(p, kHandoffModel, pts, vol, 2.5);  // the attribute says 2.5 m³, the points 2 m³
  expect_refused(p, "total_volume", "differs from the sum");
}

}  // namespace
}  // namespace geohaz
