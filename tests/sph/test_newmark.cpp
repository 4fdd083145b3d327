// Unit tests of Newmark's rigid sliding block (newmark.hpp) against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "geohaz/sph/loading.hpp"
#include "geohaz/sph/newmark.hpp"

namespace geohaz::sph {
namespace {

// A rectangular pulse of acceleration A for a time T on a block of yield acceleration a_y < A: the
// block gains (A − a_y) T, then decelerates at a_y; D = (A − a_y) T²/2 + ((A − a_y) T)²/(2 a_y)
// = A (A − a_y) T² / (2 a_y) (Newmark 1965, eq. 7 with N = a_y/g, A = a/g). 1 % as the issue asks.
TEST(Newmark, RectangularPulseMatchesTheClosedForm) {
  const double A = 3.0, T = 0.5, ay = 1.0;
  const double closed = A * (A - ay) * T * T / (2.0 * ay);  // 0.75 m
  // As samples (exact edges: the pulse from sample 1000 to 1500 at dt = 1 ms).
  const double dt = 1e-3;
  std::vector<double> a(5000, 0.0);
  for (std::size_t k = 1000; k <= 1500; ++k) a[k] = A;
  // The piecewise-linear reading ramps the edges over one step each: the impulse is A T exactly,
  // delivered dt/2 later on average; the closed form for the same impulse holds to O(dt/T).
  const auto r = newmark_displacement(a, dt, ay);
  EXPECT_NEAR(r.displacement, closed, 0.01 * closed);
  EXPECT_NEAR(r.max_velocity, (A - ay) * T, 0.01 * (A - ay) * T);
  EXPECT_NEAR(r.sliding_time, T * A / ay, 0.01 * T * A / ay);  // slides until v = 0 at t = A T / a_y
  EXPECT_EQ(r.episodes, 1);
  // As an accelerogram in the record format sph-slope reads (near-vertical edges).
  const auto rec =
      EarthquakeLoading::record({0.0, 1.0, 1.0 + 1e-9, 1.0 + T, 1.0 + T + 1e-9, 5.0}, {0.0, 0.0, A, A, 0.0, 0.0}, {});
  const auto q = newmark_displacement(rec, ay, 1, 5.0, 1e-4);
  EXPECT_NEAR(q.displacement, closed, 0.01 * closed);
  // The other way the block does not slide: the pulse pushes it up the slope.
  EXPECT_EQ(newmark_displacement(rec, ay, -1, 5.0, 1e-4).displacement, 0.0);
}

// A sine a(t) = A sin ωt, A > a_y: each cycle the block starts at t1 = asin(a_y/A)/ω with v = 0,
// v(t) = (A/ω)(cos ωt1 − cos ωt) − a_y (t − t1) until v(t2) = 0, and
// D = (A/ω) cos ωt1 (t2 − t1) − (A/ω²)(sin ωt2 − sin ωt1) − a_y (t2 − t1)²/2 per cycle (the integral
// of v; t2 found here by bisection). It stops before the next cycle starts, so n cycles give n D.
TEST(Newmark, SineMatchesTheClosedFormPerCycle) {
  const double A = 3.0, f = 1.0, ay = 1.0, w = 2.0 * std::numbers::pi * f;
  const double t1 = std::asin(ay / A) / w;
  auto v = [&](double t) { return (A / w) * (std::cos(w * t1) - std::cos(w * t)) - ay * (t - t1); };
  double lo = t1 + 0.25 / f, hi = t1 + 1.0 / f;  // v > 0 at lo (past the peak of the pulse), < 0 at hi
  ASSERT_GT(v(lo), 0.0);
  ASSERT_LT(v(hi), 0.0);
  for (int it = 0; it < 200; ++it) (v(0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
  const double t2 = 0.5 * (lo + hi), s = t2 - t1;
  ASSERT_LT(t2, 1.0 / f);  // stopped within the cycle, before the next one starts
  const double per_cycle =
      (A / w) * std::cos(w * t1) * s - (A / (w * w)) * (std::sin(w * t2) - std::sin(w * t1)) - 0.5 * ay * s * s;
  const int cycles = 3;
  const auto quake = EarthquakeLoading::sine(A, f, 0.0, cycles / f, 0.0);
  const auto r = newmark_displacement(quake, ay, 1, cycles / f + 2.0, 1e-3);
  EXPECT_NEAR(r.displacement, cycles * per_cycle, 0.01 * cycles * per_cycle);
  EXPECT_EQ(r.episodes, cycles);
  EXPECT_NEAR(r.sliding_time, cycles * s, 0.01 * cycles * s);
  // Sliding the other way: on the negative half-cycles, the same displacement for a symmetric sine
  // when each is followed by a positive half-cycle (another half-cycle of record).
  const auto longer = EarthquakeLoading::sine(A, f, 0.0, (cycles + 0.5) / f, 0.0);
  const auto m = newmark_displacement(longer, ay, -1, cycles / f + 2.0, 1e-3);
  EXPECT_NEAR(m.displacement, r.displacement, 0.01 * r.displacement);
}

// Below the yield acceleration the block never moves; with a_y = 0 and a constant push it slides
// as a free body, D = a t²/2.
TEST(Newmark, NoSlidingBelowYieldAndFreeSlidingWithoutStrength) {
  const auto quake = EarthquakeLoading::sine(2.0, 1.0, 0.0, 3.0, 0.0);
  EXPECT_EQ(newmark_displacement(quake, 2.0, 1, 4.0, 1e-3).displacement, 0.0);
  const std::vector<double> a(1001, 0.5);  // 1 s at 1 ms
  EXPECT_NEAR(newmark_displacement(a, 1e-3, 0.0).displacement, 0.25, 1e-12);
}

}  // namespace
}  // namespace geohaz::sph
