#include "geohaz/dem/packing.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "geohaz/core/errors.hpp"
#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {

namespace {

/// Random sequential addition of discs of radii s·r (largest first) in [0,W]×[0,H] without overlap.
/// Returns false when a disc cannot be placed within the attempt budget.
bool random_sequential_addition(const std::vector<double>& r, double s, double W, double H, std::mt19937_64& rng,
                                std::vector<Vec2>& out) {
  const double cell = 2.0 * s * r.front();
  const int nx = std::max(1, static_cast<int>(W / cell)), ny = std::max(1, static_cast<int>(H / cell));
  std::vector<std::vector<std::uint32_t>> grid(static_cast<std::size_t>(nx * ny));
  out.clear();
  std::uniform_real_distribution<double> ux(0.0, 1.0);
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double ri = s * r[i];
    bool placed = false;
    for (int attempt = 0; attempt < 5000 && !placed; ++attempt) {
      const Vec2 p(ri + (W - 2 * ri) * ux(rng), ri + (H - 2 * ri) * ux(rng));
      const int cx = std::clamp(static_cast<int>(p.x() / W * nx), 0, nx - 1);
      const int cy = std::clamp(static_cast<int>(p.y() / H * ny), 0, ny - 1);
      bool ok = true;
      for (int gy = std::max(0, cy - 1); gy <= std::min(ny - 1, cy + 1) && ok; ++gy)
        for (int gx = std::max(0, cx - 1); gx <= std::min(nx - 1, cx + 1) && ok; ++gx)
          for (std::uint32_t j : grid[static_cast<std::size_t>(gy * nx + gx)]) {
            const double d = ri + s * r[j];
            if ((p - out[j]).squaredNorm() < d * d) {
              ok = false;
              break;
            }
          }
      if (!ok) continue;
      grid[static_cast<std::size_t>(cy * nx + cx)].push_back(static_cast<std::uint32_t>(i));
      out.push_back(p);
      placed = true;
    }
    if (!placed) return false;
  }
  return true;
}

/// Mean |F|/(m g_ref) style measure: ratio of the mean resultant force to the mean contact force.
double unbalanced_ratio(const DemSolver& s) {
  const auto& F = s.discs.get<Force>();
  const auto& K = s.discs.get<StiffnessSum>();
  double sf = 0, sk = 0;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    sf += F[i].norm();
    sk += K[i][0];
  }
  (void)sk;
  double fc = 0;
  for (const auto& w : s.walls) fc += w.force.norm();
  return fc > 0 ? sf / fc : 1.0;
}

/// Kill the kinetic energy: the expansion is driven much faster than the discs can rearrange, so
/// velocities are zeroed every few steps (a quasi-static descent) instead of waiting for damping.
void quench(DemSolver& s) {
  s.discs.get<Velocity<2>>().assign(s.discs.size(), Vec2::Zero());
  s.discs.get<AngularVelocity>().assign(s.discs.size(), 0.0);
}

}  // namespace

