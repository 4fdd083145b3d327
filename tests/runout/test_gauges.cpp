// Gauges and the profile of a steady flow (gauges.hpp, profile.hpp; issue #33): on an infinite
// (periodic) plane carrying a steady uniform Voellmy flow, the point gauge, the line gauge and the
// thalweg profile read the analytic depth, speed and discharge; a line gauge's discharge integrated
// over time is the volume that crossed it, to round-off, for a partial and a full pass of a mass;
// gauges the flow never reaches read 0; bad gauges are InputErrors naming key, value and extent.
#include <gtest/gtest.h>
#include <omp.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster_extra.hpp"
#include "geohaz/runout/gauges.hpp"
#include "geohaz/runout/hazard_maps.hpp"
#include "geohaz/runout/profile.hpp"
#include "geohaz/runout/solver.hpp"

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace {

const int kSerial = [] {  // small flows: one thread (CI runs tests side by side on 2 cores)
  omp_set_num_threads(1);
  return 1;
}();

// nx × ny particles on a hexagonal lattice of spacing d from `origin`, volumes from `volume(k)`.
template <class F>
void hex_lattice(RunoutStore& s, int nx, int ny, double d, Vec2 origin, F volume) {
  const std::size_t first = s.append(static_cast<std::size_t>(nx * ny));
  const double dy = d * std::sqrt(3.0) / 2.0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const std::size_t k = first + static_cast<std::size_t>(j * nx + i);
      s.get<Position<2>>()[k] = origin + Vec2((i + 0.25 + 0.5 * (j % 2)) * d, (j + 0.5) * dy);
      s.get<Volume>()[k] = volume(k);
      s.get<ParticleId>()[k] = static_cast<std::int64_t>(k);
    }
}

// A raster on `g` holding `v` (the maps as the app writes them), or the plane z = −tan θ · x.
Raster raster_on(const GridGeometry& g, const std::vector<double>& v) {
  Raster r;
  r.nx = g.nx;
  r.ny = g.ny;
  r.geotransform = {g.x0, g.dx, 0.0, g.y0, 0.0, -g.dy};
  r.nodata = -9999.0;
  r.data = v;
  return r;
}

}  // namespace

