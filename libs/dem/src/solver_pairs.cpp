// The disc–disc contact pass of DemSolver (step 3 of solver.hpp, first part) and the history
// look-up it uses after a neighbour-list rebuild. In its own file because it is the hot loop of
// every unbonded run (issue #35): written on raw arrays and local constants so that nothing the
// loop reads has to be reloaded after each store, with every floating-point operation the one of
// the formulas in solver.hpp and contact_laws.hpp, in the same order.
#include <algorithm>
#include <cmath>
#include <type_traits>
#include <variant>

#include "geohaz/core/parallel.hpp"
#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {

namespace {

/// Equivalent rolling inertia of Ai et al. (2011), eq. (12).
inline double rolling_inertia(double Ii, double mi, double Ri, double Ij, double mj, double Rj) noexcept {
  return 1.0 / (1.0 / (Ii + mi * Ri * Ri) + 1.0 / (Ij + mj * Rj * Rj));
}

}  // namespace

// The arrays and constants of the plain pair loop (plain_pair_block), copied into its locals.
struct DemSolver::PlainPass {
  const Vec2* x;
  const Vec2* v;
  const double *w, *R, *m, *I;
  const std::int64_t* id;
  Vec2* F;
  double* T;
  Eigen::Vector2d* K;
  const std::uint32_t *off, *nbr;
  std::int64_t* h_partner;
  double *h_shear, *h_roll;
  std::uint32_t *owner, *slots;  // per listed pair: its lower index i; a block's contacts
  const PairBlocks* pb;
  PairReaction* reactions;
  double dt, mu, eta_r, zeta, f_t, kt_kn_root;
};

