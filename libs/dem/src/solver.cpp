#include "geohaz/dem/solver.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <tuple>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/parallel.hpp"

namespace geohaz::dem {

namespace {

/// Below this many discs (or bonds) a loop runs on one thread: fork/join costs more than it saves.

inline Vec2 perp(const Vec2& n) noexcept {
  return Vec2(-n.y(), n.x());
}
inline double sgn(double v) noexcept {
  return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
}

/// Index of a law type in the ContactLaw variant.
template <class Law, std::size_t I = 0>
constexpr std::size_t law_index_of() {
  if constexpr (std::is_same_v<Law, std::variant_alternative_t<I, ContactLaw>>)
    return I;
  else
    return law_index_of<Law, I + 1>();
}

/// (ζ + √(1+ζ²))² for the dashpot a law builds from damping parameter z: a stiffness k with this
/// dashpot limits the explicit time step like k·factor without one (see wall_forces).
template <class Law>
double dashpot_step_factor(const Law& law, double z) {
  const ContactResponse c = law.evaluate(1e-3, 1.0, 1.0, 2.0, z);  // ζ of both laws is independent of δ, m
  const double zeta = c.cn / (2.0 * std::sqrt(c.kn));
  const double g = zeta + std::sqrt(1.0 + zeta * zeta);
  return g * g;
}

/// Whether terrain segment k owns the contact of a disc at x. A vertex shared by two segments of a
/// polyline is one contact, not two: a segment whose closest point is its start skips it (the
/// previous segment owns the vertex), and one whose closest point is its end keeps it only if the
/// disc is past the start of the next segment too (convex vertex). Interior points of both
/// (concave vertex) both count.
bool owns_contact(const TerrainSegments& terrain, std::size_t k, const Vec2& x) {
  const WallSegment& s = terrain.segment(k);
  if (!s.joined_prev && !s.joined_next) return true;
  const double u = segment_parameter(s.a, s.b, x);
  if (u <= 0.0 && s.joined_prev) return false;
  if (u >= 1.0 && s.joined_next) {
    const WallSegment& nx = terrain.segment(k + 1);
    if (segment_parameter(nx.a, nx.b, x) > 0.0) return false;
  }
  return true;
}

}  // namespace

std::size_t add_disc(DiscStore& s, const Vec2& x, double r, double rho, std::int64_t id) {
  const std::size_t i = s.append(1);
  const double m = rho * std::numbers::pi * r * r;
  s.get<Position<2>>()[i] = x;
  s.get<PositionAtBuild>()[i] = x;
  s.get<Radius>()[i] = r;
  s.get<Mass>()[i] = m;
  s.get<Inertia>()[i] = 0.5 * m * r * r;
  s.get<ParticleId>()[i] = id >= 0 ? id : static_cast<std::int64_t>(i);
  auto& wc = s.get<WallContacts>()[i];
  wc.setZero();
  wc.row(0).setConstant(-1.0);
  return i;
}

std::size_t BondTable::intact_count() const noexcept {
  return static_cast<std::size_t>(std::count(state.begin(), state.end(), BondState::Intact));
}

void BondTable::add(std::int64_t a, std::int64_t b, double r, double d0, double kn, double ks, double sigma_c,
                    double tau_c) {
  id_a.push_back(a);
  id_b.push_back(b);
  radius.push_back(r);
  rest_length.push_back(d0);
  normal_stiffness.push_back(kn);
  shear_stiffness.push_back(ks);
  shear_force.push_back(0.0);
  moment.push_back(0.0);
  normal_force.push_back(0.0);
  tensile_strength.push_back(sigma_c);
  shear_strength.push_back(tau_c);
  state.push_back(BondState::Intact);
  force_on_a.push_back(Vec2::Zero());
  torque_on_a.push_back(0.0);
  torque_on_b.push_back(0.0);
}

// ---------------------------------------------------------------------------------------------
// Setup and indices

void DemSolver::set_joints(std::vector<JointPair> joints) {
  joints_ = std::move(joints);
  rebuild_joint_index();
}

void DemSolver::rebuild_id_index() {
  const auto& ids = discs.get<ParticleId>();
  std::int64_t max_id = -1;
  for (auto id : ids) max_id = std::max(max_id, id);
  index_of_id_.assign(static_cast<std::size_t>(max_id + 1), std::numeric_limits<std::uint32_t>::max());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] < 0) throw std::invalid_argument("DemSolver: negative disc id");
    if (index_of_id_[ids[i]] != std::numeric_limits<std::uint32_t>::max())
      throw std::invalid_argument("DemSolver: duplicate disc id " + std::to_string(ids[i]));
    index_of_id_[ids[i]] = static_cast<std::uint32_t>(i);
  }
}

void DemSolver::rebuild_bond_index() {
  const std::size_t nid = index_of_id_.size();
  bond_offsets_.assign(nid + 1, 0);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    if (bonds.id_a[b] < 0 || bonds.id_b[b] < 0 || static_cast<std::size_t>(bonds.id_a[b]) >= nid ||
        static_cast<std::size_t>(bonds.id_b[b]) >= nid)
      throw std::invalid_argument("DemSolver: bond " + std::to_string(b) + " names an unknown disc id");
    ++bond_offsets_[bonds.id_a[b] + 1];
    ++bond_offsets_[bonds.id_b[b] + 1];
  }
  for (std::size_t k = 0; k < nid; ++k) bond_offsets_[k + 1] += bond_offsets_[k];
  bond_entries_.resize(bond_offsets_[nid]);
  std::vector<std::uint32_t> fill(bond_offsets_.begin(), bond_offsets_.end() - 1);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    bond_entries_[fill[bonds.id_a[b]]++] = static_cast<std::int64_t>(b);
    bond_entries_[fill[bonds.id_b[b]]++] = -static_cast<std::int64_t>(b) - 1;
  }
  const std::size_t nb = bonds.size();
  bonds.force_on_a.resize(nb, Vec2::Zero());
  bonds.torque_on_a.resize(nb, 0.0);
  bonds.torque_on_b.resize(nb, 0.0);
  bonds.normal_force.resize(nb, 0.0);
}

