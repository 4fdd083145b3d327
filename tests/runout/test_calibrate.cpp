// The calibration library (calibrate.hpp): the parameter scales, the along-thalweg coordinate, the
// misfit's areas and score in closed form, the Morris design, and identifiability: a synthetic
// observation made by a run with known parameters is recovered by the search.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "calibration_case.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/calibrate.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace {

fs::path work_dir(const std::string& name) {
  const fs::path d =
      fs::path(GEOHAZ_BINARY_DIR) / "tests" / "runout" / "calibrate_work" / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

/// A 10 × 1 strip of 2 m cells along x, the thalweg along its axis from x = 0.
Observation strip(std::vector<std::uint8_t> footprint) {
  Observation o;
  o.grid = GridGeometry{10, 1, 0.0, 2.0, 2.0, 2.0};
  o.footprint = std::move(footprint);
  o.thalweg = {Vec2(0.0, 1.0), Vec2(20.0, 1.0)};
  for (int c = 0; c < 10; ++c) o.s.push_back(along_thalweg(o.thalweg, o.grid.centre(c, 0)));
  for (std::size_t k = 0; k < o.s.size(); ++k)
    if (o.footprint[k]) o.runout_s = std::max(o.runout_s, o.s[k]);
  return o;
}

nlohmann::json summary(const fs::path& out) {
  std::ifstream in(out / "summary.json");
  return nlohmann::json::parse(in);
}

}  // namespace

TEST(CalibrationParameter, LinearAndLogScalesMapTheUnitIntervalOntoTheBounds) {
  const CalibrationParameter lin{"model.n", 0.02, 0.1, false}, lg{"model.xi", 100.0, 10000.0, true};
  EXPECT_DOUBLE_EQ(lin.value(0.0), 0.02);
  EXPECT_DOUBLE_EQ(lin.value(1.0), 0.1);
  EXPECT_DOUBLE_EQ(lin.value(0.5), 0.06);
  EXPECT_NEAR(lg.value(0.5), 1000.0, 1e-9);  // the geometric mean
  for (double u : {0.0, 0.13, 0.5, 0.97, 1.0}) {
    EXPECT_NEAR(lin.unit(lin.value(u)), u, 1e-12);
    EXPECT_NEAR(lg.unit(lg.value(u)), u, 1e-12);
  }
}

TEST(Calibration, AlongThalwegIsTheArcLengthToTheNearestSegment) {
  const std::vector<Vec2> t{Vec2(0, 0), Vec2(10, 0), Vec2(10, 10)};
  EXPECT_DOUBLE_EQ(along_thalweg(t, Vec2(4, 3)), 4.0);
  EXPECT_DOUBLE_EQ(along_thalweg(t, Vec2(13, 6)), 16.0);  // second leg, 6 m up it
  EXPECT_DOUBLE_EQ(along_thalweg(t, Vec2(-5, 1)), 0.0);   // before the start: clamped
}

TEST(Calibration, MisfitAreasTverskyAndRunoutTermInClosedForm) {
  // Observed cells 2..6, modelled (depth > 0.1 m) cells 3..8: TP 4 cells, FP 2, FN 1 (4 m² each).
  const Observation o = strip({0, 0, 1, 1, 1, 1, 1, 0, 0, 0});
  std::vector<double> depth(10, 0.0), deposit(10, 0.0);
  for (int c = 3; c <= 8; ++c) depth[static_cast<std::size_t>(c)] = 0.5;
  depth[9] = 0.1;  // at the threshold: not affected
  ScoreSettings s;
  const Misfit m = compute_misfit(o, s, depth, deposit, 0.0);
  EXPECT_DOUBLE_EQ(m.tp, 16.0);
  EXPECT_DOUBLE_EQ(m.fp, 8.0);
  EXPECT_DOUBLE_EQ(m.fn, 4.0);
  EXPECT_DOUBLE_EQ(m.tversky, 16.0 / (16.0 + 0.5 * 8.0 + 0.5 * 4.0));  // Dice = 2TP / (2TP + FP + FN)
  // Run-out: cell 8's centre at s = 17 m against cell 6's at 13 m.
  EXPECT_DOUBLE_EQ(m.runout_diff, 4.0);
  EXPECT_DOUBLE_EQ(m.term_runout, 4.0 / 13.0);
  EXPECT_DOUBLE_EQ(m.score, (1.0 - m.tversky) + 4.0 / 13.0);
  // Tversky α = 1, β = 0 counts only over-prediction: T = TP / (TP + FP).
  s.alpha = 1.0, s.beta = 0.0;
  EXPECT_DOUBLE_EQ(compute_misfit(o, s, depth, deposit, 0.0).tversky, 16.0 / 24.0);
}