// Each pair once, from its lower index i (the list is a half list): disc j's share (−F on j, its
// own lever and the opposite rolling moment, the same stiffnesses) goes to the reaction buffer of
// i's block and is added in fixed block order after the pass (core PairBlocks, as in the SPH and
// runout pair passes), so the sums do not depend on the thread count. Evaluated from j, a contact
// gives the same F_s and the opposite M_r to the last bit (the relative velocity and the normal
// flip sign exactly), so this is the result of evaluating both sides up to the order of the sums.
// The dashpot mass m* of a pair of two kinematic discs (a grip against itself) is the two-body
// one, so their forces cancel exactly in the grip's reaction.
// A local copy of the law and raw pointers: the compiler may then keep the law's constants and the
// arrays' addresses in registers across the stores of the loop (through references to members it
// must assume a store to a force array could change them).
// Without a list rebuild since the last step, entry k of the history is the same pair as entry k
// of the list: it is updated in place. After a rebuild a new table is written beside the old one,
// whose entries are found by partner id (lookup_history). √(k_t/k_n) of the tangential dashpot is
// taken once per pass when the law's stiffnesses do not depend on the overlap (the same quotient
// and root as per contact, so the same bits). The pairs of a block are one lambda with `same` a
// compile-time constant, so the loop of the steps without a rebuild (most steps) holds no call that
// would spill its registers; captured by value, so the pointers and constants are the closure's
// own, which no store in the loop can change, not the shared variables of the parallel region.
// This loop is the general one (rolling resistance, joints, kinematic discs); runs without any of
// them take the plain pass (plain_pair_pass, below), the same contacts and sums in two flat loops.
template <class Law>
void DemSolver::pair_forces(const Law& law_in) {
  const Law law = law_in;
  const Vec2* const x = discs.get<Position<2>>().data();
  const Vec2* const v = discs.get<Velocity<2>>().data();
  const double* const w = discs.get<AngularVelocity>().data();
  const double* const R = discs.get<Radius>().data();
  const double* const m = discs.get<Mass>().data();
  const double* const I = discs.get<Inertia>().data();
  const std::int64_t* const id = discs.get<ParticleId>().data();
  const std::uint8_t* const kin = discs.get<Kinematic>().data();
  Vec2* const F = discs.get<Force>().data();
  double* const T = discs.get<Torque>().data();
  auto* const K = discs.get<StiffnessSum>().data();
  const std::uint32_t* const off = nb_.list().offsets().data();
  const std::uint32_t* const nbr = nb_.list().indices().data();
  const std::size_t n = discs.size();
  const bool same_layout = same_layout_ && hist_.offsets.size() == n + 1;
  PairHistory& out = pair_history_out(same_layout);
  std::int64_t* const h_partner = out.partner.data();
  double* const h_shear = out.shear.data();
  double* const h_roll = out.roll.data();
  const double dt = dt_;
  const double mu = contact.friction;
  const double mu_r = contact.rolling_friction;
  const double eta_r = contact.rolling_damping;
  const double zeta = Law::pair_damping(contact.restitution);
  const double f_t = contact.tangential_damping;
  const double mu_joint = settings.joint_friction;
  const bool any_joints = !joints_.empty();
  double kt_kn_root = 0.0;
  if constexpr (Law::constant_stiffness) {
    const ContactResponse c0 = law.evaluate(1.0, 1.0, 1.0, 2.0, zeta);
    kt_kn_root = std::sqrt(c0.kt / c0.kn);
  }
  const PairBlocks& pb = pair_blocks_;
  reactions_.resize(pb.slots());
  PairReaction* const reactions = reactions_.data();
  const auto nblocks = static_cast<std::int64_t>(pb.count());
  if (plain_pair_loop()) {
    plain_pair_pass(law, out, same_layout, zeta, kt_kn_root);
  } else {
    const auto block = [=, this](std::size_t b, auto layout) {
      constexpr bool same = decltype(layout)::value;
      PairReaction* const react = pb.buffer(reactions, b);  // react[j]: the reactions on disc j
      std::fill(react + pb.first(b), react + pb.window_end(b), PairReaction{});
      for (std::size_t i = pb.first(b); i < pb.last(b); ++i) {
        const double xi = x[i].x(), yi = x[i].y();
        const double Ri = R[i], mi = m[i], wi = w[i];
        const double vxi = v[i].x(), vyi = v[i].y();
        const std::uint8_t kini = kin[i];
        double fx = 0.0, fy = 0.0, tq = 0.0, ktr = 0.0, krot = 0.0;
        for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
          const std::uint32_t j = nbr[k];
          const double dx = xi - x[j].x(), dy = yi - x[j].y();
          const double r2 = dx * dx + dy * dy;
          const double Rj = R[j];
          const double Rs = Ri + Rj;
          if (r2 >= Rs * Rs || r2 == 0.0) {
            h_partner[k] = -1;
            continue;
          }
          const double r = std::sqrt(r2);
          const double delta = Rs - r;
          double nx = dx / r, ny = dy / r;
          double mu_c = mu, mu_rc = mu_r;
          if (any_joints) {
            if (const JointPair* jp = joint_between(id[i], id[j])) {
              const bool along = jp->normal.x() * nx + jp->normal.y() * ny >= 0;
              nx = along ? jp->normal.x() : -jp->normal.x();
              ny = along ? jp->normal.y() : -jp->normal.y();
              mu_c = mu_joint;
              mu_rc = 0.0;
            }
          }
          const double tx = -ny, ty = nx;  // t = ẑ × n
          const double mj = m[j];
          const double meff = kin[j] == kini ? mi * mj / (mi + mj) : (kin[j] ? mi : mj);
          const double reff = Ri * Rj / Rs;
          const ContactResponse c = law.evaluate(delta, meff, reff, Rs, zeta);
          // Levers to the common contact point (mid-overlap), so the pair of shear forces is a zero
          // net couple and angular momentum is conserved exactly.
          const double li = Ri - 0.5 * delta, lj = Rj - 0.5 * delta;
          const double spin = wi * li + w[j] * lj;
          const double vrx = vxi - v[j].x() - spin * tx, vry = vyi - v[j].y() - spin * ty;
          const double vn = vrx * nx + vry * ny;
          const double vt = vrx * tx + vry * ty;
          const double fn = c.fn_elastic - c.cn * vn;
          const std::int64_t pj = id[j];
          double fs = 0.0, mr = 0.0;
          if constexpr (same) {
            if (h_partner[k] == pj) {
              fs = h_shear[k];
              mr = h_roll[k];
            }
          } else {
            lookup_history(i, j, fs, mr);
          }
          // Tangential dashpot: the normal damping ratio (× f_t) on the tangential spring, same m*.
          double ct = 0.0;
          if (f_t > 0.0) ct = f_t * c.cn * (Law::constant_stiffness ? kt_kn_root : std::sqrt(c.kt / c.kn));
          const auto fr = CoulombFrictionRolling::update(
              fs, mr, c.kt, c.kn, vt, fn, reff, wi - w[j], mu_c, mu_rc, eta_r, dt,
              [&] { return rolling_inertia(I[i], mi, Ri, I[j], mj, Rj); }, ct);
          fs = fr.shear;
          mr = fr.roll;
          const double shear = fs + fr.shear_damping, roll = mr + fr.roll_damping;
          const double fcx = fn * nx + shear * tx, fcy = fn * ny + shear * ty;
          const double k_tr = std::max(c.kn, c.kt);
          fx += fcx;
          fy += fcy;
          tq += -li * shear + roll;
          ktr += k_tr;
          krot += c.kt * Ri * Ri + fr.kr;
          react[j].add_reaction(fcx, fcy, -lj * shear - roll, k_tr, c.kt * Rj * Rj + fr.kr);
          h_partner[k] = pj;
          h_shear[k] = fs;
          h_roll[k] = mr;
        }
        F[i] = Vec2(fx, fy);
        T[i] = tq;
        K[i] = Eigen::Vector2d(ktr, krot);
      }
    };
#pragma omp parallel for schedule(static) if (parallel_worth(n))
    for (std::int64_t bb = 0; bb < nblocks; ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      if (same_layout)
        block(b, std::true_type{});
      else
        block(b, std::false_type{});
    }
  }
  gather_pair_reactions();
  if (!same_layout) {
    std::swap(hist_, hist_next_);
    same_layout_ = true;
  }
}