PackedSample pack_discs_in_box(const PackingSpec& spec, const ContactLaw& law) {
  if (!(spec.r_min > 0) || !(spec.r_max >= spec.r_min)) throw std::invalid_argument("packing: need 0 < r_min ≤ r_max");
  if (!(spec.porosity > 0.05 && spec.porosity < 0.6))
    throw std::invalid_argument("packing: porosity must be in (0.05, 0.6)");
  const double W = spec.width, H = spec.height;
  std::mt19937_64 rng(spec.seed);
  std::uniform_real_distribution<double> ur(spec.r_min, spec.r_max);
  const double solid = (1.0 - spec.porosity) * W * H;
  std::vector<double> radii;
  double area = 0;
  while (area < solid) {
    const double r = ur(rng);
    if (area + std::numbers::pi * r * r > solid && !radii.empty()) break;
    radii.push_back(r);
    area += std::numbers::pi * r * r;
    if (radii.size() > 20'000'000) throw std::invalid_argument("packing: too many discs (> 2e7)");
  }
  std::sort(radii.begin(), radii.end(), std::greater<>());
  // Reduced radius factor: RSA reaches ~0.45 solid fraction easily; start at 0.35.
  double s = std::sqrt(0.35 / (1.0 - spec.porosity));
  std::vector<Vec2> pos;
  while (!random_sequential_addition(radii, s, W, H, rng, pos)) s *= 0.95;

  DemSolver solver;
  solver.law = law;
  solver.contact.friction = 0.0;
  solver.contact.restitution = 0.5;
  solver.settings.gravity = Vec2::Zero();
  solver.settings.local_damping = 0.7;
  solver.settings.safety_factor = 0.3;
  for (std::size_t i = 0; i < radii.size(); ++i) add_disc(solver.discs, pos[i], s * radii[i], spec.density);
  const std::array<std::array<Vec2, 2>, 4> sides{{{Vec2(-W, 0), Vec2(2 * W, 0)},
                                                  {Vec2(W, -H), Vec2(W, 2 * H)},
                                                  {Vec2(2 * W, H), Vec2(-W, H)},
                                                  {Vec2(0, 2 * H), Vec2(0, -H)}}};
  const std::array<Vec2, 4> inward{Vec2(0, 1), Vec2(-1, 0), Vec2(0, -1), Vec2(1, 0)};
  for (int k = 0; k < 4; ++k) {
    WallSegment w;
    w.a = sides[k][0];
    w.b = sides[k][1];
    w.friction = 0.0;
    w.servo_normal = inward[k];
    solver.walls.push_back(w);
  }
  // Radius expansion. Radii are final (cut-off from R_max) from the start of the neighbour search;
  // the list is simply rebuilt after each expansion increment.
  auto& R = solver.discs.get<Radius>();
  auto& m = solver.discs.get<Mass>();
  auto& I = solver.discs.get<Inertia>();
  const auto& ids = solver.discs.get<ParticleId>();
  solver.initialise();
  const int ne = std::max(1, spec.expansion_steps);
  for (int k = 1; k <= ne; ++k) {
    const double f = s + (1.0 - s) * static_cast<double>(k) / ne;
    for (std::size_t i = 0; i < solver.discs.size(); ++i) {
      const double r = f * radii[static_cast<std::size_t>(ids[i])];
      R[i] = r;
      m[i] = spec.density * std::numbers::pi * r * r;
      I[i] = 0.5 * m[i] * r * r;
    }
    if (k % 50 == 0 || k == ne) solver.initialise();
    solver.step();
    if (k % 10 == 0) quench(solver);
  }
  for (int k = 0; k < spec.max_relax_steps; ++k) {
    solver.step();
    if (k % 10 == 0 && k < spec.max_relax_steps / 2) quench(solver);
    if (k > 200 && k % 100 == 0 && unbalanced_ratio(solver) < 1e-3) break;
  }
  // Isotropic locked-in stress by servo walls. The wall stiffness seen by the servo is that of
  // its own contacts, stiffer than the packing behind them, so the gain is kept low (α = 0.05) and
  // the speed capped; convergence is judged on stresses averaged over a window of steps.
  std::array<double, 4> mean_stress{};
  if (spec.locked_in_stress > 0) {
    for (auto& w : solver.walls) {
      w.control = WallControl::Servo;
      w.target_stress = spec.locked_in_stress;
      w.servo_gain = 0.05;
      w.max_speed = 5e-5 * spec.r_min / std::max(solver.time_step(), 1e-12);  // 5e-5 R_min per step
    }
    std::array<double, 4> acc{};
    int nacc = 0;
    const int window = 250;
    for (int k = 1; k <= spec.max_relax_steps; ++k) {
      const double Wc = solver.walls[1].a.x() - solver.walls[3].a.x();
      const double Hc = solver.walls[2].a.y() - solver.walls[0].a.y();
      for (int q = 0; q < 4; ++q) solver.walls[q].loaded_length = (q % 2 == 0) ? Wc : Hc;
      solver.step();
      for (int q = 0; q < 4; ++q) acc[q] += solver.walls[q].normal_stress(solver.walls[q].loaded_length);
      ++nacc;
      if (k % window == 0) {
        bool ok = true;
        for (int q = 0; q < 4; ++q) {
          mean_stress[q] = acc[q] / nacc;
          ok = ok && std::abs(mean_stress[q] - spec.locked_in_stress) < 0.05 * spec.locked_in_stress;
        }
        acc = {};
        nacc = 0;
        if (ok) break;
        // Integral correction: the chattering wall contacts bias the mean stress low.
        for (int q = 0; q < 4; ++q)
          solver.walls[q].target_stress =
              std::max(0.1 * spec.locked_in_stress,
                       solver.walls[q].target_stress + 0.7 * (spec.locked_in_stress - mean_stress[q]));
      }
    }
    for (auto& w : solver.walls) {
      w.control = WallControl::Velocity;
      w.velocity.setZero();
    }
  }
  PackedSample out;
  // Shift so the container's lower-left corner is the origin.
  const Vec2 origin(solver.walls[3].a.x(), solver.walls[0].a.y());
  out.width = solver.walls[1].a.x() - origin.x();
  out.height = solver.walls[2].a.y() - origin.y();
  for (auto& x : solver.discs.get<Position<2>>()) x -= origin;
  for (auto& w : solver.walls) {
    w.a -= origin;
    w.b -= origin;
  }
  out.stress_x = 0.5 * (mean_stress[1] + mean_stress[3]);
  out.stress_y = 0.5 * (mean_stress[0] + mean_stress[2]);
  // Reset the dynamic state and sort by id, so the sample is independent of the packing history.
  std::vector<std::uint32_t> perm(solver.discs.size());
  for (std::size_t i = 0; i < perm.size(); ++i) perm[static_cast<std::size_t>(ids[i])] = static_cast<std::uint32_t>(i);
  solver.discs.reorder(perm);
  solver.discs.get<Velocity<2>>().assign(solver.discs.size(), Vec2::Zero());
  solver.discs.get<AngularVelocity>().assign(solver.discs.size(), 0.0);
  solver.discs.get<Rotation>().assign(solver.discs.size(), 0.0);
  for (auto& wc : solver.discs.get<WallContacts>()) {
    wc.setZero();
    wc.row(0).setConstant(-1.0);
  }
  double solid_area = 0;
  for (double r : solver.discs.get<Radius>()) solid_area += std::numbers::pi * r * r;
  out.porosity = 1.0 - solid_area / (out.width * out.height);
  out.coordination = coordination_number(solver.discs);
  for (auto& w : solver.walls) w.friction = spec.friction_after;
  out.walls = solver.walls;
  out.discs = std::move(solver.discs);
  return out;
}

