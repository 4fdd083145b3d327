#pragma once
/// \file processes.hpp
/// The processes of a real catchment besides gravity, head pressure and basal friction
/// (docs/runout.md, "Processes"):
///  - friction that varies in space: any coefficient of the basal law from a field over the map,
///    the global value where the field has none;
///  - forest (or any resistance area): an extra velocity-squared drag k_f |v|², k_f = ½ C_D n d
///    for n stems per m² of diameter d (emergent cylinder array, Nepf 1999);
///  - entrainment of an erodible bed layer, by one of two rate laws, joining the flow at rest;
///  - inflow hydrographs: particles injected at a point or short line with a discharge Q(t).
/// Fields are cell values on one north-up grid (the DSM's in a run), looked up at the cell holding
/// a particle: per-particle look-ups, no pair work.

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "geohaz/core/law_parameters.hpp"
#include "geohaz/core/vec.hpp"
#include "geohaz/runout/basal_friction.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {

/// The coefficients a friction field can set (each law reads those it has): the zone slots, by
/// the key a law declares in its `parameters` (friction_terms.hpp), which gives range and unit.
enum FrictionParameter : int {
  kManningN,
  kCriticalSlope,
  kYieldExponent,
  kCoulombMu,
  kVoellmyXi,
  kCohesion,
  kYieldStress,
  kViscosity,
  kConsistency,
  kFlowIndex,
  kDelta1,
  kDelta2,
  kFrictionParameters
};
/// Config names of the coefficients, as in model.<name> (zones.<name>, attributes <name>).
inline constexpr std::array<const char*, kFrictionParameters> kFrictionParameterNames{
    "n", "icr", "m", "mu", "xi", "cohesion", "tau_y", "viscosity", "consistency", "flow_index", "delta1", "delta2"};

/// For each zone slot, the index of that key in Law::parameters (-1: the law has none).
template <class Law>
inline constexpr std::array<int, kFrictionParameters> kZoneParameterIndex = [] {
  std::array<int, kFrictionParameters> j{};
  for (std::size_t k = 0; k < j.size(); ++k) j[k] = parameter_index<Law>(kFrictionParameterNames[k]);
  return j;
}();

/// The declaration of zone slot k (the first law's that reads it; laws sharing a key share it).
inline const ParamSpec& zone_parameter(int k) noexcept {
  static const std::array<ParamSpec, kFrictionParameters> specs = [] {
    std::array<ParamSpec, kFrictionParameters> out{};
    const auto keys = BasalFrictionParameters::keys();
    for (std::size_t i = 0; i < out.size(); ++i)
      for (const auto& key : keys)
        if (key.spec.key == kFrictionParameterNames[i]) {
          out[i] = key.spec;
          break;
        }
    return out;
  }();
  return specs[static_cast<std::size_t>(k)];
}

/// Set coefficient k of a law from a field value (in the unit of its declaration: δ in degrees);
/// false (and nothing set) when the law has no such coefficient (the config refuses a field for it).
template <class Law>
inline bool set_parameter(Law& l, int k, double v) noexcept {
  const int j = kZoneParameterIndex<Law>[static_cast<std::size_t>(k)];
  return j >= 0 && l.set(static_cast<std::size_t>(j), v);
}
/// Whether the law held by f has coefficient k.
inline bool has_parameter(const BasalFriction& f, int k) noexcept {
  return std::visit([k](auto l) { return set_parameter(l, k, 1.0); }, f);
}

/// Whether a law's per-particle step memory (friction_terms.hpp, StepMemory) stays valid under the
/// friction fields `friction` (by FrictionParameter; empty: none): Herschel–Bulkley keeps
/// (ζ, (ζ/K)^{1/n}), which a field of K or n would make inconsistent when a particle crosses into
/// it; the other laws keep none.
template <class Law, class Fields>
bool step_memory_valid(const Law& /*law*/, const Fields& /*friction*/) noexcept {
  return true;
}
template <class Fields>
bool step_memory_valid(const HerschelBulkleyFriction& /*law*/, const Fields& friction) noexcept {
  return friction[kConsistency].empty() && friction[kFlowIndex].empty();
}

