#pragma once
/// \file constitutive.hpp
/// Constitutive models of the SPH slope model (stress update per particle and step).
///
/// All models advance the Cauchy stress σ (3×3, tension positive) with the Jaumann rate
/// (SPH-slope paper 2020, eq. 22 / Bui et al. (2010), eq. 21, Bui et al. 2008):
///     dσ/dt = W σ − σ W + 2G ė + K tr(ε̇) I − (plastic correction)
/// where ε̇ = ½(L + Lᵀ), W = ½(L − Lᵀ) (SPH-slope paper 2020, eqs. 24–25), ė = ε̇ − ⅓ tr(ε̇) I,
/// K = E / (3(1 − 2ν)), G = E / (2(1 + ν)). In 2D plane strain L is embedded in 3×3 with
/// zero out-of-plane row/column, so σ_zz evolves with (K − 2G/3) tr(ε̇) (ε_zz = 0).
///
/// The plastic models use an elastic predictor followed by a return mapping (Bui et al. 2008,
/// Int. J. Numer. Anal. Meth. Geomech. 32:1537–1570, §3):
///   f = α_φ I1 + √J2 − k_c ,  g = α_ψ I1 + √J2 (non-associated when ψ ≠ φ),
///   Δλ = f(σ_trial) / (9 α_φ α_ψ K + G),  σ = σ_trial − Δλ (3K α_ψ I + G s_trial/√J2_trial),
/// i.e. the time-discrete form of the plastic term of Bui et al. (2010), eqs. 21–22. Then Bui's two
/// safeguards: tension cut-off (I1 > k_c/α_φ → hydrostatic shift to the apex) and scaling back
/// (√J2 > k_c − α_φ I1 → s scaled by r = (k_c − α_φ I1)/√J2).
/// Density floor (`min_density`): the continuity density of a material that cannot carry mean
/// tension beyond p_t (Drucker–Prager: the apex, p_t = k_c/(3α_φ)) is bounded below by the density
/// of the elastic dilation at p_t, ρ_min = ρ0/(1 + p_t/K) (ρ0 for c = 0). Beyond it the particles are
/// parting (SWJTU lecture 2010 "meeting and parting"), not dilating: the gap between them is not material
/// volume. Without the floor m/ρ of separating particles grows without bound (ρ → 0), their
/// neighbours' velocity gradients and σ/ρ² blow up (column collapses at Δx = L0/30–L0/40).
///
/// The model interface (checked by the concept `ConstitutiveLaw`). A model is a plain struct with
/// static members only — the solver picks one per run through the std::variant ConstitutiveModel,
/// visited once per step, so the particle loop has no dispatch — that declares everything the
/// solver needs to know about it (the solver has no special case for any model):
///   name, summary              config name (`model.constitutive`) and a sentence for --help-config;
///   parameters, set(p, j, v)   the [[material]] keys the model reads besides density, young and
///                              poisson (ParamSpec: default, range, unit, meaning; angles in
///                              degrees), and where value j lands in MaterialParams; `check(v)`
///                              (optional) its rules between them (core/law_parameters.hpp);
///   InternalVariables          FieldList of the per-particle fields the model evolves, e.g.
///                              FieldList<PlasticStrain>; each is a field of the store (fields.hpp),
///                              so it is reordered, written to snapshots and restored on restart
///                              with the rest; the geostatic phase resets them to zero;
///   wave_speed(p)              signal speed of the material (m/s): Δt (CFL), artificial viscosity,
///                              wall repulsion;
///   time_step_limit(p, h)      a bound on Δt of the model's own (s), +∞ if none;
///   min_density(p)             the density floor (below);
///   elastic_loading            whether the geostatic phase may load the material as linear elastic
///                              (a solid), or must keep the model's own law (a fluid has no elastic
///                              state to load into);
///   update(σ, L, Δt, ρ, p, iv...)  the stress update of one particle, with a reference to each of
///                              its internal variables in the order of InternalVariables; returns
///                              the plastic multiplier Δλ of the step (0 if elastic) for the step
///                              statistics.
/// A model with a shear strength also declares (both or neither; `HasShearStrength` below):
///   reduce_strength(p, F)      p with its strength divided by the factor F (the strength
///                              reduction's trial material: c/F and tan φ/F, or σ_y/F);
///   plane_strain_strength(p, residual)  the Mohr–Coulomb (c, φ) of the material in plane strain,
///                              for Bishop's method beside the SPH run (residual: the softened one).
/// A model without them (an elastic solid, a fluid) has nothing to reduce: the strength reduction
/// and the limit-equilibrium checks refuse it by name.
/// A new model (say Drucker–Prager with c and φ softening over a plastic-strain range) is a struct
/// like DruckerPrager below, with update reading its PlasticStrain argument and its `parameters`,
/// plus its entry in ConstitutiveModel (the name table); a parameter it adds is a member of
/// MaterialParams. docs/sph.md, "Adding a constitutive model".

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "geohaz/core/law_parameters.hpp"
#include "geohaz/core/name_table.hpp"
#include "geohaz/core/vec.hpp"
#include "geohaz/sph/fields.hpp"