TEST(Calibration, MisfitOfTheObservationItselfIsZeroAndDepthAndVolumeTermsAreRelative) {
  Observation o = strip({0, 1, 1, 1, 0, 0, 0, 0, 0, 0});
  o.deposit = {0, 1.0, 2.0, 1.0, 0, 0, 0, 0, 0, 0};
  o.volume = 16.0;
  const std::vector<double> depth{0, 1, 2, 1, 0, 0, 0, 0, 0, 0};
  ScoreSettings s;
  const Misfit same = compute_misfit(o, s, depth, o.deposit, 16.0);
  EXPECT_DOUBLE_EQ(same.score, 0.0);
  EXPECT_DOUBLE_EQ(same.tversky, 1.0);
  // A deposit 0.5 m thicker everywhere it lies, and 20 % more volume: RMSE 0.5 m over a mean of 4/3 m.
  std::vector<double> thicker = o.deposit;
  for (std::size_t k = 1; k <= 3; ++k) thicker[k] += 0.5;
  const Misfit m = compute_misfit(o, s, depth, thicker, 19.2);
  EXPECT_DOUBLE_EQ(m.depth_rmse, 0.5);
  EXPECT_NEAR(m.term_depth, 0.5 / (4.0 / 3.0), 1e-15);
  EXPECT_NEAR(m.term_volume, 0.2, 1e-15);
  EXPECT_NEAR(m.score, 0.375 + 0.2, 1e-15);
}

TEST(Calibration, MorrisTrajectoryMovesEveryFactorOnceByDeltaOnTheGrid) {
  for (int t = 0; t < 20; ++t) {
    const auto pts = morris_trajectory(7, t, 3, 4);
    ASSERT_EQ(pts.size(), 4u);
    std::set<int> moved;
    for (std::size_t k = 1; k < pts.size(); ++k) {
      int changed = 0;
      for (int d = 0; d < 3; ++d) {
        const double a = pts[k - 1][static_cast<std::size_t>(d)], b = pts[k][static_cast<std::size_t>(d)];
        // On the grid {0, 1/3, 2/3, 1}, inside [0, 1].
        EXPECT_NEAR(a * 3.0, std::round(a * 3.0), 1e-12);
        EXPECT_GE(b, 0.0);
        EXPECT_LE(b, 1.0);
        if (a != b) {
          ++changed;
          moved.insert(d);
          EXPECT_NEAR(std::abs(b - a), 2.0 / 3.0, 1e-12);  // Δ = p / (2 (p − 1))
        }
      }
      EXPECT_EQ(changed, 1);
    }
    EXPECT_EQ(moved.size(), 3u);
  }
}

namespace {

struct Fit {
  nlohmann::json summary;
  std::vector<double> best;
};

Fit calibrate(const calibration_case::Case& c, const std::string& config) {
  const fs::path out = c.dir / "out";
  fs::remove_all(out);
  ConfigReader cfg = ConfigReader::from_string(config, (c.dir / "calibrate.toml").string());
  CalibrationSetup s = read_calibration(cfg);
  run_calibration_serial(s, out, 1, true);
  Fit f;
  f.summary = summary(out);
  f.best = f.summary["best"]["values"].get<std::vector<double>>();
  return f;
}

const char* const kManningModel = "friction = \"manning\"\nn = 0.06\nicr = 0.15\nd0 = 5.0\nh0 = 0.5\ndensity = 1800.0";
const char* const kManningParameters =
    "[[calibration.parameter]]\nkey = \"model.n\"\nmin = 0.03\nmax = 0.12\nscale = \"log\"\n"
    "[[calibration.parameter]]\nkey = \"model.icr\"\nmin = 0.08\nmax = 0.3\n";
const char* const kSearch =
    "global_members = 12\nmorris_trajectories = 2\nlocal_starts = 2\nlocal_evaluations = 24\nlocal_algorithm = "
    "\"bobyqa\"\n";

}  // namespace

