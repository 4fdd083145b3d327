// Stored-value tests of the SPH step (label: unit), in the habit of LAMMPS's force-style tests: a
// few steps of small hand-built cases on one thread, then the state of a handful of particles —
// position, velocity, acceleration, density rate, density, stress (all nine components) and
// plastic strain — compared with values stored from the code as it was before the step was cut
// into named passes (commit "sph: golden-value step tests"; the later change to thread-independent
// pair sums moved them by round-off, ≤ 2.4e-14 relative, and they were kept). Any change to the
// arithmetic of a step (a term dropped, a sign, a wall pair treated differently, a limit of the time
// step) moves these numbers by far more than the tolerance; a reordering of a floating-point sum
// moves them by round-off only.
//
// Tolerance 1e-10, relative to max(|stored value|, the largest component of the same quantity at the
// same particle): the cases are small and run a few steps, so round-off differences of the summation
// order (another compiler, FMA contraction, a pass reordered) grow to ~1e-13 at most, while any
// change of a term moves the values by > 1e-6. The particle's scale guards components that cancel
// to near zero (a shear stress of 1e-9 Pa next to normal stresses of 1e3 Pa), where a per-value
// relative test would measure round-off of the cancellation, not the step.
//
// To regenerate after an intended change of the physics: GEOHAZ_GOLDEN_PRINT=1 ./sph_step_golden
// prints the tables in the form below; say in the commit why the numbers moved.
#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <type_traits>
#include <vector>

#include "geohaz/core/parallel.hpp"
#include "geohaz/sph/solver.hpp"
#include "support.hpp"