// The plain loop (no rolling resistance, joints or kinematic discs) over block b in two flat passes
// over its listed pairs, without a loop per disc. 1. The contact test r < R_i + R_j of every pair,
// without a branch: the pair's slot is written and the count advanced by the test's 0 or 1, so the
// contacts of the block are listed in list order (41 % of the listed pairs of a dense packing are
// not in contact, and which ones is close to a coin toss for a branch predictor); a pair out of
// contact gets partner −1 as before. 2. The forces of those contacts, the same operations as the
// general loop's with μ_r = 0, in the same order; disc i's sums go to F[i], T[i], K[i], zeroed
// first, in list order, so each is the same sum 0 + f₁ + f₂ + … as the general loop's locals.
// A member function, not a lambda: its copies of the law and of the pointers are locals, which no
// store in the loops can change.
template <bool same, class Law>
void DemSolver::plain_pair_block(const Law& law_in, const PlainPass& p_in, std::size_t b) {
  const Law law = law_in;
  const PlainPass p = p_in;
  const PairBlocks& pb = *p.pb;
  PairReaction* const react = pb.buffer(p.reactions, b);  // react[j]: the reactions on disc j
  std::fill(react + pb.first(b), react + pb.window_end(b), PairReaction{});
  const std::size_t first = pb.first(b), last = pb.last(b);
  std::fill(p.F + first, p.F + last, Vec2::Zero());
  std::fill(p.T + first, p.T + last, 0.0);
  std::fill(p.K + first, p.K + last, Eigen::Vector2d::Zero());
  const std::uint32_t k0 = p.off[first], k1 = p.off[last];
  std::uint32_t* const slot = p.slots + k0;
  std::uint32_t nc = 0;
  for (std::uint32_t k = k0; k < k1; ++k) {
    const std::uint32_t i = p.owner[k], j = p.nbr[k];
    const double dx = p.x[i].x() - p.x[j].x(), dy = p.x[i].y() - p.x[j].y();
    const double r2 = dx * dx + dy * dy;
    const double Rs = p.R[i] + p.R[j];
    const bool touch = !(r2 >= Rs * Rs) & (r2 != 0.0);
    slot[nc] = k;
    nc += touch;
    if constexpr (same) {
      // −1 out of contact, by a mask (a select here becomes the branch the test avoids).
      p.h_partner[k] |= static_cast<std::int64_t>(touch) - 1;
    } else {
      p.h_partner[k] = -1;  // a contact's entry is written in the second pass
    }
  }
  for (std::uint32_t q = 0; q < nc; ++q) {
    const std::uint32_t k = slot[q], i = p.owner[k], j = p.nbr[k];
    const double Ri = p.R[i], Rj = p.R[j], mi = p.m[i], mj = p.m[j], wi = p.w[i], wj = p.w[j];
    const double dx = p.x[i].x() - p.x[j].x(), dy = p.x[i].y() - p.x[j].y();
    const double r2 = dx * dx + dy * dy;
    const double Rs = Ri + Rj;
    const double r = std::sqrt(r2);
    const double delta = Rs - r;
    const double nx = dx / r, ny = dy / r;
    const double tx = -ny, ty = nx;  // t = ẑ × n
    const double meff = mi * mj / (mi + mj);
    const double reff = Ri * Rj / Rs;
    const ContactResponse c = law.evaluate(delta, meff, reff, Rs, p.zeta);
    const double li = Ri - 0.5 * delta, lj = Rj - 0.5 * delta;
    const double spin = wi * li + wj * lj;
    const double vrx = p.v[i].x() - p.v[j].x() - spin * tx, vry = p.v[i].y() - p.v[j].y() - spin * ty;
    const double vn = vrx * nx + vry * ny;
    const double vt = vrx * tx + vry * ty;
    const double fn = c.fn_elastic - c.cn * vn;
    const std::int64_t pj = p.id[j];
    double fs = 0.0, mr = 0.0;
    if constexpr (same) {
      if (p.h_partner[k] == pj) {
        fs = p.h_shear[k];
        mr = p.h_roll[k];
      }
    } else {
      lookup_history(i, j, fs, mr);
    }
    double ct = 0.0;
    if (p.f_t > 0.0) ct = p.f_t * c.cn * (Law::constant_stiffness ? p.kt_kn_root : std::sqrt(c.kt / c.kn));
    const auto fr = CoulombFrictionRolling::update(
        fs, mr, c.kt, c.kn, vt, fn, reff, wi - wj, p.mu, 0.0, p.eta_r, p.dt,
        [&] { return rolling_inertia(p.I[i], mi, Ri, p.I[j], mj, Rj); }, ct);
    fs = fr.shear;
    mr = fr.roll;
    const double shear = fs + fr.shear_damping, roll = mr + fr.roll_damping;
    const double fcx = fn * nx + shear * tx, fcy = fn * ny + shear * ty;
    const double k_tr = std::max(c.kn, c.kt);
    p.F[i].x() += fcx;
    p.F[i].y() += fcy;
    p.T[i] += -li * shear + roll;
    p.K[i].x() += k_tr;
    p.K[i].y() += c.kt * Ri * Ri + fr.kr;
    react[j].add_reaction(fcx, fcy, -lj * shear - roll, k_tr, c.kt * Rj * Rj + fr.kr);
    p.h_partner[k] = pj;
    p.h_shear[k] = fs;
    p.h_roll[k] = mr;
  }
}

