// Validation runs of the debris-runout model (label `validation`, not in CI; minutes). They print
// the figures quoted in docs/validation/runout.md and write the pictures to docs/figures/runout/.
//  1. The lecture's scenario at its scale (SWJTU lecture 2010, §3: a debris flow travelling 4.8 km in 10 min,
//     n = 0.06, i_cr = 0.15, 2.5 m DSM): the synthetic 5 km valley, 2000 × 1000 cells, ~5000
//     particles (d0 = 5 m).
//  2. Real terrain: the Alplehner DTM and release polygon (data/terrain/alr).
//  3. The Ritter dam break at a finer depth resolution (h0 = h/16) than the unit test.
//  4. Real terrain against a peer: the Alplehner release with Voellmy friction as AvaFrame com1DFA
//     runs it, against com1DFA's numbers measured on the same DTM; and its convergence in d0.
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

// A line plot of the front's travelled distance against time, with the lecture's point marked.
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

/// Force per metre (blue, left axis 0–fmax) and overtopped volume (red, right axis 0–vmax) against
/// time from a barrier's CSV (docs/runout.md, "Barriers").
void plot_barrier(const fs::path& csv, const fs::path& png) {
  std::vector<std::string> h;
  const auto rows = read_series(csv, h);
  const auto col = [&](const char* name) { return std::find(h.begin(), h.end(), name) - h.begin(); };
  const auto ct = col("time_s"), cf = col("force_per_m_N_m"), cv = col("overtopped_volume_m3");
  double tmax = 0.0, fmax = 0.0, vmax = 0.0;
  for (const auto& r : rows) {
    tmax = std::max(tmax, r[ct]);
    fmax = std::max(fmax, r[cf]);
    vmax = std::max(vmax, r[cv]);
  }
  fmax = std::max(fmax * 1.1, 1.0);
  vmax = std::max(vmax * 1.1, 1.0);
  const int W = 640, H = 400, m = 50;
  Image img(W, H);
  const auto px = [&](double t) { return m + (W - 2 * m) * t / tmax; };
  const auto py = [&](double f, double top) { return H - m - (H - 2 * m) * f / top; };
  img.line(px(0), py(0, 1), px(tmax), py(0, 1), {0, 0, 0});
  img.line(px(0), py(0, 1), px(0), py(1, 1), {0, 0, 0});
  img.line(px(tmax), py(0, 1), px(tmax), py(1, 1), {0, 0, 0});
  for (double t = 0; t <= tmax; t += 30) img.line(px(t), py(0, 1), px(t), py(0, 1) + 5, {0, 0, 0});
  for (std::size_t k = 1; k < rows.size(); ++k) {
    img.line(px(rows[k - 1][ct]), py(rows[k - 1][cf], fmax), px(rows[k][ct]), py(rows[k][cf], fmax), {30, 90, 200});
    img.line(px(rows[k - 1][ct]), py(rows[k - 1][cv], vmax), px(rows[k][ct]), py(rows[k][cv], vmax), {220, 40, 40});
  }
  write_png(png, img);
}

}  // namespace

