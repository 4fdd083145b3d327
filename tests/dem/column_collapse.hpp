#pragma once
// Test helper shared by the DEM regression and validation tests: the granular column collapse of
// unbonded discs (docs/validation/column_collapse.md), so the small regression case and the
// validation series run the same set-up at two sizes.
//
// Set-up, as in the quasi-2D channel experiments (Lube et al. 2005; Lajeunesse et al. 2005): a
// column of width L0 against a back wall (x = 0) on a flat frictional floor, held by a gate at
// x = L0 while it settles under gravity, then released by removing the gate. a = H0/L0 with H0 the
// settled height. Measured when the deposit is at rest:
//  - L∞, the front of the continuous deposit: walking from the back wall along x, the deposit
//    ends at the first gap wider than one mean disc diameter (the experiments measure the edge of
//    the continuous deposit, not the few grains that roll ahead of it);
//  - the tip (furthest disc) and the 99.5 % quantile of the disc fronts, for comparison;
//  - H∞, the highest disc top of the deposit.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "geohaz/dem/packing.hpp"
#include "geohaz/dem/solver.hpp"

namespace geohaz::dem::testing {

struct ColumnSpec {
  double aspect_ratio = 1.0;  ///< H0/L0 of the packing box (the settled column is slightly lower)
  double width = 0.04;        ///< L0 (m)
  double r_min = 0.8e-3, r_max = 1.2e-3;
  double porosity = 0.2;  ///< porosity of the radius-expansion packing (random dense in 2D)
  double density = 2650;
  double kn = 2e6;  ///< N/m/m: overlap ≈ ρ g H0 d / k_n ≲ 0.2 % of d for H0 ≤ 0.16 m (rigid limit)
  double kn_over_ks = 2.0;
  double friction = 0.5;          ///< disc–disc μ
  double floor_friction = 0.5;    ///< disc–floor and disc–back-wall μ
  double rolling_friction = 0.0;  ///< μ_r (Ai et al. 2011)
  double restitution = 0.3;       ///< disc–disc and disc–wall e
  std::uint64_t seed = 5;
  double settle_time = 0.15;     ///< s of damped settling under gravity behind the gate
  double max_time = 10.0;        ///< s after release, cap
  double release_damping = 0.0;  ///< Cundall α after release: 0 for the collapse, 0.7 for a quasi-static heap
};

struct ColumnResult {
  std::size_t discs = 0;
  double L0 = 0, H0 = 0, a = 0;     ///< settled column (m) and its aspect ratio
  double front = 0;                 ///< L∞, front of the continuous deposit (m from the back wall)
  double tip = 0, quantile995 = 0;  ///< furthest disc front, 99.5 % quantile of the fronts (m)
  double height = 0;                ///< H∞ (m)
  double time = 0;                  ///< s from release to rest
  double runout() const { return (front - L0) / L0; }
};

/// Front of the continuous deposit: discs sorted by their left edge, the deposit ends at the first
/// gap wider than `gap` (m).
inline double continuous_front(const DiscStore& d, double gap) {
  const auto& x = d.get<Position<2>>();
  const auto& R = d.get<Radius>();
  std::vector<std::pair<double, double>> e;
  for (std::size_t i = 0; i < d.size(); ++i) e.emplace_back(x[i].x() - R[i], x[i].x() + R[i]);
  std::sort(e.begin(), e.end());
  double reach = 0;
  for (const auto& [lo, hi] : e) {
    if (lo > reach + gap) break;
    reach = std::max(reach, hi);
  }
  return reach;
}

inline ColumnResult run_column(const ColumnSpec& c, DemSolver& s) {
  s.law = LinearSpringCoulomb{c.kn, c.kn / c.kn_over_ks};
  s.contact.friction = c.friction;
  s.contact.restitution = c.restitution;
  s.contact.rolling_friction = c.rolling_friction;
  PackingSpec pk;
  pk.width = c.width;
  pk.height = c.aspect_ratio * c.width;
  pk.r_min = c.r_min;
  pk.r_max = c.r_max;
  pk.porosity = c.porosity;
  pk.density = c.density;
  pk.locked_in_stress = 0;
  pk.friction_after = c.friction;
  pk.seed = c.seed;
  pk.expansion_steps = 4000;  // the packing this test's stored figures were made with
  pk.max_relax_steps = 20000;
  PackedSample col = pack_discs_in_box(pk, s.law);
  s.discs = col.discs;
  ColumnResult res;
  res.discs = s.discs.size();
  res.L0 = col.width;
  // Floor, back wall and gate (the packing box's bottom, left and right walls, lengthened).
  WallSegment floor;
  floor.a = Vec2(-1, 0);
  floor.b = Vec2(100 * c.width, 0);
  floor.friction = c.floor_friction;
  floor.restitution = c.restitution;
  WallSegment back = floor, gate = floor;
  back.a = Vec2(0, -0.01);
  back.b = Vec2(0, 10 * pk.height);
  gate.a = Vec2(col.width, -0.01);
  gate.b = Vec2(col.width, 10 * pk.height);
  gate.friction = 0;  // a smooth gate: the experiments lift it fast and the grains slide along it
  s.walls = {floor, back, gate};
  // Settle under gravity behind the gate (damped, quasi-static), then release at rest.
  s.settings.local_damping = 0.7;
  s.initialise();
  s.run_until(c.settle_time);
  auto& v = s.discs.get<Velocity<2>>();
  auto& w = s.discs.get<AngularVelocity>();
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    v[i].setZero();
    w[i] = 0;
  }
  const auto& x = s.discs.get<Position<2>>();
  const auto& R = s.discs.get<Radius>();
  for (std::size_t i = 0; i < s.discs.size(); ++i) res.H0 = std::max(res.H0, x[i].y() + R[i]);
  res.a = res.H0 / res.L0;
  s.walls[2].active = false;
  s.settings.local_damping = c.release_damping;  // 0: dynamic flow, dissipation only by the contacts
  s.initialise();
  // Run until at rest: kinetic energy below 1e-6 of the column's potential energy scale m g H0,
  // and the front moved less than 0.1 % of L0 in the last interval.
  double mass = 0;
  for (std::size_t i = 0; i < s.discs.size(); ++i) mass += s.discs.get<Mass>()[i];
  const double scale = mass * 9.81 * res.H0;
  const double t0 = s.time(), dtc = 0.05 * std::sqrt(res.H0 / 9.81) + 0.01;
  const double gap = c.r_min + c.r_max;  // one mean diameter
  double last_front = -1;
  while (s.time() - t0 < c.max_time) {
    s.run_until(s.time() + dtc);
    const double f = continuous_front(s.discs, gap);
    const bool still = std::abs(f - last_front) < 1e-3 * res.L0;
    last_front = f;
    // Kinetic energy of the deposit only: a lone disc rolling ahead (μ_r = 0) never stops.
    double ke = 0;
    const auto& m = s.discs.get<Mass>();
    const auto& I = s.discs.get<Inertia>();
    for (std::size_t i = 0; i < s.discs.size(); ++i)
      if (x[i].x() - R[i] <= f) ke += 0.5 * (m[i] * v[i].squaredNorm() + I[i] * w[i] * w[i]);
    if (s.time() - t0 > 2 * std::sqrt(res.H0 / 9.81) && still && ke < 1e-6 * scale) break;
  }
  res.time = s.time() - t0;
  res.front = continuous_front(s.discs, gap);
  std::vector<double> fronts;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    fronts.push_back(x[i].x() + R[i]);
    if (x[i].x() - R[i] <= res.front) res.height = std::max(res.height, x[i].y() + R[i]);
  }
  std::sort(fronts.begin(), fronts.end());
  res.tip = fronts.back();
  res.quantile995 = fronts[static_cast<std::size_t>(0.995 * static_cast<double>(fronts.size() - 1))];
  return res;
}

