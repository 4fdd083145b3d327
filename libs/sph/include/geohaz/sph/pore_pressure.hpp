#pragma once
/// \file pore_pressure.hpp
/// The prescribed pore pressure of the SPH solver (docs/sph.md, "Pore pressure and seismic
/// coefficients"): what `PoreWaterSettings` holds and how each soil particle's u is evaluated from
/// its position x = (x, [y,] z) in every step (solver.hpp, step 3). One source of water at a time:
///   * a phreatic surface z_w(x) (a polyline along axis 0; uniform across a 3D slope's width), clipped
///     to the ground z_g(x) and raised by the history Δz(t):   u = γ_w max(min(z_w(x) + Δz, z_g(x)) − z, 0)
///     (a 2D DSM section takes the cut of its raster, `water.table_raster` or the piezometric level of
///     `water.pore_pressure_raster`, as its phreatic polyline);
///   * on a 3D DSM strip, a water-table surface z_w(x, y) over the strip (the raster sampled on a grid
///     of the strip's local coordinates, StripGrid, bilinear between its nodes) clipped to the ground
///     z_g(x, y) of the same grid: u = γ_w max(min(z_w + Δz, z_g) − z, 0);
///   * a pore-pressure ratio r_u (Bishop & Morgenstern 1960: u = r_u γ h, γ h the vertical
///     overburden stress of the soil column above the point, as Bishop's method takes it on a slice
///     base, limit_equilibrium.hpp):   u = r_u g_f ∫_z^{z_g} ρ(z′) dz′,
///     ρ the density of the layer at each elevation (the slope's layers by elevation; a DSM section's
///     cover by depth over its base), z_g the ground above the point (a 3D strip: its grid's).
///   * rain infiltration (Iverson 2000, infiltration.hpp, as in TRIGRS), column by column: the
///     pressure head ψ(Z, t_r, δ, d) at the vertical depth Z = z_g − z below the ground, δ the
///     inclination of the ground segment above the point (a 3D strip: of the grid cell above it, the
///     magnitude of its mean gradient), d the initial water-table depth (vertical, the table parallel
///     to the ground), t_r the rain's time:   u = γ_w max(ψ, 0)
///     (suction, ψ < 0, is not counted as strength). The rain's clock maps the run's main-phase time
///     t to t_r = clock(t): linear between the given pairs (t_k, t_r,k), held beyond them (the
///     identity when none are given), so that hours of rain load seconds of SPH.
/// γ_w = ρ_w g_f, g_f the gravity of the step (ramped with it in the geostatic phase). u is positive
/// in compression of the pore water; the stress field is the effective stress σ′ (tension positive)
/// and the momentum equation takes the total stress σ = σ′ − u I.
/// Units SI (m, s, kg/m³, Pa).

#include <algorithm>
#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "geohaz/core/vec.hpp"
#include "geohaz/sph/infiltration.hpp"