// The check dam of data/runout/alr_check_dam.toml (docs/runout.md, "Barriers"): the force history
// figure and the volumes: retained + overtopped within the release.
TEST(RunoutValidation, AlplehnerCheckDam) {
  const fs::path cfg = fs::path(GEOHAZ_SOURCE_DIR) / "data" / "runout" / "alr_check_dam.toml";
  if (!fs::exists(fs::path(GEOHAZ_SOURCE_DIR) / "data" / "terrain" / "alr" / "avaAlr.tif"))
    GTEST_SKIP() << "data/terrain/alr not present";
  const fs::path out = work_dir() / "alr_dam_out";
  fs::remove_all(out);
  ASSERT_EQ(run("--config " + cfg.string() + " --out " + out.string()), 0);
  std::ifstream in(out / "summary.json");
  const auto j = nlohmann::json::parse(in);
  const auto& b = j["barriers"][0];
  const double read = j["volumes_m3"]["release_read"];
  std::printf(
      "VALIDATION alr check dam: retained %.0f m^3, overtopped %.0f m^3 of %.0f m^3; peak force %.3g N, %.3g N/m, "
      "peak pressure %.3g Pa; run-out %.0f m\n",
      b["retained_volume_m3"].get<double>(), b["overtopped_volume_m3"].get<double>(), read,
      b["peak_force_n"].get<double>(), b["peak_force_per_m_n_m"].get<double>(), b["peak_pressure_pa"].get<double>(),
      j["runout_length_along_path_m"].get<double>());
  EXPECT_LE(b["retained_volume_m3"].get<double>() + b["overtopped_volume_m3"].get<double>(), read * (1.0 + 1e-9));
  EXPECT_GT(b["retained_volume_m3"].get<double>(), 0.0);
  plot_barrier(out / "barriers" / (b["name"].get<std::string>() + ".csv"), figures() / "alr_check_dam_force.png");
}

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
      "VALIDATION lecture scenario: %d particles, %.0f m^3, front travelled %.0f m in %.0f s (lecture: 4800 m in "
      "600 s), H/L = %.3f (%.1f deg), max speed %.1f m/s, wall %.1f s, steps %d\n",
      j["particles_released"].get<int>(), j["volumes_m3"]["seeded"].get<double>(), travel,
      j["simulated_time_s"].get<double>(), j["fahrboeschung"]["ratio_H_over_L"].get<double>(),
      j["fahrboeschung"]["angle_deg"].get<double>(), j["max_speed_m_per_s"].get<double>(),
      j["wall_time_s"].get<double>(), j["steps"].get<int>());
  // "Travels kilometres in ten minutes": within a factor 2 of the lecture's 4.8 km.
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
      j["fahrboeschung"]["angle_deg"].get<double>(), j["max_speed_m_per_s"].get<double>(),
      j["area_affected_m2"].get<double>(), j["volumes_m3"]["deposited"].get<double>(),
      j["volumes_m3"]["lost"].get<double>(), j["ended_by"].get<std::string>().c_str(),
      j["simulated_time_s"].get<double>(), j["wall_time_s"].get<double>());
  // The data README: a ~4 ha, 1 m release (normal to the slope: 52,773 m³ in AvaFrame com1DFA,
  // which computes the surface area of its grid cells its own way) running more than 2 km down.
  EXPECT_NEAR(j["volumes_m3"]["release_read"].get<double>(), 52773.0, 0.01 * 52773.0);
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
  p.lateral_mixing = 0.0;  // Ritter's inviscid system (see test_dam_break.cpp)
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

namespace {

/// Raster metrics of a run on the Alplehner DTM, as AvaFrame's AIMEC-like comparison makes them
/// (../shared/peers/avaframe/metrics.py): cells with peak flow thickness > 0.1 m; run-out = the
/// largest along-thalweg coordinate of such a cell minus that of the top of the release (the
/// highest DTM cell in the release polygon), every cell projected on the nearest point of the
/// thalweg densified to 1 m.
struct ThalwegMetrics {
  double runout = 0.0, area_ha = 0.0, h_over_l = 0.0;
};
ThalwegMetrics thalweg_metrics(const fs::path& max_depth) {
  const fs::path alr = fs::path(GEOHAZ_SOURCE_DIR) / "data" / "terrain" / "alr";
  const Raster dem = read_raster(alr / "avaAlr.tif");
  const Raster h = read_raster(max_depth);
  const auto rel = read_polygons(alr / "relAlr.shp", "", dem.crs_wkt);
  const auto path = read_lines(alr / "path_aimec.shp", "", dem.crs_wkt).front().vertices;
  std::vector<Vec2> dense;
  for (std::size_t k = 1; k < path.size(); ++k) {
    const Vec2 a = path[k - 1], b = path[k];
    const int n = std::max(1, static_cast<int>((b - a).norm()));
    for (int q = 0; q < n; ++q) dense.push_back(a + (b - a) * (static_cast<double>(q) / n));
  }
  const auto along = [&](const Vec2& p) {  // 1 m spacing: the index is the coordinate in metres
    std::size_t best = 0;
    for (std::size_t k = 0; k < dense.size(); ++k)
      if ((dense[k] - p).squaredNorm() < (dense[best] - p).squaredNorm()) best = k;
    return static_cast<double>(best);
  };
  double ztop = -1e300;
  Vec2 top = Vec2::Zero();
  double s_max = -1e300, z_runout = 0.0;
  ThalwegMetrics m;
  for (int r = 0; r < dem.ny; ++r)
    for (int c = 0; c < dem.nx; ++c) {
      const Vec2 p = dem.cell_centre(c, r);
      if (rel.front().contains(p) && dem.at(c, r) > ztop) {
        ztop = dem.at(c, r);
        top = p;
      }
      const double v = h.at(c, r);
      if (h.is_nodata(v) || !(v > 0.1)) continue;
      m.area_ha += dem.cell_size_x() * dem.cell_size_y() / 1e4;
      const double s = along(p);
      if (s > s_max) {
        s_max = s;
        z_runout = dem.at(c, r);
      }
    }
  m.runout = s_max - along(top);
  m.h_over_l = (ztop - z_runout) / m.runout;
  return m;
}

/// The com1DFA side (AvaFrame 21e4b944, Debian Python 3.11, `frictModel = Voellmy`, μ = 0.155,
/// ξ = 4000 m/s², 1 m release normal to the slope, its defaults otherwise: sphOption 1, SAMOS
/// artificial viscosity, curvature in the friction, stop at 1 % of the peak kinetic energy),
/// measured with the metrics above (docs/validation/runout.md, "Against AvaFrame com1DFA").
constexpr double kCom1dfaRunout = 2946.0, kCom1dfaAreaHa = 36.2, kCom1dfaPeakSpeed = 56.7;

}  // namespace

