// Stored-value tests of the DEM step (label: unit), in the habit of tests/sph/test_step_golden.cpp
// and LAMMPS's force-style tests: a few dozen steps of small hand-built cases on one thread (no
// packing, tessellation or bond installer, so that only the step is under test), then the state of
// a handful of discs — position, velocity, rotation, angular velocity, resultant force and torque —
// and of a handful of parallel bonds — state, normal and shear force, moment — compared with values
// stored from the code of commit "dem: stored-value step tests" (issue #30 item 5). The number of
// contacts and of broken bonds after the steps is compared exactly. Any change to the arithmetic of
// a step (a term of a contact law dropped, a sign, a wall or bond treated differently, the time
// step) moves these numbers by far more than the tolerance; a reordering of a floating-point sum
// moves them by round-off only.
//
// Tolerance 1e-9, relative to max(|stored value|, the largest component of the same quantity at the
// same disc or bond): a reordered floating-point sum (another compiler, FMA contraction) changes a
// value by ~1e-16 relative per step, and 40–60 explicit steps of a few hundred discs grow that to
// ~1e-12 (an estimate; the SPH cases measured ≤ 2.4e-14 after a reordering), while dropping the
// tangential dashpot and the rolling resistance moved disc 0's velocity by 3e-2 and its position by
// 6e-5 relative (checked when the values were stored). The scale guards components that cancel to
// near zero (a tangential force of 1e-9 N/m next to normal forces of 1e3 N/m).
//
// To regenerate after an intended change of the physics:
//   GEOHAZ_GOLDEN_PRINT=1 ./build/tests/dem/dem_step_golden
// prints the tables in the form below; paste them over the stored ones and say in the commit why
// the numbers moved (docs/dem.md, "Stored-value step tests").
//
// The thread count: below 2048 discs the loops run on one thread (core parallel.hpp), so the
// stored cases say nothing about threads; DemStepThreads runs a larger lattice on one and on two
// threads and compares every field bit for bit (docs/dem.md: the pair sums are grouped by blocks
// of discs, the same on any thread count).
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {
namespace {

bool print_mode() {
  return std::getenv("GEOHAZ_GOLDEN_PRINT") != nullptr;
}

/// The stored state of one disc.
struct DiscGolden {
  std::int64_t id;
  std::array<double, 2> x, v;
  double rotation, omega;
  std::array<double, 2> force;
  double torque;
};

/// The stored state of one bond.
struct BondGolden {
  std::size_t index;
  int state;  // BondState
  double normal_force, shear_force, moment;
};

/// What a case ends with besides the discs and bonds: the clock and the counts.
struct Counts {
  double time;
  std::int64_t steps;
  std::size_t contacts, broken;
};

// ---- The lattice of both cases ------------------------------------------------------------------
// nx × ny discs on a triangular lattice of spacing 1.96 R (R = 1 cm), radii R (0.9 + 0.1 s_k) with
// s_k a fixed sequence in [0, 1) (no random-number distribution, whose algorithm the standard
// leaves to the library): some neighbour pairs overlap at the start (contacts from the first
// step), the others touch later. Initial velocities and spins follow a fixed pattern of ±0.2 m/s
// and ±20 rad/s, so that pairs close and open, slide and roll in the first steps.
constexpr double kR = 0.01, kSpacing = 1.96 * kR, kRho = 2650.0;

double sequence(std::size_t k) {
  const double s = std::sin(12.9898 * static_cast<double>(k) + 1.0) * 43758.5453;
  return s - std::floor(s);
}

Vec2 lattice_point(int i, int j) {
  return Vec2((i + 0.5 * (j % 2) + 0.5) * kSpacing, (j + 0.5) * kSpacing * std::sqrt(3.0) / 2.0 + kR);
}

void add_lattice(DemSolver& s, int nx, int ny) {
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto k = static_cast<std::size_t>(j * nx + i);
      const std::size_t p =
          add_disc(s.discs, lattice_point(i, j), kR * (0.9 + 0.1 * sequence(k)), kRho, static_cast<std::int64_t>(k));
      const double q = static_cast<double>(k);
      s.discs.get<Velocity<2>>()[p] = Vec2(0.2 * std::sin(0.37 * q), 0.2 * std::cos(0.23 * q));
      s.discs.get<AngularVelocity>()[p] = 20.0 * std::sin(0.71 * q);
    }
}

/// A fixed floor under the lattice (touching the bottom row) and a top platen moving down at 1 m/s.
void add_walls(DemSolver& s, int nx, int ny) {
  const double w = (nx + 1) * kSpacing, top = lattice_point(0, ny - 1).y() + kR;
  WallSegment floor;
  floor.a = Vec2(-w, 0.05 * kR);
  floor.b = Vec2(2 * w, 0.05 * kR);
  floor.friction = 0.4;
  floor.restitution = 0.3;
  s.walls.push_back(floor);
  WallSegment platen;
  platen.a = Vec2(2 * w, top);
  platen.b = Vec2(-w, top);
  platen.velocity = Vec2(0.0, -1.0);
  platen.rolling_friction = 0.05;
  s.walls.push_back(platen);
}

/// Parallel bonds between lattice neighbours (a disc and its right, upper-left and upper-right
/// neighbours), every fifth left out so that some neighbour pairs interact by contact only; the
/// strengths vary along the sequence between 30 and 300 kPa so that some bonds break in the steps.
void add_bonds(DemSolver& s, int nx, int ny, double modulus) {
  const auto& x = s.discs.get<Position<2>>();
  const auto& r = s.discs.get<Radius>();
  std::size_t count = 0;
  auto bond = [&](int i, int j, int i2, int j2) {
    if (i2 < 0 || i2 >= nx || j2 >= ny) return;
    const auto a = static_cast<std::size_t>(j * nx + i), b = static_cast<std::size_t>(j2 * nx + i2);
    if (++count % 5 == 0) return;
    const double ra = r[a], rb = r[b], d0 = (x[b] - x[a]).norm();
    const double kn = modulus / (ra + rb), sigma = 0.3e5 + 2.7e5 * sequence(1000 + count);
    s.bonds.add(static_cast<std::int64_t>(a), static_cast<std::int64_t>(b), 0.8 * std::min(ra, rb), d0, kn, kn / 2.5,
                sigma, 1.5 * sigma);
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      bond(i, j, i + 1, j);
      const int shift = j % 2;  // odd rows sit half a spacing to the right
      bond(i, j, i - 1 + shift, j + 1);
      bond(i, j, i + shift, j + 1);
    }
}

// ---- Stored values: print and compare -----------------------------------------------------------

std::string arr(const double* p, int n) {
  std::string s = "{";
  char buf[40];
  for (int k = 0; k < n; ++k) {
    std::snprintf(buf, sizeof buf, "%s%.17g", k ? ", " : "", p[k]);
    s += buf;
  }
  return s + "}";
}

std::vector<DiscGolden> discs_of(const DemSolver& s, const std::vector<std::int64_t>& ids) {
  std::vector<DiscGolden> out;
  for (const std::int64_t id : ids) {
    const std::size_t i = s.index_of(id);
    const Vec2 x = s.discs.get<Position<2>>()[i], v = s.discs.get<Velocity<2>>()[i], f = s.discs.get<Force>()[i];
    out.push_back({id,
                   {x.x(), x.y()},
                   {v.x(), v.y()},
                   s.discs.get<Rotation>()[i],
                   s.discs.get<AngularVelocity>()[i],
                   {f.x(), f.y()},
                   s.discs.get<Torque>()[i]});
  }
  return out;
}

std::vector<BondGolden> bonds_of(const DemSolver& s, const std::vector<std::size_t>& which) {
  std::vector<BondGolden> out;
  for (const std::size_t b : which)
    out.push_back(
        {b, static_cast<int>(s.bonds.state[b]), s.bonds.normal_force[b], s.bonds.shear_force[b], s.bonds.moment[b]});
  return out;
}

Counts counts_of(const DemSolver& s) {
  return {s.time(), s.step_count(), s.contact_count(), s.events.size()};
}

void print_tables(const char* name, const Counts& c, const std::vector<DiscGolden>& d,
                  const std::vector<BondGolden>& b) {
  std::printf("// %s\nconst Counts k%sCounts = {%.17g, %lld, %zu, %zu};\n", name, name, c.time,
              static_cast<long long>(c.steps), c.contacts, c.broken);
  std::printf("const std::vector<DiscGolden> k%sDiscs = {\n", name);
  for (const auto& g : d)
    std::printf("    {%lld, %s, %s, %.17g, %.17g, %s, %.17g},\n", static_cast<long long>(g.id),
                arr(g.x.data(), 2).c_str(), arr(g.v.data(), 2).c_str(), g.rotation, g.omega,
                arr(g.force.data(), 2).c_str(), g.torque);
  std::printf("};\n");
  if (b.empty()) return;
  std::printf("const std::vector<BondGolden> k%sBonds = {\n", name);
  for (const auto& g : b)
    std::printf("    {%zu, %d, %.17g, %.17g, %.17g},\n", g.index, g.state, g.normal_force, g.shear_force, g.moment);
  std::printf("};\n");
}

constexpr double kTol = 1e-9;

void near(double got, double want, double scale, const std::string& what) {
  EXPECT_LE(std::abs(got - want), kTol * std::max(std::abs(want), scale))
      << what << " got " << got << " stored " << want;
}

void expect_matches(const char* name, const DemSolver& s, const Counts& counts, const std::vector<DiscGolden>& discs,
                    const std::vector<BondGolden>& bonds) {
  std::vector<std::int64_t> ids;
  for (const auto& g : discs) ids.push_back(g.id);
  std::vector<std::size_t> which;
  for (const auto& g : bonds) which.push_back(g.index);
  const auto got_discs = discs_of(s, ids);
  const auto got_bonds = bonds_of(s, which);
  const Counts got = counts_of(s);
  if (print_mode()) print_tables(name, got, got_discs, got_bonds);
  EXPECT_EQ(got.steps, counts.steps) << name;
  near(got.time, counts.time, 0.0, std::string(name) + ": time after the steps (the time-step limit)");
  EXPECT_EQ(got.contacts, counts.contacts) << name << ": disc–disc contacts";
  EXPECT_EQ(got.broken, counts.broken) << name << ": broken bonds";
  auto largest = [](std::initializer_list<double> v) {
    double m = 0.0;
    for (double a : v) m = std::max(m, std::abs(a));
    return m;
  };
  for (std::size_t k = 0; k < discs.size(); ++k) {
    const DiscGolden &g = got_discs[k], &w = discs[k];
    const std::string p = std::string(name) + ": disc " + std::to_string(w.id) + " ";
    const double sx = largest({w.x[0], w.x[1]}), sv = largest({w.v[0], w.v[1]});
    const double sf = largest({w.force[0], w.force[1]});
    for (int d = 0; d < 2; ++d) {
      near(g.x[d], w.x[d], sx, p + "position[" + std::to_string(d) + "]");
      near(g.v[d], w.v[d], sv, p + "velocity[" + std::to_string(d) + "]");
      near(g.force[d], w.force[d], sf, p + "force[" + std::to_string(d) + "]");
    }
    near(g.rotation, w.rotation, 0.0, p + "rotation");
    near(g.omega, w.omega, 0.0, p + "angular velocity");
    near(g.torque, w.torque, sf * kR, p + "torque");
  }
  for (std::size_t k = 0; k < bonds.size(); ++k) {
    const BondGolden &g = got_bonds[k], &w = bonds[k];
    const std::string p = std::string(name) + ": bond " + std::to_string(w.index) + " ";
    EXPECT_EQ(g.state, w.state) << p << "state";
    const double sf = largest({w.normal_force, w.shear_force});
    near(g.normal_force, w.normal_force, sf, p + "normal force");
    near(g.shear_force, w.shear_force, sf, p + "shear force");
    near(g.moment, w.moment, sf * kR, p + "moment");
  }
}

// ---- Case 1: a bonded block between a floor and a moving platen, linear springs ------------------
// 14 × 12 discs, parallel bonds (E = 10 MPa) on most lattice edges, linear spring–Coulomb contacts
// with friction, restitution, rolling resistance and a tangential dashpot, gravity, local damping
// 0.1, a floor and a platen moving down: contacts, bonds (some of which break in tension or shear),
// walls and rolling moments all act in the 50 steps.
DemSolver bonded_block() {
  DemSolver s;
  s.law = LinearSpringCoulomb{2e7, 2e7 / 2.5};
  s.contact.friction = 0.5;
  s.contact.restitution = 0.4;
  s.contact.rolling_friction = 0.1;
  s.contact.tangential_damping = 0.5;
  s.settings.local_damping = 0.1;
  add_lattice(s, 14, 12);
  add_bonds(s, 14, 12, 1e7);
  add_walls(s, 14, 12);
  s.initialise();
  return s;
}

// The stored discs (both cases), id = j·14 + i: 0 and 13 the bottom corners (on the floor), 77 and
// 90 inside, 154 and 167 the top corners (under the platen). The stored bonds: 7 and 192 break in
// tension within the 50 steps, the others stay intact.

const Counts kBondedBlockCounts = {0.0010165836077688855, 50, 42, 7};
const std::vector<DiscGolden> kBondedBlockDiscs = {
    {0,
     {0.0097810979137757503, 0.018510778012814016},
     {-0.065459445699526525, -0.0071686712386718407},
     0.0037332753452042496,
     9.2232580232266042,
     {-397.20703882596149, -84.575401810108204},
     -1.5629045976541047},
    {13,
     {0.26450782286164481, 0.018378677388650844},
     {0.089327211418037206, -0.057869041020817039},
     -0.0061112894115845518,
     0.45568826477524205,
     {229.25091522569426, 348.11966026067984},
     0.11915912612331575},
    {77,
     {0.15677289902123306, 0.1033400465017239},
     {-0.038325008299897829, -0.070196144813990585},
     0.00044842260892270677,
     11.185467962184701,
     {68.452209040597936, 36.544233747473868},
     1.5457424997735898},
    {90,
     {0.12742352670275059, 0.12029402752967101},
     {-0.17733295262247289, -0.011279128968594209},
     -0.0043625980005919307,
     -6.5675760959809084,
     {370.45263345654462, -514.52206204045831},
     1.5341903062809177},
    {154,
     {0.019670192243719735, 0.20471633490325877},
     {-0.14929021810684495, -0.89388002227508112},
     0.0055516781028577379,
     13.980650799132416,
     {-226.02797653185749, -1082.5213517141735},
     -2.5336792474721919},
    {167,
     {0.27439579045761586, 0.20442742934471528},
     {-0.019656420531337666, -1.0144970485304889},
     -0.020374607395271423,
     3.8984076882938741,
     {-157.85858191659301, -146.95505332503564},
     3.1230811000102614},
};
const std::vector<BondGolden> kBondedBlockBonds = {
    {0, 0, 330.44070112139644, 9.4443560390825052, -1.1369990299688599},
    {7, 1, -436.74830513782888, -24.335931733340885, -0.82633286688508656},
    {57, 0, 338.92421052803383, -33.770648987840715, 0.2426541296288372},
    {150, 0, -250.89888136965712, -35.89425118526556, 0.0087389465390610137},
    {192, 1, -758.86438420591298, 98.227846924271148, -0.041706261141235906},
    {330, 0, 349.12176942102786, -306.82826133643948, -0.39881585699794908},
};

TEST(DemStepGolden, BondedBlockBetweenFloorAndPlaten) {
  omp_set_num_threads(1);
  auto s = bonded_block();
  for (int k = 0; k < 50; ++k) s.step();
  expect_matches("BondedBlock", s, kBondedBlockCounts, kBondedBlockDiscs, kBondedBlockBonds);
}

// ---- Case 2: unbonded discs, Hertz–Mindlin ------------------------------------------------------
// The same lattice without bonds under the Hertz–Mindlin law (nonlinear normal and tangential
// stiffness), rolling resistance, no local damping: the contact history (shear spring, rolling
// spring) across the list rebuilds the moving discs cause.
DemSolver hertz_discs() {
  DemSolver s;
  s.law = HertzMindlin{5e7, 0.25, 0.005};
  s.contact.friction = 0.3;
  s.contact.restitution = 0.6;
  s.contact.rolling_friction = 0.2;
  add_lattice(s, 14, 12);
  add_walls(s, 14, 12);
  s.initialise();
  return s;
}

const Counts kHertzDiscsCounts = {0.0020986258939602585, 40, 78, 0};
const std::vector<DiscGolden> kHertzDiscsDiscs = {
    {0,
     {0.0097524791922759362, 0.01881470417764641},
     {-0.14306647200683956, -0.037206698156614343},
     0.00030778870715149115,
     1.0320866512283555,
     {-142.86947280623576, -242.0962537535643},
     -0.04034647491750467},
    {13,
     {0.264182272786188, 0.018051863089022745},
     {-0.19904796515383255, -0.2176608135267524},
     0.0081237262342263254,
     3.8709739823596037,
     {0, -6.6834649092246705},
     0},
    {77,
     {0.15649179665711313, 0.10325445704314279},
     {-0.21105054283388605, -0.12550862803330365},
     -0.016990855100976969,
     -0.92220129556584063,
     {0, -7.6001170268735265},
     0},
    {90,
     {0.12789530938383598, 0.12005724447595459},
     {0.1998507567497555, -0.10323889092955256},
     0.025103176936636655,
     5.2164065236515338,
     {-129.97475108769942, 122.51065125763395},
     -0.66803625534160871},
    {154,
     {0.019799616878248175, 0.20382502428872104},
     {0.065513935126657707, -1.3109320714857404},
     0.023993244321362146,
     7.0983877954262296,
     {151.04307201010835, -697.82424964117718},
     -1.1067715559175928},
    {167,
     {0.27427466625031277, 0.20344516226576348},
     {0.16690435880251064, -0.89550326358194121},
     -0.03065519661369432,
     23.927489545891859,
     {73.558407908219749, 11.41824018749068},
     2.6751929749821453},
};

TEST(DemStepGolden, UnbondedDiscsHertzMindlin) {
  omp_set_num_threads(1);
  auto s = hertz_discs();
  for (int k = 0; k < 40; ++k) s.step();
  expect_matches("HertzDiscs", s, kHertzDiscsCounts, kHertzDiscsDiscs, {});
}

// ---- Thread count: one and two threads give the same bits in every field -------------------------
template <class Make>
void expect_same_bits_on_one_and_two_threads(Make make, int steps) {
  std::vector<std::vector<unsigned char>> state(2);
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    auto s = make();
    ASSERT_GE(s.discs.size(), 2048u) << "smaller problems run on one thread anyway";
    for (int k = 0; k < steps; ++k) s.step();
    auto& bytes = state[static_cast<std::size_t>(threads - 1)];
    s.discs.for_each_field([&](auto, const auto& v) {
      const auto* p = reinterpret_cast<const unsigned char*>(v.data());
      bytes.insert(bytes.end(), p, p + v.size() * sizeof(v[0]));
    });
    for (const auto* v : {&s.bonds.normal_force, &s.bonds.shear_force, &s.bonds.moment}) {
      const auto* p = reinterpret_cast<const unsigned char*>(v->data());
      bytes.insert(bytes.end(), p, p + v->size() * sizeof(double));
    }
  }
  omp_set_num_threads(1);
  ASSERT_EQ(state[0].size(), state[1].size());
  EXPECT_TRUE(state[0] == state[1]) << "values of the store or the bonds differ between one and two threads";
}

TEST(DemStepThreads, BondedLatticeSameBitsOnOneAndTwoThreads) {
  expect_same_bits_on_one_and_two_threads(
      [] {
        DemSolver s;
        s.law = LinearSpringCoulomb{2e9, 2e9 / 2.5};
        s.contact.rolling_friction = 0.1;
        s.contact.tangential_damping = 0.5;
        add_lattice(s, 52, 42);
        add_bonds(s, 52, 42, 1e9);
        add_walls(s, 52, 42);
        s.initialise();
        return s;
      },
      10);
}

}  // namespace
}  // namespace geohaz::dem
