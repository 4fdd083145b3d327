// Unit tests of sample building: packing, tessellation (CGAL), bonding and joint cutting.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "geohaz/dem/joints.hpp"
#include "geohaz/dem/packing.hpp"
#include "geohaz/dem/tessellation.hpp"

using namespace geohaz;
using namespace geohaz::dem;

namespace {
PackingSpec small_spec(std::uint64_t seed) {
  PackingSpec p;
  p.width = 0.03;
  p.height = 0.03;
  p.r_min = 0.6e-3;
  p.r_max = 1.66 * 0.6e-3;
  p.porosity = 0.18;
  p.locked_in_stress = 1e5;
  p.seed = seed;
  p.expansion_steps = 2000;
  p.max_relax_steps = 6000;
  return p;
}
const PackedSample& sample(std::uint64_t seed) {
  static std::map<std::uint64_t, PackedSample> cache;
  auto it = cache.find(seed);
  if (it == cache.end())
    it = cache.emplace(seed, pack_discs_in_box(small_spec(seed), LinearSpringCoulomb{1e9, 1e9})).first;
  return it->second;
}
}  // namespace

TEST(DemSample, PackingIsReproducibleAndSeedDependent) {
  const PackedSample& a = sample(1);
  const PackedSample b = pack_discs_in_box(small_spec(1), LinearSpringCoulomb{1e9, 1e9});
  ASSERT_EQ(a.discs.size(), b.discs.size());
  for (std::size_t i = 0; i < a.discs.size(); ++i)
    ASSERT_EQ(a.discs.get<Position<2>>()[i], b.discs.get<Position<2>>()[i]) << i;
  const PackedSample& c = sample(2);
  EXPECT_NE(
      a.discs.size() == c.discs.size() ? (a.discs.get<Position<2>>()[0] - c.discs.get<Position<2>>()[0]).norm() : 1.0,
      0.0);
  // Statistically similar: porosity within 0.02 and coordination within 10 %.
  EXPECT_NEAR(a.porosity, c.porosity, 0.02);
  EXPECT_NEAR(a.coordination, c.coordination, 0.1 * a.coordination);
  // Dense, jammed packing: porosity close to the target, coordination above the isostatic 3 for
  // frictionless discs minus rattlers (≈ 3–4).
  EXPECT_NEAR(a.porosity, 0.18, 0.03);
  EXPECT_GT(a.coordination, 2.8);
  // Locked-in isotropic stress reached (servo tolerance 2 % plus the last-step noise).
  EXPECT_NEAR(a.stress_x, 1e5, 0.1e5);
  EXPECT_NEAR(a.stress_y, 1e5, 0.1e5);
  // Radii respect the bounds.
  for (double r : a.discs.get<Radius>()) {
    EXPECT_GE(r, 0.6e-3 * (1 - 1e-12));
    EXPECT_LE(r, 1.66 * 0.6e-3 * (1 + 1e-12));
  }
}

TEST(DemSample, PowerCellsTileTheContainer) {
  const PackedSample& s = sample(1);
  const auto t = tessellate(s.discs.get<Position<2>>(), s.discs.get<Radius>(), Vec2(0, 0), Vec2(s.width, s.height));
  double sum = 0;
  std::size_t empty = 0;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    sum += t.cell_area[i];
    if (t.cell_area[i] == 0) ++empty;
  }
  EXPECT_NEAR(sum, s.width * s.height, 1e-9 * s.width * s.height);
  EXPECT_EQ(empty, 0u);
  // Mean local porosity weighted by area equals the global porosity (within the overlap volume).
  double solid = 0;
  for (double r : s.discs.get<Radius>()) solid += std::numbers::pi * r * r;
  EXPECT_NEAR(1 - solid / sum, s.porosity, 1e-9);
  // Euler: a triangulation of N points has E = 3N − 3 − h edges; here h = hull points, E ≤ 3N.
  EXPECT_LE(t.edges.size(), 3 * s.discs.size());
  EXPECT_GT(t.edges.size(), 2 * s.discs.size());
}