void DemSolver::rebuild_joint_index() {
  const std::size_t nid = index_of_id_.size();
  joint_offsets_.assign(nid + 1, 0);
  for (const auto& j : joints_) {
    if (j.id_a < 0 || j.id_b < 0 || static_cast<std::size_t>(std::max(j.id_a, j.id_b)) >= nid) continue;
    ++joint_offsets_[j.id_a + 1];
    ++joint_offsets_[j.id_b + 1];
  }
  for (std::size_t k = 0; k < nid; ++k) joint_offsets_[k + 1] += joint_offsets_[k];
  joint_entries_.resize(joint_offsets_[nid]);
  std::vector<std::uint32_t> fill(joint_offsets_.begin(), joint_offsets_.end() - 1);
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const auto& j = joints_[k];
    if (j.id_a < 0 || j.id_b < 0 || static_cast<std::size_t>(std::max(j.id_a, j.id_b)) >= nid) continue;
    joint_entries_[fill[j.id_a]++] = static_cast<std::uint32_t>(k);
    joint_entries_[fill[j.id_b]++] = static_cast<std::uint32_t>(k);
  }
}

void DemSolver::initialise() {
  if (discs.empty()) throw std::invalid_argument("DemSolver: no discs");
  rebuild_id_index();
  rebuild_bond_index();
  rebuild_joint_index();
  const auto& R = discs.get<Radius>();
  const double rmax = *std::max_element(R.begin(), R.end());
  const double rmin = *std::min_element(R.begin(), R.end());
  rmax_ = rmax;
  skin_ = settings.skin > 0 ? settings.skin : 0.3 * rmin;
  cutoff_ = 2.0 * rmax + skin_;
  NeighbourSettings<2> ns;
  ns.cutoff = 2.0 * rmax;  // list cut-off 2 R_max + skin, as cutoff_
  ns.skin = skin_;
  ns.reorder_every = settings.reorder_every;
  ns.half_list = true;  // each pair once, from its lower index (pair_forces)
  nb_.configure(ns);
  double reach = rmax;
  terrain.build(reach);
  damping_law_ = SIZE_MAX;  // terrain or walls may have been replaced: recompute their damping
  std::visit([&](const auto& l) { update_wall_damping(l); }, law);
  // Keep the contact history across re-initialisation when the layout is unchanged.
  if (hist_.offsets.size() != discs.size() + 1) {
    hist_ = {};
    hist_.offsets.assign(discs.size() + 1, 0);
  }
  update_neighbours(-1.0);  // configure() asked for a rebuild
  same_layout_ = false;
  near_valid_ = false;
  update_time_step();
}

void DemSolver::update_neighbours(double max_drift) {
  // The core Neighbours object decides (drift > skin/2 since the last build) and reorders by cell
  // at every reorder_every-th rebuild; the contact histories follow the permutation.
  const auto u = nb_.update(discs.get<Position<2>>(), discs.get<PositionAtBuild>(), max_drift);
  if (!u.rebuilt) return;
  if (u.reordered()) reorder(u.permutation);
  same_layout_ = false;
  near_valid_ = false;  // the wall candidates go with the positions of the build
  // The reaction window of the half-pair pass: the largest j − i of a listed pair (all j > i),
  // found by the list build.
  pair_blocks_ = PairBlocks::choose(nb_.size(), nb_.list().forward_reach());
}

void DemSolver::reorder(std::span<const std::uint32_t> order) {
  ++reorders_;  // the fragment labels (update_fragments) are per index
  perm_scratch_.assign(order.begin(), order.end());
  discs.reorder(perm_scratch_);
  // Move each disc's history segment with it.
  const std::size_t n = discs.size();
  PairHistory h;
  h.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t o = perm_scratch_[i];
    h.offsets[i + 1] = h.offsets[i] + (hist_.offsets[o + 1] - hist_.offsets[o]);
  }
  h.partner.resize(h.offsets[n]);
  h.shear.resize(h.offsets[n]);
  h.roll.resize(h.offsets[n]);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t o = perm_scratch_[i];
    std::copy(hist_.partner.begin() + hist_.offsets[o], hist_.partner.begin() + hist_.offsets[o + 1],
              h.partner.begin() + h.offsets[i]);
    std::copy(hist_.shear.begin() + hist_.offsets[o], hist_.shear.begin() + hist_.offsets[o + 1],
              h.shear.begin() + h.offsets[i]);
    std::copy(hist_.roll.begin() + hist_.offsets[o], hist_.roll.begin() + hist_.offsets[o + 1],
              h.roll.begin() + h.offsets[i]);
  }
  hist_ = std::move(h);
  rebuild_id_index();
}

// ---------------------------------------------------------------------------------------------
// Forces (the disc–disc contacts, pair_forces, are in solver_pairs.cpp)