std::size_t install_parallel_bonds(const DiscStore& discs,
                                   const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges,
                                   const ParallelBondProperties& props, double gap_tolerance, std::uint64_t seed,
                                   BondTable& bonds) {
  const auto& x = discs.get<Position<2>>();
  const auto& R = discs.get<Radius>();
  const auto& id = discs.get<ParticleId>();
  std::mt19937_64 rng(seed ^ 0x9E3779B97F4A7C15ULL);
  std::normal_distribution<double> sig(props.tensile_strength, props.tensile_strength_std);
  std::normal_distribution<double> tau(props.shear_strength, props.shear_strength_std);
  std::size_t added = 0;
  for (const auto& [a, b] : edges) {
    const double d = (x[a] - x[b]).norm();
    const double rmin = std::min(R[a], R[b]);
    if (d - R[a] - R[b] > gap_tolerance * rmin) continue;
    double sc = props.tensile_strength_std > 0 ? sig(rng) : props.tensile_strength;
    double tc = props.shear_strength_std > 0 ? tau(rng) : props.shear_strength;
    sc = std::max(sc, 0.01 * props.tensile_strength);
    tc = std::max(tc, 0.01 * props.shear_strength);
    const double kn = props.modulus / (R[a] + R[b]);
    bonds.add(id[a], id[b], props.radius_multiplier * rmin, d, kn, kn / props.stiffness_ratio, sc, tc);
    ++added;
  }
  return added;
}

double coordination_number(const DiscStore& discs) {
  if (discs.empty()) return 0;
  const auto& x = discs.get<Position<2>>();
  const auto& R = discs.get<Radius>();
  const double rmax = *std::max_element(R.begin(), R.end());
  NeighbourList<2> list;
  list.build(x, 2 * rmax);
  std::size_t c = 0;
  for (std::size_t i = 0; i < discs.size(); ++i)
    for (std::uint32_t j : list.neighbours(i)) {
      const double s = R[i] + R[j];
      if ((x[i] - x[j]).squaredNorm() < s * s) ++c;
    }
  return static_cast<double>(c) / static_cast<double>(discs.size());
}

}  // namespace geohaz::dem