TEST(CalibrationIdentifiability, RecoversManningNAndCriticalSlopeOfASyntheticEvent) {
  // Truth n = 0.06, i_cr = 0.15 (the valley example's values). Observation: its footprint, deposit
  // and (from the footprint) run-out. Acceptance (issue 31): both within 5 %, footprint score T
  // within 1 % of perfect.
  const auto c = calibration_case::make(work_dir("manning"), kManningModel, {"model.n=0.06", "model.icr=0.15"});
  const Fit f = calibrate(c, calibration_case::config(c, kManningParameters, kSearch));
  const double t = f.summary["best"]["misfit"]["tversky"].get<double>();
  std::printf("CALIBRATION manning: n %.5f (truth 0.06), icr %.5f (truth 0.15), T %.4f, score %.4g, %d members\n",
              f.best[0], f.best[1], t, f.summary["best"]["misfit"]["score"].get<double>(),
              f.summary["members"].get<int>());
  EXPECT_NEAR(f.best[0], 0.06, 0.05 * 0.06);
  EXPECT_NEAR(f.best[1], 0.15, 0.05 * 0.15);
  EXPECT_GE(t, 0.99);
  fs::remove_all(c.dir);
}

TEST(CalibrationIdentifiability, RecoversVoellmyMuWithXiFixed) {
  // Truth μ = 0.15, ξ = 500 m/s² (fixed in the base case): one parameter, Sbplx.
  const auto c = calibration_case::make(work_dir("voellmy"),
                                        "friction = \"voellmy\"\nmu = 0.15\nxi = 500.0\nd0 = 5.0\nh0 = 0.5", {});
  const Fit f = calibrate(
      c, calibration_case::config(c, "[[calibration.parameter]]\nkey = \"model.mu\"\nmin = 0.08\nmax = 0.3\n",
                                  "global_members = 8\nmorris_trajectories = 2\nlocal_starts = 2\nlocal_evaluations = "
                                  "16\nlocal_algorithm = \"sbplx\"\n"));
  const double t = f.summary["best"]["misfit"]["tversky"].get<double>();
  std::printf("CALIBRATION voellmy xi fixed: mu %.5f (truth 0.15), T %.4f, score %.4g, %d members\n", f.best[0], t,
              f.summary["best"]["misfit"]["score"].get<double>(), f.summary["members"].get<int>());
  EXPECT_NEAR(f.best[0], 0.15, 0.05 * 0.15);
  EXPECT_GE(t, 0.99);
  fs::remove_all(c.dir);
}

TEST(CalibrationSearch, RestartsRefillEndedSearchesWithinTheBudget) {
  // The lockstep local stage with and without restarts on the one-parameter Voellmy case, the
  // batches recorded as the ranks would receive them. Sbplx stops both searches (step below
  // local_xtol) after 15 of their 30 members; without restarts the rest of the budget is unused,
  // with them each slot is refilled by a new search, the local members stay within
  // local_starts x local_evaluations, the batches are full before the tail the budget can no
  // longer fund, and the search finds the truth either way.
  const auto c = calibration_case::make(work_dir("restarts"),
                                        "friction = \"voellmy\"\nmu = 0.15\nxi = 500.0\nd0 = 5.0\nh0 = 0.5", {});
  struct Run {
    std::vector<std::size_t> widths;  // of the local batches, in order
    int local_members = 0, searches = 0;
    double best = 0.0;
  };
  const auto search = [&](bool restarts) {
    const fs::path out = c.dir / (restarts ? "on" : "off");
    fs::remove_all(out);
    ConfigReader cfg = ConfigReader::from_string(
        calibration_case::config(
            c, "[[calibration.parameter]]\nkey = \"model.mu\"\nmin = 0.08\nmax = 0.3\n",
            std::string("global_members = 8\nmorris_trajectories = 2\nlocal_starts = 2\n"
                        "local_evaluations = 30\nlocal_xtol = 0.01\nlocal_algorithm = \"sbplx\"\nlocal_restarts = ") +
                (restarts ? "true\n" : "false\n")),
        (c.dir / "calibrate.toml").string());
    CalibrationSetup s = read_calibration(cfg);
    prepare_calibration_output(s, out);
    const auto runner = make_calibration_runner(s);
    Run r;
    bool global = true;
    const CalibrationResult res = run_calibration(
        s, out,
        [&](const std::vector<int>& batch) {
          for (int i : batch) runner->run(i, out, 0, 1);
          if (!global) r.widths.push_back(batch.size()), r.local_members += static_cast<int>(batch.size());
          global = false;
        },
        true);
    r.searches = static_cast<int>(res.local_stops.size());
    r.best = res.evaluations.at(static_cast<std::size_t>(res.best)).values[0];
    return r;
  };
  const Run off = search(false), on = search(true);
  std::printf(
      "CALIBRATION restarts: off %d searches, %d local members in %zu batches; on %d searches, %d local "
      "members in %zu batches\n",
      off.searches, off.local_members, off.widths.size(), on.searches, on.local_members, on.widths.size());
  EXPECT_EQ(off.searches, 2);
  EXPECT_LT(off.local_members, 2 * 30) << "the case must leave budget for a restart";
  EXPECT_GT(on.searches, 2);
  EXPECT_GT(on.local_members, off.local_members);
  EXPECT_LE(on.local_members, 2 * 30);
  // Full batches first, then the tail the budget can no longer fund.
  EXPECT_TRUE(std::is_sorted(on.widths.rbegin(), on.widths.rend()));
  EXPECT_NEAR(on.best, 0.15, 0.05 * 0.15);
  EXPECT_NEAR(off.best, 0.15, 0.05 * 0.15);
  fs::remove_all(c.dir);
}

