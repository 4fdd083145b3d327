#pragma once
/// \file joints.hpp
/// Discontinuities of the rock mass: joint sets (orientation, spacing, persistence) or explicit
/// traces. A trace cuts every intact bond whose centre line it crosses; those pairs become
/// joint contacts (solver.hpp: force along the joint normal, joint friction, no rolling
/// resistance — a smooth-joint-like contact after Mas Ivars et al. 2011).

#include <cstdint>
#include <vector>

#include "geohaz/dem/bonds.hpp"
#include "geohaz/dem/fields.hpp"
#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {

/// A set of parallel joints.
struct JointSet {
  double dip = 45;            ///< angle of the traces from the +x axis, counter-clockwise (degrees)
  double spacing = 1.0;       ///< normal spacing between traces (m)
  double persistence = 1.0;   ///< fraction of each trace line that is jointed, (0, 1]
  double trace_length = 1.0;  ///< length of one joint segment when persistence < 1 (m)
};

struct JointTrace {
  Vec2 a, b;
  int set = -1;  ///< −1 for explicit traces
};

/// Traces of the sets over the box [lo, hi] (random offsets and bridge positions from `seed`).
std::vector<JointTrace> generate_joint_traces(const std::vector<JointSet>& sets, const Vec2& lo, const Vec2& hi,
                                              std::uint64_t seed);

/// Whether the closed segments [a, b] and [c, d] intersect (orientation tests).
bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) noexcept;

/// Summary of the discontinuities, the lecture's "density and orientation of discontinuities".
struct DiscontinuityReport {
  std::size_t traces = 0;
  double total_length = 0;   ///< m
  double intensity_p21 = 0;  ///< trace length per area (m/m²)
  std::size_t bonds_cut = 0;
  std::vector<double> set_dip;  ///< dip of each set (degrees)
  std::vector<std::size_t> set_traces;
  std::vector<double> set_length;  ///< m
};

/// Cut the intact bonds crossed by any trace (state CutByJoint) and return the joint pairs.
std::vector<JointPair> cut_bonds_by_traces(const DiscStore& discs, BondTable& bonds,
                                           const std::vector<JointTrace>& traces, DiscontinuityReport* report = nullptr,
                                           double area = 0.0);

}  // namespace geohaz::dem