namespace geohaz::sph {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// The stored state of one particle (3D layout; 2D cases leave the third component 0).
struct Golden {
  std::int64_t id;
  std::array<double, 3> x, v, a;
  double drho, rho, eps_p;
  std::array<double, 9> sigma;  // column-major 3×3
};

bool print_mode() {
  return std::getenv("GEOHAZ_GOLDEN_PRINT") != nullptr;
}

/// A hand-built store (no scenario builder, so that only the step is under test).
template <int Dim>
struct Builder {
  SphStore<Dim> S;
  std::size_t add(const Vec<Dim>& x, Kind kind, int material, double rho, double dx) {
    const std::size_t i = S.append(1);
    S.template get<Position<Dim>>()[i] = x;
    S.template get<Density>()[i] = rho;
    S.template get<Mass>()[i] = rho * std::pow(dx, Dim);
    S.template get<MaterialId>()[i] = material;
    S.template get<ParticleKind>()[i] = static_cast<std::uint8_t>(kind);
    S.template get<ParticleId>()[i] = static_cast<std::int64_t>(i);
    return i;
  }
};

template <int Dim>
Golden state_of(const SphStore<Dim>& S, std::int64_t id) {
  const auto& ids = S.template get<ParticleId>();
  std::size_t i = 0;
  while (i < S.size() && ids[i] != id) ++i;
  EXPECT_LT(i, S.size()) << "particle id " << id << " missing";
  Golden g{};
  if (i == S.size()) return g;
  g.id = id;
  for (int d = 0; d < Dim; ++d) {
    g.x[d] = S.template get<Position<Dim>>()[i][d];
    g.v[d] = S.template get<Velocity<Dim>>()[i][d];
    g.a[d] = S.template get<Acceleration<Dim>>()[i][d];
  }
  g.drho = S.template get<DensityRate>()[i];
  g.rho = S.template get<Density>()[i];
  g.eps_p = S.template get<PlasticStrain>()[i];
  for (int c = 0; c < 9; ++c) g.sigma[c] = S.template get<Stress>()[i].data()[c];
  return g;
}

void print_table(const char* name, double time, const std::vector<Golden>& got) {
  std::printf("// %s\nconstexpr double k%sTime = %.17g;\nconst std::vector<Golden> k%s = {\n", name, name, time, name);
  auto arr = [](const double* p, int n) {
    std::string s = "{";
    char buf[40];
    for (int k = 0; k < n; ++k) {
      std::snprintf(buf, sizeof buf, "%s%.17g", k ? ", " : "", p[k]);
      s += buf;
    }
    return s + "}";
  };
  for (const auto& g : got) {
    std::printf("    {%lld, %s, %s, %s,\n     %.17g, %.17g, %.17g,\n     %s},\n", static_cast<long long>(g.id),
                arr(g.x.data(), 3).c_str(), arr(g.v.data(), 3).c_str(), arr(g.a.data(), 3).c_str(), g.drho, g.rho,
                g.eps_p, arr(g.sigma.data(), 9).c_str());
  }
  std::printf("};\n");
}

/// Compare with the stored values (see the file comment for the tolerance).
template <int Dim>
void expect_matches(const char* name, const SphSolver<Dim>& solver, const std::vector<std::int64_t>& ids, double time,
                    const std::vector<Golden>& want) {
  std::vector<Golden> got;
  for (auto id : ids) got.push_back(state_of(solver.store(), id));
  if (print_mode()) print_table(name, solver.time(), got);
  ASSERT_EQ(want.size(), ids.size()) << name << ": stored table and particle list differ";
  constexpr double kTol = 1e-10;
  EXPECT_NEAR(solver.time(), time, kTol * time) << name << ": time after the steps (the time-step limits)";
  auto near = [&](double g, double w, double scale, const std::string& what) {
    EXPECT_LE(std::abs(g - w), kTol * std::max(std::abs(w), scale))
        << name << ": " << what << " got " << g << " stored " << w;
  };
  auto largest = [](const double* p, int n) {
    double m = 0.0;
    for (int k = 0; k < n; ++k) m = std::max(m, std::abs(p[k]));
    return m;
  };
  for (std::size_t k = 0; k < want.size(); ++k) {
    const Golden &g = got[k], &w = want[k];
    ASSERT_EQ(g.id, w.id);
    const std::string p = "particle " + std::to_string(w.id) + " ";
    // Scale of each quantity at this particle (its largest component).
    const double sx = largest(w.x.data(), 3), sv = largest(w.v.data(), 3), sa = largest(w.a.data(), 3);
    const double ss = largest(w.sigma.data(), 9);
    for (int d = 0; d < 3; ++d) {
      near(g.x[d], w.x[d], sx, p + "position[" + std::to_string(d) + "]");
      near(g.v[d], w.v[d], sv, p + "velocity[" + std::to_string(d) + "]");
      near(g.a[d], w.a[d], sa, p + "acceleration[" + std::to_string(d) + "]");
    }
    near(g.drho, w.drho, 0.0, p + "density rate");
    near(g.rho, w.rho, 0.0, p + "density");
    near(g.eps_p, w.eps_p, 0.0, p + "plastic strain");
    for (int c = 0; c < 9; ++c) near(g.sigma[c], w.sigma[c], ss, p + "stress[" + std::to_string(c) + "]");
  }
}

// ---- Case 1: 2D Drucker–Prager block between a roller wall (left), a fixed wall (right) and a
// fixed base sliding at 0.01 m/s, two materials, an inclined layering normal under part of the base,
// a pile particle, one soil particle squeezed against the right wall (wall repulsion), an initial
// stress with tension near the top (artificial stress, tension cut-off), earthquake loading,
// Cundall damping, XSPH, stress vanishing at the free corners; a short elastic geostatic phase,
// then Drucker–Prager steps with the list rebuilt and the store reordered every other step.
constexpr double kBlockDx = 0.01;
constexpr int kBlockNx = 12, kBlockNz = 10;

/// Velocities of case 1 (set at the start and again after the geostatic phase, which zeroes them).
void block_velocities(SphStore<2>& S) {
  const auto& id = S.get<ParticleId>();
  const auto& kind = S.get<ParticleKind>();
  const auto& x = S.get<Position<2>>();
  auto& v = S.get<Velocity<2>>();
  for (std::size_t p = 0; p < S.size(); ++p) {
    const double q = static_cast<double>(id[p]);
    if (kind[p] == static_cast<std::uint8_t>(Kind::Soil))
      v[p] = Vec2(0.02 * std::sin(0.37 * q), 0.015 * std::cos(0.23 * q));
    else if (kind[p] == static_cast<std::uint8_t>(Kind::FixedWall) && x[p][1] < 0.0)
      v[p] = Vec2(0.01, 0.0);
  }
}

SphSolver<2> drucker_prager_block(bool corrected = false, bool quadratic = false, int nx = kBlockNx,
                                  int nz = kBlockNz) {
  const double dx = kBlockDx;
  Builder<2> b;
  const double rho[2] = {1800.0, 2100.0};
  for (int i = 0; i < nx; ++i)
    for (int k = 0; k < nz; ++k) {
      const int mat = k < 4 ? 1 : 0;
      Vec2 x((i + 0.5) * dx, (k + 0.5) * dx);
      if (i == nx - 1 && k == 5) x[0] += 0.55 * dx;  // 0.45 dx from the right wall's first layer: repulsion
      const auto p = b.add(x, Kind::Soil, mat, rho[mat] * (1.0 + 0.01 * std::sin(1.3 * i + 0.7 * k)), dx);
      const double depth = nz * dx - x[1];
      Mat3 s = Mat3::Zero();
      s(1, 1) = -rho[mat] * 9.81 * depth;
      s(0, 0) = 0.5 * s(1, 1) + (k >= nz - 2 ? 900.0 : 0.0);  // tension in the two top rows
      s(2, 2) = 0.6 * s(1, 1);
      s(0, 1) = s(1, 0) = 40.0 * std::sin(0.9 * i - 0.4 * k);
      b.S.get<Stress>()[p] = s;
    }
  for (int l = 0; l < 3; ++l) {
    for (int i = -3; i < nx + 3; ++i) {  // base; layering inclined 15° for x > 6 dx
      const auto p = b.add(Vec2((i + 0.5) * dx, -(l + 0.5) * dx), Kind::FixedWall, 0, rho[0], dx);
      b.S.get<WallNormal<2>>()[p] = Vec2(0.0, 1.0);
      b.S.get<LayerNormal<2>>()[p] = i > 6 ? Vec2(std::sin(15 * kDeg), std::cos(15 * kDeg)) : Vec2(0.0, 1.0);
    }
    for (int k = 0; k < nz + 3; ++k) {
      const auto pl = b.add(Vec2(-(l + 0.5) * dx, (k + 0.5) * dx), Kind::RollerWall, 0, rho[0], dx);
      b.S.get<WallNormal<2>>()[pl] = Vec2(1.0, 0.0);
      const auto pr = b.add(Vec2((nx + l + 0.5) * dx, (k + 0.5) * dx), Kind::FixedWall, 1, rho[1], dx);
      b.S.get<WallNormal<2>>()[pr] = Vec2(-1.0, 0.0);
    }
  }
  b.add(Vec2(5.5 * dx, (nz + 1) * dx), Kind::Pile, 0, rho[0], dx);  // a pile particle above the block
  block_velocities(b.S);
  MaterialParams m0, m1;
  m0.density = rho[0];
  m0.young = 2e6;
  m0.poisson = 0.3;
  m0.cohesion = 500.0;
  m0.friction = 30 * kDeg;
  m0.dilatancy = 5 * kDeg;
  m1 = m0;
  m1.density = rho[1];
  m1.young = 8e6;
  m1.cohesion = 0.0;
  m1.friction = 35 * kDeg;
  SolverSettings<2> s;
  s.spacing = dx;
  s.h_factor = 1.3;
  s.viscosity_beta = 0.5;
  s.xsph = 0.3;
  s.damping = 0.1;
  s.stress_free_fraction = 0.8;
  s.reorder_every = 2;
  s.neighbour_skin = 0.0;
  s.domain_lo = Vec2(-1.0, -1.0);
  s.domain_hi = Vec2(1.0, 1.0);
  s.earthquake = EarthquakeLoading::sine(3.0, 5.0, 0.0, 1.0, 0.0);
  s.kernel_correction = corrected;
  s.quadratic_correction = quadratic;
  return SphSolver<2>(std::move(b.S), {m0, m1}, DruckerPrager{}, s);
}

// Soil id = i·nz + k: 0 left bottom corner (roller wall and base), 9 left top corner, 65 middle,
// 69 top (tension), 110 right bottom corner (fixed wall and base), 115 squeezed against the right wall.
const std::vector<std::int64_t> kBlockIds = {0, 9, 65, 69, 110, 115};
constexpr double kDruckerPragerBlockTime = 0.00017388636777774695;
const std::vector<Golden> kDruckerPragerBlock = {
    {0,
     {0.0050002237560866384, 0.005002393206238789, 0},
     {-0.001669309990595909, 0.0077731335069037332, 0},
     {-14.856597373685664, -42.954727654066865, 0},
     -506.74908320100241,
     2100,
     0.00041457540390819311,
     {-534.62113530712122, -202.02391741918692, 0, -202.02391741918692, -297.97700188287212, 0, 0, 0,
      -467.64325691027727}},
    {9,
     {0.0049991440055040144, 0.094998082355856592, 0},
     {-0.0058953253321254642, -0.0074747655171057944, 0},
     {-12.031850230106324, -1.2091814981271822, 0},
     328.09504894997661,
     1800.3477238943676,
     0.00028230512597160695,
     {534.46635841448528, -17.901705603613774, 0, -17.901705603613774, -63.710764591158579, 0, 0, 0,
      -9.7282044162597572}},
    {65,
     {0.064996588835060487, 0.054997770876455396, 0},
     {-0.015459951314856028, -0.010534059304406571, 0},
     {13.704042881587787, 2.5854663039834769, 0},
     627.80818062648541,
     1799.1521278822006,
     0,
     {-630.43722462493872, -101.77208067276285, 0, -101.77208067276285, -935.62025276407701, 0, 0, 0,
      -589.00874321670483}},
    {69,
     {0.065001424760822463, 0.094996667084788197, 0},
     {0.00615943508316605, -0.014958064859210288, 0},
     {-9.0280800855283214, -0.51206665003916307, 0},
     1458.2322742078909,
     1818.3894136761428,
     0,
     {0, 0, 0, 0, 0, 0, 0, 0, 0}},
    {110,
     {0.11500108759177186, 0.0050023083919222685, 0},
     {0.0069349777888398738, 0.010542769156036488, 0},
     {27.851047315279118, -24.340543920256305, 0},
     -834.32855171263236,
     2120.3564462552613,
     0.00034605347791991878,
     {-96.301839104542623, -39.361430131760699, 0, -39.361430131760699, -57.177200922844015, 0, 0, 0,
      -97.746164978406682}},
    {115,
     {0.11990971341199599, 0.055000786154170235, 0},
     {-4.2572330534695881, 0.0041283292590335195, 0},
     {998.39202198725684, 1.0162471291006239, 0},
     -713583.71168122068,
     1799.0651783115111,
     0.082820962541837642,
     {866.02540378443871, 0, 0, 0, 866.02540378443871, 0, 0, 0, 866.02540378443871}},
};

TEST(StepGolden, DruckerPragerBlockWithFixedAndRollerWalls) {
  auto solver = drucker_prager_block();
  solver.apply_gravity_gradually(2.5 * solver.dt(), 0.7, true);  // about three elastic steps, then t = 0
  block_velocities(solver.store());
  for (int k = 0; k < 5; ++k) solver.step();
  if (print_mode()) {
    int free = 0, plastic = 0;
    for (std::size_t p = 0; p < solver.store().size(); ++p) {
      free += solver.store().get<StressFree>()[p];
      plastic += solver.store().get<PlasticStrain>()[p] > 0.0;
    }
    double rmin = 1e300;
    for (std::size_t p = 0; p < solver.store().size(); ++p)
      if (solver.store().get<ParticleKind>()[p] == 0)
        rmin = std::min(rmin, solver.store().get<SummationDensity>()[p] / solver.store().get<Density>()[p]);
    std::printf("// %d stress-free particles, %d with plastic strain, min summation/continuity density %.3f\n", free,
                plastic, rmin);
  }
  expect_matches("DruckerPragerBlock", solver, kBlockIds, kDruckerPragerBlockTime, kDruckerPragerBlock);
}

// ---- Case 1b: the same block with the kernel-gradient correction (numerics.kernel_correction,
// Bonet & Lok 1999): C_i in the velocity gradient and the stress pair, its guard at the corners and
// next to the walls, the walls' pairs with C_i of the soil particle. Values stored from the code
// that introduced the correction (no older reference exists); the corrected gradient itself is
// checked against closed forms in test_kinematics.cpp (KernelCorrection.*).
constexpr double kCorrectedDruckerPragerBlockTime = 0.00017388387504289779;
const std::vector<Golden> kCorrectedDruckerPragerBlock = {
    {0,
     {0.005000226391791783, 0.00500240166142789, 0},
     {-0.0016227201335347187, 0.0078287512028292379, 0},
     {-14.558056310920719, -42.672448692634369, 0},
     -513.43195663063102,
     2100,
     0.0004083006038449022,
     {-541.25246225608203, -205.08989420643397, 0, -205.08989420643397, -302.56954876186933, 0, 0, 0,
      -473.99864384464479}},
    {9,
     {0.0049990901978375487, 0.094998173957025117, 0},
     {-0.0062993676115613989, -0.0068863959735413014, 0},
     {-13.152701734509922, 2.9402919272344898, 0},
     335.74624327472964,
     1800.348666809133,
     0.00026412281729376157,
     {490.75436704641947, -55.112537367738696, 0, -55.112537367738696, -109.08255090829427, 0, 0, 0,
      -46.432144219729608}},
    {65,
     {0.064996586731002351, 0.054997767500428597, 0},
     {-0.015479191862265653, -0.01055278911971012, 0},
     {13.574491192717508, 2.4730754999328681, 0},
     630.09118354289149,
     1799.1523159910225,
     0,
     {-628.47181111480074, -100.88370194107155, 0, -100.88370194107155, -934.40762921738178, 0, 0, 0,
      -588.05533209965472}},
    {69,
     {0.065001342574716084, 0.094996694620252009, 0},
     {0.0057153445942435188, -0.014774461554772926, 0},
     {-11.644467797387611, 0.6888970902411955, 0},
     1466.5046881797525,
     1818.3901995602573,
     0,
     {0, 0, 0, 0, 0, 0, 0, 0, 0}},
    {110,
     {0.11500108152480522, 0.0050023116268306895, 0},
     {0.006868159792331973, 0.01056510583981461, 0},
     {27.401443010082886, -24.18918601664782, 0},
     -843.84491847448089,
     2120.3556451649506,
     0.00034063379810145213,
     {-106.89429377312098, -44.059960577222725, 0, -44.059960577222725, -64.114353428878587, 0, 0, 0,
      -109.00745857562801}},
    {115,
     {0.1199095394605771, 0.055000779762403459, 0},
     {-4.2615311586066715, 0.0040209375807413296, 0},
     {961.7107111725694, 0.18975299110350258, 0},
     -713653.47576635215,
     1799.0651783115111,
     0.09277485650149718,
     {866.02540378443871, 0, 0, 0, 866.02540378443871, 0, 0, 0, 866.02540378443871}},
};

TEST(StepGolden, CorrectedDruckerPragerBlockWithFixedAndRollerWalls) {
  auto solver = drucker_prager_block(true);
  solver.apply_gravity_gradually(2.5 * solver.dt(), 0.7, true);
  block_velocities(solver.store());
  for (int k = 0; k < 5; ++k) solver.step();
  expect_matches("CorrectedDruckerPragerBlock", solver, kBlockIds, kCorrectedDruckerPragerBlockTime,
                 kCorrectedDruckerPragerBlock);
}

// ---- Case 1c: the same block with the quadratic-complete correction (numerics.kernel_correction =
// "quadratic", solver.cpp step 2: A_i = the first rows of B_i⁻¹, g_ij = A_i b_ij in the velocity
// gradient, the stress pair and the walls' pairs, the guards). Values stored 2026-12-02 from the code
// that introduced it; against case 1b interior particles differ by ~1 % in acceleration, free-surface
// and corner ones by up to 25 % (particle 9, top corner by the fixed wall: σ_xx 491 → 590 Pa). The
// gradient itself is checked against closed forms in test_kinematics.cpp (KernelCorrection.Quadratic*).
constexpr double kQuadraticDruckerPragerBlockTime = 0.00017388265698893923;
const std::vector<Golden> kQuadraticDruckerPragerBlock = {
    {0,
     {0.0050002267162260802, 0.005002402285711101, 0},
     {-0.0016171852336685287, 0.0078380599459025434, 0},
     {-14.513584392702436, -42.597188828937568, 0},
     -513.34407357214764,
     2100,
     0.00040837336095939591,
     {-541.27885486231446, -205.07994666564286, 0, -205.07994666564286, -302.5538778007375, 0, 0, 0,
      -473.99524968311295}},
    {9,
     {0.0049991514951803744, 0.09499811664176136, 0},
     {-0.0058730058729328733, -0.0072925313520574393, 0},
     {-12.609440576946898, -0.44178435167032537, 0},
     338.21704545052307,
     1800.3482137587043,
     0.00034018740850106711,
     {589.73816189397758, 24.340902496235458, 0, 24.340902496235458, 71.825087537165189, 0, 0, 0, 83.374239653295888}},
    {65,
     {0.064996587955576085, 0.054997768369991276, 0},
     {-0.015464721559094575, -0.010547587752629962, 0},
     {13.716501987703467, 2.5026393271173455, 0},
     624.14299507067108,
     1799.1518120342641,
     0,
     {-628.6453622155218, -100.98369688353193, 0, -100.98369688353193, -933.99691544152154, 0, 0, 0,
      -587.98418329711285}},
    {69,
     {0.065001244317034398, 0.09499679573138943, 0},
     {0.0053166925992920895, -0.014059832698238158, 0},
     {-13.399606010533624, 4.9042178835641765, 0},
     1391.931669700597,
     1818.3827864142036,
     0,
     {0, 0, 0, 0, 0, 0, 0, 0, 0}},
    {110,
     {0.11500108150433945, 0.0050023123517452589, 0},
     {0.0068668495834512192, 0.010573200116963787, 0},
     {27.406404312355772, -24.094957263555351, 0},
     -847.29089461228875,
     2120.3553350895018,
     0.00034080217020966675,
     {-105.65388318249346, -43.463141339225032, 0, -43.463141339225032, -63.214544891878951, 0, 0, 0,
      -107.70772211786323}},
    {115,
     {0.11990940607877261, 0.055000778344820089, 0},
     {-4.2638448016177586, 0.0039925294953973454, 0},
     {924.09785750655089, 0.023196177710032372, 0},
     -713522.92618231534,
     1799.0651783115111,
     0.088951156592285793,
     {866.02540378443871, 0, 0, 0, 866.02540378443871, 0, 0, 0, 866.02540378443871}},
};

TEST(StepGolden, QuadraticCorrectedDruckerPragerBlockWithFixedAndRollerWalls) {
  auto solver = drucker_prager_block(true, true);
  solver.apply_gravity_gradually(2.5 * solver.dt(), 0.7, true);
  block_velocities(solver.store());
  for (int k = 0; k < 5; ++k) solver.step();
  expect_matches("QuadraticDruckerPragerBlock", solver, kBlockIds, kQuadraticDruckerPragerBlockTime,
                 kQuadraticDruckerPragerBlock);
}

// ---- Case 2: 2D Newtonian fluid in a box under a lid sliding at 0.05 m/s, under gravity: the
// fluid's wave speed √(K/ρ0), its viscous time-step limit 0.125 h²ρ/μ (which binds here: 1.5e-4 s
// against 2.7e-4 s from the CFL condition), its geostatic phase without the elastic substitute,
// and the fluid stress in the pairs.
void fluid_velocities(SphStore<2>& S) {
  const auto& id = S.get<ParticleId>();
  const auto& kind = S.get<ParticleKind>();
  const auto& x = S.get<Position<2>>();
  auto& v = S.get<Velocity<2>>();
  for (std::size_t p = 0; p < S.size(); ++p) {
    const double q = static_cast<double>(id[p]);
    if (kind[p] == static_cast<std::uint8_t>(Kind::Soil))
      v[p] = Vec2(0.01 * std::sin(0.8 * q), -0.005 * std::sin(0.6 * q));
    else if (x[p][1] > 0.05)
      v[p] = Vec2(0.05, 0.0);  // the lid
  }
}

SphSolver<2> fluid_box() {
  const double dx = 0.005;
  const int nx = 10, nz = 10;
  Builder<2> b;
  const double rho = 1000.0;
  for (int i = 0; i < nx; ++i)
    for (int k = 0; k < nz; ++k)
      b.add(Vec2((i + 0.5) * dx, (k + 0.5) * dx), Kind::Soil, 0, rho * (1.0 + 0.002 * std::cos(i + 2.0 * k)), dx);
  for (int l = 0; l < 3; ++l) {
    for (int i = -3; i < nx + 3; ++i) {
      const auto pb = b.add(Vec2((i + 0.5) * dx, -(l + 0.5) * dx), Kind::FixedWall, 0, rho, dx);
      b.S.get<WallNormal<2>>()[pb] = Vec2(0.0, 1.0);
      const auto pt = b.add(Vec2((i + 0.5) * dx, (nz + l + 0.5) * dx), Kind::FixedWall, 0, rho, dx);
      b.S.get<WallNormal<2>>()[pt] = Vec2(0.0, -1.0);
    }
    for (int k = 0; k < nz; ++k) {
      const auto pl = b.add(Vec2(-(l + 0.5) * dx, (k + 0.5) * dx), Kind::RollerWall, 0, rho, dx);
      b.S.get<WallNormal<2>>()[pl] = Vec2(1.0, 0.0);
      const auto pr = b.add(Vec2((nx + l + 0.5) * dx, (k + 0.5) * dx), Kind::FixedWall, 0, rho, dx);
      b.S.get<WallNormal<2>>()[pr] = Vec2(-1.0, 0.0);
    }
  }
  fluid_velocities(b.S);
  MaterialParams m;
  m.density = rho;
  m.young = 3.0 * 2e4;  // K = 2e4 Pa: c = 4.5 m/s
  m.poisson = 0.0;
  m.viscosity = 30.0;  // ν = 0.03 m²/s
  SolverSettings<2> s;
  s.spacing = dx;
  s.viscosity_alpha = 0.05;
  s.artificial_stress = 0.0;
  s.neighbour_skin = 0.0;
  s.domain_lo = Vec2(-1.0, -1.0);
  s.domain_hi = Vec2(1.0, 1.0);
  return SphSolver<2>(std::move(b.S), {m}, NewtonianFluid{}, s);
}

// Soil id = i·nz + k: 0 bottom left corner, 9 top left under the lid, 44 middle, 95 at the right
// wall, 99 top right corner.
const std::vector<std::int64_t> kFluidIds = {0, 9, 44, 95, 99};
constexpr double kFluidBoxTime = 0.00060000000000000006;
const std::vector<Golden> kFluidBox = {
    {0,
     {0.0024992047513896784, 0.0025006962003464514, 0},
     {-0.0013931747750535967, 0.00060878739919506075, 0},
     {-0.80912319596621862, -0.60911448740418628, 0},
     -34.279028123622616,
     1001.7508907338926,
     0,
     {-16.074745530112963, -1.9793875041734306, 0, -1.9793875041734306, -53.295002265854215, 0, 0, 0,
      -35.683696237586581}},
    {9,
     {0.0025120138651788348, 0.047508156191529947, 0},
     {0.017962042508052403, 0.013148231445445309, 0},
     {12.014822529200321, 10.367611382593436, 0},
     -631.44237221619119,
     1001.0217018929543,
     0,
     {88.181035600867546, 204.46715784655981, 0, 204.46715784655981, -116.37624815450559, 0, 0, 0,
      -33.106901023623756}},
    {44,
     {0.022496164304071684, 0.022493866669549289, 0},
     {-0.0032581864442880761, -0.0095960513752193655, 0},
     {3.7268418194516273, -7.9908322945704979, 0},
     435.45954111741116,
     1002.5409857019622,
     0,
     {-75.16822499132013, 1.6971168294608494, 0, 1.6971168294608494, -35.176222270918565, 0, 0, 0,
      -42.114694855497007}},
    {95,
     {0.047504054246012152, 0.027497206980409226, 0},
     {0.0036125122546146896, -0.0049462452164154404, 0},
     {-3.7400242986148857, -4.8111397476432778, 0},
     27.721023138597388,
     1002.0947854144588,
     0,
     {-36.328849282495348, 41.302051318985072, 0, 41.302051318985072, -48.025890530035497, 0, 0, 0,
      -41.332385054999797}},
    {99,
     {0.047500993550300435, 0.047500946795432625, 0},
     {0.0047591943194653478, 0.0023654541092179293, 0},
     {14.819036909817031, 5.8203490289114512, 0},
     739.48064138079508,
     999.6176496546118,
     0,
     {-52.316591617946742, 264.40955629132827, 0, 264.40955629132827, 52.814020573320448, 0, 0, 0, 22.443591767921255}},
};

TEST(StepGolden, NewtonianFluidBoxWithMovingLid) {
  auto solver = fluid_box();
  solver.apply_gravity_gradually(1.5 * solver.dt(), 0.5, true);  // two steps; the fluid keeps its own model
  fluid_velocities(solver.store());
  for (int k = 0; k < 4; ++k) solver.step();
  expect_matches("FluidBox", solver, kFluidIds, kFluidBoxTime, kFluidBox);
}

// ---- Case 3: 3D Drucker–Prager block (compression-cone constants), periodic across the width,
// roller walls at both ends on a fixed base, with a Verlet skin of 0.3h (the list reused between
// builds) and reordering every third step.
SphSolver<3> drucker_prager_3d(int nx = 6, int ny = 6, int nz = 5) {
  const double dx = 0.01;
  Builder<3> b;
  const double rho = 1900.0;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const auto p = b.add(Vec3((i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx), Kind::Soil, 0, rho, dx);
        const double depth = nz * dx - (k + 0.5) * dx;
        Mat3 s = Mat3::Zero();
        s(2, 2) = -rho * 9.81 * depth;
        s(0, 0) = s(1, 1) = 0.5 * s(2, 2);
        s(0, 2) = s(2, 0) = 20.0 * std::sin(1.1 * i + 0.5 * j);
        s(1, 2) = s(2, 1) = 15.0 * std::cos(0.7 * j + 0.3 * k);
        b.S.get<Stress>()[p] = s;
        b.S.get<Velocity<3>>()[p] =
            Vec3(0.01 * std::sin(0.9 * k + j), 0.004 * std::cos(1.3 * i), -0.006 * std::sin(0.5 * i + k));
      }
  for (int l = 0; l < 3; ++l)
    for (int j = 0; j < ny; ++j) {
      for (int i = -3; i < nx + 3; ++i) {
        const auto p = b.add(Vec3((i + 0.5) * dx, (j + 0.5) * dx, -(l + 0.5) * dx), Kind::FixedWall, 0, rho, dx);
        b.S.get<WallNormal<3>>()[p] = Vec3(0.0, 0.0, 1.0);
      }
      for (int k = 0; k < nz + 2; ++k) {
        const auto pl = b.add(Vec3(-(l + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx), Kind::RollerWall, 0, rho, dx);
        b.S.get<WallNormal<3>>()[pl] = Vec3(1.0, 0.0, 0.0);
        const auto pr = b.add(Vec3((nx + l + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx), Kind::RollerWall, 0, rho, dx);
        b.S.get<WallNormal<3>>()[pr] = Vec3(-1.0, 0.0, 0.0);
      }
    }
  MaterialParams m;
  m.density = rho;
  m.young = 3e6;
  m.poisson = 0.25;
  m.cohesion = 20.0;
  m.friction = 25 * kDeg;
  m.fit = DruckerPragerFit::Compression3D;
  SolverSettings<3> s;
  s.spacing = dx;
  s.neighbour_skin = 0.3;
  s.reorder_every = 3;
  s.damping = 0.05;
  s.periodic.axis = {false, true, false};
  s.periodic.lo = Vec3(-1.0, 0.0, -1.0);
  s.periodic.hi = Vec3(1.0, ny * dx, 1.0);
  s.domain_lo = Vec3(-1.0, -1.0, -1.0);
  s.domain_hi = Vec3(1.0, 1.0, 1.0);
  return SphSolver<3>(std::move(b.S), {m}, DruckerPrager{}, s);
}

// Soil id = (i·ny + j)·nz + k: 0 corner at the left roller wall and the base, 4 top at the left
// wall, 87 inside at the periodic seam, 150 bottom at the right roller wall, 179 top right corner.
const std::vector<std::int64_t> k3DIds = {0, 4, 87, 150, 179};
constexpr double kDruckerPrager3DTime = 0.0003307461703835517;
const std::vector<Golden> kDruckerPrager3D = {
    {0,
     {0.0049999016662684442, 0.0050014391738046294, 0.005000208088549148},
     {-0.00059281259022407151, 0.0047139565543137078, 0.0013897830475187423},
     {-2.4452063811944611, 2.8498694587784845, 6.5722335180757607},
     85.741498367593053,
     1900.0672033503597,
     0,
     {-432.70072062537207, 112.95194765463678, 27.252729266936541, 112.95194765463678, -470.89004022170133,
      157.99091292136018, 27.252729266936541, 157.99091292136018, -986.14205550014537}},
    {4,
     {0.0049988486269562996, 0.0050010469415114776, 0.045001141363577836},
     {-0.0025950983625617216, 0.0024739505156756185, 0.0024539732488513873},
     {7.1978920152884207, -5.28548330512902, -7.4647551108336376},
     135.48441389158472,
     1900.0644054327108,
     0.0001507829632524054,
     {-189.67343668581094, -72.780996241647685, -35.000287714183663, -72.780996241647685, -120.24139274189517,
      5.2977685600026652, -35.000287714183663, 5.2977685600026652, -79.85460937135916}},
    {87,
     {0.025001444762954211, 0.054998997585576623, 0.02499983789154089},
     {0.0038289039364689972, -0.0027179290932741787, -0.00018722821923484854},
     {-4.1263121392901692, 2.1442698202457664, 2.1258506121012166},
     -351.70788965823658,
     1899.9592552422844,
     0.0001582196181209096,
     {-96.59454032312658, 35.738994796570765, 60.175076617430108, 35.738994796570765, -93.785924917781429,
      -3.2289121120744317, 60.175076617430108, -3.2289121120744317, -63.48215890516056}},
    {150,
     {0.054999991307107435, 0.0050007987905656892, 0.0049990883584560743},
     {-0.00011176208735713149, 0.00081771157296733638, -0.0018749636770101212},
     {-0.70554591702503788, -13.405201702729389, 7.715658606323216},
     110.50721121820318,
     1900.0885412085008,
     0,
     {-506.60326087577334, 183.9766821598169, 57.014581636904154, 183.9766821598169, -467.74680087455704,
      121.52308663038404, 57.014581636904154, 121.52308663038404, -982.77468335805395}},
    {179,
     {0.055001573169082975, 0.055001397526279125, 0.045000063446253576},
     {0.0021179271754993016, 0.0045695530041360991, 0.0017527822139515191},
     {-21.83621799878955, 2.83862229688265, 12.763624871563357},
     684.54497933583082,
     1900.4079792370032,
     0,
     {-706.34501641790052, -62.616560777110941, -30.833646344583926, -62.616560777110941, -288.23247992253641,
      16.076517866820403, -30.833646344583926, 16.076517866820403, -480.15591264907357}},
};

TEST(StepGolden, DruckerPrager3DPeriodicBlockWithSkin) {
  auto solver = drucker_prager_3d();
  for (int k = 0; k < 6; ++k) solver.step();
  expect_matches("DruckerPrager3D", solver, k3DIds, kDruckerPrager3DTime, kDruckerPrager3D);
}

// ---- Thread count: the same steps on one and on two threads give the same bits in every field,
// on the cases above made larger than the small-problem threshold (kParallelMin particles)
// (issue #12 item 9; the pair reactions are summed per block of particles, not per thread, see
// solver.cpp PairBlocks). Before, two threads grouped the reaction sums differently and the results
// differed at round-off.
template <int Dim>
std::vector<double> every_field(const SphStore<Dim>& S) {
  std::vector<double> out;
  S.for_each_field([&](auto, const auto& v) {
    for (const auto& e : v) {
      if constexpr (std::is_arithmetic_v<std::decay_t<decltype(e)>>)
        out.push_back(static_cast<double>(e));
      else
        for (int c = 0; c < e.size(); ++c) out.push_back(e.data()[c]);
    }
  });
  return out;
}

template <int Dim, class Make>
void expect_same_bits_on_one_and_two_threads(Make make, int steps) {
  std::vector<double> state[2];
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    auto solver = make();
    // Loops over fewer particles run on one thread (core parallel.hpp): the case must be larger.
    ASSERT_GE(static_cast<std::int64_t>(solver.store().size()), kParallelMin);
    for (int k = 0; k < steps; ++k) solver.step();
    state[threads - 1] = every_field(solver.store());
  }
  omp_set_num_threads(1);
  ASSERT_EQ(state[0].size(), state[1].size());
  std::size_t differ = 0;
  for (std::size_t k = 0; k < state[0].size(); ++k)
    differ += std::memcmp(&state[0][k], &state[1][k], sizeof(double)) != 0;
  EXPECT_EQ(differ, 0u) << "values of the store that differ between one and two threads";
}

TEST(StepThreads, DruckerPragerBlockSameBitsOnOneAndTwoThreads) {
  expect_same_bits_on_one_and_two_threads<2>([] { return drucker_prager_block(false, false, 48, 40); }, 8);
}

TEST(StepThreads, CorrectedDruckerPragerBlockSameBitsOnOneAndTwoThreads) {
  expect_same_bits_on_one_and_two_threads<2>([] { return drucker_prager_block(true, false, 48, 40); }, 8);
  expect_same_bits_on_one_and_two_threads<2>([] { return drucker_prager_block(true, true, 48, 40); }, 8);
}

TEST(StepThreads, DruckerPrager3DSameBitsOnOneAndTwoThreads) {
  expect_same_bits_on_one_and_two_threads<3>([] { return drucker_prager_3d(12, 12, 12); }, 8);
}

// ---- Restart in-process: a solver built from a copy of the store after k steps (without the
// scratch fields a snapshot does not hold), resumed with the state of the first (SolverState),
// continues exactly as the first one does. A wrong next Δt fails it (checked: 1e-15 relative); the
// state also carries the neighbour-list build count, so the resumed solver reorders its store at
// the same rebuilds (reorder_every = 2 and 3 in these cases; over a long run it is covered by
// SphSlopeApp.RestartReproducesTheUninterruptedRunBitForBit).
template <int Dim, class Make>
void expect_resume_reproduces(Make make, int before, int after) {
  auto a = make();
  for (int k = 0; k < before; ++k) a.step();
  auto b = make();
  b.store() = a.store();
  // What a snapshot does not hold is scratch, rewritten before it is read: start b without it.
  auto& S = b.store();
  for (auto& e : S.template get<Acceleration<Dim>>()) e.setZero();
  for (auto& e : S.template get<VelocityGradient<Dim>>()) e.setZero();
  for (auto& e : S.template get<XsphCorrection<Dim>>()) e.setZero();
  for (auto& e : S.template get<ArtificialStress<Dim>>()) e.setZero();
  for (auto& e : S.template get<PairStress<Dim>>()) e.setZero();
  for (auto* f : {&S.template get<DensityRate>(), &S.template get<SummationDensity>(), &S.template get<Volume>()})
    std::fill(f->begin(), f->end(), 0.0);
  b.resume(a.state());
  for (int k = 0; k < after; ++k) {
    a.step();
    b.step();
  }
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ(a.step_count(), b.step_count());
  const auto sa = every_field(a.store()), sb = every_field(b.store());
  ASSERT_EQ(sa.size(), sb.size());
  std::size_t differ = 0;
  for (std::size_t k = 0; k < sa.size(); ++k) differ += std::memcmp(&sa[k], &sb[k], sizeof(double)) != 0;
  EXPECT_EQ(differ, 0u) << "values of the store that differ between the resumed and the uninterrupted solver";
}

TEST(StepRestart, ResumedSolverContinuesBitForBit) {
  expect_resume_reproduces<2>([] { return drucker_prager_block(); }, 5, 5);
  expect_resume_reproduces<2>([] { return drucker_prager_block(true); }, 5, 5);
  expect_resume_reproduces<2>([] { return drucker_prager_block(true, true); }, 5, 5);
  expect_resume_reproduces<3>([] { return drucker_prager_3d(); }, 4, 6);
}

}  // namespace
}  // namespace geohaz::sph
