#pragma once
/// \file fields.hpp
/// Per-particle fields of the depth-averaged debris-flow model. Every per-particle quantity of the
/// model, scratch values included, lives in the one RunoutStore so that reordering, removal and
/// snapshots act on all of them together.
///
/// Particles move in map view (x, y in the DSM's CRS, metres); each carries a fixed volume of
/// mixture (nominally V0 = h0·d0²), so mass is conserved by construction.

#include <cstdint>

#include "geohaz/core/particles.hpp"

namespace geohaz::runout {

/// Volume of mixture carried by the particle (m³); never changes during a run.
struct Volume {
  using type = double;
  static constexpr const char* label = "volume";
  static constexpr const char* unit = "m^3";
};
/// Flow thickness normal to the bed at the particle, h = Σ_j V_j W(r_ij, d0) (m), cubic spline
/// over the 3D distances r_ij = |(x_i − x_j, z_i − z_j)| of particles on the bed (the volume per
/// unit bed area).
struct FlowDepth {
  using type = double;
  static constexpr const char* label = "depth";
  static constexpr const char* unit = "m";
};
/// Speed along the terrain surface, |(v, ∇z·v)| (m/s).
struct Speed {
  using type = double;
  static constexpr const char* label = "speed";
  static constexpr const char* unit = "m/s";
};
/// Terrain elevation under the particle (m).
struct Elevation {
  using type = double;
  static constexpr const char* label = "elevation";
  static constexpr const char* unit = "m";
};
/// Terrain elevation where the particle was released (m), for the fahrböschung.
struct StartElevation {
  using type = double;
  static constexpr const char* label = "start_elevation";
  static constexpr const char* unit = "m";
};
/// Map position where the particle was released (m), for the fahrböschung.
struct StartPosition {
  using type = Vec2;
  static constexpr const char* label = "start_position";
  static constexpr const char* unit = "m";
};
/// Horizontal (map) length of the path travelled so far (m).
struct PathLength {
  using type = double;
  static constexpr const char* label = "path_length";
  static constexpr const char* unit = "m";
};
/// Terrain gradient (∂z/∂x, ∂z/∂y) under the particle (1).
struct SurfaceGradient {
  using type = Vec2;
  static constexpr const char* label = "surface_gradient";
  static constexpr const char* unit = "1";
};
/// Terrain Hessian (∂²z/∂x², ∂²z/∂x∂y, ∂²z/∂y²) under the particle, smoothed at the particle scale
/// (1/m): the bed curvature of the centripetal terms.
struct SurfaceCurvature {
  using type = Vec3;
  static constexpr const char* label = "surface_curvature";
  static constexpr const char* unit = "1/m";
};
/// cos θ of the bed under the particle, 1/√(1 + |∇z|²) (1): the hydrostatic pressure on a slope
/// comes from g cos θ.
struct BedCos {
  using type = double;
  static constexpr const char* label = "bed_cos";
  static constexpr const char* unit = "1";
};
/// Vertical component of the velocity along the bed, ∇z·v (m/s): with the map velocity, the 3D
/// velocity of the particle.
struct VerticalVelocity {
  using type = double;
  static constexpr const char* label = "vertical_velocity";
  static constexpr const char* unit = "m/s";
};
/// Kernel mean of the neighbours' velocities, Σ_j V_j W_ij v_j / h_i, map view (m/s): what the
/// lateral-mixing viscosity relaxes a particle towards (scratch of one step).
struct MeanVelocity {
  using type = Vec2;
  static constexpr const char* label = "mean_velocity";
  static constexpr const char* unit = "m/s";
};
/// Head-pressure acceleration from the neighbours, map view (m/s²): scratch of one step.
struct HeadAcceleration {
  using type = Vec2;
  static constexpr const char* label = "head_acceleration";
  static constexpr const char* unit = "m/s^2";
};
/// Velocity correction of the neighbour smoothing (SWJTU lecture 2010, §2, Monaghan 1994), map view (m/s).
struct VelocityCorrection {
  using type = Vec2;
  static constexpr const char* label = "velocity_correction";
  static constexpr const char* unit = "m/s";
};
/// Position at the last neighbour-list build (m): the list is rebuilt when a particle has moved
/// more than half the skin since.
struct ListPosition {
  using type = Vec2;
  static constexpr const char* label = "list_position";
  static constexpr const char* unit = "m";
};
/// 1 while the particle moves, 0 once friction holds it at rest.
struct Moving {
  using type = std::uint8_t;
  static constexpr const char* label = "moving";
  static constexpr const char* unit = "1";
};
/// 1 when the particle left the terrain (raster edge or nodata) in this step (scratch).
struct Leaving {
  using type = std::uint8_t;
  static constexpr const char* label = "leaving";
  static constexpr const char* unit = "1";
};

/// Memory of the Herschel–Bulkley and Bingham steps (friction/herschel_bulkley.hpp, bingham.hpp),
/// whose root finders start from the particle's last basal state: the excess basal shear stress
/// ζ = τ_b − τ_y of its last moving step (Pa) and the shear rate at the bed there, γ̇_b = (ζ/K)^{1/n}
/// (Bingham: ζ/μ_B; 1/s). Zero (no memory: a cold start) for the other laws, at rest and for new
/// particles.
struct BasalExcessStress {
  using type = double;
  static constexpr const char* label = "basal_excess_stress";
  static constexpr const char* unit = "Pa";
};
struct BasalShearRate {
  using type = double;
  static constexpr const char* label = "basal_shear_rate";
  static constexpr const char* unit = "1/s";
};

/// The particle store of the debris-runout model.
using RunoutStore = ParticleStore<Position<2>, Velocity<2>, ParticleId, Volume, FlowDepth, Speed, Elevation,
                                  StartElevation, StartPosition, PathLength, SurfaceGradient, SurfaceCurvature, BedCos,
                                  VerticalVelocity, MeanVelocity, HeadAcceleration, VelocityCorrection, ListPosition,
                                  Moving, Leaving, BasalExcessStress, BasalShearRate>;

}  // namespace geohaz::runout
