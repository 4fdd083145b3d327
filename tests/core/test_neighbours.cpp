#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "geohaz/core/neighbours.hpp"

namespace geohaz {
namespace {

enum class Layout { Uniform, Clustered };

template <int Dim>
std::vector<Vec<Dim>> make_points(std::size_t n, Layout layout, unsigned seed, double L) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, L);
  std::normal_distribution<double> g(0.0, 0.03 * L);
  std::vector<Vec<Dim>> centres(5);
  for (auto& c : centres)
    for (int d = 0; d < Dim; ++d) c[d] = u(rng);
  std::vector<Vec<Dim>> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (layout == Layout::Uniform) {
      for (int d = 0; d < Dim; ++d) x[i][d] = u(rng);
    } else {
      const auto& c = centres[i % centres.size()];
      for (int d = 0; d < Dim; ++d) x[i][d] = c[d] + g(rng);
    }
  }
  return x;
}

template <int Dim>
std::vector<std::set<std::uint32_t>> brute_force(const std::vector<Vec<Dim>>& x, double rc, const Periodicity<Dim>& p) {
  std::vector<std::set<std::uint32_t>> out(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = 0; j < x.size(); ++j)
      if (i != j && p.min_image(x[i] - x[j]).norm() < rc) out[i].insert(static_cast<std::uint32_t>(j));
  return out;
}

template <int Dim>
void check(Layout layout, bool periodic, int threads) {
  const double L = 1.0, rc = 0.09;
  // 2500 > kParallelMin: the builds fork a team when the test asks for several threads.
  auto x = make_points<Dim>(2500, layout, 11 + Dim, L);
  Periodicity<Dim> p;
  if (periodic) {
    p.axis.fill(false);
    p.axis[0] = true;
    p.axis[Dim - 1] = true;
    p.lo.setZero();
    p.hi.setConstant(L);
    for (auto& xi : x) xi = p.wrap(xi);
  }
  const auto ref = brute_force<Dim>(x, rc, p);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  NeighbourList<Dim> nl;
  nl.build(x, rc, p);
  omp_set_num_threads(saved);
  ASSERT_EQ(nl.size(), x.size());
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto nb = nl.neighbours(i);
    std::set<std::uint32_t> got(nb.begin(), nb.end());
    EXPECT_EQ(got.size(), nb.size()) << "duplicate neighbour of " << i;
    EXPECT_EQ(got, ref[i]) << "particle " << i;
    pairs += ref[i].size();
  }
  EXPECT_EQ(nl.pair_count(), pairs);
  EXPECT_GT(pairs, x.size());  // the test is not vacuous
}

TEST(NeighbourList, Uniform2D) {
  check<2>(Layout::Uniform, false, 1);
}
TEST(NeighbourList, Uniform2DTwoThreads) {
  check<2>(Layout::Uniform, false, 2);
}
TEST(NeighbourList, Clustered2D) {
  check<2>(Layout::Clustered, false, 2);
}
TEST(NeighbourList, Periodic2D) {
  check<2>(Layout::Uniform, true, 2);
}
TEST(NeighbourList, Uniform3D) {
  check<3>(Layout::Uniform, false, 1);
}
TEST(NeighbourList, Clustered3DTwoThreads) {
  check<3>(Layout::Clustered, false, 2);
}
TEST(NeighbourList, Periodic3D) {
  check<3>(Layout::Uniform, true, 2);
}
TEST(NeighbourList, Periodic3DOneThread) {
  check<3>(Layout::Clustered, true, 1);
}

TEST(NeighbourList, HalfListHoldsEachPairOnceFromItsLowerIndex) {
  // The half list (the DEM's contact pass) is the full list's j > i entries, in the same order.
  for (bool periodic : {false, true})
    for (int threads : {1, 2}) {
      auto x = make_points<2>(2500, Layout::Clustered, 7, 1.0);
      Periodicity<2> p;
      if (periodic) {
        p.axis = {true, true};
        p.lo.setZero();
        p.hi.setConstant(1.0);
        for (auto& xi : x) xi = p.wrap(xi);
      }
      const int saved = omp_get_max_threads();
      omp_set_num_threads(threads);
      NeighbourList<2> full, half;
      full.build(x, 0.09, p);
      half.build(x, 0.09, p, true);
      omp_set_num_threads(saved);
      std::size_t kept = 0;
      for (std::size_t i = 0; i < x.size(); ++i) {
        std::vector<std::uint32_t> upper;
        for (std::uint32_t j : full.neighbours(i))
          if (j > i) upper.push_back(j);
        const auto h = half.neighbours(i);
        EXPECT_EQ(std::vector<std::uint32_t>(h.begin(), h.end()), upper) << "particle " << i;
        kept += upper.size();
      }
      EXPECT_EQ(2 * half.pair_count(), full.pair_count());
      EXPECT_EQ(half.pair_count(), kept);
      EXPECT_GT(kept, x.size());  // not vacuous
    }
}