// The steady uniform Voellmy flow of test_flows.cpp (μ = 0.05, ξ = 500 m/s², tan θ = 0.3, a layer
// of bed-normal depth h = 2 m on a periodic plane): S = √(ξ h (sin θ − μ cos θ)) = 15.47 m/s. After
// 100 s (the layer is steady to 0.5 %: test_flows), 20 s of gauges every 0.5 s and of peak maps:
//  - the point gauge reads h and S at every row;
//  - the line across the whole width carries Q = h S W (W the width; = V cos θ S / L for the volume V
//    in a box of length L) on average over the 20 s, and its mean depth and speed are h and S;
//  - the profile along the flow, from the peak maps, is h and S at every station.
// Tolerances: the mean kernel depth is the layer depth to 0.4 % (2.008 m), but the layer shears into
// a packing whose particle depths spread by ±4 % (1.942–2.081 m at 100 s), and a gauge, like the
// maps, takes the largest depth of the particles within reach of its cell: depth 5 %. S ∝ √h and
// the particles' speeds lie within 0.3 % of S: speed 2 %. The discharge counts whole particles (one
// lattice column is 0.5 % of the 20 s volume): 2 %.
TEST(Gauges, SteadyUniformFlowReadsTheAnalyticDepthSpeedAndDischarge) {
  RunoutParameters p;
  p.d0 = 2.0;
  p.h0 = 1.0;
  p.duration = 1e9;
  const double mu = 0.05, xi = 500.0, tn = 0.3, h = 2.0;
  p.friction = VoellmyFriction{mu, xi};
  const double th = std::atan(tn);
  const double d = p.d0 * std::sqrt(p.h0 / 2.0 * 2.0 / std::sqrt(3.0));
  const int nx = 16, ny = 8;
  const double L = nx * d * std::cos(th), W = ny * d * std::sqrt(3.0) / 2.0;
  InclinedPlane plane;
  plane.slope = Vec2(-tn, 0.0);
  Periodicity<2> box;
  box.axis = {true, true};
  box.lo = Vec2(0.0, 0.0);
  box.hi = Vec2(L, W);
  RunoutSolver<InclinedPlane> s(plane, p, box);
  hex_lattice(s.particles(), nx, ny, d, Vec2::Zero(), [&](std::size_t) { return p.h0 * p.d0 * p.d0; });
  for (auto& x : s.particles().get<Position<2>>()) x.x() *= std::cos(th);  // laid on the bed
  s.initialise();
  while (s.time() < 100.0) s.step();
  const double S = std::sqrt(xi * h * (std::sin(th) - mu * std::cos(th)));
  const double volume = nx * ny * p.h0 * p.d0 * p.d0;
  EXPECT_NEAR(h * S * W, volume * std::cos(th) * S / L, 1e-9 * h * S * W);  // the same discharge, two ways

  // Maps and gauges on a 0.5 m grid over the box.
  const GridGeometry g{
      static_cast<int>(L / 0.5), static_cast<int>(W / 0.5), 0.0, 0.5 * static_cast<int>(W / 0.5), 0.5, 0.5};
  HazardMaps maps(g, p.d0, 2000.0);
  const double xm = 0.5 * L, ym = 0.5 * g.ny * g.dy;
  GaugeRecorder gauges({{"point", {Vec2(xm, ym)}}, {"section", {Vec2(xm, -1.0), Vec2(xm, W + 1.0)}}}, g, 0.5, box);
  const double t0 = s.time();
  maps.record(s.particles(), t0);
  gauges.start(s.particles(), maps, t0);
  while (s.time() < t0 + 20.0) {
    s.step();
    maps.record(s.particles(), s.time());
    gauges.step(s.particles(), maps, s.time(), s.time() >= t0 + 20.0);
  }
  ASSERT_EQ(gauges.rows().size(), 2u);
  ASSERT_GE(gauges.rows()[0].size(), 40u);
  for (const auto& rows : gauges.rows())
    for (const GaugeRow& r : rows) {
      EXPECT_NEAR(r.depth, h, 0.05 * h) << r.time;
      EXPECT_NEAR(r.speed, S, 0.02 * S) << r.time;
    }
  EXPECT_TRUE(std::isnan(gauges.rows()[0].back().discharge));  // a point has none
  const double T = gauges.rows()[1].back().time - t0;
  EXPECT_NEAR(gauges.crossed(1) / T, h * S * W, 0.02 * h * S * W);
  EXPECT_GT(gauges.crossed(1), 5.0 * volume);  // the layer went round the box several times

  // The profile along the flow from the peak maps of those 20 s.
  Raster dsm = raster_on(g, std::vector<double>(g.cells()));
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) dsm.at(c, r) = -tn * g.centre(c, r).x();
  const Raster depth = raster_on(g, maps.max_depth()), speed = raster_on(g, maps.max_speed()),
               pressure = raster_on(g, maps.max_pressure());
  const ThalwegProfile prof =
      thalweg_profile(dsm, depth, speed, pressure, {Vec2(1.0, ym), Vec2(L - 1.0, ym)}, 0.5, 0.01, 2.0);
  ASSERT_GE(prof.rows.size(), 40u);
  for (const ProfileRow& r : prof.rows) {
    EXPECT_NEAR(r.depth, h, 0.05 * h) << r.s;
    EXPECT_NEAR(r.speed, S, 0.02 * S) << r.s;
    EXPECT_NEAR(r.z, -tn * r.x, 1e-9) << r.s;
  }
}

namespace {

// A block of 10 × 6 particles of unequal volumes sliding down a plane (tan θ = 0.3, Coulomb
// μ = 0.1) towards +x, from x = 0–15 m, y = 0–7.8 m; a chevron gauge x = 30 + ½|y − 3.9| spanning
// y = −46 … 54 (the block never spreads that far), drawn from its south end to its north end
// so that its right-hand side, where the block goes, is downstream.
struct SlidingBlock {
  RunoutSolver<InclinedPlane> solver;
  HazardMaps maps;
  GaugeRecorder gauges;
  static constexpr double kXg = 30.0, kYc = 3.9;

