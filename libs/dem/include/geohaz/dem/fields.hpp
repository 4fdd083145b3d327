#pragma once
/// \file fields.hpp
/// Per-disc fields of the bonded-disc DEM and its particle store.
///
/// Discs are cylinders of unit thickness (1 m) in the x–y plane: masses are kg per metre of
/// thickness, forces N/m, moments N·m/m, stresses Pa (force per unit length of a wall). Every
/// per-disc quantity lives in the one store so sorting by cell moves it with the disc.

#include <Eigen/Core>
#include <cstdint>

#include "geohaz/core/particles.hpp"
#include "geohaz/core/vec.hpp"

namespace geohaz::dem {

struct Radius {
  using type = double;
  static constexpr const char* label = "radius";
  static constexpr const char* unit = "m";
};
/// Accumulated rotation angle, counter-clockwise positive.
struct Rotation {
  using type = double;
  static constexpr const char* label = "rotation";
  static constexpr const char* unit = "rad";
};
struct AngularVelocity {
  using type = double;
  static constexpr const char* label = "angular_velocity";
  static constexpr const char* unit = "rad/s";
};
/// Resultant force of the current step (contacts + bonds + walls + gravity, after local damping).
struct Force {
  using type = Vec2;
  static constexpr const char* label = "force";
  static constexpr const char* unit = "N/m";
};
struct Torque {
  using type = double;
  static constexpr const char* label = "torque";
  static constexpr const char* unit = "N*m/m";
};
/// Polar moment of inertia of the disc, ½ m R² (per unit thickness).
struct Inertia {
  using type = double;
  static constexpr const char* label = "inertia";
  static constexpr const char* unit = "kg*m^2/m";
};
/// Number of this disc's parallel bonds that have broken (for crack maps).
struct BrokenBonds {
  using type = std::int32_t;
  static constexpr const char* label = "broken_bonds";
  static constexpr const char* unit = "1";
};
/// Number of intact parallel bonds of this disc.
struct IntactBonds {
  using type = std::int32_t;
  static constexpr const char* label = "intact_bonds";
  static constexpr const char* unit = "1";
};
/// 1: the disc is kinematic (velocity prescribed, e.g. a tension grip), 0: free.
struct Kinematic {
  using type = std::uint8_t;
  static constexpr const char* label = "kinematic";
  static constexpr const char* unit = "1";
};
/// Fragment (cluster of discs still joined by intact bonds) the disc belongs to.
struct Fragment {
  using type = std::int32_t;
  static constexpr const char* label = "fragment";
  static constexpr const char* unit = "1";
};
/// Position when the neighbour list was last built (Verlet-skin check).
struct PositionAtBuild {
  using type = Vec2;
  static constexpr const char* label = "position_at_build";
  static constexpr const char* unit = "m";
};
/// Sum of the translational / rotational stiffnesses acting on the disc in the last step
/// (critical time step, Cundall & Strack 1979: Δt ≤ √(m/k)).
struct StiffnessSum {
  using type = Eigen::Matrix<double, 2, 1>;
  static constexpr const char* label = "stiffness_sum";
  static constexpr const char* unit = "N/m/m | N*m/rad/m";
};

/// Wall-contact history of one disc: up to kWallSlots contacts, each column (segment index or −1,
/// shear force N/m, rolling moment N·m/m). Fixed size, so it lives in the store and survives sorting.
inline constexpr int kWallSlots = 4;
struct WallContacts {
  using type = Eigen::Matrix<double, 3, kWallSlots>;
  static constexpr const char* label = "wall_contacts";
  static constexpr const char* unit = "1 | N/m | N*m/m";
};

/// The DEM particle store.
using DiscStore =
    ParticleStore<Position<2>, Velocity<2>, Force, Rotation, AngularVelocity, Torque, Radius, Mass, Inertia, ParticleId,
                  BrokenBonds, IntactBonds, Kinematic, Fragment, PositionAtBuild, StiffnessSum, WallContacts>;

/// Append a disc of radius r and 2D density rho (kg/m³ × 1 m thickness) at x; returns its index.
/// The id is the store size at the time of the call unless given.
std::size_t add_disc(DiscStore& s, const Vec2& x, double r, double rho, std::int64_t id = -1);

}  // namespace geohaz::dem