TEST(NeighbourList, ShortPeriodicAxisHasNoDuplicates) {
  // Period 2.5 × cutoff: only two cells fit; the ±1 neighbour cells coincide and must be visited once.
  std::vector<Vec2> x;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) x.emplace_back(0.025 * i + 0.01, 0.1 * j);
  Periodicity<2> p;
  p.axis = {true, false};
  p.lo = Vec2(0, 0);
  p.hi = Vec2(0.25, 1);
  NeighbourList<2> nl;
  nl.build(x, 0.1, p);
  const auto ref = brute_force<2>(x, 0.1, p);
  for (std::size_t i = 0; i < x.size(); ++i) {
    auto nb = nl.neighbours(i);
    EXPECT_EQ(std::set<std::uint32_t>(nb.begin(), nb.end()), ref[i]);
    EXPECT_EQ(nb.size(), ref[i].size());
  }
}

TEST(NeighbourList, PeriodicAxisTooShortIsRejected) {
  std::vector<Vec2> x = {Vec2(0.1, 0.1)};
  Periodicity<2> p;
  p.axis = {true, false};
  p.hi = Vec2(0.15, 1);
  NeighbourList<2> nl;
  EXPECT_THROW(nl.build(x, 0.1, p), std::invalid_argument);
}

TEST(NeighbourList, NonFinitePositionIsNamed) {
  std::vector<Vec2> x = {Vec2(0, 0), Vec2(NAN, 0)};
  NeighbourList<2> nl;
  try {
    nl.build(x, 0.1);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("particle 1"), std::string::npos);
  }
}

TEST(NeighbourList, FarAwayParticleDoesNotBlowUpTheGrid) {
  auto x = make_points<3>(1000, Layout::Uniform, 3, 1.0);
  x.push_back(Vec3(1e7, -1e7, 1e7));
  NeighbourList<3> nl;
  nl.build(x, 0.05);
  EXPECT_LE(nl.cells().cell_count(), 8u * x.size() + 4096u);
  EXPECT_TRUE(nl.neighbours(x.size() - 1).empty());
  const auto ref = brute_force<3>(x, 0.05, {});
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_EQ(nl.neighbours(i).size(), ref[i].size());
}