TEST(CalibrationIdentifiability, VoellmyMuAndXiFreeAcceptableSetHoldsTheTruth) {
  // μ and ξ trade off (equifinality, docs/calibration.md): the acceptable set (score within the
  // tolerance of the best) must contain the truth μ = 0.15, ξ = 500 m/s² within its ranges.
  const auto c = calibration_case::make(work_dir("voellmy2"),
                                        "friction = \"voellmy\"\nmu = 0.15\nxi = 500.0\nd0 = 5.0\nh0 = 0.5", {});
  const Fit f = calibrate(
      c, calibration_case::config(c,
                                  "[[calibration.parameter]]\nkey = \"model.mu\"\nmin = 0.08\nmax = 0.3\n"
                                  "[[calibration.parameter]]\nkey = \"model.xi\"\nmin = 100.0\nmax = 5000.0\nscale = "
                                  "\"log\"\n[score]\nacceptable_tolerance = 0.1\n",
                                  kSearch));
  const auto& range = f.summary["acceptable_range"];
  std::printf(
      "CALIBRATION voellmy mu, xi free: best mu %.4f xi %.1f, acceptable mu [%.4f, %.4f] xi [%.0f, %.0f], "
      "%d acceptable of %d\n",
      f.best[0], f.best[1], range["model.mu"][0].get<double>(), range["model.mu"][1].get<double>(),
      range["model.xi"][0].get<double>(), range["model.xi"][1].get<double>(),
      f.summary["acceptable_members"].get<int>(), f.summary["members"].get<int>());
  EXPECT_LE(range["model.mu"][0].get<double>(), 0.15 * 1.05);
  EXPECT_GE(range["model.mu"][1].get<double>(), 0.15 * 0.95);
  EXPECT_LE(range["model.xi"][0].get<double>(), 500.0 * 1.05);
  EXPECT_GE(range["model.xi"][1].get<double>(), 500.0 * 0.95);
  fs::remove_all(c.dir);
}

TEST(CalibrationIdentifiability, FootprintErodedOrDilatedByOneCellShiftsTheFitByADocumentedAmount) {
  // The Manning case with the observed footprint eroded, then dilated, by one cell (deposit raster
  // unchanged): the shift of n and i_cr is printed and written in docs/calibration.md; the bound
  // (15 %) is what one 5 m cell on a ~100 m wide footprint can move, not a tuned figure.
  const auto c = calibration_case::make(work_dir("noise"), kManningModel, {"model.n=0.06", "model.icr=0.15"});
  for (const int grow : {-1, 1}) {
    calibration_case::morph(c.footprint, c.dir / "morphed.tif", grow);
    auto cm = c;
    cm.footprint = c.dir / "morphed.tif";
    const Fit f = calibrate(cm, calibration_case::config(cm, kManningParameters, kSearch));
    std::printf("CALIBRATION manning, footprint %s by one cell: n %.5f (%+.1f %%), icr %.5f (%+.1f %%), T %.4f\n",
                grow < 0 ? "eroded" : "dilated", f.best[0], 100.0 * (f.best[0] / 0.06 - 1.0), f.best[1],
                100.0 * (f.best[1] / 0.15 - 1.0), f.summary["best"]["misfit"]["tversky"].get<double>());
    EXPECT_NEAR(f.best[0], 0.06, 0.15 * 0.06);
    EXPECT_NEAR(f.best[1], 0.15, 0.15 * 0.15);
  }
  fs::remove_all(c.dir);
}