namespace geohaz::sph {

/// A regular grid over a 3D strip in the strip's local coordinates (x along the section, y across)
/// holding the ground z_g at its nodes: bilinear between the nodes, clamped at the edges. Each cell
/// also has a ground inclination δ: atan of the magnitude of the cell's mean gradient (exact for a
/// plane), the 3D counterpart of a 2D section's segment.
struct StripGrid {
  double x0 = 0.0, y0 = 0.0;   ///< the first node (m)
  double dx = 1.0, dy = 1.0;   ///< node spacing (m)
  int nx = 0, ny = 0;          ///< nodes along x and y (≥ 2 each)
  std::vector<double> ground;  ///< z_g at node (i, j), index j·nx + i (m)
  /// The cell holding (x, y) (clamped to the grid) and the bilinear weights within it.
  struct Locus {
    std::size_t node;  ///< the cell's lower-left node j·nx + i
    std::size_t cell;  ///< the cell's index j·(nx − 1) + i
    double wx, wy;     ///< weights in [0, 1]
  };
  Locus locate(double x, double y) const noexcept;
  /// f bilinear at a locus (f given at the nodes).
  double at(const std::vector<double>& f, const Locus& q) const noexcept;
  /// z_g(x, y) (m).
  double ground_at(double x, double y) const noexcept { return at(ground, locate(x, y)); }
  /// The inclination δ (rad) of cell k (StripGrid::Locus::cell).
  double cell_slope(std::size_t k) const noexcept;
};

/// The soil column above a point of a section: ∫_z^{z_g} ρ dz (kg/m²), ρ piecewise constant by
/// elevation (layer k holds z < tops[k], as ProfileDomain; above the last top the last density) below
/// an optional cover of vertical depth `surface_layer_depth` under the ground (a DSM section's soil
/// layer, as ProfileDomain::surface_layer_depth) that has `surface_density`. The ground: a polyline
/// along axis 0, or (a 3D DSM strip) `grid`.
struct OverburdenProfile {
  std::vector<std::array<double, 2>> ground;  ///< (x, z) of the ground surface, x non-decreasing (m)
  std::vector<double> tops;                   ///< layer tops, ascending (m); empty: one density
  std::vector<double> densities;              ///< kg/m³, tops.size() + 1 values
  double surface_layer_depth = 0.0;           ///< m; 0: no cover layer
  double surface_density = 0.0;               ///< kg/m³ of the cover layer
  std::shared_ptr<const StripGrid> grid;      ///< 3D strip: the ground over it; null: `ground`
  /// ∫_z^{z_g(x)} ρ dz (kg/m²); 0 at or above the ground.
  double mass_above(double x, double z) const noexcept;
  /// The same under the grid's ground z_g(x, y) (requires `grid`).
  double mass_above(double x, double y, double z) const noexcept;

 private:
  double column(double zg, double z) const noexcept;
};

/// The pore pressure of rain infiltration on a section (see the file comment): column by column
/// under a ground polyline along axis 0 (a 2D section, a 3D slope uniform across), or under the
/// ground of a 3D strip's grid, δ then the inclination of the grid cell above the point.
class RainPorePressure {
 public:
  /// `ground`: (x, z) of the ground surface, x non-decreasing (m); `water_table_depth` d ≥ 0 (m);
  /// `clock`: (t, t_r) pairs, t increasing, t_r non-decreasing (s), or empty for t_r = t.
  RainPorePressure(const InfiltrationParameters& p, const RainfallHistory& rain,
                   std::vector<std::array<double, 2>> ground, double water_table_depth,
                   std::vector<std::array<double, 2>> clock);
  /// The same under a 3D strip's ground grid (`grid` not null).
  RainPorePressure(const InfiltrationParameters& p, const RainfallHistory& rain, std::shared_ptr<const StripGrid> grid,
                   double water_table_depth, std::vector<std::array<double, 2>> clock);
  const InfiltrationHistory& history() const noexcept { return history_; }
  const RainfallHistory& rain() const noexcept { return rain_; }
  const std::vector<std::array<double, 2>>& ground() const noexcept { return ground_; }
  const std::vector<std::array<double, 2>>& clock() const noexcept { return clock_; }
  double water_table_depth() const noexcept { return d_; }
  /// The 3D strip's grid, or null (a ground polyline).
  const std::shared_ptr<const StripGrid>& grid() const noexcept { return grid_; }
  /// The smallest β = cos²δ − I_ZLT/K_s over the ground's segments (or cells).
  double smallest_beta() const noexcept;
  /// t_r = clock(t) (s).
  double rain_time(double t) const noexcept;
  /// Inclination δ (rad) of the ground segment above x (0 beyond the ends, where the ground is level).
  double slope_at(double x) const noexcept;
  /// ψ (m) at (x, z) at rain time t_r: InfiltrationHistory::pressure_head(Z, t_r, δ(x), d),
  /// Z = z_g(x) − z; −∞ at or above the ground (no water there).
  double head(double x, double z, double t_rain) const noexcept;
  /// ψ (m) at (x, y, z) under the grid's ground (requires grid()): Z = z_g(x, y) − z, δ of the cell.
  double head(double x, double y, double z, double t_rain) const noexcept;
  /// The elevation of the initial water table at x, z_g(x) − d (m).
  double initial_level(double x) const noexcept;
  /// The same under the grid's ground, z_g(x, y) − d (requires grid()).
  double initial_level(double x, double y) const noexcept;

