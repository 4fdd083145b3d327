// Validation runs of the debris-runout model (label `validation`, not in CI; minutes). They print
// the figures quoted in docs/validation/runout.md and write the pictures to docs/figures/runout/.
//  1. The seed's scenario at its scale (seed 000 §3: a debris flow travelling 4.8 km in 10 min,
//     n = 0.06, i_cr = 0.15, 2.5 m DSM): the synthetic 5 km valley, 2000 × 1000 cells, ~5000
//     particles (d0 = 5 m).
//  2. Real terrain: the Alplehner DTM and release polygon (data/terrain/alr).
//  3. The Ritter dam break at a finer depth resolution (h0 = h/16) than the unit test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"
#include "geohaz/runout/solver.hpp"
#include "run_command.hpp"

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace {

int run(const std::string& args, std::string* output = nullptr) {
  const auto r = geohaz::testing::run_command(std::string(DEBRIS_RUNOUT_EXE) + " " + args);
  std::fputs(r.output.c_str(), stdout);
  if (output) *output = r.output;
  return r.code;
}

fs::path work_dir() {
  const fs::path d = fs::path(GEOHAZ_BINARY_DIR) / "tests" / "runout" / "validation_work";
  fs::create_directories(d);
  return d;
}
fs::path figures() {
  const fs::path d = fs::path(GEOHAZ_SOURCE_DIR) / "docs" / "figures" / "runout";
  fs::create_directories(d);
  return d;
}

// Columns of series.csv by name.
std::vector<std::vector<double>> read_series(const fs::path& csv, std::vector<std::string>& header) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::stringstream hs(line);
  for (std::string h; std::getline(hs, h, ',');) header.push_back(h);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::vector<double> row;
    for (std::string v; std::getline(ls, v, ',');) row.push_back(std::stod(v));
    rows.push_back(row);
  }
  return rows;
}

// A line plot of the front's travelled distance against time, with the seed's point marked.
void plot_front(const fs::path& csv, const fs::path& png, double seed_t, double seed_s) {
  std::vector<std::string> h;
  const auto rows = read_series(csv, h);
  const auto col = [&](const char* name) { return std::find(h.begin(), h.end(), name) - h.begin(); };
  const auto ct = col("time_s"), cs = col("front_travel_m");
  const int W = 640, H = 400, m = 50;
  Image img(W, H);
  const double tmax = std::max(seed_t, rows.back()[ct]) * 1.05, smax = std::max(seed_s, rows.back()[cs]) * 1.1;
  const auto px = [&](double t) { return m + (W - 2 * m) * t / tmax; };
  const auto py = [&](double s) { return H - m - (H - 2 * m) * s / smax; };
  img.line(px(0), py(0), px(tmax), py(0), {0, 0, 0});
  img.line(px(0), py(0), px(0), py(smax), {0, 0, 0});
  for (double t = 0; t <= tmax; t += 60) img.line(px(t), py(0), px(t), py(0) + 5, {0, 0, 0});
  for (double s = 0; s <= smax; s += 1000) img.line(px(0) - 5, py(s), px(0), py(s), {0, 0, 0});
  for (std::size_t k = 1; k < rows.size(); ++k)
    img.line(px(rows[k - 1][ct]), py(rows[k - 1][cs]), px(rows[k][ct]), py(rows[k][cs]), {30, 90, 200});
  img.fill_circle(px(seed_t), py(seed_s), 6, {220, 40, 40});
  write_png(png, img);
}

}  // namespace