TEST(Calibration, ObservedRunoutFromTheFootprintAPointOrALine) {
  // The observed run-out s_obs: by default the footprint's farthest cell along the thalweg; a
  // run-out point: its own coordinate; a run-out line (e.g. the mapped deposit front): its vertex
  // farthest along the thalweg, so a line between two thalweg vertices, either way round, gives
  // exactly the point at the farther one. Point and line together, or a line off the DSM: exit 2.
  const auto c = calibration_case::make(work_dir("runout_line"), kManningModel, {});
  const std::string params = "[[calibration.parameter]]\nkey = \"model.n\"\nmin = 0.03\nmax = 0.12\n";
  const auto read = [&](const std::string& observation) {
    ConfigReader cfg = ConfigReader::from_string(calibration_case::config(c, params) + observation,
                                                 (c.dir / "calibrate.toml").string());
    return read_calibration(cfg).observation;
  };
  const Observation by_footprint = read("");
  EXPECT_EQ(by_footprint.runout_from, "footprint");
  double farthest = 0.0;
  for (std::size_t k = 0; k < by_footprint.s.size(); ++k)
    if (by_footprint.footprint[k]) farthest = std::max(farthest, by_footprint.s[k]);
  EXPECT_EQ(by_footprint.runout_s, farthest);
  const Vec2 near = by_footprint.thalweg.at(20), far = by_footprint.thalweg.at(30);
  std::ostringstream point;
  point << std::setprecision(17) << "runout_point = [" << far.x() << ", " << far.y() << "]\n";
  const Observation by_point = read(point.str());
  EXPECT_EQ(by_point.runout_from, "runout_point");
  EXPECT_NEAR(by_point.runout_s, along_thalweg(by_point.thalweg, far), 1e-9);
  const auto line_file = [&](const std::string& name, const Vec2& a, const Vec2& b) {
    std::ofstream f(c.dir / name);
    f << std::setprecision(17)
      << "{\"type\": \"FeatureCollection\", \"crs\": {\"type\": \"name\", \"properties\": {\"name\": "
         "\"urn:ogc:def:crs:EPSG::32654\"}}, \"features\": [{\"type\": \"Feature\", \"properties\": {}, "
         "\"geometry\": {\"type\": \"LineString\", \"coordinates\": [["
      << a.x() << ", " << a.y() << "], [" << b.x() << ", " << b.y() << "]]}}]}\n";
    return "runout_line = \"" + (c.dir / name).string() + "\"\n";
  };
  for (const auto& [a, b] : {std::pair{near, far}, std::pair{far, near}}) {
    const Observation by_line = read(line_file("front.geojson", a, b));
    EXPECT_EQ(by_line.runout_from, "runout_line");
    EXPECT_NEAR(by_line.runout_s, by_point.runout_s, 1e-9);
  }
  EXPECT_LT(by_point.runout_s, by_footprint.runout_s);  // the check has teeth: not the default
  const std::string both = point.str() + line_file("front.geojson", near, far);
  try {
    read(both);
    ADD_FAILURE() << "point and line accepted together";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("observation.runout_line"), std::string::npos) << e.what();
  }
  try {
    read(line_file("off.geojson", near, Vec2(near.x() + 1e5, near.y())));
    ADD_FAILURE() << "a line off the DSM accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("leaves the DSM"), std::string::npos) << e.what();
  }
  fs::remove_all(c.dir);
}

TEST(Calibration, ModelledVolumeIsTheDepositIntegralSoMassConservationZeroesTheVolumeTerm) {
  // One member at the truth's parameters (bounds 1e-10 wide) against the observed volume = the
  // integral of the event's deposit raster: the flow stops by the kinetic-energy criterion, which
  // deposits every particle, so the member's deposit holds the whole release (mass conservation)
  // and the volume term vanishes to round-off (the rasters are float64).
  const auto c = calibration_case::make(work_dir("volume"), kManningModel, {"model.n=0.06", "model.icr=0.15"});
  const Raster dep = read_raster(c.deposit);
  double v_obs = 0.0;
  for (double d : dep.data) v_obs += dep.is_nodata(d) ? 0.0 : d;
  v_obs *= dep.cell_size_x() * dep.cell_size_y();
  std::ostringstream cfg;
  cfg << calibration_case::config(c, "[[calibration.parameter]]\nkey = \"model.n\"\nmin = 0.06\nmax = 0.0600000001\n",
                                  "global_members = 1\nmorris_trajectories = 0\nlocal_starts = 0\n")
      << "volume = " << std::setprecision(17) << v_obs << "\n";
  const Fit f = calibrate(c, cfg.str());
  const auto& m = f.summary["best"]["misfit"];
  EXPECT_GT(v_obs, 1000.0);
  EXPECT_NEAR(m["volume_m3"].get<double>(), v_obs, 1e-9 * v_obs);
  EXPECT_LT(m["terms"]["volume"].get<double>(), 1e-9);
  fs::remove_all(c.dir);
}