 private:
  InfiltrationHistory history_;
  RainfallHistory rain_;
  std::vector<std::array<double, 2>> ground_, clock_;
  std::shared_ptr<const StripGrid> grid_;
  double d_ = 0.0;
  struct Segment {
    double beta, dhat;  // β = cos²δ − I_ZLT/K_s, D̂ = 4 D₀/cos²δ
  };
  // Polyline: segment k between ground_[k − 1] and ground_[k]; 0 before the first vertex, the last
  // beyond the last vertex. Grid: one per cell.
  std::vector<Segment> segment_;
  std::size_t segment_of(double x) const noexcept;
  Segment segment(double delta) const noexcept;
  double head_in(const Segment& s, double Z, double t_rain) const noexcept;
};

/// A water table over a 3D strip: z_w and the ground z_g on the strip's grid (StripGrid).
struct WaterTableGrid : StripGrid {
  std::vector<double> table;  ///< z_w at node (i, j), index j·nx + i (m)
  /// min(z_w(x, y) + dz, z_g(x, y)) (m).
  double level(double x, double y, double dz) const noexcept;
};

/// Prescribed pore water (see the file comment): a phreatic surface (along axis 0; uniform across a
/// 3D width), or r_u with the overburden profile. Default: dry.
struct PoreWaterSettings {
  std::vector<std::array<double, 2>> phreatic;   ///< (x, z) at the start, x non-decreasing (m); empty: none
  std::vector<std::array<double, 2>> ground;     ///< (x, z) ground surface the table is clipped to (m); empty: none
  double density = 1000.0;                       ///< ρ_w, kg/m³
  std::vector<double> history_times;             ///< s (main-phase time), increasing; empty: no rise
  std::vector<double> history_offsets;           ///< m: Δz at those times
  double ru = 0.0;                               ///< r_u in [0, 1); > 0: u = r_u σ_v (no phreatic surface)
  OverburdenProfile overburden;                  ///< the soil column of r_u
  std::shared_ptr<const RainPorePressure> rain;  ///< rain infiltration (no phreatic surface, no r_u); null: none
  std::shared_ptr<const WaterTableGrid> table;   ///< 3D DSM strip: the table over the strip; null: none
  bool active() const noexcept { return !phreatic.empty() || ru > 0.0 || rain || table; }
  /// Δz(t) (m).
  double offset(double t) const noexcept;
  /// Elevation of the (clipped) water table at x with offset dz (m).
  double level(double x, double dz) const noexcept;
};

/// The pore water of one step: the settings at main-phase time t (0 in the geostatic phase) and
/// gravity g·factor, evaluated per particle by pressure().
struct PoreWaterStep {
  const PoreWaterSettings* pw = nullptr;
  double dz = 0.0;       ///< Δz(t) of the phreatic surface (m)
  double gamma_w = 0.0;  ///< ρ_w g_f (N/m³)
  double g = 0.0;        ///< g_f (m/s²)
  double t_rain = 0.0;   ///< the rain's time t_r = clock(t) (s)

  PoreWaterStep() = default;
  PoreWaterStep(const PoreWaterSettings& s, double t, double gravity, double factor) noexcept
      : pw(&s),
        dz(s.offset(t)),
        gamma_w(s.density * gravity * factor),
        g(gravity * factor),
        t_rain(s.rain ? s.rain->rain_time(t) : 0.0) {}

  /// u (Pa) at position x (axis 0 along the section, axis Dim − 1 up).
  template <int Dim>
  double pressure(const Vec<Dim>& x) const noexcept {
    if constexpr (Dim == 3) {  // a 3D DSM strip: the ground of its grid
      if (pw->ru > 0.0 && pw->overburden.grid) return pw->ru * g * pw->overburden.mass_above(x[0], x[1], x[2]);
      if (pw->rain && pw->rain->grid()) return gamma_w * std::max(pw->rain->head(x[0], x[1], x[2], t_rain), 0.0);
      if (pw->table) return gamma_w * std::max(pw->table->level(x[0], x[1], dz) - x[2], 0.0);
    }
    if (pw->ru > 0.0) return pw->ru * g * pw->overburden.mass_above(x[0], x[Dim - 1]);
    if (pw->rain) return gamma_w * std::max(pw->rain->head(x[0], x[Dim - 1], t_rain), 0.0);
    return gamma_w * std::max(pw->level(x[0], dz) - x[Dim - 1], 0.0);
  }
};

}  // namespace geohaz::sph
