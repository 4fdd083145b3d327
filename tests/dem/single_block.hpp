#pragma once
// The scene of the single-block studies (test_dem_validation.cpp, SingleBlock*; test_dem_block_support.cpp):
// a 4 m × 4 m block held by a support on a 40° slope 100 m high that runs onto a 1 km flat floor.
#include <cmath>
#include <numbers>

#include "geohaz/dem/experiments.hpp"

namespace geohaz::dem::block_scene {

/// The slope's frame: height of its top above the floor (m), unit vectors downhill along it and
/// normal to it (up).
struct Slope {
  double top;
  Vec2 along, up;
};

/// Terrain, source square (its uphill edge 10 m from the top, 0.2 m above the slope), the support
/// that holds it 0.7 m below its downhill edge, and 0.5 s of settling, written into `a`.
inline Slope place_on_40_degree_slope(AvalancheSpec& a) {
  const double t = std::tan(40 * std::numbers::pi / 180), H0 = 100;
  a.terrain = {Vec2(0, H0), Vec2(H0 / t, 0), Vec2(H0 / t + 1000, 0)};
  const Vec2 o(10, H0 - 10 * t);  // on the slope
  const Vec2 along = Vec2(1, -t).normalized(), up = Vec2(t, 1).normalized();
  const double b = 4.0;
  a.source = {o + 0.2 * up, o + b * along + 0.2 * up, o + b * along + (b + 0.2) * up, o + (b + 0.2) * up};
  const Vec2 s0 = o + b * along + 0.7 * along;
  a.support = {s0 - 2 * up, s0 + (b + 3) * up};
  a.settle_time = 0.5;
  return {H0, along, up};
}

}  // namespace geohaz::dem::block_scene
