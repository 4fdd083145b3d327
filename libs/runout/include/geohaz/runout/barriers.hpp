#pragma once
/// \file barriers.hpp
/// Barriers (check dams, walls, slit and net barriers) across a debris flow (docs/runout.md,
/// "Barriers"): vertical walls along polylines in map view whose crest stands `height` metres above
/// the terrain under the line.
///
/// A particle whose step x → x + Δt v would cross a barrier segment is held by the wall unless its
/// flow surface is above the crest (overtopping) or it is one of the fraction p that passes an open
/// barrier. A held particle is stopped at the wall and its velocity reflected:
///     v_n' = −e v_n,     |v_t'| = max(|v_t| − μ_w (1 + e) v_n, 0)
/// (e: restitution, μ_w: Coulomb friction along the wall, acting with the normal impulse); the rest
/// of its step continues from the wall with v'. The wall takes the momentum ρ V (1 + e) v_n; summed
/// over the particles and divided by the time it is the normal force on the barrier (N). A particle
/// resting against the wall is pushed into it every step by its unbalanced head-pressure force, so
/// the same sum is the hydrostatic load of a pile at rest.
///
/// Overtopping: the particle's flow surface z + h_w/cos θ against the crest z_t(x_c) + H at the
/// crossing point x_c, with h_w = h / F(d/d0) the depth corrected for the part of the kernel support
/// beyond the wall (F: fraction of the 2D cubic spline on the particle's side of a straight wall at
/// distance d; ½ on the wall, 1 from 2 d0), since no mirror particles fill it.
///
/// Open barriers: a particle passes a barrier of permeability p when a hash of its id and the
/// barrier is below p: whole particles (mass conserved), deterministic and independent of the
/// thread count; the volume passed is p × the volume arriving up to the sampling of whole particles.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz::runout {

/// One barrier as given (map coordinates of the DSM's CRS, SI units).
struct Barrier {
  std::string name;            ///< "barrier_<feature>" (file feature id) or set by the caller
  std::int64_t feature = -1;   ///< feature id in the file (messages)
  std::vector<Vec2> vertices;  ///< the line, ≥ 2 vertices (m)
  double height = 0.0;         ///< crest height above the terrain under the line (m)
  double permeability = 0.0;   ///< fraction of the arriving particles that pass (1), [0, 1)
  bool upstream_left = true;   ///< the flow comes from the left of the directed line a → b
  double length() const noexcept;
};

/// How particles meet the walls (the same for every barrier of a run).
struct WallLaw {
  double restitution = 0.0;           ///< e: normal speed after the impact over before (1), [0, 1]
  double friction = 0.0;              ///< μ_w: Coulomb friction along the wall on the normal impulse (1)
  double retention_distance = 100.0;  ///< retained = upstream volume at the end within this distance (m)
};

/// The nearest wall point of a particle within the kernel reach 2 d0 (not at a line's free end).
struct WallProximity {
  int barrier = -1;
  double distance = 0.0;      ///< m
  Vec2 point = Vec2::Zero();  ///< nearest point on the line (m)
  Vec2 away = Vec2::Zero();   ///< unit normal from the wall towards the particle
  double arclength = 0.0;     ///< distance along the line from its first vertex (m)
};

/// Where a particle's step first crosses a barrier.
struct BarrierCrossing {
  int barrier = -1;
  std::size_t segment = 0;
  double t = 0.0;              ///< fraction of the step x0 → x1 at the crossing
  Vec2 point = Vec2::Zero();   ///< crossing point (m)
  Vec2 normal = Vec2::Zero();  ///< unit normal of the segment pointing from x0's side to x1's side
  double arclength = 0.0;      ///< distance along the barrier line from its first vertex (m)
  bool from_upstream = true;   ///< x0 lies on the barrier's upstream side
};

/// The barriers of a run, prepared for the particle loop: segment list, bounding box, bins along
/// each line of at most half a particle spacing (the wetted length is the length of the bins the
/// particles touch).
class BarrierSet {
 public:
  BarrierSet() = default;
  BarrierSet(std::vector<Barrier> barriers, WallLaw law, double d0);

