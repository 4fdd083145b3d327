#include <gtest/gtest.h>

#include <cmath>

#include "geohaz/core/kernels.hpp"

namespace geohaz {
namespace {

// Sum of W·ΔV over a fine lattice approximates ∫W dV = 1; the midpoint rule on a lattice of
// spacing h/20 is accurate to ~1e-4 for these C1/C2 kernels.
template <class K, int Dim>
double lattice_integral(double h) {
  const double dx = h / 20.0;
  const int n = static_cast<int>(std::ceil(2.0 * h / dx)) + 1;
  double sum = 0.0;
  if constexpr (Dim == 2) {
    for (int i = -n; i <= n; ++i)
      for (int j = -n; j <= n; ++j) sum += K::value(std::hypot(i * dx, j * dx), h);
    return sum * dx * dx;
  } else {
    for (int i = -n; i <= n; ++i)
      for (int j = -n; j <= n; ++j)
        for (int k = -n; k <= n; ++k) sum += K::value(std::sqrt(double(i * i + j * j + k * k)) * dx, h);
    return sum * dx * dx * dx;
  }
}

template <class K>
class KernelTest : public ::testing::Test {};
using Kernels = ::testing::Types<CubicSpline<2>, CubicSpline<3>, WendlandC2<2>, WendlandC2<3>>;
TYPED_TEST_SUITE(KernelTest, Kernels);

template <class K>
struct DimOf;
template <template <int> class KT, int D>
struct DimOf<KT<D>> : std::integral_constant<int, D> {};

TYPED_TEST(KernelTest, NormalisedOverLattice) {
  constexpr int D = DimOf<TypeParam>::value;
  for (double h : {0.3, 1.0, 2.5}) EXPECT_NEAR((lattice_integral<TypeParam, D>(h)), 1.0, 2e-4) << "h=" << h;
}

TYPED_TEST(KernelTest, CompactSupportAndPositivity) {
  const double h = 0.7;
  EXPECT_EQ(TypeParam::value(2.0 * h, h), 0.0);
  EXPECT_EQ(TypeParam::value(2.5 * h, h), 0.0);
  EXPECT_EQ(TypeParam::derivative(2.0 * h, h), 0.0);
  for (double q = 0.0; q < 2.0; q += 0.01) {
    EXPECT_GT(TypeParam::value(q * h, h), 0.0);
    EXPECT_LE(TypeParam::derivative(q * h, h), 0.0);  // monotonically decreasing
  }
}

TYPED_TEST(KernelTest, DerivativeMatchesFiniteDifference) {
  const double h = 1.3, e = 1e-6;
  for (double q = 0.05; q < 1.99; q += 0.07) {
    const double r = q * h;
    const double fd = (TypeParam::value(r + e, h) - TypeParam::value(r - e, h)) / (2 * e);
    EXPECT_NEAR(TypeParam::derivative(r, h), fd, 1e-6 * TypeParam::value(0.0, h) / h) << "q=" << q;
  }
}

TYPED_TEST(KernelTest, GradientIsOddAndRadial) {
  constexpr int D = DimOf<TypeParam>::value;
  const double h = 0.9;
  Vec<D> x = Vec<D>::LinSpaced(0.3, 0.6);
  const double r = x.norm();
  const Vec<D> g = TypeParam::gradient(x, r, h);
  const Vec<D> gm = TypeParam::gradient(Vec<D>(-x), r, h);
  EXPECT_NEAR((g + gm).norm(), 0.0, 1e-14);
  EXPECT_NEAR(g.normalized().dot(x.normalized()), -1.0, 1e-12);  // points towards the centre
  EXPECT_EQ(TypeParam::gradient(Vec<D>::Zero(), 0.0, h), Vec<D>::Zero());
}

// ∑_j V_j ∇W(x_i − x_j) (x_j − x_i) = I on a regular lattice interior (first-moment consistency);
// a kernel gradient with the wrong scale or sign fails this.
TYPED_TEST(KernelTest, GradientFirstMomentIsIdentityOnLattice) {
  constexpr int D = DimOf<TypeParam>::value;
  const double dx = 0.1, h = 1.5 * dx;
  Mat<D> m = Mat<D>::Zero();
  const int n = 5;
  if constexpr (D == 2) {
    for (int i = -n; i <= n; ++i)
      for (int j = -n; j <= n; ++j) {
        const Vec<D> xij(-i * dx, -j * dx);  // x_i − x_j with x_i at the origin
        const double r = xij.norm();
        if (r == 0) continue;
        m += dx * dx * (-xij) * TypeParam::gradient(xij, r, h).transpose();
      }
  } else {
    for (int i = -n; i <= n; ++i)
      for (int j = -n; j <= n; ++j)
        for (int k = -n; k <= n; ++k) {
          const Vec<D> xij(-i * dx, -j * dx, -k * dx);
          const double r = xij.norm();
          if (r == 0) continue;
          m += dx * dx * dx * (-xij) * TypeParam::gradient(xij, r, h).transpose();
        }
  }
  // Lattice sums at h = 1.5 dx reproduce the identity to about 1 % (measured: cubic spline 0.7 % in 2D,
  // 1.0 % in 3D; Wendland C2 0.3 % and 0.06 %). A gradient of wrong scale or sign is off by O(1).
  EXPECT_NEAR((m - Mat<D>::Identity()).cwiseAbs().maxCoeff(), 0.0, 0.015);
}

TEST(CubicSpline, NormalisationConstantsMatchTheIssueForm) {
  // 10/(7πh²) and 1/(πh³) for the form 1 − 3q²/2 + 3q³/4 equal the W(0) of the source papers' form.
  const double h = 0.5;
  EXPECT_NEAR(CubicSpline<2>::value(0.0, h), 10.0 / (7.0 * std::numbers::pi * h * h), 1e-12);
  EXPECT_NEAR(CubicSpline<3>::value(0.0, h), 1.0 / (std::numbers::pi * h * h * h), 1e-12);
}

}  // namespace
}  // namespace geohaz
