// Diagnostics of the DEM solver's state (energies, momentum, contacts, grip reactions): read
// once per output, never inside a step.
#include <cmath>
#include <utility>
#include <variant>
#include <vector>

#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {

double DemSolver::kinetic_energy() const {
  const auto& v = discs.get<Velocity<2>>();
  const auto& w = discs.get<AngularVelocity>();
  const auto& m = discs.get<Mass>();
  const auto& I = discs.get<Inertia>();
  double e = 0;
  for (std::size_t i = 0; i < discs.size(); ++i) e += 0.5 * m[i] * v[i].squaredNorm() + 0.5 * I[i] * w[i] * w[i];
  return e;
}

double DemSolver::strain_energy() const {
  double e = 0.0;
  // Contacts: normal spring energy from the overlap (the law's normal_energy), shear ½F_s²/k_s.
  const auto& x = discs.get<Position<2>>();
  const auto& R = discs.get<Radius>();
  const auto& m = discs.get<Mass>();
  const auto off = nb_.list().offsets();
  const auto nbr = nb_.list().indices();
  for (std::size_t i = 0; i < discs.size(); ++i) {
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = nbr[k];
      if (j < i) continue;
      const double delta = R[i] + R[j] - (x[i] - x[j]).norm();
      if (delta <= 0) continue;
      const double reff = R[i] * R[j] / (R[i] + R[j]);
      const double meff = m[i] * m[j] / (m[i] + m[j]);
      std::visit(
          [&](const auto& l) {
            const ContactResponse c = l.evaluate(delta, meff, reff, R[i] + R[j], 0.0);
            e += l.normal_energy(c.fn_elastic, delta);
            const double fs = hist_.partner.size() > k && hist_.partner[k] >= 0 ? hist_.shear[k] : 0.0;
            if (c.kt > 0) e += 0.5 * fs * fs / c.kt;
          },
          law);
    }
  }
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    if (bonds.state[b] != BondState::Intact) continue;
    const double kn = bonds.normal_stiffness[b], ks = bonds.shear_stiffness[b];
    const double A = 2 * bonds.radius[b], In = 2.0 / 3.0 * std::pow(bonds.radius[b], 3);
    e += bonds.normal_force[b] * bonds.normal_force[b] / (2 * kn * A) +
         bonds.shear_force[b] * bonds.shear_force[b] / (2 * ks * A) + bonds.moment[b] * bonds.moment[b] / (2 * kn * In);
  }
  return e;
}

double DemSolver::potential_energy() const {
  const auto& x = discs.get<Position<2>>();
  const auto& m = discs.get<Mass>();
  double e = 0;
  for (std::size_t i = 0; i < discs.size(); ++i) e -= m[i] * settings.gravity.dot(x[i]);
  return e;
}

Vec2 DemSolver::momentum() const {
  const auto& v = discs.get<Velocity<2>>();
  const auto& m = discs.get<Mass>();
  Vec2 p = Vec2::Zero();
  for (std::size_t i = 0; i < discs.size(); ++i) p += m[i] * v[i];
  return p;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> DemSolver::contact_pairs() const {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  const auto& x = discs.get<Position<2>>();
  const auto& R = discs.get<Radius>();
  const auto off = nb_.list().offsets();
  const auto nbr = nb_.list().indices();
  for (std::size_t i = 0; i < discs.size(); ++i)
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = nbr[k];
      if (j <= i) continue;
      const double s = R[i] + R[j];
      if ((x[i] - x[j]).squaredNorm() < s * s) out.emplace_back(static_cast<std::uint32_t>(i), j);
    }
  return out;
}

std::size_t DemSolver::contact_count() const {
  return contact_pairs().size();
}

Vec2 DemSolver::kinematic_group_force(std::uint8_t group) const {
  const auto& F = discs.get<Force>();
  const auto& kin = discs.get<Kinematic>();
  Vec2 s = Vec2::Zero();
  for (std::size_t i = 0; i < discs.size(); ++i)
    if (kin[i] == group) s += F[i];
  return s;
}

}  // namespace geohaz::dem