  static SlidingBlock make(double interval) {
    RunoutParameters p;
    p.d0 = 1.5;
    p.h0 = 1.0;
    p.duration = 1e9;
    p.friction = CoulombFriction{0.1};
    InclinedPlane plane;
    plane.slope = Vec2(-0.3, 0.0);
    const GridGeometry g{120, 100, -20.0, 60.0, 1.0, 1.0};
    std::vector<GaugeSpec> specs{
        {"chevron", {Vec2(kXg + 25.0, kYc - 50.0), Vec2(kXg, kYc), Vec2(kXg + 25.0, kYc + 50.0)}},
        {"on the path", {Vec2(kXg, kYc)}},
        {"dry point", {Vec2(0.0, 50.0)}},
        {"dry line", {Vec2(-10.0, 40.0), Vec2(10.0, 40.0)}}};
    SlidingBlock b{RunoutSolver<InclinedPlane>(plane, p), HazardMaps(g, p.d0, 2000.0),
                   GaugeRecorder(specs, g, interval)};
    hex_lattice(b.solver.particles(), 10, 6, 1.5, Vec2::Zero(), [](std::size_t k) { return 1.0 + 0.1 * (k % 7); });
    b.solver.initialise();
    b.maps.record(b.solver.particles(), 0.0);
    b.gauges.start(b.solver.particles(), b.maps, 0.0);
    return b;
  }
  // Step until `done` holds, then take a row (as the last step of a run does).
  template <class F>
  void run_until(F done) {
    while (solver.time() < 300.0) {  // the block passes in about 10 s
      solver.step();
      maps.record(solver.particles(), solver.time());
      const bool last = done();
      gauges.step(solver.particles(), maps, solver.time(), last);
      if (last) return;
    }
  }
  // Volume downstream of the chevron now, by particle (independent of the recorder), and how many.
  double downstream(std::size_t* count = nullptr) const {
    const auto& x = solver.particles().get<Position<2>>();
    const auto& v = solver.particles().get<Volume>();
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x[i].x() >= kXg + 0.5 * std::abs(x[i].y() - kYc)) {
        sum += v[i];
        ++n;
      }
    if (count) *count = n;
    return sum;
  }
  bool all_passed() const {
    std::size_t n = 0;
    downstream(&n);
    return n == solver.particles().size();
  }
  double integrated(std::size_t g) const {  // Σ Q Δt over the rows
    double sum = 0.0;
    const auto& rows = gauges.rows()[g];
    for (std::size_t k = 1; k < rows.size(); ++k) sum += rows[k].discharge * (rows[k].time - rows[k - 1].time);
    return sum;
  }
};

}  // namespace