// The plain pass: the pair owners written with each new list (the first plain pass after a
// build), then the blocks in parallel as in pair_forces.
template <class Law>
void DemSolver::plain_pair_pass(const Law& law, PairHistory& out, bool same_layout, double zeta, double kt_kn_root) {
  if (!same_layout) owner_valid_ = false;
  const std::uint32_t* const off = nb_.list().offsets().data();
  pair_owner_.resize(nb_.list().indices().size());
  contact_slots_.resize(pair_owner_.size());
  const PlainPass pp{.x = discs.get<Position<2>>().data(),
                     .v = discs.get<Velocity<2>>().data(),
                     .w = discs.get<AngularVelocity>().data(),
                     .R = discs.get<Radius>().data(),
                     .m = discs.get<Mass>().data(),
                     .I = discs.get<Inertia>().data(),
                     .id = discs.get<ParticleId>().data(),
                     .F = discs.get<Force>().data(),
                     .T = discs.get<Torque>().data(),
                     .K = discs.get<StiffnessSum>().data(),
                     .off = off,
                     .nbr = nb_.list().indices().data(),
                     .h_partner = out.partner.data(),
                     .h_shear = out.shear.data(),
                     .h_roll = out.roll.data(),
                     .owner = pair_owner_.data(),
                     .slots = contact_slots_.data(),
                     .pb = &pair_blocks_,
                     .reactions = reactions_.data(),
                     .dt = dt_,
                     .mu = contact.friction,
                     .eta_r = contact.rolling_damping,
                     .zeta = zeta,
                     .f_t = contact.tangential_damping,
                     .kt_kn_root = kt_kn_root};
  const bool fill_owner = !owner_valid_;
  const PairBlocks& pb = pair_blocks_;
  const auto nblocks = static_cast<std::int64_t>(pb.count());
#pragma omp parallel for schedule(static) if (parallel_worth(discs.size()))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    if (fill_owner)
      for (std::size_t i = pb.first(b); i < pb.last(b); ++i)
        std::fill(pp.owner + off[i], pp.owner + off[i + 1], static_cast<std::uint32_t>(i));
    if (same_layout)
      plain_pair_block<true>(law, pp, b);
    else
      plain_pair_block<false>(law, pp, b);
  }
  owner_valid_ = true;
}

