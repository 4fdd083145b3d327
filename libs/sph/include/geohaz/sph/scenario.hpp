#pragma once
/// \file scenario.hpp
/// Scenario builders: particles on a square (cubic) lattice of spacing Δx inside a soil region,
/// plus layers of boundary particles (Bui et al. 2008) along the walls.
///
/// Axes: axis 0 is horizontal along the section (x), axis Dim−1 vertical (z, up); in 3D axis 1
/// is the width (y), periodic when requested (SPH-slope paper 2020: "periodic boundary condition was applied
/// across the smaller side"). Every scenario is a *profile domain*: soil between the top of a
/// bottom wall z_b and a piecewise-linear surface z_s(x), between x_left and x_right, with
/// materials assigned by elevation (layers), optional walls at both ends and optional piles.

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "geohaz/core/neighbours.hpp"
#include "geohaz/sph/fields.hpp"

namespace geohaz::sph {

/// A wall's boundary condition ("none" leaves the side free).
enum class WallType { None, Fixed, Roller };

/// A vertical cylindrical pile (3D) of boundary particles.
struct Pile {
  double x = 0.0;         ///< centre along the section (m)
  double y = 0.0;         ///< centre across the width (m), 3D only
  double diameter = 0.1;  ///< m
};

/// The general soil domain all scenarios reduce to.
struct ProfileDomain {
  std::vector<std::array<double, 2>> surface;  ///< (x, z) vertices with non-decreasing x (m); soil below
  double x_left = 0.0, x_right = 1.0;          ///< extent of the soil and the bottom wall (m)
  double z_bottom = 0.0;                       ///< top of the bottom wall (m)
  double width = 0.0;                          ///< 3D width along axis 1 (m)
  bool periodic_width = true;                  ///< 3D: periodic along axis 1, else roller walls
  WallType bottom = WallType::Fixed, left = WallType::Fixed, right = WallType::Fixed;
  double wall_height = 0.0;      ///< height of end walls above z_bottom (0: surface max + 3Δx)
  double floor_extension = 0.0;  ///< bottom wall continues this far beyond x_right (m)
  /// Material by elevation: layer k holds z < layer_tops[k] (ascending); above the last → last material.
  std::vector<double> layer_tops;
  std::vector<int> layer_materials;  ///< size layer_tops.size() + 1 (or empty: all 0)
  /// Optional: material by depth below the surface (for DSM sections): z > z_s(x) − depth → material
  /// `surface_material`, else by elevation.
  double surface_layer_depth = 0.0;
  int surface_material = 0;
  /// Optional (DSM sections): > 0 fills soil only down to this depth below the surface, resting on
  /// fixed boundary particles that follow the surface ("bedrock"), instead of filling down to a flat
  /// z_bottom. A 500 m section through a mountainside then costs its soil cover, not its relief.
  double bedrock_depth = 0.0;
  /// Optional (3D DSM sections): the surface elevation z_s(x, y) across the width, y ∈ [0, width];
  /// replaces `surface` (which then still gives the along-section extent). Requires bedrock_depth
  /// > 0 and non-periodic width: the side walls are roller walls that follow the terrain.
  std::function<double(double, double)> surface_xy;
  std::vector<Pile> piles;
  double pile_top_margin = 0.0;  ///< piles stick out of the surface by this (m)
};

/// A rigid structure made of boundary particles (a wall, a pile, a platen): the solver sums the
/// force the soil exerts on its particles (solver.hpp, structure loads). Its moment is taken about
/// `base`, the point where it meets the ground: the foot of a wall's face, the foot of a pile's
/// axis, the middle of a bottom wall's top face.
template <int Dim>
struct Structure {
  std::string name;                  ///< "bottom", "left_wall", "right_wall", "pile_1", … (unique in a scenario)
  Vec<Dim> base = Vec<Dim>::Zero();  ///< m
  /// Unit normal of the loaded face, pointing from the soil into the structure: the normal force
  /// F·n is positive in compression (a pile: +x, the downslope direction of the section).
  Vec<Dim> normal = Vec<Dim>::Zero();
};

/// Result of a builder: the particles and the numbers a run needs for its diagnostics.
template <int Dim>
struct Scenario {
  SphStore<Dim> store;
  Vec<Dim> domain_lo, domain_hi;  ///< escape box
  Periodicity<Dim> periodic;
  double spacing = 0.0;
  double toe_x = 0.0;             ///< initial front (m) from which run-out is measured
  double base_length = 1.0;       ///< normalisation length of run-out (m)
  double reference_height = 1.0;  ///< height of the soil body above its base (m)
  double base_top = 0.0;          ///< particles initially above this elevation count for the front (m)
  std::size_t soil_count = 0, boundary_count = 0;
  /// The structures; a boundary particle's StructureId indexes this table.
  std::vector<Structure<Dim>> structures;
};

/// Which of a scenario's particles a builder keeps (domain decomposition, docs/sph.md "Domain
/// decomposition"): the particles are numbered 0, 1, … (ParticleId) in the order they are made, and
/// the builder keeps block `part` of `parts` blocks of consecutive ids, [n·part/parts,
/// n·(part+1)/parts) of n, the block DomainDecomposition::scatter keeps of the whole store. With
/// parts > 1 it makes the particles twice (first counting them), storing only its block: a rank's
/// memory scales with its share. `count_only`: keep none (the dry run of validate). `visit`, if
/// set, sees every particle made, kept or not (position, kind), once.
template <int Dim>
struct BuildShare {
  int part = 0, parts = 1;
  bool count_only = false;
  std::function<void(const Vec<Dim>&, Kind)> visit;
};

/// Surface elevation of a profile at x (linear interpolation; first segment wins at a vertical step).
double surface_at(const std::vector<std::array<double, 2>>& surface, double x);

/// Fill a store from a profile domain. densities[k] is ρ0 of material k (for masses).
/// Throws InputError when the domain is empty or inconsistent.
/// `share`: the particles kept (BuildShare); the counts, structures and extents are the whole scenario's.
template <int Dim>
Scenario<Dim> build_profile(const ProfileDomain& dom, double spacing, const std::vector<double>& densities,
                            double h_factor, const BuildShare<Dim>& share = {});

/// Parametric slope (SPH-slope paper 2020, Fig. 3): base of thickness `base_thickness`, crest of length
/// `crest_length` at height `height` above the base, face with gradient `gradient`:1 (H:V), front
/// of length `front_length`. Optional upper cut (SPH-slope paper 2020, Fig. 15): the face is cut back from
/// depth `cut_depth` below the crest at gradient `cut_gradient`:1.
struct SlopeGeometry {
  double height = 0.25, gradient = 1.5, crest_length = 0.3, front_length = 0.6, base_thickness = 0.05;
  double cut_depth = 0.0, cut_gradient = 2.0;
  /// Convert to a profile domain (walls: fixed bottom and ends; materials: base = 0, above by layers).
  ProfileDomain profile() const;
  double toe_x() const { return crest_length + gradient * height; }
  double base_length() const { return crest_length + gradient * height; }
};

/// Biaxial specimen: soil rectangle width × height between a bottom and a top platen (fixed-wall
/// particles), lateral faces free. The platens move towards each other (compression) or apart
/// (tension) at `platen_speed` each (m/s) in the main phase.
struct BiaxialGeometry {
  double width = 0.05, height = 0.1;
};
template <int Dim>
Scenario<Dim> build_biaxial(const BiaxialGeometry& g, double spacing, double density, double h_factor,
                            const BuildShare<Dim>& share = {});

}  // namespace geohaz::sph