/// Angle (degrees) of a heap's free surface falling towards +x: the top of the highest disc in
/// each of `nb` bins of [0, length), fitted by a straight line over bins first..last−1.
inline double surface_angle(const DiscStore& d, double length, int nb, int first, int last) {
  const auto& x = d.get<Position<2>>();
  const auto& R = d.get<Radius>();
  std::vector<double> xs, zs;
  for (int b = first; b < last; ++b) {
    const double x0 = length * b / nb, x1 = length * (b + 1) / nb;
    double top = 0;
    for (std::size_t i = 0; i < d.size(); ++i)
      if (x[i].x() >= x0 && x[i].x() < x1) top = std::max(top, x[i].y() + R[i]);
    xs.push_back(0.5 * (x0 + x1));
    zs.push_back(top);
  }
  double mx = 0, mz = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    mx += xs[k] / static_cast<double>(xs.size());
    mz += zs[k] / static_cast<double>(zs.size());
  }
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    sxy += (xs[k] - mx) * (zs[k] - mz);
    sxx += (xs[k] - mx) * (xs[k] - mx);
  }
  return std::atan(-sxy / sxx) * 180.0 / 3.141592653589793;
}

/// Angle of repose (degrees) of the material of `c`: a column of aspect ratio 1 slumps
/// quasi-statically (local damping 0.7, so inertia plays no part) and the free surface of the heap
/// between 20 % and 80 % of its length is fitted by a straight line.
inline double repose_angle(ColumnSpec c) {
  c.aspect_ratio = 1.0;
  c.release_damping = 0.7;
  DemSolver s;
  const ColumnResult r = run_column(c, s);
  return surface_angle(s.discs, r.front, 10, 2, 8);
}

}  // namespace geohaz::dem::testing