DemSolver::PairHistory& DemSolver::pair_history_out(bool same_layout) {
  if (same_layout) return hist_;  // the list is the one the history was written with: in place
  const auto offsets = nb_.list().offsets();
  const std::size_t npairs = nb_.list().indices().size();
  hist_next_.offsets.assign(offsets.begin(), offsets.end());
  hist_next_.partner.resize(npairs);
  hist_next_.shear.resize(npairs);
  hist_next_.roll.resize(npairs);
  return hist_next_;
}

// Without rolling resistance (μ_r ≤ 0: every contact's μ_r is 0, a joint's too), joints and
// kinematic discs, the plain pass (plain_pair_block): its μ_r is the constant 0, so the compiler
// drops the rolling branch of the friction update (roll = 0 there as before) and what only it reads
// (R* of the linear law, ω_i − ω_j), and the joint test; every m* is the two-body one.
bool DemSolver::plain_pair_loop() const {
  if (contact.rolling_friction > 0.0 || !joints_.empty()) return false;
  std::uint8_t any_kinematic = 0;
  for (const std::uint8_t k : discs.get<Kinematic>()) any_kinematic |= k;
  return !any_kinematic;
}

void DemSolver::gather_pair_reactions() {
  // The fixed-order gather (PairBlocks::gather: disc a adds the reactions of the blocks whose
  // window holds it in ascending block order), looped block by block over the discs each block's
  // window holds instead of disc by disc over the blocks: the same additions in the same order
  // for every disc, without a window test per disc and block.
  Vec2* const F = discs.get<Force>().data();
  double* const T = discs.get<Torque>().data();
  auto* const K = discs.get<StiffnessSum>().data();
  const PairReaction* const reactions = reactions_.data();
  const PairBlocks& pb = pair_blocks_;
  const auto nblocks = static_cast<std::int64_t>(pb.count());
#pragma omp parallel for schedule(static) if (parallel_worth(discs.size()))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    const std::size_t begin = pb.first(b), end = pb.last(b);
    for (std::size_t c = pb.first_block_reaching(b); c <= b; ++c) {
      const PairReaction* const r = pb.buffer(reactions, c);
      const std::size_t stop = std::min(end, c * pb.size + pb.window());
      for (std::size_t a = begin; a < stop; ++a) {
        F[a] += r[a].f;
        T[a] += r[a].tq;
        K[a] += Eigen::Vector2d(r[a].ktr, r[a].krot);
      }
    }
  }
}

const JointPair* DemSolver::joint_between(std::int64_t id_a, std::int64_t id_b) const {
  for (std::uint32_t q = joint_offsets_[id_a]; q < joint_offsets_[id_a + 1]; ++q) {
    const JointPair& jp = joints_[joint_entries_[q]];
    if (jp.id_a == id_b || jp.id_b == id_b) return &jp;
  }
  return nullptr;
}

void DemSolver::lookup_history(std::size_t i, std::size_t j, double& fs, double& mr) const {
  // By partner id: the pair's entry is in the segment of the disc that was its lower index when it
  // was written (i's, or j's before a reordering swapped them; seen from j, M_r has the other sign).
  const auto& id = discs.get<ParticleId>();
  const std::int64_t pj = id[j], pi = id[i];
  for (std::uint32_t q = hist_.offsets[i]; q < hist_.offsets[i + 1]; ++q)
    if (hist_.partner[q] == pj) {
      fs = hist_.shear[q];
      mr = hist_.roll[q];
      return;
    }
  for (std::uint32_t q = hist_.offsets[j]; q < hist_.offsets[j + 1]; ++q)
    if (hist_.partner[q] == pi) {
      fs = hist_.shear[q];
      mr = -hist_.roll[q];
      return;
    }
}

// The pass for every contact law (compute_forces in solver.cpp visits the law once per step).
static_assert(std::variant_size_v<ContactLaw> == 2, "instantiate pair_forces for every contact law");
template void DemSolver::pair_forces<LinearSpringCoulomb>(const LinearSpringCoulomb&);
template void DemSolver::pair_forces<HertzMindlin>(const HertzMindlin&);

}  // namespace geohaz::dem
