#pragma once
/// \file walls.hpp
/// Rigid straight walls and terrain polylines the discs touch.
///  - WallSegment: a straight segment with its own friction and restitution, moving with a
///    prescribed velocity, or servo-controlled on a target normal stress (Itasca's servo:
///    v = G (σ_measured − σ_target), G = α L / (Σk_n Δt), α < 1).
///  - Terrain polylines are many static segments; they are binned along x for lookup.
/// Contact with a segment uses the closest point of the segment (interior or end point); at a
/// vertex shared by two polyline segments the vertex counts once, so a disc resting across a vertex
/// has two contacts only where the polyline is concave (and one on a straight or convex vertex).

#include <cstdint>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz::dem {

enum class WallControl : std::uint8_t { Velocity, Servo };

struct WallSegment {
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();  ///< end points (m)
  Vec2 velocity = Vec2::Zero();             ///< prescribed velocity (m/s), or servo output
  double friction = 0.5;                    ///< μ of disc–wall contacts
  double restitution = 0.5;                 ///< e of disc–wall contacts
  double rolling_friction = -1.0;           ///< μ_r of disc–wall contacts (< 0: the discs' contact μ_r)
  WallControl control = WallControl::Velocity;
  Vec2 servo_normal = Vec2::Zero();  ///< unit normal pointing into the sample (servo only)
  double target_stress = 0.0;        ///< servo target compressive normal stress (Pa)
  double servo_gain = 0.5;           ///< α ∈ (0, 1)
  double max_speed = 1.0;            ///< servo speed cap (m/s)
  double loaded_length = 0.0;        ///< length over which the servo stress is measured (0: length)
  bool active = true;                ///< false: removed (e.g. a support taken away)
  bool joined_prev = false;          ///< a polyline neighbour shares this segment's a
  bool joined_next = false;          ///< a polyline neighbour shares this segment's b
  // Measured in the last step:
  Vec2 force = Vec2::Zero();  ///< force of the discs on the wall (N/m)
  double stiffness = 0.0;     ///< Σ k_n of its contacts (N/m/m)
  int contacts = 0;

  double length() const noexcept { return (b - a).norm(); }
  /// Compressive normal stress on the wall (Pa), from the last step's force and the current length
  /// of the part of the wall in contact, taken as `loaded_length` when given (>0) else the length.
  double normal_stress(double loaded_length = 0.0) const noexcept;
};

/// Parameter u of the projection of p on the line a + u (b − a), unclamped.
inline double segment_parameter(const Vec2& a, const Vec2& b, const Vec2& p) noexcept {
  const Vec2 ab = b - a;
  const double l2 = ab.squaredNorm();
  return l2 > 0 ? (p - a).dot(ab) / l2 : 0.0;
}

/// Closest point of segment [a, b] to p.
inline Vec2 closest_point_on_segment(const Vec2& a, const Vec2& b, const Vec2& p) noexcept {
  const Vec2 ab = b - a;
  const double l2 = ab.squaredNorm();
  double t = l2 > 0 ? (p - a).dot(ab) / l2 : 0.0;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  return a + t * ab;
}

/// Static terrain made of polylines, binned along x so a disc looks up only nearby segments.
class TerrainSegments {
 public:
  /// Add a polyline (≥ 2 vertices) with its friction, restitution and rolling resistance
  /// (< 0: the discs' contact μ_r).
  void add_polyline(const std::vector<Vec2>& pts, double friction, double restitution, double rolling_friction = -1.0);
  /// Build the x-bins; max_reach is the largest disc radius (m).
  void build(double max_reach);
  std::size_t size() const noexcept { return segs_.size(); }
  const WallSegment& segment(std::size_t k) const noexcept { return segs_[k]; }
  /// Segments whose x-range (expanded by max_reach) covers x: [begin, end) into index().
  std::pair<const std::uint32_t*, const std::uint32_t*> candidates(double x) const noexcept;
  /// Whether a disc whose centre stays within dx of p along each axis (its drift since p) could be
  /// within reach of a segment that candidates() lists for its position: a segment of the bins of
  /// [p.x − dx, p.x + dx] whose bounding box grown by reach + dx holds p.
  bool near(const Vec2& p, double dx, double reach) const noexcept;
  /// Terrain elevation (highest segment) under x, or NaN.
  double elevation(double x) const noexcept;
  const std::vector<WallSegment>& segments() const noexcept { return segs_; }

 private:
  std::vector<WallSegment> segs_;
  double x0_ = 0, dx_ = 1;
  std::vector<std::uint32_t> start_, index_;
};

}  // namespace geohaz::dem
