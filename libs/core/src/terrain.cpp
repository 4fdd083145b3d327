/// \file terrain.cpp
/// BilinearGrid construction (the sampler itself is inline in terrain.hpp).

#include "geohaz/core/terrain.hpp"

#include <string>
#include <utility>

#include "geohaz/core/errors.hpp"

namespace geohaz {

BilinearGrid::BilinearGrid(const GridGeometry& g, std::vector<double> values) : g_(g), z_(std::move(values)) {
  // A patch needs 2 × 2 centres; the sampler's last-patch rule (min(⌊u⌋, nx − 2)) relies on it.
  if (g_.nx < 2 || g_.ny < 2)
    throw InputError("a terrain grid needs at least 2 x 2 cells (got " + std::to_string(g_.nx) + " x " +
                     std::to_string(g_.ny) + ")");
  if (!(g_.dx > 0.0) || !(g_.dy > 0.0) || !std::isfinite(g_.dx) || !std::isfinite(g_.dy))
    throw InputError("terrain grid cells must be positive and finite (got " + std::to_string(g_.dx) + " x " +
                     std::to_string(g_.dy) + " m)");
  if (z_.size() != g_.cells())
    throw InputError("terrain grid of " + std::to_string(g_.nx) + " x " + std::to_string(g_.ny) + " cells given " +
                     std::to_string(z_.size()) + " values");
}

}  // namespace geohaz