namespace geohaz::sph {

/// Which Drucker–Prager fit to the Mohr–Coulomb parameters (c, φ).
enum class DruckerPragerFit {
  PlaneStrain,  ///< Bui et al. (2010), eqs. 18–19: α = tanφ/√(9+12tan²φ), k = 3c/√(9+12tan²φ)
  Compression3D,  ///< SPH-slope paper (2020), eq. 21: α = 2sinφ/(√3(3−sinφ)), k = 6c cosφ/(√3(3−sinφ)) (outer cone)
  /// Plane strain matched to Mohr–Coulomb for the flow rule in use (dilatancy ψ):
  /// α = sinφ √(3 + sin²ψ) / (√3 (3 + sinφ sinψ)), k = √3 c cosφ √(3 + sin²ψ) / (3 + sinφ sinψ),
  /// α_ψ as PlaneStrain. ψ = φ gives PlaneStrain exactly; ψ = 0 gives α = sinφ/3, k = c cosφ.
  /// Derivation (docs/sph.md, "Drucker–Prager constants"): in plane-strain plastic flow ε̇ᵖ_zz = 0,
  /// i.e. α_ψ + s_zz/(2√J2) = 0, so s_zz = −2α_ψ√J2 and J2 = t²/(1 − 3α_ψ²) with t = (σ1 − σ3)/2;
  /// the cone α I1 + √J2 = k then reads t = (k − 3α m) √(1 − 3α_ψ²)/(1 − 3α α_ψ), m = (σ1 + σ3)/2,
  /// which is Mohr–Coulomb t = c cosφ − m sinφ for the constants above.
  PlaneStrainFlowRule
};

/// Config name of a fit (`model.dp_fit`).
inline const char* drucker_prager_fit_name(DruckerPragerFit f) noexcept {
  switch (f) {
    case DruckerPragerFit::PlaneStrain:
      return "plane_strain";
    case DruckerPragerFit::Compression3D:
      return "compression_3d";
    case DruckerPragerFit::PlaneStrainFlowRule:
      return "plane_strain_flow_rule";
  }
  return "";
}

/// Drucker–Prager constants α_φ, k_c (Pa) and α_ψ.
struct DruckerPragerConstants {
  double alpha_phi = 0.0;
  double kc = 0.0;
  double alpha_psi = 0.0;
};

/// DP constants from cohesion c (Pa), friction φ and dilatancy ψ (radians) for the chosen fit.
inline DruckerPragerConstants drucker_prager_constants(double c, double phi, double psi, DruckerPragerFit fit) {
  DruckerPragerConstants k;
  if (fit == DruckerPragerFit::PlaneStrain) {
    const double tp = std::tan(phi), tq = std::tan(psi);
    const double d = std::sqrt(9.0 + 12.0 * tp * tp);
    k.alpha_phi = tp / d;
    k.kc = 3.0 * c / d;
    k.alpha_psi = tq / std::sqrt(9.0 + 12.0 * tq * tq);
  } else if (fit == DruckerPragerFit::PlaneStrainFlowRule) {
    const double sp = std::sin(phi), sq = std::sin(psi), tq = std::tan(psi);
    const double r = std::sqrt(3.0 + sq * sq), d = 3.0 + sp * sq;
    k.alpha_phi = sp * r / (std::sqrt(3.0) * d);
    k.kc = std::sqrt(3.0) * c * std::cos(phi) * r / d;
    k.alpha_psi = tq / std::sqrt(9.0 + 12.0 * tq * tq);
  } else {
    const double sp = std::sin(phi), sq = std::sin(psi);
    k.alpha_phi = 2.0 * sp / (std::sqrt(3.0) * (3.0 - sp));
    k.kc = 6.0 * c * std::cos(phi) / (std::sqrt(3.0) * (3.0 - sp));
    k.alpha_psi = 2.0 * sq / (std::sqrt(3.0) * (3.0 - sq));
  }
  return k;
}

/// Parameters of one material (SI units). Derived constants are filled by `finalise()`.
struct MaterialParams {
  double density = 1800.0;    ///< ρ0, kg/m³
  double young = 1e6;         ///< E, Pa
  double poisson = 0.3;       ///< ν, 1
  double cohesion = 0.0;      ///< c, Pa (Drucker–Prager)
  double friction = 0.5;      ///< φ, rad (Drucker–Prager)
  double dilatancy = 0.0;     ///< ψ, rad (Drucker–Prager)
  double yield_stress = 1e5;  ///< σ_y (uniaxial), Pa (von Mises: k = σ_y/√3)
  double viscosity = 1e-3;    ///< μ, Pa·s (Newtonian fluid)
  // Strain softening (DruckerPragerSoftening): c and φ fall linearly with the accumulated plastic
  // multiplier κ = Σ Δλ from the peak values above to these residual ones at κ = softening_strain.
  double residual_cohesion = 0.0;  ///< c_r, Pa (≤ cohesion)
  double residual_friction = 0.5;  ///< φ_r, rad (≤ friction)
  double softening_strain = 0.05;  ///< κ_r, 1 (> 0)
  DruckerPragerFit fit = DruckerPragerFit::PlaneStrain;
  // derived
  double bulk = 0.0, shear = 0.0;  ///< K, G (Pa)
  DruckerPragerConstants dp;
  double p_wave_speed = 0.0;  ///< √((K + 4G/3)/ρ0), m/s