TEST(DemSample, BondsJoinTessellationNeighboursOnly) {
  const PackedSample& s = sample(1);
  const auto t = tessellate(s.discs.get<Position<2>>(), s.discs.get<Radius>(), Vec2(0, 0), Vec2(s.width, s.height));
  BondTable bonds;
  ParallelBondProperties p;
  p.tensile_strength_std = 1e6;
  const std::size_t n = install_parallel_bonds(s.discs, t.edges, p, 0.1, 7, bonds);
  ASSERT_GT(n, s.discs.size());  // more than one bond per disc in a dense sample
  std::set<std::pair<std::int64_t, std::int64_t>> edges;
  for (auto [a, b] : t.edges) edges.insert({a, b});  // ids equal indices in a fresh sample
  const auto& x = s.discs.get<Position<2>>();
  const auto& R = s.discs.get<Radius>();
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const auto key = std::make_pair(std::min(bonds.id_a[b], bonds.id_b[b]), std::max(bonds.id_a[b], bonds.id_b[b]));
    EXPECT_TRUE(edges.count(key)) << "bond " << b << " is not a triangulation edge";
    const double gap = (x[bonds.id_a[b]] - x[bonds.id_b[b]]).norm() - R[bonds.id_a[b]] - R[bonds.id_b[b]];
    EXPECT_LE(gap, 0.1 * std::min(R[bonds.id_a[b]], R[bonds.id_b[b]]) + 1e-15);
  }
  // Strengths drawn from N(50 MPa, 1 MPa) (the struct's mean): sample mean within 4 standard errors.
  double mean = 0;
  for (double v : bonds.tensile_strength) mean += v / static_cast<double>(bonds.size());
  EXPECT_NEAR(mean, 50e6, 4 * 1e6 / std::sqrt(static_cast<double>(bonds.size())));
}

TEST(DemSample, JointCuttingRemovesExactlyTheBondsCrossingATrace) {
  const PackedSample& s = sample(1);
  const auto t = tessellate(s.discs.get<Position<2>>(), s.discs.get<Radius>(), Vec2(0, 0), Vec2(s.width, s.height));
  BondTable bonds;
  install_parallel_bonds(s.discs, t.edges, ParallelBondProperties{}, 0.1, 7, bonds);
  std::vector<JointTrace> traces =
      generate_joint_traces({JointSet{30.0, 0.01, 1.0, 0.0}}, Vec2(0, 0), Vec2(s.width, s.height), 3);
  traces.push_back({Vec2(0.005, 0.0), Vec2(0.005, 0.015), -1});  // an explicit trace
  ASSERT_GE(traces.size(), 3u);
  DiscontinuityReport rep;
  BondTable cut = bonds;
  const auto pairs = cut_bonds_by_traces(s.discs, cut, traces, &rep, s.width * s.height);
  const auto& x = s.discs.get<Position<2>>();
  std::size_t expected = 0;
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    // Independent crossing test: the two centres lie on opposite sides of a trace line and the
    // crossing point lies within the trace.
    bool crosses = false;
    for (const auto& tr : traces) {
      const Vec2 d = tr.b - tr.a, nrm(-d.y(), d.x());
      const Vec2 p = x[bonds.id_a[b]], q = x[bonds.id_b[b]];
      const double sp = (p - tr.a).dot(nrm), sq = (q - tr.a).dot(nrm);
      if (sp * sq >= 0) continue;
      const Vec2 c = p + (q - p) * (sp / (sp - sq));
      const double u = (c - tr.a).dot(d) / d.squaredNorm();
      if (u > 0 && u < 1) crosses = true;
    }
    expected += crosses;
    EXPECT_EQ(cut.state[b] == BondState::CutByJoint, crosses) << "bond " << b;
  }
  EXPECT_EQ(pairs.size(), expected);
  EXPECT_EQ(rep.bonds_cut, expected);
  EXPECT_GT(expected, 10u);
  // Persistent set with spacing 1 cm over a 3 cm square: P21 ≈ 1/spacing = 100 m⁻¹ (+ the explicit trace).
  EXPECT_NEAR(rep.intensity_p21, 100.0 + 0.015 / (s.width * s.height), 15.0);
  EXPECT_NEAR(rep.set_dip[0], 30.0, 1e-9);
}

TEST(DemSample, JointPersistenceControlsTraceLength) {
  const auto traces = generate_joint_traces({JointSet{0.0, 0.1, 0.5, 0.2}}, Vec2(0, 0), Vec2(10, 10), 5);
  double total = 0;
  for (const auto& t : traces) total += (t.b - t.a).norm();
  // 100 lines of 10 m, half of each jointed: 500 m ± end effects (≤ one trace length per line).
  EXPECT_NEAR(total, 500.0, 25.0);
}
