#pragma once
/// \file obrien_julien.hpp
/// The quadratic rheology of O'Brien & Julien (1985) and O'Brien, Julien & Fullerton (1993) in the
/// depth-integrated form of FLO-2D (FLO-2D reference manual, "Sediment concentration and
/// rheology"): the friction slope of a mudflow is the sum of a yield, a viscous and a
/// turbulent-dispersive slope,
///
///     S_f = τ_y/(ρ g h) + K η U/(8 ρ g h²) + n_td² U²/h^{4/3},
///
/// τ_y the yield stress (Pa), η the Bingham viscosity (Pa·s), K the laminar resistance parameter
/// (24 for laminar sheet flow on a smooth plane, up to ~5·10⁴ on rough vegetated ground), n_td the
/// turbulent-dispersive Manning coefficient (s/m^{1/3}). τ_b = ρ g h S_f, so with h = h_n
///
///     a = g S_f = τ_y/(ρ h_n) + (K η/(8 ρ h_n²)) s + (g n_td²/h_n^{4/3}) s²:
///
/// rest, visc and drag of the closed-form implicit step, computed from y = h_n^{−1/3}
/// (inverse_cbrt, Newton's iteration without a division; 1/h_n = y³) and 1/ρ: one division and no
/// libm call per particle. With K = 24 the viscous term is the
/// Newtonian laminar film (U = ρ g h² S/(3η)). Steady uniform flow on slope θ: the positive root
/// of drag s² + visc s + rest − g sin θ = 0 (at rest while g sin θ ≤ τ_y/(ρ h_n)).
/// The optional parameterisation by the volumetric sediment concentration C_v (O'Brien & Julien
/// 1988), τ_y = α₂ exp(β₂ C_v), η = α₁ exp(β₁ C_v), is resolved by the config reader.

#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>

#include "geohaz/runout/friction/friction_terms.hpp"

namespace geohaz::runout {

struct OBrienJulienFriction {
  /// The yield stress and viscosity given directly, or (cv > 0) from the sediment concentration;
  /// the defaults of α, β: Aspen Pit 1 of O'Brien & Julien (1988), 0.181 dyn/cm² and 0.036 P in SI.
  static constexpr std::array<ParamSpec, 9> parameters{
      {kYieldStressParameter,
       kBinghamViscosityParameter,
       {"laminar_k", 24.0, Range::closed(1.0, 1e5), "1", "laminar resistance K of the viscous slope Kη U/(8ρ g h²)",
        "24 smooth plane"},
       kManningNParameter,
       {"cv", 0.0, Range::closed(0.0, 0.65), "1", "volumetric sediment concentration C_v",
        "τ_y = yield_alpha·exp(yield_beta·C_v), η = viscosity_alpha·exp(viscosity_beta·C_v), O'Brien & Julien 1988; "
        "0: model.tau_y and model.viscosity"},
       {"yield_alpha", 0.0181, Range::open_closed(0.0, 1e6), "Pa", "α₂ of τ_y = α₂ exp(β₂ C_v)", "with model.cv"},
       {"yield_beta", 25.7, Range::closed(0.0, 100.0), "1", "β₂ of τ_y = α₂ exp(β₂ C_v)", "with model.cv"},
       {"viscosity_alpha", 0.0036, Range::open_closed(0.0, 1e6), "Pa*s", "α₁ of η = α₁ exp(β₁ C_v)", "with model.cv"},
       {"viscosity_beta", 22.1, Range::closed(0.0, 100.0), "1", "β₁ of η = α₁ exp(β₁ C_v)", "with model.cv"}}};
  double tau_y = kYieldStressParameter.def;           ///< yield stress τ_y (Pa)
  double viscosity = kBinghamViscosityParameter.def;  ///< Bingham viscosity η (Pa·s)
  double laminar_k = parameters[2].def;               ///< laminar resistance parameter K (1)
  double n_td = kManningNParameter.def;               ///< turbulent-dispersive Manning coefficient (s/m^{1/3})
  static constexpr const char* name = "obrien_julien";
  static constexpr const char* summary =
      "O'Brien-Julien quadratic, yield + viscous + turbulent (tau_y, viscosity, laminar_k, n; or cv; FLO-2D)";
  /// One coefficient (a friction zone's): τ_y, η, K or n_td; the concentration group only as a whole.
  bool set(std::size_t j, double v) noexcept {
    if (j > 3) return false;
    return (j == 0 ? tau_y : j == 1 ? viscosity : j == 2 ? laminar_k : n_td) = v, true;
  }
  static OBrienJulienFriction from_parameters(const ParamValues& v) {
    const double cv = v["cv"];
    if (cv > 0.0)
      return {v["yield_alpha"] * std::exp(v["yield_beta"] * cv),
              v["viscosity_alpha"] * std::exp(v["viscosity_beta"] * cv), v["laminar_k"], v["n"]};
    return {v["tau_y"], v["viscosity"], v["laminar_k"], v["n"]};
  }
  /// With a concentration, τ_y and η come from it: giving them as well is a contradiction.
  static std::optional<ParamProblem> check(const ParamValues& v) {
    if (v["cv"] > 0.0)
      for (const char* k : {"tau_y", "viscosity"})
        if (v.is_given(k))
          return ParamProblem{k,
                              "model." + std::string(k) +
                                  " and model.cv both set: with model.cv the yield stress and viscosity come "
                                  "from the concentration (give one or the other)",
                              ""};
    return std::nullopt;
  }
  /// Without cbrt and with one division (1/ρ): y = h_n^{−1/3} (inverse_cbrt), 1/h_n = y³,
  /// 1/h_n² = y⁶, 1/h_n^{4/3} = y⁴.
  FrictionTerms terms(double g, double /*g_n*/, double h_n, double /*speed*/, double rho) const noexcept {
    const double inv_rho = 1.0 / rho, y = inverse_cbrt(h_n), y3 = y * y * y;
    return {tau_y * inv_rho * y3, g * n_td * n_td * (y3 * y), laminar_k * viscosity * 0.125 * inv_rho * (y3 * y3)};
  }
};

}  // namespace geohaz::runout
