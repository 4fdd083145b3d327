#pragma once
/// \file contact_laws.hpp
/// Disc–disc and disc–wall contact laws. Each law is a small value type (see the concept
/// `DemContactLaw` below for what it declares: config name, normal force and stiffnesses, its
/// dashpot from the restitution, its stored elastic energy, reference stiffnesses for the time
/// step); the solver picks one with std::visit once per step. The tangential friction and the
/// rolling resistance are one sub-model shared by every law (`CoulombFrictionRolling`), for
/// disc–disc and disc–wall contacts alike.
///
/// Sign conventions (2D, unit thickness): overlap δ = R_i + R_j − |x_i − x_j| > 0 in contact,
/// the normal n points from j to i, the tangent t = ẑ × n. The normal force on i is
/// F_n = f_el(δ) − c_n v_n (v_n = relative normal velocity, > 0 separating). No clamp to F_n ≥ 0 is
/// applied while δ > 0, so the restitution coefficient e is reproduced exactly by the linear law
/// (documented in docs/dem.md); the friction limit uses max(F_n, 0). Disc–wall contacts are
/// clamped to F_n ≥ 0 (a wall never pulls); their damping comes from `wall_damping(e)`, which for
/// the linear law is the clamped-dashpot inverse, so the configured e is reproduced there too.

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <numbers>
#include <optional>
#include <string_view>
#include <type_traits>
#include <variant>

#include "geohaz/core/law_parameters.hpp"
#include "geohaz/core/name_table.hpp"

