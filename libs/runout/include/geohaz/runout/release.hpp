#pragma once
/// \file release.hpp
/// Turning a release (thickness on the DSM grid) into particles.
///
/// Seeding (volume-exact): the DSM grid is cut into blocks of about d0 × d0 (kx = max(1, round(d0/dx))
/// cells across); the release volume V_b of a block (Σ thickness·cell area over its cells) goes to
/// N_b = max(1, round(V_b / V0)) particles of volume V_b / N_b each, V0 = h0·d0². The particles sit
/// on a regular sub-lattice over the bounding box of the block's release cells, so a release of
/// thickness h is seeded at spacing ≈ d0·√(h0/h) (SWJTU lecture 2010, §3) and the volume seeded equals the
/// volume given, block by block, to round-off. Particle volumes therefore differ slightly from V0;
/// the head-pressure force and the depth both weight neighbours by their actual volume.

#include <cstddef>
#include <vector>

#include "geohaz/runout/fields.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {

/// What seeding produced.
struct SeedReport {
  std::size_t particles = 0;
  double volume_given = 0.0;   ///< Σ thickness·cell area (m³)
  double volume_seeded = 0.0;  ///< Σ particle volumes (m³)
};

/// Append particles for `thickness` (m per cell of `grid`; ≤ 0 or NaN: no release) to `store`
/// (velocity zero, ids continuing from the store's size). d0, h0 in metres.
SeedReport seed_release(const GridGeometry& grid, const std::vector<double>& thickness, double d0, double h0,
                        RunoutStore& store);

/// Bin point volumes (m³) into the cells of `grid` as a thickness (m). Returns the index of the
/// first point outside the grid in `outside` (or SIZE_MAX when all are inside).
std::vector<double> bin_point_volumes(const GridGeometry& grid, const std::vector<Vec2>& points,
                                      const std::vector<double>& volumes, std::size_t& outside);

}  // namespace geohaz::runout
