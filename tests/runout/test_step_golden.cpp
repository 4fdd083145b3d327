// Stored-value tests of the debris-runout step (label: unit), in the habit of
// tests/sph/test_step_golden.cpp and LAMMPS's force-style tests: a few dozen steps of small
// hand-built cases on one thread (no release polygon or DSM, so that only the step is under test),
// then the state of a handful of particles — position, velocity, bed-normal flow depth and volume —
// and the volume budget, compared with values stored from the code of commit "runout: stored-value
// step tests" (issue #30 item 5). Any change to the arithmetic of a step (a friction or pressure
// term dropped, a sign, the curvature terms, the erosion, the barrier) moves these numbers by far
// more than the tolerance; a reordering of a floating-point sum moves them by round-off only.
//
// Tolerance 1e-9, relative to max(|stored value|, the largest component of the same quantity at the
// same particle): a reordered floating-point sum (another compiler, FMA contraction) changes a
// value by ~1e-16 relative per step, and 40 explicit steps of a few hundred particles grow that to
// ~1e-12 (an estimate; the SPH cases measured ≤ 2.4e-14 after a reordering), while removing the
// barrier of case 2 moved its front particles by 6e-3 relative (checked when the values were
// stored). The particle's scale guards components that cancel to near zero (a cross-slope velocity
// of 1e-12 m/s next to a down-slope one of 1 m/s).
//
// To regenerate after an intended change of the physics:
//   GEOHAZ_GOLDEN_PRINT=1 ./build/tests/runout/runout_step_golden
// prints the tables in the form below; paste them over the stored ones and say in the commit why
// the numbers moved (docs/runout.md, "Stored-value step tests").
//
// The thread count: below 2048 particles the loops run on one thread (core parallel.hpp), so these
// cases say nothing about threads; Flows, Processes and Barriers.OneAndTwoThreadsGiveIdenticalResults
// compare one and two threads bit for bit on larger cases.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "geohaz/runout/barriers.hpp"
#include "geohaz/runout/processes.hpp"
#include "geohaz/runout/solver.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {
namespace {

bool print_mode() {
  return std::getenv("GEOHAZ_GOLDEN_PRINT") != nullptr;
}

/// The stored state of one particle.
struct Golden {
  std::int64_t id;
  std::array<double, 2> x, v;
  double depth, volume;
};

/// What a case ends with besides the particles: the clock and the volume budget.
struct Totals {
  double time;
  std::int64_t steps;
  double mobile, deposited, entrained, kinetic_energy;
};

/// nx × ny particles on a square lattice of spacing d from `origin`, volume h0 d0² each, velocity
/// `v0` plus a fixed pattern of ±0.1 m/s (so that neighbours move relative to each other).
template <class Surface>
void add_block(RunoutSolver<Surface>& s, int nx, int ny, double d, const Vec2& origin, const Vec2& v0) {
  RunoutStore& st = s.particles();
  st.append(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto k = static_cast<std::size_t>(j * nx + i);
      const double q = static_cast<double>(k);
      st.get<Position<2>>()[k] = origin + Vec2(i * d, j * d);
      st.get<Velocity<2>>()[k] = v0 + Vec2(0.1 * std::sin(0.37 * q), 0.1 * std::cos(0.23 * q));
      st.get<Volume>()[k] = s.parameters().nominal_volume();
      st.get<ParticleId>()[k] = static_cast<std::int64_t>(k);
    }
}

std::string arr(const double* p, int n) {
  std::string s = "{";
  char buf[40];
  for (int k = 0; k < n; ++k) {
    std::snprintf(buf, sizeof buf, "%s%.17g", k ? ", " : "", p[k]);
    s += buf;
  }
  return s + "}";
}

template <class Surface>
Golden state_of(const RunoutSolver<Surface>& s, std::int64_t id) {
  const RunoutStore& st = s.particles();
  const auto& ids = st.get<ParticleId>();
  std::size_t i = 0;
  while (i < st.size() && ids[i] != id) ++i;
  EXPECT_LT(i, st.size()) << "particle id " << id << " missing";
  if (i == st.size()) return {};
  const Vec2 x = st.get<Position<2>>()[i], v = st.get<Velocity<2>>()[i];
  return {id, {x.x(), x.y()}, {v.x(), v.y()}, st.get<FlowDepth>()[i], st.get<Volume>()[i]};
}

template <class Surface>
Totals totals_of(const RunoutSolver<Surface>& s) {
  const VolumeBudget& b = s.budget();
  return {s.time(), s.step_count(), b.mobile, b.deposited, b.entrained, b.kinetic_energy};
}

void print_tables(const char* name, const Totals& t, const std::vector<Golden>& got) {
  std::printf("// %s\nconst Totals k%sTotals = {%.17g, %lld, %.17g, %.17g, %.17g, %.17g};\n", name, name, t.time,
              static_cast<long long>(t.steps), t.mobile, t.deposited, t.entrained, t.kinetic_energy);
  std::printf("const std::vector<Golden> k%s = {\n", name);
  for (const auto& g : got)
    std::printf("    {%lld, %s, %s, %.17g, %.17g},\n", static_cast<long long>(g.id), arr(g.x.data(), 2).c_str(),
                arr(g.v.data(), 2).c_str(), g.depth, g.volume);
  std::printf("};\n");
}

constexpr double kTol = 1e-9;

void near(double got, double want, double scale, const std::string& what) {
  EXPECT_LE(std::abs(got - want), kTol * std::max(std::abs(want), scale))
      << what << " got " << got << " stored " << want;
}

template <class Surface>
void expect_matches(const char* name, const RunoutSolver<Surface>& s, const Totals& totals,
                    const std::vector<Golden>& want) {
  std::vector<Golden> got;
  for (const auto& w : want) got.push_back(state_of(s, w.id));
  const Totals t = totals_of(s);
  if (print_mode()) print_tables(name, t, got);
  EXPECT_EQ(t.steps, totals.steps) << name;
  near(t.time, totals.time, 0.0, std::string(name) + ": time after the steps (the time-step limit)");
  const double v_scale = totals.mobile + totals.deposited;
  near(t.mobile, totals.mobile, v_scale, std::string(name) + ": mobile volume");
  near(t.deposited, totals.deposited, v_scale, std::string(name) + ": deposited volume");
  near(t.entrained, totals.entrained, v_scale, std::string(name) + ": entrained volume");
  near(t.kinetic_energy, totals.kinetic_energy, 0.0, std::string(name) + ": kinetic energy");
  for (std::size_t k = 0; k < want.size(); ++k) {
    const Golden &g = got[k], &w = want[k];
    const std::string p = std::string(name) + ": particle " + std::to_string(w.id) + " ";
    const double sx = std::max(std::abs(w.x[0]), std::abs(w.x[1]));
    const double sv = std::max(std::abs(w.v[0]), std::abs(w.v[1]));
    for (int d = 0; d < 2; ++d) {
      near(g.x[d], w.x[d], sx, p + "position[" + std::to_string(d) + "]");
      near(g.v[d], w.v[d], sv, p + "velocity[" + std::to_string(d) + "]");
    }
    near(g.depth, w.depth, 0.0, p + "flow depth");
    near(g.volume, w.volume, 0.0, p + "volume");
  }
}

// ---- Case 1: a block in a cylindrical trough, Voellmy ----------------------------------------------
// 16 × 16 particles (d0 = 2 m, h0 = 1 m, spacing d0/√2: a block nominally 2 m deep) released on the
// flank of a trough of radius 150 m (slopes 12–20° under the block), sliding down across its axis: the head
// pressure, Voellmy friction, lateral mixing, the velocity smoothing and the bed-curvature terms
// (centripetal normal force and the bed constraint) all act; 40 steps.
RunoutSolver<CylindricalTrough> trough_block() {
  RunoutParameters p;
  p.d0 = 2.0;
  p.h0 = 1.0;
  p.friction = VoellmyFriction{0.2, 400.0};
  p.smoothing = 0.05;
  CylindricalTrough trough;
  trough.radius = 150.0;
  RunoutSolver<CylindricalTrough> s(trough, p);
  add_block(s, 16, 16, p.d0 / std::sqrt(2.0), Vec2(30.0, 0.0), Vec2(-1.0, 0.0));
  s.initialise();
  return s;
}

// Particle id = j·16 + i (i across the trough): 0 and 15 the downslope and upslope corners of the
// first row, 119 and 136 inside, 240 and 255 the corners of the last row.
const Totals kTroughBlockTotals = {3.4407455208174782, 40, 1024, 0, 0, 8078616.286383708};
const std::vector<Golden> kTroughBlock = {
    {0, {20.30140854391712, -3.8266160540872471}, {-2.9077610243794707, -1.2158550401490136}, 0.53301438151439562, 4},
    {15,
     {45.537272949555074, -2.8564843627033194},
     {-2.4719795881184417, -0.91504461036040396},
     0.50238223859715259,
     4},
    {119, {32.881094637864457, 9.702344088199192}, {-3.0085546333611077, -0.21043575850540297}, 1.2557976311981656, 4},
    {136, {34.624998367612179, 11.545550965127109}, {-2.404436930142007, 0.20334517772101304}, 1.2647429620321735, 4},
    {240, {20.327184646691428, 25.086361015140422}, {-2.9197798318816699, 1.252958712240259}, 0.54276519955940594, 4},
    {255, {45.674918408787981, 23.997510242224717}, {-2.4125863443891844, 0.90085635181110668}, 0.49278259455858181, 4},
};

TEST(RunoutStepGolden, BlockInACylindricalTroughVoellmy) {
  omp_set_num_threads(1);
  auto s = trough_block();
  for (int k = 0; k < 40; ++k) s.step();
  expect_matches("TroughBlock", s, kTroughBlockTotals, kTroughBlock);
}

// ---- Case 2: a block on a plane with processes and a barrier, modified Manning -------------------
// 20 × 12 particles on a 15° plane (d0 = 5 m), the default modified-Manning law with a friction zone
// (n field), a forest drag and an erodible layer (growth-rate entrainment) on the downslope half,
// and a 1.5 m high barrier across the path a few metres ahead of the front: the cell look-ups, the
// erosion and the barrier's impulses act in the 40 steps.
RunoutSolver<InclinedPlane> plane_with_processes() {
  RunoutParameters p;
  p.d0 = 5.0;
  p.h0 = 1.0;
  p.entrainment = {EntrainmentLaw::GrowthRate, 2e-3, 0.0, 0.0};
  InclinedPlane plane;
  plane.slope = Vec2(-std::tan(15.0 * std::acos(-1.0) / 180.0), 0.0);
  RunoutSolver<InclinedPlane> s(plane, p);
  SpatialProcesses proc;
  proc.grid = {40, 20, -50.0, 80.0, 5.0, 5.0};  // x ∈ [−50, 150], y ∈ [−20, 80]
  proc.erodible_depth.assign(proc.grid.cells(), 0.0);
  proc.forest_drag.assign(proc.grid.cells(), 0.0);
  proc.friction[kManningN].assign(proc.grid.cells(), 0.06);
  for (int row = 0; row < proc.grid.ny; ++row)
    for (int col = 0; col < proc.grid.nx; ++col)
      if (proc.grid.centre(col, row).x() > 40.0) {
        proc.erodible_depth[proc.grid.index(col, row)] = 0.5;
        proc.forest_drag[proc.grid.index(col, row)] = 2e-3;
        proc.friction[kManningN][proc.grid.index(col, row)] = 0.08;
      }
  s.set_processes(std::move(proc));
  Barrier b;
  b.name = "golden";
  b.vertices = {Vec2(75.0, -20.0), Vec2(75.0, 80.0)};
  b.height = 1.5;
  b.upstream_left = true;
  s.set_barriers(BarrierSet({b}, WallLaw{0.2, 0.1, 100.0}, p.d0));
  add_block(s, 20, 12, p.d0 / std::sqrt(2.0), Vec2(0.0, 10.0), Vec2(3.0, 0.0));
  s.initialise();
  return s;
}

// Particle id = j·20 + i (i down the slope): 0 and 19 the upslope and downslope corners of the first
// row, 109 and 130 inside, 220 and 239 the corners of the last row.
const Totals kPlaneProcessesTotals = {6.2531921263316903, 40, 6232.2123193909019, 0, 232.21231939090126,
                                      155021701.96089298};
const std::vector<Golden> kPlaneProcesses = {
    {0, {20.746540722454114, 5.1270891767711628}, {3.3376790277016406, -0.45906949106299155}, 0.58713819370714126, 25},
    {19,
     {96.439072128903732, 5.1295066917686265},
     {4.6968014195665981, -0.64523948327180281},
     0.8958700012947004,
     26.583111787069239},
    {109,
     {62.202745694604076, 27.101677797887707},
     {5.5382569534396016, -0.25225957094885226},
     1.835995829655432,
     26.166874609425907},
    {130,
     {65.185671580981008, 31.812746204132527},
     {5.6299929065545156, 0.26396472432172435},
     1.8447502411756052,
     26.30658185558228},
    {220, {20.522704000460713, 53.725880979278543}, {3.3173544140238049, 0.44795324223008265}, 0.58849751930156069, 25},
    {239,
     {96.331097700525788, 53.757626798939903},
     {4.7095647084053249, 0.63182767897302328},
     0.89961820854785735,
     26.577318135963139},
};

TEST(RunoutStepGolden, BlockOnAPlaneWithProcessesAndABarrier) {
  omp_set_num_threads(1);
  auto s = plane_with_processes();
  for (int k = 0; k < 40; ++k) s.step();
  expect_matches("PlaneProcesses", s, kPlaneProcessesTotals, kPlaneProcesses);
}

}  // namespace
}  // namespace geohaz::runout
