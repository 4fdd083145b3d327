#pragma once
/// \file basal_friction.hpp
/// Basal shear laws of the depth-averaged debris-flow model, each written as a deceleration
/// (basal shear stress τ_b divided by ρ h_n, h_n the flow depth normal to the bed = hydraulic
/// radius R_h of a wide flow) acting against the velocity (3D, along the bed),
///
///     a_f(|v|) = a_rest + a_move(|v|),   a_move(0) = 0, increasing,
///
/// so one implicit step serves all of them (friction/friction_terms.hpp, RunoutSolver): a_rest is
/// the yield part that can hold a particle at rest (Coulomb, cohesion, yield stress, h_stop),
/// a_move the rate-dependent part. Laws with a_move = visc |v| + k |v|² return FrictionTerms; the
/// plug-flow and granular laws return their own terms with a closed-form or Newton step.
/// g_n = g cos θ is the bed-normal component of gravity. The laws of issue 34 (Voellmy with
/// cohesion, Bingham, Herschel–Bulkley, O'Brien–Julien, Pouliquen–Forterre) live one per file in
/// friction/, each with its source and equation as implemented; docs/runout.md tabulates them.
///
/// The law is chosen once (a std::variant visited once per step), never inside the particle loop.

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <variant>

#include "geohaz/core/law_parameters.hpp"
#include "geohaz/core/name_table.hpp"
#include "geohaz/runout/friction/bingham.hpp"
#include "geohaz/runout/friction/friction_terms.hpp"
#include "geohaz/runout/friction/herschel_bulkley.hpp"
#include "geohaz/runout/friction/obrien_julien.hpp"
#include "geohaz/runout/friction/pouliquen_forterre.hpp"
#include "geohaz/runout/friction/voellmy_cohesion.hpp"

namespace geohaz::runout {

/// Modified Manning law for a soil–water mixture (SWJTU lecture 2010, §3):
///   τ_b = (τ_cr |v|^m + ρ g n² |v|² / R_h^{1/3}) v/|v|,   τ_cr = ρ g_n R_h i_cr,   R_h = h_n.
/// Divided by ρ h_n: a = g_n i_cr |v|^m + g n² |v|² / h_n^{4/3}.
/// n: Manning roughness (s/m^{1/3}), 0.02–0.1 for natural rivers, seed example 0.06;
/// i_cr: critical slope gradient (1), seed example 0.15; m: exponent of the yield term (1), 0 by default.
/// Steady uniform flow on slope θ: v = h_n^{2/3} √(sin θ − i_cr cos θ)/n (Manning with S = sin θ).
struct ModifiedManningFriction {
  static constexpr std::array<ParamSpec, 3> parameters{
      {kManningNParameter,
       {"icr", 0.15, Range::closed(0.0, 2.0), "1", "critical slope gradient i_cr", "tan of the stopping angle"},
       {"m", 0.0, Range::closed(0.0, 2.0), "1", "exponent of |v| in the yield term"}}};
  double n = parameters[0].def;
  double i_cr = parameters[1].def;
  double m = parameters[2].def;
  static constexpr const char* name = "manning";
  static constexpr const char* summary = "modified Manning for a debris flow (n, icr, m; SWJTU lecture 2010)";
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? n : j == 1 ? i_cr : m) = v, true; }
  FrictionTerms terms(double g, double g_n, double h_n, double speed, double /*rho*/) const noexcept {
    const double rest = m == 0.0 ? g_n * i_cr : g_n * i_cr * std::pow(speed, m);
    return {rest, g * n * n / (h_n * std::cbrt(h_n))};
  }
};

/// Voellmy law (Voellmy 1955; as in RAMMS / r.avaflow): τ_b = μ ρ g_n h_n + ρ g |v|²/ξ.
/// μ: Coulomb friction coefficient (1); ξ: turbulent friction coefficient (m/s²).
/// Equals ModifiedManning with m = 0 for μ = i_cr and ξ = h_n^{1/3}/n².
struct VoellmyFriction {
  static constexpr std::array<ParamSpec, 2> parameters{{kCoulombMuParameter, kVoellmyXiParameter}};
  double mu = kCoulombMuParameter.def;
  double xi = kVoellmyXiParameter.def;
  static constexpr const char* name = "voellmy";
  static constexpr const char* summary = "Voellmy, Coulomb plus turbulent drag (mu, xi; Voellmy 1955, as in RAMMS)";
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? mu : xi) = v, true; }
  FrictionTerms terms(double g, double g_n, double h_n, double /*speed*/, double /*rho*/) const noexcept {
    return {g_n * mu, g / (xi * h_n)};
  }
};

/// Dry Coulomb friction: τ_b = μ ρ g_n h_n (μ = tan of the basal friction angle, 1).
struct CoulombFriction {
  static constexpr std::array<ParamSpec, 1> parameters{{kCoulombMuParameter}};
  double mu = kCoulombMuParameter.def;
  static constexpr const char* name = "coulomb";
  static constexpr const char* summary = "dry Coulomb friction (mu)";
  bool set(std::size_t /*j*/, double v) noexcept { return mu = v, true; }
  FrictionTerms terms(double /*g*/, double g_n, double /*h_n*/, double /*speed*/, double /*rho*/) const noexcept {
    return {g_n * mu, 0.0};
  }
};

/// The law of a run, chosen from the config: the one registration of the laws. Its alternatives'
/// `name`s are the values of `model.friction` (the name table) and their `parameters` the
/// model.<key> coefficients (LawParameters: reader, help text, refusal of another law's key,
/// friction zones, the report's labels), so a law is added here and in its own file only.
using BasalFriction =
    std::variant<ModifiedManningFriction, VoellmyFriction, CoulombFriction, VoellmyCohesionFriction, BinghamFriction,
                 HerschelBulkleyFriction, OBrienJulienFriction, PouliquenForterreFriction>;
using BasalFrictionNames = NameTable<BasalFriction>;
using BasalFrictionParameters = LawParameters<BasalFriction>;
static_assert(BasalFrictionParameters::consistent(),
              "two basal laws declare the same key differently: share one ParamSpec (friction_terms.hpp)");

/// The name of the law held ("manning", "voellmy", ...).
inline std::string friction_name(const BasalFriction& f) {
  return std::string(BasalFrictionNames::name_of(f));
}

}  // namespace geohaz::runout