TEST(RunoutValidation, SeedScenarioFiveKilometreValley) {
  const fs::path dsm = work_dir() / "valley.tif";
  ASSERT_EQ(run("--make-synthetic-dsm " + dsm.string()), 0);
  const fs::path out = work_dir() / "valley_out";
  fs::remove_all(out);
  ASSERT_EQ(run(dsm.string() + " --release " + (work_dir() / "valley_release.tif").string() +
                " --n 0.06 --icr 0.15 --d0 5 --h0 1 --duration 600 --out " + out.string() +
                " --set output.snapshot_interval=60"),
            0);
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  const double travel = j["runout_length_along_path_m"];
  std::printf(
      "VALIDATION seed scenario: %d particles, %.0f m^3, front travelled %.0f m in %.0f s (seed: 4800 m in "
      "600 s), H/L = %.3f (%.1f deg), max speed %.1f m/s, wall %.1f s, steps %d\n",
      j["particles_released"].get<int>(), j["volumes_m3"]["seeded"].get<double>(), travel,
      j["simulated_time_s"].get<double>(), j["fahrboeschung"]["ratio_H_over_L"].get<double>(),
      j["fahrboeschung"]["angle_deg"].get<double>(), j["max_speed_m_s"].get<double>(), j["wall_time_s"].get<double>(),
      j["steps"].get<int>());
  // "Travels kilometres in ten minutes": within a factor 2 of the seed's 4.8 km.
  EXPECT_GT(travel, 2400.0);
  EXPECT_LT(travel, 9600.0);
  EXPECT_LT(std::abs(j["mass_balance_error_relative"].get<double>()), 1e-12);
  fs::copy_file(out / "deposit.png", figures() / "valley_deposit.png", fs::copy_options::overwrite_existing);
  fs::copy_file(out / "max_speed.png", figures() / "valley_max_speed.png", fs::copy_options::overwrite_existing);
  plot_front(out / "series.csv", figures() / "valley_front_travel.png", 600.0, 4800.0);
  fs::copy_file(out / "summary.json", figures() / "valley_summary.json", fs::copy_options::overwrite_existing);
}

TEST(RunoutValidation, AlpineTerrainAlr) {
  const fs::path cfg = fs::path(GEOHAZ_SOURCE_DIR) / "data" / "runout" / "alr.toml";
  if (!fs::exists(fs::path(GEOHAZ_SOURCE_DIR) / "data" / "terrain" / "alr" / "avaAlr.tif"))
    GTEST_SKIP() << "data/terrain/alr not present";
  const fs::path out = work_dir() / "alr_out";
  fs::remove_all(out);
  ASSERT_EQ(run("--config " + cfg.string() + " --out " + out.string()), 0);
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  std::printf(
      "VALIDATION alr: %d particles, %.0f m^3, run-out %.0f m along the path, H/L = %.3f (%.1f deg), max "
      "speed %.1f m/s, affected %.0f m^2, deposited %.0f m^3, lost %.0f m^3, ended by %s at %.0f s, wall %.1f s\n",
      j["particles_released"].get<int>(), j["volumes_m3"]["seeded"].get<double>(),
      j["runout_length_along_path_m"].get<double>(), j["fahrboeschung"]["ratio_H_over_L"].get<double>(),
      j["fahrboeschung"]["angle_deg"].get<double>(), j["max_speed_m_s"].get<double>(),
      j["area_affected_m2"].get<double>(), j["volumes_m3"]["deposited"].get<double>(),
      j["volumes_m3"]["lost"].get<double>(), j["ended_by"].get<std::string>().c_str(),
      j["simulated_time_s"].get<double>(), j["wall_time_s"].get<double>());
  // The data README: a ~4 ha, 1 m release running more than 2 km down to the valley floor.
  EXPECT_NEAR(j["volumes_m3"]["release_read"].get<double>(), 4.1e4, 0.2 * 4.1e4);
  EXPECT_GT(j["runout_length_along_path_m"].get<double>(), 1000.0);
  fs::copy_file(out / "deposit.png", figures() / "alr_deposit.png", fs::copy_options::overwrite_existing);
  fs::copy_file(out / "max_speed.png", figures() / "alr_max_speed.png", fs::copy_options::overwrite_existing);
  fs::copy_file(out / "summary.json", figures() / "alr_summary.json", fs::copy_options::overwrite_existing);
}

