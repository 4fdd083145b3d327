#pragma once
/// \file newmark.hpp
/// Newmark's (1965) rigid sliding block: the permanent displacement of a slope's sliding mass under
/// an earthquake, given the yield acceleration a_y = k_y g of its slip surface (limit_equilibrium.hpp,
/// BishopResult::yield_coefficient).
///
/// The mass is a rigid block on a rigid-plastic base that slides one way only, down the slope. With
/// a(t) the body acceleration the earthquake applies to the mass in the direction of sliding (the
/// record's horizontal component times the direction of sliding, in the convention of loading.hpp,
/// where the record is the acceleration applied to every soil particle), the relative velocity v ≥ 0
/// of the block obeys
///     dv/dt = a(t) − a_y   while v > 0 or a(t) > a_y,   v = 0 otherwise,
/// and the displacement is D = ∫ v dt (Newmark 1965; Jibson 2007, eq. 2, as implemented in his
/// rigorous Newmark analysis). a(t) is sampled at a step Δt and taken piecewise linear between samples;
/// v and D are integrated exactly for that piecewise-linear a(t) (trapezoidal velocity, Simpson
/// displacement), and the stop of the block inside a step is found from the quadratic v(t) = 0.
/// Units SI (m, s, m/s²).

#include <vector>

#include "geohaz/sph/loading.hpp"

namespace geohaz::sph {

/// Result of a Newmark analysis.
struct NewmarkResult {
  double displacement = 0.0;    ///< permanent displacement along the slope's sliding direction (m)
  double max_velocity = 0.0;    ///< largest sliding velocity (m/s)
  double sliding_time = 0.0;    ///< total time the block slides (s)
  int episodes = 0;             ///< number of separate sliding episodes
  double final_velocity = 0.0;  ///< sliding velocity at the end of the samples (m/s; 0: at rest)
};

/// Newmark displacement for the driving acceleration a(t) = direction · record.horizontal(t)
/// (direction ±1: the direction of sliding along x) over [0, end_time], sampled every `dt` seconds
/// (the samples of a record are taken at least every dt; pass dt ≤ the record's step). The vertical
/// component is not used (the yield acceleration is that of the static vertical load).
/// yield_acceleration ≥ 0 (m/s²); end_time > 0 (s); dt > 0 (s).
NewmarkResult newmark_displacement(const EarthquakeLoading& record, double yield_acceleration, int direction,
                                   double end_time, double dt);

/// The same for sampled accelerations a_k at t_k = k dt (m/s², already in the direction of sliding).
NewmarkResult newmark_displacement(const std::vector<double>& acceleration, double dt, double yield_acceleration);

}  // namespace geohaz::sph