void DemSolver::bond_forces() {
  const std::size_t nb = bonds.size();
  if (nb == 0) return;
  const auto& x = discs.get<Position<2>>();
  const auto& v = discs.get<Velocity<2>>();
  const auto& w = discs.get<AngularVelocity>();
  const auto& R = discs.get<Radius>();
  const double dt = dt_;
  const int nthreads = omp_get_max_threads();
  std::vector<std::vector<AcousticEvent>> local(static_cast<std::size_t>(nthreads));
#pragma omp parallel if (parallel_worth(nb))
  {
    auto& ev = local[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (std::int64_t bb = 0; bb < static_cast<std::int64_t>(nb); ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      if (bonds.state[b] != BondState::Intact) continue;
      const std::uint32_t ia = index_of_id_[bonds.id_a[b]], ib = index_of_id_[bonds.id_b[b]];
      const double kn = bonds.normal_stiffness[b], ks = bonds.shear_stiffness[b];
      const Vec2 d = x[ia] - x[ib];
      const double r = d.norm();
      const Vec2 nrm = d / r;
      const Vec2 t = perp(nrm);
      const double Rb = bonds.radius[b];
      const double A = 2.0 * Rb, In = 2.0 / 3.0 * Rb * Rb * Rb;
      const double fn = -kn * A * (r - bonds.rest_length[b]);            // on A along n; < 0 in tension
      const double la = R[ia] + 0.5 * (r - R[ia] - R[ib]), lb = r - la;  // levers to the bond centre
      const Vec2 vrel = v[ia] - v[ib] - (w[ia] * la + w[ib] * lb) * t;
      double fs = bonds.shear_force[b] - ks * A * vrel.dot(t) * dt;
      double mo = bonds.moment[b] - kn * In * (w[ia] - w[ib]) * dt;
      const double sigma = -fn / A + std::abs(mo) * Rb / In;
      const double tau = std::abs(fs) / A;
      bonds.normal_force[b] = fn;
      bonds.shear_force[b] = fs;
      bonds.moment[b] = mo;
      const bool tensile = sigma >= bonds.tensile_strength[b];
      if (tensile || tau >= bonds.shear_strength[b]) {
        const double energy = fn * fn / (2 * kn * A) + fs * fs / (2 * ks * A) + mo * mo / (2 * kn * In);
        const Vec2 centre = x[ib] + nrm * lb;
        ev.push_back(
            {time_, centre, tensile ? FailureMode::Tensile : FailureMode::Shear, energy, static_cast<std::int64_t>(b)});
        bonds.state[b] = tensile ? BondState::BrokenTension : BondState::BrokenShear;
        bonds.force_on_a[b].setZero();
        bonds.torque_on_a[b] = bonds.torque_on_b[b] = 0.0;
        continue;
      }
      bonds.force_on_a[b] = fn * nrm + fs * t;
      bonds.torque_on_a[b] = -la * fs + mo;
      bonds.torque_on_b[b] = -lb * fs - mo;
    }
  }
  const std::size_t before = events.size();
  for (auto& l : local) events.insert(events.end(), l.begin(), l.end());
  std::sort(events.begin() + static_cast<std::ptrdiff_t>(before), events.end(),
            [](const AcousticEvent& a, const AcousticEvent& b) { return a.bond < b.bond; });

  // Gather per disc (each disc writes only its own entries).
  auto& F = discs.get<Force>();
  auto& T = discs.get<Torque>();
  auto& K = discs.get<StiffnessSum>();
  auto& intact = discs.get<IntactBonds>();
  auto& broken = discs.get<BrokenBonds>();
  const auto& id = discs.get<ParticleId>();
  const std::int64_t n = static_cast<std::int64_t>(discs.size());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    Vec2 f = Vec2::Zero();
    double tq = 0, ktr = 0, krot = 0;
    std::int32_t ni = 0, nbk = 0;
    for (std::uint32_t q = bond_offsets_[id[i]]; q < bond_offsets_[id[i] + 1]; ++q) {
      const std::int64_t e = bond_entries_[q];
      const std::size_t b = static_cast<std::size_t>(e >= 0 ? e : -e - 1);
      const BondState s = bonds.state[b];
      if (s == BondState::BrokenTension || s == BondState::BrokenShear) ++nbk;
      if (s != BondState::Intact) continue;
      ++ni;
      const double kn = bonds.normal_stiffness[b], ks = bonds.shear_stiffness[b];
      const double Rb = bonds.radius[b];
      const double A = 2.0 * Rb, In = 2.0 / 3.0 * Rb * Rb * Rb;
      if (e >= 0) {
        f += bonds.force_on_a[b];
        tq += bonds.torque_on_a[b];
      } else {
        f -= bonds.force_on_a[b];
        tq += bonds.torque_on_b[b];
      }
      ktr += std::max(kn, ks) * A;
      krot += kn * In + ks * A * R[i] * R[i];
    }
    F[i] += f;
    T[i] += tq;
    K[i] += Eigen::Vector2d(ktr, krot);
    intact[i] = ni;
    broken[i] = nbk;
  }
}

template <class Law>
void DemSolver::update_wall_damping(const Law& law) {
  // Normal damping per wall and terrain segment (clamped contacts, Law::wall_damping), cached.
  const std::size_t nw = walls.size();
  if (damping_law_ != law_index_of<Law>() || terrain_damping_.size() != terrain.size() || wall_damping_.size() != nw) {
    damping_law_ = law_index_of<Law>();
    terrain_damping_.resize(terrain.size());
    for (std::size_t k = 0; k < terrain.size(); ++k)
      terrain_damping_[k] = Law::wall_damping(terrain.segment(k).restitution);
    wall_damping_.assign(nw, 0.0);
    wall_damping_e_.assign(nw, -1.0);
    wall_step_factor_ = 1.0;
    for (double z : terrain_damping_) wall_step_factor_ = std::max(wall_step_factor_, dashpot_step_factor(law, z));
  }
  for (std::size_t k = 0; k < nw; ++k)
    if (wall_damping_e_[k] != walls[k].restitution) {
      wall_damping_[k] = Law::wall_damping(walls[k].restitution);
      wall_damping_e_[k] = walls[k].restitution;
      wall_step_factor_ = std::max(wall_step_factor_, dashpot_step_factor(law, wall_damping_[k]));
    }
}