// The discharge across the chevron integrated over the rows is the cumulative volume of the last
// row, which is the volume downstream of the line counted particle by particle — to round-off —
// when part of the block has passed and when all of it has. The dry gauges read 0 throughout.
TEST(Gauges, LineDischargeIntegratesToTheVolumeThatCrossed) {
  SlidingBlock b = SlidingBlock::make(0.5);
  const double total = b.solver.budget().initial;
  ASSERT_EQ(b.downstream(), 0.0);
  b.run_until([&] { return b.downstream() > 0.3 * total; });  // a partial pass
  const double part = b.downstream();
  ASSERT_LT(part, 0.9 * total);
  EXPECT_NEAR(b.gauges.crossed(0), part, 1e-12 * total);
  EXPECT_NEAR(b.gauges.rows()[0].back().cumulative, part, 1e-12 * total);
  EXPECT_NEAR(b.integrated(0), part, 1e-12 * total);
  b.run_until([&] { return b.all_passed(); });  // the whole block
  ASSERT_TRUE(b.all_passed());
  EXPECT_NEAR(b.gauges.crossed(0), total, 1e-12 * total);
  EXPECT_NEAR(b.integrated(0), total, 1e-12 * total);
  double qmax = 0.0;
  for (const GaugeRow& r : b.gauges.rows()[0]) qmax = std::max(qmax, r.discharge);
  EXPECT_GT(qmax, 0.0);
  for (std::size_t g : {2u, 3u})
    for (const GaugeRow& r : b.gauges.rows()[g]) {
      EXPECT_EQ(r.depth, 0.0) << b.gauges.gauges()[g].name;
      EXPECT_EQ(r.speed, 0.0);
      if (g == 3) {
        EXPECT_EQ(r.discharge, 0.0);
        EXPECT_EQ(r.cumulative, 0.0);
      }
    }
  // The point on the path saw the block pass.
  double hmax = 0.0;
  for (const GaugeRow& r : b.gauges.rows()[1]) hmax = std::max(hmax, r.depth);
  EXPECT_GT(hmax, 0.1);

  // The files: a header and a row per gauge and time; the figure.
  const fs::path dir = fs::temp_directory_path() / ("geohaz_gauges_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  write_gauges_csv(dir / "gauges.csv", b.gauges);
  write_gauges_png(dir / "gauges.png", b.gauges);
  std::ifstream in(dir / "gauges.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "gauge,t_s,depth_m,speed_m_per_s,discharge_m3_per_s,cumulative_volume_m3");
  std::size_t n = 0;
  while (std::getline(in, line)) ++n;
  EXPECT_EQ(n, 4 * b.gauges.rows()[0].size());
  EXPECT_EQ(read_image(dir / "gauges.png").width, 1800);
  fs::remove_all(dir);
}

// With a row every step, the largest depth and speed a point gauge reads are the peak maps' values
// in its cell: the gauges and the maps use one painting rule.
TEST(Gauges, PointGaugeReadsWhatTheMapsPaint) {
  SlidingBlock b = SlidingBlock::make(1e-9);
  b.run_until([&] { return b.all_passed(); });
  ASSERT_TRUE(b.all_passed());
  double hmax = 0.0, vmax = 0.0;
  for (const GaugeRow& r : b.gauges.rows()[1]) {
    hmax = std::max(hmax, r.depth);
    vmax = std::max(vmax, r.speed);
  }
  int c, r;
  ASSERT_TRUE(b.maps.grid().cell_of(Vec2(SlidingBlock::kXg, SlidingBlock::kYc), c, r));
  EXPECT_GT(hmax, 0.0);
  EXPECT_EQ(hmax, b.maps.max_depth()[b.maps.grid().index(c, r)]);
  EXPECT_EQ(vmax, b.maps.max_speed()[b.maps.grid().index(c, r)]);
}

// Bad gauges: off the terrain's data, a line without length, a nameless or duplicate gauge.
TEST(Gauges, BadGaugesAreInputErrorsNamingKeyValueAndExtent) {
  Raster dsm = raster_on({40, 20, 1000.0, 2000.0, 5.0, 5.0}, std::vector<double>(800, 100.0));
  const auto message = [&](const std::vector<GaugeSpec>& g) {
    try {
      check_gauges(g, dsm, "case.toml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({{"a", {Vec2(1050.0, 1950.0)}}, {"b", {Vec2(1050.0, 1950.0), Vec2(1100.0, 1950.0)}}}), "no error");
  const std::string off = message({{"a", {Vec2(1050.0, 1950.0)}}, {"b", {Vec2(1050.0, 1950.0), Vec2(1300.0, 1950.0)}}});
  for (const char* part :
       {"case.toml", "output.gauges[1].line", "1950.0)", "x in [1000.0, 1200.0]", "y in [1900.0, 2000.0]"})
    EXPECT_NE(off.find(part), std::string::npos) << part << " in " << off;
  EXPECT_NE(message({{"p", {Vec2(900.0, 1950.0)}}}).find("output.gauges[0].point"), std::string::npos);
  EXPECT_NE(message({{"l", {Vec2(1050.0, 1950.0), Vec2(1050.0, 1950.0)}}}).find("two or more distinct"),
            std::string::npos);
  EXPECT_NE(message({{"", {Vec2(1050.0, 1950.0)}}}).find("output.gauges[0].name"), std::string::npos);
  EXPECT_NE(message({{"a", {Vec2(1050.0, 1950.0)}}, {"a", {Vec2(1060.0, 1950.0)}}}).find("unique"), std::string::npos);
  EXPECT_NE(message({{"a,b", {Vec2(1050.0, 1950.0)}}}).find("commas"), std::string::npos);
  EXPECT_NE(message({{"a", {}}}).find("point = [x, y] or line"), std::string::npos);
}