  bool empty() const noexcept { return barriers_.empty(); }
  std::size_t size() const noexcept { return barriers_.size(); }
  const Barrier& operator[](std::size_t b) const noexcept { return barriers_[b]; }
  const std::vector<Barrier>& barriers() const noexcept { return barriers_; }
  const WallLaw& law() const noexcept { return law_; }
  double bin_length(std::size_t b) const noexcept { return bin_length_[b]; }
  std::size_t bins() const noexcept { return bin0_.empty() ? 0 : bin0_.back(); }
  /// Bins of barrier b are [first_bin(b), first_bin(b + 1)).
  std::size_t first_bin(std::size_t b) const noexcept { return bin0_[b]; }
  std::size_t bin_of(const BarrierCrossing& c) const noexcept;

  /// The first barrier segment the step x0 → x1 crosses (x1 on the line counts; x0 on it does
  /// not). Inline box test first: a step far from every barrier costs four comparisons.
  bool first_crossing(const Vec2& x0, const Vec2& x1, BarrierCrossing& c) const noexcept {
    if (barriers_.empty()) return false;
    if (std::max(x0.x(), x1.x()) < lo_.x() || std::min(x0.x(), x1.x()) > hi_.x() ||
        std::max(x0.y(), x1.y()) < lo_.y() || std::min(x0.y(), x1.y()) > hi_.y())
      return false;
    return crossing(x0, x1, c);
  }
  /// Whether p is within the kernel reach of the barriers' bounding box (inline: four comparisons).
  bool near(const Vec2& p) const noexcept {
    return !barriers_.empty() && p.x() >= lo_.x() - reach_ && p.x() <= hi_.x() + reach_ && p.y() >= lo_.y() - reach_ &&
           p.y() <= hi_.y() + reach_;
  }
  /// The nearest wall point within 2 d0 of p, unless it is a free end of its line.
  bool nearest_wall(const Vec2& p, WallProximity& w) const noexcept;
  std::size_t bin_at(std::size_t b, double arclength) const noexcept;
  /// Distance from p to segment k of barrier b (m).
  double distance_to_segment(std::size_t b, std::size_t k, const Vec2& p) const noexcept;
  /// Distance from p to barrier b's line (m) and whether p is on its upstream side.
  double distance(std::size_t b, const Vec2& p, bool& upstream) const noexcept;
  /// Whether particle `id` passes the open barrier b (hash of id and b below its permeability).
  bool passes(std::int64_t id, std::size_t b) const noexcept;

  /// F(s): fraction of the 2D cubic spline's support (h = d0, radius 2 d0) on the particle's side of
  /// a straight wall at distance s·d0; ½ at s = 0, 1 for s ≥ 2.
  static double kernel_fraction(double s) noexcept;
  /// M(s) = ∫ W_f(√(s² + y²)) dy / (C/d0): the head-pressure kernel W_f of head_pressure.hpp
  /// (W_f′(r) = −C f(r/d0)/d0³) integrated along a straight wall at distance s·d0, in units of d0
  /// and without C. A layer of depth h_w mirrored behind the wall pushes a particle at distance s·d0
  /// away from it with g cos θ h_w C M(s)/d0: the pressure of the mirror particles that a wall
  /// without them lacks (zero beyond 2 d0).
  static double mirror_push(double s) noexcept;

 private:
  bool crossing(const Vec2& x0, const Vec2& x1, BarrierCrossing& c) const noexcept;

  std::vector<Barrier> barriers_;
  WallLaw law_;
  std::vector<double> bin_length_;
  std::vector<std::size_t> bin0_;               // size() + 1 entries
  std::vector<std::vector<double>> arclength_;  // per barrier, at each vertex
  Vec2 lo_ = Vec2::Zero(), hi_ = Vec2::Zero();
  double reach_ = 0.0;  // 2 d0
};

/// What the walls have taken so far, per barrier (the solver adds to it in store order, so it is
/// the same for any thread count).
struct BarrierTally {
  std::vector<double> impulse;        ///< Σ ρ V (1 + e) v_n since the start (N·s)
  std::vector<double> passed;         ///< net volume crossed from the upstream side (m³)
  std::vector<double> contacts;       ///< particles held, counted since the start
  std::vector<double> window_depth;   ///< largest depth at the wall h_w (within d0) since the last window reset (m)
  std::vector<std::uint8_t> touched;  ///< per bin: touched since the last window reset
};

}  // namespace geohaz::runout