TEST(NeighbourList, CellOrderIsAPermutationSortedByCell) {
  auto x = make_points<2>(3000, Layout::Uniform, 5, 1.0);
  NeighbourList<2> nl;
  nl.build(x, 0.05);
  auto order = nl.cell_order();
  std::vector<std::uint32_t> v(order.begin(), order.end());
  std::vector<std::uint32_t> sorted = v;
  std::sort(sorted.begin(), sorted.end());
  for (std::uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  auto cell = nl.cells().cell_of();
  for (std::size_t k = 1; k < v.size(); ++k) EXPECT_LE(cell[v[k - 1]], cell[v[k]]);
}

TEST(NeighbourList, PairLoopSeesEveryPairWithMinimumImage) {
  std::vector<Vec2> x = {Vec2(0.01, 0.5), Vec2(0.99, 0.5), Vec2(0.5, 0.5)};
  Periodicity<2> p;
  p.axis = {true, false};
  p.hi = Vec2(1, 1);
  NeighbourList<2> nl;
  nl.build(x, 0.1, p);
  std::vector<double> dx(3, 0.0);
  std::vector<int> count(3, 0);
  nl.for_each_pair(x, [&](std::size_t i, std::size_t, const Vec2& xij, double r) {
    dx[i] = xij.x();
    count[i]++;
    EXPECT_NEAR(r, 0.02, 1e-12);
  });
  EXPECT_EQ(count, (std::vector<int>{1, 1, 0}));
  EXPECT_NEAR(dx[0], 0.02, 1e-12);  // x0 − x1 across the boundary
  EXPECT_NEAR(dx[1], -0.02, 1e-12);
}

// CellPairScan visits, for every i, exactly the neighbours NeighbourList stores, in the same
// order, with the same displacement and r² (so a pair sum over either is bit-identical).
template <int Dim>
void check_scan(Layout layout, bool periodic, int threads) {
  const double L = 1.0, rc = 0.09;
  auto x = make_points<Dim>(2500, layout, 17 + Dim, L);
  Periodicity<Dim> p;
  if (periodic) {
    p.axis.fill(false);
    p.axis[0] = true;
    p.axis[Dim - 1] = true;
    p.lo.setZero();
    p.hi.setConstant(L);
    for (auto& xi : x) xi = p.wrap(xi);
  }
  NeighbourList<Dim> nl;
  nl.build(x, rc, p);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  CellPairScan<Dim> scan;
  scan.build(x, rc, p);
  omp_set_num_threads(saved);
  ASSERT_EQ(scan.size(), x.size());
  const auto order = scan.cell_order();
  const auto list_order = nl.cell_order();
  EXPECT_TRUE(std::equal(order.begin(), order.end(), list_order.begin(), list_order.end()));
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto nb = nl.neighbours(i);
    std::size_t k = 0;
    scan.for_each_neighbour(i, [&](std::size_t j, const Vec<Dim>& xij, double r2) {
      ASSERT_LT(k, nb.size()) << "particle " << i;
      EXPECT_EQ(j, nb[k]) << "particle " << i << ", neighbour " << k;
      const Vec<Dim> d = nl.displacement(x[i], x[j]);
      EXPECT_EQ(xij, d);
      EXPECT_EQ(r2, d.squaredNorm());
      ++k;
    });
    EXPECT_EQ(k, nb.size()) << "particle " << i;
    pairs += k;
  }
  EXPECT_GT(pairs, x.size());  // the test is not vacuous
}

TEST(CellPairScan, SameNeighboursInTheSameOrderAsTheList2D) {
  check_scan<2>(Layout::Uniform, false, 1);
}
TEST(CellPairScan, Clustered2DTwoThreads) {
  check_scan<2>(Layout::Clustered, false, 2);
}
TEST(CellPairScan, Periodic2D) {
  check_scan<2>(Layout::Uniform, true, 2);
}
TEST(CellPairScan, Clustered3D) {
  check_scan<3>(Layout::Clustered, false, 1);
}
TEST(CellPairScan, Periodic3D) {
  check_scan<3>(Layout::Uniform, true, 2);
}

