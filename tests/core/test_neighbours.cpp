#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
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
  auto x = make_points<Dim>(1500, layout, 11 + Dim, L);
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
  auto x = make_points<Dim>(1500, layout, 17 + Dim, L);
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

}  // namespace
}  // namespace geohaz
