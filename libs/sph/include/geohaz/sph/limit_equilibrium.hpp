#pragma once
/// \file limit_equilibrium.hpp
/// Limit-equilibrium cross-check of a 2D slope section: Bishop's simplified method of slices
/// (Bishop 1955, Géotechnique 5:7–17) on circular slip surfaces, with a search for the circle of the
/// smallest factor of safety. It reads the same profile, layers and strengths as the SPH scenario
/// (scenario.hpp ProfileDomain), so sph-slope can report it beside the strength-reduction factor.
///
/// For a circle of centre (x_c, z_c) and radius R, the sliding mass lies between the circle's lower
/// arc z_a(x) = z_c − √(R² − (x − x_c)²) and the surface z_s(x). It is cut into n vertical slices of
/// width b; slice i has its base mid-point at x_i, weight W_i = b ∫ γ(z) dz over [z_a, z_s] (layers by
/// elevation), base inclination α_i with sin α_i = s (x_c − x_i)/R (s = ±1 so that the mass moves
/// down the slope, i.e. Σ W sin α > 0) and base strength c_i, φ_i of the layer at the base. Moment
/// equilibrium about the centre with the slices' vertical side forces neglected gives, dry soil,
///     F = Σ [c_i b + W_i tan φ_i] / m_α,i  /  Σ W_i sin α_i ,   m_α = cos α + sin α tan φ / F,
/// solved by fixed-point iteration from F = 1. For φ = 0 it is the exact moment balance of the
/// circle (Fellenius), the case of Taylor's (1937) stability chart.
/// The sliding masses of a circle are the stretches between an entry into the surface and the next
/// exit (a toe circle may dip under the ground in front of the toe: it leaves the slope at the toe
/// and the soil it cuts beyond is another mass); the circle's factor is that of its weakest mass.
/// A mass is admissible when its arc stays above the rigid bottom z_bottom, the circle leaves the
/// section through the surface (not through an end of the section or its own vertical side while
/// below the surface), and every
/// slice whose base rises in the direction of sliding (α < 0, near the toe) has m_α ≥ 0.2
/// (Whitman & Bailey 1967: there a small m_α makes Bishop's base normal force unreliably large).
/// Where α > 0, m_α ≥ cos α and a small m_α only means a steep base whose length b/cos α the
/// cohesion term measures correctly (vertical cuts, φ = 0), so no limit applies.
///
/// Pore pressure and seismic coefficients (docs/sph.md, "Pore pressure and seismic coefficients").
/// With a pore pressure u on the slice base (from a phreatic surface, u = γ_w h_w, or from
/// r_u = u / (γ h)), a vertical seismic coefficient k_v (positive upward: the slice carries
/// V = (1 − k_v) W + W_w, W_w the weight of ponded water above it) and a horizontal one k_h (a force
/// k_h W at the slice's centre of gravity z_g, in the direction of sliding), the slice's vertical
/// equilibrium and the moment equilibrium about the centre give
///     F = Σ [c′ b + (V − u b) tan φ′] / m_α  /  Σ [V sin α + k_h W (z_c − z_g)/R] + M_w/R,
/// with b = ℓ cos α (ℓ the slice's arc length) and M_w the moment of the horizontal water thrusts
/// at the ends of any ponded water. The horizontal force enters only the driving moment, so the
/// k_h that makes F = 1 on a given circle (its yield coefficient k_y) is explicit:
///     k_y = (Σ [c′ b + (V − u b) tan φ′] / m_α(F = 1) − Σ V sin α − M_w/R) / Σ W (z_c − z_g)/R.
/// A DSM section (a soil cover of given depth below the surface over a base layer, on bedrock that
/// follows the surface at `bedrock_depth`) is represented too: there a mass is admissible when every
/// slice base stays above the bedrock, and the critical circle is searched by its entry and exit on the
/// surface and its depth (bishop_critical_circle), since a centre grid over a long mountainside
/// section almost never hits a circle that stays inside a cover a few metres thick.
/// Units SI (m, Pa, N/m³, radians).

#include <array>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "geohaz/sph/scenario.hpp"