/// How the bed is eroded (docs/runout.md, "Entrainment").
enum class EntrainmentLaw {
  None,
  /// dV/ds = E_s V inside erodible areas (McDougall & Hungr 2005): each particle grows by the
  /// factor exp(E_s Δs) over a surface path increment Δs.
  GrowthRate,
  /// ė = k_e (τ_b − τ_c)⁺ (m/s of bed depth) where the basal shear stress τ_b exceeds τ_c
  /// (RAMMS-type excess-shear law); a particle of bed area A = V/h_n takes ė A Δt.
  ShearStress
};
const char* to_string(EntrainmentLaw law) noexcept;

/// Rate-law coefficients (SI).
struct EntrainmentParameters {
  EntrainmentLaw law = EntrainmentLaw::None;
  double growth_rate = 0.0;          ///< E_s (1/m)
  double critical_shear = 0.0;       ///< τ_c (Pa)
  double erosion_coefficient = 0.0;  ///< k_e (m/(s·Pa))
};

/// An inflow hydrograph: discharge Q(t) (m³/s, linear between the rows, zero outside them)
/// entering at a point (a = b) or across a short line a–b, in the map direction `direction`, with
/// the surface speed `speed`.
struct Hydrograph {
  std::string source;  ///< the file it came from (messages)
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();
  Vec2 direction = Vec2(1.0, 0.0);  ///< unit map vector
  double speed = 5.0;               ///< m/s
  std::vector<double> time;         ///< s, strictly increasing
  std::vector<double> discharge;    ///< m³/s, ≥ 0

  /// ∫₀ᵗ Q dt (m³): exact for the piecewise-linear table.
  double volume_until(double t) const noexcept {
    double v = 0.0;
    for (std::size_t k = 0; k + 1 < time.size(); ++k) {
      const double t0 = time[k], t1 = time[k + 1];
      if (t <= t0) break;
      const double te = std::min(t, t1);
      const double qe = discharge[k] + (discharge[k + 1] - discharge[k]) * (te - t0) / (t1 - t0);
      v += 0.5 * (discharge[k] + qe) * (te - t0);
    }
    return v;
  }
  double volume() const noexcept { return time.empty() ? 0.0 : volume_until(time.back()); }
  double end_time() const noexcept { return time.empty() ? 0.0 : time.back(); }
  /// The time at which ∫Q reaches `v` (≤ volume()), by bisection (s).
  double time_of_volume(double v) const noexcept {
    double lo = time.front(), hi = time.back();
    for (int it = 0; it < 80 && hi - lo > 1e-12 * std::max(1.0, hi); ++it) {
      const double mid = 0.5 * (lo + hi);
      (volume_until(mid) < v ? lo : hi) = mid;
    }
    return hi;
  }
};

/// Fields over one north-up grid (NaN or empty: none there) and the inflows of a run.
struct SpatialProcesses {
  GridGeometry grid;
  /// Friction coefficient fields by FrictionParameter (empty vector: the global value everywhere).
  std::array<std::vector<double>, kFrictionParameters> friction;
  /// Forest drag k_f (1/m): extra deceleration k_f |v|² (empty: no forest).
  std::vector<double> forest_drag;
  /// Erodible depth still available (m, vertical); lowered as the bed is eroded (empty: none).
  std::vector<double> erodible_depth;
  std::vector<Hydrograph> inflows;

  bool has_friction_fields() const noexcept {
    for (const auto& f : friction)
      if (!f.empty()) return true;
    return false;
  }
  bool has_cell_fields() const noexcept {
    return has_friction_fields() || !forest_drag.empty() || !erodible_depth.empty();
  }
  /// Cell index of p, or npos outside the grid.
  static constexpr std::size_t npos = std::numeric_limits<std::size_t>::max();
  std::size_t cell(const Vec2& p) const noexcept {
    int c, r;
    return grid.cell_of(p, c, r) ? grid.index(c, r) : npos;
  }
  /// The law of `global` with the coefficients of cell k where the fields hold a value.
  template <class Law>
  Law law_at(const Law& global, std::size_t k) const noexcept {
    Law l = global;
    if (k == npos) return l;
    for (int p = 0; p < kFrictionParameters; ++p) {
      const auto& f = friction[static_cast<std::size_t>(p)];
      if (!f.empty() && std::isfinite(f[k])) set_parameter(l, p, f[k]);
    }
    return l;
  }
};

}  // namespace geohaz::runout
