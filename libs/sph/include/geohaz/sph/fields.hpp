#pragma once
/// \file fields.hpp
/// Per-particle fields of the SPH slope model and the particle store that holds them all.
///
/// Every per-particle quantity (physical state and per-step scratch alike) is a field of the one
/// store, so reordering by cell, restart and output can never forget one (STYLE.md §1).
/// Stress is always a 3×3 tensor: in 2D plane strain the out-of-plane normal stress σ_zz is
/// non-zero (ε_zz = 0) and is needed for the invariants I1 and J2 of the yield functions.
/// Sign convention: tension positive (Bui et al. 2010: σ' is negative in compression).

#include <cstdint>

#include "geohaz/core/particles.hpp"
#include "geohaz/core/vec.hpp"

namespace geohaz::sph {

/// What a particle is. Soil particles carry the continuum; the others are boundary particles
/// (Bui et al. 2008) that act in each pair as the soil particle's mirror image (solver_passes.cpp, step 1).
enum class Kind : std::uint8_t {
  Soil = 0,
  FixedWall = 1,   ///< full fixity (no slip): velocity 2 v_wall − v_i, stress σ_i extrapolated along ν
  RollerWall = 2,  ///< free roller (free slip): normal velocity mirrored, shear stress mirrored
  Pile = 3         ///< rigid pile: treated as full fixity
};

/// Kind::Soil as the byte the store's kind array holds (the pair loops compare against it).
inline constexpr std::uint8_t kSoil = static_cast<std::uint8_t>(Kind::Soil);

/// Displacement since the start of the main phase (after geostatic loading), m.
template <int Dim>
struct Displacement {
  using type = Vec<Dim>;
  static constexpr const char* label = "displacement";
  static constexpr const char* unit = "m";
};
/// Cauchy stress (3×3, tension positive), Pa.
struct Stress {
  using type = Mat3;
  static constexpr const char* label = "stress";
  static constexpr const char* unit = "Pa";
};
/// Velocity gradient L = ∂v/∂x (scratch, recomputed each step), 1/s.
template <int Dim>
struct VelocityGradient {
  using type = Mat<Dim>;
  static constexpr const char* label = "velocity_gradient";
  static constexpr const char* unit = "1/s";
};
/// Density from the continuity equation, kg/m³.
struct Density {
  using type = double;
  static constexpr const char* label = "density";
  static constexpr const char* unit = "kg/m^3";
};
/// dρ/dt (scratch), kg/m³/s.
struct DensityRate {
  using type = double;
  static constexpr const char* label = "density_rate";
  static constexpr const char* unit = "kg/m^3/s";
};
/// Material index (soil: into the material table; boundary: the material it was built next to).
struct MaterialId {
  using type = std::int32_t;
  static constexpr const char* label = "material_id";
  static constexpr const char* unit = "1";
};
/// Kind (see enum Kind), stored as uint8.
struct ParticleKind {
  using type = std::uint8_t;
  static constexpr const char* label = "kind";
  static constexpr const char* unit = "1";
};
/// Outward unit normal of the wall a boundary particle belongs to (zero for soil and piles).
template <int Dim>
struct WallNormal {
  using type = Vec<Dim>;
  static constexpr const char* label = "wall_normal";
  static constexpr const char* unit = "1";
};
/// Unit normal of the soil layering next to a fixed boundary particle (zero for soil). The stress a
/// boundary particle carries in a pair is extrapolated from the soil particle assuming it varies
/// along this direction only, as in a layered deposit: vertical for walls under flat-lying soil, the smoothed
/// surface normal for bedrock under a DSM-section cover (see solver_passes.cpp, step 1).
template <int Dim>
struct LayerNormal {
  using type = Vec<Dim>;
  static constexpr const char* label = "layer_normal";
  static constexpr const char* unit = "1";
};
/// Accumulated plastic multiplier Σ Δλ (equals the engineering plastic shear strain for the √J2 potential).
struct PlasticStrain {
  using type = double;
  static constexpr const char* label = "plastic_strain";
  static constexpr const char* unit = "1";
};
/// 1 when the particle is stress-free ("meeting and parting", SWJTU lecture (2010)), else 0.
struct StressFree {
  using type = std::uint8_t;
  static constexpr const char* label = "stress_free";
  static constexpr const char* unit = "1";
};
/// Kernel-summation density Σ_j m_j W_ij (incl. self), used for the stress-vanishing test, kg/m³.
struct SummationDensity {
  using type = double;
  static constexpr const char* label = "summation_density";
  static constexpr const char* unit = "kg/m^3";
};
/// XSPH velocity correction Σ (m_j/ρ_j)(v_j − v_i) W_ij (scratch), m/s.
template <int Dim>
struct XsphCorrection {
  using type = Vec<Dim>;
  static constexpr const char* label = "xsph_correction";
  static constexpr const char* unit = "m/s";
};
/// Gray–Monaghan artificial stress R_i/ρ_i² in the simulation plane (scratch), m²/s².
template <int Dim>
struct ArtificialStress {
  using type = Mat<Dim>;
  static constexpr const char* label = "artificial_stress";
  static constexpr const char* unit = "m^2/s^2";
};

/// Scratch for the pair sums: a soil particle's in-plane stress after its update (Pa); a boundary
/// particle's stress-extrapolation matrix ḡ_n I + ḡ_t ⊗ ν + ν ⊗ ḡ_t (m/s², solver_passes.cpp step 1).
template <int Dim>
struct PairStress {
  using type = Mat<Dim>;
  static constexpr const char* label = "pair_stress";
  static constexpr const char* unit = "Pa (soil), m/s^2 (boundary)";
};
/// Particle volume m/ρ for the pair sums (scratch), m³ (m² in 2D, per unit thickness).
struct Volume {
  using type = double;
  static constexpr const char* label = "volume";
  static constexpr const char* unit = "m^3";
};
/// Index of the structure a boundary particle belongs to, into the scenario's structure table
/// (scenario.hpp `Scenario::structures`: each wall, each pile); the solver sums the pair forces
/// on it per structure (solver.hpp, structure loads). Soil particles carry 0 and are never counted;
/// a store built by hand without it puts every boundary particle in structure 0.
struct StructureId {
  using type = std::int32_t;
  static constexpr const char* label = "structure_id";
  static constexpr const char* unit = "1";
};
/// Position when the neighbour list was last built (Verlet skin bookkeeping), m.
template <int Dim>
struct PositionAtBuild {
  using type = Vec<Dim>;
  static constexpr const char* label = "position_at_build";
  static constexpr const char* unit = "m";
};

/// 1 when a soil particle is clamped (held at rest in place: a clamped region of the scenario,
/// e.g. the built-in end of a cantilever); it still takes part in every pair sum. Else 0.
struct Clamped {
  using type = std::uint8_t;
  static constexpr const char* label = "clamped";
  static constexpr const char* unit = "1";
};

/// A list of field tags: the internal variables a constitutive model evolves (constitutive.hpp).
template <class... Tags>
struct FieldList {};

/// Pore pressure u of a soil particle (prescribed: a phreatic surface, r_u, rain or a water-table
/// raster, pore_pressure.hpp PoreWaterSettings; 0 when dry), Pa, positive in compression of the pore water: the stress
/// field is the effective stress σ′ and the momentum equation takes the total stress σ′ − u I.
struct PorePressure {
  using type = double;
  static constexpr const char* label = "pore_pressure";
  static constexpr const char* unit = "Pa";
};

/// The store of the SPH model.
template <int Dim>
using SphStore =
    ParticleStore<Position<Dim>, Velocity<Dim>, Acceleration<Dim>, Displacement<Dim>, Stress, VelocityGradient<Dim>,
                  Density, DensityRate, Mass, MaterialId, ParticleKind, WallNormal<Dim>, LayerNormal<Dim>,
                  PlasticStrain, StressFree, SummationDensity, XsphCorrection<Dim>, ArtificialStress<Dim>,
                  PairStress<Dim>, Volume, PositionAtBuild<Dim>, StructureId, ParticleId, Clamped, PorePressure>;

/// Boundary particles without a layering normal (stores built by hand, snapshots written before the
/// field existed) take the vertical one, the flat-lying-soil default of the scenario builders.
template <int Dim>
void fill_missing_layer_normals(SphStore<Dim>& s) {
  const auto& kind = s.template get<ParticleKind>();
  auto& nu = s.template get<LayerNormal<Dim>>();
  for (std::size_t i = 0; i < s.size(); ++i)
    if (kind[i] != static_cast<std::uint8_t>(Kind::Soil) && nu[i].squaredNorm() == 0.0) nu[i] = Vec<Dim>::Unit(Dim - 1);
}

}  // namespace geohaz::sph