// for_each_forward_neighbour visits every unordered pair of for_each_neighbour exactly once, from
// its lower slot, within forward_reach() slots; a half-pair sum through PairBlocks equals the full
// sum to round-off and is bit-identical on 1 and 3 threads.
template <int Dim>
void check_forward(Layout layout, bool periodic) {
  const double L = 1.0, rc = 0.09;
  auto x = make_points<Dim>(2500, layout, 29 + Dim, L);
  Periodicity<Dim> p;
  if (periodic) {
    p.axis.fill(true);
    p.lo.setZero();
    p.hi.setConstant(L);
    for (auto& xi : x) xi = p.wrap(xi);
  }
  CellPairScan<Dim> scan;
  scan.build(x, rc, p);
  const auto order = scan.cell_order();
  const auto rank = scan.rank();
  std::set<std::pair<std::size_t, std::size_t>> full, half;
  for (std::size_t i = 0; i < x.size(); ++i)
    scan.for_each_neighbour(i, [&](std::size_t j, const Vec<Dim>&, double) {
      full.insert({std::min(i, j), std::max(i, j)});
    });
  std::size_t visits = 0;
  for (std::size_t a = 0; a < x.size(); ++a)
    scan.for_each_forward_neighbour(a, [&](std::size_t s, const Vec<Dim>& xas, double r2) {
      ASSERT_GT(s, a);
      ASSERT_LE(s - a, scan.forward_reach());
      const std::size_t i = order[a], j = order[s];
      EXPECT_EQ(rank[i], a);
      const Vec<Dim> d = p.any() ? p.min_image(x[i] - x[j]) : Vec<Dim>(x[i] - x[j]);
      EXPECT_EQ(xas, d);
      EXPECT_EQ(r2, d.squaredNorm());
      half.insert({std::min(i, j), std::max(i, j)});
      ++visits;
    });
  EXPECT_EQ(visits, half.size());  // no pair twice
  EXPECT_EQ(half, full);
  EXPECT_GT(visits, x.size());

  // Σ_j φ(r_ij) x_j per particle (asymmetric in i, j), by half pairs with block reactions.
  const auto half_sum = [&](int threads) {
    const std::size_t n = x.size();
    const PairBlocks blocks = PairBlocks::choose(n, scan.forward_reach());
    EXPECT_GE(blocks.size, 64u);
    std::vector<double> own(n), buf(blocks.slots()), out(n);
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
#pragma omp parallel for schedule(static)
    for (std::int64_t bb = 0; bb < static_cast<std::int64_t>(blocks.count()); ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      double* mine = blocks.buffer(buf.data(), b);
      std::fill(mine + blocks.first(b), mine + blocks.window_end(b), 0.0);
      for (std::size_t a = blocks.first(b); a < blocks.last(b); ++a) {
        double sum = 0.0;
        scan.for_each_forward_neighbour(a, [&](std::size_t s, const Vec<Dim>&, double r2) {
          const double phi = std::exp(-r2 / (rc * rc));
          sum += phi * x[order[s]][0];
          mine[s] += phi * x[order[a]][0];
        });
        own[a] = sum;
      }
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t bb = 0; bb < static_cast<std::int64_t>(blocks.count()); ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      for (std::size_t a = blocks.first(b); a < blocks.last(b); ++a) {
        double t = own[a];
        for (std::size_t c = blocks.first_block_reaching(b); c <= b; ++c)
          if (a < blocks.window_end(c)) t += buf[c * blocks.reach + a];
        out[order[a]] = t;
      }
    }
    omp_set_num_threads(saved);
    return out;
  };
  const auto one = half_sum(1), three = half_sum(3);
  EXPECT_EQ(one, three);
  for (std::size_t i = 0; i < x.size(); ++i) {
    double ref = 0.0;
    scan.for_each_neighbour(
        i, [&](std::size_t j, const Vec<Dim>&, double r2) { ref += std::exp(-r2 / (rc * rc)) * x[j][0]; });
    EXPECT_NEAR(one[i], ref, 1e-12 * (1.0 + std::abs(ref))) << "particle " << i;
  }
}

TEST(CellPairScan, ForwardPairsOnceWithBlockReactions2D) {
  check_forward<2>(Layout::Uniform, false);
}
TEST(CellPairScan, ForwardPairsClustered2D) {
  check_forward<2>(Layout::Clustered, false);
}
TEST(CellPairScan, ForwardPairsPeriodic2D) {
  check_forward<2>(Layout::Uniform, true);
}
TEST(CellPairScan, ForwardPairsClustered3D) {
  check_forward<3>(Layout::Clustered, false);
}

TEST(CellPairScan, ShortPeriodicAxisAndTooShortAxis) {
  // Period 2.5 × cutoff (the ±1 neighbour cells coincide) and a period below 2 × cutoff (rejected).
  std::vector<Vec2> x;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) x.emplace_back(0.025 * i + 0.01, 0.1 * j);
  Periodicity<2> p;
  p.axis = {true, false};
  p.lo = Vec2(0, 0);
  p.hi = Vec2(0.25, 1);
  CellPairScan<2> scan;
  scan.build(x, 0.1, p);
  const auto ref = brute_force<2>(x, 0.1, p);
  for (std::size_t i = 0; i < x.size(); ++i) {
    std::vector<std::uint32_t> got;
    scan.for_each_neighbour(i,
                            [&](std::size_t j, const Vec2&, double) { got.push_back(static_cast<std::uint32_t>(j)); });
    EXPECT_EQ(std::set<std::uint32_t>(got.begin(), got.end()), ref[i]);
    EXPECT_EQ(got.size(), ref[i].size());
  }
  p.hi = Vec2(0.15, 1);
  EXPECT_THROW(scan.build(x, 0.1, p), std::invalid_argument);
}

// ---- Neighbours: the object the three solvers share ----------------------------------------------

