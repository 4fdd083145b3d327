#pragma once
// Rigid-body view of a set of discs and the planar rigid-body impact at a point (Stronge 2000),
// shared by the corner-impact tests (test_dem_corner.cpp) and the single-block support study
// (test_dem_block_support.cpp).
#include <Eigen/Dense>
#include <cmath>

#include "geohaz/dem/solver.hpp"

namespace geohaz::dem::rigid {

/// Rigid-body state of a set of discs: mass, centre, velocity, spin about the centre (angular
/// momentum / inertia), translational and rotational energy, and the rest of the kinetic energy
/// (internal vibration). Per metre of thickness.
struct RigidState {
  double mass = 0, inertia = 0, omega = 0, ke_trans = 0, ke_rot = 0, ke_internal = 0;
  Vec2 centre = Vec2::Zero(), velocity = Vec2::Zero();
  double angular_momentum = 0;  ///< about the centre
  /// Angular momentum about a fixed point p.
  double angular_momentum_about(const Vec2& p) const {
    const Vec2 r = centre - p;
    return angular_momentum + mass * (r.x() * velocity.y() - r.y() * velocity.x());
  }
  /// Rigid-body velocity of the point p.
  Vec2 point_velocity(const Vec2& p) const { return velocity + omega * Vec2(-(p - centre).y(), (p - centre).x()); }
};

inline RigidState rigid_state(const DemSolver& s) {
  const auto& x = s.discs.get<Position<2>>();
  const auto& v = s.discs.get<Velocity<2>>();
  const auto& w = s.discs.get<AngularVelocity>();
  const auto& m = s.discs.get<Mass>();
  const auto& I = s.discs.get<Inertia>();
  RigidState r;
  double ke = 0;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    r.mass += m[i];
    r.centre += m[i] * x[i];
    r.velocity += m[i] * v[i];
    ke += 0.5 * m[i] * v[i].squaredNorm() + 0.5 * I[i] * w[i] * w[i];
  }
  r.centre /= r.mass;
  r.velocity /= r.mass;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    const Vec2 d = x[i] - r.centre, u = v[i] - r.velocity;
    r.inertia += m[i] * d.squaredNorm() + I[i];
    r.angular_momentum += m[i] * (d.x() * u.y() - d.y() * u.x()) + I[i] * w[i];
  }
  r.omega = r.angular_momentum / r.inertia;
  r.ke_trans = 0.5 * r.mass * r.velocity.squaredNorm();
  r.ke_rot = 0.5 * r.inertia * r.omega * r.omega;
  r.ke_internal = ke - r.ke_trans - r.ke_rot;
  return r;
}

/// Rigid-body impact at point p of flat ground (normal +y, tangent +x), Stronge (2000) §2–3:
/// the contact-point velocity changes by Δu = K P with K = 𝟙/M + r⊥ r⊥ᵀ/I_G, r = p − G,
/// r⊥ = (−r_y, r_x). Sticking (u_t' = 0) with Newton's normal restitution u_n' = −e u_n gives
/// P = K⁻¹ Δu; if |P_t| > μ P_n it slides throughout, P_t = −μ sgn(u_t) P_n, with P_n from the
/// normal condition. Returns the state after.
struct RigidImpact {
  Vec2 velocity;
  double omega, impulse_t, impulse_n;
  bool sticks;
};
inline RigidImpact rigid_impact(const RigidState& b, const Vec2& p, double e, double mu) {
  const Vec2 r = p - b.centre, rp(-r.y(), r.x());
  Eigen::Matrix2d K = Eigen::Matrix2d::Identity() / b.mass + rp * rp.transpose() / b.inertia;
  const Vec2 u = b.point_velocity(p);
  Vec2 P = K.inverse() * Vec2(-u.x(), -(1 + e) * u.y());
  bool sticks = std::abs(P.x()) <= mu * P.y();
  if (!sticks) {
    const double s = u.x() > 0 ? 1.0 : -1.0;
    const double pn = -(1 + e) * u.y() / (K(1, 1) - mu * s * K(1, 0));
    P = Vec2(-mu * s * pn, pn);
  }
  const double dw = (r.x() * P.y() - r.y() * P.x()) / b.inertia;
  return {b.velocity + P / b.mass, b.omega + dw, P.x(), P.y(), sticks};
}

}  // namespace geohaz::dem::rigid