namespace geohaz::sph {

/// Strength and unit weight of one soil for the limit-equilibrium analysis.
struct LimitEquilibriumSoil {
  double unit_weight = 18e3;  ///< γ, N/m³ (moist: above the phreatic surface)
  double cohesion = 0.0;      ///< c′, Pa
  double friction = 0.5;      ///< φ′, rad
  /// γ_sat below the phreatic surface, N/m³; 0: the same as unit_weight.
  double saturated_unit_weight = 0.0;
  double unit_weight_below_water() const noexcept {
    return saturated_unit_weight > 0.0 ? saturated_unit_weight : unit_weight;
  }
};

/// Pore water of a section: a phreatic surface, or a pore-pressure ratio r_u, or neither (dry).
struct PoreWater {
  /// Phreatic surface (x, z), non-decreasing x (m), held constant beyond its ends; empty: none.
  /// Where it lies above the ground the water is ponded on the slope.
  std::vector<std::array<double, 2>> phreatic;
  /// true: u = γ_w h_w cos²θ (θ the phreatic surface's inclination: straight equipotentials normal
  /// to a straight phreatic line, steady seepage); false: u = γ_w h_w (hydrostatic below the line).
  bool head_loss_correction = false;
  double ru = 0.0;              ///< r_u = u / (γ h) on the slice base, [0, 1); 0 with a phreatic surface
  double unit_weight = 9.81e3;  ///< γ_w, N/m³
  /// A prescribed pore pressure u(x, z) (Pa) on the slice bases (rain infiltration at one time,
  /// pore_pressure.hpp); replaces the phreatic surface's u (which then only sets where the soil
  /// weighs its saturated unit weight) and r_u. Empty: none.
  std::function<double(double, double)> pressure_field;
  bool active() const noexcept { return !phreatic.empty() || ru > 0.0 || pressure_field; }
  /// Elevation of the phreatic surface at x (m); requires a phreatic surface.
  double level_at(double x) const noexcept;
  /// Pore pressure (Pa) at (x, z) from the phreatic surface (0 above it); requires one.
  double pressure_at(double x, double z) const noexcept;
};

/// Pseudo-static seismic coefficients: forces k_h W horizontally in the direction of sliding and
/// k_v W vertically (positive upward) on every slice, W its weight.
struct SeismicCoefficients {
  double kh = 0.0;  ///< horizontal, 1 (fraction of g)
  double kv = 0.0;  ///< vertical, positive upward, 1
};

/// A 2D slope section: the profile domain of the SPH scenario (surface, extent, rigid bottom,
/// layers by elevation) and a soil per material index.
struct SlopeSection {
  std::vector<std::array<double, 2>> surface;  ///< (x, z), non-decreasing x (m)
  double x_left = 0.0, x_right = 1.0;          ///< ends of the section (m)
  double z_bottom = 0.0;                       ///< rigid bottom (m)
  std::vector<double> layer_tops;              ///< as ProfileDomain: layer k holds z < layer_tops[k]
  std::vector<int> layer_materials;            ///< size layer_tops.size() + 1, or empty (all 0)
  std::vector<LimitEquilibriumSoil> soils;     ///< by material index
  PoreWater water;                             ///< pore pressure (default: dry)
  SeismicCoefficients seismic;                 ///< pseudo-static coefficients (default: none)
  /// As ProfileDomain: z > z_s(x) − surface_layer_depth holds `surface_material` (0: no such layer).
  double surface_layer_depth = 0.0;
  int surface_material = 0;
  /// As ProfileDomain: > 0 puts the rigid bottom at z_s(x) − bedrock_depth instead of z_bottom.
  double bedrock_depth = 0.0;