// Rebuild decision: a particle may drift exactly skin/2 without a rebuild (no pair can then have
// closed by more than the skin); one ulp more rebuilds. Particle count changes and invalidate()
// rebuild too.
TEST(Neighbours, RebuildsWhenTheDriftExceedsHalfTheSkin) {
  NeighbourSettings<2> s;
  s.cutoff = 1.0;
  s.skin = 0.5;  // skin/2 = 0.25, exact in binary
  Neighbours<2> nb(s);
  std::vector<Vec2> x = {Vec2(0.0, 0.0), Vec2(1.25, 0.0), Vec2(3.5, 0.0)}, xb(3);
  EXPECT_TRUE(nb.update(x, xb).rebuilt);  // first update
  EXPECT_EQ(xb, x);
  EXPECT_EQ(nb.builds(), 1);
  x[2] = Vec2(3.5 - 0.25, 0.0);  // exactly skin/2
  EXPECT_FALSE(nb.update(x, xb).rebuilt);
  EXPECT_EQ(nb.max_drift(x, xb), 0.25);
  x[2] = Vec2(std::nextafter(3.5 - 0.25, 0.0), 0.0);  // one ulp more
  EXPECT_TRUE(nb.update(x, xb).rebuilt);
  EXPECT_EQ(nb.builds(), 2);
  EXPECT_FALSE(nb.update(x, xb).rebuilt);
  EXPECT_FALSE(nb.update(x, xb, 0.25).rebuilt);  // a drift the caller computed itself
  EXPECT_TRUE(nb.update(x, xb, std::nextafter(0.25, 1.0)).rebuilt);
  nb.invalidate();
  EXPECT_TRUE(nb.update(x, xb).rebuilt);
  x.push_back(Vec2(5.0, 5.0));
  xb.resize(4);
  EXPECT_TRUE(nb.update(x, xb).rebuilt);  // one particle more
  // Skin 0: every update rebuilds; a cell scan needs no reference positions.
  s.skin = 0.0;
  s.storage = PairStorage::scan;
  nb.configure(s);
  EXPECT_TRUE(nb.update(x, {}).rebuilt);
  EXPECT_TRUE(nb.update(x, {}).rebuilt);
  // The pairs within cut-off + skin of a list (0–1 at 1.25 < 1.5 with the skin), none beyond.
  s.skin = 0.5;
  s.storage = PairStorage::list;
  nb.configure(s);
  nb.update(x, xb);
  std::set<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < x.size(); ++i)
    nb.for_each_neighbour(x, i, [&](std::size_t j, const Vec2&, double) { pairs.insert({i, j}); });
  EXPECT_EQ(pairs, (std::set<std::pair<std::size_t, std::size_t>>{{0, 1}, {1, 0}}));
}

TEST(Neighbours, BadSettingsAreRejected) {
  NeighbourSettings<2> s;
  EXPECT_THROW(Neighbours<2>{s}, std::invalid_argument);  // cut-off 0
  s.cutoff = 1.0;
  s.skin = -0.1;
  EXPECT_THROW(Neighbours<2>{s}, std::invalid_argument);
  s.skin = 0.1;
  s.storage = PairStorage::scan;  // a scan keeps no list to reuse
  EXPECT_THROW(Neighbours<2>{s}, std::invalid_argument);
  s.skin = 0.0;
  s.half_list = true;  // nor half of one
  EXPECT_THROW(Neighbours<2>{s}, std::invalid_argument);
  s.half_list = false;
  s.skin = 0.1;
  s.storage = PairStorage::list;
  s.reorder_every = -1;
  EXPECT_THROW(Neighbours<2>{s}, std::invalid_argument);
  s.reorder_every = 0;
  Neighbours<2> nb(s);
  std::vector<Vec2> x(3, Vec2::Zero()), xb(2);
  EXPECT_THROW(nb.update(x, xb), std::invalid_argument);  // x_build of the wrong size with a skin
}