TEST(RunoutValidation, AlpineTerrainVoellmyAgainstCom1DFA) {
  // The same release (1 m normal to the slope), law and coefficients as com1DFA, its particle
  // volume (h0 = 0.25 m, d0 = 5 m: ~6.25 m³) and kernel radius. Acceptance (issue 13): < 0.5 % of
  // the volume lost at the DTM edge; run-out along the thalweg within 10 %, area with peak
  // thickness > 0.1 m within 30 %, peak speed within 30 % of com1DFA's.
  const fs::path alr = fs::path(GEOHAZ_SOURCE_DIR) / "data" / "terrain" / "alr";
  for (const double d0 : {5.0, 3.5, 2.5}) {
    const fs::path out = work_dir() / ("alr_voellmy_d" + std::to_string(d0));
    fs::remove_all(out);
    std::ostringstream args;
    args << (alr / "avaAlr.tif").string() << " --release " << (alr / "relAlr.shp").string()
         << " --friction voellmy --mu 0.155 --xi 4000 --h0 0.25 --d0 " << d0
         << " --duration 400 --set output.snapshots=false --quiet --out " << out.string();
    ASSERT_EQ(run(args.str()), 0);
    std::ifstream in(out / "summary.json");
    const auto j = nlohmann::json::parse(in);
    const ThalwegMetrics m = thalweg_metrics(out / "max_depth.tif");
    const double lost = j["volumes_m3"]["lost"].get<double>() / j["volumes_m3"]["seeded"].get<double>();
    const double vmax = j["max_speed_m_per_s"].get<double>();
    std::printf(
        "VALIDATION alr voellmy d0 = %.1f m: %d particles, run-out along the thalweg %.0f m (com1DFA %.0f), H/L %.3f, "
        "area > 0.1 m %.1f ha (com1DFA %.1f), peak speed %.1f m/s (com1DFA %.1f), lost %.3f %%, ended by %s at %.0f "
        "s, wall %.0f s\n",
        d0, j["particles_released"].get<int>(), m.runout, kCom1dfaRunout, m.h_over_l, m.area_ha, kCom1dfaAreaHa, vmax,
        kCom1dfaPeakSpeed, 100.0 * lost, j["ended_by"].get<std::string>().c_str(), j["simulated_time_s"].get<double>(),
        j["wall_time_s"].get<double>());
    EXPECT_LT(lost, 0.005) << "d0 " << d0;
    EXPECT_NEAR(m.runout / kCom1dfaRunout, 1.0, 0.10) << "d0 " << d0;
    EXPECT_NEAR(m.area_ha / kCom1dfaAreaHa, 1.0, 0.30) << "d0 " << d0;
    EXPECT_NEAR(vmax / kCom1dfaPeakSpeed, 1.0, 0.30) << "d0 " << d0;
    if (d0 == 5.0) {
      fs::copy_file(out / "max_depth.png", figures() / "alr_voellmy_max_depth.png",
                    fs::copy_options::overwrite_existing);
    }
  }
}