void DemSolver::reset_walls() {
  // Bounding boxes of the walls grown by the largest radius: a cheap reject before the distance.
  // An inactive wall gets an empty box (lower corner +inf, upper −inf), so it rejects every disc.
  const std::size_t nw = walls.size();
  wall_boxes_.resize(nw);
  constexpr double inf = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < nw; ++k) {
    auto& wl = walls[k];
    wl.force.setZero();
    wl.stiffness = 0.0;
    wl.contacts = 0;
    const Vec2 lo = wl.a.cwiseMin(wl.b) - Vec2::Constant(1.1 * rmax_);  // 10 %: radii grow while packing
    const Vec2 hi = wl.a.cwiseMax(wl.b) + Vec2::Constant(1.1 * rmax_);
    wall_boxes_[k] =
        wl.active ? std::array<double, 4>{lo.x(), lo.y(), hi.x(), hi.y()} : std::array<double, 4>{inf, inf, -inf, -inf};
  }
}

void DemSolver::update_wall_candidates() {
  const std::size_t n = discs.size(), nw = walls.size();
  bool valid = near_valid_ && near_wall_.size() == n && near_boxes_.size() == nw;
  for (std::size_t k = 0; k < nw && valid; ++k) {
    const auto& now = wall_boxes_[k];
    const auto& was = near_boxes_[k];
    valid = now[0] >= was[0] && now[1] >= was[1] && now[2] <= was[2] && now[3] <= was[3];
  }
  if (valid) return;
  // A disc stays within h of its position at the list build (the rebuild rule, drift ≤ skin/2;
  // 1 % more for the rounding of that test); each wall may move by up to h before the flags are
  // set again, so a disc is flagged within 2h of a wall's box. Terrain is static.
  const double h = 0.505 * skin_;
  near_boxes_.resize(nw);
  flag_boxes_.resize(nw);
  for (std::size_t k = 0; k < nw; ++k) {
    const auto& b = wall_boxes_[k];
    near_boxes_[k] = {b[0] - h, b[1] - h, b[2] + h, b[3] + h};
    flag_boxes_[k] = {Vec2(b[0] - 2 * h, b[1] - 2 * h), Vec2(b[2] + 2 * h, b[3] + 2 * h)};
  }
  near_wall_.resize(n);
  const Vec2* const xb = discs.get<PositionAtBuild>().data();
  const double* const R = discs.get<Radius>().data();
  const auto* const WC = discs.get<WallContacts>().data();
  const auto* const boxes = flag_boxes_.data();
  std::uint8_t* const near = near_wall_.data();
  const bool any_terrain = terrain.size() > 0;
  const double reach = 1.1 * rmax_;  // as the wall boxes (radii grow while packing)
  const auto nn = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static) if (parallel_worth(nn))
  for (std::int64_t ii = 0; ii < nn; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const Vec2 p = xb[i];
    bool flag = WC[i](0, 0) >= 0.0;
    // In box k iff lo − p ≤ 0 and p − hi ≤ 0 on both axes (a difference of two doubles is
    // positive exactly when the first is larger); both axes at once, no early exit.
    for (std::size_t k = 0; k < nw; ++k) flag |= (boxes[k][0] - p).cwiseMax(p - boxes[k][1]).maxCoeff() <= 0.0;
    near[i] = flag;
  }
  if (any_terrain) {
#pragma omp parallel for schedule(static) if (parallel_worth(nn))
    for (std::int64_t ii = 0; ii < nn; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      if (!near[i]) near[i] = terrain.near(xb[i], h, std::max(reach, R[i]));
    }
  }
  near_valid_ = true;
}