// Reordering every second rebuild: the permutation sorts by cell, the caller applies it to its
// store and to a side table (here particle ids), and the pairs are already those of the new order.
template <int Dim>
void check_reorder(PairStorage storage) {
  const double L = 1.0, rc = 0.09;
  auto x = make_points<Dim>(1500, Layout::Clustered, 41 + Dim, L);
  std::vector<Vec<Dim>> xb(x.size());
  std::vector<int> id(x.size());
  for (std::size_t i = 0; i < id.size(); ++i) id[i] = static_cast<int>(i);
  const auto original = x;
  NeighbourSettings<Dim> s;
  s.cutoff = rc;
  s.skin = storage == PairStorage::list ? 0.01 : 0.0;
  s.reorder_every = 2;
  s.storage = storage;
  Neighbours<Dim> nb(s);
  std::vector<std::int64_t> reordered_at;
  for (int k = 0; k < 5; ++k) {
    nb.invalidate();
    const auto u = nb.update(x, xb);
    ASSERT_TRUE(u.rebuilt);
    if (!u.reordered()) continue;
    reordered_at.push_back(nb.builds());
    const auto apply = [&](auto& v) {
      auto old = v;
      for (std::size_t q = 0; q < v.size(); ++q) v[q] = old[u.permutation[q]];
    };
    apply(x);
    apply(xb);
    apply(id);
    // Sorted by cell, and the cell order of the new positions is the identity.
    CellList<Dim> cells;
    cells.build(x, nb.list_cutoff() / NeighbourList<Dim>::kReach, s.periodic);
    for (std::size_t q = 0; q < x.size(); ++q) ASSERT_EQ(cells.sorted()[q], q);
  }
  EXPECT_EQ(reordered_at, (std::vector<std::int64_t>{1, 3, 5}));  // rebuilds 0, 2 and 4
  EXPECT_EQ(xb, x);                                               // reference positions reordered with the store
  EXPECT_FALSE(s.skin > 0.0 && nb.update(x, xb).rebuilt);
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(x[i], original[static_cast<std::size_t>(id[i])]);
  // The pairs are those of the reordered positions.
  const auto ref = brute_force<Dim>(x, rc, s.periodic);
  for (std::size_t i = 0; i < x.size(); ++i) {
    std::set<std::uint32_t> got;
    nb.for_each_neighbour(x, i, [&](std::size_t j, const Vec<Dim>&, double r2) {
      if (r2 < rc * rc) got.insert(static_cast<std::uint32_t>(j));
    });
    ASSERT_EQ(got, ref[i]) << "particle " << i;
  }
}
TEST(Neighbours, PermutationReordersTheStoreAndASideTableList2D) {
  check_reorder<2>(PairStorage::list);
}
TEST(Neighbours, PermutationReordersTheStoreAndASideTableScan3D) {
  check_reorder<3>(PairStorage::scan);
}

// A restart: restore(x_build, builds) rebuilds the saved pairs without reordering and carries on
// the build count, so an object resumed after five builds reorders at the same rebuild as the one
// that never stopped (0-based rebuilds 0, 3, 6 with reorder_every = 3; builds() = 7 after the last);
// without the count the restored build is rebuild 0 and the next reordering comes three rebuilds
// early.
TEST(Neighbours, RestoreCarriesTheReorderScheduleOn) {
  const auto x = make_points<2>(600, Layout::Clustered, 7, 1.0);
  std::vector<Vec<2>> xb(x.size());
  NeighbourSettings<2> s;
  s.cutoff = 0.09;
  s.skin = 0.01;
  s.reorder_every = 3;
  const auto reorders = [&](Neighbours<2>& nb, int updates) {
    std::vector<std::int64_t> at;
    for (int k = 0; k < updates; ++k) {
      nb.invalidate();
      if (nb.update(x, xb).reordered()) at.push_back(nb.builds());
    }
    return at;
  };
  Neighbours<2> a(s);
  EXPECT_EQ(reorders(a, 8), (std::vector<std::int64_t>{1, 4, 7}));
  Neighbours<2> b(s);
  b.restore(xb, 5);  // the saved run had built five times
  EXPECT_EQ(b.builds(), 5);
  EXPECT_EQ(reorders(b, 3), (std::vector<std::int64_t>{7}));
  Neighbours<2> c(s);
  c.restore(xb);  // no count: the restored build is the first
  EXPECT_EQ(c.builds(), 1);
  EXPECT_EQ(reorders(c, 3), (std::vector<std::int64_t>{4}));
}