  /// Compute K, G, the DP constants and the P-wave speed.
  void finalise() {
    bulk = young / (3.0 * (1.0 - 2.0 * poisson));
    shear = young / (2.0 * (1.0 + poisson));
    dp = drucker_prager_constants(cohesion, friction, dilatancy, fit);
    p_wave_speed = std::sqrt((bulk + 4.0 * shear / 3.0) / density);
  }
};

/// Embed a Dim×Dim velocity gradient into 3×3 (plane strain: zero out-of-plane row/column).
template <int Dim>
inline Mat3 embed3(const Mat<Dim>& L) noexcept {
  if constexpr (Dim == 3) {
    return L;
  } else {
    Mat3 m = Mat3::Zero();
    m.template topLeftCorner<2, 2>() = L;
    return m;
  }
}

/// Elastic trial stress: σ + Δt (Wσ − σW + 2G ė + K tr(ε̇) I) (Jaumann rate, Hooke's law).
inline Mat3 elastic_trial(const Mat3& sigma, const Mat3& L, double dt, double K, double G) noexcept {
  const Mat3 D = 0.5 * (L + L.transpose());
  const Mat3 W = 0.5 * (L - L.transpose());
  const double trD = D.trace();
  Mat3 dev = D;
  dev.diagonal().array() -= trD / 3.0;
  Mat3 rate = W * sigma - sigma * W + 2.0 * G * dev;
  rate.diagonal().array() += K * trD;
  return sigma + dt * rate;
}

/// Drucker–Prager return mapping with tension cut-off and scaling back (Bui et al. 2008).
/// Modifies sigma in place and returns Δλ (≥ 0). α_φ = α_ψ = 0 gives von Mises with k_c = σ_y/√3.
inline double drucker_prager_return(Mat3& sigma, double alpha_phi, double alpha_psi, double kc, double K,
                                    double G) noexcept {
  double I1 = sigma.trace();
  Mat3 s = sigma;
  s.diagonal().array() -= I1 / 3.0;
  double sq = std::sqrt(0.5 * s.squaredNorm());
  const double f = alpha_phi * I1 + sq - kc;
  double dl = 0.0;
  if (f > 0.0) {
    dl = f / (9.0 * alpha_phi * alpha_psi * K + G);
    if (sq > G * dl && sq > 0.0) {
      // Radial return onto the cone (exact for the DP cone away from the apex).
      s *= (sq - G * dl) / sq;
      I1 -= 9.0 * K * alpha_psi * dl;
      sq -= G * dl;
    } else {
      // The return passes the apex: the stress goes to the apex.
      s.setZero();
      sq = 0.0;
      I1 = alpha_phi > 0.0 ? kc / alpha_phi : I1;
    }
  }
  // Tension cut-off (Bui 2008 eq. 33): no hydrostatic tension beyond the apex.
  if (alpha_phi > 0.0 && I1 > kc / alpha_phi) I1 = kc / alpha_phi;
  // Scaling back (Bui 2008 eq. 34): put the deviator back on the surface if it is outside.
  const double limit = kc - alpha_phi * I1;
  if (sq > limit && sq > 0.0) {
    s *= (limit > 0.0 ? limit : 0.0) / sq;
  }
  sigma = s;
  sigma.diagonal().array() += I1 / 3.0;
  return dl;
}

/// Yield function f = α_φ I1 + √J2 − k_c (Pa), for tests and diagnostics.
inline double drucker_prager_yield(const Mat3& sigma, double alpha_phi, double kc) noexcept {
  const double I1 = sigma.trace();
  Mat3 s = sigma;
  s.diagonal().array() -= I1 / 3.0;
  return alpha_phi * I1 + std::sqrt(0.5 * s.squaredNorm()) - kc;
}

/// The [[material]] keys of the Mohr–Coulomb strength, shared by the Drucker–Prager models.
inline constexpr ParamSpec kCohesionParameter{"cohesion", 0.0, Range::non_negative(), "Pa", "cohesion c"};
inline constexpr ParamSpec kFrictionAngleParameter{"friction", 30.0, Range::closed_open(0.0, 90.0), "deg",
                                                   "friction angle phi"};
inline constexpr ParamSpec kDilatancyParameter{"dilatancy",           0.0,     Range::closed_open(0.0, 90.0), "deg",
                                               "dilatancy angle psi", "<= phi"};
inline constexpr double kDegree = std::numbers::pi / 180.0;  ///< one degree in radians

/// A number summary.json reports for each material under a model (`materials[].<key>`, also
/// printed in the log): the key (with its unit's suffix, as every summary key), what a reader
/// calls it, its unit as the config declarations write it, and its value for a material. A figure
/// that is one of the model's own parameters takes its label and unit from that parameter's
/// declaration (ParamSpec), so they are stated once; the summary's key list (summary_keys.cpp) is
/// built from the models' figures.
struct MaterialFigure {
  std::string_view key;
  std::string_view label;
  std::string_view unit;
  double (*value)(const MaterialParams&);
  constexpr MaterialFigure(std::string_view k, std::string_view l, std::string_view u,
                           double (*v)(const MaterialParams&)) noexcept
      : key(k), label(l), unit(u), value(v) {}
  /// The figure of a declared parameter: its label is the parameter's meaning, its unit the parameter's.
  constexpr MaterialFigure(std::string_view k, const ParamSpec& parameter, double (*v)(const MaterialParams&)) noexcept
      : key(k), label(parameter.meaning), unit(parameter.unit), value(v) {}
};

/// The figures several models report.
inline constexpr MaterialFigure kBulkModulusFigure{"K_Pa", "bulk modulus K", "Pa",
                                                   [](const MaterialParams& m) { return m.bulk; }};
inline constexpr MaterialFigure kShearModulusFigure{"G_Pa", "shear modulus G", "Pa",
                                                    [](const MaterialParams& m) { return m.shear; }};
inline constexpr MaterialFigure kAlphaPhiFigure{"alpha_phi", "Drucker–Prager α_φ", "1",
                                                [](const MaterialParams& m) { return m.dp.alpha_phi; }};
inline constexpr MaterialFigure kKcFigure{"k_c_Pa", "Drucker–Prager k_c", "Pa",
                                          [](const MaterialParams& m) { return m.dp.kc; }};
inline constexpr MaterialFigure kAlphaPsiFigure{"alpha_psi", "Drucker–Prager α_ψ", "1",
                                                [](const MaterialParams& m) { return m.dp.alpha_psi; }};

/// Linear elasticity with the Jaumann rate (Hooke's law, K and G from E and ν).
struct LinearElastic {
  static constexpr const char* name = "linear_elastic";
  static constexpr const char* summary = "linear elasticity (E, nu), Jaumann rate";
  static constexpr std::array<ParamSpec, 0> parameters{};
  static void set(MaterialParams& /*p*/, std::size_t /*j*/, double /*v*/) noexcept {}
  using InternalVariables = FieldList<>;
  static double update(Mat3& sigma, const Mat3& L, double dt, double /*rho*/, const MaterialParams& p) noexcept {
    sigma = elastic_trial(sigma, L, dt, p.bulk, p.shear);
    return 0.0;
  }
  /// The P-wave speed √((K + 4G/3)/ρ0).
  static double wave_speed(const MaterialParams& p) noexcept { return p.p_wave_speed; }
  static double time_step_limit(const MaterialParams& /*p*/, double /*h*/) noexcept {
    return std::numeric_limits<double>::infinity();
  }
  /// No floor: an elastic solid carries any tension.
  static double min_density(const MaterialParams& /*p*/) noexcept { return 0.0; }
  static constexpr bool elastic_loading = true;
  static constexpr std::array<MaterialFigure, 2> figures{{kBulkModulusFigure, kShearModulusFigure}};
};

/// Elastic–perfectly plastic von Mises: f = √J2 − σ_y/√3, associated flow, radial return.
struct VonMises {
  static constexpr const char* name = "von_mises";
  static constexpr const char* summary = "elastic-perfectly plastic von Mises (E, nu, yield_stress)";
  static constexpr std::array<ParamSpec, 1> parameters{
      {{"yield_stress", 1e5, Range::positive(), "Pa", "uniaxial yield stress"}}};
  static void set(MaterialParams& p, std::size_t /*j*/, double v) noexcept { p.yield_stress = v; }
  using InternalVariables = FieldList<PlasticStrain>;
  static double update(Mat3& sigma, const Mat3& L, double dt, double /*rho*/, const MaterialParams& p,
                       double& plastic_strain) noexcept {
    sigma = elastic_trial(sigma, L, dt, p.bulk, p.shear);
    const double dl = drucker_prager_return(sigma, 0.0, 0.0, p.yield_stress / std::sqrt(3.0), p.bulk, p.shear);
    plastic_strain += dl;
    return dl;
  }
  static double wave_speed(const MaterialParams& p) noexcept { return p.p_wave_speed; }
  static double time_step_limit(const MaterialParams& /*p*/, double /*h*/) noexcept {
    return std::numeric_limits<double>::infinity();
  }
  /// No floor: von Mises has no tension cut-off.
  static double min_density(const MaterialParams& /*p*/) noexcept { return 0.0; }
  static constexpr bool elastic_loading = true;
  /// An undrained (total-stress) strength: σ_y/F.
  static void reduce_strength(MaterialParams& p, double F) noexcept { p.yield_stress /= F; }
  /// In plane strain with associated flow σ_zz = (σ1 + σ3)/2, so √J2 = (σ1 − σ3)/2 and the yield
  /// √J2 = σ_y/√3 is Tresca's with c_u = σ_y/√3, φ = 0.
  static std::pair<double, double> plane_strain_strength(const MaterialParams& p, bool /*residual*/) noexcept {
    return {p.yield_stress / std::sqrt(3.0), 0.0};
  }
  static constexpr std::array<MaterialFigure, 3> figures{
      {kBulkModulusFigure, kShearModulusFigure, {"yield_stress_Pa", parameters[0], [](const MaterialParams& m) {
                                                   return m.yield_stress;
                                                 }}}};
};

/// Elastic–perfectly plastic Drucker–Prager, non-associated (dilatancy ψ), Jaumann rate,
/// Bui et al. (2010), eqs. 17–22 / SPH-slope paper (2020), eqs. 18–23, return mapping after Bui et al. (2008).
/// Internal variable: the accumulated plastic multiplier Σ Δλ (PlasticStrain).
struct DruckerPrager {
  static constexpr const char* name = "drucker_prager";
  static constexpr const char* summary =
      "elastic-perfectly plastic Drucker-Prager (E, nu, cohesion, friction, dilatancy), Bui et al. 2008";
  static constexpr std::array<ParamSpec, 3> parameters{
      {kCohesionParameter, kFrictionAngleParameter, kDilatancyParameter}};
  /// c (Pa), φ and ψ (read in degrees, held in radians).
  static void set(MaterialParams& p, std::size_t j, double v) noexcept {
    if (j == 0) p.cohesion = v;
    if (j == 1) p.friction = kDegree * v;
    if (j == 2) p.dilatancy = kDegree * v;
  }
  /// ψ ≤ φ.
  static std::optional<ParamProblem> check(const ParamValues& v) {
    if (kDegree * v["dilatancy"] > kDegree * v["friction"] + 1e-12)
      return ParamProblem{"dilatancy", "dilatancy must not exceed the friction angle", std::to_string(v["dilatancy"])};
    return std::nullopt;
  }
  using InternalVariables = FieldList<PlasticStrain>;
  static double update(Mat3& sigma, const Mat3& L, double dt, double /*rho*/, const MaterialParams& p,
                       double& plastic_strain) noexcept {
    sigma = elastic_trial(sigma, L, dt, p.bulk, p.shear);
    const double dl = drucker_prager_return(sigma, p.dp.alpha_phi, p.dp.alpha_psi, p.dp.kc, p.bulk, p.shear);
    plastic_strain += dl;
    return dl;
  }
  static double wave_speed(const MaterialParams& p) noexcept { return p.p_wave_speed; }
  static double time_step_limit(const MaterialParams& /*p*/, double /*h*/) noexcept {
    return std::numeric_limits<double>::infinity();
  }
  /// ρ0/(1 + p_t/K) with the apex tension p_t = k_c/(3α_φ): elastic dilation up to the tension
  /// cut-off, parting beyond it (see the file comment). α_φ = 0 (φ = 0): no cut-off, no floor.
  static double min_density(const MaterialParams& p) noexcept {
    if (!(p.dp.alpha_phi > 0.0)) return 0.0;
    return p.density / (1.0 + p.dp.kc / (3.0 * p.dp.alpha_phi * p.bulk));
  }
  static constexpr bool elastic_loading = true;
  /// c/F, atan(tan φ/F), atan(tan ψ/F) (Griffiths & Lane 1999; ψ with φ keeps ψ ≤ φ).
  static void reduce_strength(MaterialParams& p, double F) noexcept {
    p.cohesion /= F;
    p.friction = std::atan(std::tan(p.friction) / F);
    p.dilatancy = std::atan(std::tan(p.dilatancy) / F);
  }
  static std::pair<double, double> plane_strain_strength(const MaterialParams& p, bool /*residual*/) noexcept {
    return {p.cohesion, p.friction};
  }
  static constexpr std::array<MaterialFigure, 6> figures{
      {kBulkModulusFigure,
       kShearModulusFigure,
       kAlphaPhiFigure,
       kKcFigure,
       kAlphaPsiFigure,
       {"min_density_kg_per_m3", "density floor", "kg/m^3",
        [](const MaterialParams& m) { return DruckerPrager::min_density(m); }}}};
};

/// Drucker–Prager with strain softening: as DruckerPrager, but cohesion and friction fall linearly
/// with the internal variable κ = Σ Δλ (PlasticStrain; in simple shear Δλ is the increment of the
/// engineering plastic shear strain γ_p, since Δε_p,dev = Δλ s/(2√J2)) from their peak values
/// (c, φ) to residual ones (c_r, φ_r) over κ ∈ [0, κ_r] and stay residual beyond:
///     c(κ) = c_r + (c − c_r) max(0, 1 − κ/κ_r),  φ(κ) = φ_r + (φ − φ_r) max(0, 1 − κ/κ_r),
/// the shape of the softening laws of strength-reduction and progressive-failure studies (e.g.
/// Potts, Dounias & Vaughan 1990 in c′–φ′ form, linear over a plastic-strain range). The step's
/// return mapping uses the strength at κ of the start of the step (explicit in κ; with Δλ per step
/// ≪ κ_r the lag is negligible), then κ += Δλ. ψ is constant. The density floor is that of the peak
/// strength (the lowest; the floor of a fully softened cohesionless particle would be ρ0).
struct DruckerPragerSoftening {
  static constexpr const char* name = "drucker_prager_softening";
  static constexpr const char* summary =
      "Drucker-Prager with cohesion and friction softening linearly from peak (cohesion, friction) to residual "
      "(residual_cohesion, residual_friction) over the plastic strain softening_strain";
  static constexpr std::array<ParamSpec, 6> parameters{
      {kCohesionParameter,
       kFrictionAngleParameter,
       kDilatancyParameter,
       {"residual_cohesion", 0.0, Range::non_negative(), "Pa", "residual cohesion c_r <= cohesion", "default: cohesion",
        "cohesion"},
       {"residual_friction", 30.0, Range::closed_open(0.0, 90.0), "deg", "residual friction angle phi_r <= friction",
        "default: friction", "friction"},
       {"softening_strain", 0.05, Range::positive(), "1",
        "plastic strain (sum of plastic multipliers) over which c and phi fall to residual"}}};
  static void set(MaterialParams& p, std::size_t j, double v) noexcept {
    if (j < 3) DruckerPrager::set(p, j, v);
    if (j == 3) p.residual_cohesion = v;
    if (j == 4) p.residual_friction = kDegree * v;
    if (j == 5) p.softening_strain = v;
  }
  /// Residual strength at most the peak one, and ψ ≤ φ.
  static std::optional<ParamProblem> check(const ParamValues& v) {
    if (v["residual_cohesion"] > v["cohesion"])
      return ParamProblem{
          "residual_cohesion",
          "residual cohesion must not exceed the peak cohesion (" + std::to_string(v["cohesion"]) + " Pa)",
          std::to_string(v["residual_cohesion"])};
    if (kDegree * v["residual_friction"] > kDegree * v["friction"] + 1e-12)
      return ParamProblem{
          "residual_friction",
          "residual friction must not exceed the peak friction angle (" + std::to_string(v["friction"]) + " deg)",
          std::to_string(v["residual_friction"])};
    return DruckerPrager::check(v);
  }
  using InternalVariables = FieldList<PlasticStrain>;
  /// c (Pa) and φ (rad) at the accumulated plastic multiplier κ.
  static std::pair<double, double> strength(const MaterialParams& p, double kappa) noexcept {
    const double w = std::max(0.0, 1.0 - kappa / p.softening_strain);
    return {p.residual_cohesion + (p.cohesion - p.residual_cohesion) * w,
            p.residual_friction + (p.friction - p.residual_friction) * w};
  }
  static double update(Mat3& sigma, const Mat3& L, double dt, double /*rho*/, const MaterialParams& p,
                       double& plastic_strain) noexcept {
    sigma = elastic_trial(sigma, L, dt, p.bulk, p.shear);
    const auto [c, phi] = strength(p, plastic_strain);
    const auto k = drucker_prager_constants(c, phi, p.dilatancy, p.fit);
    const double dl = drucker_prager_return(sigma, k.alpha_phi, k.alpha_psi, k.kc, p.bulk, p.shear);
    plastic_strain += dl;
    return dl;
  }
  static double wave_speed(const MaterialParams& p) noexcept { return p.p_wave_speed; }
  static double time_step_limit(const MaterialParams& /*p*/, double /*h*/) noexcept {
    return std::numeric_limits<double>::infinity();
  }
  static double min_density(const MaterialParams& p) noexcept { return DruckerPrager::min_density(p); }
  static constexpr bool elastic_loading = true;
  /// The peak and the residual strength alike.
  static void reduce_strength(MaterialParams& p, double F) noexcept {
    DruckerPrager::reduce_strength(p, F);
    p.residual_cohesion /= F;
    p.residual_friction = std::atan(std::tan(p.residual_friction) / F);
  }
  static std::pair<double, double> plane_strain_strength(const MaterialParams& p, bool residual) noexcept {
    return residual ? std::pair{p.residual_cohesion, p.residual_friction} : std::pair{p.cohesion, p.friction};
  }
  /// The Drucker–Prager constants of the residual strength.
  static DruckerPragerConstants residual_constants(const MaterialParams& p) noexcept {
    return drucker_prager_constants(p.residual_cohesion, p.residual_friction, p.dilatancy, p.fit);
  }
  static constexpr std::array<MaterialFigure, 9> figures{
      {kBulkModulusFigure,
       kShearModulusFigure,
       kAlphaPhiFigure,
       kKcFigure,
       kAlphaPsiFigure,
       {"residual_alpha_phi", "residual α_φ", "1",
        [](const MaterialParams& m) { return DruckerPragerSoftening::residual_constants(m).alpha_phi; }},
       {"residual_k_c_Pa", "residual k_c", "Pa",
        [](const MaterialParams& m) { return DruckerPragerSoftening::residual_constants(m).kc; }},
       {"softening_strain", parameters[5], [](const MaterialParams& m) { return m.softening_strain; }},
       {"min_density_kg_per_m3", "density floor", "kg/m^3",
        [](const MaterialParams& m) { return DruckerPragerSoftening::min_density(m); }}}};
};

/// Weakly compressible Newtonian fluid: σ = −p I + 2μ ė, p = K (ρ/ρ0 − 1) (linear equation of
/// state with bulk modulus K = E/(3(1−2ν))). Used for the viscous simple-shear check of SWJTU lecture (2010).
struct NewtonianFluid {
  static constexpr const char* name = "newtonian_fluid";
  static constexpr const char* summary = "weakly compressible Newtonian fluid (viscosity; bulk modulus from E, nu)";
  static constexpr std::array<ParamSpec, 1> parameters{
      {{"viscosity", 1e-3, Range::non_negative(), "Pa s", "dynamic viscosity"}}};
  static void set(MaterialParams& p, std::size_t /*j*/, double v) noexcept { p.viscosity = v; }
  using InternalVariables = FieldList<>;
  static double update(Mat3& sigma, const Mat3& L, double /*dt*/, double rho, const MaterialParams& p) noexcept {
    const Mat3 D = 0.5 * (L + L.transpose());
    Mat3 dev = D;
    dev.diagonal().array() -= D.trace() / 3.0;
    sigma = 2.0 * p.viscosity * dev;
    sigma.diagonal().array() -= p.bulk * (rho / p.density - 1.0);
    return 0.0;
  }
  /// The sound speed of the equation of state, √(K/ρ0) (no shear wave in a fluid).
  static double wave_speed(const MaterialParams& p) noexcept { return std::sqrt(p.bulk / p.density); }
  /// Viscous diffusion: Δt ≤ 0.125 h²/ν with ν = μ/ρ0 (Morris et al. 1997).
  static double time_step_limit(const MaterialParams& p, double h) noexcept {
    if (!(p.viscosity > 0.0)) return std::numeric_limits<double>::infinity();
    return 0.125 * h * h / (p.viscosity / p.density);
  }
  /// No floor: the equation of state reacts to ρ < ρ0 itself.
  static double min_density(const MaterialParams& /*p*/) noexcept { return 0.0; }
  static constexpr bool elastic_loading = false;
  static constexpr std::array<MaterialFigure, 2> figures{
      {kBulkModulusFigure, {"viscosity_Pa_s", parameters[0], [](const MaterialParams& m) { return m.viscosity; }}}};
};

/// What the solver requires of a constitutive model (see the file comment).
template <class M>
concept ConstitutiveLaw = requires(const MaterialParams& p, double h) {
  { M::name } -> std::convertible_to<const char*>;
  { M::summary } -> std::convertible_to<const char*>;
  M::parameters.size();
  typename M::InternalVariables;
  { M::wave_speed(p) } -> std::same_as<double>;
  { M::time_step_limit(p, h) } -> std::same_as<double>;
  { M::min_density(p) } -> std::same_as<double>;
  { M::elastic_loading } -> std::convertible_to<bool>;
  { M::figures[0] } -> std::convertible_to<const MaterialFigure&>;
};

/// A model with a shear strength to reduce and to use in Bishop's method (see the file comment).
template <class M>
concept HasShearStrength = requires(MaterialParams& p, const MaterialParams& cp) {
  M::reduce_strength(p, 1.0);
  { M::plane_strain_strength(cp, false) } -> std::same_as<std::pair<double, double>>;
};

/// The run-time choice of model (one per run; all materials of a run share the model type), and
/// the one name table of the models: its alternatives' `name`s are the values of
/// `model.constitutive`. A model is added here and nowhere else in the solver or the app.
using ConstitutiveModel = std::variant<LinearElastic, VonMises, DruckerPrager, DruckerPragerSoftening, NewtonianFluid>;

template <class... M>
constexpr bool every_model_is_a_law(std::type_identity<std::variant<M...>>) {
  return (ConstitutiveLaw<M> && ...);
}
static_assert(every_model_is_a_law(std::type_identity<ConstitutiveModel>{}),
              "every alternative of ConstitutiveModel is a ConstitutiveLaw");
using ConstitutiveModelNames = NameTable<ConstitutiveModel>;
/// The models' [[material]] keys (law_parameters.hpp): reader, help text and labels.
using ConstitutiveModelParameters = LawParameters<ConstitutiveModel>;
static_assert(ConstitutiveModelParameters::consistent(), "two models declare the same material key differently");

/// Put the values of the model's own keys (as read: angles in degrees) into a material.
inline void set_model_parameters(const ConstitutiveModel& m, MaterialParams& p, const ParamValues& v) {
  std::visit(
      [&](const auto& law) {
        using M = std::decay_t<decltype(law)>;
        for (std::size_t j = 0; j < v.value.size(); ++j) M::set(p, j, v.value[j]);
      },
      m);
}

/// The figures summary.json reports for a material under the run's model (its `figures`).
inline std::span<const MaterialFigure> material_figures(const ConstitutiveModel& m) noexcept {
  return std::visit(
      [](const auto& law) { return std::span<const MaterialFigure>(std::decay_t<decltype(law)>::figures); }, m);
}

/// Every model's figures, each key once: a key first met in a later model goes before the next key
/// of that model already listed, so each model's figures keep their declared order (the column
/// order of the report's material table).
inline std::vector<MaterialFigure> all_material_figures() {
  std::vector<MaterialFigure> out;
  const auto listed = [&](std::string_view key) {
    return std::find_if(out.begin(), out.end(), [&](const MaterialFigure& f) { return f.key == key; });
  };
  const auto add = [&]<class M>(std::type_identity<M>) {
    for (std::size_t i = 0; i < M::figures.size(); ++i) {
      if (listed(M::figures[i].key) != out.end()) continue;
      auto at = out.end();
      for (std::size_t j = i + 1; j < M::figures.size() && at == out.end(); ++j) at = listed(M::figures[j].key);
      out.insert(at, M::figures[i]);
    }
  };
  [&]<class... M>(std::type_identity<std::variant<M...>>) {
    (add(std::type_identity<M>{}), ...);
  }(std::type_identity<ConstitutiveModel>{});
  return out;
}

/// Whether every figure key reported by several models has one label and unit (compile-time check).
constexpr bool material_figures_consistent() noexcept {
  bool ok = true;
  const auto against = [&]<class... M>(std::type_identity<std::variant<M...>>, const MaterialFigure& f) {
    const auto one = [&]<class N>(std::type_identity<N>) {
      for (const MaterialFigure& g : N::figures)
        if (g.key == f.key && (g.label != f.label || g.unit != f.unit)) ok = false;
    };
    (one(std::type_identity<M>{}), ...);
  };
  [&]<class... M>(std::type_identity<std::variant<M...>> v) {
    const auto each = [&]<class N>(std::type_identity<N>) {
      for (const MaterialFigure& f : N::figures) against(v, f);
    };
    (each(std::type_identity<M>{}), ...);
  }(std::type_identity<ConstitutiveModel>{});
  return ok;
}
static_assert(material_figures_consistent(), "two models report one figure key with different labels or units");

/// Config names of the models, in the order of ConstitutiveModel.
inline constexpr auto constitutive_model_names = ConstitutiveModelNames::names;
/// One sentence per model (same order), for --help-config.
inline constexpr auto constitutive_model_summaries = ConstitutiveModelNames::summaries;

/// The model of that config name; std::nullopt for an unknown name.
inline std::optional<ConstitutiveModel> constitutive_model_from_name(std::string_view name) {
  return ConstitutiveModelNames::from_name(name);
}

/// Name of a model.
inline std::string_view constitutive_model_name(const ConstitutiveModel& m) noexcept {
  return constitutive_model_names[m.index()];
}

/// Whether the run's model has a shear strength (HasShearStrength): what the strength reduction
/// and Bishop's method need.
inline bool has_shear_strength(const ConstitutiveModel& m) noexcept {
  return std::visit([](const auto& law) { return HasShearStrength<std::decay_t<decltype(law)>>; }, m);
}

/// The config names of the models with a shear strength, comma-separated (for messages).
inline std::string models_with_shear_strength() {
  std::string names;
  auto add = [&]<class... M>(std::type_identity<std::variant<M...>>) {
    ((HasShearStrength<M> ? (names += (names.empty() ? "" : ", ") + std::string(M::name), 0) : 0), ...);
  };
  add(std::type_identity<ConstitutiveModel>{});
  return names;
}

/// The materials with their strength divided by F, each as the run's model reduces it. The model
/// must have a shear strength (the config check refuses the others by name).
inline std::vector<MaterialParams> reduced_strength(const ConstitutiveModel& m, std::vector<MaterialParams> mats,
                                                    double F) {
  std::visit(
      [&](const auto& law) {
        using M = std::decay_t<decltype(law)>;
        if constexpr (HasShearStrength<M>) {
          for (auto& p : mats) M::reduce_strength(p, F);
        } else {
          throw std::invalid_argument(std::string("the constitutive model ") + M::name + " has no strength to reduce");
        }
      },
      m);
  return mats;
}

/// The plane-strain Mohr–Coulomb (c, φ) of a material under the run's model (residual: the
/// softened strength); a model without a shear strength has none (std::nullopt).
inline std::optional<std::pair<double, double>> plane_strain_strength(const ConstitutiveModel& m,
                                                                      const MaterialParams& p, bool residual = false) {
  return std::visit(
      [&](const auto& law) -> std::optional<std::pair<double, double>> {
        using M = std::decay_t<decltype(law)>;
        if constexpr (HasShearStrength<M>)
          return M::plane_strain_strength(p, residual);
        else
          return std::nullopt;
      },
      m);
}

}  // namespace geohaz::sph