template <class Law>
void DemSolver::wall_forces(const Law& law) {
  const std::size_t nw = walls.size();
  if (nw == 0 && terrain.size() == 0) return;
  const auto& x = discs.get<Position<2>>();
  const auto& v = discs.get<Velocity<2>>();
  const auto& w = discs.get<AngularVelocity>();
  const auto& R = discs.get<Radius>();
  const auto& m = discs.get<Mass>();
  const auto& I = discs.get<Inertia>();
  const auto& kin = discs.get<Kinematic>();
  auto& F = discs.get<Force>();
  auto& T = discs.get<Torque>();
  auto& K = discs.get<StiffnessSum>();
  auto& WC = discs.get<WallContacts>();
  const double dt = dt_;
  const double mu_r = contact.rolling_friction, eta_r = contact.rolling_damping;
  const double f_t = contact.tangential_damping;
  const Vec2 gravity = settings.gravity;
  const std::int64_t n = static_cast<std::int64_t>(discs.size());
  update_wall_damping(law);
  const bool frag_mass = contact.fragment_damping_mass, frag_roll = contact.fragment_rolling;
  if (frag_mass || frag_roll) update_fragments();
  if (frag_roll) roll_moment_.assign(discs.size(), 0.0);
  reset_walls();
  update_wall_candidates();
#pragma omp parallel if (parallel_worth(n))
  {
    std::vector<Vec2> wf(nw, Vec2::Zero());
    std::vector<double> wk(nw, 0.0);
    std::vector<int> wn(nw, 0);
    // Private pointers for the candidate test: kept in registers.
    const auto [boxes, kinematic, position, history, near] =
        std::tuple(wall_boxes_.data(), kin.data(), x.data(), WC.data(), near_wall_.data());
#pragma omp for schedule(static)
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      // Far from every wall and terrain segment since the list build, without a wall contact
      // then (update_wall_candidates): none now either; the tests below would find nothing.
      if (!near[i] || kinematic[i]) continue;
      const Vec2 xi = position[i];
      const bool had = history[i](0, 0) >= 0.0;  // slots are filled from the first one
      const auto in_box = [=](std::size_t k) {
        return xi.x() >= boxes[k][0] && xi.y() >= boxes[k][1] && xi.x() <= boxes[k][2] && xi.y() <= boxes[k][3];
      };
      const auto [tb, te] = terrain.size() > 0
                                ? terrain.candidates(xi.x())
                                : std::pair<const std::uint32_t*, const std::uint32_t*>{nullptr, nullptr};
      const double Ri = R[i];
      const WallContacts::type& old = WC[i];
      WallContacts::type now;
      now.row(0).setConstant(-1.0);
      now.row(1).setZero();
      now.row(2).setZero();
      int used = 0;
      Vec2 f = Vec2::Zero();
      double tq = 0, ktr = 0, krot = 0;
      auto touch = [&](const WallSegment& s, std::size_t seg, std::size_t wall_index, double zeta) {
        const Vec2 p = closest_point_on_segment(s.a, s.b, xi);
        const Vec2 d = xi - p;
        const double r2 = d.squaredNorm();
        if (r2 >= Ri * Ri || r2 == 0.0) return;
        const double r = std::sqrt(r2);
        const Vec2 nrm = d / r;
        const Vec2 t = perp(nrm);
        const double md = frag_mass ? fragment_dashpot_mass(i, m[i], p, nrm) : m[i];
        const ContactResponse c = law.evaluate(Ri - r, md, Ri, 2.0 * Ri, zeta);
        const Vec2 vrel = v[i] - s.velocity - w[i] * Ri * t;
        // A wall never pulls a disc: the dashpot cannot make the normal force tensile (ζ is
        // the clamped-dashpot value, so the rebound still has the configured restitution).
        // The force of this step acts over [t − ½Δt, t + ½Δt]; in the first step of a contact
        // the disc touched τ = δ/|v_n| ago (it drifted in at v_n), so the dashpot impulse is
        // c v_n (τ + ½Δt), not c v_n Δt. Without this e = 0.1 came out anywhere in 0.04–0.11
        // depending on where in the step the disc arrived.
        const double vn = vrel.dot(nrm), delta = Ri - r;
        const double cn = vn < 0.0 && delta < -vn * dt ? c.cn * (0.5 + delta / (-vn * dt)) : c.cn;
        // The dashpot acts on the end-of-step normal velocity, not on the half-step one the
        // drift used: v_n' = v_n + ½Δt/m (F_el − c v_n' + F_o·n), implicit in this dashpot,
        // with F_o the other forces of this step already known (discs, bonds, walls before this
        // one, gravity). With the half-step velocity e was first-order in Δt too low (−7 % at
        // e = 0.1, −3.5 % at 0.3); F_o keeps a disc at rest at rest (v_n' = 0).
        const double h = 0.5 * dt / m[i];
        const double fo = (F[i] + m[i] * gravity + f).dot(nrm);
        const double vn_end = (vn + h * (c.fn_elastic + fo)) / (1.0 + h * cn);
        const double fn = std::max(c.fn_elastic - cn * vn_end, 0.0);
        double fs = 0.0, mr = 0.0;
        for (int q = 0; q < kWallSlots; ++q)
          if (old(0, q) == static_cast<double>(seg)) {
            fs = old(1, q);
            mr = old(2, q);
          }
        const double mu_rw = s.rolling_friction >= 0.0 ? s.rolling_friction : mu_r;  // the wall's own, if set
        // Tangential dashpot: the wall's normal damping ratio (× f_t) on the tangential spring.
        const double ct = f_t > 0.0 ? f_t * c.cn * std::sqrt(c.kt / c.kn) : 0.0;
        // Rolling resistance on the disc, or on terrain with contact.fragment_rolling on its
        // fragment; walls (platens, the avalanche's support) always act on the disc.
        const RollingBody rb = rolling_body(i, p, nrm, frag_roll && wall_index == SIZE_MAX);
        const auto fr = CoulombFrictionRolling::update(
            fs, mr, c.kt, c.kn, vrel.dot(t), fn, rb.arm, rb.spin, s.friction, mu_rw, eta_r, dt,
            [&] { return rb.inertia_at_contact; }, ct);
        fs = fr.shear;
        mr = fr.roll;
        // The rolling spring acts on the fragment's inertia: on disc i's share I_i/I_f of it.
        const double kr = rb.on_fragment ? fr.kr * I[i] / rb.fragment_inertia : fr.kr;
        const Vec2 fc = fn * nrm + (fs + fr.shear_damping) * t;
        f += fc;
        if (rb.on_fragment) {
          tq += -Ri * (fs + fr.shear_damping);
          roll_moment_[i] += mr + fr.roll_damping;
        } else {
          tq += -Ri * (fs + fr.shear_damping) + mr + fr.roll_damping;  // one expression: bit-identical to before
        }
        // Time step: a dashpot of ratio ζ lowers the critical step of the explicit scheme to
        // (2/ω)(√(1+ζ²) − ζ) (Belytschko et al. 2000, §6.3), i.e. k acts as k (ζ + √(1+ζ²))².
        // Without it a strongly damped contact (e = 0.1, ζ = 1.24) changes v by 57 % per step
        // and e = 0.1 came out 0.098–0.112 depending on the arrival within the step.
        const double zc = c.cn / (2.0 * std::sqrt(m[i] * c.kn)), gz = zc + std::sqrt(1.0 + zc * zc);
        ktr += std::max(c.kn * gz * gz, c.kt);
        krot += c.kt * Ri * Ri + kr;
        if (wall_index < nw) {
          wf[wall_index] -= fc;
          wk[wall_index] += c.kn;
          ++wn[wall_index];
        }
        if (used < kWallSlots) {
          now(0, used) = static_cast<double>(seg);
          now(1, used) = fs;
          now(2, used) = mr;
          ++used;
        }
      };
      for (std::size_t k = 0; k < nw; ++k)
        if (in_box(k)) touch(walls[k], k, k, wall_damping_[k]);
      for (auto p = tb; p != te; ++p)
        if (owns_contact(terrain, *p, xi)) touch(terrain.segment(*p), nw + *p, SIZE_MAX, terrain_damping_[*p]);
      if (used == 0 && !had) continue;  // no wall contact before or now: nothing to write
      WC[i] = now;
      F[i] += f;
      T[i] += tq;
      K[i] += Eigen::Vector2d(ktr, krot);
    }
#pragma omp critical
    for (std::size_t k = 0; k < nw; ++k) {
      walls[k].force += wf[k];
      walls[k].stiffness += wk[k];
      walls[k].contacts += wn[k];
    }
  }
  if (frag_roll) apply_fragment_rolling();
}

