#pragma once
/// \file parameters.hpp
/// The parameters of the depth-averaged debris-flow model (RunoutSolver, solver.hpp) and its
/// volume budget.

#include <cstddef>

#include "geohaz/runout/basal_friction.hpp"
#include "geohaz/runout/head_pressure.hpp"
#include "geohaz/runout/processes.hpp"

namespace geohaz::runout {

/// Model parameters (SI units), filled from the config by the app.
struct RunoutParameters {
  double gravity = 9.81;    ///< g (m/s²)
  double density = 1800.0;  ///< ρ of the mixture (kg/m³), for pressures ρv² in the outputs
  double d0 = 5.0;          ///< reference particle spacing (m); kernel h = d0, support 2·d0
  double h0 = 1.0;          ///< reference depth (m): nominal particle volume V0 = h0·d0²
  double cfl = 0.3;         ///< Courant number on d0 (1)
  double dt_max = 1.0;      ///< largest time step (s)
  double dt_min = 1e-7;     ///< a smaller step is a blow-up (s)
  double duration = 600.0;  ///< simulated time (s)
  double min_depth = 0.01;  ///< floor on the bed-normal depth in the friction law (m)
  double smoothing = 0.0;   ///< ε of the velocity correction per step (1), 0 switches it off
  double pressure_scale = HeadPressureForce::consistent_normalisation();  ///< C (1)
  /// C_mix of the lateral-mixing viscosity (1), 0 switches it off. AvaFrame com1DFA's default
  /// subgridMixingFactor, 100; the relaxation vanishes with the velocity differences at the
  /// particle scale, so results converge as d0 shrinks (docs/validation/runout.md).
  double lateral_mixing = 100.0;
  /// Bed curvature in the normal force (friction) and in the bed constraint (acceleration).
  bool curvature = true;
  /// The run ends when the kinetic energy falls below this fraction of its peak (1); 0: never.
  double stop_energy_fraction = 0.01;
  int reorder_every = 25;  ///< sort the store by cell at every this-many-th neighbour rebuild (0: never)
  double skin = 0.0;       ///< neighbour-list skin in units of d0 (list cutoff (2 + skin)·d0)
  BasalFriction friction = ModifiedManningFriction{};
  /// Bed erosion law and coefficients (the erodible layer is a field: SpatialProcesses).
  EntrainmentParameters entrainment;

  double nominal_volume() const noexcept { return h0 * d0 * d0; }
};

/// Volumes (m³) at a moment of the run; initial + injected + entrained = mobile + deposited + lost
/// up to round-off.
struct VolumeBudget {
  double initial = 0.0, mobile = 0.0, deposited = 0.0, lost = 0.0;
  double injected = 0.0;   ///< brought in by inflow hydrographs
  double entrained = 0.0;  ///< eroded from the bed
  std::size_t lost_particles = 0;
  double kinetic_energy = 0.0;       ///< Σ ½ ρ V S² now (J)
  double peak_kinetic_energy = 0.0;  ///< its maximum so far (J)
  /// Everything that has entered the flow.
  double total_in() const noexcept { return initial + injected + entrained; }
  double balance_error() const noexcept { return mobile + deposited + lost - total_in(); }
};

}  // namespace geohaz::runout