TEST(RunoutValidation, DamBreakFineDepthResolution) {
  // As the unit test, with h0 = h/16 (spacing d0/4): the Ritter profile and the wet front.
  RunoutParameters p;
  p.d0 = 1.0;
  p.h0 = 1.0 / 16.0;
  p.duration = 10.0;
  p.cfl = 0.25;
  p.friction = CoulombFriction{0.0};
  const double h = 1.0, d = p.d0 * std::sqrt(p.h0 / h), c = std::sqrt(9.81 * h);
  const int nx = static_cast<int>(100 / d), ny = static_cast<int>(6 / d);
  Periodicity<2> per;
  per.axis = {false, true};
  per.lo = Vec2(-1e3, 0);
  per.hi = Vec2(1e3, ny * d);
  RunoutSolver<InclinedPlane> s(InclinedPlane{}, p, per);
  auto& st = s.particles();
  st.append(static_cast<std::size_t>(nx * ny));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto k = static_cast<std::size_t>(j * nx + i);
      st.get<Position<2>>()[k] = Vec2(-nx * d + (i + 0.5) * d, (j + 0.5) * d);
      st.get<Volume>()[k] = p.nominal_volume();
    }
  s.initialise();
  while (!s.finished()) s.step();
  const auto& x = st.get<Position<2>>();
  const auto& hh = st.get<FlowDepth>();
  double front = -1e9, hd = 0.0;
  int k = 0;
  for (std::size_t i = 0; i < st.size(); ++i) {
    front = std::max(front, x[i].x());
    if (std::abs(x[i].x()) < 1.0) {
      hd += hh[i];
      ++k;
    }
  }
  hd /= k;
  {
    // Depth of every particle (grey dots) against Ritter's profile (red) at t = 10 s.
    const int W = 800, H = 400, m = 40;
    Image img(W, H);
    const double x0 = -60.0, x1 = 70.0;
    const auto px = [&](double xx) { return m + (W - 2 * m) * (xx - x0) / (x1 - x0); };
    const auto py = [&](double hh_) { return H - m - (H - 2 * m) * hh_ / 1.1; };
    img.line(px(x0), py(0), px(x1), py(0), {0, 0, 0});
    img.line(px(0), py(0), px(0), py(1.1), {0, 0, 0});
    for (double xx = -60; xx <= 70; xx += 10) img.line(px(xx), py(0), px(xx), py(0) + 5, {0, 0, 0});
    for (std::size_t i = 0; i < st.size(); ++i)
      if (x[i].x() > x0 && x[i].x() < x1) img.fill_circle(px(x[i].x()), py(hh[i]), 1.2, {90, 90, 160});
    const double t = s.time();
    double xp = x0, hp = h;
    for (double xx = x0; xx <= x1; xx += 0.25) {
      const double xi = xx / t;
      const double hr = xi < -c ? h : (xi > 2 * c ? 0.0 : (2 * c - xi) * (2 * c - xi) / (9 * 9.81));
      img.line(px(xp), py(hp), px(xx), py(hr), {220, 40, 40});
      xp = xx;
      hp = hr;
    }
    write_png(figures() / "dam_break_ritter.png", img);
  }
  std::printf(
      "VALIDATION dam break h0 = h/16: front speed %.3f m/s = %.3f x 2 sqrt(g h); depth at dam %.3f m (Ritter "
      "4h/9 = %.3f m)\n",
      front / s.time(), front / s.time() / (2 * c), hd, 4.0 / 9.0);
  // Measured: +11 % at the dam (0.49 m) for h0 = h/16, against +20 % for h0 = h/4: the excess
  // shrinks with the depth resolution; 15 % keeps this run honest without hiding a regression.
  EXPECT_NEAR(hd, 4.0 * h / 9.0, 0.15 * 4.0 * h / 9.0);
  EXPECT_GT(front / s.time(), 0.6 * 2 * c);
  EXPECT_LE(front / s.time(), 2 * c);
}