void DemSolver::apply_fragment_rolling() {
  const std::size_t n = discs.size();
  const auto& x = discs.get<Position<2>>();
  const auto& m = discs.get<Mass>();
  const auto& I = discs.get<Inertia>();
  auto& F = discs.get<Force>();
  auto& T = discs.get<Torque>();
  // Sum per fragment (indexed by its root disc, as update_fragments), then the angular
  // acceleration α = M/I_f of a rigid body: disc j gets the force m_j α ẑ × (x_j − G) and the
  // moment I_j α, which sum to no force and to M about G. Lone discs: T_i += M_i.
  std::vector<double>& moment = roll_moment_;
  const std::int64_t nf = static_cast<std::int64_t>(frag_start_.size()) - 1;
#pragma omp parallel for schedule(dynamic, 256) if (parallel_worth(n))
  for (std::int64_t k = 0; k < nf; ++k) {
    const std::size_t a = frag_start_[static_cast<std::size_t>(k)], b = frag_start_[static_cast<std::size_t>(k) + 1];
    const std::uint32_t q = frag_members_[a];  // the root, first in index order
    for (std::size_t p = a + 1; p < b; ++p) {
      moment[q] += moment[frag_members_[p]];
      moment[frag_members_[p]] = 0.0;
    }
  }
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t jj = 0; jj < static_cast<std::int64_t>(n); ++jj) {
    const auto j = static_cast<std::size_t>(jj);
    const std::uint32_t q = frag_of_[j];
    if (moment[q] == 0.0) continue;
    const double alpha = moment[q] / frag_inertia_[q];
    F[j] += m[j] * alpha * perp(x[j] - frag_centre_[q]);
    T[j] += I[j] * alpha;
  }
}

template <class Law>
void DemSolver::compute_forces(const Law& law) {
  pair_forces(law);
  bond_forces();
  wall_forces(law);
}

DemSolver::RollingBody DemSolver::rolling_body(std::size_t i, const Vec2& p, const Vec2& n, bool on_fragment) const {
  const double Ri = discs.get<Radius>()[i];
  if (!on_fragment) {
    const auto& I = discs.get<Inertia>();
    const auto& m = discs.get<Mass>();
    return {false, Ri, discs.get<AngularVelocity>()[i], I[i] + m[i] * Ri * Ri, I[i]};
  }
  const std::uint32_t q = frag_of_[i];
  const Vec2 r = frag_centre_[q] - p;
  return {true, std::max(Ri, r.dot(n)), frag_spin_[q],
          frag_inertia_[q] + frag_mass_[q] * std::max(r.squaredNorm(), Ri * Ri), frag_inertia_[q]};
}

double DemSolver::fragment_dashpot_mass(std::size_t i, double mi, const Vec2& p, const Vec2& n) const {
  const std::uint32_t q = frag_of_[i];
  const Vec2 rc = p - frag_centre_[q];
  const double rn = rc.x() * n.y() - rc.y() * n.x();
  return std::max(mi, 1.0 / (1.0 / frag_mass_[q] + rn * rn / frag_inertia_[q]));
}