// Σ_j φ(r_ij) x_j,0 by half pairs (forward pairs by slot, reactions in the object's blocks,
// gathered by PairBlocks::gather) against the full-pair sum; and 1 vs 3 threads bit-identical,
// with enough particles (4000 > kParallelMin) for the loops to fork.
template <int Dim>
void check_half_sum(bool periodic) {
  const double L = 1.0, rc = Dim == 2 ? 0.06 : 0.12;
  auto x = make_points<Dim>(4000, Layout::Uniform, 53 + Dim, L);
  ASSERT_TRUE(parallel_worth(x.size()));
  NeighbourSettings<Dim> s;
  s.cutoff = rc;
  s.storage = PairStorage::scan;
  if (periodic) {
    s.periodic.axis.fill(true);
    s.periodic.lo.setZero();
    s.periodic.hi.setConstant(L);
    for (auto& xi : x) xi = s.periodic.wrap(xi);
  }
  Neighbours<Dim> nb(s);
  nb.update(x, {});
  const auto phi = [&](double r2) { return std::exp(-r2 / (rc * rc)); };
  const auto half_sum = [&](int threads) {
    const std::size_t n = x.size();
    const PairBlocks& blocks = nb.blocks();
    const auto order = nb.cell_order();
    std::vector<double> own(n), buf(blocks.slots()), out(n);
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
#pragma omp parallel for schedule(static)
    for (std::int64_t bb = 0; bb < static_cast<std::int64_t>(blocks.count()); ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      double* mine = blocks.buffer(buf.data(), b);
      std::fill(mine + blocks.first(b), mine + blocks.window_end(b), 0.0);
      for (std::size_t a = blocks.first(b); a < blocks.last(b); ++a) {
        double sum = 0.0;
        nb.for_each_forward_neighbour(a, [&](std::size_t q, const Vec<Dim>&, double r2) {
          sum += phi(r2) * x[order[q]][0];
          mine[q] += phi(r2) * x[order[a]][0];
        });
        own[a] = sum;
      }
    }
    blocks.gather(
        buf.data(), [](std::size_t) { return true; }, [&](std::size_t a, double r) { own[a] += r; },
        [&](std::size_t a) { out[order[a]] = own[a]; });
    omp_set_num_threads(saved);
    return out;
  };
  const auto one = half_sum(1), three = half_sum(3);
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(one[i], three[i]) << "particle " << i;  // bits
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    double full = 0.0;
    nb.for_each_neighbour(x, i, [&](std::size_t j, const Vec<Dim>&, double r2) {
      full += phi(r2) * x[j][0];
      ++pairs;
    });
    // Same terms, summed in another order: round-off of a sum of ~30 terms of size ≤ 1.
    EXPECT_NEAR(one[i], full, 1e-13 * (1.0 + std::abs(full))) << "particle " << i;
  }
  EXPECT_GT(pairs, 10 * x.size());
}
TEST(Neighbours, HalfPairSumEqualsFullSumAndIsThreadCountIndependent2D) {
  check_half_sum<2>(false);
}
TEST(Neighbours, HalfPairSumEqualsFullSumAndIsThreadCountIndependentPeriodic3D) {
  check_half_sum<3>(true);
}

// Periodic axes: a pair across the boundary is found with its minimum-image displacement, and a
// particle wrapped back into the box has drifted only its true displacement.
TEST(Neighbours, PeriodicPairsUseTheMinimumImage) {
  NeighbourSettings<2> s;
  s.cutoff = 0.2;
  s.skin = 0.1;
  s.periodic.axis = {true, false};
  s.periodic.lo = Vec2(0.0, 0.0);
  s.periodic.hi = Vec2(1.0, 1.0);
  Neighbours<2> nb(s);
  std::vector<Vec2> x = {Vec2(0.05, 0.5), Vec2(0.95, 0.5), Vec2(0.5, 0.5)}, xb(3);
  nb.update(x, xb);
  std::vector<std::pair<std::size_t, Vec2>> seen;
  nb.for_each_neighbour(x, 0, [&](std::size_t j, const Vec2& xij, double r2) {
    seen.push_back({j, xij});
    EXPECT_NEAR(r2, 0.01, 1e-15);
  });
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].first, 1u);
  EXPECT_NEAR(seen[0].second.x(), 0.1, 1e-15);  // x_0 − x_1 through the boundary, not −0.9
  EXPECT_EQ(nb.displacement(x[0], x[1]), seen[0].second);
  // Particle 1 moves 0.08 to the right, through the boundary (0.95 → 1.03, wrapped to 0.03).
  x[1] = s.periodic.wrap(Vec2(0.95 + 0.08, 0.5));
  EXPECT_NEAR(nb.max_drift(x, xb), 0.08, 1e-12);       // 0.95 → 1.03: 0.08 through the boundary
  EXPECT_TRUE(nb.update(x, xb).rebuilt);               // 0.08 > skin/2 = 0.05
  x[1] = s.periodic.wrap(Vec2(x[1].x() + 0.98, 0.5));  // −0.02 through the boundary
  EXPECT_NEAR(nb.max_drift(x, xb), 0.02, 1e-12);
  EXPECT_FALSE(nb.update(x, xb).rebuilt);
}

}  // namespace
}  // namespace geohaz