namespace geohaz::dem {

/// Normal and tangential response of a contact at overlap δ.
struct ContactResponse {
  double fn_elastic;  ///< elastic normal force (N/m), ≥ 0
  double kn;          ///< tangent normal stiffness (N/m/m) — also enters the critical time step
  double cn;          ///< normal dashpot coefficient (N·s/m/m)
  double kt;          ///< tangential stiffness (N/m/m)
};

/// Damping ratio ζ giving restitution e for a linear spring-dashpot:
/// e = exp(−ζπ/√(1−ζ²))  ⇔  ζ = −ln e / √(π² + ln² e)   (e.g. Ting & Corkum 1992).
inline double damping_ratio_from_restitution(double e) {
  if (e >= 1.0) return 0.0;
  if (e <= 0.0) return 1.0;
  const double l = std::log(e);
  return -l / std::sqrt(std::numbers::pi * std::numbers::pi + l * l);
}

/// Restitution of a linear spring–dashpot whose normal force is clamped to F_n ≥ 0 (a wall never
/// pulls), at damping ratio ζ. The contact then ends when the force, not the overlap, returns to
/// zero. Solving m δ'' + c δ' + k δ = 0 (δ(0) = 0, δ'(0) = v₀) to the first t > 0 with
/// k δ + c δ' = 0 gives ωt = π − 2 asin ζ and a rebound speed v₀ e^{−ζω₀t}, hence
///   e = exp(−2ζ acos ζ / √(1−ζ²))    (ζ < 1),   e^{−2} at ζ = 1,
///   e = exp(−2ζ acosh ζ / √(ζ²−1))   (ζ > 1; still a rebound: the clamped dashpot never sticks),
/// as in Schwager & Pöschel (2007). Monotonic in ζ; e → 1/(4ζ²) for ζ → ∞.
inline double clamped_dashpot_restitution(double zeta) {
  if (zeta <= 0.0) return 1.0;
  if (std::abs(zeta - 1.0) < 1e-9) return std::exp(-2.0);
  if (zeta < 1.0) return std::exp(-2.0 * zeta * std::acos(zeta) / std::sqrt(1.0 - zeta * zeta));
  return std::exp(-2.0 * zeta * std::acosh(zeta) / std::sqrt(zeta * zeta - 1.0));
}

/// Damping ratio ζ giving restitution e ∈ (0, 1] for the force-clamped linear dashpot (the inverse
/// of clamped_dashpot_restitution, by bisection on ζ ∈ [0, 10⁴]; e ≥ 2.5·10⁻⁹). The unclamped
/// ζ of damping_ratio_from_restitution used on a clamped contact rebounds harder than asked
/// (e = 0.3 → 0.40, 0.5 → 0.55, 0.1 → 0.25).
inline double clamped_damping_ratio_from_restitution(double e) {
  if (e >= 1.0) return 0.0;
  double lo = 0.0, hi = 1e4;
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    (clamped_dashpot_restitution(mid) > e ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// Linear spring–dashpot with Coulomb friction (Cundall & Strack 1979):
/// F_n = k_n δ − c_n v_n, c_n = 2ζ√(m* k_n); ΔF_t = −k_s Δu_t, |F_t| ≤ μ F_n.
/// Undamped contact duration t_c = π√(m*/k_n).
struct LinearSpringCoulomb {
  static constexpr const char* name = "linear";
  static constexpr const char* summary = "linear spring-dashpot + Coulomb friction (Cundall & Strack 1979)";
  // dem-avalanche's defaults: contact modulus E_c = 20 GPa (k_n = 2 E_c, PFC2D at unit thickness),
  // k_n/k_s = 2.5 (Potyondy & Cundall 2004), read as material.contact_modulus, .stiffness_ratio.
  static constexpr std::array<ParamSpec, 2> parameters{
      {{"contact_modulus", 20e9, Range::positive(), "Pa", "contact modulus E_c, k_n = 2 E_c", "PFC2D, unit thickness"},
       {"stiffness_ratio", 2.5, Range::positive(), "1", "k_n/k_s"}}};
  double kn = 2 * parameters[0].def;                      ///< normal stiffness (N/m per m thickness)
  double ks = 2 * parameters[0].def / parameters[1].def;  ///< shear stiffness (N/m per m thickness)
  static LinearSpringCoulomb from_parameters(const ParamValues& v) {
    return {2 * v["contact_modulus"], 2 * v["contact_modulus"] / v["stiffness_ratio"]};
  }
  /// k_n and k_t do not depend on the overlap (the solver computes √(k_t/k_n) once per step).
  static constexpr bool constant_stiffness = true;

  /// \param zeta damping ratio from the restitution coefficient (damping_ratio_from_restitution).
  ContactResponse evaluate(double delta, double meff, double /*reff*/, double /*slice*/, double zeta) const noexcept {
    return {kn * delta, kn, 2.0 * zeta * std::sqrt(meff * kn), ks};
  }
  /// Damping ratio of a disc–disc contact (unclamped) giving restitution e.
  static double pair_damping(double e) { return damping_ratio_from_restitution(e); }
  /// Damping ratio of a disc–wall contact (normal force clamped to ≥ 0) giving restitution e.
  static double wall_damping(double e) { return clamped_damping_ratio_from_restitution(e); }
  /// Elastic energy of the normal spring at overlap δ with elastic force F = k_n δ: ∫F dδ = ½ F δ (J/m).
  static double normal_energy(double fn_elastic, double delta) noexcept { return 0.5 * fn_elastic * delta; }
  /// Stiffness used for the critical time step before any contact exists.
  double reference_kn(double /*radius*/) const noexcept { return kn; }
  double reference_kt(double /*radius*/) const noexcept { return ks; }
};

/// Hertz–Mindlin (no-slip) contact of two elastic spheres (Hertz 1882; Mindlin 1949; the usual
/// DEM form of Tsuji et al. 1992), turned into a force per unit thickness of the discs by taking
/// the disc as a row of spheres of its diameter: forces and stiffnesses are divided by the slice
/// length l = R_i + R_j (disc pair) or 2R_i (disc–wall). This is our choice (docs/dem.md): the
/// plain sphere law gives newtons, not N/m, and is far too soft for mm-size discs.
///   F_n = 4/3 E* √R* δ^{3/2} / l, S_n = 2E*√(R*δ) / l, S_t = 8G*√(R*δ) / l,
///   c_n = 2√(5/6) β √(S_n m*), β = −ln e/√(π² + ln² e),
///   E* = E/(2(1−ν²)), G* = E/(4(2−ν)(1+ν)) for identical materials.
/// Elastic contact duration t_c = 2.868 (m*² l² /(R* E*² v))^{1/5} (m* per unit thickness).
struct HertzMindlin {
  static constexpr const char* name = "hertz";
  static constexpr const char* summary =
      "Hertz-Mindlin no-slip, spheres of the disc diameter per metre (Tsuji et al. 1992)";
  static constexpr std::array<ParamSpec, 2> parameters{
      {{"youngs_modulus", 20e9, Range::positive(), "Pa", "particle Young's modulus"},
       {"poisson_ratio", 0.25, Range::closed_open(0.0, 0.5), "1", "particle Poisson's ratio"}}};
  double youngs = parameters[0].def;   ///< particle Young's modulus E (Pa)
  double poisson = parameters[1].def;  ///< Poisson's ratio ν
  double reference_overlap = 0.005;    ///< δ/R used for the time step of a disc with no contact yet
  bool set(std::size_t j, double v) noexcept { return (j == 0 ? youngs : poisson) = v, true; }
  /// S_n and S_t grow with the contact radius √(R*δ).
  static constexpr bool constant_stiffness = false;

  double estar() const noexcept { return youngs / (2.0 * (1.0 - poisson * poisson)); }
  double gstar() const noexcept { return youngs / (4.0 * (2.0 - poisson) * (1.0 + poisson)); }
  /// \param slice row-of-spheres length l (m); \param beta damping factor (= damping_ratio_from_restitution(e)).
  ContactResponse evaluate(double delta, double meff, double reff, double slice, double beta) const noexcept {
    const double a = std::sqrt(reff * delta);  // contact radius
    const double Es = estar() / slice;
    const double sn = 2.0 * Es * a;
    return {4.0 / 3.0 * Es * a * delta, sn, 2.0 * std::sqrt(5.0 / 6.0) * beta * std::sqrt(sn * meff),
            8.0 * gstar() / slice * a};
  }
  /// Damping factor β of a disc–disc contact giving restitution e (Tsuji et al. 1992).
  static double pair_damping(double e) { return damping_ratio_from_restitution(e); }
  /// Damping factor β of a disc–wall contact. Tsuji's β, not corrected for the clamp to F_n ≥ 0
  /// (no closed form for the Hertz law; docs/dem.md gives the measured bias).
  static double wall_damping(double e) { return damping_ratio_from_restitution(e); }
  /// Elastic energy of the normal spring at overlap δ with elastic force F ∝ δ^{3/2}:
  /// ∫F dδ = ⅖ F δ (J/m).
  static double normal_energy(double fn_elastic, double delta) noexcept { return 0.4 * fn_elastic * delta; }
  /// Stiffness of a contact of a disc of radius R with an equal disc at the reference overlap.
  double reference_kn(double radius) const noexcept {
    return 2.0 * estar() * std::sqrt(0.5 * radius * reference_overlap * radius) / (2.0 * radius);
  }
  double reference_kt(double radius) const noexcept {
    return 8.0 * gstar() * std::sqrt(0.5 * radius * reference_overlap * radius) / (2.0 * radius);
  }
};

/// What the solver requires of a contact law. Every member is used by the solver; a law that
/// lacks one does not compile (no default stands in for it).
///   name, summary          config name (`material.contact_law`) and a sentence for --help-config;
///   parameters             its material.<key> coefficients (ParamSpec: default, range, unit,
///                          meaning), landing in the struct by `set(j, v)` or `from_parameters`;
///   evaluate(δ, m*, R*, l, z)  elastic normal force, normal and tangential stiffness, dashpot
///                          coefficient from the damping parameter z;
///   pair_damping(e), wall_damping(e)  z giving restitution e for a disc–disc (unclamped) and a
///                          disc–wall (clamped to F_n ≥ 0) contact;
///   normal_energy(F_el, δ) elastic energy stored in the normal spring (J/m);
///   reference_kn(R), reference_kt(R)  stiffnesses for the time step of a disc with no contact;
///   constant_stiffness     whether k_n and k_t are the same at every overlap (then the solver
///                          computes factors of them once per step instead of per contact).
template <class L>
concept DemContactLaw = requires(const L& l, double x) {
  { L::name } -> std::convertible_to<const char*>;
  { L::constant_stiffness } -> std::convertible_to<bool>;
  { L::summary } -> std::convertible_to<const char*>;
  L::parameters.size();
  { l.evaluate(x, x, x, x, x) } -> std::same_as<ContactResponse>;
  { L::pair_damping(x) } -> std::same_as<double>;
  { L::wall_damping(x) } -> std::same_as<double>;
  { L::normal_energy(x, x) } -> std::same_as<double>;
  { l.reference_kn(x) } -> std::same_as<double>;
  { l.reference_kt(x) } -> std::same_as<double>;
};

/// The contact law chosen by the configuration (visited once per step), and the one name table
/// of the laws: its alternatives' `name`s are the values of `material.contact_law` and their
/// `parameters` (core/law_parameters.hpp) the material.<key> keys, read, checked, described and
/// labelled from there. A law is added here and in its own struct only.
using ContactLaw = std::variant<LinearSpringCoulomb, HertzMindlin>;

template <class... L>
constexpr bool every_law_is_a_contact_law(std::type_identity<std::variant<L...>>) {
  return (DemContactLaw<L> && ...);
}
static_assert(every_law_is_a_contact_law(std::type_identity<ContactLaw>{}),
              "every alternative of ContactLaw is a DemContactLaw");
using ContactLawNames = NameTable<ContactLaw>;
using ContactLawParameters = LawParameters<ContactLaw>;
static_assert(ContactLawParameters::consistent(), "two contact laws declare the same key differently");

/// Config names of the contact laws, in the order of ContactLaw.
inline constexpr auto contact_law_names = ContactLawNames::names;
/// One sentence per law (same order), for --help-config.
inline constexpr auto contact_law_summaries = ContactLawNames::summaries;

/// The law of that config name with its default parameters; std::nullopt for an unknown name.
inline std::optional<ContactLaw> contact_law_from_name(std::string_view name) {
  return ContactLawNames::from_name(name);
}

/// Config name of a law.
inline std::string_view contact_law_name(const ContactLaw& law) noexcept {
  return contact_law_names[law.index()];
}

/// Parameters shared by the contact laws.
struct ContactProperties {
  double friction = 0.5;     ///< Coulomb friction coefficient μ
  double restitution = 0.5;  ///< normal restitution coefficient e ∈ (0, 1]
  /// Rolling-resistance coefficient μ_r (elastic–plastic spring-dashpot, Ai et al. 2011 model C,
  /// also Iwashita & Oda 1998): k_r = 2.25 μ_r² k_n R*², |M_r| ≤ μ_r R* F_n.
  double rolling_friction = 0.0;
  /// Rolling viscous damping ratio η_r (of the critical rolling damping 2√(I_r k_r)), applied
  /// while the rolling spring is not at its plastic limit.
  double rolling_damping = 0.3;
  /// Tangential dashpot as a fraction f ∈ [0, 1] of the normal one's damping ratio: c_t =
  /// f c_n √(k_t/k_n), i.e. the damping ratio f ζ on the tangential spring with the same m*
  /// (Cundall & Strack 1979 damp both directions). Applied only
  /// while the contact sticks; 0 (default): no tangential dashpot.
  double tangential_damping = 0.0;
  /// Mass m* of the disc–wall and disc–terrain dashpots (normal and tangential): false (default)
  /// the disc's own mass; true the effective mass of its bonded fragment at the contact point,
  /// m* = 1/(1/M_f + (r × n)²/I_f) (M_f, I_f the fragment's mass and inertia about its centre,
  /// r from that centre to the contact; Stronge 2000), so a bonded block hitting the terrain
  /// rebounds with the configured e instead of a disc's dashpot on a block's mass.
  bool fragment_damping_mass = false;
  /// Lever arm of the disc–terrain rolling resistance: false (default) the disc's radius, the
  /// moment acting on the disc (model C as for disc–disc and disc–wall contacts); true the height
  /// h = (G − p)·n of its bonded fragment's centre G above the contact point p (at least the disc
  /// radius), the spring turning with the fragment's spin and its moment μ_r h F_n applied to the
  /// fragment as a rigid body (every disc j gets m_j α × r_j and I_j α, α = M/I_f), so a fragment
  /// rolling on the terrain loses μ_r N per metre as a lumped rockfall block does (STONE, Guzzetti
  /// et al. 2002) instead of μ_r N R_disc/h. A lone disc is unchanged.
  bool fragment_rolling = false;
};

/// Combined rolling stiffness per Ai et al. (2011), eq. (9).
inline double rolling_stiffness(double mu_r, double kn, double reff) noexcept {
  return 2.25 * mu_r * mu_r * kn * reff * reff;
}

/// Tangential friction and rolling resistance of one contact, shared by every contact law and by
/// disc–disc and disc–wall contacts (the law only supplies k_n, k_t and F_n):
///   Coulomb friction on an incremental tangential spring with an optional dashpot c_t (Cundall &
///   Strack 1979):
///     F_s ← F_s − k_t v_t Δt;  F_d = −c_t v_t;
///     stick (|F_s + F_d| ≤ μ max(F_n, 0)): shear force F_s + F_d (F_d is not history);
///     slip: F_s ← ±μ max(F_n, 0) (sign of F_s + F_d), F_d = 0, so the Coulomb limit holds;
///   elastic–plastic rolling spring with viscous damping (Ai et al. 2011, model C; Iwashita &
///   Oda 1998), for μ_r > 0:
///     k_r = 2.25 μ_r² k_n R*²,  M_r ← M_r − k_r ω_r Δt,  |M_r| ≤ μ_r R* max(F_n, 0),
///     M_d = −η_r 2√(I_r k_r) ω_r while |M_r| is below the limit (0 at the limit);
///   μ_r = 0 gives M_r = M_d = 0.
struct CoulombFrictionRolling {
  /// State after the update: shear force (N/m), rolling moment (N·m/m), rolling damping moment
  /// (N·m/m, not part of the history) and the rolling stiffness k_r (N·m/m per rad, for the step).
  struct Result {
    double shear, roll, roll_damping, kr;
    double shear_damping;  ///< tangential dashpot force F_d (N/m, not part of the history)
  };
  /// \param shear, roll       history of the contact (F_s, M_r) from the last step
  /// \param kt, kn            tangential and normal stiffness of the law at this overlap
  /// \param vt                relative tangential velocity at the contact point (m/s)
  /// \param fn                normal force (N/m; the friction limits use max(F_n, 0))
  /// \param reff              R* of the rolling law (m)
  /// \param omega_r           relative angular velocity ω_i − ω_j (rad/s; ω_i for a wall)
  /// \param rolling_inertia   callable returning I_r (kg·m²/m), called only when it is needed
  /// \param ct                tangential dashpot coefficient (N·s/m/m), 0: none
  template <class RollingInertia>
  static Result update(double shear, double roll, double kt, double kn, double vt, double fn, double reff,
                       double omega_r, double mu, double mu_r, double eta_r, double dt,
                       RollingInertia&& rolling_inertia, double ct = 0.0) noexcept {
    shear -= kt * vt * dt;
    const double limit = mu * std::max(fn, 0.0);
    double fd = -ct * vt;
    if (std::abs(shear + fd) > limit) {
      shear = sign(shear + fd) * limit;
      fd = 0.0;
    }
    double damping = 0.0, kr = 0.0;
    if (mu_r > 0.0) {
      kr = rolling_stiffness(mu_r, kn, reff);
      roll -= kr * omega_r * dt;
      const double mmax = mu_r * reff * std::max(fn, 0.0);
      if (std::abs(roll) >= mmax)
        roll = sign(roll) * mmax;
      else
        damping = -eta_r * 2.0 * std::sqrt(rolling_inertia() * kr) * omega_r;
    } else {
      roll = 0.0;
    }
    return {shear, roll, damping, kr, fd};
  }

 private:
  static double sign(double v) noexcept { return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0); }
};

}  // namespace geohaz::dem