  /// The section of a profile domain. Throws InputError for what it cannot represent (a terrain
  /// across the width) or a material index without a soil.
  static SlopeSection from_profile(const ProfileDomain& d, std::vector<LimitEquilibriumSoil> soils);
  /// Checks what the per-key ranges cannot: r_u in [0, 1) and not with a phreatic surface, the
  /// phreatic surface's x non-decreasing and below the ground somewhere, γ_sat ≥ γ ≥ 0.
  /// Throws InputError naming `key_prefix` + the key ("water.phreatic", "water.ru", ...).
  void validate_water(const std::string& key_prefix = "") const;
  /// Material index at (x, z): the surface layer by depth, else the layers by elevation.
  int material_at(double x, double z) const noexcept;
  /// Elevation of the rigid bottom below x (m).
  double bottom_at(double x) const noexcept;
};

/// A circular slip surface (m).
struct SlipCircle {
  double xc = 0.0, zc = 0.0, radius = 0.0;
};

/// Bishop's factor of one circle and where the sliding mass meets the surface.
struct BishopResult {
  double factor = std::numeric_limits<double>::infinity();  ///< +∞: circle not admissible
  SlipCircle circle;
  double x_entry = 0.0, x_exit = 0.0;  ///< ends of the sliding mass on the surface (m)
  double weight = 0.0;                 ///< weight of the sliding mass per metre (N/m)
  int iterations = 0;                  ///< fixed-point iterations
  /// Yield coefficient of this circle: the k_h (with the section's k_v and water) that makes F = 1;
  /// 0 if F ≤ 1 without it; +∞ if not determined (a toe slice's m_α below the limit at F = 1).
  double yield_coefficient = std::numeric_limits<double>::infinity();
  int direction = 1;  ///< +1: the mass slides towards +x, −1 towards −x
  bool admissible() const noexcept { return factor < std::numeric_limits<double>::infinity(); }
};

/// Bishop's simplified factor of safety of one circle with `slices` slices.
BishopResult bishop_factor(const SlopeSection& s, const SlipCircle& c, int slices = 200);

/// Settings of the critical-circle search: a grid of centres × depths, then a pattern search
/// (step halving) around the best grid circles.
struct BishopSearchSettings {
  int grid = 24;           ///< centres per axis and depths per centre of the grid stage
  int slices = 200;        ///< slices per circle
  int refine_starts = 4;   ///< best grid circles refined by the pattern search
  double min_depth = 0.0;  ///< m: circles whose mass is shallower than this are skipped (0: none)
  /// false: the circle of the smallest factor of safety; true: the circle of the smallest yield
  /// coefficient k_y (the surface a Newmark analysis slides on; it may differ from the former).
  bool minimise_yield_coefficient = false;
};

/// The circle of the smallest Bishop factor. On a flat rigid bottom the grid spans centres over the
/// section's extent from the highest surface point up to the larger of twice the section's height
/// and half its length above it, and circle bottoms (the lowest point of the whole circle, which may
/// lie beyond the mass) from one section height below z_bottom to the highest surface point. On
/// bedrock that follows the surface (bedrock_depth > 0) the circles are given by their entry and
/// exit points on the surface and their sagitta below the chord instead: entries every
/// `bedrock_depth` along the section, chords from 2 to 60 bedrock depths (geometric), sagittas from
/// 0.05 to 1.5 bedrock depths (geometric), `grid` values each. In both cases the best grid circles are
/// refined by a compass search in the grid's own coordinates. Throws InputError if no admissible
/// circle exists (with minimise_yield_coefficient: none with a determined k_y).
BishopResult bishop_critical_circle(const SlopeSection& s, const BishopSearchSettings& settings = {});

/// The translational slide along the base of a section's surface layer (a soil cover on a DSM
/// section): the infinite-slope factor F∞ = c / (γ t sin β cos β) + tan φ / tan β of the surface
/// layer's soil at its vertical depth t (Taylor 1948; Skempton & DeLory 1957), with β the surface
/// inclination over a window of `window` m centred at x, sampled every window/10 along the section.
/// A circle cannot follow the base of a thin cover (its mass is a lens about 2t/3 deep on average), so
/// on such sections Bishop's circle overestimates the factor of the slide the cover would make; this
/// is its bound from below. The window (10 t by default, the length beyond which end effects stay
/// below about 10 %, Griffiths et al. 2011) keeps single DSM steps from posing as slopes.
struct InfiniteSlopeResult {
  double factor = std::numeric_limits<double>::infinity();  ///< +∞: no surface layer or flat ground
  double x = 0.0;                                           ///< where the minimum lies (m)
  double angle = 0.0;                                       ///< surface inclination there (rad)
  double window = 0.0;                                      ///< m
};

/// The smallest infinite-slope factor of the surface layer along the section (window ≤ 0: 10 t).
InfiniteSlopeResult infinite_slope_minimum(const SlopeSection& s, double window = 0.0);

}  // namespace geohaz::sph
