#pragma once
/// \file infinite_slope.hpp
/// The factor of safety of an infinite slope with pore pressure on a plane parallel to the surface
/// at vertical depth Z (Iverson 2000, eq. 28; TRIGRS, Baum et al. 2008, eq. 2):
///     FS = tan φ′/tan δ + (c′ − ψ γ_w tan φ′) / (γ_s Z sin δ cos δ),
/// with ψ the pressure head on the plane (m), γ_w the unit weight of water and γ_s the depth-averaged
/// unit weight of the soil above the plane. Here γ_s Z is the weight W of the vertical soil column
/// above the plane per unit horizontal area, moist above the water table and saturated below it:
///     W = γ_m (Z − Z_w) + γ_sat Z_w,      Z_w = min(Z, max(0, ψ/β)),
/// where Z_w is the saturated height above the plane that slope-parallel seepage with pressure head
/// ψ on the plane implies (ψ = β Z_w; β = cos²δ without a long-term flux, infiltration.hpp). At the
/// initial state ψ = β (Z − d) this is exactly the water table at depth d. The formula is the
/// limit equilibrium of the slice: normal effective stress σ′ = W cos²δ − ψ γ_w, shear stress
/// τ = W sin δ cos δ, FS = (c′ + σ′ tan φ′)/τ; with W = γ_s Z it is Iverson's form above.
/// Negative ψ (suction above the water table) adds strength only when `suction` is set; otherwise
/// ψ < 0 counts as 0 (TRIGRS's option of the same meaning; the linearised model's suction is not an
/// unsaturated-soil model). The frictional part never goes below zero (c′ alone remains): a pore
/// pressure above the overburden makes no negative friction. Units SI (m, Pa, N/m³, rad).

#include <algorithm>
#include <cmath>

namespace geohaz::sph {

/// Strength and unit weights of the soil cover.
struct InfiniteSlopeSoil {
  double cohesion = 2e3;                                    ///< c′ (Pa)
  double friction = 35.0 * 3.14159265358979323846 / 180.0;  ///< φ′ (rad)
  double unit_weight_moist = 18e3;                          ///< γ_m above the water table (N/m³)
  double unit_weight_saturated = 20e3;                      ///< γ_sat below it (N/m³), ≥ γ_m and > γ_w
  double unit_weight_water = 9810.0;                        ///< γ_w (N/m³)
  bool suction = false;                                     ///< negative pressure heads add strength
};

/// Weight W of the vertical column of depth Z (m) per unit horizontal area (N/m²) with pressure head
/// psi (m) on its base, β as in infiltration.hpp (see the file comment).
inline double infinite_slope_column_weight(double Z, double psi, double beta, const InfiniteSlopeSoil& s) noexcept {
  const double zw = beta > 0.0 ? std::clamp(psi / beta, 0.0, Z) : 0.0;
  return s.unit_weight_moist * (Z - zw) + s.unit_weight_saturated * zw;
}

/// FS of the infinite slope of angle δ (rad, > 0) on the plane at vertical depth Z (m, > 0) with
/// pressure head psi (m) on it; β as in infiltration.hpp (cos²δ without a long-term flux).
inline double infinite_slope_fs(double slope, double Z, double psi, double beta, const InfiniteSlopeSoil& s) noexcept {
  const double sn = std::sin(slope), cs = std::cos(slope);
  const double W = infinite_slope_column_weight(Z, psi, beta, s);
  const double p = (psi < 0.0 && !s.suction) ? 0.0 : psi;
  const double normal = std::max(0.0, W * cs * cs - p * s.unit_weight_water);  // σ′ (Pa)
  return (s.cohesion + normal * std::tan(s.friction)) / (W * sn * cs);
}

}  // namespace geohaz::sph
