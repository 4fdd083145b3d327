// Hazard products of docs/runout.md "Outputs": intensity classes from peak depth, speed and
// pressure, with every class boundary hit (thresholds: strict ">" for depth and speed, "≥" for
// pressure, as the guidelines word them).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "geohaz/runout/hazard_maps.hpp"

using namespace geohaz::runout;

TEST(Intensity, DepthSpeedClassesAtEveryBoundary) {
  IntensityTable t;  // Swiss debris-flow defaults: strong h > 1 m and v > 1 m/s, medium elsewhere reached
  t.min_depth = 0.05;
  const std::vector<double> h = {0.0, 0.05, 0.0500001, 1.0, 1.0000001, 1.0000001, 5.0, 0.2};
  const std::vector<double> v = {3.0, 3.0, 3.0, 3.0, 1.0, 1.0000001, 0.5, 20.0};
  const std::vector<double> expect = {0, 0, 2, 2, 2, 3, 2, 2};
  EXPECT_EQ(intensity_classes(h, v, 2000.0, t), expect);
}

TEST(Intensity, PressureClassesAtEveryBoundary) {
  IntensityTable t;
  t.scheme = IntensityScheme::Pressure;
  t.medium_pressure = 3e3;
  t.strong_pressure = 30e3;
  const double rho = 1200.0;
  // Speeds giving ρv² just below, at and above 3 kPa and 30 kPa (v = √(p/ρ)).
  const auto v_of = [&](double p) { return std::sqrt(p / rho); };
  const std::vector<double> v = {
      v_of(2999.0), v_of(3000.0) * (1 + 1e-12), v_of(29999.0), v_of(30000.0) * (1 + 1e-12), v_of(1e6), 0.0, 10.0};
  const std::vector<double> h = {0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.0};
  const std::vector<double> expect = {1, 2, 2, 3, 3, 1, 0};
  EXPECT_EQ(intensity_classes(h, v, rho, t), expect);
}