void DemSolver::update_fragments() {
  const std::size_t n = discs.size();
  // The fragments change only when a bond breaks (or bonds or discs are added, or the discs are
  // reordered): relabel then, with union–find over the intact bonds and a list of each fragment's
  // discs in index order.
  std::size_t intact = 0;
  for (const BondState st : bonds.state) intact += st == BondState::Intact;
  const std::array<std::size_t, 4> key{n, bonds.size(), intact, static_cast<std::size_t>(reorders_)};
  if (key != frag_key_) {
    frag_key_ = key;
    frag_of_.resize(n);
    std::iota(frag_of_.begin(), frag_of_.end(), 0u);
    auto find = [&](std::uint32_t a) {
      while (frag_of_[a] != a) a = frag_of_[a] = frag_of_[frag_of_[a]];
      return a;
    };
    for (std::size_t b = 0; b < bonds.size(); ++b) {
      if (bonds.state[b] != BondState::Intact) continue;
      const std::uint32_t a = find(index_of(bonds.id_a[b])), c = find(index_of(bonds.id_b[b]));
      if (a != c) frag_of_[std::max(a, c)] = std::min(a, c);
    }
    for (std::size_t i = 0; i < n; ++i) frag_of_[i] = find(static_cast<std::uint32_t>(i));
    // Each root is its fragment's smallest index; members listed by fragment, in index order.
    std::vector<std::uint32_t> roots, count(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (frag_of_[i] == i) roots.push_back(static_cast<std::uint32_t>(i));
      ++count[frag_of_[i]];
    }
    frag_start_.assign(roots.size() + 1, 0);
    std::vector<std::uint32_t> slot(n, 0);
    for (std::size_t k = 0; k < roots.size(); ++k) {
      frag_start_[k + 1] = frag_start_[k] + count[roots[k]];
      slot[roots[k]] = frag_start_[k];
    }
    frag_members_.resize(n);
    for (std::size_t i = 0; i < n; ++i) frag_members_[slot[frag_of_[i]]++] = static_cast<std::uint32_t>(i);
    frag_mass_.assign(n, 0.0);  // per root disc; the entries of other discs are not used
    frag_inertia_.assign(n, 0.0);
    frag_spin_.assign(n, 0.0);
    frag_centre_.assign(n, Vec2::Zero());
  }
  // Mass, centre, momentum, inertia about the centre and spin (angular momentum about the centre /
  // inertia) of every fragment, each summed over its discs in index order.
  const auto& x = discs.get<Position<2>>();
  const auto& v = discs.get<Velocity<2>>();
  const auto& w = discs.get<AngularVelocity>();
  const auto& m = discs.get<Mass>();
  const auto& I = discs.get<Inertia>();
  const std::int64_t nf = static_cast<std::int64_t>(frag_start_.size()) - 1;
#pragma omp parallel for schedule(dynamic, 256) if (parallel_worth(n))
  for (std::int64_t k = 0; k < nf; ++k) {
    const std::uint32_t* b = frag_members_.data() + frag_start_[static_cast<std::size_t>(k)];
    const std::uint32_t* e = frag_members_.data() + frag_start_[static_cast<std::size_t>(k) + 1];
    const std::uint32_t q = *b;  // the root, first in index order
    double mass = 0;
    Vec2 centre = Vec2::Zero(), momentum = Vec2::Zero();
    for (const std::uint32_t* p = b; p != e; ++p) {
      mass += m[*p];
      centre += m[*p] * x[*p];
    }
    centre /= mass;
    for (const std::uint32_t* p = b; p != e; ++p) momentum += m[*p] * v[*p];
    double inertia = 0, spin = 0;
    for (const std::uint32_t* p = b; p != e; ++p) {
      const Vec2 d = x[*p] - centre, u = v[*p] - momentum / mass;
      inertia += I[*p] + m[*p] * d.squaredNorm();
      spin += I[*p] * w[*p] + m[*p] * (d.x() * u.y() - d.y() * u.x());
    }
    frag_mass_[q] = mass;
    frag_centre_[q] = centre;
    frag_inertia_[q] = inertia;
    frag_spin_[q] = spin / inertia;
  }
}

void DemSolver::update_time_step() {
  const auto& m = discs.get<Mass>();
  const auto& I = discs.get<Inertia>();
  const auto& R = discs.get<Radius>();
  const auto& K = discs.get<StiffnessSum>();
  const std::int64_t n = static_cast<std::int64_t>(discs.size());
  double inv2 = 0.0;  // max of k/m
#pragma omp parallel for reduction(max : inv2) schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const double kn0 = std::visit([&](const auto& l) { return l.reference_kn(R[i]); }, law) * wall_step_factor_;
    const double kt0 = std::visit([&](const auto& l) { return l.reference_kt(R[i]); }, law);
    const double ktr = std::max(K[i][0], std::max(kn0, kt0));
    const double krot = std::max(K[i][1], kt0 * R[i] * R[i]);
    inv2 = std::max(inv2, std::max(ktr / m[i], krot / I[i]));
  }
  dt_crit_ = inv2 > 0 ? 1.0 / std::sqrt(inv2) : 1.0;
  if (settings.fixed_time_step > 0) {
    dt_ = settings.fixed_time_step;
  } else {
    dt_ = settings.safety_factor * dt_crit_;
  }
}

void DemSolver::check_state() const {
  const auto& x = discs.get<Position<2>>();
  const auto& v = discs.get<Velocity<2>>();
  const auto& id = discs.get<ParticleId>();
  const std::int64_t n = static_cast<std::int64_t>(discs.size());
  const double vmax2 = settings.max_speed * settings.max_speed;
  std::int64_t bad = -1;
#pragma omp parallel for reduction(max : bad) schedule(static) if (parallel_worth(n))
  for (std::int64_t i = 0; i < n; ++i)
    if (!x[i].allFinite() || !v[i].allFinite() || v[i].squaredNorm() > vmax2) bad = std::max(bad, i);
  if (bad >= 0) {
    std::ostringstream s;
    s << "disc id " << id[bad] << " at (" << x[bad].x() << ", " << x[bad].y() << ") m has velocity (" << v[bad].x()
      << ", " << v[bad].y() << ") m/s at step " << steps_ << ", t = " << time_ << " s (limit " << settings.max_speed
      << " m/s): the time step is too large for the stiffnesses, or walls overlap discs";
    throw SimulationError(s.str());
  }
}

void DemSolver::step() {
  // Raw pointers and locals, so the loop keeps them in registers across its stores.
  Vec2* const x = discs.get<Position<2>>().data();
  Vec2* const v = discs.get<Velocity<2>>().data();
  double* const th = discs.get<Rotation>().data();
  double* const w = discs.get<AngularVelocity>().data();
  const Vec2* const F = discs.get<Force>().data();
  const double* const T = discs.get<Torque>().data();
  const double* const m = discs.get<Mass>().data();
  const double* const I = discs.get<Inertia>().data();
  const std::uint8_t* const kin = discs.get<Kinematic>().data();
  const Vec2* const xb = discs.get<PositionAtBuild>().data();
  const double dt = dt_;
  const std::int64_t n = static_cast<std::int64_t>(discs.size());
  // 1. half kick + drift (and the largest displacement since the last list build)
  double dmax2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : dmax2) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    double vx = v[i].x(), vy = v[i].y(), wi = w[i];
    if (!kin[i]) {
      const double hm = 0.5 * dt / m[i];
      vx += hm * F[i].x();
      vy += hm * F[i].y();
      wi += 0.5 * dt / I[i] * T[i];
      v[i] = Vec2(vx, vy);
      w[i] = wi;
    }
    const double px = x[i].x() + dt * vx, py = x[i].y() + dt * vy;
    x[i] = Vec2(px, py);
    th[i] += dt * wi;
    const double ex = px - xb[i].x(), ey = py - xb[i].y();
    dmax2 = std::max(dmax2, ex * ex + ey * ey);
  }
  for (auto& wl : walls) {
    wl.a += dt * wl.velocity;
    wl.b += dt * wl.velocity;
  }
  time_ += dt;
  ++steps_;
  // 2. neighbours
  update_neighbours(std::sqrt(dmax2));
  // 3. forces, 4. second half kick, blow-up check and next time step (the law is resolved once here)
  std::visit(
      [&](const auto& l) {
        compute_forces(l);
        finish_step(l);
      },
      law);
}

template <class Law>
void DemSolver::finish_step(const Law& law) {
  // Gravity, Cundall's local damping, the second half kick, the blow-up check and the stiffness
  // bound of the next time step, fused into one pass over the discs. Raw pointers and a local
  // copy of the law, so its reference stiffnesses are loaded once, not after every store.
  const Law lw = law;
  Vec2* const F = discs.get<Force>().data();
  double* const T = discs.get<Torque>().data();
  Vec2* const v = discs.get<Velocity<2>>().data();
  double* const w = discs.get<AngularVelocity>().data();
  const Vec2* const x = discs.get<Position<2>>().data();
  const double* const m = discs.get<Mass>().data();
  const double* const I = discs.get<Inertia>().data();
  const double* const R = discs.get<Radius>().data();
  const auto* const K = discs.get<StiffnessSum>().data();
  const std::uint8_t* const kin = discs.get<Kinematic>().data();
  const double gx = settings.gravity.x(), gy = settings.gravity.y();
  const double alpha = settings.local_damping;
  const double step_factor = wall_step_factor_;
  const double dt = dt_;
  const double vmax2 = settings.max_speed * settings.max_speed;
  const std::int64_t n = static_cast<std::int64_t>(discs.size());
  double inv2 = 0.0;
  std::int64_t bad = -1;
#pragma omp parallel for schedule(static) reduction(max : inv2, bad) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const double mi = m[i];
    double vx = v[i].x(), vy = v[i].y();
    if (!kin[i]) {
      double fx = F[i].x() + mi * gx, fy = F[i].y() + mi * gy;
      double tq = T[i];
      if (alpha > 0) {
        fx -= alpha * std::abs(fx) * sgn(vx);
        fy -= alpha * std::abs(fy) * sgn(vy);
        tq -= alpha * std::abs(tq) * sgn(w[i]);
      }
      F[i] = Vec2(fx, fy);
      T[i] = tq;
      const double hm = 0.5 * dt / mi;
      vx += hm * fx;
      vy += hm * fy;
      v[i] = Vec2(vx, vy);
      w[i] += 0.5 * dt / I[i] * tq;
    }
    // A non-finite or too fast velocity fails the comparison; the position is checked apart.
    if (!(vx * vx + vy * vy <= vmax2) || !std::isfinite(x[i].x()) || !std::isfinite(x[i].y())) bad = std::max(bad, ii);
    const double Ri = R[i];
    const double kn0 = lw.reference_kn(Ri) * step_factor, kt0 = lw.reference_kt(Ri);
    const double ktr = std::max(K[i][0], std::max(kn0, kt0));
    const double krot = std::max(K[i][1], kt0 * Ri * Ri);
    inv2 = std::max(inv2, std::max(ktr / mi, krot / I[i]));
  }
  // Servo walls: v = G (σ − σ_target) outward, G = α L / (Σk_n Δt).
  for (auto& wl : walls) {
    if (wl.control != WallControl::Servo || !wl.active) continue;
    const double L = wl.loaded_length > 0 ? wl.loaded_length : wl.length();
    const double sigma = wl.normal_stress(L);
    const double k = std::max(wl.stiffness, 1e-300);
    double speed = wl.servo_gain * L / (k * dt) * (sigma - wl.target_stress);
    if (wl.contacts == 0) speed = -wl.max_speed;  // no contact: move in towards the sample
    speed = std::clamp(speed, -wl.max_speed, wl.max_speed);
    wl.velocity = -speed * wl.servo_normal;
  }
  if (bad >= 0) check_state();  // throws with the diagnosis
  dt_crit_ = inv2 > 0 ? 1.0 / std::sqrt(inv2) : 1.0;
  dt_ = settings.fixed_time_step > 0 ? settings.fixed_time_step : settings.safety_factor * dt_crit_;
}

void DemSolver::run_until(double t_end, std::int64_t max_steps) {
  std::int64_t k = 0;
  while (time_ < t_end && k < max_steps) {
    step();
    ++k;
  }
}

}  // namespace geohaz::dem
